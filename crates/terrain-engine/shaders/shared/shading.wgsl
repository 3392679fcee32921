// Surface shading shared by the mesh renderers and the reference ray marcher: the sky and the
// aerial perspective from one single-scattering atmosphere (the twin of src/light.rs), surface
// types from slope, height, aspect and curvature, water, sun and sky light, the sketch's shadow
// (SHADOWS) and the detail's (DETAIL_SHADOWS), the world beyond the sketch, exposure and the
// tone map. Needs `frame` and the atlas.
#import atlas
#import surface
#import constants

// Ground within this of the water's surface is water (the reference's bisection lands within it).
const ON_WATER_M: f32 = 0.01;

// Whether ground at height `z` is the water's surface.
fn on_water(z: f32) -> bool {
    return z <= frame.atlas.water_m + ON_WATER_M;
}

// The frame colour's alpha at ground of height `z`: 0 where the shaded picture shows water, 1
// elsewhere, for the output pass, which gives specks of water or land (regions under 4 pixels)
// the colour of the region around them. A ramp colours the bed, so no ground is water then.
fn water_alpha(z: f32) -> f32 {
#ifdef RAMP
    return 1.0;
#else
    return select(1.0, 0.0, on_water(z) && frame.camera.view == VIEW_SHADED);
#endif
}
// The atmosphere's constants (RAYLEIGH, RAYLEIGH_SCALE_M, HAZE_ALBEDO, MIE_G, MULTIPLE, STEPS,
// TOP_M, FAR_M) are src/light.rs's, through `#import constants`.

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
    // The surface view's colours are labels: no air between them and the eye.
    if (frame.camera.view == VIEW_SURFACE) {
        return Scatter(vec3<f32>(0.0), vec3<f32>(1.0));
    }
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
    if (frame.camera.view == VIEW_SURFACE) {
        return c_in;
    }
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

// The sketch's form around `local` at the scale e of the pixel's footprint (at least four
// sketch cells): its gradient (xy); how much the ground lies below its surroundings e metres
// around (a gully, > 0) or above them (a ridge, < 0) per metre of e (z), read on the pyramid
// level whose texels are half of e; and (w) how far it lies below the land B = max(BROAD_M,
// 4e) around it per metre of B (> 0 toward the valley floor), read alike on B's level. The
// surface types follow this form, not the shading normal: it is the same in every mode, whatever
// mesh carries the surface, and band-limited to the pixel.
fn sketch_form(local: vec2<f32>, footprint: f32) -> vec4<f32> {
    // The plain and the sea beyond the margin are level.
    if (!on_sketch(local, frame.shading.margin_m)) {
        return vec4<f32>(0.0);
    }
    let e = max(footprint, 4.0 * frame.atlas.d_atlas);
    let near = ring(local, e);
    return vec4<f32>(near, ring(local, max(BROAD_M, 4.0 * e)).z);
}

// The land B metres around `local`, read on the level whose texels are half of B (the margin's
// beyond the sketch, so the surface types run on across its edge): its gradient (xy) and how far
// the centre lies below the mean of the four points B away, per metre of B (z).
fn ring(local: vec2<f32>, b: f32) -> vec3<f32> {
    let l = u32(clamp(log2(b / frame.atlas.d_atlas) - 1.0, 0.0, f32(frame.atlas.levels - 1u)));
    let h = ground_bilinear(local, l);
    let east = ground_bilinear(local + vec2<f32>(b, 0.0), l);
    let west = ground_bilinear(local - vec2<f32>(b, 0.0), l);
    let north = ground_bilinear(local + vec2<f32>(0.0, b), l);
    let south = ground_bilinear(local - vec2<f32>(0.0, b), l);
    let gradient = vec2<f32>(east - west, north - south) / (2.0 * b);
    return vec3<f32>(gradient, (0.25 * (east + west + north + south) - h) / b);
}

// The least width of the land a point's height above its surroundings is measured over: a
// valley's floor lies below its ridges over a few kilometres.
const BROAD_M: f32 = 2000.0;

