// Sampling the sketch atlas: Catmull-Rom bicubic on one pyramid level, linear between two.
// The twin of src/gpu/warp_zoom.rs's `atlas_height`.
//
// The pyramid lives in a read-only storage buffer, its levels one after another. A mip-mapped
// R32Float texture read with textureLoad gave wrong heights on llvmpipe (GL) in 8×8 workgroups,
// in lane 7 of each row (off by hundreds of metres against the CPU twin), and right ones with one
// invocation per workgroup; vertices of one workgroup read different mip levels. Plain loads from
// a buffer agree with the CPU twin to 1e-6 of the height range.

@group(0) @binding(1) var<storage, read> atlas: array<f32>;

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

fn atlas_texel(x: i32, y: i32, l: u32, size: vec2<i32>) -> f32 {
    let c = vec2<u32>(clamp(vec2<i32>(x, y), vec2<i32>(0), size - 1));
    return atlas[frame.atlas.level[l].z + c.y * frame.atlas.level[l].x + c.x];
}

// One row of four taps.
fn atlas_row(x: i32, y: i32, l: u32, size: vec2<i32>, w: vec4<f32>) -> f32 {
    var r = 0.0;
    r += w.x * atlas_texel(x - 1, y, l, size);
    r += w.y * atlas_texel(x, y, l, size);
    r += w.z * atlas_texel(x + 1, y, l, size);
    r += w.w * atlas_texel(x + 2, y, l, size);
    return r;
}

// Level-0 texel coordinates `uv` in level `l`'s texels (a level-l texel's centre lies at level-0
// coordinate 2^l·i + (2^l − 1)/2).
fn level_coords(uv: vec2<f32>, l: u32) -> vec2<f32> {
    let s = f32(1u << l);
    return (uv - vec2<f32>((s - 1.0) * 0.5)) / s;
}

// Bilinear height on level `l` at level-0 texel coordinates `uv`: a quarter of the bicubic's
// loads, for rays that take many samples (the sun's shadow).
fn atlas_bilinear(uv: vec2<f32>, l: u32) -> f32 {
    let x = level_coords(uv, l);
    let size = vec2<i32>(frame.atlas.level[l].xy);
    let i = vec2<i32>(floor(x));
    let f = x - floor(x);
    let a = mix(atlas_texel(i.x, i.y, l, size), atlas_texel(i.x + 1, i.y, l, size), f.x);
    let b = mix(atlas_texel(i.x, i.y + 1, l, size), atlas_texel(i.x + 1, i.y + 1, l, size), f.x);
    return mix(a, b, f.y);
}

// Bicubic height on level `l` at level-0 texel coordinates `uv`.
fn atlas_level(uv: vec2<f32>, l: u32) -> f32 {
    let x = level_coords(uv, l);
    let size = vec2<i32>(frame.atlas.level[l].xy);
    let i = floor(x);
    let f = x - i;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let ix = i32(i.x);
    let iy = i32(i.y);
    var h = 0.0;
    h += wy.x * atlas_row(ix, iy - 1, l, size, wx);
    h += wy.y * atlas_row(ix, iy, l, size, wx);
    h += wy.z * atlas_row(ix, iy + 1, l, size, wx);
    h += wy.w * atlas_row(ix, iy + 2, l, size, wx);
    return h;
}

// Height at `local` (metres from the frame origin) for a mesh spacing of `spacing` metres.
fn atlas_height(local: vec2<f32>, spacing: f32) -> f32 {
    let uv = (local + frame.atlas.offset) * frame.atlas.inv_spacing;
    let lod = clamp(log2(max(spacing, 1e-6) / frame.atlas.d_atlas), 0.0, f32(frame.atlas.levels - 1u));
    let l0 = u32(lod);
    let t = lod - f32(l0);
    let a = atlas_level(uv, l0);
    if (t <= 0.0 || l0 + 1u >= frame.atlas.levels) {
        return a;
    }
    return a + (atlas_level(uv, l0 + 1u) - a) * t;
}

// The weights' derivatives by f.
fn catmull_rom_d(f: f32) -> vec4<f32> {
    let f2 = f * f;
    return vec4<f32>(-1.5 * f2 + 2.0 * f - 0.5, 4.5 * f2 - 5.0 * f, -4.5 * f2 + 4.0 * f + 0.5, 1.5 * f2 - f);
}

// The bicubic's gradient on level `l` at level-0 texel coordinates `uv`, per level-0 texel.
fn atlas_level_gradient(uv: vec2<f32>, l: u32) -> vec2<f32> {
    let x = level_coords(uv, l);
    let size = vec2<i32>(frame.atlas.level[l].xy);
    let i = floor(x);
    let f = x - i;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let dx = catmull_rom_d(f.x);
    let dy = catmull_rom_d(f.y);
    let ix = i32(i.x);
    let iy = i32(i.y);
    var g = vec2<f32>(0.0);
    for (var r = 0; r < 4; r++) {
        let t = vec4<f32>(
            atlas_texel(ix - 1, iy - 1 + r, l, size),
            atlas_texel(ix, iy - 1 + r, l, size),
            atlas_texel(ix + 1, iy - 1 + r, l, size),
            atlas_texel(ix + 2, iy - 1 + r, l, size),
        );
        g += vec2<f32>(wy[r] * dot(dx, t), dy[r] * dot(wx, t));
    }
    return g / f32(1u << l);
}

// The sketch's gradient at `local` for a footprint of `footprint` metres: the derivative of the
// height `atlas_height` gives there (the bicubic on the footprint's pyramid level, linear
// between two), in metres per metre. Analytic rather than central differences: 32 loads where
// the four heights take 128.
fn sketch_gradient(local: vec2<f32>, footprint: f32) -> vec2<f32> {
    let uv = (local + frame.atlas.offset) * frame.atlas.inv_spacing;
    let lod = clamp(log2(max(footprint, 1e-6) / frame.atlas.d_atlas), 0.0, f32(frame.atlas.levels - 1u));
    let l0 = u32(lod);
    let t = lod - f32(l0);
    var g = atlas_level_gradient(uv, l0);
    if (t > 0.0 && l0 + 1u < frame.atlas.levels) {
        g = mix(g, atlas_level_gradient(uv, l0 + 1u), t);
    }
    return g * frame.atlas.inv_spacing;
}
