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
    let b = vec4<u32>(round(textureLoad(depth_in, p, 0) * 255.0));
    let bits = b.x | (b.y << 8u) | (b.z << 16u) | (b.w << 24u);
    out.depth = depth_of(bitcast<f32>(bits));
#endif
    if (output.encode_srgb == 1u) {
        colour = srgb(colour);
    }
    out.colour = vec4<f32>(colour, 1.0);
    return out;
}