// The surface types, each from what the ground is, never from a pattern of its own (docs/picture.md,
// "Surface types"): grass, lusher toward the valley floor and drier on crests; forest on moderate
// slopes and in hollows below the tree line; bare soil on steep ground; rock and scree on cliffs;
// sand at the shore; snow above the snow line (lower facing north) where it can lie. The
// vegetation differs in hue, not brightness (Rec. 709 luminance 0.15 within 5 %), and the bare
// ground and the shore are at most 1.6 times as bright: the light, not the colour, draws the
// relief. Every weight
// is a smoothstep of the form at the pixel's footprint, so a transition is as wide as the
// landform that makes it.
fn albedo(local: vec3<f32>, footprint: f32) -> vec3<f32> {
    let w = cover(local, footprint);
    let meadow = vec3<f32>(0.100, 0.175, 0.062);
    let heath = vec3<f32>(0.170, 0.163, 0.080);
    let forest = vec3<f32>(0.070, 0.170, 0.085);
    let soil = vec3<f32>(0.250, 0.205, 0.150);
    let scree = vec3<f32>(0.260, 0.250, 0.235);
    let rock = vec3<f32>(0.230, 0.222, 0.210);
    let sand = vec3<f32>(0.220, 0.195, 0.145);
    let snow = vec3<f32>(0.800, 0.820, 0.870);
    var c = mix(meadow, heath, w.dry);
    c = mix(c, forest, w.wooded);
    c = mix(c, soil, w.soil);
    c = mix(c, scree, w.scree);
    c = mix(c, rock, w.rock);
    c = mix(c, sand, w.sand);
    return mix(c, snow, w.snowy);
}

// The surface types' weights at a point, each laid over the ones before it in this order.
struct Cover {
    dry: f32,
    wooded: f32,
    soil: f32,
    scree: f32,
    rock: f32,
    sand: f32,
    snowy: f32,
}

fn cover(local: vec3<f32>, footprint: f32) -> Cover {
    let form = sketch_form(local.xy, footprint);
    let steepness = length(form.xy);
    let slope = 1.0 - inverseSqrt(1.0 + steepness * steepness);
    let hollow = form.z;
    // Above the land around, per metre of its width.
    let above = -form.w;
    let h = local.z;
    // Facing north: the ground falls toward the north.
    let north = -form.y / max(steepness, 1e-3) * smoothstep(0.0, 0.05, slope);
    var w: Cover;
    // Grass: dry on crests, lush toward the valley floor.
    w.dry = smoothstep(-0.02, 0.05, above - 2.0 * hollow);
    // Forest: moderate slopes, hollows and slopes facing north, up to the tree line.
    let tree_line = 1700.0;
    let moist = 0.5 + 8.0 * hollow - 4.0 * above + 0.25 * north;
    w.wooded = smoothstep(0.01, 0.06, slope) * (1.0 - smoothstep(0.25, 0.35, slope))
        * smoothstep(0.3, 0.8, moist) * (1.0 - smoothstep(tree_line - 150.0, tree_line, h));
    // Bare ground where the slope sheds its soil, scree below cliffs, rock on them.
    w.soil = smoothstep(0.22, 0.32, slope) * (1.0 - w.wooded);
    w.scree = smoothstep(0.30, 0.40, slope) * smoothstep(-0.01, 0.02, hollow);
    w.rock = smoothstep(0.38, 0.50, slope - 2.0 * hollow);
    w.sand = 1.0 - smoothstep(frame.atlas.water_m + 1.0, frame.atlas.water_m + 5.0, h);
    let snow_line = 1900.0 - 250.0 * north;
    w.snowy = smoothstep(snow_line, snow_line + 200.0, h) * (1.0 - smoothstep(0.45, 0.6, slope));
    return w;
}

// The surface classes of the surface view: `CLASS_SKY`, `CLASS_WATER`, … and their colours
// `CLASS_COLOURS` come from `truth::SURFACE_CLASSES` through `#import constants` (0, the sky,
// the CPU knows from the depth). A point's class is the type that shows most there: the last laid
// over the rest with at least half its weight.
fn natural_class(local: vec3<f32>, footprint: f32) -> u32 {
    let w = cover(local, footprint);
    var c = select(CLASS_MEADOW, CLASS_HEATH, w.dry >= 0.5);
    c = select(c, CLASS_FOREST, w.wooded >= 0.5);
    c = select(c, CLASS_SOIL, w.soil >= 0.5);
    c = select(c, CLASS_SCREE, w.scree >= 0.5);
    c = select(c, CLASS_ROCK, w.rock >= 0.5);
    c = select(c, CLASS_SAND, w.sand >= 0.5);
    return select(c, CLASS_SNOW, w.snowy >= 0.5);
}

