// The planet pass: the clipmap rings the clipmaps pass carried to the terrain, drawn from the
// storage buffer (vertex pulling: each vertex finds its neighbours on its ring and the next rings
// for its normal), shaded in the local frame of each point of the sphere: the sun sets across the
// planet, the air is a shell. Then the sky (or space) as one full-screen triangle where no ring
// was drawn.
// Bump detail adds the octaves from the vertex's split octave up to the pixel's, as in the plane.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<uniform> planet: Planet;
#import sphere

@group(0) @binding(4) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> hemisphere: array<vec4<f32>>;

#import raster
#ifdef BUMP_FADE
#import fade
#endif

@fragment
fn sky_fs(in: SkyOut) -> FragOut {
    let out = planet_sky_of(in);
    add_work();
    return out;
}

fn planet_sky_of(in: SkyOut) -> FragOut {
    if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(0.0), 0.0);
    }
    // The point at infinity under the pixel (depth 0 with reversed Z): a direction, with none
    // of the eye's translation, which from orbit is 2e7 m and would cost an f32 its metres.
    let dir = normalize((frame.camera.inv_view_proj * vec4<f32>(in.ndc, 0.0, 1.0)).xyz);
    return frag_out(planet_sky(frame.camera.eye, dir), 0.0);
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) rel: vec3<f32>,
    @location(3) split: f32,
    @location(4) inscatter: vec3<f32>,
    @location(5) through: vec3<f32>,
    @location(6) grid: vec2<f32>,
    @location(7) height: f32,
    @location(8) sketch_height: f32,
    // The view depth for the position copy (see terrain.wgsl's VsOut).
    @location(9) view_w: f32,
}

fn at(i: u32) -> vec3<f32> {
    return vertices[i].xyz;
}

// Vertex `i`'s neighbour `dk` bearings along its ring and `dr` rings outward, within the rings
// computed this frame (the innermost ring's inner neighbour is the nadir).
fn neighbour(r: u32, k: u32, dk: i32, dr: i32) -> vec3<f32> {
    let n = planet.phi_steps;
    let first = planet.first_vertex / n;
    let ring = i32(r) + dr;
    if (ring > i32(planet.inner_ring)) {
        return at(planet.nadir);
    }
    let rr = u32(max(ring, i32(first)));
    let kk = u32((i32(k) + dk + i32(n)) % i32(n));
    return at(rr * n + kk);
}

@vertex
fn planet_vs(@builtin(vertex_index) i: u32) -> VsOut {
    let p = vertices[i];
    let n_steps = planet.phi_steps;
    var normal: vec3<f32>;
    var grid = vec2<f32>(0.0);
    if (i == planet.nadir) {
        // The nadir: across the innermost ring, east–west and north–south.
        let base = planet.inner_ring * n_steps;
        let q = n_steps / 4u;
        let east = at(base + q) - at(base + 3u * q);
        let north = at(base) - at(base + 2u * q);
        normal = normalize(cross(east, north));
    } else {
        let r = i / n_steps;
        let k = i % n_steps;
        // Along the ring (bearing growing from north to east) and outward across the rings.
        let along = neighbour(r, k, 1, 0) - neighbour(r, k, -1, 0);
        let outward = neighbour(r, k, 0, -1) - neighbour(r, k, 0, 1);
        normal = normalize(cross(along, outward));
        grid = vec2<f32>(f32(k), f32(r));
    }
    let to_eye = frame.camera.eye - p.xyz;
    let dist = max(length(to_eye), 1e-3);
    let air = planet_scatter(frame.camera.eye, -to_eye / dist, dist);
    var out: VsOut;
    out.clip = frame.camera.view_proj * vec4<f32>(p.xyz, 1.0);
    out.view_w = out.clip.w;
    out.local = p.xyz;
    out.normal = normal;
    let v = hemisphere[i];
    out.rel = planet.radius * vec3<f32>(v.x, v.y, -v.z);
    out.split = log2(frame.atlas.d_atlas / ring_spacing(v.w)) - planet.bias;
    out.inscatter = air.inscatter;
    out.through = air.through;
    out.grid = grid;
    // The ground's height before the sea covers it, per vertex (from the fragment's
    // interpolated position it would be the chord's, which from orbit sags kilometres below the
    // sphere between a coarse ring's vertices).
    out.height = p.w;
    // The sketch's part of it, so the fragment can trade it for the sketch at its own footprint
    // and keep the octaves the mesh carries.
    out.sketch_height = planet_sketch(planet_texel_of(v), ring_spacing(v.w));
    return out;
}

