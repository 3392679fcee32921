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
    ctx: &terrain_engine::GpuContext,
    scene: &terrain_engine::Scene,
    atlas: &terrain_engine::sketch::Atlas,
    mode: terrain_engine::Mode,
    view: terrain_engine::View,
    camera: &terrain_engine::Camera,
) -> terrain_engine::Result<terrain_engine::Work> {
    let mut r =
        terrain_engine::Renderer::counting_work(ctx.clone(), scene, atlas.clone(), mode, view)?;
    r.render_settled(camera)?
        .work
        .ok_or(terrain_engine::Error::Internal(
            "a counting renderer's frame carries its work",
        ))
}
