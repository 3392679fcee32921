// The terrain pass: the detailed geometry image drawn as a quad mesh (two triangles per cell,
// split along the diagonal mesh_split.wgsl chose, or along (s,t)–(s+1,t+1)), shaded with the terrain function's normal at each pixel
// (PIXEL_NORMALS, shared with the reference) or with the mesh's normals plus per-pixel bump
// detail from the split octave up to the pixel's own octave (BUMP); procedural surface types, sun
// and sky light and aerial perspective. GEOMIPMAP draws a baked grid's blocks instead; with
// GRID_STREAMED (a tile pyramid) there is no baked grid, and each vertex reads the sketch.
// Also the sky, one full-screen triangle drawn after the ground where none was drawn; with DEFERRED
// (single-sampled frames) that triangle shades the ground too, from the G-buffer the mesh wrote.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
#ifdef GRID_STREAMED
#ifdef GEOMIPMAP
// GeoMipMap over a streamed sketch: no baked grid, no vertex normals (see grid_vertex).
#else
@group(0) @binding(3) var<storage, read> detailed: array<vec4<f32>>;
#endif
#else
@group(0) @binding(3) var<storage, read> detailed: array<vec4<f32>>;
#endif
#ifdef PIXEL_NORMALS
// Shading reads the terrain function's normal per pixel: no vertex normals are bound.
fn vertex_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(0.0, 0.0, 1.0);
}
#else
#ifdef GRID_STREAMED
#ifdef GEOMIPMAP
// A streamed grid's normals are differences of its vertices (level_normal): none are bound.
#else
@group(0) @binding(4) var<storage, read> normals: array<vec4<f32>>;
fn vertex_normal(i: u32) -> vec3<f32> {
    return normals[i].xyz;
}
#endif
#else
@group(0) @binding(4) var<storage, read> normals: array<vec4<f32>>;
fn vertex_normal(i: u32) -> vec3<f32> {
    return normals[i].xyz;
}
#endif
#endif
#ifdef IMPORTANCE_VIEW
@group(0) @binding(5) var<storage, read> importance: array<f32>;
#endif
#ifdef NOISE
#import noise
#endif
#ifdef BUMP
#import noise
#ifdef BUMP_FADE
#import fade
#endif
#endif
#import surface
#import shading
#import raster

@fragment
fn sky_fs(in: SkyOut) -> FragOut {
    let out = sky(in);
    add_work();
    return out;
}

fn sky(in: SkyOut) -> FragOut {
    if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(0.0), 0.0);
    }
    let far = frame.camera.inv_view_proj * vec4<f32>(in.ndc, 1e-4, 1.0);
    let dir = normalize(far.xyz / far.w - frame.camera.eye);
    // Depth 0, as the sky: the image metrics measure the mesh, not the world beyond it.
    let outside = beyond(frame.camera.eye, dir);
    return frag_out(mix(sky_colour(frame.camera.eye.z, dir), outside.rgb, outside.w), 0.0);
}

// The aerial perspective travels with the vertex (`inscatter`, `through`): the air between the
// eye and the ground varies smoothly over a triangle, and a vertex is evaluated once where a
// forward frame shades a pixel once for every triangle that covers it (docs/decisions.md,
// “Aerial perspective per vertex”). Deferred, the air takes 24 of the G-buffer's 64 bytes a
// pixel.
struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) split: f32,
    @location(3) grid: vec2<f32>,
    @location(4) inscatter: vec3<f32>,
    @location(5) through: vec3<f32>,
    @location(6) spacing: f32,
    // The view depth (clip w, metres along the view direction), for the position copy: exact to
    // f32's relative precision, where the rasteriser's depth is not (see raster.wgsl).
    @location(7) view_w: f32,
}

// A vertex at `p` (frame metres) with its clip position and the air between it and the eye;
// `spacing` is the mesh spacing its split octave stands for there (metres, see mesh_spacing).
fn vertex_out(p: vec3<f32>, n: vec3<f32>, split: f32, grid: vec2<f32>, spacing: f32) -> VsOut {
    let to_eye = frame.camera.eye - p;
    let dist = max(length(to_eye), 1e-3);
    let air = scatter(frame.camera.eye.z, -to_eye / dist, dist);
    var out: VsOut;
    out.clip = frame.camera.view_proj * vec4<f32>(p, 1.0);
    out.local = p;
    out.normal = n;
    out.split = split;
    out.grid = grid;
    out.inscatter = air.inscatter;
    out.through = air.through;
    out.spacing = spacing;
    out.view_w = out.clip.w;
    return out;
}

