// The planet pass: the sky (or space) as one full-screen triangle, then the clipmap rings the
// clipmaps pass carried to the terrain, drawn from the storage buffer (vertex pulling: each
// vertex finds its neighbours on its ring and the next rings for its normal), shaded in the
// local frame of each point of the sphere: the sun sets across the planet, the air is a shell.
// Bump detail adds the octaves from the vertex's split octave up to the pixel's, as in the plane.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<uniform> planet: Planet;
#import sphere

@group(0) @binding(4) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> hemisphere: array<vec4<f32>>;

fn frag_out(colour: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(select(colour, display(colour), frame.camera.view <= VIEW_WIREFRAME), 1.0);
}

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

@fragment
fn sky_fs(in: SkyOut) -> @location(0) vec4<f32> {
    if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(0.0));
    }
    // The point at infinity under the pixel (depth 0 with reversed Z): a direction, with none
    // of the eye's translation, which from orbit is 2e7 m and would cost an f32 its metres.
    let dir = normalize((frame.camera.inv_view_proj * vec4<f32>(in.ndc, 0.0, 1.0)).xyz);
    return frag_out(planet_sky(frame.camera.eye, dir));
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
    out.local = p.xyz;
    out.normal = normal;
    let v = hemisphere[i];
    out.rel = planet.radius * vec3<f32>(v.x, v.y, -v.z);
    out.split = p.w;
    out.inscatter = air.inscatter;
    out.through = air.through;
    out.grid = grid;
    // The height above the sphere, per vertex: z = h − (R + h)·(1 − cos θ̃) undone. From the
    // fragment's interpolated position it would be the chord's, which from orbit sags kilometres
    // below the sphere between a coarse ring's vertices.
    out.height = (p.z + planet.radius * v.z) / (1.0 - v.z);
    // The sketch's part of it, so the fragment can trade it for the sketch at its own footprint
    // and keep the octaves the mesh carries.
    out.sketch_height = planet_sketch(planet_texel_of(v), ring_spacing(v.w));
    return out;
}

// The hemisphere point (sin a·sin b, sin a·cos b, 1 − cos a, a) under the point `rel` (metres
// in the tangent frame from the nadir, near the sphere): its direction from the centre, with
// 1 − cos a from sin² a so that near the nadir it keeps its digits.
fn hemisphere_of(rel: vec3<f32>) -> vec4<f32> {
    let q = rel / planet.radius + vec3<f32>(0.0, 0.0, 1.0);
    let d = q / length(q);
    let s2 = dot(d.xy, d.xy);
    let vers = s2 / (1.0 + sqrt(max(1.0 - s2, 0.0)));
    return vec4<f32>(d.x, d.y, vers, asin(min(sqrt(s2), 1.0)));
}

// The surfaces of a planet by height, slope and latitude: sea, beach, grass and forest below
// the tree line, rock on steep ground, snow high up (lower toward the poles).
fn planet_albedo(h: f32, slope: f32, polar: f32) -> vec3<f32> {
    let grass = vec3<f32>(0.16, 0.25, 0.08);
    let forest = vec3<f32>(0.05, 0.09, 0.04);
    let dry = vec3<f32>(0.36, 0.30, 0.20);
    let rock = vec3<f32>(0.30, 0.28, 0.26);
    let sand = vec3<f32>(0.62, 0.55, 0.40);
    let snow = vec3<f32>(0.86, 0.88, 0.93);
    // Lowland grass with forest on moderate slopes, thinning with height.
    var c = mix(grass, forest, smoothstep(0.03, 0.12, slope) * (1.0 - smoothstep(800.0, 1800.0, h)) * (1.0 - smoothstep(0.25, 0.35, slope)));
    c = mix(c, dry, smoothstep(1500.0, 2600.0, h));
    c = mix(c, rock, smoothstep(0.25, 0.45, slope));
    c = mix(c, sand, 1.0 - smoothstep(planet.water_m + 2.0, planet.water_m + 12.0, h));
    let snow_line = 4200.0 * (1.0 - polar) + 200.0;
    return mix(c, snow, smoothstep(snow_line, snow_line + 400.0, h) * (1.0 - smoothstep(0.5, 0.7, slope)));
}

