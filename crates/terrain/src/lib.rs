//! `terrain`: large terrains whose rough shape comes from a height map (the *sketch*) and whose
//! fine detail is procedural, rendered by geometry image warping (Dachsbacher & Stamminger,
//! *Rendering Procedural Terrain by Geometry Image Warping*, 2004).
//!
//! A host application draws a terrain with its own device through [`host`]: a [`host::Description`]
//! (a [`scene::Scene`] with its sketch read) states the limits and features a device needs, a
//! [`host::Terrain`] prepares each frame on the CPU and records it into the host's encoder,
//! into the host's colour and depth views. [`query`] answers heights, normals and rays on the
//! same ground.
//!
//! The folders follow a frame, in the order data flows through it: [`scene`] (the terrain's
//! description, and building a camera, the detail and the sketch from it) → [`sketch`] (the
//! height map read into its atlas; [`tiles`] for pyramids larger than memory) → [`stage`] (the
//! CPU stage: sketch map → importance → warp → Φ, measured by its quality) → [`gpu`] (the passes:
//! warp & zoom, mesh split, normals, terrain, reference, output) driven by one
//! [`render::Renderer`] through a level-of-detail scheme from [`lod`]. [`detail`] is the
//! procedural model both sides share; [`planet`] carries it onto a sphere.
//!
//! Rules: the library prints nothing and writes no file it was not asked to: its notes go
//! through the `log` crate, its long work reports to [`progress`]. It holds no command line,
//! chart, progress bar or image metric: those are the tools' (the `terrain-cli` crate and its
//! `terrain` binary). Rejected: one crate for both, where every embedder compiled the commands'
//! dependencies.

pub mod camera;
pub mod detail;
pub mod error;
pub mod geomipmap;
pub mod gpu;
pub mod host;
pub mod io;
pub mod light;
pub mod lod;
pub mod names;
pub mod planet;
pub mod progress;
pub mod query;
pub mod render;
pub mod scene;
pub mod sketch;
pub mod stage;
pub mod tiles;

pub use error::{Error, Result};
