//! Counter-based random numbers keyed by (seed, pixel, sample, dimension).
//! Twin: `wgsl/rng.wgsl`. Integer operations only, so both paths draw bit-identical numbers.
//!
//! The hash is the PCG-based one recommended by Jarzynski and Olano, "Hash Functions for GPU
//! Rendering", JCGT 9(3), 2020: <https://jcgt.org/published/0009/03/02/>

/// PCG hash of one 32-bit word.
#[inline(always)]
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The key of the stream of sample `sample` of pixel `pixel` in the render seeded `seed`.
#[inline(always)]
pub(crate) fn stream_key(seed: u32, pixel: u32, sample: u32) -> u32 {
    pcg_hash(pcg_hash(pcg_hash(seed) ^ pixel) ^ sample)
}

/// The 32 random bits of dimension `dim` of the stream keyed `key`.
#[inline(always)]
pub(crate) fn draw_bits(key: u32, dim: u32) -> u32 {
    pcg_hash(key ^ pcg_hash(dim))
}

/// The random stream of one camera sample: dimension `dim` of sample `sample` of pixel `pixel`.
/// Dimensions are drawn in the same order by both paths, so a stream is reproducible from
/// its key alone, in any order of pixels and samples.
#[derive(Clone, Copy, Debug)]
pub struct Rng {
    key: u32,
    dim: u32,
    /// The pixel (`y * width + x`) and camera sample the stream belongs to: the sample patterns
    /// of later dimensions (the light samples) index by them.
    pub pixel: u32,
    /// The camera sample's index within its pixel (see `pixel`).
    pub sample: u32,
}

impl Rng {
    /// The stream of sample `sample` of pixel `pixel` (`y * width + x`) in the render seeded
    /// `seed`, at dimension 0.
    pub fn new(seed: u32, pixel: u32, sample: u32) -> Self {
        Rng::with_key(stream_key(seed, pixel, sample), 0, pixel, sample)
    }

    /// The stream of key `key` (`stream_key(seed, pixel, sample)`) at dimension `dim`, for code
    /// that computes keys and draws several streams at a time.
    pub(crate) fn with_key(key: u32, dim: u32, pixel: u32, sample: u32) -> Self {
        Rng {
            key,
            dim,
            pixel,
            sample,
        }
    }

    /// Continue the stream at dimension `dim` (light samples draw from computed dimensions).
    pub fn seek(&mut self, dim: u32) {
        self.dim = dim;
    }

    /// The next dimension's 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let h = draw_bits(self.key, self.dim);
        self.dim += 1;
        h
    }

    /// Uniform in [0, 1): the top 24 bits, exactly representable, so exact on both paths.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two consecutive dimensions, uniform in [0, 1)^2.
    pub fn next_2d(&mut self) -> [f32; 2] {
        let x = self.next_f32();
        let y = self.next_f32();
        [x, y]
    }
}
