// Sampling the sketch atlas: Catmull-Rom bicubic on one pyramid level, linear between two.
// The twin of src/gpu/warp_zoom.rs's `atlas_height`.
//
// The pyramid lives in a read-only storage buffer. A mip-mapped R32Float texture read with
// textureLoad gives wrong heights on llvmpipe (GL) in 8×8 workgroups, in lane 7 of each row (off
// by hundreds of metres against the CPU twin), and right ones with one invocation per workgroup;
// vertices of one workgroup read different mip levels. Plain loads from a buffer agree with the
// CPU twin to 1e-6 of the height range.
//
// Whole (the default): the levels one after another, level l's first texel at level[l].z.
// STREAMED (a tile pyramid through the tile cache, src/tiles/cache.rs): the buffer holds pages,
// each one tile of side² texels with its border, and after them the page table, one entry per
// tile of every level (level l's first float at level[l].z, level[l].w tiles a row). An entry is
// two exact floats: page·256 + fade (fade 255: fully arrived) and the level of the tile in that
// page — the entry's own, or where its tile is not resident, its finest resident ancestor's (the
// coarsest levels always are). Every lookup leaves a mark in `wanted` (1: missing, 2: used),
// which the cache reads back after the frame to load and to keep. A tile that has just arrived
// blends in over the next coarser resident level as its fade rises, so nothing pops.

#import work

@group(0) @binding(1) var<storage, read> atlas: array<f32>;
#ifdef STREAMED
@group(0) @binding(7) var<storage, read_write> wanted: array<u32>;
#endif

// Where a sample's texels are read: the index of node `origin` of level l, the row stride, and
// the level's size (loads clamp to its edge, like a texture sampler).
struct Texels {
    base: u32,
    stride: u32,
    origin: vec2<i32>,
    size: vec2<i32>,
}

fn load(t: Texels, x: i32, y: i32) -> f32 {
    count_atlas_tap();
    let c = vec2<u32>(clamp(vec2<i32>(x, y), vec2<i32>(0), t.size - 1) - t.origin);
    return atlas[t.base + c.y * t.stride + c.x];
}

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

// One row of four taps.
fn atlas_row(t: Texels, x: i32, y: i32, w: vec4<f32>) -> f32 {
    var r = 0.0;
    r += w.x * load(t, x - 1, y);
    r += w.y * load(t, x, y);
    r += w.z * load(t, x + 1, y);
    r += w.w * load(t, x + 2, y);
    return r;
}

// Level-0 texel coordinates `uv` in level `l`'s texels (a level-l texel's centre lies at level-0
// coordinate 2^l·i + (2^l − 1)/2).
fn level_coords(uv: vec2<f32>, l: u32) -> vec2<f32> {
    let s = f32(1u << l);
    return (uv - vec2<f32>((s - 1.0) * 0.5)) / s;
}

// A level resolved for one sample: the level read, its texels, and how far it has arrived
// (below 1, the sample blends from `coarser`, the next resident level).
struct Resolved {
    level: u32,
    texels: Texels,
    fade: f32,
    coarser: u32,
    coarser_texels: Texels,
}

#ifdef STREAMED
// Level l's tile holding node `i` (clamped into the level).
fn tile_of(l: u32, i: vec2<i32>) -> vec2<u32> {
    let size = vec2<i32>(frame.atlas.level[l].xy);
    return vec2<u32>(clamp(i, vec2<i32>(0), size - 1)) / frame.atlas.tile;
}

// The index of the first float of level l's entry for tile `t`.
fn table_index(l: u32, t: vec2<u32>) -> u32 {
    return frame.atlas.level[l].z + 2u * (t.y * frame.atlas.level[l].w + t.x);
}

fn mark(index: u32, m: u32) {
    wanted[(index - frame.atlas.level[0].z) / 2u] = m;
}

// The tile a sample on level l reads around level-0 coordinates `uv`: the entry holds its own
// page, or (filled down by the cache) the page of its finest resident ancestor, with that tile's
// level r. The ancestor of tile t is t >> (r − l), clamped to level r's tiles; its page holds
// every node a bicubic sample on level r reads there (the two-node border covers the half-texel
// shift between levels). With `want`, the entry is marked missing when it stands in; the tile
// read is marked used. No loop up the levels: llvmpipe's compiler spends minutes on such a loop
// unrolled in a fragment shader.
struct Lookup {
    level: u32,
    page_fade: u32,
    texels: Texels,
}

fn lookup(uv: vec2<f32>, l: u32, want: bool) -> Lookup {
    let t = tile_of(l, vec2<i32>(floor(level_coords(uv, l))));
    let e = table_index(l, t);
    let page_fade = u32(atlas[e]);
    let r = u32(atlas[e + 1u]);
    let tiles = vec2<u32>(frame.atlas.level[r].w, (frame.atlas.level[r].y + frame.atlas.tile - 1u) / frame.atlas.tile);
    let a = min(t >> vec2<u32>(r - l), tiles - 1u);
    if (r == l) {
        mark(e, 2u);
    } else {
        if (want) {
            mark(e, 1u);
        }
        mark(table_index(r, a), 2u);
    }
    let side = frame.atlas.tile + 2u * frame.atlas.border;
    let page = page_fade >> 8u;
    let origin = vec2<i32>(a * frame.atlas.tile) - i32(frame.atlas.border);
    return Lookup(r, page_fade, Texels(page * side * side, side, origin, vec2<i32>(frame.atlas.level[r].xy)));
}

