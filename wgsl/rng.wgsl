// Counter-based random numbers keyed by (seed, pixel, sample, dimension).
// Mirrors: src/math/rng.rs (bit-identical: integer operations only).

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng {
    key: u32,
    dim: u32,
    // The pixel (y * width + x) and camera sample of the stream (see the Rust twin).
    pixel: u32,
    sample: u32,
}

fn rng_new(seed: u32, pixel: u32, sample: u32) -> Rng {
    return Rng(pcg_hash(pcg_hash(pcg_hash(seed) ^ pixel) ^ sample), 0u, pixel, sample);
}

fn rng_seek(rng: ptr<function, Rng>, dim: u32) {
    (*rng).dim = dim;
}

fn rng_next_u32(rng: ptr<function, Rng>) -> u32 {
    let h = pcg_hash((*rng).key ^ pcg_hash((*rng).dim));
    (*rng).dim += 1u;
    return h;
}

fn rng_next_f32(rng: ptr<function, Rng>) -> f32 {
    return f32(rng_next_u32(rng) >> 8u) * (1.0 / 16777216.0);
}

fn rng_next_2d(rng: ptr<function, Rng>) -> vec2<f32> {
    let x = rng_next_f32(rng);
    let y = rng_next_f32(rng);
    return vec2<f32>(x, y);
}
