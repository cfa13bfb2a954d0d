//! Adaptive sampling (`render.noise_target`, `--noise-target`): samples go where they reduce
//! the image's error most, until its estimated relative error is below the target or
//! `render.spp` (then the most a pixel takes) is reached. The method, why it holds and its
//! measurements: `docs/convergence.md`, "Adaptive sampling".
//!
//! **The measure.** The error of an image is its relative MSE against the converged image,
//! `(1/3N) Σ_pixels Σ_c (x − r)² / (r² + 0.01)` (`metrics::rel_mse`). A pixel's share is
//! estimated from its samples as
//!
//! ```text
//! v = (1/3) Σ_c SE_c² / (I_c² + 0.01)
//! ```
//!
//! with `I` its mean and `SE` the standard error of that mean, and the image's estimated
//! relative error is `E = sqrt(mean_pixels v)`. The target `X` asks for `E ≤ X`.
//!
//! **Halves that are the pattern.** A pixel's samples are the indices `0..n` of a progressive
//! pattern (`sampler.rs`: every prefix stratified), and decisions come at powers of two
//! `n = min_spp, 2 min_spp, ...` (`min_spp` rounded up to a power of two). There the samples
//! split into two halves `[0, n/2)` and `[n/2, n)`: blocks of the pattern aligned to powers of
//! two, each as stratified on its own as a render of `n/2` samples (an elementary net of the
//! scrambled Sobol and progressive stratified patterns; independent for random ones), so their
//! difference measures the error of the pattern in use. The driver keeps the sums at the last
//! split on the host, so the accumulation needs one layer. With means `a` and `b` of `n_a` and
//! `n_b` samples (`n = n_a + n_b`), `SE² = (a − b)² n_a n_b / n²` (`(a − b)² / 4` for equal
//! halves, Dammertz et al. 2010 and Cycles' two-half-image estimate). Two halves of one
//! stratified set are negatively correlated, `E[(a − b)²] / 4 ≥ Var I`: the estimate errs on the
//! high side.
//!
//! **Where the samples go.** At a decision every pixel still sampled has `n` samples and an
//! estimate `v_p`; the pixels that stopped keep theirs. Predicting `v_p n / n'` after `n'`
//! samples (Monte Carlo's rate, slower than a stratified pattern's), the fewest samples that
//! bring the image's mean to `X²` are `n'_p = K sqrt(v_p n)`, with `K` such that the predicted
//! mean is `X²` (Lagrange; the optimal allocation of a sample budget, `n_p ∝ σ_p`), and no pixel
//! below the `n` it has: the pixels whose `n'_p ≤ n` stop, and `K` is recomputed without them
//! until none changes side (water-filling, over the estimates in increasing order). A pixel
//! whose `n'_p` is beyond `2n` goes to `2n` and is decided again there; one short of it goes to
//! `n'_p` (rounded up to a quarter of `n`, [`step_after`]) and stops. A pixel that stopped
//! never restarts. Uniform sampling is one allocation among those considered, so with honest
//! estimates this one needs no more samples for the same estimated error.
//!
//! **Decisions that luck cannot make.** One pixel's estimate is one draw of a noisy statistic,
//! zero when its halves agree by chance (a penumbra pixel whose first samples all saw the
//! light). A pixel's `v` is therefore at least the mean of its neighbourhood's (3x3, among the
//! pixels decided with it): a lucky pixel among noisy ones is given their error. And halves
//! that agree only say the samples agree: `n` stratified samples can all miss a sliver of up
//! to `1/n` of the pixel, and when a neighbour is an emitter that sliver matters (the row of
//! pixels along a ceiling light's far edge, each 1% covered, all black after 16 samples).
//! A pixel's `v` is at least [`unseen_squared_errors`]': the contrast with its neighbours over
//! `n`, relative to what the pixel may then hold.
//!
//! The decisions are made on the host from the backend's accumulation, by the same code for
//! the GPU and the CPU path.

/// Adaptive sampling's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// The image's estimated relative error `E` (module docs) to reach.
    pub noise_target: f32,
    /// Samples every pixel receives before the first decision (both halves need some); the
    /// first decision comes at the power of two at or above it.
    pub min_spp: u32,
}

