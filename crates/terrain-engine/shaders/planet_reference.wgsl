// The planet's reference: per pixel, a ray marched to the terrain function on the sphere (the
// sketch at the pixel's footprint plus every octave k with b_k as geometry, `planet_ground`),
// shaded as the planet pass shades, with the normal of that same function. Writes display
// colour and the hit position (metres in the nadir's tangent frame; w = 1 on ground, 0 on sky).
//
// March: from where the ray enters the sphere of the highest ground, steps of `step factor` ×
// the height above the ground (at least that fraction of the pixel's footprint), until it is
// under the ground or leaves that sphere; then a bisection of the last step.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(4) var<uniform> planet: Planet;
#import sphere

@group(0) @binding(2) var<storage, read_write> colour_out: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> position_out: array<vec4<f32>>;

const MAX_STEPS: u32 = 4096u;

// Where a ray from `eye` along `dir` is inside the sphere of radius R + `top` (t0 > t1: never).
fn shell(eye: vec3<f32>, dir: vec3<f32>, top: f32) -> vec2<f32> {
    let r = planet.radius;
    let b = (r + eye.z) * dir.z + dot(eye.xy, dir.xy);
    let c = (eye.z - top) * (2.0 * r + eye.z + top) + dot(eye.xy, eye.xy);
    let disc = b * b - c;
    if (disc <= 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let q = -(b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc));
    let t_b = select(c / q, 0.0, q == 0.0);
    return vec2<f32>(max(min(q, t_b), 0.0), max(q, t_b));
}

// How far the point `p` (`t` along the ray) lies above the ground there.
fn above(p: vec3<f32>, t: f32) -> f32 {
    return planet_altitude(p) - planet_ground(hemisphere_of(p), t * frame.camera.pixel_scale);
}

struct Ray {
    colour: vec3<f32>,
    hit: vec4<f32>,
}

fn trace(ndc: vec2<f32>) -> Ray {
    // The point at infinity under the pixel: a direction, free of the eye's translation.
    let dir = normalize((frame.camera.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0)).xyz);
    let eye = frame.camera.eye;
    let range = shell(eye, dir, frame.march.hi);
    var t = range.x;
    var t_prev = range.x;
    var hit = false;
    for (var step = 0u; step < MAX_STEPS && t_prev < range.y; step++) {
        t = min(t, range.y);
        let a = above(eye + dir * t, t);
        if (a <= 0.0) {
            hit = true;
            break;
        }
        t_prev = t;
        t += max(a, t * frame.camera.pixel_scale) * frame.march.step;
    }
    var ray: Ray;
    if (!hit) {
        ray.colour = planet_sky(eye, dir);
        return ray;
    }
    var lo = t_prev;
    var hi = t;
    for (var i = 0u; i < 16u; i++) {
        let mid = 0.5 * (lo + hi);
        if (above(eye + dir * mid, mid) > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t_hit = 0.5 * (lo + hi);
    let p = eye + dir * t_hit;
    let footprint = t_hit * frame.camera.pixel_scale;
    // The normal of the terrain function: central differences along two tangents of the sphere
    // at the hit, over the footprint, at least 5 cm: heights of kilometres keep a few tenths of a
    // millimetre in f32, so a shorter span would turn their rounding into slope.
    let up = normalize(p + vec3<f32>(0.0, 0.0, planet.radius));
    let side = normalize(cross(up, select(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(1.0, 0.0, 0.0), abs(up.z) > 0.9)));
    let fwd = cross(up, side);
    let e = max(footprint, 0.05);
    let h = planet_ground(hemisphere_of(p), footprint);
    let ds = planet_ground(hemisphere_of(p + side * e), footprint) - planet_ground(hemisphere_of(p - side * e), footprint);
    let df = planet_ground(hemisphere_of(p + fwd * e), footprint) - planet_ground(hemisphere_of(p - fwd * e), footprint);
    let n = normalize(up - (side * ds + fwd * df) / (2.0 * e));
    let to_eye = eye - p;
    let dist = max(length(to_eye), 1e-3);
    let air = planet_scatter(eye, -to_eye / dist, dist);
    ray.colour = planet_lit(p, n, h, to_eye, dist) * air.through + air.inscatter;
    ray.hit = vec4<f32>(p, 1.0);
    return ray;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = frame.camera.image;
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let k = id.y * size.x + id.x;
    let pixel = vec2<f32>(id.xy) + 0.5;
    let ndc = vec2<f32>(pixel.x / f32(size.x) * 2.0 - 1.0, 1.0 - pixel.y / f32(size.y) * 2.0);
    let ray = trace(ndc);
    colour_out[k] = vec4<f32>(display(ray.colour), 1.0);
    position_out[k] = ray.hit;
    add_work();
}
