// Planets: the terrain function on a sphere (the twin of src/planet/), map offsets from the
// nadir, the global sketch across the date line and the poles, the octaves on a 3-D lattice, and
// the air as a spherical shell. The pass declares `planet: Planet` (uniform, binding 2).
// Positions are metres in the nadir's tangent frame (x east, y north, z up), origin on the
// sphere of radius R under the camera.

#import atlas
#import shading
#import constants
#ifdef NOISE
#import noise
#endif

struct SphereOctave {
    lattice: vec3<i32>,   // whole lattice cell of the nadir (f64 split on the CPU)
    seed: u32,
    phase: vec3<f32>,     // fraction of the nadir inside that cell
    scale: f32,           // lattice cells per metre
    weight: f32,          // w_k, metres
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

struct Planet {
    east: vec3<f32>,             // the nadir's tangent frame in world axes
    radius: f32,
    north: vec3<f32>,
    eye_m: f32,                  // the eye's height above the radius
    up: vec3<f32>,
    sin_lat: f32,                // the nadir's latitude
    sun: vec3<f32>,              // toward the sun, in the tangent frame
    cos_lat: f32,
    texel_origin: vec2<i32>,     // the nadir's whole level-0 texel (x: longitude, y: latitude)
    texel_frac: vec2<f32>,       // and its fraction
    texels_per_rad: vec2<f32>,   // level-0 texels per radian of longitude, of latitude
    phi_steps: u32,              // bearings per ring
    rings_per_level: u32,
    first_vertex: u32,           // the first ring vertex computed this frame
    vertex_count: u32,           // ring vertices computed this frame (the nadir follows)
    nadir: u32,                  // index of the nadir vertex
    inner_ring: u32,             // the innermost drawn ring
    levels: u32,                 // pyramid levels the wrap can use
    octaves: u32,
    min_spacing: f32,            // the vertices' spacing at the innermost ring, metres
    bias: f32,
    water_m: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    octave: array<SphereOctave, MAX_OCTAVES>,
}

// The change of latitude (x) and longitude (y) from the nadir to the hemisphere point `v`
// = (sin a·sin b, sin a·cos b, 1 − cos a, a): the spherical direct problem in a form that keeps
// relative precision for small a (src/planet/mod.rs, `map_offset`).
fn map_offset(v: vec4<f32>) -> vec2<f32> {
    let s1 = planet.sin_lat;
    let c1 = planet.cos_lat;
    let x = c1 * (1.0 - v.z) - s1 * v.y;
    let ds = c1 * v.y - s1 * v.z;
    let c2 = sqrt(x * x + v.x * v.x);
    return vec2<f32>(2.0 * atan2(ds, c1 + c2), atan2(v.x, x));
}

// Texel (i, j) of level `l`: wrapped across the date line, continued across a pole on the
// opposite meridian.
fn planet_texel(i_in: i32, j_in: i32, l: u32) -> f32 {
    count_atlas_tap();
    let w = i32(frame.atlas.level[l].x);
    let h = i32(frame.atlas.level[l].y);
    var i = i_in;
    var j = j_in;
    if (j < 0) {
        j = -1 - j;
        i += w / 2;
    } else if (j >= h) {
        j = 2 * h - 1 - j;
        i += w / 2;
    }
    j = clamp(j, 0, h - 1);
    i = ((i % w) + w) % w;
#ifdef STREAMED
    // A tile still blending in mixes over the next coarser level's node.
    let a = page_texel(vec2<i32>(i, j), l, true);
    let r = u32(a.z);
    if (a.y >= 1.0 || r + 1u >= frame.atlas.levels) {
        return a.x;
    }
    let b = page_texel(vec2<i32>(i, j) >> vec2<u32>(r + 1u - l), r + 1u, false);
    return mix(b.x, a.x, a.y);
#else
    return atlas[frame.atlas.level[l].z + u32(j * w + i)];
#endif
}

#ifdef STREAMED
// Node `n` of level l through the tile cache: (height, fade, level read). atlas.wgsl's `lookup`
// at the node's centre finds its tile's page, or its finest resident ancestor's on level r (and
// marks them); there the node over n stands in, a point sample.
fn page_texel(n: vec2<i32>, l: u32, want: bool) -> vec3<f32> {
    let s = f32(1u << l);
    let a = lookup((vec2<f32>(n) + 0.5) * s - 0.5, l, want);
    let node = n >> vec2<u32>(a.level - l);
    return vec3<f32>(load(a.texels, node.x, node.y), f32(a.page_fade & 255u) / 255.0, f32(a.level));
}
#endif

// Bicubic on level `l` at level-0 texel `t` relative to the nadir's whole texel: the level's
// whole texel comes from integer shifts, so only a small fraction is ever an f32.
fn planet_level(t: vec2<f32>, l: u32) -> f32 {
    let s = f32(1u << l);
    let mask = vec2<i32>((1 << l) - 1);
    let base = planet.texel_origin >> vec2<u32>(l);
    let x = (vec2<f32>(planet.texel_origin & mask) + t - vec2<f32>((s - 1.0) * 0.5)) / s;
    let c = floor(x);
    let f = x - c;
    let i = base + vec2<i32>(c);
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    var h = 0.0;
    for (var r = 0; r < 4; r++) {
        let row = vec4<f32>(
            planet_texel(i.x - 1, i.y - 1 + r, l),
            planet_texel(i.x, i.y - 1 + r, l),
            planet_texel(i.x + 1, i.y - 1 + r, l),
            planet_texel(i.x + 2, i.y - 1 + r, l),
        );
        h += wy[r] * dot(wx, row);
    }
    return h;
}

// The sketch at level-0 texel `t` (relative to the nadir's) for a footprint of `footprint`
// metres: the footprint's level, linear between two.
fn planet_sketch(t: vec2<f32>, footprint: f32) -> f32 {
    let lod = clamp(log2(max(footprint, 1e-6) / frame.atlas.d_atlas), 0.0, f32(planet.levels - 1u));
    let l0 = u32(lod);
    let a = planet_level(t, l0);
    let f = lod - f32(l0);
    if (f <= 0.0 || l0 + 1u >= planet.levels) {
        return a;
    }
    return a + (planet_level(t, l0 + 1u) - a) * f;
}

// The distance to the vertex's farthest neighbour on a ring of angle `a`: across the rings
// (a·(2^(1/m) − 1)) or along the ring (sin a · 2π/n), metres on the sphere.
fn ring_spacing(a: f32) -> f32 {
    let across = a * (exp2(1.0 / f32(planet.rings_per_level)) - 1.0);
    let along = sin(a) * 6.2831855 / f32(planet.phi_steps);
    return max(planet.radius * max(across, along), planet.min_spacing);
}

// Level-0 texel of the hemisphere point `v`, relative to the nadir's whole texel.
fn planet_texel_of(v: vec4<f32>) -> vec2<f32> {
    let d = map_offset(v);
    return planet.texel_frac + vec2<f32>(d.y, d.x) * planet.texels_per_rad;
}

#ifdef NOISE
fn lattice_gradient3(cell: vec3<i32>, seed: u32) -> vec3<f32> {
    let h = hash(bitcast<u32>(cell.x) ^ hash(bitcast<u32>(cell.y) ^ hash(bitcast<u32>(cell.z) ^ hash(seed))));
    let z = 1.0 - 2.0 * f32(h & 0xffffu) / 65535.0;
    let a = f32(h >> 16u) * (6.2831855 / 65536.0);
    let r = sqrt(max(1.0 - z * z, 0.0));
    return vec3<f32>(r * cos(a), r * sin(a), z);
}

// Value (x) and gradient d/df (yzw) in the cell with lower corner `cell` at fraction `f`.
fn gradient_noise3(cell: vec3<i32>, f: vec3<f32>, seed: u32) -> vec4<f32> {
    let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let du = 30.0 * f * f * (f * (f - 2.0) + 1.0);
    var value = 0.0;
    var grad = vec3<f32>(0.0);
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<i32>(i32(corner & 1u), i32((corner >> 1u) & 1u), i32(corner >> 2u));
        let g = lattice_gradient3(cell + o, seed);
        let v = dot(g, f - vec3<f32>(o));
        let one = o == vec3<i32>(1);
        let w = select(vec3<f32>(1.0) - u, u, one);
        let dw = select(-du, du, one);
        let weight = w.x * w.y * w.z;
        value += weight * v;
        grad += weight * g + v * vec3<f32>(dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z);
    }
    return vec4<f32>(value, grad) * 1.63;
}

