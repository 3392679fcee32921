//! `terrain`: large terrains whose rough shape comes from a height map (the *sketch*) and whose
//! fine detail is procedural, rendered by geometry image warping (Dachsbacher & Stamminger).
//!
//! The folders follow a frame, in the order data flows through it: [`scene`] (the scene file, and
//! building a camera, the detail and the sketch from it) → [`sketch`] (the height map read into
//! its atlas) → [`stage`] (the CPU stage: sketch map → importance → warp → Φ, measured by its
//! quality) → [`gpu`] (the passes: warp & zoom, mesh split, normals, terrain, reference) driven
//! by one [`render::Renderer`] through a level-of-detail scheme from [`lod`]. [`detail`] is the
//! procedural model both sides share. [`eval`] measures images against the reference
//! (`compare`); [`app`] holds the jobs users run (fly, batch, the window) and what they share
//! (outputs, progress, camera paths).
//!
//! Outside [`app`], [`eval`] and the binary the library prints nothing and writes no file it was
//! not asked to: its notes go through the `log` crate (the binary prints them as `note:` lines),
//! its long work reports to [`progress`], and neither reaches into [`app`] or [`eval`].

pub mod app;
pub mod camera;
pub mod detail;
pub mod error;
pub mod eval;
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
