//! Adaptive sampling (`render.noise_target`, `--noise-target`): sample only the pixels whose
//! estimated error is above a target, in passes over a list of them, until all meet it or
//! `render.spp` (then the maximum) is reached.
//!
//! The estimate is Cycles' (after Dammertz et al., "A hierarchical automatic stopping condition
//! for Monte Carlo global illumination", 2010): the accumulation keeps two halves that take
//! alternate passes (`render::AccumulationLayout`). With means `a` and `b` of `n_a` and `n_b`
//! samples, the image's mean `I` has the standard error `|a − b| / sqrt(n (1/n_a + 1/n_b))`
//! (`n = n_a + n_b`; `|a − b| / 2` for equal halves), and the error of a pixel is
//!
//! ```text
//! e = Σ_c |a_c − b_c| / sqrt(n (1/n_a + 1/n_b))  /  (1e-4 + sqrt(Σ_c I_c))
//! ```
//!
//! normalised by the square root of the intensity: between absolute and relative error, so a
//! pixel whose variance grows with its mean (shot-noise-like) needs the same samples at every
//! brightness. A single estimate is itself noisy, so a pixel stops only when it and its eight
//! neighbours still sampled are all below the target (Cycles' filter), and a pixel that stopped
//! never restarts: every pixel's samples are then the consecutive indices `0..n` of its
//! pattern. The decisions are made on
//! the host from the backend's accumulation, by the same code for the GPU and the CPU path.

use crate::render::AccumulationLayout;

/// Adaptive sampling's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// A pixel stops once its error estimate `e` (module docs) is below this.
    pub noise_target: f32,
    /// Samples every pixel receives before the first decision (both halves need some).
    pub min_spp: u32,
}

/// `render.min_spp` when the scene does not give it (capped at `render.spp`).
pub const DEFAULT_MIN_SPP: u32 = 16;

/// Keeps the intensity normalisation finite for black pixels (Cycles' constant).
const INTENSITY_EPSILON: f32 = 1e-4;

/// The error estimate `e` of a pixel from its halves' sums `(Σ rgb, samples)`; infinite while
/// a half has no sample.
pub fn pixel_error(a: [f32; 4], b: [f32; 4]) -> f32 {
    let (na, nb) = (a[3], b[3]);
    if na <= 0.0 || nb <= 0.0 {
        return f32::INFINITY;
    }
    let n = na + nb;
    let difference: f32 = (0..3).map(|c| (a[c] / na - b[c] / nb).abs()).sum();
    let standard_error = difference / (n * (1.0 / na + 1.0 / nb)).sqrt();
    let intensity: f32 = (0..3).map(|c| (a[c] + b[c]) / n).sum();
    standard_error / (INTENSITY_EPSILON + intensity.max(0.0).sqrt())
}

/// Every pixel's error estimate, row by row, from both halves (`Backend::halves`).
pub fn pixel_errors(layout: &AccumulationLayout, halves: &[[f32; 4]]) -> Vec<f32> {
    let (first, second) = halves.split_at(layout.pixels);
    first
        .iter()
        .zip(second)
        .map(|(&a, &b)| pixel_error(a, b))
        .collect()
}

/// Which pixels of an image are still sampled, and the decisions that narrow them.
#[derive(Clone, Debug)]
pub struct ActivePixels {
    width: u32,
    /// The crop window `[x0, x1, y0, y1]`: pixels outside it are never sampled.
    crop: [u32; 4],
    /// Per pixel of the image: still sampled.
    active: Vec<bool>,
}

impl ActivePixels {
    /// Every pixel of `crop` active.
    pub fn new(width: u32, height: u32, crop: [u32; 4]) -> ActivePixels {
        let [x0, x1, y0, y1] = crop;
        let active = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x0..x1).contains(&x) && (y0..y1).contains(&y)))
            .collect();
        ActivePixels {
            width,
            crop,
            active,
        }
    }

    /// Stops every active pixel whose own and active neighbours' errors (of the eight, within
    /// the crop window) are below `target`; returns how many are still active.
    pub fn decide(&mut self, errors: &[f32], target: f32) -> usize {
        let [x0, x1, y0, y1] = self.crop;
        let width = self.width as usize;
        // A stopped pixel's sums no longer change, nor should it hold its neighbours.
        let above = |x: u32, y: u32| {
            let pixel = y as usize * width + x as usize;
            self.active[pixel] && errors[pixel] >= target
        };
        let mut still = vec![false; self.active.len()];
        for y in y0..y1 {
            for x in x0..x1 {
                let pixel = y as usize * width + x as usize;
                if !self.active[pixel] {
                    continue;
                }
                let (xs, ys) = (
                    x.saturating_sub(1).max(x0)..(x + 2).min(x1),
                    y.saturating_sub(1).max(y0)..(y + 2).min(y1),
                );
                still[pixel] = ys.clone().any(|ny| xs.clone().any(|nx| above(nx, ny)));
            }
        }
        self.active = still;
        self.count()
    }

    /// How many pixels are still sampled.
    pub fn count(&self) -> usize {
        self.active.iter().filter(|&&a| a).count()
    }

    /// The active pixels' indices (`y * width + x`), in image order.
    pub fn list(&self) -> Vec<u32> {
        (0..self.active.len() as u32)
            .filter(|&p| self.active[p as usize])
            .collect()
    }
}

/// What an adaptive render achieved (`RenderOutput::adaptive`).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveReport {
    /// The target the render sampled towards (`AdaptiveSettings::noise_target`).
    pub noise_target: f32,
    /// Pixels of the crop window whose final error estimate is below the target.
    pub pixels_converged: usize,
    /// Pixels of the crop window.
    pub pixels: usize,
    /// Mean and largest error estimate over the crop window's pixels.
    pub mean_error: f32,
    /// Largest error estimate over the crop window's pixels (infinite while one is).
    pub max_error: f32,
    /// Mean samples per pixel: what the render spent, against `render.spp` for every pixel.
    pub mean_spp: f64,
    /// Decisions made (each reads the accumulation back).
    pub decisions: u32,
}

