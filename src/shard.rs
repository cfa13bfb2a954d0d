//! Renders split over machines: `chambre render --shard I/N` renders a deterministic band of
//! rows (shard I of N) and writes it as linear floats with a manifest; `chambre merge` puts the
//! bands back together. Each pixel is rendered whole by one shard, with the random numbers of
//! the full image, so the merged image is bit-identical to a single render.
//!
//! The shard index can come from the batch engine that runs array jobs (`--shard auto/N`):
//! Kubernetes Indexed Jobs (`JOB_COMPLETION_INDEX`), Slurm arrays (`SLURM_ARRAY_TASK_ID`), AWS
//! Batch (`AWS_BATCH_JOB_ARRAY_INDEX`). See `docs/shards.md`.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::render::Image;

/// Variables array-job engines set to a task's index, in the order they are looked up.
pub const INDEX_VARIABLES: [&str; 3] = [
    "JOB_COMPLETION_INDEX",
    "SLURM_ARRAY_TASK_ID",
    "AWS_BATCH_JOB_ARRAY_INDEX",
];

/// Shard `index` (from 0) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, 0..`count`.
    pub index: u32,
    /// Shards the render is split into, at least 1.
    pub count: u32,
}

impl Shard {
    /// `I/N`, or `auto/N` with I from the first of [`INDEX_VARIABLES`] that is set.
    pub fn parse(text: &str) -> std::result::Result<Shard, String> {
        let (index, count) = text
            .split_once('/')
            .ok_or_else(|| format!("`{text}`: a shard is I/N (or auto/N), e.g. 0/4"))?;
        let count: u32 =
            count.parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
                format!("`{text}`: N must be a whole number of shards, at least 1")
            })?;
        let index: u32 = if index == "auto" {
            let (name, value) = INDEX_VARIABLES
                .iter()
                .find_map(|name| std::env::var(name).ok().map(|v| (*name, v)))
                .ok_or_else(|| {
                    format!(
                        "`{text}`: none of {} is set to give the shard's index",
                        INDEX_VARIABLES.join(", ")
                    )
                })?;
            value
                .trim()
                .parse()
                .map_err(|_| format!("{name}={value} is not a shard index"))?
        } else {
            index
                .parse()
                .map_err(|_| format!("`{text}`: I must be a whole number or auto"))?
        };
        if index >= count {
            return Err(format!(
                "`{text}`: shard {index} of {count} does not exist (0..{count})"
            ));
        }
        Ok(Shard { index, count })
    }

    /// This shard's band of the rows of `crop` (columns `crop[0]..crop[1]`, rows
    /// `crop[2]..crop[3]`): rows split as evenly as whole rows allow.
    pub fn rows(&self, crop: [u32; 4]) -> [u32; 4] {
        let [x0, x1, y0, y1] = crop;
        let rows = (y1 - y0) as u64;
        let at = |i: u32| y0 + (rows * i as u64 / self.count as u64) as u32;
        [x0, x1, at(self.index), at(self.index + 1)]
    }

    /// `out.exr` becomes `out.shard-2-of-4.exr` (the band) and `out.shard-2-of-4.json` (its
    /// manifest).
    pub fn paths(&self, output: &Path) -> (PathBuf, PathBuf) {
        let stem = output.with_extension("");
        let name = format!("{}.shard-{}-of-{}", stem.display(), self.index, self.count);
        (
            PathBuf::from(format!("{name}.exr")),
            PathBuf::from(format!("{name}.json")),
        )
    }
}

/// What a shard wrote: enough to check and place its band.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Which shard wrote it.
    pub shard: Shard,
    /// The full image's size.
    pub width: u32,
    /// The full image's height (pixels); `width` is its width.
    pub height: u32,
    /// The band: columns `band[0]..band[1]`, rows `band[2]..band[3]`.
    pub band: [u32; 4],
    /// The band's EXR, beside the manifest.
    pub image: String,
    /// FNV-1a 64 of the scene file and the overrides: shards of one render agree on it.
    pub render_hash: String,
    /// Samples of the band's least-sampled pixel.
    pub spp_min: u32,
    /// Samples of the band's most-sampled pixel.
    pub spp_max: u32,
    /// FNV-1a 64 of the band's pixels as written (each channel's f32 bits, little-endian):
    /// a band file replaced by another of the same size is refused.
    pub band_hash: String,
}

/// The hash a manifest keeps of its band's pixels ([`Manifest::band_hash`]).
pub fn band_hash(pixels: impl Iterator<Item = [f32; 3]>) -> String {
    // Streamed: a band of a 16384^2 render would be 800 MB gathered.
    let bytes = pixels.flat_map(|p| p.map(f32::to_le_bytes)).flatten();
    format!("{:016x}", crate::provenance::fnv1a64_of(bytes))
}

/// What the merged image is, and what a user should know of it.
pub struct Merged {
    /// The columns and rows the shards cover together.
    pub image: Image,
    /// Where the bands differ in samples (a shard interrupted or on a time budget): the image
    /// is whole, but not as even as one render of the samples asked.
    pub notes: Vec<String>,
    /// Every file read: the manifests and their bands.
    pub inputs: Vec<PathBuf>,
}

