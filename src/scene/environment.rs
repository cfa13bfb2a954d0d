//! Environment maps as scenes give them: an equirectangular image of linear RGB radiance
//! (OpenEXR or Radiance HDR), and the piecewise-constant distribution over its texels that an
//! environment light's samples draw from (pbrt-v4's `PiecewiseConstant2D`: a marginal over
//! rows, a conditional over each row's texels), packed into the one array the kernels read
//! (`FlatScene::environment`). Sampling and lookups: `integrator::environment` and its twin
//! `wgsl/environment.wgsl`; the equations: `docs/lights.md`.
//!
//! Texel (column i, row j) covers u in [i / W, (i + 1) / W) and v in [j / H, (j + 1) / H),
//! row 0 the image's top (v = 0, the +y pole). Its weight is its luminance times sin(theta) at
//! the row's centre, theta = pi v: a texel's solid angle is proportional to it, so a constant
//! map is sampled uniformly over the sphere.

use std::path::{Path, PathBuf};

use crate::scene::texture::MAX_TEXTURE_SIDE;

/// A decoded environment map.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    /// The file it was read from (for messages and exports).
    pub source: PathBuf,
    /// Texels per row (longitude).
    pub width: u32,
    /// Rows (colatitude), from the +y pole down.
    pub height: u32,
    /// Linear RGB radiance, row by row from the image's top row.
    pub texels: Vec<[f32; 3]>,
}

/// Rec. 709 luminance of linear RGB: the texels' sampling weight.
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

impl EnvironmentMap {
    /// The map in file `path` (OpenEXR or Radiance HDR). The error is a sentence without the
    /// path.
    pub fn read(path: &Path) -> Result<EnvironmentMap, String> {
        let reader = image::ImageReader::open(path)
            .map_err(|e| e.to_string())?
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let image = reader
            .decode()
            .map_err(|e| format!("not a readable OpenEXR or HDR image: {e}"))?
            .into_rgb32f();
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| p.0).collect();
        EnvironmentMap::new(path, width, height, texels)
    }

    /// The map of `texels` (`width` x `height`, rows from the top), which came from `source`:
    /// refused where a side is out of range, a texel is negative or not finite, or every
    /// texel is black (there would be no light to sample).
    pub fn new(
        source: &Path,
        width: u32,
        height: u32,
        texels: Vec<[f32; 3]>,
    ) -> Result<EnvironmentMap, String> {
        if width == 0 || height == 0 || width.max(height) > MAX_TEXTURE_SIDE {
            return Err(format!(
                "a map of {width} x {height} texels: each side must be 1 to {MAX_TEXTURE_SIDE}"
            ));
        }
        assert_eq!(texels.len(), width as usize * height as usize);
        if let Some(k) = texels
            .iter()
            .position(|t| t.iter().any(|c| !c.is_finite() || *c < 0.0))
        {
            let (column, row) = (k as u32 % width, k as u32 / width);
            return Err(format!(
                "texel (column {column}, row {row}) is {:?}: radiance must be finite and not \
                 negative",
                texels[k]
            ));
        }
        if texels.iter().all(|t| luminance(*t) <= 0.0) {
            return Err("every texel is black: the map gives no light to sample".into());
        }
        Ok(EnvironmentMap {
            source: source.to_path_buf(),
            width,
            height,
            texels,
        })
    }

    /// The mean radiance over the sphere (each texel weighted by its solid angle).
    pub fn mean(&self) -> [f32; 3] {
        let mut sum = [0f64; 3];
        let mut weight = 0f64;
        for (k, t) in self.texels.iter().enumerate() {
            let s = self.row_sin(k as u32 / self.width);
            for c in 0..3 {
                sum[c] += t[c] as f64 * s;
            }
            weight += s;
        }
        sum.map(|c| (c / weight) as f32)
    }

    /// sin(theta) at the centre of row `row`.
    fn row_sin(&self, row: u32) -> f64 {
        (std::f64::consts::PI * (row as f64 + 0.5) / self.height as f64).sin()
    }

    /// The array the kernels read (`layout::LIGHT_ENVIRONMENT`): the texels' RGB (3 W H
    /// floats), each texel's density in (u, v) (W H), the marginal CDF over rows (H + 1),
    /// then each row's conditional CDF over its texels (W + 1 each). CDFs start at 0 and end
    /// at exactly 1; a black row's conditional is uniform (no sample lands in it). Sums in f64.
    pub fn packed(&self) -> Vec<f32> {
        let (w, h) = (self.width as usize, self.height as usize);
        let weights: Vec<f64> = (0..w * h)
            .map(|k| luminance(self.texels[k]) * self.row_sin((k / w) as u32))
            .collect();
        let rows: Vec<f64> = weights.chunks(w).map(|r| r.iter().sum::<f64>()).collect();
        let total: f64 = rows.iter().sum();
        // The density in (u, v) of texel k is its weight over the mean weight.
        let mean = total / (w * h) as f64;
        let mut packed = Vec::with_capacity(5 * w * h + 2 * h + 1);
        packed.extend(self.texels.iter().flatten());
        packed.extend(weights.iter().map(|&f| (f / mean) as f32));
        packed.extend(cdf(&rows));
        for row in weights.chunks(w) {
            packed.extend(cdf(row));
        }
        packed
    }
}

