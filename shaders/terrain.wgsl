// The terrain pass: the detailed geometry image drawn as a quad mesh (two triangles per cell,
// split along (s,t)–(s+1,t+1)), with per-pixel bump detail from the split octave up to the
// pixel's own octave, procedural surface types, sun and sky light and aerial perspective.
// Also the sky, drawn first as one full-screen triangle.

#import frame
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(3) var<storage, read> detailed: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> normals: array<vec4<f32>>;
#ifdef IMPORTANCE_VIEW
@group(0) @binding(5) var<storage, read> importance: array<f32>;
#endif
#ifdef NOISE
#import noise
#endif
#ifdef BUMP
#import noise
#endif

const SEA_LEVEL: f32 = 0.0;
const FOG_DENSITY: f32 = 0.000035;

fn sky_colour(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.z, -0.2, 1.0);
    let horizon = vec3<f32>(0.72, 0.80, 0.90);
    let zenith = vec3<f32>(0.22, 0.42, 0.78);
    var c = mix(horizon, zenith, pow(max(up, 0.0), 0.6));
    let sun = max(dot(dir, frame.sun.xyz), 0.0);
    c += vec3<f32>(1.0, 0.85, 0.6) * (pow(sun, 400.0) * 4.0 + pow(sun, 12.0) * 0.25);
    return c;
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
    if (frame.view == 5u) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let far = frame.inv_view_proj * vec4<f32>(in.ndc, 0.5, 1.0);
    let dir = normalize(far.xyz / far.w - frame.eye.xyz);
    return vec4<f32>(sky_colour(dir), 1.0);
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) split: f32,
    @location(3) grid: vec2<f32>,
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
    return g.y * frame.mesh + g.x;
}

// Index = block slot << bits | (j·(cells+1) + i), cells and bits from frame.block. Vertices that
// the next level drops move toward the midpoint of their two neighbours on it (Wagner's
// geomorph); edge vertices follow the level and morph range of the coarser block of their edge,
// so neighbours agree on them.
@vertex
fn terrain_vs(@builtin(vertex_index) vi: u32) -> VsOut {
    let cells = frame.block.x;
    let b = blocks[vi >> frame.block.y];
    let local = vi & ((1u << frame.block.y) - 1u);
    let l2 = vec2<u32>(local % (cells + 1u), local / (cells + 1u));
    let g = b.origin + l2;
    var p = detailed[grid_index(g)];
    var n = normals[grid_index(g)].xyz;
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
    if (level + 1u < frame.block.z && (g.x % s2 != 0u || g.y % s2 != 0u)) {
        let d = vec2<u32>(select(0u, s, g.x % s2 != 0u), select(0u, s, g.y % s2 != 0u));
        let a = detailed[grid_index(g - d)];
        let c = detailed[grid_index(g + d)];
        // Inside: the block's factor (continuous when it changes level); on an edge: the
        // vertex's own distance over the edge's shared range (both blocks compute the same).
        var m = b.morph.z;
        if (side < 4u) {
            let eye_d = distance(p.xyz + vec3<f32>(frame.mesh_offset, 0.0), frame.eye.xyz);
            m = 0.0;
            if (end > start) {
                m = clamp((eye_d - start) / (end - start), 0.0, 1.0);
            }
        }
        p.z = mix(p.z, 0.5 * (a.z + c.z), m);
        let nc = normals[grid_index(g - d)].xyz + normals[grid_index(g + d)].xyz;
        n = normalize(mix(n, normalize(nc), m));
    }
    let local_pos = p.xyz + vec3<f32>(frame.mesh_offset, 0.0);
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(local_pos, 1.0);
    out.local = local_pos;
    out.normal = n;
    out.split = p.w;
    out.grid = vec2<f32>(g);
    return out;
}
#else
@vertex
fn terrain_vs(@builtin(vertex_index) vi: u32) -> VsOut {
    let p = detailed[vi];
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(p.xyz, 1.0);
    out.local = p.xyz;
    out.normal = normals[vi].xyz;
    out.split = p.w;
    out.grid = vec2<f32>(f32(vi % frame.mesh), f32(vi / frame.mesh));
    return out;
}
#endif

