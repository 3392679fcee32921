//! `terrain`: large terrains whose rough shape comes from a height map (the *sketch*) and whose
//! fine detail is procedural, rendered by geometry image warping (Dachsbacher & Stamminger).
//!
//! The CPU stage of a frame, in the order data flows through it:
//! [`atlas`] (the sketch atlas) → [`sketch_map`] → [`importance`] → [`warp`] → Φ, measured by
//! [`quality`]; [`detail`] is the procedural model the GPU adds on top. [`gpu`] holds the passes
//! (warp & zoom, normals, terrain, reference), [`geomipmap`] the baseline's levels and stitching,
//! [`render`] puts a mode's CPU and GPU halves together, [`metrics`] measures images against the
//! reference.

pub mod animation;
pub mod atlas;
pub mod batch;
pub mod camera;
pub mod compare;
pub mod cpu_stage;
pub mod detail;
pub mod error;
pub mod figures;
pub mod fly;
pub mod flycam;
pub mod geomipmap;
pub mod gpu;
pub mod importance;
pub mod lod;
pub mod metrics;
pub mod names;
pub mod output;
pub mod path;
pub mod plot;
pub mod progress;
pub mod quality;
pub mod render;
pub mod scene;
pub mod sketch_map;
#[cfg(feature = "view")]
pub mod view;
pub mod warp;

pub use error::{Error, Result};