// n_k and its gradient per metre (world axes) at `rel` metres (world axes) from the nadir on the
// sphere.
fn octave_rel(o: SphereOctave, rel: vec3<f32>) -> vec4<f32> {
    count_octave();
    let q = rel * o.scale + o.phase;
    let c = floor(q);
    let n = gradient_noise3(o.lattice + vec3<i32>(c), q - c, o.seed);
    return vec4<f32>(n.x, n.yzw * o.scale);
}
#endif

// The sphere's point under hemisphere point `v`, in world axes, relative to the nadir's: the
// noise's argument, small near the camera.
fn sphere_rel(v: vec4<f32>) -> vec3<f32> {
    return planet.radius * (v.x * planet.east + v.y * planet.north - v.z * planet.up);
}

// The air as a shell around the sphere: the single-scattering integral over the ray from `eye`
// along `dir` for `len` metres (cut to the shell), STEPS samples spaced quadratically from
// where the ray enters the air, each lit by the sun as it stands there (the sun sets across the
// planet), plus the isotropic share for higher orders. The planar `scatter` is this with the
// sun at one elevation everywhere and the shell flattened.
fn planet_scatter(eye: vec3<f32>, dir: vec3<f32>, len: f32) -> Scatter {
    var out: Scatter;
    out.inscatter = vec3<f32>(0.0);
    out.through = vec3<f32>(1.0);
    let r = planet.radius;
    // The eye lies on the nadir's vertical: its distance from the centre is r + eye.z, so the
    // shell's quadratic needs no difference of two large squares.
    let b = (r + eye.z) * dir.z + dot(eye.xy, dir.xy);
    let c = (eye.z - TOP_M) * (2.0 * r + eye.z + TOP_M) + dot(eye.xy, eye.xy);
    let disc = b * b - c;
    if (disc <= 0.0) {
        return out;
    }
    let q = -(b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc));
    let t_a = q;
    let t_b = select(c / q, 0.0, q == 0.0);
    let t0 = max(min(t_a, t_b), 0.0);
    let t1 = min(max(t_a, t_b), len);
    if (t1 <= t0) {
        return out;
    }
    let hm = frame.shading.haze_height_m;
    let haze = frame.shading.haze_per_m;
    let phase = phases(dot(dir, planet.sun));
    var tau = vec3<f32>(0.0);
    for (var i = 0; i < STEPS; i++) {
        let u = (f32(i) + 0.5) / f32(STEPS);
        let t = t0 + (t1 - t0) * u * u;
        let dt = (t1 - t0) * 2.0 * u / f32(STEPS);
        let p = eye + dir * t;
        let from_centre = p + vec3<f32>(0.0, 0.0, r);
        let dist = length(from_centre);
        let z = max(dist - r, 0.0);
        let ext = RAYLEIGH * density(z, RAYLEIGH_SCALE_M) + vec3<f32>(haze * density(z, hm));
        let scattered = RAYLEIGH * density(z, RAYLEIGH_SCALE_M) * phase.x
            + vec3<f32>(haze * HAZE_ALBEDO * density(z, hm) * phase.y);
        let at = tau + 0.5 * ext * dt;
        out.inscatter += scattered * exp(-at) * planet_sun(z, dot(from_centre / dist, planet.sun)) * dt;
        tau += ext * dt;
    }
    out.through = exp(-tau);
    return out;
}

