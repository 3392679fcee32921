// Surface shading shared by the mesh renderers and the reference ray marcher: the sky and the
// aerial perspective from one single-scattering atmosphere (the twin of src/light.rs), surface
// types from slope, height, aspect and curvature, water, sun and sky light, the sketch's shadow
// (SHADOWS) and the detail's (DETAIL_SHADOWS), the world beyond the sketch, exposure and the
// tone map. Needs `frame` and the atlas; turbulence needs the noise.
#import atlas
#ifdef NOISE
#import noise
#endif
#ifdef DETAIL_SHADOWS
#import surface
#endif

// Ground within this of the water's surface is water (the reference's bisection lands within it).
const ON_WATER_M: f32 = 0.01;

// Whether ground at height `z` is the water's surface.
fn on_water(z: f32) -> bool {
    return z <= frame.atlas.water_m + ON_WATER_M;
}
// The atmosphere, twins of src/light.rs's constants of the same names.
const RAYLEIGH: vec3<f32> = vec3<f32>(5.8e-6, 13.5e-6, 33.1e-6);
const RAYLEIGH_SCALE_M: f32 = 8000.0;
const HAZE_ALBEDO: f32 = 0.9;
const MIE_G: f32 = 0.76;
const MULTIPLE: f32 = 1.0;
const STEPS: i32 = 12;
const TOP_M: f32 = 60000.0;
const FAR_M: f32 = 400000.0;

fn density(z: f32, scale: f32) -> f32 {
    return exp(-z / scale);
}

// The air along a segment from height z0 to z1, `dist` long, whose density falls as
// exp(−z / scale): ∫ exp(−z(t) / scale) dt, in metres of sea-level air; a difference of two
// bounded exponentials, so a segment from 100 km up does not overflow.
fn air_along(z0: f32, z1: f32, dist: f32, scale: f32) -> f32 {
    let x = (z1 - z0) / scale;
    let a = density(z0, scale);
    if (abs(x) < 1e-3) {
        return dist * a * (1.0 - 0.5 * x);
    }
    return dist * (a - density(z1, scale)) / x;
}

// The sunlight reaching height z: above the air, less the column above z times the air mass.
fn sun_at(z: f32) -> vec3<f32> {
    let haze = frame.shading.haze_per_m * frame.shading.haze_height_m * density(z, frame.shading.haze_height_m);
    let column = RAYLEIGH * RAYLEIGH_SCALE_M * density(z, RAYLEIGH_SCALE_M) + vec3<f32>(haze);
    return frame.shading.sun_top * exp(-frame.shading.air_mass * column);
}

// What the air along a ray does: the light it scatters toward the eye, and the share of the
// light behind it it lets through.
struct Scatter {
    inscatter: vec3<f32>,
    through: vec3<f32>,
}

// The air's (x) and the haze's (y) phase at the cosine `mu` between the ray and the sun, each
// with the isotropic share for the orders of scattering the integral leaves out.
fn phases(mu: f32) -> vec2<f32> {
    let g = MIE_G;
    let rayleigh = 3.0 / 16.0 * (1.0 + mu * mu);
    let mie = 3.0 / 8.0 * (1.0 - g * g) * (1.0 + mu * mu) / ((2.0 + g * g) * pow(1.0 + g * g - 2.0 * g * mu, 1.5));
    return vec2<f32>(rayleigh, mie) + MULTIPLE * 0.25;
}

// The single-scattering integral over `len` metres from height `eye_z` along `dir`, in STEPS
// samples spaced quadratically from the eye, plus an isotropic share for higher orders.
fn scatter(eye_z: f32, dir: vec3<f32>, len: f32) -> Scatter {
    let hm = frame.shading.haze_height_m;
    let haze = frame.shading.haze_per_m;
    let phase = phases(dot(dir, frame.shading.sun));
    var inscatter = vec3<f32>(0.0);
    for (var i = 0; i < STEPS; i++) {
        let u = (f32(i) + 0.5) / f32(STEPS);
        let t = len * u * u;
        let dt = len * 2.0 * u / f32(STEPS);
        let z = eye_z + dir.z * t;
        let scattered = RAYLEIGH * density(z, RAYLEIGH_SCALE_M) * phase.x
            + vec3<f32>(haze * HAZE_ALBEDO * density(z, hm) * phase.y);
        let tau = RAYLEIGH * air_along(eye_z, z, t, RAYLEIGH_SCALE_M) + vec3<f32>(haze * air_along(eye_z, z, t, hm));
        inscatter += scattered * exp(-tau) * sun_at(z) * dt;
    }
    let z1 = eye_z + dir.z * len;
    let tau = RAYLEIGH * air_along(eye_z, z1, len, RAYLEIGH_SCALE_M) + vec3<f32>(haze * air_along(eye_z, z1, len, hm));
    var out: Scatter;
    out.inscatter = inscatter * frame.shading.daylight;
    out.through = exp(-tau);
    return out;
}