impl AdaptiveReport {
    /// The report of the crop window's pixels of `errors`, with `samples` the crop window's
    /// sample counts.
    pub fn new(
        settings: &AdaptiveSettings,
        errors: &[f32],
        samples: &[u32],
        decisions: u32,
    ) -> AdaptiveReport {
        let finite: Vec<f32> = errors.iter().copied().filter(|e| e.is_finite()).collect();
        AdaptiveReport {
            noise_target: settings.noise_target,
            pixels_converged: errors
                .iter()
                .filter(|&&e| e < settings.noise_target)
                .count(),
            pixels: errors.len(),
            mean_error: if finite.len() == errors.len() && !errors.is_empty() {
                finite.iter().sum::<f32>() / finite.len() as f32
            } else {
                f32::INFINITY
            },
            // f32::max would pass over a NaN estimate (a pixel whose radiance is NaN).
            max_error: if finite.len() == errors.len() {
                finite.iter().copied().fold(0.0, f32::max)
            } else {
                f32::INFINITY
            },
            mean_spp: samples.iter().map(|&n| n as f64).sum::<f64>() / samples.len().max(1) as f64,
            decisions,
        }
    }

    /// One line for the render's report.
    pub fn summary(&self) -> String {
        format!(
            "adaptive sampling: {} of {} pixels below the noise target {} (mean error {:.3e}, \
             largest {:.3e}); {:.1} samples per pixel on average, {} decisions",
            self.pixels_converged,
            self.pixels,
            self.noise_target,
            self.mean_error,
            self.max_error,
            self.mean_spp,
            self.decisions
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_halves_have_no_error() {
        assert_eq!(pixel_error([2.0, 4.0, 6.0, 4.0], [2.0, 4.0, 6.0, 4.0]), 0.0);
    }

    #[test]
    fn a_half_without_samples_is_unconverged() {
        assert_eq!(pixel_error([1.0; 4], [0.0; 4]), f32::INFINITY);
        assert_eq!(pixel_error([0.0; 4], [1.0; 4]), f32::INFINITY);
    }

    #[test]
    fn error_of_equal_halves_is_half_their_difference_over_root_intensity() {
        // Means 1 and 3 in every channel, 8 samples each: I = 2 per channel, so the standard
        // error of each channel is |1 - 3| / 2 = 1 and e = 3 / (1e-4 + sqrt(6)).
        let e = pixel_error([8.0, 8.0, 8.0, 8.0], [24.0, 24.0, 24.0, 8.0]);
        let expected = 3.0 / (1e-4 + 6f32.sqrt());
        assert!((e - expected).abs() < 1e-6 * expected, "{e} vs {expected}");
    }

    #[test]
    fn unequal_halves_weight_their_difference_by_both_counts() {
        // n_a = 2, n_b = 6: sqrt(8 (1/2 + 1/6)) = sqrt(16/3).
        let e = pixel_error([2.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 6.0]);
        let expected = 1.0 / (16.0f32 / 3.0).sqrt() / (1e-4 + 0.25f32.sqrt());
        assert!((e - expected).abs() < 1e-6 * expected, "{e} vs {expected}");
    }

    #[test]
    fn scaling_a_pixel_scales_its_error_by_the_root_of_the_scale() {
        let (a, b) = ([1.0, 2.0, 3.0, 4.0], [2.0, 2.5, 2.0, 4.0]);
        let scale = |h: [f32; 4], k: f32| [h[0] * k, h[1] * k, h[2] * k, h[3]];
        let ratio = pixel_error(scale(a, 100.0), scale(b, 100.0)) / pixel_error(a, b);
        assert!((ratio - 10.0).abs() < 1e-3, "{ratio}");
    }

    #[test]
    fn a_pixel_stops_only_with_its_neighbours() {
        let mut active = ActivePixels::new(5, 5, [0, 5, 0, 5]);
        let mut errors = vec![0.0; 25];
        errors[2 * 5 + 2] = 1.0; // the centre is noisy
        assert_eq!(active.decide(&errors, 0.5), 9);
        assert_eq!(active.list(), vec![6, 7, 8, 11, 12, 13, 16, 17, 18]);
        // Once the centre meets the target, everything stops: a stopped pixel holds none of its
        // neighbours, and never restarts.
        errors[2 * 5 + 2] = 0.0;
        errors[0] = 1.0;
        assert_eq!(active.decide(&errors, 0.5), 0);
        assert!(active.list().is_empty());
    }

    #[test]
    fn pixels_outside_the_crop_window_are_never_active() {
        let mut active = ActivePixels::new(4, 3, [1, 3, 1, 2]);
        assert_eq!(active.list(), vec![5, 6]);
        // A noisy pixel outside the window does not keep its neighbours inside it going.
        let mut errors = vec![0.0; 12];
        errors[0] = 1.0;
        assert_eq!(active.decide(&errors, 0.5), 0);
    }

    #[test]
    fn the_report_counts_converged_pixels_and_spent_samples() {
        let settings = AdaptiveSettings {
            noise_target: 0.1,
            min_spp: 4,
        };
        let report = AdaptiveReport::new(&settings, &[0.05, 0.2, 0.01, 0.1], &[4, 16, 4, 8], 3);
        assert_eq!(report.pixels_converged, 2);
        assert_eq!(report.max_error, 0.2);
        assert!((report.mean_error - 0.09).abs() < 1e-6);
        assert_eq!(report.mean_spp, 8.0);
    }
}
