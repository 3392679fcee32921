//! Evaluation: image [`metrics`] against the ray-marched reference, the [`compare`] sweeps and
//! their reports, and the [`plot`]s they draw.

pub mod compare;
pub mod metrics;
pub mod plot;