impl AdaptiveSettings {
    /// Samples every pixel has at the first decision: `min_spp` rounded up to a power of two.
    pub fn first_decision(&self) -> u32 {
        self.min_spp.max(2).next_power_of_two()
    }
}

/// After a decision at `n` samples, the samples pixels are given in: a quarter of `n`, at least
/// 8 (the CPU path traces a pixel's camera rays in packets of 8), at most `n`.
pub fn step_after(n: u32) -> u32 {
    (n / 4).max(8).min(n)
}

/// `render.min_spp` when the scene does not give it (capped at `render.spp`).
pub const DEFAULT_MIN_SPP: u32 = 16;

/// The relative MSE's term that keeps dark pixels from dominating (`metrics::rel_mse`).
const DARK: f32 = 0.01;

/// The squared relative error `v` of a pixel (module docs) from its halves' sums
/// `(Σ rgb, samples)`; infinite while a half has no sample.
pub fn pixel_squared_error(a: [f32; 4], b: [f32; 4]) -> f32 {
    let (na, nb) = (a[3], b[3]);
    if na <= 0.0 || nb <= 0.0 {
        return f32::INFINITY;
    }
    let n = na + nb;
    let weight = na * nb / (n * n);
    (0..3)
        .map(|c| {
            let (ma, mb) = (a[c] / na, b[c] / nb);
            let mean = (a[c] + b[c]) / n;
            weight * (ma - mb) * (ma - mb) / (mean * mean + DARK)
        })
        .sum::<f32>()
        / 3.0
}

/// Every pixel's `v` from its sums now (`(Σ rgb, samples)`) and at its last split: the halves
/// are the samples before the split and after it.
pub fn pixel_squared_errors(sums: &[[f32; 4]], split: &[[f32; 4]]) -> Vec<f32> {
    sums.iter()
        .zip(split)
        .map(|(now, before)| {
            let after = std::array::from_fn(|c| now[c] - before[c]);
            pixel_squared_error(*before, after)
        })
        .collect()
}

/// Every pixel's estimate `v`: the larger of its halves' ([`pixel_squared_errors`]) and of what
/// its samples cannot have seen ([`unseen_squared_errors`]). `sums` and `split` are the
/// image's, `width` pixels a row; pixels outside `crop` (`[x0, x1, y0, y1]`) are left out.
pub fn squared_error_estimates(
    sums: &[[f32; 4]],
    split: &[[f32; 4]],
    width: u32,
    crop: [u32; 4],
) -> Vec<f32> {
    let unseen = unseen_squared_errors(sums, width, crop);
    pixel_squared_errors(sums, split)
        .into_iter()
        .zip(unseen)
        // A NaN estimate stays NaN (f32::max would drop it).
        .map(|(v, u)| if v.is_nan() { v } else { v.max(u) })
        .collect()
}

/// The squared error a pixel's `n` samples cannot rule out, in the measure `v`: `n` stratified
/// samples leave unseen a sliver of up to `1/n` of the pixel (a strip between two strata),
/// where a neighbour's radiance may reach in. So each channel's mean may be off by `C_c / n`,
/// `C_c` the largest difference between the pixel's mean `I_c` and a neighbour's (of the eight
/// within the crop window that have samples), and its true value be as large as
/// `I_c + C_c / n`: `(1/3) Σ_c (C_c / n)² / ((I_c + C_c / n)² + 0.01)`. A black pixel beside an
/// emitter is then nearly 100% uncertain until `n` is in the hundreds; the bound falls as
/// `1/n²` once `C_c / n` is small, faster than any pattern's variance, so it matters only where
/// the halves agree beside contrast.
pub fn unseen_squared_errors(sums: &[[f32; 4]], width: u32, crop: [u32; 4]) -> Vec<f32> {
    let [x0, x1, y0, y1] = crop;
    let width = width as usize;
    let mean = |p: usize| -> Option<[f32; 3]> {
        let n = sums[p][3];
        (n > 0.0).then(|| [sums[p][0] / n, sums[p][1] / n, sums[p][2] / n])
    };
    let mut unseen = vec![0.0; sums.len()];
    for y in y0..y1 {
        for x in x0..x1 {
            let pixel = y as usize * width + x as usize;
            let Some(own) = mean(pixel) else { continue };
            let mut contrast = [0.0f32; 3];
            for ny in y.saturating_sub(1).max(y0)..(y + 2).min(y1) {
                for nx in x.saturating_sub(1).max(x0)..(x + 2).min(x1) {
                    if let Some(other) = mean(ny as usize * width + nx as usize) {
                        for c in 0..3 {
                            contrast[c] = contrast[c].max((other[c] - own[c]).abs());
                        }
                    }
                }
            }
            let n = sums[pixel][3];
            unseen[pixel] = (0..3)
                .map(|c| {
                    let missed = contrast[c] / n;
                    let most = own[c].max(0.0) + missed;
                    missed * missed / (most * most + DARK)
                })
                .sum::<f32>()
                / 3.0;
        }
    }
    unseen
}