// The spacing the split octave stands for (o = log2(d_atlas / spacing) − bias in
// warp_zoom.wgsl): the mesh's own, or, where the mesh is finer than its pixels and the split
// octave stops at the pixel octave, the spacing whose octaves a pixel shows (then
// `shading_normal` takes the terrain function's normal, as the reference's).
fn mesh_spacing(split: f32) -> f32 {
    return frame.atlas.d_atlas * exp2(-(split + frame.detail.bias));
}

#ifdef GEOMIPMAP
// A block drawn this frame (the twin of geomipmap.rs's `BlockGpu`).
struct Block {
    origin: vec2<u32>,
    level: u32,
    pad: u32,
    side_level: vec4<u32>,   // the level governing each edge: S, E, N, W
    morph: vec4<f32>,        // own morph range: start, end; the interior's morph factor
    side_start: vec4<f32>,
    side_end: vec4<f32>,
}
@group(0) @binding(6) var<storage, read> blocks: array<Block>;

fn grid_index(g: vec2<u32>) -> u32 {
    return g.y * frame.mesh.mesh + g.x;
}

#ifdef GRID_STREAMED
// Grid vertex `g` (x, y from the grid's origin, z, split octave) evaluated where it is drawn, as
// warp_zoom.wgsl bakes it with Φ the identity: a grid over a tile pyramid samples the sketch at
// its own spacing (k = 0) with no octaves in it (baseline.rs refuses the rest), so the vertex is
// the sketch's bicubic height there, read through the tile cache, which the read marks.
fn grid_vertex(g: vec2<u32>) -> vec4<f32> {
    let d = frame.atlas.d_atlas;
    let p = vec2<f32>(min(g, vec2<u32>(frame.mesh.mesh - 1u))) * d;
    // Past the sketch's edge, on it, as the bake draws its vertices.
    let drawn = on_sketch_edge(p + frame.mesh.mesh_offset);
    let z = atlas_height(drawn, d);
    return vec4<f32>(drawn - frame.mesh.mesh_offset, max(z, frame.atlas.water_m), -frame.detail.bias);
}
#else
fn grid_vertex(g: vec2<u32>) -> vec4<f32> {
    return detailed[grid_index(g)];
}
#endif

// The normal of the surface a block of grid step `s` draws at vertex `g`: central differences
// over the vertices `s` steps away (clamped at the grid's edge). The baked grid's own normal at
// `g` is the finest level's; a coarse block that took it would point-sample a normal field far
// finer than its cells, and its shading would alias from afar.
fn level_normal(g: vec2<u32>, s: u32) -> vec3<f32> {
#ifdef PIXEL_NORMALS
    // Shading takes the terrain function's normal per pixel; the mesh's is not read.
    return vec3<f32>(0.0, 0.0, 1.0);
#else
#ifdef GRID_STREAMED
    // No normals pass: at s = 1 the differences below are its own.
#else
    if (s == 1u) {
        return vertex_normal(grid_index(g));
    }
#endif
    let hi = vec2<u32>(frame.mesh.mesh - 1u);
    let east = grid_vertex(min(g + vec2<u32>(s, 0u), hi)).xyz;
    let west = grid_vertex(g - min(vec2<u32>(s, 0u), g)).xyz;
    let north = grid_vertex(min(g + vec2<u32>(0u, s), hi)).xyz;
    let south = grid_vertex(g - min(vec2<u32>(0u, s), g)).xyz;
    // Zero where every neighbour was drawn on one point of the sketch's edge (`on_sketch_edge`):
    // up, as the normals pass gives it, rather than NaN.
    let c = cross(east - west, north - south);
    let len = length(c);
    if (len > 0.0) {
        return c / len;
    }
    return vec3<f32>(0.0, 0.0, 1.0);
#endif
}

