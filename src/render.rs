//! The render driver: splits a render into passes of samples and tiles of pixels, runs them on
//! a [`Backend`] (GPU or CPU), reports progress, and returns an [`Image`].
//!
//! Each pass adds the same number of samples to every pixel, so the accumulation is a valid
//! image at every pass boundary: an interrupted or failing render keeps what it computed.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::accel::FlatScene;
use crate::error::{Error, Result};
use crate::layout::{
    GpuPass, STATUS_FLAGS, STATUS_PERMUTE_CAP, STATUS_RAYS, STATUS_STACK_OVERFLOW,
    STATUS_TRAVERSAL_CAP, STATUS_TRUNCATED,
};

/// Tile edge in pixels: one dispatch covers at most TILE x TILE pixels.
pub const TILE: u32 = 128;
/// Samples a pass aims to take in one tile (pixels x samples), to keep each dispatch short.
const SAMPLES_PER_DISPATCH: u32 = 1 << 17;

/// What one tile dispatch reported.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileStatus {
    pub flags: u32,
    pub rays: u64,
    pub truncated: u64,
}

impl TileStatus {
    pub fn from_words(words: &[u32]) -> TileStatus {
        TileStatus {
            flags: words[STATUS_FLAGS as usize],
            rays: words[STATUS_RAYS as usize] as u64,
            truncated: words[STATUS_TRUNCATED as usize] as u64,
        }
    }
}

/// A device that renders tiles into its own accumulation buffer (sum of radiance, samples).
pub trait Backend {
    fn render_tile(&mut self, pass: GpuPass) -> Result<TileStatus>;
    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>>;
}

/// Linear radiance, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// Mean of the accumulated samples of each pixel (a box filter).
    pub fn from_accumulation(width: u32, height: u32, accumulation: &[[f32; 4]]) -> Image {
        let pixels = accumulation
            .iter()
            .map(|a| {
                if a[3] > 0.0 {
                    Vec3::new(a[0], a[1], a[2]) / a[3]
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    pub fn non_finite_count(&self) -> usize {
        self.pixels.iter().filter(|p| !p.is_finite()).count()
    }
}

/// Progress events, for a bar or log lines.
pub trait Progress {
    fn advance(&mut self, done: u64, total: u64);
}

impl<F: FnMut(u64, u64)> Progress for F {
    fn advance(&mut self, done: u64, total: u64) {
        self(done, total)
    }
}

#[derive(Debug)]
pub struct RenderOutput {
    pub image: Image,
    /// Samples of the least-sampled pixel: `spp` when the render completed.
    pub samples_per_pixel: u32,
    /// Samples of the most-sampled pixel: a stopped render can end inside a pass.
    pub max_samples_per_pixel: u32,
    /// Pixels without a single sample (a render stopped before reaching them); they are 0.
    pub pixels_without_samples: usize,
    pub elapsed: Duration,
    pub rays: u64,
    pub truncated_paths: u64,
    /// Kernel loop caps hit (`layout::STATUS_*` bits); a non-zero value is reported as an error.
    pub status_flags: u32,
    /// Why the render stopped early, if it did; `image` then holds the samples taken so far.
    pub stopped: Option<Error>,
}

impl RenderOutput {
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Sample range of every pass for `spp` samples over tiles of `tile_pixels` pixels.
pub fn sample_passes(spp: u32, tile_pixels: u32) -> Vec<(u32, u32)> {
    let per_pass = (SAMPLES_PER_DISPATCH / tile_pixels.max(1)).clamp(1, spp);
    (0..spp.div_ceil(per_pass))
        .map(|i| (i * per_pass, per_pass.min(spp - i * per_pass)))
        .collect()
}

pub fn tiles(width: u32, height: u32) -> Vec<(u32, u32, u32, u32)> {
    let mut tiles = Vec::new();
    for y in (0..height).step_by(TILE as usize) {
        for x in (0..width).step_by(TILE as usize) {
            tiles.push((x, y, TILE.min(width - x), TILE.min(height - y)));
        }
    }
    tiles
}

/// Renders `scene` on `backend`. `cancel` is polled between dispatches.
pub fn render(
    scene: &FlatScene,
    backend: &mut dyn Backend,
    progress: &mut dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    let frame = &scene.frame;
    let start = Instant::now();
    let tiles = tiles(frame.width, frame.height);
    let passes = sample_passes(frame.spp, TILE * TILE);
    let total = (tiles.len() * passes.len()) as u64;
    let mut done = 0;
    let mut output = RenderOutput {
        image: Image {
            width: frame.width,
            height: frame.height,
            pixels: Vec::new(),
        },
        samples_per_pixel: 0,
        max_samples_per_pixel: 0,
        pixels_without_samples: 0,
        elapsed: Duration::ZERO,
        rays: 0,
        truncated_paths: 0,
        status_flags: 0,
        stopped: None,
    };
    'passes: for &(sample_start, sample_count) in &passes {
        for &(tile_x, tile_y, tile_width, tile_height) in &tiles {
            if cancel.load(Ordering::Relaxed) {
                output.stopped = Some(Error::Interrupted {
                    done: output.samples_per_pixel,
                    total: frame.spp,
                });
                break 'passes;
            }
            let pass = GpuPass {
                tile_x,
                tile_y,
                tile_width,
                tile_height,
                sample_start,
                sample_count,
                ..Default::default()
            };
            match backend.render_tile(pass) {
                Ok(status) => {
                    output.rays += status.rays;
                    output.truncated_paths += status.truncated;
                    output.status_flags |= status.flags;
                }
                Err(e) => {
                    output.stopped = Some(e);
                    break 'passes;
                }
            }
            done += 1;
            progress.advance(done, total);
        }
        output.samples_per_pixel += sample_count;
    }
    let accumulation = backend.accumulation()?;
    output.image = Image::from_accumulation(frame.width, frame.height, &accumulation);
    if output.stopped.is_some() {
        // Pixels of an unfinished pass carry more samples than the rest; the image stays a
        // per-pixel mean, so it is still correct, only less converged in places.
        let counts = || accumulation.iter().map(|a| a[3] as u32);
        output.samples_per_pixel = counts().min().unwrap_or(0);
        output.max_samples_per_pixel = counts().max().unwrap_or(0);
        output.pixels_without_samples = counts().filter(|&n| n == 0).count();
    } else {
        output.max_samples_per_pixel = output.samples_per_pixel;
    }
    output.elapsed = start.elapsed();
    Ok(output)
}

/// A one-line explanation of kernel status flags.
pub fn describe_status_flags(flags: u32) -> Option<String> {
    let mut reasons = Vec::new();
    if flags & STATUS_TRAVERSAL_CAP != 0 {
        reasons.push("a BVH traversal hit its iteration cap (corrupt or cyclic BVH)");
    }
    if flags & STATUS_STACK_OVERFLOW != 0 {
        reasons.push("a BVH traversal overflowed its stack");
    }
    if flags & STATUS_PERMUTE_CAP != 0 {
        reasons.push(
            "the stratified sampler's permutation hit its walk cap (use --pixel-sampler/--lens-sampler sobol)",
        );
    }
    (!reasons.is_empty()).then(|| reasons.join("; "))
}
