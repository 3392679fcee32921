// Surface shading shared by the mesh renderers and the reference ray marcher: sky, surface
// types, sun and sky light, the sketch's shadow (SHADOWS), aerial perspective through air that
// thins with height, and the world beyond the sketch. Needs `frame`; turbulence needs the noise,
// the shadow the atlas.
#ifdef NOISE
#import noise
#endif
#ifdef SHADOWS
#import atlas
#endif

const SEA_LEVEL: f32 = 0.0;
// Rayleigh extinction at sea level per metre (red, green, blue) and its scale height: the twin
// of src/light.rs's RAYLEIGH and RAYLEIGH_SCALE_M.
const RAYLEIGH: vec3<f32> = vec3<f32>(5.8e-6, 13.5e-6, 33.1e-6);
const RAYLEIGH_SCALE_M: f32 = 8000.0;

fn sky_colour(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.z, -0.2, 1.0);
    // The horizon takes the low sun's colour; the sky dims through twilight.
    let warm = frame.shading.sun_colour / vec3<f32>(1.1, 1.045, 0.935);
    let horizon = vec3<f32>(0.72, 0.80, 0.90) * mix(vec3<f32>(1.0), warm, 0.35);
    let zenith = vec3<f32>(0.22, 0.42, 0.78);
    var c = mix(horizon, zenith, pow(max(up, 0.0), 0.6)) * (0.04 + 0.96 * frame.shading.daylight);
    let sun = max(dot(dir, frame.shading.sun), 0.0);
    c += frame.shading.sun_colour * vec3<f32>(0.91, 0.81, 0.64) * (pow(sun, 400.0) * 4.0 + pow(sun, 12.0) * 0.25);
    return c;
}

// Low-frequency turbulence that moves the boundaries between surface types.
fn turbulence(local: vec2<f32>) -> f32 {
#ifdef NOISE
    return octave_local(frame.shading.turbulence[0], local).x + 0.5 * octave_local(frame.shading.turbulence[1], local).x;
#else
    return 0.0;
#endif
}

fn albedo(local: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let t = turbulence(local.xy);
    let h = local.z + 40.0 * t;
    let slope = 1.0 - n.z;
    let grass = mix(vec3<f32>(0.20, 0.33, 0.10), vec3<f32>(0.33, 0.40, 0.16), 0.5 + 0.5 * t);
    let soil = vec3<f32>(0.42, 0.34, 0.24);
    let sand = vec3<f32>(0.70, 0.63, 0.46);
    let rock = mix(vec3<f32>(0.36, 0.33, 0.30), vec3<f32>(0.50, 0.47, 0.43), 0.5 + 0.5 * t);
    let snow = vec3<f32>(0.92, 0.93, 0.96);
    var c = grass;
    c = mix(c, soil, smoothstep(0.18, 0.30, slope + 0.08 * t));
    c = mix(c, rock, smoothstep(0.32, 0.45, slope + 0.1 * t));
    c = mix(c, sand, 1.0 - smoothstep(SEA_LEVEL + 2.0, SEA_LEVEL + 8.0, h));
    // Snow settles above the snow line, lower on north-facing slopes, and slides off cliffs.
    let snow_line = 1800.0 - 250.0 * n.y;
    let snowy = smoothstep(snow_line, snow_line + 150.0, h) * (1.0 - smoothstep(0.45, 0.6, slope));
    return mix(c, snow, snowy);
}

#ifdef SHADOWS
const SHADOW_STEPS: i32 = 40;

// What can cast a shadow at `local`: the sketch (level `l`) on its rectangle, the plain or the
// sea beyond it (whose flat ground casts none), nothing over the void.
fn shadow_caster(local: vec2<f32>, l: u32) -> f32 {
    if (on_sketch(local, 0.0)) {
        return atlas_bilinear((local + frame.atlas.offset) * frame.atlas.inv_spacing, l);
    }
    switch frame.shading.outside {
        case 1u: { return frame.shading.plain_m; }
        case 2u: { return SEA_LEVEL; }
        default: { return -1.0e30; }
    }
}

