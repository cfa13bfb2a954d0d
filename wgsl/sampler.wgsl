// Camera sample patterns: where sample i of a pixel falls in the pixel and on the aperture.
// Mirrors: src/sampler.rs (see there for the five patterns; integer hashing is bit-identical).
// Reads the `sample_table` binding (wgsl/bindings.wgsl).


struct PatternSource {
    sampler: u32,
    strata_columns: u32,
    table_offset: u32,
    dim: u32,
}

fn pixel_hash(seed: u32, pixel: u32, dim: u32) -> u32 {
    return pcg_hash(pcg_hash(pcg_hash(seed) ^ pixel) ^ (dim | 0x80000000u));
}

fn unit_float(bits: u32) -> f32 {
    return f32(bits >> 8u) * (1.0 / 16777216.0);
}

fn permute(index: u32, n: u32, key: u32) -> u32 {
    var w = n - 1u;
    w |= w >> 1u;
    w |= w >> 2u;
    w |= w >> 4u;
    w |= w >> 8u;
    w |= w >> 16u;
    var i = index;
    for (var walk = 0u; walk < PERMUTE_WALK_CAP; walk += 1u) {
        i ^= key;
        i *= 0xe170893du;
        i ^= key >> 16u;
        i ^= (i & w) >> 4u;
        i ^= key >> 8u;
        i *= 0x0929eb3fu;
        i ^= key >> 23u;
        i ^= (i & w) >> 1u;
        i *= 1u | (key >> 27u);
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11u;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2u;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2u;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5u;
        if (i < n) {
            return remainder(i + key, n);
        }
    }
    flag_status(STATUS_PERMUTE_CAP);
    return index;
}

fn laine_karras_permutation(value: u32, seed: u32) -> u32 {
    var x = value + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(laine_karras_permutation(reverseBits(x), seed));
}

// Sobol dimension 1 of `index` (v_k = v_{k-1} ^ (v_{k-1} >> 1) from 1 << 31). Rust twin:
// layout::SOBOL_MATRIX_1, applied through byte tables (a CPU mispredicts this loop's branches;
// a GPU lane runs it as selects).
fn sobol_dimension_1(index: u32) -> u32 {
    var bits = index;
    var v = 1u << 31u;
    var result = 0u;
    for (var k = 0u; k < 32u && bits != 0u; k += 1u) {
        if ((bits & 1u) != 0u) {
            result ^= v;
        }
        bits >>= 1u;
        v ^= v >> 1u;
    }
    return result;
}

// Sobol dimensions 2 and 3 of `index`: the XOR of the direction numbers of its set bits, the
// numbers made by Joe and Kuo's recurrences as the bits go (in registers: a table indexed at run
// time is slow on some drivers). Dimension 2: v_k = v_{k-2} ^ (v_{k-2} >> 2) ^ v_{k-1} from
// 1 << 31, 3 << 30; dimension 3: v_k = v_{k-3} ^ (v_{k-3} >> 3) ^ v_{k-2} from 1 << 31, 3 << 30,
// 1 << 29. Rust twin: layout::SOBOL_MATRIX_2 and SOBOL_MATRIX_3, as byte tables in sampler.rs.
fn sobol_dimension_2(index: u32) -> u32 {
    var bits = index;
    var result = 0u;
    var a = 1u << 31u;
    var b = 3u << 30u;
    while (bits != 0u) {
        if ((bits & 1u) != 0u) {
            result ^= a;
        }
        bits >>= 1u;
        let next = a ^ (a >> 2u) ^ b;
        a = b;
        b = next;
    }
    return result;
}

fn sobol_dimension_3(index: u32) -> u32 {
    var bits = index;
    var result = 0u;
    var a = 1u << 31u;
    var b = 3u << 30u;
    var c = 1u << 29u;
    while (bits != 0u) {
        if ((bits & 1u) != 0u) {
            result ^= a;
        }
        bits >>= 1u;
        let next = a ^ (a >> 3u) ^ b;
        a = b;
        b = c;
        c = next;
    }
    return result;
}

// The lens point of the joint pixel x lens Sobol pattern (Rust twin: sobol_owen_lens).
fn sobol_owen_lens(index: u32, pixel_seed: u32, lens_seed: u32) -> vec2<f32> {
    let shuffled = nested_uniform_scramble(index, pixel_seed);
    let x = nested_uniform_scramble(sobol_dimension_2(shuffled), pcg_hash(lens_seed ^ 0x0000a511u));
    let y = nested_uniform_scramble(sobol_dimension_3(shuffled), pcg_hash(lens_seed ^ 0x0000b0b1u));
    return vec2<f32>(unit_float(x), unit_float(y));
}

