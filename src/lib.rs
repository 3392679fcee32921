//! The tools around the `terrain` library: the jobs users run ([`app`]: fly, batch, the window,
//! camera paths) and the evaluation ([`eval`]: image metrics, `compare`), over what both use:
//! the files they write ([`output`], and [`ground_truth`] beside images), their charts and text ([`plot`]), progress bars
//! ([`progress`]) and order statistics ([`stats`]). The `terrain` binary (`src/bin/terrain/`) is their command line.
//! Modules lower in that list do not use the ones above them: the jobs do not use the evaluation.
//!
//! Rules: everything here is built on the library's public API; nothing here is needed to embed
//! a terrain. Rejected: these modules inside the library, where every host would compile clap,
//! plotters, indicatif and the metrics.

pub mod app;
pub mod error;
pub mod eval;
pub mod ground_truth;
pub mod output;
pub mod plot;
pub mod progress;
pub mod stats;

pub use error::{Error, Result};

/// docs/embedding.md's host, compiled with the doctests so that the page cannot drift from the
/// API it describes.
#[cfg(doctest)]
#[doc = include_str!("../docs/embedding.md")]
pub struct Embedding;