// A class's colour in the surface view (copied to a variable: an index into an array constant
// must be a constant).
fn class_colour(c: u32) -> vec3<f32> {
    var palette = CLASS_COLOURS;
    return palette[min(c, CLASS_COUNT - 1u)];
}

// The reflectance a map's white stands for (paper's, a little below fresh snow's): lit on level
// ground by the sun the exposure is metered for, it lands below the tone map's shoulder, so the
// map's colours keep their proportions instead of bleaching toward white.
const MAP_WHITE: f32 = 0.6;

// How much of the light's variation over the relief a map's colours show (1: all of it, as the
// natural surface does): GIS maps lay their hillshade over a colour ramp or an image at part
// opacity, so the colours still read as the map's while the relief shows through.
const MAP_RELIEF: f32 = 0.4;

// The light on a map's colours at ground lit by `light` (`sun_light` the sunlight there): as a
// map's hillshade overlay, at part strength, the light on level ground moved MAP_RELIEF of the
// way to this ground's own.
fn map_light(sun_light: vec3<f32>, light: vec3<f32>) -> vec3<f32> {
    let level = sun_light * max(frame.shading.sun.z, 0.0) + frame.shading.sky_light;
    return mix(level, light, MAP_RELIEF);
}

// The reflectance of a map's or an image's encoded (sRGB) colour `c`.
fn map_albedo(c: vec3<f32>) -> vec3<f32> {
    let linear = select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
    return MAP_WHITE * linear;
}

#ifdef IMAGE
// The user's imagery resampled onto the sketch's grid (src/surface/image.rs): a header (width,
// height, texel size in metres as f32 bits), then RGBA8 texels from the sketch's south-west
// node, row 0 south; alpha is the image's coverage.
@group(0) @binding(11) var<storage, read> drape: array<u32>;

// Texel (x, y), its colour premultiplied by its coverage.
fn drape_texel(x: i32, y: i32) -> vec4<f32> {
    let size = vec2<i32>(i32(drape[0]), i32(drape[1]));
    let c = clamp(vec2<i32>(x, y), vec2<i32>(0), size - 1);
    let t = unpack4x8unorm(drape[4u + u32(c.y * size.x + c.x)]);
    return vec4<f32>(t.rgb * t.a, t.a);
}

// The image at `local`, bilinear: its encoded colour premultiplied by its coverage (rgb), and
// the coverage (a); nothing beyond the drape's grid.
fn drape_at(local: vec2<f32>) -> vec4<f32> {
    let texel = vec2<f32>(bitcast<f32>(drape[2]), bitcast<f32>(drape[3]));
    let size = vec2<f32>(f32(drape[0]), f32(drape[1]));
    let x = (local + frame.atlas.offset) / texel;
    if (any(x < vec2<f32>(-0.5)) || any(x > size - 0.5)) {
        return vec4<f32>(0.0);
    }
    let i = vec2<i32>(floor(x));
    let f = x - floor(x);
    let a = mix(drape_texel(i.x, i.y), drape_texel(i.x + 1, i.y), f.x);
    let b = mix(drape_texel(i.x, i.y + 1), drape_texel(i.x + 1, i.y + 1), f.x);
    return mix(a, b, f.y);
}
#endif

#ifdef RAMP
// The colour ramp's stops (src/surface/ramp.rs), ordered by height: the colour as the ramp file
// encodes it (0–1) and the height in metres (w).
@group(0) @binding(10) var<storage, read> ramp: array<vec4<f32>>;

// The ramp's colour at height `h`, as gdaldem `color-relief` gives it: linear in the encoded
// values between the two stops around `h`, the end colours beyond them; decoded from sRGB.
fn ramp_albedo(h: f32) -> vec3<f32> {
    let n = arrayLength(&ramp);
    var c = ramp[n - 1u].rgb;
    if (h <= ramp[0].w) {
        c = ramp[0].rgb;
    } else {
        for (var i = 1u; i < n; i++) {
            if (h < ramp[i].w) {
                let a = ramp[i - 1u];
                let t = (h - a.w) / (ramp[i].w - a.w);
                c = mix(a.rgb, ramp[i].rgb, t);
                break;
            }
        }
    }
    return map_albedo(c);
}

