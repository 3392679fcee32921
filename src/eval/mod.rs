//! Evaluation: image [`metrics`] against the ray-marched reference, the [`compare`] sweeps and
//! their reports (drawn with [`crate::plot`]), and how well a picture shows the land's form
//! ([`relief`]).

pub mod compare;
pub mod metrics;
pub mod relief;

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