/// The image's estimated relative error `E = sqrt(mean v)` over `estimates` (NaN stays NaN).
pub fn image_error(estimates: &[f32]) -> f32 {
    let sum: f64 = estimates.iter().map(|&v| v as f64).sum();
    (sum / estimates.len().max(1) as f64).sqrt() as f32
}

/// Which pixels of an image are still sampled: the samples each is to reach, and the decisions
/// that set them.
#[derive(Clone, Debug)]
pub struct ActivePixels {
    width: u32,
    /// The crop window `[x0, x1, y0, y1]`: pixels outside it are never sampled.
    crop: [u32; 4],
    /// Per pixel of the image: the samples it is to have (0 outside the crop window).
    goal: Vec<u32>,
}

impl ActivePixels {
    /// Every pixel of `crop` to be sampled `first` times.
    pub fn new(width: u32, height: u32, crop: [u32; 4], first: u32) -> ActivePixels {
        let [x0, x1, y0, y1] = crop;
        let goal = (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| {
                    let inside = (x0..x1).contains(&x) && (y0..y1).contains(&y);
                    if inside { first } else { 0 }
                })
            })
            .collect();
        ActivePixels { width, crop, goal }
    }

    /// The decision at `n` samples, which every pixel whose goal is `n` has, from every pixel's
    /// estimate `v` (`estimates`, the image's; a stopped pixel's is final): each decided
    /// pixel's `v` is raised to its neighbourhood's mean, then the goals that bring the image's
    /// mean `v` to `target²` with the fewest samples (module docs), at most `2n` and `most`.
    /// Returns how many pixels go on.
    pub fn decide(&mut self, estimates: &[f32], target: f32, n: u32, most: u32) -> usize {
        let deciding: Vec<usize> = (0..self.goal.len())
            .filter(|&p| self.goal[p] == n)
            .collect();
        let pooled = self.pooled(estimates, n, &deciding);
        // The stopped pixels' error is spent; the rest of the budget is the deciding ones'.
        let pixels = self.goal.iter().filter(|&&g| g > 0).count() as f64;
        let spent: f64 = (0..self.goal.len())
            .filter(|&p| self.goal[p] > 0 && self.goal[p] != n)
            .map(|p| estimates[p].max(0.0) as f64)
            .filter(|v| v.is_finite())
            .sum();
        let budget = pixels * (target as f64).powi(2) - spent;
        let mut order: Vec<(f64, usize)> = deciding
            .iter()
            .zip(&pooled)
            .map(|(&p, &v)| (v, p))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let scale = water_level(&order, budget, n);
        let step = step_after(n) as f64;
        for &(v, pixel) in &order {
            let wanted = scale * (v * n as f64).sqrt();
            if wanted > n as f64 {
                let steps = ((wanted - n as f64) / step).ceil();
                let goal = (n as f64 + steps * step)
                    .min(2.0 * n as f64)
                    .min(most as f64);
                self.goal[pixel] = goal as u32;
            }
        }
        self.count_beyond(n)
    }

    /// Each deciding pixel's `v`, at least the mean of its neighbourhood's (the deciding
    /// pixels of its 3x3 within the crop window); NaN counts as infinite.
    fn pooled(&self, estimates: &[f32], n: u32, deciding: &[usize]) -> Vec<f64> {
        let [x0, x1, y0, y1] = self.crop;
        let width = self.width as usize;
        let v = |p: usize| match estimates[p] {
            e if e.is_nan() => f64::INFINITY,
            e => e.max(0.0) as f64,
        };
        deciding
            .iter()
            .map(|&pixel| {
                let (x, y) = ((pixel % width) as u32, (pixel / width) as u32);
                let (mut sum, mut count) = (0.0, 0.0);
                for ny in y.saturating_sub(1).max(y0)..(y + 2).min(y1) {
                    for nx in x.saturating_sub(1).max(x0)..(x + 2).min(x1) {
                        let q = ny as usize * width + nx as usize;
                        if self.goal[q] == n {
                            sum += v(q);
                            count += 1.0;
                        }
                    }
                }
                v(pixel).max(sum / count)
            })
            .collect()
    }

    /// How many pixels are to be sampled beyond `samples`.
    pub fn count_beyond(&self, samples: u32) -> usize {
        self.goal.iter().filter(|&&g| g > samples).count()
    }

    /// The indices (`y * width + x`), in image order, of the pixels to be sampled beyond
    /// `samples`.
    pub fn list_beyond(&self, samples: u32) -> Vec<u32> {
        (0..self.goal.len() as u32)
            .filter(|&p| self.goal[p as usize] > samples)
            .collect()
    }
}

