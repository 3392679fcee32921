// The per-frame uniform block, shared by every pass. Its Rust twin is `gpu::FrameUniforms`.
// Positions are metres relative to the frame origin (the camera's ground point), f32.
#import constants

struct Octave {
    lattice: vec2<i32>,   // whole lattice cell of the frame origin (f64 split on the CPU)
    phase: vec2<f32>,     // fraction of the frame origin inside that cell
    scale: f32,           // lattice cells per metre
    weight: f32,          // w_k, metres
    seed: u32,
    pad: u32,
}

// The debug views, `frame.camera.view`: the Rust enum `View` in declaration order (tests/shaders.rs
// checks each name and number).
const VIEW_SHADED: u32 = 0u;
const VIEW_WIREFRAME: u32 = 1u;
const VIEW_SPLIT_OCTAVE: u32 = 2u;
const VIEW_IMPORTANCE: u32 = 3u;
const VIEW_NORMALS: u32 = 4u;
const VIEW_COVERAGE: u32 = 5u;
const VIEW_SURFACE: u32 = 6u;

// The frame's uniform block, one struct per concern, each with its Rust twin of the same name in
// `gpu::uniforms` (tests/shaders.rs checks every field's offset and size). `pad` fields only fill
// to the uniform address space's 16-byte alignment; no value lives in a spare lane.

// The eye and the image.
struct CameraUniforms {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    pixel_scale: f32,            // 2·tan(fov/2)/height: a pixel's footprint per metre of distance
    image: vec2<u32>,            // width, height in pixels
    view: u32,                   // debug view, one of VIEW_*
    pad: u32,
}

// The sun, the air and what lies beyond the sketch (src/light.rs).
struct ShadingUniforms {
    sun: vec3<f32>,              // direction to the sun
    daylight: f32,               // the sky's share of its daylight (0 after dusk)
    sun_top: vec3<f32>,          // the sunlight above the air, linear RGB
    air_mass: f32,               // the sun's relative air mass
    sky_light: vec3<f32>,        // the sky's light on level ground at sea level
    exposure: f32,               // light's factor before the tone map
    haze_per_m: f32,             // haze extinction at sea level
    haze_height_m: f32,          // haze scale height
    outside: u32,                // beyond the sketch: 0 nothing, 1 a plain, 2 the sea
    plain_m: f32,                // the level the margin fades to: the plain's height or the sea floor
    margin_m: f32,               // the margin's width (src/beyond.rs)
    margin_lo_m: f32,            // the lowest and highest the margin's ground reaches
    margin_hi_m: f32,
    pad: f32,
}

// The sketch's pyramid in the atlas buffer.
struct AtlasUniforms {
    level: array<vec4<u32>, 16>, // per level: width, height, first texel (streamed: first page-table entry), 0 (streamed: tiles a row)
    offset: vec2<f32>,           // frame origin − atlas origin
    inv_spacing: vec2<f32>,
    d_atlas: f32,
    levels: u32,                 // mip levels in use
    max_m: f32,                  // the sketch's highest height (a ray above it hits nothing)
    water_m: f32,                // the water's surface: the terrain function is never below it
    tile: u32,                   // streamed: interior nodes per tile side
    border: u32,                 // streamed: border nodes on each side of a tile
    pad: vec2<u32>,
}

// The procedural octaves.
struct DetailUniforms {
    octave: array<Octave, MAX_OCTAVES>,
    octaves: u32,
    bias: f32,
    shore_m: f32,                // the band above the water over which the octaves fade in
    pad: u32,
}

// The mesh the terrain pass draws: the warped geometry image (or GeoMipMap's baked grid).
struct MeshUniforms {
    phi_offset: vec2<f32>,       // sketch-map region corner − frame origin
    mesh_offset: vec2<f32>,      // origin of the mesh's coordinates − frame origin (0 for warped)
    n: u32,                      // warp size (128)
    mesh: u32,                   // detailed geometry image size (512)
    d0: f32,                     // sketch-map spacing: metres per warp texel
    importance_max: f32,         // the importance view's scale
    phi_s: vec2<f32>,            // the region's s axis in the world (x unless turned 45°)
    phi_t: vec2<f32>,            // its t axis (y unless turned)
}

// GeoMipMap's blocks.
struct BlockUniforms {
    cells: u32,                  // cells per block side
    index_bits: u32,             // bits of the block-local vertex in an index
    levels: u32,
    pad: u32,
}

// The reference's ray march.
struct MarchUniforms {
    lo: f32,                     // lowest ground, with the detail's reach
    hi: f32,                     // highest ground, with the detail's reach
    step: f32,                   // step as a fraction of the height above ground
    pad: f32,
}

struct Frame {
    camera: CameraUniforms,
    shading: ShadingUniforms,
    atlas: AtlasUniforms,
    detail: DetailUniforms,
    mesh: MeshUniforms,
    blocks: BlockUniforms,
    march: MarchUniforms,
}

// The octave level a footprint of `footprint` metres shows: log2(d_atlas / footprint), the
// pixel octave (octave k is drawn with share clamp(o − k + 1, 0, 1)).
fn footprint_octave(footprint: f32) -> f32 {
    return log2(frame.atlas.d_atlas / max(footprint, 1e-6));
}

// The share of the octaves ground whose sketch height is `z` carries: none at the water's
// surface, all from `shore_m` (twice the octaves' reach) above it, a smoothstep between. Within
// the band the share is below (z − water) / reach, so the octaves never take land below the
// water nor leave a pool on it: the shore is the sketch's own contour at every distance
// (`detail::shore` is the twin).
fn shore(z: f32) -> f32 {
    if (frame.detail.shore_m <= 0.0) {
        return 1.0;
    }
    return smoothstep(frame.atlas.water_m, frame.atlas.water_m + frame.detail.shore_m, z);
}

// The sketch's rectangle in frame coordinates (metres from the frame origin): its south-west and
// north-east nodes. The reference's march box, the mesh's edge and the world beyond all end there.
fn sketch_lo() -> vec2<f32> {
    return -frame.atlas.offset;
}

fn sketch_hi() -> vec2<f32> {
    return sketch_lo() + vec2<f32>(frame.atlas.level[0].xy - 1u) / frame.atlas.inv_spacing;
}

// Whether `local` lies on the sketch's rectangle, within `margin` metres.
fn on_sketch(local: vec2<f32>, margin: f32) -> bool {
    return all(local >= sketch_lo() - margin) && all(local <= sketch_hi() + margin);
}

// Where a mesh vertex at `p` is drawn: on the sketch's edge when it lies beyond it (a warped
// region turned by 45° excepted: `drawn_xy` in warp_zoom.wgsl). The warped region is a square on
// a lattice and the baked grid the square enclosing the sketch, and both reach past it; a cell
// the edge crosses then ends there with the edge's own heights at its vertices, as the
// reference's surface ends, not a line to a vertex beyond. The cells between two such vertices
// stand in the edge's vertical plane, and the terrain pass leaves them out (`inside_sketch` in
// terrain.wgsl).
fn on_sketch_edge(p: vec2<f32>) -> vec2<f32> {
    return clamp(p, sketch_lo(), sketch_hi());
}
