// Sample warping: strata, the concentric disk, and trigonometry without sin/cos.
// Mirrors: src/math/sampling.rs

const FRAC_PI_4: f32 = 0.78539816339744830962;

fn stratified_2d(index: u32, n: u32, columns: u32, u: vec2<f32>) -> vec2<f32> {
    let rows = quotient(n, columns);
    let cx = f32(remainder(index, columns));
    let cy = f32(quotient(index, columns));
    return vec2<f32>(over(cx + u.x, columns), over(cy + u.y, rows));
}

// a / d and a % d (d > 0): a shift and a mask where d is a power of two, as most strata counts
// are (twin: div_rem in src/math/sampling.rs; lavapipe divides integers lane by lane).
fn is_power_of_two(d: u32) -> bool {
    return (d & (d - 1u)) == 0u;
}

fn quotient(a: u32, d: u32) -> u32 {
    if (is_power_of_two(d)) {
        return a >> countTrailingZeros(d);
    }
    return a / d;
}

fn remainder(a: u32, d: u32) -> u32 {
    if (is_power_of_two(d)) {
        return a & (d - 1u);
    }
    return a % d;
}

// x / d, as a product with the exact reciprocal where d is a power of two (twin: over).
fn over(x: f32, d: u32) -> f32 {
    if (is_power_of_two(d)) {
        return x * (1.0 / f32(d));
    }
    return x / f32(d);
}

fn sin_quarter(x: f32) -> f32 {
    let x2 = x * x;
    return x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0)))));
}

fn cos_quarter(x: f32) -> f32 {
    let x2 = x * x;
    return 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3628800.0)))));
}

fn concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * u.x - 1.0;
    let b = 2.0 * u.y - 1.0;
    if (a == 0.0 && b == 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    if (abs(a) > abs(b)) {
        let phi = FRAC_PI_4 * (b / a);
        return vec2<f32>(a * cos_quarter(phi), a * sin_quarter(phi));
    }
    // angle = pi/2 - phi: cos(angle) = sin(phi), sin(angle) = cos(phi)
    let phi = FRAC_PI_4 * (a / b);
    return vec2<f32>(b * sin_quarter(phi), b * cos_quarter(phi));
}
