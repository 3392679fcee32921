// Band-limited gradient noise: the twin of src/detail.rs, line for line.

#import work

fn hash(x_in: u32) -> u32 {
    var x = x_in;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn lattice_gradient(cell: vec2<i32>, seed: u32) -> vec2<f32> {
    let h = hash(bitcast<u32>(cell.x) ^ hash(bitcast<u32>(cell.y) ^ hash(seed)));
    let angle = f32(h >> 8u) * (6.2831855 / 16777216.0);
    return vec2<f32>(cos(angle), sin(angle));
}

// Value (x) and gradient d/df (yz) in the cell with lower corner `cell` at fraction `f`.
fn gradient_noise(cell: vec2<i32>, f: vec2<f32>, seed: u32) -> vec3<f32> {
    let ga = lattice_gradient(cell, seed);
    let gb = lattice_gradient(cell + vec2<i32>(1, 0), seed);
    let gc = lattice_gradient(cell + vec2<i32>(0, 1), seed);
    let gd = lattice_gradient(cell + vec2<i32>(1, 1), seed);
    let va = dot(ga, f);
    let vb = dot(gb, f - vec2<f32>(1.0, 0.0));
    let vc = dot(gc, f - vec2<f32>(0.0, 1.0));
    let vd = dot(gd, f - vec2<f32>(1.0, 1.0));
    let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let du = 30.0 * f * f * (f * (f - 2.0) + 1.0);
    let k = va - vb - vc + vd;
    let value = va + u.x * (vb - va) + u.y * (vc - va) + u.x * u.y * k;
    let grad = ga
        + u.x * (gb - ga)
        + u.y * (gc - ga)
        + u.x * u.y * (ga - gb - gc + gd)
        + du * (vec2<f32>(u.y, u.x) * k + vec2<f32>(vb - va, vc - va));
    return vec3<f32>(value, grad) * 1.4142135;
}

// n_k and its gradient per metre at `local` metres from the frame origin.
fn octave_local(o: Octave, local: vec2<f32>) -> vec3<f32> {
    count_octave();
    let q = local * o.scale + o.phase;
    let c = floor(q);
    let cell = o.lattice + vec2<i32>(c);
    let n = gradient_noise(cell, q - c, o.seed);
    return vec3<f32>(n.x, n.yz * o.scale);
}

// The share of octave k: geometry g_k plus the bump remainder (1 − g_k)·b_k.
fn octave_share(k: u32, o: f32, o_px: f32) -> f32 {
    let g = clamp(o - f32(k) + 1.0, 0.0, 1.0);
    let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
    return g + (1.0 - g) * b;
}

// The bump remainder alone, (1 − g_k)·b_k: what the per-pixel normal takes of octave k.
fn bump_share(k: u32, o: f32, o_px: f32) -> f32 {
    let g = clamp(o - f32(k) + 1.0, 0.0, 1.0);
    let b = clamp(o_px - f32(k) + 1.0, 0.0, 1.0);
    return (1.0 - g) * b;
}
