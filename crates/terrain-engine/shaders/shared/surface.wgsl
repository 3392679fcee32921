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

// The margin's ground at distance `d` beyond an edge point of height `edge` and outward slope
// `slope`: the edge continued along its slope and faded to the level beyond over the margin,
// within the span of the sketch and the level (the twin of src/beyond.rs's `Beyond::ground`).
fn margin_ground(edge: f32, slope: f32, d: f32) -> f32 {
    let m = frame.shading.margin_m;
    let level = frame.shading.plain_m;
    if (d >= m) {
        return level;
    }
    let t = d / m;
    let u = (1.0 - t) * (1.0 - t) * (1.0 - t);
    let h = level + (edge - level) * margin_fade(d) + slope * d * u;
    return clamp(h, frame.shading.margin_lo_m, frame.shading.margin_hi_m);
}

// The margin's fade: 1 at the sketch's edge, 0 from the margin's width on, flat at both ends.
fn margin_fade(d: f32) -> f32 {
    let t = clamp(d / frame.shading.margin_m, 0.0, 1.0);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

// The ground beyond the sketch at `p`, off its rectangle (`sketch.outside` a plain or the sea):
// the margin from the nearest edge point's height and slope at the footprint, with the octaves
// fading alike, then the level; before the water.
fn beyond_ground(p: vec2<f32>, footprint: f32) -> f32 {
    let c = on_sketch_edge(p);
    let off = p - c;
    let d = length(off);
    if (d >= frame.shading.margin_m) {
        return frame.shading.plain_m;
    }
    // The edge read ever more broadly outward, so its profile does not streak across the margin.
    let broad = max(footprint, 0.5 * d);
    let edge = atlas_height_gradient(c, broad);
    var slope = 0.0;
    if (d > 0.0) {
        slope = dot(edge.yz, off) / d;
    }
    let ground = margin_ground(edge.x, slope, d);
    return ground + margin_fade(d) * shore(ground) * surface_octaves(p, footprint).x;
}

// The surface beyond the sketch at `p`: its ground, or the water over it.
fn beyond_surface(p: vec2<f32>, footprint: f32) -> f32 {
    return max(beyond_ground(p, footprint), frame.atlas.water_m);
}

// The margin's ground at `local` from the edge's bilinear height on level `l`, without the
// edge's slope or the octaves: for rays that take many samples (the sun's shadow) and a ramp's
// colour, which read the sketch bilinearly too.
fn margin_bilinear(local: vec2<f32>, l: u32) -> f32 {
    let c = on_sketch_edge(local);
    let d = distance(local, c);
    // The edge read ever more broadly outward, as `beyond_ground` reads it, linear between levels
    // so no level's end draws a line along the margin.
    let top = f32(frame.atlas.levels - 1u);
    let broad = clamp(log2(max(0.5 * d / frame.atlas.d_atlas, 1.0)), f32(l), top);
    let l0 = u32(broad);
    let uv = (c + frame.atlas.offset) * frame.atlas.inv_spacing;
    var edge = atlas_bilinear(uv, l0);
    if (broad > f32(l0) && l0 + 1u < frame.atlas.levels) {
        edge = mix(edge, atlas_bilinear(uv, l0 + 1u), broad - f32(l0));
    }
    return margin_ground(edge, 0.0, d);
}

// The part [t0, t1] of the ray from `eye` along `dir` inside the box `lo`…`hi`, or t0 > t1.
fn box_span(eye: vec3<f32>, dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    var t0 = 0.0;
    var t1 = 3.0e38;
    for (var a = 0; a < 3; a++) {
        if (abs(dir[a]) < 1e-12) {
            if (eye[a] < lo[a] || eye[a] > hi[a]) {
                return vec2<f32>(1.0, 0.0);
            }
        } else {
            let ta = (lo[a] - eye[a]) / dir[a];
            let tb = (hi[a] - eye[a]) / dir[a];
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    return vec2<f32>(t0, t1);
}

// The ground's bilinear height at `local` on level `l`: the sketch on its rectangle, the margin
// beyond it (the sketch's edge, clamped, over the void).
fn ground_bilinear(local: vec2<f32>, l: u32) -> f32 {
    if (frame.shading.outside == 0u || on_sketch(local, 0.0)) {
        return atlas_bilinear((local + frame.atlas.offset) * frame.atlas.inv_spacing, l);
    }
    return margin_bilinear(local, l);
}
