// The output pass: a finished frame written into a host's colour and depth targets, so that the
// host's own geometry, drawn with the same view-projection (reversed-Z, infinite far plane), is
// depth-tested against the terrain. One full-screen triangle: each pixel's colour as the frame
// drew it, and its depth from the view distance the frame kept (`depth_bytes` in raster.wgsl) or,
// for the reference, from its hit position. Sky and anything not in front of the eye lie at
// depth 0, where reversed-Z clears.

struct Output {
    // Relative to the frame's origin, as the reference's positions are.
    view_proj: mat4x4<f32>,
    near: f32,
    width: u32,
    height: u32,
    // 1: the host's colour target does not encode sRGB, so the shader does.
    encode_srgb: u32,
}

@group(0) @binding(0) var<uniform> output: Output;
#ifdef FROM_BUFFERS
@group(0) @binding(1) var<storage, read> colour_in: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> position_in: array<vec4<f32>>;
#else
@group(0) @binding(1) var colour_in: texture_2d<f32>;
@group(0) @binding(2) var depth_in: texture_2d<f32>;
#endif

struct VsOut {
    @builtin(position) position: vec4<f32>,
}

@vertex
fn vs(@builtin(vertex_index) i: u32) -> VsOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: VsOut;
    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

struct FsOut {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

fn srgb(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(max(c, vec3<f32>(0.0)), vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

// Reversed-Z depth of a view distance: near / w, or 0 for sky and what is not in front.
fn depth_of(w: f32) -> f32 {
    if (!(w > 0.0) || w > 3.0e38) {
        return 0.0;
    }
    return clamp(output.near / w, 0.0, 1.0);
}

// SHORE: the scene can show water, whose specks the pass cleans up.
#ifdef SHORE
// What a pixel shows: 0 no ground of the sketch (sky, or the world beyond it), 1 land, 2 water.
// The frame's colour alpha is 0 on water (`water_alpha` in shading.wgsl), 1 elsewhere.
fn class_at(q: vec2<i32>) -> u32 {
    if (any(q < vec2<i32>(0)) || q.x >= i32(output.width) || q.y >= i32(output.height)) {
        return 0u;
    }
    let p = vec2<u32>(q);
#ifdef FROM_BUFFERS
    let i = p.y * output.width + p.x;
    let ground = position_in[i].w > 0.5;
    let alpha = colour_in[i].a;
#else
    let ground = depth_of(view_w_at(p)) > 0.0;
    let alpha = textureLoad(colour_in, p, 0).a;
#endif
    return select(0u, select(1u, 2u, alpha < 0.5), ground);
}

fn colour_at(q: vec2<i32>) -> vec3<f32> {
    let p = vec2<u32>(q);
#ifdef FROM_BUFFERS
    return colour_in[p.y * output.width + p.x].rgb;
#else
    return textureLoad(colour_in, p, 0).rgb;
#endif
}

const SIDES: array<vec2<i32>, 4> = array<vec2<i32>, 4>(
    vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1)
);

// Whether the land or water at `p` is a speck: a region of fewer than SPECK_PX pixels (sides
// touching), which the map reader sees as noise at the shore, not as a pool or an islet. Found
// by filling from `p` until SPECK_PX pixels are found or the region ends.
const SPECK_PX: u32 = 4u;
fn is_speck(p: vec2<i32>, kind: u32) -> bool {
    var found: array<vec2<i32>, 4>;
    found[0] = p;
    var n = 1u;
    for (var i = 0u; i < n && n < SPECK_PX; i++) {
        for (var s = 0u; s < 4u && n < SPECK_PX; s++) {
            let q = found[i] + SIDES[s];
            var seen = false;
            for (var j = 0u; j < n; j++) {
                seen = seen || all(found[j] == q);
            }
            if (!seen && class_at(q) == kind) {
                found[n] = q;
                n++;
            }
        }
    }
    return n < SPECK_PX;
}

// The colour at `p`, a speck of land or water taking the colour of the region around it.
fn cleaned(p: vec2<i32>, colour: vec3<f32>) -> vec3<f32> {
    let kind = class_at(p);
    if (kind == 0u || !is_speck(p, kind)) {
        return colour;
    }
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var s = 0u; s < 4u; s++) {
        let q = p + SIDES[s];
        let c = class_at(q);
        if (c != 0u && c != kind) {
            sum += colour_at(q);
            count += 1.0;
        }
    }
    return select(colour, sum / max(count, 1.0), count > 0.0);
}
#endif

#ifdef FROM_BUFFERS
#else
// The view distance the frame kept at `p` (`depth_bytes` in raster.wgsl).
fn view_w_at(p: vec2<u32>) -> f32 {
    let b = vec4<u32>(round(textureLoad(depth_in, p, 0) * 255.0));
    return bitcast<f32>(b.x | (b.y << 8u) | (b.z << 16u) | (b.w << 24u));
}
#endif

@fragment
fn fs(in: VsOut) -> FsOut {
    let p = vec2<u32>(in.position.xy);
    var out: FsOut;
    var colour: vec3<f32>;
#ifdef FROM_BUFFERS
    let i = p.y * output.width + p.x;
    colour = colour_in[i].rgb;
    let hit = position_in[i];
    out.depth = 0.0;
    if (hit.w > 0.5) {
        let clip = output.view_proj * vec4<f32>(hit.xyz, 1.0);
        out.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    }
#else
    colour = textureLoad(colour_in, p, 0).rgb;
    out.depth = depth_of(view_w_at(p));
#endif
#ifdef SHORE
    colour = cleaned(vec2<i32>(p), colour);
#endif
    if (output.encode_srgb == 1u) {
        colour = srgb(colour);
    }
    out.colour = vec4<f32>(colour, 1.0);
    return out;
}
