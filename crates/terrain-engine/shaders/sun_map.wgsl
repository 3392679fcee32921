// The sketch's sun clearance map (src/gpu/sun_map.rs): shared/shading.wgsl's
// `sketch_sun_clearance` marched from the centre of every texel of every level of the whole
// sketch, made once per sun direction; the terrain pass then reads it (SUN_MAP) where it
// marched per pixel. One invocation per level-0 texel, which also fills the coarser levels' texel
// of its own index while there is one.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
#import shading

@group(0) @binding(10) var<storage, read_write> seen_out: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    // Made with SHADOWS alone (`gpu::sun_map`); other variants are only validated.
#ifdef SHADOWS
    let spacing = 1.0 / frame.atlas.inv_spacing;
    for (var l = 0u; l < frame.atlas.levels; l++) {
        let size = frame.atlas.level[l].xy;
        // Each level is at most the one before it: none further has this texel.
        if (id.x >= size.x || id.y >= size.y) {
            return;
        }
        let s = f32(1u << l);
        let uv = s * vec2<f32>(id.xy) + vec2<f32>(0.5 * (s - 1.0));
        let local = uv * spacing - frame.atlas.offset;
        seen_out[frame.atlas.level[l].z + id.y * size.x + id.x] = sketch_sun_clearance(local, l, false, true);
    }
#endif
}
