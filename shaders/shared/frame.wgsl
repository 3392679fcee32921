// The per-frame uniform block, shared by every pass. Its Rust twin is `gpu::FrameUniforms`.
// Positions are metres relative to the frame origin (the camera's ground point), f32.

struct Octave {
    lattice: vec2<i32>,   // whole lattice cell of the frame origin (f64 split on the CPU)
    phase: vec2<f32>,     // fraction of the frame origin inside that cell
    scale: f32,           // lattice cells per metre
    weight: f32,          // w_k, metres
    seed: u32,
    pad: u32,
}

// The debug views, `frame.view`: the Rust enum `View` in declaration order (tests/shaders.rs
// checks each name and number).
const VIEW_SHADED: u32 = 0u;
const VIEW_WIREFRAME: u32 = 1u;
const VIEW_SPLIT_OCTAVE: u32 = 2u;
const VIEW_IMPORTANCE: u32 = 3u;
const VIEW_NORMALS: u32 = 4u;
const VIEW_COVERAGE: u32 = 5u;

struct Frame {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    eye: vec4<f32>,              // xyz: eye; w: pixel scale (2·tan(fov/2)/height)
    phi_offset: vec2<f32>,       // sketch-map region corner − frame origin
    atlas_offset: vec2<f32>,     // frame origin − atlas origin
    atlas_inv_spacing: vec2<f32>,
    d_atlas: f32,
    bias: f32,
    n: u32,                      // warp size (128)
    mesh: u32,                   // detailed geometry image size (512)
    octaves: u32,
    levels: u32,                 // atlas mip levels
    sun: vec4<f32>,              // xyz: direction to the sun; w: sketch-map spacing d0
    view: u32,                   // debug view: 0 shaded, 1 wireframe, 2 split octave, 3 importance, 4 normals, 5 coverage
    importance_max: f32,
    mesh_offset: vec2<f32>,      // origin of the mesh's coordinates − frame origin (0 for warped)
    octave: array<Octave, 24>,
    turbulence: array<Octave, 2>,
    // The atlas pyramid's levels in the atlas buffer: (width, height, first texel, 0).
    level: array<vec4<u32>, 16>,
    // GeoMipMap blocks: cells per side, bits of the block-local vertex in an index, levels, 0.
    block: vec4<u32>,
    // Reference ray march: lowest and highest ground (with the detail's reach), step factor, 0.
    march: vec4<f32>,
    // Image width and height in pixels, 0, 0.
    image: vec4<u32>,
}
