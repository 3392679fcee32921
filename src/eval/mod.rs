//! Evaluation: image [`metrics`] against the ray-marched reference, the [`compare`] sweeps and
//! their reports, the [`plot`]s they draw, and how well a picture shows the land's form
//! ([`relief`]).

pub mod compare;
pub mod metrics;
pub mod plot;
pub mod relief;

/// The `q` quantile of `v` (not empty) by nearest rank: the value at `⌊len·q⌋` in order, so
/// that the median of an odd count is its middle value, and each quartile of 15 frames has three
/// frames beyond it.
pub fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() as f64 * q) as usize).min(s.len() - 1)]
}

/// What the shading of `camera`'s frame of `scene` in `mode` evaluates, counted by a renderer in
/// the counting variant made on `ctx` for this and dropped after (its frame settled, as a
/// measured one is): `render --json`'s and `compare --work`'s figures.
pub fn counted_work(
    ctx: &terrain::GpuContext,
    scene: &terrain::Scene,
    atlas: &terrain::sketch::Atlas,
    mode: terrain::Mode,
    view: terrain::View,
    camera: &terrain::Camera,
) -> terrain::Result<terrain::Work> {
    let mut r = terrain::Renderer::counting_work(ctx.clone(), scene, atlas.clone(), mode, view)?;
    r.render_settled(camera)?
        .work
        .ok_or(terrain::Error::Internal(
            "a counting renderer's frame carries its work",
        ))
}