// Index = block slot << bits | (j·(cells+1) + i), cells and bits from frame.blocks. Vertices that
// the next level drops move toward the midpoint of their two neighbours on it (Wagner's
// geomorph); edge vertices follow the level and morph range of the coarser block of their edge,
// so neighbours agree on them.
@vertex
fn terrain_vs(@builtin(vertex_index) vi: u32) -> VsOut {
    let cells = frame.blocks.cells;
    let b = blocks[vi >> frame.blocks.index_bits];
    let local = vi & ((1u << frame.blocks.index_bits) - 1u);
    let l2 = vec2<u32>(local % (cells + 1u), local / (cells + 1u));
    let g = b.origin + l2;
    var p = grid_vertex(g);
    var level = b.level;
    var start = b.morph.x;
    var end = b.morph.y;
    var side = 4u;
    if (l2.y == 0u) { side = 0u; } else if (l2.x == cells) { side = 1u; } else if (l2.y == cells) { side = 2u; } else if (l2.x == 0u) { side = 3u; }
    if (side < 4u) {
        level = b.side_level[side];
        start = b.side_start[side];
        end = b.side_end[side];
    }
    let s = 1u << level;
    let s2 = 2u << level;
    var n = level_normal(g, s);
    var morph = 0.0;
    if (level + 1u < frame.blocks.levels && (g.x % s2 != 0u || g.y % s2 != 0u)) {
        let d = vec2<u32>(select(0u, s, g.x % s2 != 0u), select(0u, s, g.y % s2 != 0u));
        let a = grid_vertex(g - d);
        let c = grid_vertex(g + d);
        // Inside: the block's factor (continuous when it changes level); on an edge: the
        // vertex's own distance over the edge's shared range (both blocks compute the same).
        var m = b.morph.z;
        if (side < 4u) {
            let eye_d = distance(p.xyz + vec3<f32>(frame.mesh.mesh_offset, 0.0), frame.camera.eye);
            m = 0.0;
            if (end > start) {
                m = clamp((eye_d - start) / (end - start), 0.0, 1.0);
            }
        }
        p.z = mix(p.z, 0.5 * (a.z + c.z), m);
        n = normalize(mix(n, level_normal(g, s2), m));
        morph = m;
    }
    let local_pos = p.xyz + vec3<f32>(frame.mesh.mesh_offset, 0.0);
    return vertex_out(local_pos, n, p.w, vec2<f32>(g), mesh_spacing(p.w) * f32(s) * (1.0 + morph));
}
#else
@vertex
fn terrain_vs(@builtin(vertex_index) vi: u32) -> VsOut {
    let p = detailed[vi];
    let grid = vec2<f32>(f32(vi % frame.mesh.mesh), f32(vi / frame.mesh.mesh));
    return vertex_out(p.xyz, vertex_normal(vi), p.w, grid, mesh_spacing(p.w));
}
#endif

// Whether a fragment is drawn: the sketch ends at its edge, as the reference's does. The cells
// between vertices drawn on the edge (`on_sketch_edge`) stand in its vertical plane, spanning
// chords of its height profile: they are left out with a margin inside the edge, a thousandth of
// the sketch's spacing. That is above f32's rounding of a coordinate up to about 8,000 spacings
// from the frame's origin (the camera's ground point); farther away, a pixel spans hundreds of
// metres there (240 km for 30 m spacings: about 500 m at 512², 60°).
fn inside_sketch(local: vec2<f32>) -> bool {
    return on_sketch(local, -1e-3 * frame.atlas.d_atlas);
}

#ifdef POSITIONS
// The depth copy alone, for a multisampled frame: its colour pass leaves positions out (its
// samples cannot hold four bytes of one depth through a resolve), and this single-sampled pass
// writes each pixel centre's depth, as a single-sampled frame does.
@fragment
fn depth_fs(in: VsOut) -> @location(1) vec4<f32> {
    if (!inside_sketch(in.local.xy)) {
        discard;
    }
    return depth_bytes(in.view_w);
}
#endif