// Sunlight at height z where the sun stands `mu` (the cosine of its zenith angle) above the
// local horizon: the column above z times Kasten and Young's air mass, nothing once the sun is
// below the horizon as seen from z (the planet's shadow).
fn planet_sun(z: f32, mu: f32) -> vec3<f32> {
    let el = degrees(asin(clamp(mu, -1.0, 1.0)));
    let h = max(el, 0.0);
    let air_mass = 1.0 / (sin(radians(h)) + 0.50572 * pow(h + 6.07995, -1.6364));
    let hm = frame.shading.haze_height_m;
    let haze = frame.shading.haze_per_m * hm * density(z, hm);
    let column = RAYLEIGH * RAYLEIGH_SCALE_M * density(z, RAYLEIGH_SCALE_M) + vec3<f32>(haze);
    let dip = -sqrt(2.0 * z / planet.radius);
    let lit = smoothstep(dip - 0.01, dip + 0.005, mu);
    return frame.shading.sun_top * exp(-air_mass * column) * lit;
}

// The sky (or space) seen from `eye` along `dir`: the air to the ground or out of the shell,
// and the sun's disc where nothing hides it.
fn planet_sky(eye: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let r = planet.radius;
    // The sphere of radius R: where a ray below the horizon meets the ground (or the sea).
    let b = (r + eye.z) * dir.z + dot(eye.xy, dir.xy);
    let c = eye.z * (2.0 * r + eye.z) + dot(eye.xy, eye.xy);
    let disc = b * b - c;
    var len = 1e12;
    var hidden = false;
    if (disc > 0.0 && b < 0.0) {
        let q = -(b - sqrt(disc));
        len = c / q;
        hidden = true;
    }
    let air = planet_scatter(eye, dir, len);
    var colour = air.inscatter;
    if (!hidden) {
        let disc_sun = smoothstep(0.99995, 0.99998, dot(dir, planet.sun));
        colour += frame.shading.sun_top * air.through * disc_sun * 40.0;
    }
    return colour;
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

// The light a point `p` of the ground at height `h` with normal `n` (tangent frame) sends toward
// the eye `dist` away along `to_eye`, before the air between: the sun as it stands at the point
// (so across the terminator it sets), the sky's light, the sea as a dark body reflecting the sky.
fn planet_lit(p: vec3<f32>, n: vec3<f32>, h: f32, to_eye: vec3<f32>, dist: f32) -> vec3<f32> {
    let up = normalize(p + vec3<f32>(0.0, 0.0, planet.radius));
    let mu_s = dot(up, planet.sun);
    if (h <= planet.water_m + ON_WATER_M) {
        let cos_v = clamp(dot(to_eye / dist, up), 0.0, 1.0);
        let fresnel = 0.02 + 0.98 * pow(1.0 - cos_v, 5.0);
        let reflected = planet_sky(p, reflect(-to_eye / dist, up));
        let sky = frame.shading.sky_light * smoothstep(-0.1, 0.17, mu_s);
        let body = vec3<f32>(0.015, 0.045, 0.06) * (planet_sun(h, mu_s) * max(mu_s, 0.0) + sky);
        return mix(body, reflected, fresnel);
    }
    let slope = 1.0 - clamp(dot(n, up), 0.0, 1.0);
    // The sine of the point's latitude: its up's world z (east has none).
    let polar = abs(dot(up.yz, vec2<f32>(planet.cos_lat, planet.sin_lat)));
    let albedo = planet_albedo(h, slope, smoothstep(0.8, 0.98, polar));
    let sun = max(dot(n, planet.sun), 0.0);
    // The sky's light dims from 10° above the local horizon to 6° below it, as in the plane.
    let sky = frame.shading.sky_light * smoothstep(-0.1, 0.17, mu_s) * (0.5 + 0.5 * dot(n, up));
    return albedo * (planet_sun(h, mu_s) * sun + sky);
}

// The terrain function at the hemisphere point `v` for a footprint of `footprint` metres: the
// sketch at the footprint's level plus every octave k with its pixel share b_k, never below the
// sea (the reference's surface).
fn planet_ground(v: vec4<f32>, footprint: f32) -> f32 {
    var h = planet_sketch(planet_texel_of(v), footprint);
#ifdef NOISE
    let o_px = footprint_octave(footprint);
    let last = min(planet.octaves, u32(max(ceil(o_px), 0.0)));
    let rel = sphere_rel(v);
    for (var k = 1u; k <= last; k++) {
        let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
        h += planet.octave[k - 1u].weight * b * octave_rel(planet.octave[k - 1u], rel).x;
    }
#endif
    return max(h, planet.water_m);
}

// A point's height above the sphere, |p − centre| − R without the difference of two large
// numbers (p in the tangent frame, the centre R below its origin).
fn planet_altitude(p: vec3<f32>) -> f32 {
    let r = planet.radius;
    return (dot(p.xy, p.xy) + p.z * (p.z + 2.0 * r)) / (length(p + vec3<f32>(0.0, 0.0, r)) + r);
}