@fragment
fn planet_fs(in: VsOut) -> FragOut {
    let out = planet_shade(in);
    add_work();
    return out;
}

fn planet_shade(in: VsOut) -> FragOut {
    let r = planet.radius;
    let from_centre = in.local + vec3<f32>(0.0, 0.0, r);
    let up = normalize(from_centre);
    let to_eye = frame.camera.eye - in.local;
    let dist = max(length(to_eye), 1e-3);
    let footprint = dist * frame.camera.pixel_scale;
    // The surface's height at the pixel, from the sketch at the pixel's footprint: coasts, snow
    // lines and surface types follow the terrain function, not the mesh's interpolated vertex
    // heights, which from orbit run in steps of a few pixels. Where the mesh is finer than the
    // sketch's own cells the two agree.
    let octaves = in.height - in.sketch_height;
    var h = planet_sketch(planet_texel_of(hemisphere_of(in.rel)), footprint) + octaves;
    var n = normalize(in.normal);
#ifdef BUMP
#ifdef NOISE
    let o_px = footprint_octave(footprint);
    let last = min(planet.octaves, u32(max(ceil(o_px), 0.0)));
    var grad = vec3<f32>(0.0);
    let rel = in.rel.x * planet.east + in.rel.y * planet.north + in.rel.z * planet.up;
#ifdef BUMP_FADE
    // The bump's weights by a fitted power of their expected correlation (shared/fade.wgsl); the
    // height keeps every octave whole.
    var height_var = 0.0;
    for (var k = 1u; k <= last; k++) {
        let hk = FADE_NOISE_RMS * planet.octave[k - 1u].weight * bump_share(k, in.split, o_px);
        height_var += hk * hk;
    }
    let spread = fade_spread(height_var, to_eye / dist, n, up);
#endif
    for (var k = 1u; k <= last; k++) {
        let share = bump_share(k, in.split, o_px);
        if (share > 0.0) {
            let o = planet.octave[k - 1u].weight * share * octave_rel(planet.octave[k - 1u], rel);
            // The bump's octaves count in the pixel's height too, as the reference's surface
            // holds them: a small lake the mesh cannot carry still shows as water.
            h += o.x;
#ifdef BUMP_FADE
            grad += bump_fade(planet.octave[k - 1u].scale, spread, FADE_SPECTRUM) * o.yzw;
#else
            grad += o.yzw;
#endif
        }
    }
    // The gradient in the tangent frame, less its part along the vertical.
    let gt = vec3<f32>(dot(grad, planet.east), dot(grad, planet.north), dot(grad, planet.up));
    n = normalize(n - (gt - dot(gt, up) * up));
#endif
#endif
    h = max(h, planet.water_m);
    var colour = planet_lit(in.local, n, h, to_eye, dist);
    if (frame.camera.view == VIEW_WIREFRAME) {
        colour = mix(vec3<f32>(0.05, 0.05, 0.08), colour, grid_line_weight(in.grid));
    } else if (frame.camera.view == VIEW_SPLIT_OCTAVE) {
        let t = clamp(in.split / f32(max(planet.octaves, 1u)), 0.0, 1.0);
        colour = mix(vec3<f32>(0.1, 0.1, 0.6), vec3<f32>(1.0, 0.9, 0.1), t);
    } else if (frame.camera.view == VIEW_NORMALS) {
        colour = n * 0.5 + 0.5;
    } else if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(1.0), in.view_w);
    }
    return frag_out(colour * in.through + in.inscatter, in.view_w);
}
