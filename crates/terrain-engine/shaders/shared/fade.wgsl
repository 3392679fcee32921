// Bump fade (`detail.bump_fade`), imported with BUMP_FADE by the terrain and planet passes.
//
// Bump detail has no parallax. Where the mesh lacks the height of the octaves it bumps, the ray
// meets the true surface away from where it meets the mesh, by that height along the normal over
// the cosine of the ray's incidence, so at grazing angles a bump octave drawn whole is the
// reference's pattern shifted by a fraction of its wavelength or more. For a shift δ of spread σ,
// an octave of frequency f keeps E[cos 2πfδ] = exp(−2π²f²σ²) =: ρ of its correlation with the
// true pattern; drawn with weight ρ its expected squared error is (1 − ρ²) of its variance, below
// both the full copy's 2(1 − ρ) and leaving it out's 1.
//
// The exponent is fitted, not the model's: σ counts only the bumped octaves' height, not the
// mesh's own error nor, in GeoMipMap's coarse blocks, the octaves in neither its geometry nor its
// bump, so the true shift is larger. `FADE_SPECTRUM` multiplies 2π²σ² by the octave's lattice
// frequency squared (its noise frequency f_k is 1/1.6 of it: src/detail.rs's LATTICE_PER_CYCLE),
// so the model is 1/1.6² ≈ 0.39; the fitted factor is 2 (docs/decisions.md, “Bump fade”).
//
// A departure from `docs/design.md` (Procedural detail), whose octave k contributes w_k·n_k·(g_k +
// (1 − g_k)·b_k): with the fade the normal takes the bump share (1 − g_k)·b_k times this weight, in
// the mesh's normal and in the terrain function's normal that coarse ground takes (terrain.wgsl's
// `coarse_normal`); the geometry share and every height are as `docs/design.md` defines them.
// `detail.bump_fade = false` restores its definition.

const FADE_SPECTRUM: f32 = 2.0;
// The model's own factor, 1/1.6² (src/detail.rs's LATTICE_PER_CYCLE; tests/shaders.rs holds
// them equal), for the terrain function's normal on coarse ground (terrain.wgsl's
// `coarse_normal`; docs/decisions.md, “Fade of the coarse normal's octaves”).
const FADE_MODEL: f32 = 0.390625;
// The noise's RMS value per unit weight: src/detail.rs's NOISE_RMS (tests/shaders.rs holds them
// equal).
const FADE_NOISE_RMS: f32 = 0.31;
// Below this weight an octave's bump is not evaluated: it would turn the normal by less than a
// five-hundredth of the octave's slope.
const FADE_SKIP: f32 = 0.002;

// The variance (m²) of the shift along the ground where the surface lacks `height_var` m² of
// height variance, for a ray of unit direction `view` meeting ground of unit normal `n`, `up` the
// vertical: a height h moves the surface h·(n·up) along its normal, the ray's hit h·(n·up)/|v·n|
// along itself, and the part of that across `up` along the ground. (On level ground, h·tan i.)
fn fade_spread(height_var: f32, view: vec3<f32>, n: vec3<f32>, up: vec3<f32>) -> f32 {
    let c = max(abs(dot(view, n)), 0.02);
    let along = dot(n, up) * length(view - dot(view, up) * up) / c;
    return height_var * along * along;
}

// ρ^(spectrum / FADE_MODEL) for an octave of `scale` lattice cells per metre at shift variance
// `spread`: FADE_SPECTRUM for the bump, FADE_MODEL for the terrain function's normal.
fn bump_fade(scale: f32, spread: f32, spectrum: f32) -> f32 {
    return exp(-19.739209 * spectrum * scale * scale * spread);
}
