//! Where an image or a figure came from: the date, a hash of the scene, and the sidecar that
//! `chambre render --sidecar` writes beside an image so it can be reproduced.

use serde::Serialize;

/// Today's date (UTC) as YYYY-MM-DD, from the system clock.
pub fn utc_date() -> String {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    civil_date(seconds)
}

/// The UTC calendar date of a Unix time (H. Hinnant's civil-from-days).
fn civil_date(unix_seconds: u64) -> String {
    let days = (unix_seconds / 86_400) as i64 + 719_468;
    let era = days.div_euclid(146_097);
    let day_of_era = days.rem_euclid(146_097);
    let year_of_era =
        (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let month_index = (5 * day_of_year + 2) / 153;
    let day = day_of_year - (153 * month_index + 2) / 5 + 1;
    let month = if month_index < 10 {
        month_index + 3
    } else {
        month_index - 9
    };
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// FNV-1a, 64 bits: a stable fingerprint of a scene file (not a cryptographic hash).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    fnv1a64_of(bytes.iter().copied())
}

/// [`fnv1a64`] of bytes as they come, for data too large to gather into one slice first.
pub fn fnv1a64_of(bytes: impl Iterator<Item = u8>) -> u64 {
    bytes.fold(0xcbf2_9ce4_8422_2325, |hash, b| {
        (hash ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Everything needed to reproduce a rendered image, written as JSON beside it.
#[derive(Clone, Debug, Serialize)]
pub struct Sidecar {
    /// The crate version that rendered the image.
    pub chambre_version: &'static str,
    /// Render date (UTC), YYYY-MM-DD.
    pub date_utc: String,
    /// The command line, as given.
    pub command: Vec<String>,
    /// The scene file's path, as given.
    pub scene: String,
    /// FNV-1a 64 of the scene file's bytes, in hex.
    pub scene_hash: String,
    /// `--set` overrides and the flags that stand for them, in the order applied.
    pub overrides: Vec<String>,
    /// `render.seed`.
    pub seed: u32,
    /// Image width in pixels (of the crop window, when cropped).
    pub width: u32,
    /// Image height in pixels (of the crop window, when cropped).
    pub height: u32,
    /// `render.spp` after overrides.
    pub spp_requested: u32,
    /// Samples of the least and most sampled pixel (they differ when a render was stopped).
    pub spp_min: u32,
    /// Samples of the most sampled pixel.
    pub spp_max: u32,
    /// The backend that rendered: "CPU" or "GPU: " and the adapter.
    pub backend: String,
    /// Wall-clock time of the render (s).
    pub wall_seconds: f64,
    /// Device time in the kernels (s), where the GPU measures it.
    pub kernel_seconds: Option<f64>,
    /// Rays traced.
    pub rays: u64,
    /// "complete", or why the render stopped.
    pub status: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unix_times_become_their_calendar_dates() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(951_782_400), "2000-02-29");
        assert_eq!(civil_date(1_795_392_000 + 86_399), "2026-11-23");
    }

    #[test]
    fn fnv1a_matches_its_reference_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
