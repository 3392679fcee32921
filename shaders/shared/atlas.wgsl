// Sampling the sketch atlas: Catmull-Rom bicubic on one mip level, linear between two.
// The twin of src/gpu/cpu_twin.rs's `atlas_height`.

@group(0) @binding(1) var atlas: texture_2d<f32>;

fn catmull_rom(f: f32) -> vec4<f32> {
    let f2 = f * f;
    let f3 = f2 * f;
    return vec4<f32>(
        -0.5 * f3 + f2 - 0.5 * f,
        1.5 * f3 - 2.5 * f2 + 1.0,
        -1.5 * f3 + 2.0 * f2 + 0.5 * f,
        0.5 * f3 - 0.5 * f2,
    );
}

// Bicubic height on level `l` at level-0 texel coordinates `uv`.
fn atlas_level(uv: vec2<f32>, l: u32) -> f32 {
    let s = f32(1u << l);
    let x = (uv - vec2<f32>((s - 1.0) * 0.5)) / s;
    let size = vec2<i32>(textureDimensions(atlas, l));
    let i = floor(x);
    let f = x - i;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    var h = 0.0;
    for (var b = 0; b < 4; b++) {
        let y = clamp(i32(i.y) - 1 + b, 0, size.y - 1);
        var row = 0.0;
        for (var a = 0; a < 4; a++) {
            let xx = clamp(i32(i.x) - 1 + a, 0, size.x - 1);
            row += wx[a] * textureLoad(atlas, vec2<i32>(xx, y), i32(l)).r;
        }
        h += wy[b] * row;
    }
    return h;
}

// Height at `local` (metres from the frame origin) for a mesh spacing of `spacing` metres.
fn atlas_height(local: vec2<f32>, spacing: f32) -> f32 {
    let uv = (local + frame.atlas_offset) * frame.atlas_inv_spacing;
    let lod = clamp(log2(max(spacing, 1e-6) / frame.d_atlas), 0.0, f32(frame.levels - 1u));
    let l0 = u32(lod);
    let t = lod - f32(l0);
    let a = atlas_level(uv, l0);
    if (t <= 0.0 || l0 + 1u >= frame.levels) {
        return a;
    }
    return a + (atlas_level(uv, l0 + 1u) - a) * t;
}