// How far a ray from height `eye_z` along `dir` crosses the sky: to the top of the air going
// up, to sea level going down, never past the planar horizon.
fn sky_length(eye_z: f32, dir: vec3<f32>) -> f32 {
    var to = FAR_M;
    if (dir.z > 1e-6) {
        to = max(TOP_M - eye_z, 0.0) / dir.z;
    } else if (dir.z < -1e-6) {
        to = max(eye_z, 0.0) / -dir.z;
    }
    return min(to, FAR_M);
}

// The sky seen from height `eye_z` along `dir`, with the sun's disc (about half a degree wide,
// 40 times the sunlight's radiance: bright enough that the tone map clips it to white).
fn sky_colour(eye_z: f32, dir: vec3<f32>) -> vec3<f32> {
    let len = sky_length(eye_z, dir);
    let air = scatter(eye_z, dir, len);
    let disc = smoothstep(0.99995, 0.99998, dot(dir, frame.shading.sun));
    return air.inscatter + sun_at(eye_z) * air.through * disc * 40.0;
}

// Aerial perspective: the air between the eye and the ground at `dist` takes away the ground's
// light and scatters the sun's in.
fn aerial(colour: vec3<f32>, to_eye: vec3<f32>, dist: f32) -> vec3<f32> {
    let air = scatter(frame.camera.eye.z, -to_eye / dist, dist);
    return colour * air.through + air.inscatter;
}