// The normal the pixel is shaded with. With PIXEL_NORMALS: the terrain function's at the pixel's
// footprint, as the reference shades; the mesh only places the surface, and a mesh that slides
// between frames leaves the light alone. Otherwise the mesh's own normal plus bump detail where
// the mesh samples the sketch at its own cells or finer, and the terrain function's normal where
// it samples the sketch at twice its cells or coarser (views from high up, far ground,
// GeoMipMap's coarse levels) or holds octaves more than one past the pixel's own (GeoMipMap's
// baked grid seen from afar), blended between. There the mesh's facets point-sample the
// sketch's pyramid and miss its relief between the mesh's spacing and the pixel's footprint, or
// point-sample octaves the pixel averages. It costs what PIXEL_NORMALS costs, on those pixels
// only (docs/decisions.md, “Terrain function's normal on coarse ground”).
fn shading_normal(in: Surface, footprint: f32) -> vec3<f32> {
#ifdef PIXEL_NORMALS
    return normalize(vec3<f32>(-surface_gradient(in.local.xy, footprint), 1.0));
#else
    // Also where the mesh holds octaves more than one past the pixel's own (GeoMipMap's baked
    // grid seen from afar, and brute force's; the warped mesh's split stops at the pixel octave
    // of the vertex's nearest possible height, so only a fragment more than twice as far as that
    // can pass it): its normal point-samples them and aliases. Not from the first octave past the
    // pixel's: there the bump over the mesh's normal serves better than the terrain function's
    // faded octaves (docs/decisions.md, “Terrain function's normal on coarse ground”).
    let excess = in.split - footprint_octave(footprint);
    let coarse_mesh = max(log2(in.spacing / frame.atlas.d_atlas), excess - 1.0);
    let coarse = select(clamp(coarse_mesh, 0.0, 1.0), 0.0, on_water(in.local.z));
    if (coarse >= 1.0) {
        return coarse_normal(in, footprint);
    }
    let n = mesh_normal(in, footprint);
    if (coarse <= 0.0) {
        return n;
    }
    return normalize(mix(n, coarse_normal(in, footprint), coarse));
#endif
}

#ifdef PIXEL_NORMALS
#else
// The mesh's interpolated normal, with BUMP the octaves from the vertex's split octave up to the
// pixel's own octave added as bump detail; the geometry already holds g_k of each, octaves past
// the pixel octave are never evaluated.
fn mesh_normal(in: Surface, footprint: f32) -> vec3<f32> {
    let n = normalize(in.normal);
#ifdef BUMP
    return normalize(vec3<f32>(n.xy / max(n.z, 0.05) - octaves_gradient(in, footprint, n, in.split, false), 1.0));
#else
    return n;
#endif
}

// The terrain function's normal, where the mesh samples the sketch at twice its cells or
// coarser or holds octaves well past the pixel's: the sketch's gradient and the octaves'. With
// BUMP_FADE the octaves the mesh does not hold are faded as the bump is, for the same reason: the
// ray meets the true surface away from where it meets the mesh, by the height the mesh lacks, and
// drawn whole they are the reference's pattern shifted. Here with the model's own factor
// (FADE_MODEL), not the bump's fitted one, which fades too many of the octaves worth keeping
// (docs/decisions.md, “Fade of the coarse normal's octaves”).
fn coarse_normal(in: Surface, footprint: f32) -> vec3<f32> {
#ifdef BUMP
#ifdef BUMP_FADE
    // The split octave the mesh's spacing stands for: GeoMipMap's coarse blocks carry the bake's
    // (`in.split`), which holds octaves between the bake's vertices that the block's lack: with
    // the bake's split nothing would fade there. In the warped mode it is `in.split` at the
    // vertices; inside a triangle, the split of the spacing interpolated, at most about
    // (ln 2/8)·Δ² octaves below `in.split` interpolated, Δ the vertices' difference.
    let split = log2(frame.atlas.d_atlas / in.spacing) - frame.detail.bias;
    let gradient = sketch_gradient(in.local.xy, footprint) + octaves_gradient(in, footprint, normalize(in.normal), split, true);
    return normalize(vec3<f32>(-gradient, 1.0));
#endif
#endif
    return normalize(vec3<f32>(-land_gradient(in.local.xy, footprint), 1.0));
}

