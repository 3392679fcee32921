//! The jobs users run, on the renderer: flythroughs ([`fly`], along a camera [`path`], into an
//! [`animation`]), snapshots in [`batch`], the interactive window ([`view`], flown by
//! [`flycam`], its figures drawn by [`hud`]); and what they share: [`output`] (atomic files,
//! written together) and [`progress`].

pub mod animation;
pub mod batch;
pub mod fly;
pub mod flycam;
#[cfg(feature = "view")]
pub mod hud;
pub mod output;
pub mod path;
pub mod progress;
#[cfg(feature = "view")]
pub mod view;
