//! Sample warping: strata, the concentric disk, and trigonometry without `sin`/`cos`.
//! Twin: `wgsl/sampling.wgsl`.
//!
//! WGSL only promises `sin`/`cos` to 2^-11 absolute error, which would make lens samples differ
//! between the paths by 5e-4 of the lens radius. The concentric mapping needs angles only in
//! [-pi/4, pi/4], where short polynomials are accurate to 1e-8 and use only `+` and `*`.

use std::f32::consts::FRAC_PI_4;

/// Strata of an `n`-sample 2-D stratification: `nx` columns by `n / nx` rows, with `nx` the
/// largest divisor of `n` not above sqrt(n), so every `n` (even a prime) gets equal-area strata.
pub fn strata_columns(n: u32) -> u32 {
    let mut nx = (n as f64).sqrt().floor().max(1.0) as u32;
    while !n.is_multiple_of(nx) {
        nx -= 1;
    }
    nx
}

/// Sample `index` of an `n`-sample stratification with `columns` columns, jittered by `u`.
pub fn stratified_2d(index: u32, n: u32, columns: u32, u: [f32; 2]) -> [f32; 2] {
    let (rows, _) = div_rem(n, columns);
    let (cy, cx) = div_rem(index, columns);
    [
        over(cx as f32 + u[0], columns),
        over(cy as f32 + u[1], rows),
    ]
}

/// (a / d, a % d) for d > 0; by a shift and a mask where d is a power of two, as the strata
/// counts of most sample counts are: an integer division costs about 25 cycles, and a camera
/// sample with a light sample divided six times.
pub fn div_rem(a: u32, d: u32) -> (u32, u32) {
    if d.is_power_of_two() {
        (a >> d.trailing_zeros(), a & (d - 1))
    } else {
        (a / d, a % d)
    }
}

/// x / d for x in [0, 2^24] and 0 < d <= 2^24; a product with 1 / d where d is a power of two,
/// which is exact, so the quotient is the division's, bit for bit.
pub fn over(x: f32, d: u32) -> f32 {
    if d.is_power_of_two() {
        x * (1.0 / d as f32)
    } else {
        x / d as f32
    }
}

/// sin(x) for |x| <= pi/4 (Taylor to x^9; error below 2e-9).
pub fn sin_quarter(x: f32) -> f32 {
    let x2 = x * x;
    x * (1.0
        + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))))
}

/// cos(x) for |x| <= pi/4 (Taylor to x^10; error below 2e-10).
pub fn cos_quarter(x: f32) -> f32 {
    let x2 = x * x;
    1.0 + x2
        * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))))
}

/// Shirley and Chiu's concentric map of the unit square to the unit disk (area-preserving up to
/// a constant, so strata stay equal-area). `[0.5, 0.5]` maps to the centre.
pub fn concentric_disk(u: [f32; 2]) -> [f32; 2] {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0];
    }
    if a.abs() > b.abs() {
        let phi = FRAC_PI_4 * (b / a);
        [a * cos_quarter(phi), a * sin_quarter(phi)]
    } else {
        // angle = pi/2 - phi: cos(angle) = sin(phi), sin(angle) = cos(phi)
        let phi = FRAC_PI_4 * (a / b);
        [b * sin_quarter(phi), b * cos_quarter(phi)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shortcuts are the divisions, bit for bit, for powers of two and other divisors,
    /// numerators at the extremes included.
    #[test]
    fn div_rem_and_over_are_the_divisions() {
        let divisors = (1..=70).chain([127, 128, 129, 1 << 12, 1 << 16, (1 << 24) - 1, 1 << 24]);
        for d in divisors {
            for a in (0..300).chain([u32::MAX - 1, u32::MAX, 1 << 31, 123_456_789]) {
                assert_eq!(div_rem(a, d), (a / d, a % d), "{a} / {d}");
            }
            for x in [
                0.0,
                1e-30,
                5.9604645e-8,
                0.3,
                0.999_999_94,
                1.0,
                7.5,
                63.99,
                16_777_216.0,
            ] {
                assert_eq!(over(x, d).to_bits(), (x / d as f32).to_bits(), "{x} / {d}");
            }
        }
    }
}