// How much of the sun the ground at `local` sees past the sketch: a ray marched toward the sun in
// steps that grow with distance, each sampling the pyramid level whose texels match the step (a
// cone), soft by the closest miss (the penumbra of a sun of finite size), until it rises above
// the sketch's highest point. The ray starts two cells
// out, so the octaves a mesh adds to the sketch do not shadow the point they lift.
fn sun_visibility(local: vec3<f32>) -> f32 {
    let sun = frame.shading.sun;
    if (sun.z <= 0.0) {
        return 0.0;
    }
    let d = frame.atlas.d_atlas;
    var t = 2.0 * d;
    var seen = 1.0;
    for (var i = 0; i < SHADOW_STEPS; i++) {
        let p = local + sun * t;
        if (p.z > frame.atlas.max_m) {
            break;
        }
        let l = u32(clamp(log2(max(0.25 * t / d, 1.0)), 0.0, f32(frame.atlas.levels - 1u)));
        let clearance = p.z - shadow_caster(p.xy, l);
        seen = min(seen, clamp(0.5 + clearance / (0.03 * t), 0.0, 1.0));
        if (seen <= 0.0) {
            break;
        }
        t += max(0.25 * t, 0.5 * d);
    }
    return seen;
}
#endif

// The lit colour of ground at `local` with normal `n`, seen from `to_eye` (distance `dist`).
fn lit(local: vec3<f32>, n: vec3<f32>, to_eye: vec3<f32>, dist: f32) -> vec3<f32> {
    if (local.z < SEA_LEVEL) {
        let fresnel = pow(1.0 - clamp(to_eye.z / dist, 0.0, 1.0), 4.0);
        let reflected = sky_colour(reflect(-to_eye / dist, vec3<f32>(0.0, 0.0, 1.0)));
        return mix(vec3<f32>(0.04, 0.12, 0.20), reflected, fresnel);
    }
    var sun = max(dot(n, frame.shading.sun), 0.0);
#ifdef SHADOWS
    if (sun > 0.0) {
        sun *= sun_visibility(local);
    }
#endif
    let sky = 0.35 * (0.6 + 0.4 * n.z) * (0.04 + 0.96 * frame.shading.daylight);
    let light = frame.shading.sun_colour * sun + vec3<f32>(0.55, 0.65, 0.85) * sky;
    return albedo(local, n) * light;
}

// The air along a segment from height z0 to z1, `dist` long, whose density falls as
// exp(−z / scale): ∫ exp(−z(t) / scale) dt, in metres of sea-level air.
fn air_along(z0: f32, z1: f32, dist: f32, scale: f32) -> f32 {
    let x = (z1 - z0) / scale;
    // (1 − e^−x) / x, by its series where x is too small for the quotient.
    let f = select((1.0 - exp(-x)) / x, 1.0 - 0.5 * x, abs(x) < 1e-3);
    return dist * exp(-z0 / scale) * f;
}

// Aerial perspective: the air and haze between the eye and the ground, each thinning
// exponentially with height, take away the ground's light and scatter in the horizon sky's.
fn aerial(colour: vec3<f32>, to_eye: vec3<f32>, dist: f32) -> vec3<f32> {
    let z_eye = frame.camera.eye.z;
    let z_ground = z_eye - to_eye.z;
    let tau = RAYLEIGH * air_along(z_eye, z_ground, dist, RAYLEIGH_SCALE_M)
        + vec3<f32>(frame.shading.haze_per_m * air_along(z_eye, z_ground, dist, frame.shading.haze_height_m));
    let through = exp(-tau);
    let horizon = normalize(-to_eye) * vec3<f32>(1.0, 1.0, 0.0) + vec3<f32>(0.0, 0.0, 0.02);
    return colour * through + sky_colour(horizon) * (1.0 - through);
}

// The world beyond the sketch seen along `dir` from `eye`: a plain at the sketch's mean edge
// height or the sea, to the horizon, lit and hazed like the terrain (and shadowed by it); w is 1
// where it is seen, 0 for sky, for the sketch's own rectangle and with `sketch.outside = "void"`.
fn beyond(eye: vec3<f32>, dir: vec3<f32>) -> vec4<f32> {
    let kind = frame.shading.outside;
    let level = select(frame.shading.plain_m, SEA_LEVEL, kind == 2u);
    if (kind == 0u || dir.z >= 0.0 || eye.z <= level) {
        return vec4<f32>(0.0);
    }
    let t = (level - eye.z) / dir.z;
    let p = eye + dir * t;
    if (on_sketch(p.xy, 0.0)) {
        return vec4<f32>(0.0);
    }
    // Just under sea level the shading draws water.
    let ground = vec3<f32>(p.xy, select(level, SEA_LEVEL - 0.01, kind == 2u));
    let to_eye = eye - ground;
    return vec4<f32>(aerial(lit(ground, vec3<f32>(0.0, 0.0, 1.0), to_eye, t), to_eye, t), 1.0);
}
