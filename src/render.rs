//! The render driver: splits a render into passes of samples and tiles of pixels, runs them on
//! a [`Backend`] (GPU or CPU), reports progress, and returns an [`Image`].
//!
//! Each pass adds the same number of samples to every pixel, so the accumulation is a valid
//! image at every pass boundary: an interrupted or failing render keeps what it computed.
//!
//! Passes are sized by the rays they may trace, not by samples alone: one invocation traces at
//! most [`RAYS_PER_INVOCATION`] rays per dispatch, so a sample whose area lights ask for more
//! shadow rays is split into windows of light samples (`GpuPass`), each its own dispatch.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::accel::FlatScene;
use crate::error::{Error, Result};
use crate::layout::{
    GpuPass, LIGHT_AREA, LOOP_CHECK_ITERATIONS, STATUS_FLAGS, STATUS_LOOP_LIMIT,
    STATUS_PERMUTE_CAP, STATUS_RAYS, STATUS_STACK_OVERFLOW, STATUS_TRAVERSAL_CAP, STATUS_TRUNCATED,
};

/// Tile edge in pixels: one dispatch covers at most TILE x TILE pixels.
pub const TILE: u32 = 128;
/// Rays one invocation may trace in one dispatch. lavapipe ends every loop of an invocation
/// once 65535 loop iterations have run in total, and one ray costs tens of traversal
/// iterations (`layout::STATUS_LOOP_LIMIT` reports a dispatch that still exceeds it).
pub const RAYS_PER_INVOCATION: u64 = 64;
/// Rays one dispatch may trace: well under a second on lavapipe, far below any GPU watchdog.
pub const RAYS_PER_DISPATCH: u64 = 1 << 22;

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

/// How a render is cut into dispatches: passes of samples, each over every tile, and within a
/// pass the windows of light samples each dispatch covers in turn.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderPlan {
    /// `(sample_start, sample_count)` of each pass.
    pub passes: Vec<(u32, u32)>,
    /// `(light_sample_start, light_sample_count)` of each dispatch of a pass; the last commits.
    pub light_windows: Vec<(u32, u32)>,
}

/// An upper bound on the rays one camera sample traces: at every path vertex (one per bounce
/// when a material reflects) the incoming ray, a shadow ray per point or directional light, and
/// one per area-light sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayBound {
    pub vertices: u64,
    pub punctual_per_vertex: u64,
    pub light_samples_per_vertex: u64,
}

impl RayBound {
    pub fn of(scene: &FlatScene) -> RayBound {
        let reflects = scene
            .materials
            .iter()
            .any(|m| m.mirror.iter().any(|&c| c > 0.0));
        RayBound {
            vertices: if reflects {
                scene.frame.max_depth as u64 + 1
            } else {
                1
            },
            punctual_per_vertex: scene.lights.iter().filter(|l| l.kind != LIGHT_AREA).count()
                as u64,
            light_samples_per_vertex: scene.frame.light_samples_per_vertex as u64,
        }
    }

    pub fn per_sample(&self) -> u64 {
        self.vertices * (1 + self.punctual_per_vertex + self.light_samples_per_vertex)
    }
}

/// The passes of a render over tiles of `tile_pixels` pixels: as many samples per dispatch as
/// the ray budgets allow, or one sample split into light windows when a sample alone is over
/// the per-invocation budget.
pub fn plan_passes(scene: &FlatScene, tile_pixels: u32) -> RenderPlan {
    let spp = scene.frame.spp;
    let bound = RayBound::of(scene);
    let rays = bound.per_sample();
    let by_invocation = RAYS_PER_INVOCATION / rays;
    let by_dispatch = RAYS_PER_DISPATCH / (tile_pixels.max(1) as u64 * rays);
    let per_pass = by_invocation.min(by_dispatch).clamp(1, spp as u64) as u32;
    RenderPlan {
        passes: (0..spp.div_ceil(per_pass))
            .map(|i| (i * per_pass, per_pass.min(spp - i * per_pass)))
            .collect(),
        light_windows: light_windows(scene, bound),
    }
}

/// One window with every light sample when a sample fits the per-invocation budget; else
/// windows of equal width, sized so that one window's rays fit it (at least one sample wide:
/// a scene whose path vertices alone exceed the budget is left to the loop-limit check).
fn light_windows(scene: &FlatScene, bound: RayBound) -> Vec<(u32, u32)> {
    let area_lights = scene.lights.iter().filter(|l| l.kind == LIGHT_AREA);
    let most = area_lights.clone().map(|l| l.samples).max().unwrap_or(0);
    if bound.per_sample() <= RAYS_PER_INVOCATION || most <= 1 {
        return vec![(0, u32::MAX)];
    }
    let per_vertex = RAYS_PER_INVOCATION / bound.vertices;
    let for_light_samples = per_vertex.saturating_sub(1 + bound.punctual_per_vertex);
    let width = (for_light_samples / area_lights.count() as u64).clamp(1, most as u64) as u32;
    (0..most.div_ceil(width))
        .map(|i| (i * width, width))
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
    let plan = plan_passes(scene, TILE * TILE);
    let windows = &plan.light_windows;
    let total = (plan.passes.len() * tiles.len() * windows.len()) as u64;
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
    'passes: for &(sample_start, sample_count) in &plan.passes {
        for &(tile_x, tile_y, tile_width, tile_height) in &tiles {
            for (i, &(light_sample_start, light_sample_count)) in windows.iter().enumerate() {
                if cancel.load(Ordering::Relaxed) {
                    output.stopped = Some(Error::Interrupted {
                        done: output.samples_per_pixel,
                        total: frame.spp,
                    });
                    break 'passes;
                }
                let dispatch = GpuPass {
                    tile_x,
                    tile_y,
                    tile_width,
                    tile_height,
                    sample_start,
                    sample_count,
                    light_sample_start,
                    light_sample_count,
                    commit: (i + 1 == windows.len()) as u32,
                    loop_check: LOOP_CHECK_ITERATIONS,
                    ..Default::default()
                };
                match backend.render_tile(dispatch) {
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
    if flags & STATUS_LOOP_LIMIT != 0 {
        reasons.push(
            "the GPU driver cut the kernel's loops short (lavapipe stops an invocation after \
             65535 loop iterations): this scene traces too many rays per sample for it; use \
             --backend cpu",
        );
    }
    if flags & STATUS_PERMUTE_CAP != 0 {
        reasons.push(
            "the stratified sampler's permutation hit its walk cap (use --pixel-sampler/--lens-sampler sobol)",
        );
    }
    (!reasons.is_empty()).then(|| reasons.join("; "))
}
