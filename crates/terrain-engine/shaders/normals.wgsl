// Normals of the detailed geometry image: central differences across the mesh grid.
// Rust twin: src/gpu/normals.rs (`normal_cpu`).

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(3) var<storage, read> detailed: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normals: array<vec4<f32>>;

fn vertex(ij: vec2<i32>) -> vec3<f32> {
    let m = i32(frame.mesh.mesh);
    let c = clamp(ij, vec2<i32>(0), vec2<i32>(m - 1));
    return detailed[u32(c.y * m + c.x)].xyz;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.mesh.mesh || id.y >= frame.mesh.mesh) {
        return;
    }
    let ij = vec2<i32>(id.xy);
    let ds = vertex(ij + vec2<i32>(1, 0)) - vertex(ij - vec2<i32>(1, 0));
    let dt = vertex(ij + vec2<i32>(0, 1)) - vertex(ij - vec2<i32>(0, 1));
    let c = cross(ds, dt);
    let len = length(c);
    // Rows run east and columns north (the warp guarantees it), so the cross product points up.
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (len > 0.0) {
        n = c / len;
    }
    normals[id.y * frame.mesh.mesh + id.x] = vec4<f32>(n, 0.0);
}
