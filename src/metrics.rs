//! How far one image is from another, and how fast an error falls: RMSE and relative MSE of
//! linear radiance, FLIP (NVIDIA's perceptual difference, through `nv-flip`) of the sRGB
//! images, and the slope of a log-log error curve. `chambre converge`, the benchmarks and the
//! tests measure with these.

use crate::output::srgb_encode;
use crate::render::Image;

/// Root mean square error of linear radiance over pixels and channels.
pub fn rmse(image: &Image, reference: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| (*p - *q).length_squared() as f64)
        .sum();
    (sum / (3 * image.pixels.len()) as f64).sqrt()
}

/// Relative MSE, mean of (x - r)^2 / (r^2 + 0.01) over pixels and channels (the 0.01 keeps dark
/// pixels from dominating; Rousselle et al.'s definition, which Mitsuba's tools use).
pub fn rel_mse(image: &Image, reference: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| {
            let (p, q) = (p.as_dvec3(), q.as_dvec3());
            ((p - q) * (p - q) / (q * q + 0.01)).element_sum()
        })
        .sum();
    sum / (3 * image.pixels.len()) as f64
}

/// Mean FLIP error of the two images shown as sRGB 8-bit (clamped), at FLIP's default viewing
/// distance (67 pixels per degree): 0 for identical images, 1 at most.
pub fn flip(image: &Image, reference: &Image) -> f64 {
    let map = flip_map(image, reference);
    map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64
}

/// FLIP's per-pixel error map (row-major, row 0 at the top) of the two images shown as sRGB
/// 8-bit, at FLIP's default viewing distance.
pub fn flip_map(image: &Image, reference: &Image) -> Vec<f32> {
    let rgb8 = |i: &Image| {
        let bytes: Vec<u8> = i
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(srgb_encode))
            .collect();
        nv_flip::FlipImageRgb8::with_data(i.width, i.height, &bytes)
    };
    let map = nv_flip::flip(
        rgb8(reference),
        rgb8(image),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    map.to_vec()
}

/// Least-squares slope of log(error) against log(x): -0.5 for error falling as 1/sqrt(x).
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}