fn sobol_owen_2d(index: u32, seed: u32) -> vec2<f32> {
    let shuffled = nested_uniform_scramble(index, seed);
    let x = nested_uniform_scramble(reverseBits(shuffled), pcg_hash(seed ^ 0x0000a511u));
    let y = nested_uniform_scramble(sobol_dimension_1(shuffled), pcg_hash(seed ^ 0x0000b0b1u));
    return vec2<f32>(unit_float(x), unit_float(y));
}

// Point `index` of the progressive stratified pattern of `n` points (Rust twin:
// progressive_stratified): the stratum of Sobol (0,2) point `index` in the grid of the power of
// two at or above n, jittered by u.
fn progressive_stratified(index: u32, n: u32, key: u32, u: vec2<f32>) -> vec2<f32> {
    let p = sobol_owen_2d(index, key);
    let bits = 32u - countLeadingZeros(max(n, 1u) - 1u);
    let columns = 1u << (bits / 2u);
    let rows = 1u << (bits - bits / 2u);
    let cell = u32(p.y * f32(rows)) * columns + u32(p.x * f32(columns));
    return stratified_2d(cell, columns * rows, columns, u);
}

fn wrap_unit(x: f32) -> f32 {
    var w = x;
    if (x >= 1.0) {
        w = x - 1.0;
    }
    return min(w, 0.99999994);
}

fn sample_2d(source: PatternSource, x: u32, y: u32, sample: u32, rng: ptr<function, Rng>) -> vec2<f32> {
    let u = rng_next_2d(rng);
    if (source.sampler == SAMPLER_RANDOM) {
        return u;
    }
    let key = pixel_hash(frame.seed, y * frame.width + x, source.dim);
    switch source.sampler {
        case SAMPLER_STRATIFIED: {
            if (frame.progressive != 0u) {
                return progressive_stratified(sample, frame.spp, key, u);
            }
            let stratum = permute(sample, frame.spp, key);
            return stratified_2d(stratum, frame.spp, source.strata_columns, u);
        }
        case SAMPLER_POISSON: {
            let set_index = key % POISSON_SETS;
            let p = sample_table[source.table_offset + set_index * frame.spp + sample];
            let shift = vec2<f32>(unit_float(pcg_hash(key)), unit_float(pcg_hash(key ^ 0x5151u)));
            return vec2<f32>(wrap_unit(p.x + shift.x), wrap_unit(p.y + shift.y));
        }
        case SAMPLER_INTERLEAVED: {
            let pattern = (x % INTERLEAVED_TILE) + INTERLEAVED_TILE * (y % INTERLEAVED_TILE);
            return sample_table[source.table_offset + pattern * frame.spp + sample];
        }
        case SAMPLER_SOBOL: {
            // A Sobol lens under a Sobol pixel pattern: the joint 4-D pattern.
            if (source.dim == LENS_DIMENSION && frame.pixel_sampler == SAMPLER_SOBOL) {
                let pixel_key = pixel_hash(frame.seed, y * frame.width + x, PIXEL_DIMENSION);
                return sobol_owen_lens(sample, pixel_key, key);
            }
            return sobol_owen_2d(sample, key);
        }
        default: {
            return u;
        }
    }
}

// The point of light sample `k` of camera sample `sample`; `key` is the pixel's key for the
// light, made once per light (see the Rust twin).
fn light_sample_2d(light_samples: u32, light_columns: u32, sample: u32, k: u32, key: u32,
                   u: vec2<f32>) -> vec2<f32> {
    if (frame.pixel_sampler == SAMPLER_RANDOM || frame.spp > MAX_LIGHT_PATTERN_POINTS / light_samples) {
        return stratified_2d(k, light_samples, light_columns, u);
    }
    let index = sample * light_samples + k;
    if (frame.pixel_sampler == SAMPLER_SOBOL) {
        return sobol_owen_2d(index, key);
    }
    let n = frame.spp * light_samples;
    if (frame.progressive != 0u) {
        return progressive_stratified(index, n, key, u);
    }
    return stratified_2d(permute(index, n, key), n, frame.pixel_strata_columns * light_columns, u);
}

fn sample_aperture(u: vec2<f32>) -> vec2<f32> {
    let r = camera.lens_radius_mm;
    if (camera.aperture_blades == 0u) {
        return r * concentric_disk(u);
    }
    let n = camera.aperture_blades;
    let scaled = u.x * f32(n);
    let k = min(u32(scaled), n - 1u);
    let radial = sqrt(scaled - f32(k));
    let a = sample_table[camera.aperture_table_offset + k];
    let b = sample_table[camera.aperture_table_offset + k + 1u];
    let s = r * radial;
    return vec2<f32>(s * (a.x + u.y * (b.x - a.x)), s * (a.y + u.y * (b.y - a.y)));
}
