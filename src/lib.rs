//! The tools around the `terrain` library: the jobs users run ([`app`]: fly, batch, the window,
//! camera paths, outputs, progress bars) and the evaluation ([`eval`]: image metrics, `compare`,
//! its charts). The `terrain` binary (`src/bin/terrain/`) is their command line.
//!
//! Rules: everything here is built on the library's public API; nothing here is needed to embed
//! a terrain. Rejected: these modules inside the library, where every host would compile clap,
//! plotters, indicatif and the metrics.

pub mod app;
pub mod eval;

/// docs/embedding.md's host, compiled with the doctests so that the page cannot drift from the
/// API it describes.
#[cfg(doctest)]
#[doc = include_str!("../docs/embedding.md")]
pub struct Embedding;