/// The CDF of the piecewise-constant function `f` (n + 1 values from 0 to exactly 1): uniform
/// where `f` is zero everywhere.
fn cdf(f: &[f64]) -> Vec<f32> {
    let total: f64 = f.iter().sum();
    let n = f.len();
    let mut out = Vec::with_capacity(n + 1);
    let mut running = 0.0;
    out.push(0.0);
    for (i, &x) in f.iter().enumerate() {
        running += x;
        let value = match total > 0.0 {
            true => running / total,
            false => (i + 1) as f64 / n as f64,
        };
        out.push(value as f32);
    }
    out[n] = 1.0;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Result<EnvironmentMap, String> {
        EnvironmentMap::new(Path::new("test.exr"), width, height, texels)
    }

    /// Negative, non-finite and all-black maps are refused, naming the texel.
    #[test]
    fn bad_texels_and_black_maps_are_refused() {
        let e = map(2, 1, vec![[1.0; 3], [0.0, -1.0, 0.0]]).unwrap_err();
        assert!(e.contains("column 1, row 0"), "{e}");
        let e = map(2, 1, vec![[f32::NAN, 0.0, 0.0], [1.0; 3]]).unwrap_err();
        assert!(e.contains("column 0, row 0"), "{e}");
        let e = map(2, 1, vec![[0.0; 3]; 2]).unwrap_err();
        assert!(e.contains("black"), "{e}");
        assert!(map(0, 1, vec![]).is_err());
    }

    /// The packed densities average to 1 over (u, v) and the CDFs are monotone, from 0 to 1;
    /// a black row has a uniform conditional and no probability in the marginal.
    #[test]
    fn packed_densities_average_to_one_and_cdfs_are_monotone() {
        let (w, h) = (5usize, 3usize);
        let mut texels = vec![[0.5f32, 1.0, 2.0]; w * h];
        for t in &mut texels[w..2 * w] {
            *t = [0.0; 3];
        }
        texels[2 * w + 3] = [40.0, 0.0, 0.0];
        let packed = map(w as u32, h as u32, texels).unwrap().packed();
        assert_eq!(packed.len(), 5 * w * h + 2 * h + 1);
        let pdf = &packed[3 * w * h..4 * w * h];
        let mean: f64 = pdf.iter().map(|&p| p as f64).sum::<f64>() / (w * h) as f64;
        assert!((mean - 1.0).abs() < 1e-6, "{mean}");
        let marginal = &packed[4 * w * h..4 * w * h + h + 1];
        assert_eq!((marginal[0], marginal[h]), (0.0, 1.0));
        assert_eq!(marginal[1], marginal[2], "the black row has no probability");
        let black_row = &packed[4 * w * h + h + 1 + (w + 1)..][..w + 1];
        for (i, &c) in black_row.iter().enumerate() {
            assert!((c - i as f32 / w as f32).abs() < 1e-7);
        }
        for pair in packed[4 * w * h..].windows(2) {
            assert!(pair[1] >= pair[0] || pair[1] == 0.0);
        }
    }
}
