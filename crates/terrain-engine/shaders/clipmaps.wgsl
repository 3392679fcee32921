// Spherical clipmaps (Clasen & Hege, *Terrain Rendering using Spherical Clipmaps*, 2006): each ring
// vertex of the static hemisphere drawn this frame, and the nadir, carried to the terrain. Its map
// coordinates come from its offset and the nadir (eq. 1–4, in the precise form of sphere.wgsl's
// `map_offset`), its height from the global sketch at the pyramid level of its spacing (trilinear:
// continuous across rings and levels, so none pops) plus the octaves up to its split octave. Output
// per vertex: (x, y, z, its height before the sea covers it), metres in the nadir's tangent frame
// from the sphere's point under the camera. (The split octave follows from the ring alone; the
// planet pass works it out again, and keeps the unclamped height, which tells a lake from the
// geometry's rounding.) Rust twin: src/gpu/clipmaps.rs (`vertex_cpu`).

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<uniform> planet: Planet;
#import sphere

@group(0) @binding(3) var<storage, read> hemisphere: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> vertices: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x > planet.vertex_count) {
        return;
    }
    // The last invocation computes the nadir.
    let i = select(planet.first_vertex + id.x, planet.nadir, id.x == planet.vertex_count);
    let v = hemisphere[i];
    let spacing = ring_spacing(v.w);
    var h = planet_sketch(planet_texel_of(v), spacing);
    let o = log2(frame.atlas.d_atlas / spacing) - planet.bias;
#ifdef NOISE
    let rel = sphere_rel(v);
    let last = min(planet.octaves, u32(max(ceil(o), 0.0)));
    for (var k = 1u; k <= last; k++) {
        let g = clamp(o - f32(k) + 1.0, 0.0, 1.0);
        h += planet.octave[k - 1u].weight * g * octave_rel(planet.octave[k - 1u], rel).x;
    }
#endif
    let ground = max(h, planet.water_m);
    let rh = planet.radius + ground;
    vertices[i] = vec4<f32>(rh * v.x, rh * v.y, ground - rh * v.z, h);
}
