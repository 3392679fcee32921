//! The jobs users run, on the renderer: flythroughs ([`fly`], along a camera [`path`], into an
//! [`animation`]), snapshots in [`batch`], the interactive window ([`view`], flown by
//! [`flycam`], its figures drawn by [`hud`]), the CPU stage's figures of `terrain warp`
//! ([`stage_figures`]); and what they share: [`output`] (atomic files, written together) and
//! [`progress`] (which also shows the library's, [`terrain::progress`]).

pub mod animation;
pub mod batch;
pub mod fly;
pub mod flycam;
#[cfg(feature = "view")]
pub mod hud;
pub mod output;
pub mod path;
pub mod progress;
pub mod stage_figures;
#[cfg(feature = "view")]
pub mod view;
