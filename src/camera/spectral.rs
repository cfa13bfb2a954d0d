//! The spectral mode's film: which wavelength a camera sample is traced at, and what its RGB
//! radiance then counts for in each channel. The scene stays RGB; only the lens's glass sees
//! the wavelength (its dispersion, `super::glass`), so that lateral and axial colour appear.
//!
//! A sample's wavelength λ is uniform on [λ₀, λ₁] = [SPECTRAL_MIN_NM, SPECTRAL_MAX_NM], drawn
//! from the random dimension the shutter time leaves unused (dimension 5, paired with it). The
//! film has three dye layers, each sensitive to one third of the range: blue below 500 nm, green
//! to 620 nm, red above, neighbours crossing over linearly across 40 nm. Their responses q_c(λ)
//! sum to 1 at every λ and each covers a third of the range, so the sample's channel c counts
//! its radiance's channel c times
//!
//! w_c(λ) = q_c(λ) / (∫ q_c dλ / (λ₁ − λ₀)) = 3 q_c(λ),
//!
//! whose mean over λ is exactly 1: a lens without dispersion renders the RGB image in
//! expectation (tested), and Σ_c w_c = 3 keeps a grey pixel's luminance noise down. Twins:
//! `sample_wavelength`, `film_response` in wgsl/camera.wgsl. docs/lens.md ("Spectral mode").

use glam::Vec3;

use crate::layout::{
    SPECTRAL_BLUE_GREEN_NM, SPECTRAL_CROSSOVER_NM, SPECTRAL_GREEN_RED_NM, SPECTRAL_MAX_NM,
    SPECTRAL_MIN_NM,
};

/// The wavelength (nm) of a sample whose pattern point is `u` in [0, 1).
pub fn sample_wavelength(u: f32) -> f32 {
    SPECTRAL_MIN_NM as f32 + u * (SPECTRAL_MAX_NM - SPECTRAL_MIN_NM) as f32
}

/// What a sample's RGB radiance counts for in each channel at wavelength `nm` (w_c above).
pub fn film_response(nm: f32) -> Vec3 {
    let half = 0.5 * SPECTRAL_CROSSOVER_NM as f32;
    let width = SPECTRAL_CROSSOVER_NM as f32;
    let blue = ((SPECTRAL_BLUE_GREEN_NM as f32 + half - nm) / width).clamp(0.0, 1.0);
    let red = ((nm - (SPECTRAL_GREEN_RED_NM as f32 - half)) / width).clamp(0.0, 1.0);
    3.0 * Vec3::new(red, 1.0 - blue - red, blue)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each channel's weight averages to 1 over the range (midpoint rule on 36000 points,
    /// exact for the piecewise-linear bands up to the kinks), and the weights always sum to 3.
    #[test]
    fn each_channel_counts_once_on_average() {
        let n = 36000;
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let w = film_response(sample_wavelength((k as f32 + 0.5) / n as f32));
            assert!(
                (w.element_sum() - 3.0).abs() < 1e-5 && w.min_element() >= 0.0,
                "{w}"
            );
            sum += w;
        }
        let mean = sum / n as f32;
        assert!((mean - Vec3::ONE).abs().max_element() < 1e-4, "{mean}");
    }

    #[test]
    fn the_bands_run_blue_to_red() {
        assert_eq!(film_response(400.0), Vec3::new(0.0, 0.0, 3.0));
        assert_eq!(film_response(560.0), Vec3::new(0.0, 3.0, 0.0));
        assert_eq!(film_response(700.0), Vec3::new(3.0, 0.0, 0.0));
        let crossing = film_response(SPECTRAL_BLUE_GREEN_NM as f32);
        assert!((crossing - Vec3::new(0.0, 1.5, 1.5)).abs().max_element() < 1e-6);
    }
}
