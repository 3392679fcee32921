//! The jobs users run, on the renderer: flythroughs ([`fly`], along the engine's camera path, into an
//! [`animation`]), snapshots in [`batch`], the interactive window ([`view`], flown by
//! the engine's fly camera, its figures drawn by [`hud`]), the CPU stage's figures of `terrain warp`
//! ([`stage_figures`]). What they share with the evaluation is beside them: [`crate::output`]
//! (atomic files, written together) and [`crate::progress`] (which also shows the library's,
//! [`terrain_engine::progress`]).

pub mod animation;
pub mod batch;
pub mod fly;
#[cfg(feature = "view")]
pub mod hud;
pub mod stage_figures;
#[cfg(feature = "view")]
pub mod view;