// Exposure and the tone map (Khronos PBR Neutral: linear through the mid-tones, so the terrain's
// contrast stays as lit, highlights rolled off to white without shifting hue).
fn display(c_in: vec3<f32>) -> vec3<f32> {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    var c = c_in * frame.shading.exposure;
    let x = min(c.r, min(c.g, c.b));
    let offset = select(0.04, x - 6.25 * x * x, x < 0.08);
    c -= offset;
    let peak = max(c.r, max(c.g, c.b));
    if (peak < start) {
        return c;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    c *= new_peak / peak;
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(c, vec3<f32>(new_peak), g);
}

// Low-frequency turbulence that moves the boundaries between surface types, each octave faded
// out as its lattice cells shrink from four to two pixels `footprint` wide, as a texture's mip
// would: a boundary finer than the pixel would alias, and differently in every mode.
fn turbulence(local: vec2<f32>, footprint: f32) -> vec2<f32> {
#ifdef NOISE
    let o = frame.shading.turbulence;
    let fade = vec2<f32>(1.0) - smoothstep(vec2<f32>(0.25), vec2<f32>(0.5), footprint * vec2<f32>(o[0].scale, o[1].scale));
    return fade * vec2<f32>(octave_local(o[0], local).x, octave_local(o[1], local).x);
#else
    return vec2<f32>(0.0);
#endif
}

// The sketch's form around `local` at the scale e of the pixel's footprint (at least four
// sketch cells): its gradient (xy) and how much the ground lies below its surroundings e metres
// around (a gully, > 0) or above them (a ridge, < 0) per metre of e (z), read on the pyramid
// level whose texels are half of e. The surface types follow this form, not the shading normal:
// it is the same in every mode, whatever mesh carries the surface, and band-limited to the pixel.
fn sketch_form(local: vec2<f32>, footprint: f32) -> vec3<f32> {
    // The plain and the sea beyond the sketch are level.
    if (!on_sketch(local, 0.0)) {
        return vec3<f32>(0.0);
    }
    let e = max(footprint, 4.0 * frame.atlas.d_atlas);
    let l = u32(clamp(log2(e / frame.atlas.d_atlas) - 1.0, 0.0, f32(frame.atlas.levels - 1u)));
    let uv = (local + frame.atlas.offset) * frame.atlas.inv_spacing;
    let du = e * frame.atlas.inv_spacing;
    let h = atlas_bilinear(uv, l);
    let east = atlas_bilinear(uv + vec2<f32>(du.x, 0.0), l);
    let west = atlas_bilinear(uv - vec2<f32>(du.x, 0.0), l);
    let north = atlas_bilinear(uv + vec2<f32>(0.0, du.y), l);
    let south = atlas_bilinear(uv - vec2<f32>(0.0, du.y), l);
    let gradient = vec2<f32>(east - west, north - south) / (2.0 * e);
    return vec3<f32>(gradient, (0.25 * (east + west + north + south) - h) / e);
}

// The surface types: rock on cliffs and sharp ridges, scree below them, soil on steep ground and
// in gullies, forest in patches on moderate slopes below the tree line (denser in hollows and on
// slopes facing away from the sun's side of the sky), grass elsewhere, sand at the shore, snow
// above the snow line (lower facing north) where it can lie. Turbulence at 600 m and 150 m moves
// every boundary.
fn albedo(local: vec3<f32>, footprint: f32) -> vec3<f32> {
    let t = turbulence(local.xy, footprint);
    let tt = t.x + 0.5 * t.y;
    let h = local.z + 40.0 * tt;
    let form = sketch_form(local.xy, footprint);
    let steepness = length(form.xy);
    let slope = 1.0 - inverseSqrt(1.0 + steepness * steepness);
    let cav = form.z;
    // Facing north: the ground falls toward the north.
    let north = -form.y / max(steepness, 1e-3) * smoothstep(0.0, 0.05, slope);
    let grass = mix(vec3<f32>(0.13, 0.24, 0.06), vec3<f32>(0.30, 0.33, 0.13), clamp(0.5 + 0.7 * t.y - 0.4 * t.x, 0.0, 1.0));
    let forest = mix(vec3<f32>(0.035, 0.070, 0.030), vec3<f32>(0.06, 0.09, 0.035), 0.5 + 0.5 * t.y);
    let soil = vec3<f32>(0.30, 0.22, 0.14);
    let scree = mix(vec3<f32>(0.42, 0.40, 0.36), vec3<f32>(0.52, 0.49, 0.44), 0.5 + 0.5 * t.y);
    let rock = mix(vec3<f32>(0.22, 0.21, 0.20), vec3<f32>(0.38, 0.35, 0.31), 0.5 + 0.5 * tt);
    let sand = vec3<f32>(0.62, 0.55, 0.40);
    let snow = vec3<f32>(0.86, 0.88, 0.93);
    var c = grass;
    let tree_line = 1600.0 + 200.0 * t.x;
    let wooded = smoothstep(0.0, 0.25, 0.45 * t.x + 0.35 * t.y + 0.3 * north + 10.0 * cav + 0.02)
        * (1.0 - smoothstep(0.22, 0.32, slope)) * (1.0 - smoothstep(tree_line - 100.0, tree_line, h));
    c = mix(c, forest, wooded);
    c = mix(c, soil, smoothstep(0.16, 0.26, slope + 0.06 * t.y + 2.0 * max(cav, 0.0)) * (1.0 - wooded));
    let steep = slope + 0.08 * tt - 2.0 * cav;
    c = mix(c, scree, smoothstep(0.26, 0.36, slope + 0.08 * t.y) * smoothstep(-0.01, 0.02, cav));
    c = mix(c, rock, smoothstep(0.36, 0.48, steep));
    c = mix(c, sand, 1.0 - smoothstep(frame.atlas.water_m + 2.0, frame.atlas.water_m + 8.0, h));
    let snow_line = 1800.0 - 250.0 * north;
    let snowy = smoothstep(snow_line, snow_line + 150.0, h) * (1.0 - smoothstep(0.45, 0.6, slope));
    return mix(c, snow, snowy);
}

#ifdef SHADOWS
const SHADOW_STEPS: i32 = 40;

// What can cast a shadow at `local`: the sketch (level `l`, or the water over it) on its
// rectangle, the plain or the sea beyond it (whose flat ground casts none), nothing over the void.
fn shadow_caster(local: vec2<f32>, l: u32) -> f32 {
    if (on_sketch(local, 0.0)) {
        let ground = atlas_bilinear((local + frame.atlas.offset) * frame.atlas.inv_spacing, l);
        return max(ground, frame.atlas.water_m);
    }
    switch frame.shading.outside {
        case 1u: { return frame.shading.plain_m; }
        case 2u: { return frame.atlas.water_m; }
        default: { return -1.0e30; }
    }
}

#ifdef DETAIL_SHADOWS
const NEAR_STEPS: i32 = 5;

// The detail's own shadow (the octaves, whether a mesh carries them as geometry or as bump): the
// sun ray over the first two sketch cells, marched from twice the pixel's footprint in steps
// growing geometrically, against the sketch (bilinear) plus the octaves down to twice each step's
// own footprint (a cone: far steps see only the broad octaves; a shadow finer than two pixels is
// not drawn). The ray leaves from this same function's height at the pixel, not the mesh's, so
// every mode casts the same shadow and no mesh shadows itself.
fn detail_visibility(local: vec2<f32>, footprint: f32) -> f32 {
    let sun = frame.shading.sun;
    let d = frame.atlas.d_atlas;
    let t_end = 2.0 * d;
    let fine = 2.0 * footprint;
    var t = max(fine, 0.01 * d);
    if (t >= t_end) {
        return 1.0;
    }
    let grow = pow(t_end / t, 1.0 / f32(NEAR_STEPS));
    let caster = atlas_bilinear((local + frame.atlas.offset) * frame.atlas.inv_spacing, 0u);
    let z0 = max(caster + surface_octaves(local, fine).x, frame.atlas.water_m);
    var seen = 1.0;
    for (var i = 0; i < NEAR_STEPS; i++) {
        count_shadow_step();
        let p = local + sun.xy * t;
        let ground = atlas_bilinear((p + frame.atlas.offset) * frame.atlas.inv_spacing, 0u)
            + surface_octaves(p, max(fine, 0.5 * t)).x;
        let under = max(ground, frame.atlas.water_m);
        seen = min(seen, clamp(0.5 + (z0 + sun.z * t - under) / (0.03 * t), 0.0, 1.0));
        t *= grow;
    }
    return seen;
}
#endif

// How much of the sun the ground at `local` sees, its pixel `footprint` metres wide: past the
// detail (DETAIL_SHADOWS), then past the sketch on no level finer than the pixel's footprint
// (`sketch_sun_visibility`; with SUN_MAP, read from the sun clearance map where it decides).
fn sun_visibility(local: vec3<f32>, footprint: f32) -> f32 {
    if (frame.shading.sun.z <= 0.0) {
        return 0.0;
    }
    // The sketch under a pixel is band-limited to its footprint: the ray reads no level finer
    // than the footprint's, so a far pixel neither pays for nor (streamed) asks for level-0
    // tiles whose detail it cannot show.
    let lf = clamp(log2(max(footprint / frame.atlas.d_atlas, 1.0)), 0.0, f32(frame.atlas.levels - 1u));
#ifdef SUN_MAP
    var seen = sun_seen_at(local.xy, u32(lf));
#else
    var seen = sketch_sun_visibility(local.xy, u32(lf));
#endif
#ifdef DETAIL_SHADOWS
    // The detail's march, the costlier, only where the sketch leaves some sun.
    if (seen > 0.0) {
        seen = min(seen, detail_visibility(local.xy, footprint));
    }
#endif
    return seen;
}

// A ray that passes beyond the sketch's edge below its highest point, in the sun clearance map
// (src/gpu/sun_map.rs): the ground beyond (a plain, the sea) changes its clearance abruptly
// between texels; near such a texel the march runs per pixel.
const LEFT_SKETCH: f32 = 1.0e30;

// How much of the sun the sketch leaves at `local`, read from level `l` and coarser.
fn sketch_sun_visibility(local: vec2<f32>, l: u32) -> f32 {
    if (!on_sketch(local, 0.0) && !meets_sketch(local)) {
        return clamp(0.5 + flat_clearance(local, l), 0.0, 1.0);
    }
    return clamp(0.5 + sketch_sun_clearance(local, l, true, false), 0.0, 1.0);
}

// Whether the sun ray from `local` beside the sketch crosses the sketch's rectangle below its
// highest point (the slab test; the ray leaves from the ground beyond, `shadow_caster`).
fn meets_sketch(local: vec2<f32>) -> bool {
    let sun = frame.shading.sun;
    var near = 0.0;
    var far = 1.0e30;
    for (var a = 0; a < 2; a++) {
        let lo = sketch_lo()[a] - local[a];
        let hi = sketch_hi()[a] - local[a];
        if (abs(sun[a]) < 1e-9) {
            if (lo > 0.0 || hi < 0.0) {
                return false;
            }
        } else {
            let t1 = lo / sun[a];
            let t2 = hi / sun[a];
            near = max(near, min(t1, t2));
            far = min(far, max(t1, t2));
        }
    }
    return far >= near && shadow_caster(local, 0u) + sun.z * near <= frame.atlas.max_m;
}

// The march's clearance over flat ground beyond the sketch that its ray never crosses: the
// ground (a plain, the sea) shadows only itself, alike at every step, so the first step tells.
fn flat_clearance(local: vec2<f32>, l: u32) -> f32 {
    let t = 2.0 * frame.atlas.d_atlas;
    let z0 = shadow_caster(local, l);
    let z = z0 + frame.shading.sun.z * t;
    if (z > frame.atlas.max_m) {
        return 0.5;
    }
    return min(0.5, (z - z0) / (0.03 * t));
}

// The sketch's shadow at `local`: a ray marched toward the sun in steps that grow with distance,
// each sampling the pyramid level whose texels match the step (a cone) from level `l` on, until it
// rises above the sketch's highest point; its least clearance over the ground, in penumbra widths
// (3 % of the distance, a sun of finite size), is the shadow: clamp(0.5 + clearance, 0, 1) of the
// sun is seen. The ray leaves from the sketch's own height under the point, two cells out (where
// the detail's ends): the detail a mesh or the reference adds is the detail's to shadow, so a dip
// in it is not shadowed by the bare sketch around it, in every mode alike. Above 0.5 the sun is
// whole, so no more is kept; `stop` ends the march once the sun is gone (below −0.5), `edge`
// once the ray passes beyond the sketch's edge, with LEFT_SKETCH.
fn sketch_sun_clearance(local: vec2<f32>, l: u32, stop: bool, edge: bool) -> f32 {
    let sun = frame.shading.sun;
    let d = frame.atlas.d_atlas;
    let lf = f32(l);
    let start = vec3<f32>(local, shadow_caster(local, l));
    var t = 2.0 * d;
    var least = 0.5;
    for (var i = 0; i < SHADOW_STEPS; i++) {
        count_shadow_step();
        let p = start + sun * t;
        if (p.z > frame.atlas.max_m) {
            break;
        }
        if (edge && !on_sketch(p.xy, 0.0)) {
            return LEFT_SKETCH;
        }
        let level = u32(clamp(max(log2(max(0.25 * t / d, 1.0)), lf), 0.0, f32(frame.atlas.levels - 1u)));
        least = min(least, (p.z - shadow_caster(p.xy, level)) / (0.03 * t));
        if (stop && least <= -0.5) {
            break;
        }
        t += max(0.25 * t, 0.5 * d);
    }
    return least;
}

#ifdef SUN_MAP
// The sketch's sun clearance map (src/gpu/sun_map.rs): `sketch_sun_clearance` from the centre
// of every texel of every level, laid out as the atlas's levels, remade when the sun moves.
@group(0) @binding(9) var<storage, read> sun_seen: array<f32>;

fn seen_texel(l: u32, x: i32, y: i32) -> f32 {
    count_atlas_tap();
    let c = vec2<u32>(clamp(vec2<i32>(x, y), vec2<i32>(0), vec2<i32>(frame.atlas.level[l].xy) - 1));
    return sun_seen[frame.atlas.level[l].z + c.y * frame.atlas.level[l].x + c.x];
}

// The sketch's shadow at `local` from the map's level `l`: where the four texel centres around it
// all see the whole sun, or all none of it, so does `local` (a shadow narrower than a texel between
// them is lost); elsewhere (shadow boundaries and penumbrae, which no interpolation of the
// texels' values follows on steep ground, the sketch's edges, the plain or the sea around it,
// which the sketch shadows near its edges) the march.
fn sun_seen_at(local: vec2<f32>, l: u32) -> f32 {
    let x = level_coords((local + frame.atlas.offset) * frame.atlas.inv_spacing, l);
    let s = f32(1u << l);
    let far = s * (floor(x) + 1.0) + 0.5 * (s - 1.0);
    if (any(x < vec2<f32>(0.0)) || any(far > vec2<f32>(frame.atlas.level[0].xy - 1u))) {
        return sketch_sun_visibility(local, l);
    }
    let i = vec2<i32>(floor(x));
    let f = x - floor(x);
    let a = vec2<f32>(seen_texel(l, i.x, i.y), seen_texel(l, i.x + 1, i.y));
    let b = vec2<f32>(seen_texel(l, i.x, i.y + 1), seen_texel(l, i.x + 1, i.y + 1));
    let lo = min(min(a.x, a.y), min(b.x, b.y));
    let hi = max(max(a.x, a.y), max(b.x, b.y));
    if (lo >= 0.5 && hi < LEFT_SKETCH) {
        return 1.0;
    }
    if (hi <= -0.5) {
        return 0.0;
    }
    return sketch_sun_visibility(local, l);
}
#endif
#endif

// The lit colour of ground at `local` with normal `n`, seen from `to_eye` (distance `dist`):
// sunlight at the ground's height, shadowed, and the sky's light by how much of the sky the
// ground faces. On the water's surface (`sketch.water_level_m`), water: its body lit alike, and
// the sky it reflects (Schlick).
fn lit(local: vec3<f32>, n: vec3<f32>, to_eye: vec3<f32>, dist: f32) -> vec3<f32> {
    let sun_light = sun_at(local.z);
    if (on_water(local.z)) {
        let up = vec3<f32>(0.0, 0.0, 1.0);
        let cos_v = clamp(to_eye.z / dist, 0.0, 1.0);
        let fresnel = 0.02 + 0.98 * pow(1.0 - cos_v, 5.0);
        let reflected = sky_colour(local.z, reflect(-to_eye / dist, up));
        let body = vec3<f32>(0.015, 0.045, 0.06) * (sun_light * max(frame.shading.sun.z, 0.0) + frame.shading.sky_light);
        return mix(body, reflected, fresnel);
    }
    let footprint = dist * frame.camera.pixel_scale;
    var sun = max(dot(n, frame.shading.sun), 0.0);
#ifdef SHADOWS
    if (sun > 0.0) {
        sun *= sun_visibility(local, footprint);
    }
#endif
    let light = sun_light * sun + frame.shading.sky_light * (0.5 + 0.5 * n.z);
    return albedo(local, footprint) * light;
}

// The world beyond the sketch seen along `dir` from `eye`: a plain at the sketch's mean edge
// height or the sea, to the horizon, lit and hazed like the terrain (and shadowed by it); w is 1
// where it is seen, 0 for sky, for the sketch's own rectangle and with `sketch.outside = "void"`.
fn beyond(eye: vec3<f32>, dir: vec3<f32>) -> vec4<f32> {
    let kind = frame.shading.outside;
    // A plain below the water's surface is under water.
    let level = select(max(frame.shading.plain_m, frame.atlas.water_m), frame.atlas.water_m, kind == 2u);
    if (kind == 0u || dir.z >= 0.0 || eye.z <= level) {
        return vec4<f32>(0.0);
    }
    let t = (level - eye.z) / dir.z;
    let p = eye + dir * t;
    if (on_sketch(p.xy, 0.0)) {
        return vec4<f32>(0.0);
    }
    // At the water's height the shading draws water.
    let ground = vec3<f32>(p.xy, level);
    let to_eye = eye - ground;
    return vec4<f32>(aerial(lit(ground, vec3<f32>(0.0, 0.0, 1.0), to_eye, t), to_eye, t), 1.0);
}