@fragment
fn planet_fs(in: VsOut) -> @location(0) vec4<f32> {
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
    // (A vertex on the sea has lost its octaves to the water's level: none are kept there.)
    let octaves = select(in.height - in.sketch_height, 0.0, in.height <= planet.water_m + ON_WATER_M);
    let h = max(planet_sketch(planet_texel_of(hemisphere_of(in.rel)), footprint) + octaves, planet.water_m);
    var n = normalize(in.normal);
#ifdef BUMP
#ifdef NOISE
    let o_px = log2(frame.atlas.d_atlas / max(footprint, 1e-6));
    let last = min(planet.octaves, u32(max(ceil(o_px), 0.0)));
    var grad = vec3<f32>(0.0);
    let rel = in.rel.x * planet.east + in.rel.y * planet.north + in.rel.z * planet.up;
    for (var k = 1u; k <= last; k++) {
        let g = clamp(in.split - f32(k) + 1.0, 0.0, 1.0);
        let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
        let share = (1.0 - g) * b;
        if (share > 0.0) {
            grad += planet.octave[k - 1u].weight * share * octave_rel(planet.octave[k - 1u], rel).yzw;
        }
    }
    // The gradient in the tangent frame, less its part along the vertical.
    let gt = vec3<f32>(dot(grad, planet.east), dot(grad, planet.north), dot(grad, planet.up));
    n = normalize(n - (gt - dot(gt, up) * up));
#endif
#endif
    let mu_s = dot(up, planet.sun);
    var colour: vec3<f32>;
    if (h <= planet.water_m + ON_WATER_M) {
        let cos_v = clamp(dot(to_eye / dist, up), 0.0, 1.0);
        let fresnel = 0.02 + 0.98 * pow(1.0 - cos_v, 5.0);
        let reflected = planet_sky(in.local, reflect(-to_eye / dist, up));
        let sky = frame.shading.sky_light * smoothstep(-0.1, 0.17, mu_s);
        let body = vec3<f32>(0.015, 0.045, 0.06) * (planet_sun(h, mu_s) * max(mu_s, 0.0) + sky);
        colour = mix(body, reflected, fresnel);
    } else {
        let slope = 1.0 - clamp(dot(n, up), 0.0, 1.0);
        // The sine of the point's latitude: its up's world z (east has none).
        let polar = abs(dot(up.yz, vec2<f32>(planet.cos_lat, planet.sin_lat)));
        let albedo = planet_albedo(h, slope, smoothstep(0.8, 0.98, polar));
        let sun = max(dot(n, planet.sun), 0.0);
        // The sky's light dims from 10° above the local horizon to 6° below it, as in the plane.
        let sky = frame.shading.sky_light * smoothstep(-0.1, 0.17, mu_s) * (0.5 + 0.5 * dot(n, up));
        colour = albedo * (planet_sun(h, mu_s) * sun + sky);
    }
    if (frame.camera.view == VIEW_WIREFRAME) {
        let d = abs(fract(in.grid + 0.5) - 0.5) / max(fwidth(in.grid), vec2<f32>(1e-6));
        colour = mix(vec3<f32>(0.05, 0.05, 0.08), colour, clamp(min(d.x, d.y), 0.0, 1.0));
    } else if (frame.camera.view == VIEW_SPLIT_OCTAVE) {
        let t = clamp(in.split / f32(max(planet.octaves, 1u)), 0.0, 1.0);
        colour = mix(vec3<f32>(0.1, 0.1, 0.6), vec3<f32>(1.0, 0.9, 0.1), t);
    } else if (frame.camera.view == VIEW_NORMALS) {
        colour = n * 0.5 + 0.5;
    } else if (frame.camera.view == VIEW_COVERAGE) {
        return frag_out(vec3<f32>(1.0));
    }
    return frag_out(colour * in.through + in.inscatter);
}