/// The `K` of the allocation `n'_p = K sqrt(v_p n)` (module docs) for pixels of estimates `v`
/// at `n` samples each, `order` sorted by increasing `v`, and a squared-error `budget` (the
/// target's sum less the stopped pixels'): the pixels of the smallest `v` stop (`n'_p ≤ n`,
/// their `v` spent from the budget) until the rest, predicted at `v n / n'`, share what is left.
/// Infinite when nothing is left: every pixel with an error goes on.
fn water_level(order: &[(f64, usize)], budget: f64, n: u32) -> f64 {
    let n = n as f64;
    let roots: f64 = order.iter().map(|(v, _)| (v * n).sqrt()).sum();
    let (mut stopped, mut roots_left) = (0.0, roots);
    for &(v, _) in order {
        let left = budget - stopped;
        if left <= 0.0 || !roots_left.is_finite() {
            return f64::INFINITY;
        }
        let scale = roots_left / left;
        // This pixel and every larger one go on: the level holds.
        if scale * (v * n).sqrt() > n {
            return scale;
        }
        stopped += v;
        roots_left -= (v * n).sqrt();
    }
    // Every pixel stops.
    0.0
}

/// What an adaptive render achieved (`RenderOutput::adaptive`).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveReport {
    /// The target the render sampled towards (`AdaptiveSettings::noise_target`).
    pub noise_target: f32,
    /// The image's estimated relative error `E` at the end (infinite while a pixel's is).
    pub image_error: f32,
    /// Pixels of the crop window.
    pub pixels: usize,
    /// The largest pixel's estimated relative error `sqrt(v)` (infinite while one is).
    pub max_pixel_error: f32,
    /// Mean samples per pixel: what the render spent, against `render.spp` for every pixel.
    pub mean_spp: f64,
    /// Decisions made (each reads the accumulation back).
    pub decisions: u32,
    /// Pixels that stopped short of the most samples a pixel takes (`render.spp`).
    pub pixels_short: usize,
    /// The render was interrupted, failed or spent its time budget before its decisions
    /// were done.
    pub stopped_early: bool,
}

impl AdaptiveReport {
    /// The report of the crop window's pixels of `estimates` (`v`), with `samples` the crop
    /// window's sample counts and `most` the samples a pixel takes at most.
    pub fn new(
        settings: &AdaptiveSettings,
        estimates: &[f32],
        samples: &[u32],
        most: u32,
        decisions: u32,
    ) -> AdaptiveReport {
        // f32::max would pass over a NaN estimate (a pixel whose radiance is NaN).
        let largest = estimates.iter().fold(0.0f32, |m, &v| match v.is_nan() {
            true => f32::INFINITY,
            false => m.max(v),
        });
        AdaptiveReport {
            noise_target: settings.noise_target,
            image_error: match estimates.iter().any(|v| v.is_nan()) {
                true => f32::INFINITY,
                false => image_error(estimates),
            },
            pixels: estimates.len(),
            max_pixel_error: largest.sqrt(),
            mean_spp: samples.iter().map(|&n| n as f64).sum::<f64>() / samples.len().max(1) as f64,
            decisions,
            pixels_short: samples.iter().filter(|&&n| n < most).count(),
            stopped_early: false,
        }
    }

