// The terrain function's surface at a footprint of `footprint` metres: the sketch (bicubic, at the
// footprint's pyramid level) plus each octave k weighted by its pixel share
// b_k = clamp(o_px − k + 1, 0, 1). The reference ray-marches it and shades with its gradient; with
// PIXEL_NORMALS the mesh modes shade with that same gradient at their pixels, so a mesh only
// decides where the surface is, and a mesh that slides between frames does not change its light.

#import atlas
#ifdef NOISE
#import noise
#endif

// The octaves down to the footprint, each weighted by b_k: value (x) and gradient (yz).
fn surface_octaves(p: vec2<f32>, footprint: f32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
#ifdef NOISE
    let o_px = footprint_octave(footprint);
    let last = min(frame.detail.octaves, u32(max(ceil(o_px), 0.0)));
    for (var k = 1u; k <= last; k++) {
        let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
        sum += frame.detail.octave[k - 1u].weight * b * octave_local(frame.detail.octave[k - 1u], p);
    }
#endif
    return sum;
}

// The terrain function at `p`: the ground, or the water's flat surface over it.
fn surface_height(p: vec2<f32>, footprint: f32) -> f32 {
    let sketch = atlas_height(p, footprint);
    return max(sketch + shore(sketch) * surface_octaves(p, footprint).x, frame.atlas.water_m);
}

// Its gradient; level on the water.
fn surface_gradient(p: vec2<f32>, footprint: f32) -> vec2<f32> {
    if (surface_height(p, footprint) <= frame.atlas.water_m) {
        return vec2<f32>(0.0);
    }
    return land_gradient(p, footprint);
}

// The ground's gradient (no water): the octaves' analytically, the sketch's by central
// differences of the bicubic.
// The shore's fade scales the octaves' gradient and leaves its own out (a slope of at most
// reach / shore_m, a half, times the octaves' value).
fn land_gradient(p: vec2<f32>, footprint: f32) -> vec2<f32> {
    let fade = shore(atlas_height(p, footprint));
    return sketch_gradient(p, footprint) + fade * surface_octaves(p, footprint).yz;
}
