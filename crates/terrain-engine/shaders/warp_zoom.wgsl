// Warp & zoom: Φ (n², from the CPU stage) upsampled bilinearly to the mesh size, the height
// sampled from the atlas at Φ (bicubic, at the pyramid level of the vertex's pixel), the split
// octave o from the largest distance to the four neighbours (no finer than the pixel octave at
// the vertex), and noise octaves added as displacement up to it (octave ⌊o⌋+1 shared with the
// bump by g_k).
// Output: the detailed geometry image, (x, y, z, split octave) per vertex, metres from the frame
// origin. With CENTRES, also the height of each cell's centre (the mean of its corners), for
// mesh_split.wgsl to choose the cell's diagonal by.
// Rust twin: src/gpu/warp_zoom.rs (`vertex_cpu`, `centre_cpu`).

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
#import atlas
#ifdef DETAIL
#import noise
#endif

@group(0) @binding(2) var<storage, read> phi: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> detailed: array<vec4<f32>>;
#ifdef CENTRES
@group(0) @binding(4) var<storage, read_write> centres: array<f32>;
#endif

// Φ at warp coordinates `st` (bilinear), metres from the frame origin.
fn phi_at(st: vec2<f32>) -> vec2<f32> {
    let n = frame.mesh.n;
    let c = clamp(st, vec2<f32>(0.0), vec2<f32>(f32(n - 1u)));
    let i = min(vec2<u32>(c), vec2<u32>(n - 2u));
    let f = c - vec2<f32>(i);
    let p00 = phi[i.y * n + i.x];
    let p10 = phi[i.y * n + i.x + 1u];
    let p01 = phi[(i.y + 1u) * n + i.x];
    let p11 = phi[(i.y + 1u) * n + i.x + 1u];
    let q = mix(mix(p00, p10, f.x), mix(p01, p11, f.x), f.y);
    // Φ lies along the region's axes, turned 45° on a diagonal heading.
    return frame.mesh.phi_s * q.x + frame.mesh.phi_t * q.y + frame.mesh.phi_offset;
}

// The horizontal position of mesh vertex `ij` (clamped to the mesh), where Φ puts it.
fn mesh_xy(ij: vec2<i32>) -> vec2<f32> {
    let m = i32(frame.mesh.mesh);
    let c = clamp(ij, vec2<i32>(0), vec2<i32>(m - 1));
    return phi_at(vec2<f32>(c) * (f32(frame.mesh.n - 1u) / f32(frame.mesh.mesh - 1u)));
}

// Where a vertex Φ puts at `p` is drawn: on the sketch's edge where `p` lies beyond it
// (`on_sketch_edge`), in a region along x and y (and the bake's grid). A region turned by 45°
// keeps its vertices where Φ puts them: its rows cross the sketch's edges at 45°, and a vertex
// moved onto an edge across them can turn its cell over. Rejected: each moved along its column
// (the region's t axis) to where the column meets the edge, worst at the near corner, where the
// columns change from one edge to the other (docs/decisions.md, “Mesh ends at the
// sketch's edge”).
fn drawn_xy(p: vec2<f32>) -> vec2<f32> {
    if (frame.mesh.phi_s.y != 0.0) {
        return p;
    }
    return on_sketch_edge(p);
}

// The detailed surface at `p` for a mesh whose spacing there is `d_max` metres: (height, split
// octave).
fn detailed_at(p: vec2<f32>, d_max: f32) -> vec2<f32> {
    var o = log2(frame.atlas.d_atlas / max(d_max, 1e-6)) - frame.detail.bias;
    // The sketch's pyramid level is −o_sketch: without a camera (a bake), −o; with one, its
    // pixel octave's, the reference's level there or finer (sketch_octave_in_view in the Rust
    // twin).
    var o_sketch = o;
    // No finer than the pixel octave at the vertex: the reference's surface holds no more
    // (split_octave_in_view in the Rust twin). A bake has no camera (pixel_scale 0). The
    // distance is taken to the nearest height the sketch can have there, so that the sketch is
    // read once, at its final level (a streamed read marks its tiles as wanted).
    if (frame.camera.pixel_scale > 0.0) {
        let nearest = vec3<f32>(p, min(frame.camera.eye.z, frame.atlas.max_m));
        let footprint = distance(nearest, frame.camera.eye) * frame.camera.pixel_scale;
        o_sketch = footprint_octave(footprint);
        o = min(o, o_sketch);
    }
    var z = atlas_height(p, frame.atlas.d_atlas * exp2(-o_sketch));
#ifdef DETAIL
    let last = min(frame.detail.octaves, u32(max(ceil(o), 0.0)));
    var octaves = 0.0;
    for (var k = 1u; k <= last; k++) {
        let g = clamp(o - f32(k) + 1.0, 0.0, 1.0);
        octaves += frame.detail.octave[k - 1u].weight * g * octave_local(frame.detail.octave[k - 1u], p).x;
    }
    z += shore(z) * octaves;
#endif
    // Under the water the surface is the water's, flat.
    return vec2<f32>(max(z, frame.atlas.water_m), o);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.mesh.mesh || id.y >= frame.mesh.mesh) {
        return;
    }
    let ij = vec2<i32>(id.xy);
    let p = mesh_xy(ij);
    let east = mesh_xy(ij + vec2<i32>(1, 0));
    let north = mesh_xy(ij + vec2<i32>(0, 1));
    let d_max = max(
        max(distance(p, east), distance(p, mesh_xy(ij - vec2<i32>(1, 0)))),
        max(distance(p, north), distance(p, mesh_xy(ij - vec2<i32>(0, 1)))),
    );
    // The spacing (the split octave, a cell's side) stays Φ's, so the bake's grid keeps the
    // figures its blocks' measurement on tiles gives (src/tiles/blocks.rs).
    let drawn = drawn_xy(p);
    let z = detailed_at(drawn, d_max);
    detailed[id.y * frame.mesh.mesh + id.x] = vec4<f32>(drawn, z.x, z.y);
#ifdef CENTRES
    // The cell from this vertex to (s+1, t+1), at the spacing of its longest side.
    if (id.x + 1u < frame.mesh.mesh && id.y + 1u < frame.mesh.mesh) {
        let far = mesh_xy(ij + vec2<i32>(1, 1));
        let side = max(
            max(distance(p, east), distance(p, north)),
            max(distance(far, east), distance(far, north)),
        );
        let mean = 0.25 * (drawn + drawn_xy(east) + drawn_xy(north) + drawn_xy(far));
        centres[id.y * frame.mesh.mesh + id.x] = detailed_at(mean, side).x;
    }
#endif
}