    /// One line for the render's report.
    pub fn summary(&self) -> String {
        format!(
            "adaptive sampling: estimated relative error {:.3e} of the image against the noise \
             target {} ({}; largest pixel {:.3e}); {:.1} samples per pixel on average over {} \
             pixels, {} decisions",
            self.image_error,
            self.noise_target,
            if self.image_error <= self.noise_target {
                "met".to_string()
            } else if self.stopped_early {
                "not met: the render stopped before its samples were taken".to_string()
            } else if self.pixels_short > 0 {
                // A stopped pixel never restarts (its samples stay the first indices of its
                // pattern), so an allocation from early, noisy estimates can fall short.
                format!(
                    "not met: {} pixels stopped short of render.spp on the estimates of their \
                     first samples; a larger render.min_spp estimates better",
                    self.pixels_short
                )
            } else {
                "not met within render.spp".to_string()
            },
            self.max_pixel_error,
            self.mean_spp,
            self.pixels,
            self.decisions
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_halves_have_no_error() {
        assert_eq!(
            pixel_squared_error([2.0, 4.0, 6.0, 4.0], [2.0, 4.0, 6.0, 4.0]),
            0.0
        );
    }

    #[test]
    fn a_half_without_samples_is_unconverged() {
        assert_eq!(pixel_squared_error([1.0; 4], [0.0; 4]), f32::INFINITY);
        assert_eq!(pixel_squared_error([0.0; 4], [1.0; 4]), f32::INFINITY);
    }

    #[test]
    fn the_error_of_equal_halves_is_their_squared_half_difference_over_the_mean_squared() {
        // Means 1 and 3 in every channel, 8 samples each: I = 2, SE² = (1 - 3)² / 4 = 1, so
        // v = 1 / (4 + 0.01).
        let v = pixel_squared_error([8.0, 8.0, 8.0, 8.0], [24.0, 24.0, 24.0, 8.0]);
        let expected = 1.0 / 4.01;
        assert!((v - expected).abs() < 1e-6 * expected, "{v} vs {expected}");
    }

    #[test]
    fn unequal_halves_weight_their_difference_by_both_counts() {
        // n_a = 2 (mean 1 in red), n_b = 6 (mean 0): SE² = 1 * 2 * 6 / 64, I = 0.25 in red.
        let v = pixel_squared_error([2.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 6.0]);
        let expected = (12.0 / 64.0) / (0.0625 + 0.01) / 3.0;
        assert!((v - expected).abs() < 1e-6 * expected, "{v} vs {expected}");
    }

    #[test]
    fn a_bright_pixel_is_measured_relative_to_its_mean() {
        // Scaling a pixel far above the dark term leaves its relative error unchanged.
        let (a, b) = ([10.0, 20.0, 30.0, 4.0], [20.0, 25.0, 20.0, 4.0]);
        let scale = |h: [f32; 4], k: f32| [h[0] * k, h[1] * k, h[2] * k, h[3]];
        let ratio =
            pixel_squared_error(scale(a, 100.0), scale(b, 100.0)) / pixel_squared_error(a, b);
        assert!((ratio - 1.0).abs() < 2e-3, "{ratio}");
    }

    #[test]
    fn a_lucky_pixel_takes_its_neighbourhoods_error() {
        // A 3x3 image at 16 samples: every pixel noisy (v = 0.09) but the centre, whose halves
        // agreed. Target 0.1 (0.01 summed per pixel): the image's mean 0.08 is above it.
        let mut active = ActivePixels::new(3, 3, [0, 3, 0, 3], 16);
        let mut estimates = vec![0.09; 9];
        estimates[4] = 0.0;
        assert_eq!(active.decide(&estimates, 0.1, 16, 1024), 9);
        assert_eq!(
            active.list_beyond(16).len(),
            9,
            "the lucky centre goes on too"
        );
    }

    #[test]
    fn the_samples_go_where_they_reduce_the_error_most() {
        // A row of 4 pixels at 16 samples, target 0.1 (a mean v of 0.01): pixels 0-1 noisy
        // (v = 0.04), 2-3 exact; pixel 2 is pooled to its neighbourhood's mean, 0.04 / 3.
        // n' = K sqrt(v n) with K = Σ sqrt(v n) / 0.04 = 51.5: the noisy pair wants 41 samples
        // (beyond 32: decided again there), pixel 2 wants 24, pixel 3 stops.
        let mut active = ActivePixels::new(4, 1, [0, 4, 0, 1], 16);
        let estimates = [0.04, 0.04, 0.0, 0.0];
        assert_eq!(active.decide(&estimates, 0.1, 16, 1024), 3);
        assert_eq!(active.list_beyond(23), vec![0, 1, 2]);
        assert_eq!(active.list_beyond(24), vec![0, 1]);
        assert!(active.list_beyond(32).is_empty());
    }

    #[test]
    fn an_image_below_its_target_stops_everywhere() {
        let mut active = ActivePixels::new(2, 2, [0, 2, 0, 2], 16);
        assert_eq!(
            active.decide(&[0.001, 0.002, 0.0, 0.0005], 0.1, 16, 1024),
            0
        );
        assert!(active.list_beyond(16).is_empty());
    }

    #[test]
    fn a_nan_estimate_keeps_its_pixel_going() {
        let mut active = ActivePixels::new(1, 1, [0, 1, 0, 1], 16);
        assert_eq!(active.decide(&[f32::NAN], 0.1, 16, 1024), 1);
        assert_eq!(active.list_beyond(31), vec![0]);
    }

    #[test]
    fn goals_stop_at_twice_the_samples_and_at_the_most() {
        let mut active = ActivePixels::new(1, 1, [0, 1, 0, 1], 64);
        // 1.2² the target: 64 * 1.44 = 92.2 samples, rounded up to quarters of 64: 96.
        assert_eq!(active.decide(&[0.0144], 0.1, 64, 1024), 1);
        assert_eq!(active.list_beyond(95), vec![0]);
        assert!(active.list_beyond(96).is_empty());
        let mut active = ActivePixels::new(1, 1, [0, 1, 0, 1], 64);
        active.decide(&[100.0], 0.1, 64, 1024);
        assert!(active.list_beyond(128).is_empty(), "decided again at 128");
        let mut active = ActivePixels::new(1, 1, [0, 1, 0, 1], 64);
        active.decide(&[100.0], 0.1, 64, 100);
        assert_eq!(active.list_beyond(99), vec![0]);
        assert!(active.list_beyond(100).is_empty());
    }

    #[test]
    fn a_stopped_pixels_error_is_spent_from_the_budget() {
        // Pixel 0 stopped at 16 with v = 0.015: the image (2 pixels, target 0.1: 0.02 in all)
        // has 0.005 left for pixel 1 (v = 0.01 at 32 samples): it needs 64.
        let mut active = ActivePixels::new(2, 1, [0, 2, 0, 1], 16);
        assert_eq!(active.decide(&[0.2, 0.2], 0.1, 16, 1024), 2);
        // Pretend pixel 0 stopped at 16 (a goal short of 32 reached).
        active.goal[0] = 24;
        assert_eq!(active.decide(&[0.015, 0.01], 0.1, 32, 1024), 1);
        assert_eq!(active.list_beyond(63), vec![1]);
        assert!(active.list_beyond(64).is_empty());
    }

    #[test]
    fn pixels_outside_the_crop_window_are_never_active() {
        let mut active = ActivePixels::new(4, 3, [1, 3, 1, 2], 16);
        assert_eq!(active.list_beyond(0), vec![5, 6]);
        // A noisy pixel outside the window does not keep its neighbours inside it going.
        let mut estimates = vec![0.0; 12];
        estimates[0] = 1.0;
        assert_eq!(active.decide(&estimates, 0.5, 16, 64), 0);
    }

    #[test]
    fn a_pixel_beside_contrast_cannot_claim_to_have_seen_everything() {
        // A row of 3 pixels, 16 samples each: black, black, and an emitter of 11 a channel.
        let sums = [
            [0.0, 0.0, 0.0, 16.0],
            [0.0, 0.0, 0.0, 16.0],
            [11.0 * 16.0, 11.0 * 16.0, 11.0 * 16.0, 16.0],
        ];
        let unseen = unseen_squared_errors(&sums, 3, [0, 3, 0, 1]);
        assert_eq!(unseen[0], 0.0, "no contrast beside it");
        // The middle pixel: C = 11 a channel, so it may be 11/16 where it saw 0: 98% unsure.
        let missed = 11.0f32 / 16.0;
        let expected = missed * missed / (missed * missed + 0.01);
        assert!(
            (unseen[1] - expected).abs() < 1e-5 * expected,
            "{}",
            unseen[1]
        );
        assert!(unseen[1] > 0.97);
        // The emitter beside it: off by at most 11/16 of 11, about 0.4%.
        assert!(unseen[2] < 0.004, "{}", unseen[2]);
        // Its halves agree (both black), yet its estimate is the unseen one; a pixel without
        // samples has none.
        let split = [
            [0.0, 0.0, 0.0, 8.0],
            [0.0, 0.0, 0.0, 8.0],
            [88.0, 88.0, 88.0, 8.0],
        ];
        let estimates = squared_error_estimates(&sums, &split, 3, [0, 3, 0, 1]);
        assert_eq!(estimates[1], unseen[1]);
        assert_eq!(estimates[0], 0.0);
        let empty = [[0.0; 4], [0.0, 0.0, 0.0, 4.0]];
        assert_eq!(
            unseen_squared_errors(&empty, 2, [0, 2, 0, 1]),
            vec![0.0, 0.0]
        );
    }

    #[test]
    fn the_halves_are_the_samples_before_and_after_the_split() {
        let v = pixel_squared_errors(&[[32.0, 32.0, 32.0, 16.0]], &[[8.0, 8.0, 8.0, 8.0]]);
        assert_eq!(
            v,
            vec![pixel_squared_error(
                [8.0, 8.0, 8.0, 8.0],
                [24.0, 24.0, 24.0, 8.0]
            )]
        );
        assert_eq!(
            pixel_squared_errors(&[[4.0; 4]], &[[4.0; 4]]),
            vec![f32::INFINITY]
        );
    }

    #[test]
    fn the_report_gives_the_images_error_and_spent_samples() {
        let settings = AdaptiveSettings {
            noise_target: 0.1,
            min_spp: 4,
        };
        let report = AdaptiveReport::new(&settings, &[0.01, 0.03, 0.0, 0.0], &[4, 16, 4, 8], 16, 3);
        assert!((report.image_error - 0.1).abs() < 1e-6);
        assert!((report.max_pixel_error - 0.03f32.sqrt()).abs() < 1e-6);
        assert_eq!(report.mean_spp, 8.0);
        assert_eq!(report.pixels_short, 3);
        assert!(report.summary().contains("(met;"));
        // Above the target with pixels short of render.spp: said so, with the way out.
        let short = AdaptiveReport::new(&settings, &[0.02, 0.03, 0.0, 0.0], &[4, 16, 4, 8], 16, 3);
        assert!(
            short
                .summary()
                .contains("not met: 3 pixels stopped short of render.spp"),
            "{}",
            short.summary()
        );
        let spent = AdaptiveReport::new(&settings, &[0.02, 0.03, 0.0, 0.0], &[16; 4], 16, 3);
        assert!(spent.summary().contains("not met within render.spp"));
        let stopped = AdaptiveReport {
            stopped_early: true,
            ..short
        };
        assert!(
            stopped
                .summary()
                .contains("not met: the render stopped before")
        );
        let nan = AdaptiveReport::new(&settings, &[0.01, f32::NAN], &[4, 4], 4, 1);
        assert_eq!(
            (nan.image_error, nan.max_pixel_error),
            (f32::INFINITY, f32::INFINITY)
        );
    }
}