#ifdef BUMP
// The octaves' gradient for a shading normal at the pixel's footprint, for a mesh whose split
// octave there is `split`: each octave's bump share (1 − g_k)·b_k; for the terrain function's
// normal (`terrain_function`) also the part of its pixel share the mesh holds, g_k·b_k, so that
// it takes b_k of each octave as the reference does (the mesh's normal holds g_k already). With
// BUMP_FADE the bump share is weighted by a power of its expected correlation with the surface
// the ray meets, for ground of normal `n` (shared/fade.wgsl): FADE_SPECTRUM for the mesh's
// normal, FADE_MODEL for the terrain function's.
fn octaves_gradient(in: Surface, footprint: f32, n: vec3<f32>, split: f32, terrain_function: bool) -> vec2<f32> {
    let o_px = footprint_octave(footprint);
    let last = min(frame.detail.octaves, u32(max(ceil(o_px), 0.0)));
    var grad = vec2<f32>(0.0);
#ifdef BUMP_FADE
    var height_var = 0.0;
    for (var k = 1u; k <= last; k++) {
        let h = FADE_NOISE_RMS * frame.detail.octave[k - 1u].weight * bump_share(k, split, o_px);
        height_var += h * h;
    }
    let to_eye = frame.camera.eye - in.local;
    let spread = fade_spread(height_var, to_eye / max(length(to_eye), 1e-3), n, vec3<f32>(0.0, 0.0, 1.0));
    let spectrum = select(FADE_SPECTRUM, FADE_MODEL, terrain_function);
#endif
    for (var k = 1u; k <= last; k++) {
        var held = 0.0;
        if (terrain_function) {
            held = clamp(split - f32(k) + 1.0, 0.0, 1.0) * clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
        }
#ifdef BUMP_FADE
        let share = held + bump_share(k, split, o_px) * bump_fade(frame.detail.octave[k - 1u].scale, spread, spectrum);
        if (share > FADE_SKIP) {
#else
        let share = held + bump_share(k, split, o_px);
        if (share > 0.0) {
#endif
            grad += frame.detail.octave[k - 1u].weight * share * octave_local(frame.detail.octave[k - 1u], in.local.xy).yz;
        }
    }
    // Faded at the shore as the terrain function's octaves are (the mesh's height stands for
    // the sketch's there: within the band it carries little of the octaves).
    return shore(in.local.z) * grad;
}
#endif
#endif

// What shading needs of a fragment of the ground: VsOut's values without the clip position, and
// the wireframe's line weight, which takes derivatives and so is found where the mesh is
// rasterised.
struct Surface {
    local: vec3<f32>,
    normal: vec3<f32>,
    split: f32,
    spacing: f32,
    inscatter: vec3<f32>,
    through: vec3<f32>,
    view_w: f32,
    wire: f32,
}

fn surface_of(in: VsOut) -> Surface {
    var wire = 1.0;
    if (frame.camera.view == VIEW_WIREFRAME) {
        wire = grid_line_weight(in.grid);
    }
    return Surface(in.local, in.normal, in.split, in.spacing, in.inscatter, in.through, in.view_w, wire);
}

@fragment
fn terrain_fs(in: VsOut) -> FragOut {
    if (!inside_sketch(in.local.xy)) {
        discard;
    }
    let out = shade(surface_of(in));
    add_work();
    return out;
}

// Where the mesh lies within its own spacing of the water's level, the point a pixel is shaded at
// takes the sketch's height at the pixel's footprint (the terrain function's there, the octaves
// fading out at the shore), so the shore is the sketch's contour through the pixel. The mesh's
// height alone draws it along the edges between the mesh's water vertices: facets wherever its
// triangles are coarser than the sketch's cells (docs/decisions.md, “The shore is the sketch's
// contour”). The world position, hence depth and distance, stays the mesh's.
fn shore_local(in: Surface, footprint: f32) -> vec3<f32> {
#ifdef RAMP
    return in.local;
#else
    let water = frame.atlas.water_m;
    if (in.local.z > water + max(in.spacing, frame.detail.shore_m)) {
        return in.local;
    }
    return vec3<f32>(in.local.xy, max(atlas_height(in.local.xy, footprint), water));
#endif
}

fn shade(surface: Surface) -> FragOut {
    var in = surface;
    let to_eye = frame.camera.eye - in.local;
    let dist = max(length(to_eye), 1e-3);
    let footprint = dist * frame.camera.pixel_scale;
    in.local = shore_local(in, footprint);
    let n = shading_normal(in, footprint);
    var colour = lit(in.local, n, to_eye, dist);
    if (frame.camera.view == VIEW_WIREFRAME) {
        // Wireframe: the quad mesh's grid lines over the shaded terrain.
        colour = mix(vec3<f32>(0.05, 0.05, 0.08), colour, in.wire);
    } else if (frame.camera.view == VIEW_SPLIT_OCTAVE) {
        let t = clamp(in.split / f32(max(frame.detail.octaves, 1u)), 0.0, 1.0);
        colour = mix(vec3<f32>(0.1, 0.1, 0.6), vec3<f32>(1.0, 0.9, 0.1), t);
    } else if (frame.camera.view == VIEW_NORMALS) {
        colour = n * 0.5 + 0.5;
    } else if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(1.0), in.view_w);
    }
