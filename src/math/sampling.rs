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
    let rows = n / columns;
    let cx = (index % columns) as f32;
    let cy = (index / columns) as f32;
    [(cx + u[0]) / columns as f32, (cy + u[1]) / rows as f32]
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
