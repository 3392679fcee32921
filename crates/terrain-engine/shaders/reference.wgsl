// The reference: per pixel, a ray marched to the terrain function (the sketch, bicubic at the
// pixel's footprint, plus every octave k with b_k = clamp(o_px − k + 1, 0, 1) as geometry),
// shaded as the meshes are, with the normal of that same function. Writes display colour (tone
// mapped, before sRGB encoding) and the hit position (metres from the frame origin; w = 1 on
// terrain, 0 on sky) per pixel; with SUPERSAMPLE the colour averages four rays at the 4×
// multisampling positions, as the mesh modes' multisampled edges are.
//
// March: steps of `step factor` × the height above the ground, at least that fraction of the
// pixel's footprint, then a bisection of the last step. Halving the factor is the convergence
// check (tests/reference.rs).

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
#import surface
#import shading

@group(0) @binding(2) var<storage, read_write> colour_out: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> position_out: array<vec4<f32>>;

const MAX_STEPS: u32 = 4096u;

// The part of the ray inside the box of the sketch's rectangle and its heights, or t0 > t1.
fn span(eye: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    return box_span(eye, dir, vec3<f32>(sketch_lo(), frame.march.lo), vec3<f32>(sketch_hi(), frame.march.hi));
}

// A ray from the eye through `ndc`: what it sees (display colour, when `shade`) and where it hits
// the ground (w = 1) or not (w = 0).
struct Ray {
    colour: vec3<f32>,
    hit: vec4<f32>,
}

fn trace(ndc: vec2<f32>, shade: bool) -> Ray {
    // Reversed-Z: depth 1e-4 is ~500 m out, far enough that f32 rounding of the point does not
    // bend the direction (at 0.5 it lay 0.1 m from the eye, and rays missed by 0.1 px).
    let far = frame.camera.inv_view_proj * vec4<f32>(ndc, 1e-4, 1.0);
    let eye = frame.camera.eye;
    let dir = normalize(far.xyz / far.w - eye);
    let range = span(eye, dir);
    var t = range.x;
    var t_prev = range.x;
    var hit = false;
    // The last sample is taken at the box's exit itself: a ray leaving through the floor (the
    // lowest the surface goes) has reached the surface there. Stepping past it instead missed a
    // plain lying exactly at the sketch's lowest height, seen from above.
    for (var step = 0u; step < MAX_STEPS && t_prev < range.y; step++) {
        t = min(t, range.y);
        let p = eye + dir * t;
        let footprint = t * frame.camera.pixel_scale;
        let above = p.z - surface_height(p.xy, footprint);
        if (above <= 0.0) {
            hit = true;
            break;
        }
        t_prev = t;
        t += max(above, footprint) * frame.march.step;
    }
    // A ray entering the box through a side wall already under the surface comes from beyond the
    // sketch, under the margin, the plain or the water there: it met that first, as the mesh
    // modes' sky pass draws it.
    let entered_under = hit && range.x > 0.0 && t == range.x;
    var outside = vec4<f32>(0.0);
    if ((!hit && shade) || entered_under) {
        outside = beyond(eye, dir);
    }
    if (entered_under && outside.w > 0.0) {
        hit = false;
    }
    var ray: Ray;
    if (!hit && !shade) {
        return ray;
    }
    if (!hit) {
        ray.colour = display(mix(sky_colour(eye.z, dir), outside.rgb, outside.w));
        ray.hit = vec4<f32>(0.0);
        return ray;
    }
    // Bisect the last step to the crossing.
    var lo = t_prev;
    var hi = t;
    for (var i = 0u; i < 16u; i++) {
        let mid = 0.5 * (lo + hi);
        let p = eye + dir * mid;
        if (p.z - surface_height(p.xy, mid * frame.camera.pixel_scale) > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t_hit = 0.5 * (lo + hi);
    let footprint = t_hit * frame.camera.pixel_scale;
    let p = eye + dir * t_hit;
    ray.hit = vec4<f32>(p, 1.0);
    if (!shade) {
        return ray;
    }
    let g = surface_gradient(p.xy, footprint);
    let n = normalize(vec3<f32>(-g, 1.0));
    let to_eye = eye - p;
    let dist = max(length(to_eye), 1e-3);
    ray.colour = display(aerial(lit(p, n, to_eye, dist), to_eye, dist));
    return ray;
}

// The colour's alpha at a pixel whose centre's ray met `hit` (w = 1 on ground): the mesh modes'
// water flag (`water_alpha`), for the output pass.
fn ground_alpha(hit: vec4<f32>) -> f32 {
    return select(1.0, water_alpha(hit.z), hit.w > 0.5);
}

fn ndc_of(pixel: vec2<f32>) -> vec2<f32> {
    let size = vec2<f32>(frame.camera.image);
    return vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
}

#ifdef SUPERSAMPLE
// The standard 4× multisampling positions within a pixel (y down), which the mesh modes'
// multisampled edges are resolved from: the reference averages its rays alike, in display
// colour as the hardware resolve does.
const SAMPLES: array<vec2<f32>, 4> = array<vec2<f32>, 4>(
    vec2<f32>(0.375, 0.125),
    vec2<f32>(0.875, 0.375),
    vec2<f32>(0.125, 0.625),
    vec2<f32>(0.625, 0.875),
);
#endif

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = frame.camera.image;
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let k = id.y * size.x + id.x;
    // The position is the pixel centre's, as the mesh modes' depth is.
#ifdef SUPERSAMPLE
    position_out[k] = trace(ndc_of(vec2<f32>(id.xy) + 0.5), false).hit;
    var sum = vec3<f32>(0.0);
    for (var i = 0; i < 4; i++) {
        sum += trace(ndc_of(vec2<f32>(id.xy) + SAMPLES[i]), true).colour;
    }
    colour_out[k] = vec4<f32>(0.25 * sum, ground_alpha(position_out[k]));
#else
    let centre = trace(ndc_of(vec2<f32>(id.xy) + 0.5), true);
    position_out[k] = centre.hit;
    colour_out[k] = vec4<f32>(centre.colour, ground_alpha(centre.hit));
#endif
    add_work();
}
