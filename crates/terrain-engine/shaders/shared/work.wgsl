// The counting variant (`COUNT_WORK`, src/gpu/work.rs): each invocation tallies the work it
// evaluates, noise octaves, steps of a shadow ray and texels read from the sketch, and the passes
// that shade pixels add their tallies to `work` as each pixel (or sample) is finished; vertices and
// compute passes over the mesh tally without adding. Without the flag every function here is
// empty and the compiler drops the calls: the shaders users draw with carry none of it.
#ifdef COUNT_WORK
// Octaves, shadow steps, atlas taps: this invocation's so far.
var<private> tally: vec3<u32>;

// Octaves, shadow steps, atlas taps, and the invocations that added theirs: each a 64-bit sum
// as two words, low then high (a frame's atlas taps pass 2^32 at 1080p).
@group(0) @binding(8) var<storage, read_write> work: array<atomic<u32>, 8>;

fn count_octave() {
    tally.x += 1u;
}

fn count_shadow_step() {
    tally.y += 1u;
}

fn count_atlas_tap() {
    tally.z += 1u;
}

// Adds `v` to sum `i`, carrying into its high word where the low one wraps.
fn add_to(i: u32, v: u32) {
    let old = atomicAdd(&work[2u * i], v);
    if (old + v < old) {
        atomicAdd(&work[2u * i + 1u], 1u);
    }
}

// Adds this invocation's tallies to the frame's.
fn add_work() {
    add_to(0u, tally.x);
    add_to(1u, tally.y);
    add_to(2u, tally.z);
    add_to(3u, 1u);
}
#else
fn count_octave() {}
fn count_shadow_step() {}
fn count_atlas_tap() {}
fn add_work() {}
#endif
