// Mesh split: the two triangles of each cell of the detailed geometry image, written as indices.
// A cell is split along the diagonal whose midpoint's height lies nearer the surface's at the
// cell's centre (warp_zoom.wgsl's `centres`), where both of the other diagonal's triangles are
// counter-clockwise; else along (s,t)–(s+1,t+1), the diagonal the warp's guard keeps unfolded.
// Rust twin: src/gpu/mesh_split.rs (`split_cpu`).

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(3) var<storage, read> detailed: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> centres: array<f32>;
@group(0) @binding(5) var<storage, read_write> indices: array<u32>;

fn ccw(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>) -> bool {
    let u = b - a;
    let v = c - a;
    return u.x * v.y - u.y * v.x > 0.0;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = frame.mesh.mesh;
    if (id.x + 1u >= m || id.y + 1u >= m) {
        return;
    }
    // Corners counter-clockwise from (s, t): a, b = (s+1, t), c = (s+1, t+1), d = (s, t+1).
    let a = id.y * m + id.x;
    let b = a + 1u;
    let c = a + m + 1u;
    let d = a + m;
    let pa = detailed[a];
    let pb = detailed[b];
    let pc = detailed[c];
    let pd = detailed[d];
    let z = centres[a];
    let along = abs(z - 0.5 * (pa.z + pc.z));
    let across = abs(z - 0.5 * (pb.z + pd.z));
    var q = array<u32, 6>(a, b, c, a, c, d);
    if (across < along && ccw(pa.xy, pb.xy, pd.xy) && ccw(pb.xy, pc.xy, pd.xy)) {
        q = array<u32, 6>(a, b, d, b, c, d);
    }
    let at = 6u * (id.y * (m - 1u) + id.x);
    for (var k = 0u; k < 6u; k++) {
        indices[at + k] = q[k];
    }
}