// The finest resident level at or coarser than `l` around `uv`, and while it blends in, the next
// resident one under it (read as it is: a tile blending in does not ask for its parent).
fn resolve(uv: vec2<f32>, l: u32) -> Resolved {
    let a = lookup(uv, l, true);
    let fade = f32(a.page_fade & 255u) / 255.0;
    if (fade >= 1.0 || a.level + 1u >= frame.atlas.levels) {
        return Resolved(a.level, a.texels, 1.0, a.level, a.texels);
    }
    let b = lookup(uv, a.level + 1u, false);
    return Resolved(a.level, a.texels, fade, b.level, b.texels);
}
#else
fn whole_texels(l: u32) -> Texels {
    let size = vec2<i32>(frame.atlas.level[l].xy);
    return Texels(frame.atlas.level[l].z, frame.atlas.level[l].x, vec2<i32>(0), size);
}

fn resolve(uv: vec2<f32>, l: u32) -> Resolved {
    let t = whole_texels(l);
    return Resolved(l, t, 1.0, l, t);
}
#endif

fn bilinear_in(t: Texels, uv: vec2<f32>, l: u32) -> f32 {
    let x = level_coords(uv, l);
    let i = vec2<i32>(floor(x));
    let f = x - floor(x);
    let a = mix(load(t, i.x, i.y), load(t, i.x + 1, i.y), f.x);
    let b = mix(load(t, i.x, i.y + 1), load(t, i.x + 1, i.y + 1), f.x);
    return mix(a, b, f.y);
}

// Bilinear height on level `l` at level-0 texel coordinates `uv`: a quarter of the bicubic's
// loads, for rays that take many samples (the sun's shadow).
fn atlas_bilinear(uv: vec2<f32>, l: u32) -> f32 {
    let r = resolve(uv, l);
    let h = bilinear_in(r.texels, uv, r.level);
    if (r.fade >= 1.0) {
        return h;
    }
    return mix(bilinear_in(r.coarser_texels, uv, r.coarser), h, r.fade);
}

fn bicubic_in(t: Texels, uv: vec2<f32>, l: u32) -> f32 {
    let x = level_coords(uv, l);
    let i = floor(x);
    let f = x - i;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let ix = i32(i.x);
    let iy = i32(i.y);
    var h = 0.0;
    h += wy.x * atlas_row(t, ix, iy - 1, wx);
    h += wy.y * atlas_row(t, ix, iy, wx);
    h += wy.z * atlas_row(t, ix, iy + 1, wx);
    h += wy.w * atlas_row(t, ix, iy + 2, wx);
    return h;
}

// Bicubic height on level `l` at level-0 texel coordinates `uv`.
fn atlas_level(uv: vec2<f32>, l: u32) -> f32 {
    let r = resolve(uv, l);
    let h = bicubic_in(r.texels, uv, r.level);
    if (r.fade >= 1.0) {
        return h;
    }
    return mix(bicubic_in(r.coarser_texels, uv, r.coarser), h, r.fade);
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

// The sketch's gradient at `local` for a footprint of `footprint` metres: the derivative of the
// height `atlas_height` gives there (the bicubic on the footprint's pyramid level, linear
// between two), in metres per metre. Analytic rather than central differences: 32 loads where
// the four heights take 128.
fn sketch_gradient(local: vec2<f32>, footprint: f32) -> vec2<f32> {
    return atlas_height_gradient(local, footprint).yz;
}

// The bicubic's height (x) and gradient per level-0 texel (yz) on level `l`, from one set of 16
// loads: the gradient alone costs the same, and rays beyond the sketch need both at every step.
fn height_gradient_in(t: Texels, uv: vec2<f32>, l: u32) -> vec3<f32> {
    let x = level_coords(uv, l);
    let i = floor(x);
    let f = x - i;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let dx = catmull_rom_d(f.x);
    let dy = catmull_rom_d(f.y);
    let ix = i32(i.x);
    let iy = i32(i.y);
    var h = vec3<f32>(0.0);
    for (var r = 0; r < 4; r++) {
        let v = vec4<f32>(
            load(t, ix - 1, iy - 1 + r),
            load(t, ix, iy - 1 + r),
            load(t, ix + 1, iy - 1 + r),
            load(t, ix + 2, iy - 1 + r),
        );
        h += vec3<f32>(wy[r] * dot(wx, v), wy[r] * dot(dx, v), dy[r] * dot(wx, v));
    }
    return vec3<f32>(h.x, h.yz / f32(1u << l));
}

fn atlas_level_height_gradient(uv: vec2<f32>, l: u32) -> vec3<f32> {
    let r = resolve(uv, l);
    let h = height_gradient_in(r.texels, uv, r.level);
    if (r.fade >= 1.0) {
        return h;
    }
    return mix(height_gradient_in(r.coarser_texels, uv, r.coarser), h, r.fade);
}

// `atlas_height` and `sketch_gradient` at once (x: metres; yz: metres per metre).
fn atlas_height_gradient(local: vec2<f32>, footprint: f32) -> vec3<f32> {
    let uv = (local + frame.atlas.offset) * frame.atlas.inv_spacing;
    let lod = clamp(log2(max(footprint, 1e-6) / frame.atlas.d_atlas), 0.0, f32(frame.atlas.levels - 1u));
    let l0 = u32(lod);
    let t = lod - f32(l0);
    var h = atlas_level_height_gradient(uv, l0);
    if (t > 0.0 && l0 + 1u < frame.atlas.levels) {
        h = mix(h, atlas_level_height_gradient(uv, l0 + 1u), t);
    }
    return vec3<f32>(h.x, h.yz * frame.atlas.inv_spacing);
}
