// What the two raster passes (terrain, planet) share: the fragment's outputs and the sky's
// full-screen triangle. The pass declares `frame` (binding 0) before importing this.
#import shading

// The colour, and with POSITIONS each pixel's view depth (clip w, metres; 0 on sky), for
// recovering its ground position on the CPU. The rasteriser's own depth will not do: where the
// driver maps depth through −1..1 (wgpu's GL backend on llvmpipe), reversed-Z's near/w lands next
// to −1 and keeps a few bits; with the 5 cm near plane it put jacksboro-high's ground (20 km out)
// hundreds of metres off along the ray, a third of a pixel of screen-space error on every mode
// and every setting. The interpolated w keeps f32's relative precision everywhere. Its 32 bits go
// out as the four bytes of an 8-bit RGBA target, which every adapter renders and stores exactly;
// float targets are not renderable everywhere (llvmpipe's GL path), nor are depth textures
// copyable.
struct FragOut {
    @location(0) colour: vec4<f32>,
#ifdef POSITIONS
    @location(1) depth_bytes: vec4<f32>,
#endif
}

// An f32's 32 bits as the four bytes of an 8-bit RGBA target.
fn depth_bytes(depth: f32) -> vec4<f32> {
    let bits = bitcast<u32>(depth);
    let bytes = vec4<u32>(bits & 255u, (bits >> 8u) & 255u, (bits >> 16u) & 255u, bits >> 24u);
    return vec4<f32>(bytes) / 255.0;
}

fn frag_out(colour: vec3<f32>, view_w: f32) -> FragOut {
    var out: FragOut;
    // The debug views show their colours as they are; the picture goes through the tone map.
    out.colour = vec4<f32>(select(colour, display(colour), frame.camera.view <= VIEW_WIREFRAME), 1.0);
#ifdef POSITIONS
    out.depth_bytes = depth_bytes(view_w);
#endif
    return out;
}

// The wireframe view's weight of the picture at a fragment of mesh coordinates `grid`: 0 on a
// grid line, 1 a pixel or more from it. It takes derivatives, so it is found where the mesh is
// rasterised.
fn grid_line_weight(grid: vec2<f32>) -> f32 {
    let d = abs(fract(grid + 0.5) - 0.5) / max(fwidth(grid), vec2<f32>(1e-6));
    return clamp(min(d.x, d.y), 0.0, 1.0);
}

// The sky: one triangle over the whole screen, each pixel knowing its normalised device
// coordinates to find its view direction.
struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
}

@vertex
fn sky_vs(@builtin(vertex_index) vi: u32) -> SkyOut {
    let xy = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u)) * 2.0 - 1.0;
    var out: SkyOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    out.ndc = xy;
    return out;
}