// The sketch's own height under the pixel, on the level of its footprint: the ramp colours the
// land the user gave; the octaves below it add light, not colour.
fn ramp_height(local: vec2<f32>, footprint: f32) -> f32 {
    let l = clamp(log2(max(footprint / frame.atlas.d_atlas, 1.0)), 0.0, f32(frame.atlas.levels - 1u));
    return ground_bilinear(local, u32(l));
}
#endif

#ifdef SHADOWS
const SHADOW_STEPS: i32 = 40;

// What can cast a shadow at `local`: the sketch (level `l`, or the water over it) on its
// rectangle, the margin and the plain or the sea beyond it, nothing over the void.
fn shadow_caster(local: vec2<f32>, l: u32) -> f32 {
    if (frame.shading.outside == 0u && !on_sketch(local, 0.0)) {
        return -1.0e30;
    }
    return max(ground_bilinear(local, l), frame.atlas.water_m);
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
    let z0 = max(caster + shore(caster) * surface_octaves(local, fine).x, frame.atlas.water_m);
    var seen = 1.0;
    for (var i = 0; i < NEAR_STEPS; i++) {
        count_shadow_step();
        let p = local + sun.xy * t;
        let sketch = atlas_bilinear((p + frame.atlas.offset) * frame.atlas.inv_spacing, 0u);
        let ground = sketch + shore(sketch) * surface_octaves(p, max(fine, 0.5 * t)).x;
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
    if (!on_sketch(local, frame.shading.margin_m) && !meets_sketch(local)) {
        return clamp(0.5 + flat_clearance(local, l), 0.0, 1.0);
    }
    return clamp(0.5 + sketch_sun_clearance(local, l, true, false), 0.0, 1.0);
}

// Whether the sun ray from `local` beside the sketch crosses the sketch's rectangle or its margin
// below the sketch's highest point (the slab test; the ray leaves from the ground beyond,
// `shadow_caster`).
fn meets_sketch(local: vec2<f32>) -> bool {
    let sun = frame.shading.sun;
    let m = frame.shading.margin_m;
    var near = 0.0;
    var far = 1.0e30;
    for (var a = 0; a < 2; a++) {
        let lo = sketch_lo()[a] - m - local[a];
        let hi = sketch_hi()[a] + m - local[a];
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
    if (frame.camera.view == VIEW_SURFACE) {
        return class_colour(surface_class(local, dist * frame.camera.pixel_scale));
    }
    let sun_light = sun_at(local.z);
    // A ramp colours the bed under the water too, as a map's depth tints do.
#ifdef RAMP
    let water = false;
#else
    let water = on_water(local.z);
#endif
    if (water) {
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
#ifdef RAMP
    var colour = ramp_albedo(ramp_height(local.xy, footprint)) * map_light(sun_light, light);
#else
    var colour = albedo(local, footprint) * light;
#endif
#ifdef IMAGE
    // The image where it covers, the surface beneath it fading in over its feathered edge.
    let image = drape_at(local.xy);
    if (image.a > 0.0) {
        colour = mix(colour, map_albedo(image.rgb / image.a) * map_light(sun_light, light), image.a);
    }
#endif
    return colour;
}

// The class the shaded picture shows at `local`: water, the ramp's or the image's colours, or
// the natural surface's type, as `lit` decides.
fn surface_class(local: vec3<f32>, footprint: f32) -> u32 {
#ifdef RAMP
    var c = CLASS_RAMP;
#else
    if (on_water(local.z)) {
        return CLASS_WATER;
    }
    var c = natural_class(local, footprint);
#endif
#ifdef IMAGE
    if (drape_at(local.xy).a >= 0.5) {
        c = CLASS_IMAGE;
    }
#endif
    return c;
}

// The margin's march: at most this many steps, then a bisection of the last in MARGIN_HALVINGS.
const MARGIN_STEPS: u32 = 160u;
const MARGIN_HALVINGS: u32 = 5u;

// Where the ray from `eye` along `dir` first meets the margin beyond the sketch: its distance, or
// −1. Marched as the reference marches the sketch, in longer steps over the smooth margin (0.9 of
// the height above the ground, at least the pixel's footprint and a quarter cell; a step that
// passes under it is bisected), over the box of the margin and its heights,
// skipping the sketch's own rectangle, whose ground the mesh or the reference draws.
fn margin_hit(eye: vec3<f32>, dir: vec3<f32>) -> f32 {
    let m = frame.shading.margin_m;
    // The octaves reach at most half the shore's band above or below the ground.
    let reach = frame.detail.shore_m;
    let water = frame.atlas.water_m;
    let lo = vec3<f32>(sketch_lo() - m, min(frame.shading.margin_lo_m - reach, water));
    let hi = vec3<f32>(sketch_hi() + m, max(frame.shading.margin_hi_m + reach, water));
    let span = box_span(eye, dir, lo, hi);
    let own = box_span(eye, dir, vec3<f32>(sketch_lo(), -3.0e38), vec3<f32>(sketch_hi(), 3.0e38));
    var t = span.x;
    var t_prev = span.x;
    for (var i = 0u; i < MARGIN_STEPS && t_prev < span.y; i++) {
        t = min(t, span.y);
        if (t >= own.x && t < own.y) {
            t = min(own.y, span.y);
            t_prev = t;
        }
        let p = eye + dir * t;
        let footprint = t * frame.camera.pixel_scale;
        let above = p.z - beyond_surface(p.xy, footprint);
        if (above <= 0.0) {
            var a = t_prev;
            var b = t;
            for (var k = 0u; k < MARGIN_HALVINGS; k++) {
                let mid = 0.5 * (a + b);
                let q = eye + dir * mid;
                if (q.z - beyond_surface(q.xy, mid * frame.camera.pixel_scale) > 0.0) {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            return 0.5 * (a + b);
        }
        t_prev = t;
        t += max(0.9 * above, max(footprint, 0.25 * frame.atlas.d_atlas));
    }
    return -1.0;
}

// The margin's normal at `p`, whose surface lies at `z`: forward differences a footprint (at
// least a sixteenth of a cell) apart. The margin is smooth at that scale, and two samples are
// half the central differences' cost.
fn beyond_normal(p: vec2<f32>, z: f32, footprint: f32) -> vec3<f32> {
    let h = max(footprint, frame.atlas.d_atlas / 16.0);
    let dx = beyond_surface(p + vec2<f32>(h, 0.0), footprint) - z;
    let dy = beyond_surface(p + vec2<f32>(0.0, h), footprint) - z;
    return normalize(vec3<f32>(-dx, -dy, h));
}

// The world beyond the sketch seen along `dir` from `eye`: the margin that joins the sketch's
// edge to the plain or the sea (src/beyond.rs), then that plain or sea to the horizon, lit and
// hazed like the terrain (and shadowed by it); w is 1 where it is seen, 0 for sky, for the
// sketch's own rectangle and with `sketch.outside = "void"`.
fn beyond(eye: vec3<f32>, dir: vec3<f32>) -> vec4<f32> {
    if (frame.shading.outside == 0u) {
        return vec4<f32>(0.0);
    }
    var t = margin_hit(eye, dir);
    var n = vec3<f32>(0.0, 0.0, 1.0);
    var ground: vec3<f32>;
    if (t > 0.0) {
        let p = eye + dir * t;
        let footprint = t * frame.camera.pixel_scale;
        ground = vec3<f32>(p.xy, beyond_surface(p.xy, footprint));
        if (!on_water(ground.z)) {
            n = beyond_normal(p.xy, ground.z, footprint);
        }
    } else {
        // A plain below the water's surface is under water.
        let level = max(frame.shading.plain_m, frame.atlas.water_m);
        if (dir.z >= 0.0 || eye.z <= level) {
            return vec4<f32>(0.0);
        }
        t = (level - eye.z) / dir.z;
        let p = eye + dir * t;
        if (on_sketch(p.xy, frame.shading.margin_m)) {
            return vec4<f32>(0.0);
        }
        // At the water's height the shading draws water.
        ground = vec3<f32>(p.xy, level);
    }
    let to_eye = eye - ground;
    return vec4<f32>(aerial(lit(ground, n, to_eye, t), to_eye, t), 1.0);
}