fn merge_error(path: &Path, message: impl Into<String>) -> Error {
    Error::File {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads the manifests of every shard of one render and assembles their bands into the image
/// of the columns and rows they cover together. Missing, repeated, foreign or overlapping
/// shards are errors naming the manifest.
pub fn merge(manifest_paths: &[PathBuf]) -> Result<Merged> {
    let mut manifests = Vec::new();
    for path in manifest_paths {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let manifest: Manifest = serde_json::from_str(&text)
            .map_err(|e| merge_error(path, format!("not a shard manifest: {e}")))?;
        manifests.push((path.clone(), manifest));
    }
    // In the shards' order, whatever the order given (a glob, `ls -t`, `find`).
    manifests.sort_by_key(|(_, m)| m.shard.index);
    let Some((first_path, first)) = manifests.first().cloned() else {
        return Err(merge_error(Path::new("."), "no shard manifest given"));
    };
    let count = first.shard.count as usize;
    if manifests.len() != count {
        return Err(merge_error(
            &first_path,
            format!(
                "{} manifests given for a render of {count} shards",
                manifests.len()
            ),
        ));
    }
    let (x0, x1) = (first.band[0], first.band[1]);
    let mut next_row = first.band[2];
    let mut pixels = Vec::new();
    let mut inputs = Vec::new();
    for (i, (path, m)) in manifests.iter().enumerate() {
        let same_render = m.render_hash == first.render_hash
            && m.shard.count == first.shard.count
            && (m.width, m.height) == (first.width, first.height)
            && (m.band[0], m.band[1]) == (x0, x1);
        if !same_render {
            return Err(merge_error(
                path,
                "belongs to another render than the first manifest",
            ));
        }
        if m.shard.index as usize != i || m.band[2] != next_row {
            return Err(merge_error(
                path,
                format!(
                    "shard {} does not follow the shards before it (a shard is missing or repeated)",
                    m.shard.index
                ),
            ));
        }
        let image_path = path.parent().unwrap_or(Path::new(".")).join(&m.image);
        inputs.extend([path.clone(), image_path.clone()]);
        let band = read_band(&image_path).map_err(|e| merge_error(&image_path, e.to_string()))?;
        let expected = (x1 - x0, m.band[3] - m.band[2]);
        if band.dimensions() != expected {
            return Err(merge_error(
                &image_path,
                format!(
                    "is {:?} pixels, the manifest says {expected:?}",
                    band.dimensions()
                ),
            ));
        }
        if band_hash(band.pixels().map(|p| p.0)) != m.band_hash {
            return Err(merge_error(
                &image_path,
                "is not the band its manifest describes (its pixels' hash differs)",
            ));
        }
        pixels.extend(band.pixels().map(|p| glam::Vec3::from(p.0)));
        next_row = m.band[3];
    }
    let image = Image {
        width: x1 - x0,
        height: next_row - first.band[2],
        pixels,
    };
    Ok(Merged {
        image,
        notes: uneven_samples(&manifests),
        inputs,
    })
}

/// A note where the bands' samples differ (a shard interrupted, failed or on a time budget).
fn uneven_samples(manifests: &[(PathBuf, Manifest)]) -> Vec<String> {
    let least = manifests.iter().map(|(_, m)| m.spp_min).min();
    let most = manifests.iter().map(|(_, m)| m.spp_max).max();
    match (least, most) {
        (Some(least), Some(most)) if least != most => {
            let bands: Vec<String> = manifests
                .iter()
                .map(|(_, m)| match m.spp_min == m.spp_max {
                    true => format!("shard {}: {} spp", m.shard.index, m.spp_min),
                    false => format!(
                        "shard {}: {} to {} spp",
                        m.shard.index, m.spp_min, m.spp_max
                    ),
                })
                .collect();
            vec![format!(
                "note: the bands hold {least} to {most} samples per pixel ({}): a shard was \
                 stopped early or given a time budget, so their noise differs",
                bands.join(", ")
            )]
        }
        _ => Vec::new(),
    }
}

/// A band's pixels, whatever its size: the image crate's default limit (512 MiB a decode) would
/// refuse the bands of the renders large enough to be split (a quarter of 16384^2 is 768 MiB).
fn read_band(path: &Path) -> image::ImageResult<image::Rgb32FImage> {
    let mut reader = image::ImageReader::open(path)?;
    reader.no_limits();
    Ok(reader.decode()?.into_rgb32f())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_rows_once_and_evenly() {
        let crop = [0, 10, 3, 103];
        let bands: Vec<[u32; 4]> = (0..7)
            .map(|index| Shard { index, count: 7 }.rows(crop))
            .collect();
        assert_eq!(bands[0][2], 3);
        assert_eq!(bands[6][3], 103);
        for pair in bands.windows(2) {
            assert_eq!(pair[0][3], pair[1][2]);
        }
        assert!(bands.iter().all(|b| (14..=15).contains(&(b[3] - b[2]))));
    }

    #[test]
    fn shard_specs_parse_or_say_why_not() {
        assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
        assert!(Shard::parse("4/4").unwrap_err().contains("does not exist"));
        assert!(Shard::parse("1/0").unwrap_err().contains("at least 1"));
        assert!(
            Shard::parse("x/2")
                .unwrap_err()
                .contains("whole number or auto")
        );
        assert!(Shard::parse("3").unwrap_err().contains("I/N"));
    }
}