#ifdef IMPORTANCE_VIEW
    let rel = in.local.xy - frame.mesh.phi_offset;
    let texel = vec2<f32>(dot(rel, frame.mesh.phi_s), dot(rel, frame.mesh.phi_t)) / frame.mesh.d0;
    let i = clamp(vec2<u32>(max(texel, vec2<f32>(0.0))), vec2<u32>(0u), vec2<u32>(frame.mesh.n - 1u));
    let v = importance[i.y * frame.mesh.n + i.x];
    let t = clamp(log2(v / frame.mesh.importance_max) / 12.0 + 1.0, 0.0, 1.0);
    colour = mix(vec3<f32>(0.27, 0.0, 0.33), vec3<f32>(0.99, 0.9, 0.14), t);
#endif
    var out = frag_out(colour * in.through + in.inscatter, in.view_w);
    out.colour.a = water_alpha(in.local.z);
    return out;
}

#ifdef DEFERRED
// Deferred (single-sampled frames): the mesh writes each pixel's Surface to four integer targets
// and one full-screen pass shades each pixel once, or draws the sky where no ground was written
// (src/gpu/terrain.rs's `Deferred` says why). Integer targets keep the f32s' bits, so the pass
// shades with exactly the values a forward fragment has.
struct GBuffer {
    @location(0) local_w: vec4<u32>,
    @location(1) normal_split: vec4<u32>,
    @location(2) inscatter_spacing: vec4<u32>,
    @location(3) through_wire: vec4<u32>,
}

// The pair that fixes the G-buffer's layout: a Surface packed, and unpacked.
fn gbuffer_of(s: Surface) -> GBuffer {
    return GBuffer(
        bitcast<vec4<u32>>(vec4<f32>(s.local, s.view_w)),
        bitcast<vec4<u32>>(vec4<f32>(s.normal, s.split)),
        bitcast<vec4<u32>>(vec4<f32>(s.inscatter, s.spacing)),
        bitcast<vec4<u32>>(vec4<f32>(s.through, s.wire)),
    );
}

fn surface_from(g: GBuffer) -> Surface {
    let a = bitcast<vec4<f32>>(g.local_w);
    let b = bitcast<vec4<f32>>(g.normal_split);
    let c = bitcast<vec4<f32>>(g.inscatter_spacing);
    let d = bitcast<vec4<f32>>(g.through_wire);
    return Surface(a.xyz, b.xyz, b.w, c.w, c.xyz, d.xyz, a.w, d.w);
}

@fragment
fn gbuffer_fs(in: VsOut) -> GBuffer {
    if (!inside_sketch(in.local.xy)) {
        discard;
    }
    let out = gbuffer_of(surface_of(in));
    add_work();
    return out;
}

@group(1) @binding(0) var gbuffer_local_w: texture_2d<u32>;
@group(1) @binding(1) var gbuffer_normal_split: texture_2d<u32>;
@group(1) @binding(2) var gbuffer_inscatter_spacing: texture_2d<u32>;
@group(1) @binding(3) var gbuffer_through_wire: texture_2d<u32>;

@fragment
fn deferred_fs(in: SkyOut) -> FragOut {
    let p = vec2<i32>(in.clip.xy);
    let local_w = textureLoad(gbuffer_local_w, p, 0);
    // view_w is the clip w of a fragment in front of the near plane, above 0: the clear value's
    // 0 bits mark a pixel with no ground.
    var out: FragOut;
    if (local_w.w == 0u) {
        out = sky(in);
    } else {
        out = shade(surface_from(GBuffer(
            local_w,
            textureLoad(gbuffer_normal_split, p, 0),
            textureLoad(gbuffer_inscatter_spacing, p, 0),
            textureLoad(gbuffer_through_wire, p, 0),
        )));
    }
    add_work();
    return out;
}
#endif