// Low-frequency turbulence that moves the boundaries between surface types.
fn turbulence(local: vec2<f32>) -> f32 {
#ifdef NOISE
    return octave_local(frame.turbulence[0], local).x + 0.5 * octave_local(frame.turbulence[1], local).x;
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

@fragment
fn terrain_fs(in: VsOut) -> @location(0) vec4<f32> {
    let to_eye = frame.eye.xyz - in.local;
    let dist = max(length(to_eye), 1e-3);
    var n = normalize(in.normal);
#ifdef BUMP
    // Bump detail: octaves from the vertex's split octave up to the pixel's own octave; the
    // geometry already holds g_k of each, octaves past the pixel octave are never evaluated.
    let o_px = log2(frame.d_atlas / max(dist * frame.eye.w, 1e-6));
    let last = min(frame.octaves, u32(max(ceil(o_px), 0.0)));
    var grad = vec2<f32>(0.0);
    for (var k = 1u; k <= last; k++) {
        let g = clamp(in.split - f32(k) + 1.0, 0.0, 1.0);
        let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
        let share = (1.0 - g) * b;
        if (share > 0.0) {
            grad += frame.octave[k - 1u].weight * share * octave_local(frame.octave[k - 1u], in.local.xy).yz;
        }
    }
    n = normalize(vec3<f32>(n.xy / max(n.z, 0.05) - grad, 1.0));
#endif
    var colour: vec3<f32>;
    if (in.local.z < SEA_LEVEL) {
        let fresnel = pow(1.0 - clamp(to_eye.z / dist, 0.0, 1.0), 4.0);
        colour = mix(vec3<f32>(0.04, 0.12, 0.20), sky_colour(reflect(-to_eye / dist, vec3<f32>(0.0, 0.0, 1.0))), fresnel);
    } else {
        let sun = max(dot(n, frame.sun.xyz), 0.0);
        let sky = 0.35 * (0.6 + 0.4 * n.z);
        colour = albedo(in.local, n) * (vec3<f32>(1.0, 0.95, 0.85) * sun * 1.1 + vec3<f32>(0.55, 0.65, 0.85) * sky);
    }
    if (frame.view == 1u) {
        // Wireframe: the quad mesh's grid lines over the shaded terrain.
        let d = abs(fract(in.grid + 0.5) - 0.5) / max(fwidth(in.grid), vec2<f32>(1e-6));
        colour = mix(vec3<f32>(0.05, 0.05, 0.08), colour, clamp(min(d.x, d.y), 0.0, 1.0));
    } else if (frame.view == 2u) {
        let t = clamp(in.split / f32(max(frame.octaves, 1u)), 0.0, 1.0);
        colour = mix(vec3<f32>(0.1, 0.1, 0.6), vec3<f32>(1.0, 0.9, 0.1), t);
    } else if (frame.view == 4u) {
        colour = n * 0.5 + 0.5;
    } else if (frame.view == 5u) {
        return vec4<f32>(1.0, 1.0, 1.0, 1.0);
    }
#ifdef IMPORTANCE_VIEW
    let texel = (in.local.xy - frame.phi_offset) / frame.sun.w;
    let i = clamp(vec2<u32>(max(texel, vec2<f32>(0.0))), vec2<u32>(0u), vec2<u32>(frame.n - 1u));
    let v = importance[i.y * frame.n + i.x];
    let t = clamp(log2(v / frame.importance_max) / 12.0 + 1.0, 0.0, 1.0);
    colour = mix(vec3<f32>(0.27, 0.0, 0.33), vec3<f32>(0.99, 0.9, 0.14), t);
#endif
    // Aerial perspective: the air between the eye and the ground scatters toward the horizon sky.
    let fog = 1.0 - exp(-dist * FOG_DENSITY);
    colour = mix(colour, sky_colour(normalize(-to_eye) * vec3<f32>(1.0, 1.0, 0.0) + vec3<f32>(0.0, 0.0, 0.02)), fog);
    return vec4<f32>(colour, 1.0);
}
