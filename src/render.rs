//! The render driver: cuts a render into passes of samples over the whole image, each pass into
//! dispatches over bands of rows, and the dispatches into batches; runs the batches on a
//! [`Backend`] (GPU or CPU), reports progress, and returns an [`Image`].
//!
//! Every dispatch covers whole rows of the image (the whole frame when the ray budget allows),
//! so a real GPU gets hundreds of thousands of invocations per dispatch. The host never waits
//! between dispatches: a batch is one submission, and up to [`BATCHES_IN_FLIGHT`] batches are
//! queued while the host reads the status words of older ones, asynchronously.
//!
//! Sizes come from [`RayBudgets`], not samples alone: one invocation traces a bounded number
//! of rays per dispatch (a sample whose area lights ask for more shadow rays is split into
//! windows of light samples, each its own dispatch), one dispatch a bounded number (no driver
//! watchdog trips), one batch too (a Ctrl-C waits for at most the batches in flight).
//!
//! Each dispatch adds whole samples to the pixels it covers (light windows sum in a scratch
//! buffer until the last commits), so the accumulation is a per-pixel mean after every
//! dispatch: an interrupted or failing render keeps what it computed.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::adaptive::{ActivePixels, AdaptiveReport, AdaptiveSettings};
use crate::error::{Error, Result};
use crate::layout::{
    GpuPass, INTEGRATOR_PATH, LOOP_CHECK_ITERATIONS, STATUS_FLAGS, STATUS_LOOP_LIMIT,
    STATUS_PERMUTE_CAP, STATUS_RAYS, STATUS_STACK_OVERFLOW, STATUS_TRAVERSAL_CAP, STATUS_TRUNCATED,
    STATUS_WAVE_OVERFLOW,
};
use crate::pack::FlatScene;

/// Upper bounds on the rays traced by one invocation, one dispatch and one batch, and the
/// invocations a dispatch should have.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayBudgets {
    /// Rays per invocation and dispatch, at most. Fewer when the BVH makes rays expensive:
    /// lavapipe ends every loop of an invocation once 65535 loop iterations have run in total
    /// (`layout::STATUS_LOOP_LIMIT` reports a dispatch that still exceeds it).
    pub per_invocation: u64,
    /// Loop iterations one invocation may expect to run: a quarter of lavapipe's 65535, since
    /// the 8 lanes of a SIMD group loop as long as the slowest and the estimate is an average
    /// (`FlatScene::traversal_iterations`).
    pub loop_iterations_per_invocation: f64,
    /// Well under a second on lavapipe, far below any GPU watchdog.
    pub per_dispatch: u64,
    /// One submission: a few seconds on lavapipe, milliseconds on a real GPU, where the
    /// batches in flight keep it busy; a Ctrl-C waits for at most the batches in flight.
    pub per_batch: u64,
    /// Invocations (pixels of a band) a dispatch should have where the image has as many:
    /// fewer samples per invocation buy them. A real GPU needs hundreds of thousands of
    /// threads in flight; a CPU adapter runs a few and pays per invocation.
    pub min_invocations_per_dispatch: u64,
}

impl RayBudgets {
    /// The budgets of CPU-type adapters (lavapipe) and of the CPU path.
    pub const DEFAULT: RayBudgets = RayBudgets {
        per_invocation: 64,
        loop_iterations_per_invocation: 16384.0,
        per_dispatch: 1 << 22,
        per_batch: 1 << 24,
        min_invocations_per_dispatch: 0,
    };

    /// Real GPUs: a dispatch over a megapixel image has a million invocations rather than half
    /// as many with twice the samples each. On an H100, 1.3x faster on the 1024^2 dragon and
    /// the same on images too small to fill it (BENCHMARKS.md, "Dispatch shape").
    pub const REAL_GPU: RayBudgets = RayBudgets {
        min_invocations_per_dispatch: 1 << 20,
        ..RayBudgets::DEFAULT
    };

    /// The budgets for an adapter.
    pub fn for_adapter(is_cpu_adapter: bool) -> RayBudgets {
        if is_cpu_adapter {
            RayBudgets::DEFAULT
        } else {
            RayBudgets::REAL_GPU
        }
    }
}
/// Batches queued on the device at once: the next is queued while the last is read back.
pub const BATCHES_IN_FLIGHT: usize = 2;

/// What the dispatches of a batch reported.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DispatchStatus {
    /// The `layout::STATUS_*` bits raised (kernel loop caps hit), ORed together.
    pub flags: u32,
    /// Rays traced: camera, shadow and mirror rays.
    pub rays: u64,
    /// Camera samples whose path was cut off at `max_depth` while it still reflected.
    pub truncated: u64,
}

impl DispatchStatus {
    /// Reads the status buffer's words (indexed by `layout::STATUS_FLAGS`, `STATUS_RAYS`,
    /// `STATUS_TRUNCATED`).
    pub fn from_words(words: &[u32]) -> DispatchStatus {
        DispatchStatus {
            flags: words[STATUS_FLAGS as usize],
            rays: words[STATUS_RAYS as usize] as u64,
            truncated: words[STATUS_TRUNCATED as usize] as u64,
        }
    }
}

/// A device that runs dispatches into its own accumulation buffer (sum of radiance, samples).
pub trait Backend {
    /// Starts a batch of dispatches, run in order. The GPU queues them and returns at once; the
    /// CPU runs them before it returns.
    fn submit(&mut self, dispatches: &[GpuPass]) -> Result<()>;
    /// Waits for the oldest batch submitted and not yet finished; returns what it reported.
    fn finish(&mut self) -> Result<DispatchStatus>;
    /// Batches submitted and not yet finished.
    fn in_flight(&self) -> usize;
    /// The accumulation, read once at the end.
    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>>;
    /// The accumulation so far, during a render (`--progressive`): every finished sample, and
    /// the render goes on.
    fn snapshot(&mut self) -> Result<Vec<[f32; 4]>>;
    /// The accumulation's slots `slots` (`AccumulationLayout`), with every finished sample;
    /// the render goes on.
    fn read_slots(&mut self, slots: std::ops::Range<usize>) -> Result<Vec<[f32; 4]>>;
    /// The pixels (`y * width + x`) that dispatches with `listed_pixels` sample, from the next
    /// batch submitted on.
    fn set_pixel_list(&mut self, pixels: &[u32]) -> Result<()>;
    /// Empties the accumulation, so that the next render starts from zero: every render
    /// starts so, and a backend may render its scene again.
    fn clear(&mut self) -> Result<()>;
    /// Device time spent in the kernels of finished batches, where the device measures it.
    fn kernel_time(&self) -> Option<Duration> {
        None
    }
    /// The budgets renders on this backend are planned with.
    fn budgets(&self) -> RayBudgets {
        RayBudgets::DEFAULT
    }
}

/// How a backend's accumulation buffer is laid out, in pixel slots of `[f32; 4]`: the image's
/// running sums (radiance, samples); then, when AOVs are asked for, two layers of first-hit
/// sums, (normal, depth) and (albedo, 0); then, when passes are split into light windows, the
/// scratch sums of the pass in progress. Both backends use it, so the CPU path twins the
/// kernel's indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccumulationLayout {
    /// Pixels of the image (a layer's slots).
    pub pixels: usize,
    /// The AOV layers are there.
    pub aovs: bool,
    /// The scratch layer is there.
    pub scratch: bool,
}

impl AccumulationLayout {
    /// The layout for `scene`, with a scratch layer when `scratch`.
    pub fn of(scene: &FlatScene, scratch: bool) -> AccumulationLayout {
        AccumulationLayout {
            pixels: scene.frame.width as usize * scene.frame.height as usize,
            aovs: scene.aovs,
            scratch,
        }
    }

    /// Slots of the image's sums.
    pub fn image_len(&self) -> usize {
        self.pixels
    }

    /// Where the AOV layers start; 0 (the image's place) when there are none.
    pub fn aov_offset(&self) -> u32 {
        if self.aovs {
            self.image_len() as u32
        } else {
            0
        }
    }

    /// Slots of the AOV layers.
    pub fn aov_len(&self) -> usize {
        if self.aovs { 2 * self.pixels } else { 0 }
    }

    /// Slots of the whole buffer.
    pub fn len(&self) -> usize {
        self.image_len() + self.aov_len() + if self.scratch { self.pixels } else { 0 }
    }

    /// Whether the buffer has no slots (an image without pixels).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where the scratch sums start.
    pub fn scratch_offset(&self) -> u32 {
        (self.image_len() + self.aov_len()) as u32
    }

    /// The image's sums from a buffer of this layout (or its first `image_len` slots).
    pub fn image_sums(&self, mut buffer: Vec<[f32; 4]>) -> Vec<[f32; 4]> {
        buffer.truncate(self.image_len());
        buffer
    }
}

/// Linear radiance, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Linear RGB radiance, row by row: `width * height` of them.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// Mean of the accumulated samples of each pixel (a box filter), on all cores: after a
    /// Ctrl-C on a 16384^2 render this is on the way to the written image. The pixels start as
    /// a zeroed allocation, which the system maps only where it is written: a pixel without a
    /// sample (most of a huge render stopped early) costs no memory and no time.
    pub fn from_accumulation(width: u32, height: u32, accumulation: &[[f32; 4]]) -> Image {
        use rayon::prelude::*;
        let mut pixels: Vec<Vec3> = bytemuck::zeroed_vec(accumulation.len());
        pixels
            .par_iter_mut()
            .zip(accumulation)
            .filter(|(_, a)| a[3] > 0.0)
            .for_each(|(p, a)| *p = Vec3::new(a[0], a[1], a[2]) / a[3]);
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// A grey image of `counts` (samples per pixel), to see where samples went.
    pub fn of_counts(width: u32, height: u32, counts: &[u32]) -> Image {
        Image {
            width,
            height,
            pixels: counts.iter().map(|&n| Vec3::splat(n as f32)).collect(),
        }
    }

    /// Pixels with a NaN or infinite channel (on all cores: a 16384^2 image has 268M).
    pub fn non_finite_count(&self) -> usize {
        use rayon::prelude::*;
        self.pixels.par_iter().filter(|p| !p.is_finite()).count()
    }
}

/// Progress events, for a bar or log lines.
pub trait Progress {
    /// `done` of the render's `total` batches have finished (`total` is an upper bound in an
    /// adaptive render, which may end early).
    fn advance(&mut self, done: u64, total: u64);
}

impl<F: FnMut(u64, u64)> Progress for F {
    fn advance(&mut self, done: u64, total: u64) {
        self(done, total)
    }
}

/// What a render produced: the image (the crop window's pixels), its samples, and its cost.
#[derive(Debug)]
pub struct RenderOutput {
    /// Per-pixel mean of the samples taken.
    pub image: Image,
    /// Samples of the least-sampled pixel: `spp` when the render completed.
    pub samples_per_pixel: u32,
    /// Samples of the most-sampled pixel: a stopped render can end inside a pass.
    pub max_samples_per_pixel: u32,
    /// Pixels without a single sample (a render stopped before reaching them); they are 0.
    pub pixels_without_samples: usize,
    /// Wall time of the whole render, planning and read-backs included.
    pub elapsed: Duration,
    /// Wall time until the last pass finished on the device, before the image was read back
    /// (what a frame shown from the device would take).
    pub traced: Duration,
    /// Device time in the kernels (GPU timestamp queries), where the adapter offers them.
    pub kernel_time: Option<Duration>,
    /// Dispatches finished.
    pub dispatches: u64,
    /// Batches (submissions) finished.
    pub batches: u64,
    /// Rays traced: camera, shadow and mirror rays.
    pub rays: u64,
    /// Camera samples whose path was cut off at `max_depth` while it still reflected.
    pub truncated_paths: u64,
    /// Kernel loop caps hit (`layout::STATUS_*` bits); a non-zero value is reported as an error.
    pub status_flags: u32,
    /// Why the render stopped early, if it did; `image` then holds the samples taken so far.
    pub stopped: Option<Error>,
    /// The render stopped, as asked, at its deadline (`render_until`); not an error.
    pub deadline_reached: bool,
    /// Samples each pixel of `image` received, row by row.
    pub sample_counts: Vec<u32>,
    /// Images handed to `Snapshots::write` during the render.
    pub snapshots: u32,
    /// What adaptive sampling achieved, in an adaptive render.
    pub adaptive: Option<AdaptiveReport>,
    /// The AOV layers, when the scene asked for them (`FlatScene::aovs`).
    pub aovs: Option<Aovs>,
}

/// The arbitrary output variables of a render, per pixel of `image` (row by row): the means
/// over its samples of what each camera ray's first hit showed (`integrator::FirstHit`), zero
/// where no sample hit anything. A mean of depths across a silhouette is a blend, as in
/// Mitsuba's AOV integrator; the normals are averaged, not renormalised, as denoisers expect.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    /// Distance along the camera ray, scene units.
    pub depth: Vec<f32>,
    /// Shading normal in world space, facing the camera.
    pub normal: Vec<Vec3>,
    /// Diffuse plus mirror reflectance, at most 1; zero on emitters.
    pub albedo: Vec<Vec3>,
}

impl Aovs {
    /// The means from the AOV layers' sums and the image's sums (whose `w` counts samples).
    pub fn from_sums(normal_depth: &[[f32; 4]], albedo: &[[f32; 4]], image: &[[f32; 4]]) -> Aovs {
        let mean = |sum: f32, count: f32| if count > 0.0 { sum / count } else { 0.0 };
        let mut aovs = Aovs::default();
        for ((nd, a), i) in normal_depth.iter().zip(albedo).zip(image) {
            let n = i[3];
            aovs.depth.push(mean(nd[3], n));
            aovs.normal
                .push(Vec3::new(mean(nd[0], n), mean(nd[1], n), mean(nd[2], n)));
            aovs.albedo
                .push(Vec3::new(mean(a[0], n), mean(a[1], n), mean(a[2], n)));
        }
        aovs
    }
}

impl RenderOutput {
    /// Rays traced per second of wall time (`rays / elapsed`).
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// How a render is cut into dispatches: passes of samples over the whole image; within a pass,
/// bands of rows, each band once per window of light samples.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderPlan {
    /// `(sample_start, sample_count)` of each pass.
    pub passes: Vec<(u32, u32)>,
    /// `(light_sample_start, light_sample_count)` of each window; the last commits.
    pub light_windows: Vec<(u32, u32)>,
    /// `(first row, rows)` of each band.
    pub bands: Vec<(u32, u32)>,
    /// The columns every band covers: `first_column .. first_column + width`.
    pub first_column: u32,
    /// Columns of every band (the crop window's width); in a pass over a pixel list, the
    /// entries of one of its rows.
    pub width: u32,
    /// Upper bound on the rays one dispatch traces.
    pub rays_per_dispatch: u64,
    /// Dispatches per batch: as many as fit the batch budget, at least one.
    pub dispatches_per_batch: usize,
    /// Where the passes' sums go.
    pub layout: AccumulationLayout,
}

impl RenderPlan {
    /// Batches of the whole render.
    pub fn batch_count(&self) -> usize {
        let per_pass = self.bands.len() * self.light_windows.len();
        self.passes.len() * per_pass.div_ceil(self.dispatches_per_batch)
    }

    /// Camera samples one dispatch takes at most: a band's pixels (a band of a pixel list has
    /// no more) times a pass's samples (an adaptive pass takes no more).
    pub fn samples_per_dispatch(&self) -> u64 {
        let rows = self.bands.iter().map(|b| b.1).max().unwrap_or(0);
        let samples = self.passes.iter().map(|p| p.1).max().unwrap_or(0);
        self.width as u64 * rows as u64 * samples as u64
    }

    /// The dispatches of pass `pass`, in order: each band in every light window.
    pub fn dispatches(&self, pass: usize) -> Vec<GpuPass> {
        let (sample_start, sample_count) = self.passes[pass];
        self.dispatches_of(sample_start, sample_count, 0)
    }

    /// The dispatches of samples `sample_start .. sample_start + sample_count`: over the bands
    /// of the image when `listed` is 0, else over bands of rows of the pixel list (`width`
    /// entries a row) of `listed` pixels.
    pub fn dispatches_of(&self, sample_start: u32, sample_count: u32, listed: u32) -> Vec<GpuPass> {
        let list_bands;
        let (bands, first_column) = if listed == 0 {
            (&self.bands, self.first_column)
        } else {
            let rows = listed.div_ceil(self.width);
            let per_band = self.bands[0].1;
            list_bands = (0..rows.div_ceil(per_band))
                .map(|i| (i * per_band, per_band.min(rows - i * per_band)))
                .collect::<Vec<_>>();
            (&list_bands, 0)
        };
        let windows = &self.light_windows;
        let mut dispatches = Vec::with_capacity(bands.len() * windows.len());
        for &(tile_y, tile_height) in bands {
            for (i, &(light_sample_start, light_sample_count)) in windows.iter().enumerate() {
                dispatches.push(GpuPass {
                    tile_x: first_column,
                    tile_y,
                    tile_width: self.width,
                    tile_height,
                    sample_start,
                    sample_count,
                    light_sample_start,
                    light_sample_count,
                    commit: (i + 1 == windows.len()) as u32,
                    loop_check: LOOP_CHECK_ITERATIONS,
                    listed_pixels: listed,
                    scratch_offset: self.layout.scratch_offset(),
                    aov_offset: self.layout.aov_offset(),
                    ..Default::default()
                });
            }
        }
        dispatches
    }
}

/// An upper bound on the rays one camera sample traces: at every path vertex (one per bounce
/// when a material reflects) the incoming ray, a shadow ray per point or directional light, and
/// one per area-light sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayBound {
    /// Path vertices a sample may reach: `max_depth + 1` when a material reflects, else 1;
    /// under the path tracer, `max_depth + 2` (its last vertex only sees emission).
    pub vertices: u64,
    /// Shadow rays to point and directional lights at each vertex: one per such light.
    pub punctual_per_vertex: u64,
    /// Shadow rays to area lights at each vertex: the sum of their `samples`.
    pub light_samples_per_vertex: u64,
}

impl RayBound {
    /// The bound for `scene`'s materials, lights and `max_depth`.
    pub fn of(scene: &FlatScene) -> RayBound {
        let reflects = scene
            .materials
            .iter()
            .any(|m| m.mirror.iter().any(|&c| c > 0.0));
        let max_depth = scene.frame.max_depth as u64;
        let vertices = match scene.frame.integrator {
            INTEGRATOR_PATH => max_depth + 2,
            _ if reflects => max_depth + 1,
            _ => 1,
        };
        RayBound {
            vertices,
            punctual_per_vertex: scene.lights.iter().filter(|l| !l.is_sampled()).count() as u64,
            light_samples_per_vertex: scene.frame.light_samples_per_vertex as u64,
        }
    }

    /// Rays one camera sample traces at most.
    pub fn per_sample(&self) -> u64 {
        self.vertices * (1 + self.punctual_per_vertex + self.light_samples_per_vertex)
    }
}

/// The plan of a render: as many samples per pass as one invocation may trace, then bands of
/// as many rows as one dispatch may trace.
pub fn plan_passes(scene: &FlatScene, budgets: &RayBudgets) -> RenderPlan {
    let frame = &scene.frame;
    let spp = frame.spp;
    let bound = RayBound::of(scene);
    // The loop itself, the light loop's iteration, and the expected traversal.
    let iterations_per_ray = 2.0 + scene.traversal_iterations as f64;
    let [x0, x1, y0, y1] = scene.crop;
    let (width, height) = (x1 - x0, y1 - y0);
    let pixels = width as u64 * height as u64;
    // Enough invocations per dispatch: no more rays each than the dispatch budget shared by
    // `min_invocations_per_dispatch` of them (or by every pixel of a smaller image).
    let invocations = budgets.min_invocations_per_dispatch.min(pixels).max(1);
    let rays_per_invocation = ((budgets.loop_iterations_per_invocation / iterations_per_ray)
        as u64)
        .min(budgets.per_dispatch / invocations)
        .clamp(1, budgets.per_invocation);
    let per_pass = (rays_per_invocation / bound.per_sample()).clamp(1, spp as u64) as u32;
    let light_windows = light_windows(scene, bound, rays_per_invocation);
    let window_width = light_windows[0].1.min(frame.light_samples_per_vertex) as u64;
    let area_lights = sampled_lights_per_vertex(scene);
    let rays_per_sample_and_window = if light_windows.len() > 1 {
        bound.vertices * (1 + bound.punctual_per_vertex + window_width * area_lights)
    } else {
        bound.per_sample()
    };
    let rays_per_row = width as u64 * per_pass as u64 * rays_per_sample_and_window;
    let rows = (budgets.per_dispatch / rays_per_row).clamp(1, height as u64) as u32;
    let rays_per_dispatch = rows as u64 * rays_per_row;
    RenderPlan {
        passes: (0..spp.div_ceil(per_pass))
            .map(|i| (i * per_pass, per_pass.min(spp - i * per_pass)))
            .collect(),
        bands: (0..height.div_ceil(rows))
            .map(|i| (y0 + i * rows, rows.min(height - i * rows)))
            .collect(),
        first_column: x0,
        width,
        rays_per_dispatch,
        dispatches_per_batch: (budgets.per_batch / rays_per_dispatch).max(1) as usize,
        layout: AccumulationLayout::of(scene, light_windows.len() > 1),
        light_windows,
    }
}

/// The sampled lights a vertex draws samples of: every sky light and, under Whitted's
/// integrator, every area light; under the path tracer, the one area light it chooses.
fn sampled_lights_per_vertex(scene: &FlatScene) -> u64 {
    let frame = &scene.frame;
    let every_vertex = scene.lights[..frame.light_choice_start as usize]
        .iter()
        .filter(|l| l.is_sampled())
        .count();
    (every_vertex + frame.chooses_lights() as usize) as u64
}

/// One window with every light sample when a sample fits the per-invocation budget; else
/// windows of equal width, sized so that one window's rays fit it (at least one sample wide:
/// a scene whose path vertices alone exceed the budget is left to the loop-limit check).
fn light_windows(scene: &FlatScene, bound: RayBound, per_invocation: u64) -> Vec<(u32, u32)> {
    let sampled = scene.lights.iter().filter(|l| l.is_sampled());
    let most = sampled.map(|l| l.samples).max().unwrap_or(0);
    if bound.per_sample() <= per_invocation || most <= 1 {
        return vec![(0, u32::MAX)];
    }
    let per_vertex = per_invocation / bound.vertices;
    let for_light_samples = per_vertex.saturating_sub(1 + bound.punctual_per_vertex);
    let width = (for_light_samples / sampled_lights_per_vertex(scene)).clamp(1, most as u64) as u32;
    (0..most.div_ceil(width))
        .map(|i| (i * width, width))
        .collect()
}

/// Renders `scene` on `backend` with the backend's budgets. `cancel` is polled before each
/// batch; the batches already queued finish (at most [`BATCHES_IN_FLIGHT`]).
pub fn render(
    scene: &FlatScene,
    backend: &mut dyn Backend,
    progress: &mut dyn Progress,
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    drive(scene, backend, progress, cancel, None, None)
}

/// Images written during a render: `write` receives the image of every finished sample each
/// time `every` has passed since the last (after the batch that crosses it).
pub struct Snapshots<'a> {
    /// Wall time between two snapshots, at least.
    pub every: Duration,
    /// Receives each snapshot (the crop window's pixels); an error stops the render.
    pub write: &'a mut dyn FnMut(&Image) -> Result<()>,
}

/// [`render`] (stopping, successfully, at `deadline` when given) that hands an image to
/// `snapshots` as it goes; `RenderOutput::snapshots` counts them. A failing write stops the
/// render with its error, keeping the samples.
pub fn render_with_snapshots(
    scene: &FlatScene,
    backend: &mut dyn Backend,
    progress: &mut dyn Progress,
    cancel: &AtomicBool,
    deadline: Option<Instant>,
    snapshots: Snapshots<'_>,
) -> Result<RenderOutput> {
    drive(scene, backend, progress, cancel, deadline, Some(snapshots))
}

/// [`render`] that stops, successfully, once `deadline` has passed: no batch is queued after
/// it, the batches in flight finish, and the image holds every finished sample
/// (`RenderOutput::deadline_reached`).
pub fn render_until(
    scene: &FlatScene,
    backend: &mut dyn Backend,
    progress: &mut dyn Progress,
    cancel: &AtomicBool,
    deadline: Instant,
) -> Result<RenderOutput> {
    drive(scene, backend, progress, cancel, Some(deadline), None)
}

fn drive(
    scene: &FlatScene,
    backend: &mut dyn Backend,
    progress: &mut dyn Progress,
    cancel: &AtomicBool,
    deadline: Option<Instant>,
    snapshots: Option<Snapshots<'_>>,
) -> Result<RenderOutput> {
    let frame = &scene.frame;
    let plan = plan_passes(scene, &backend.budgets());
    backend.clear()?;
    let mut run = Run {
        scene,
        progress,
        cancel,
        deadline,
        snapshots,
        start: Instant::now(),
        last_snapshot: Instant::now(),
        dispatches_per_batch: plan.dispatches_per_batch,
        total: plan.batch_count() as u64,
        finished: 0,
        completions: VecDeque::new(),
        output: RenderOutput {
            image: Image {
                width: frame.width,
                height: frame.height,
                pixels: Vec::new(),
            },
            samples_per_pixel: 0,
            max_samples_per_pixel: 0,
            pixels_without_samples: 0,
            elapsed: Duration::ZERO,
            traced: Duration::ZERO,
            kernel_time: None,
            dispatches: 0,
            batches: 0,
            rays: 0,
            truncated_paths: 0,
            status_flags: 0,
            stopped: None,
            deadline_reached: false,
            sample_counts: Vec::new(),
            snapshots: 0,
            adaptive: None,
            aovs: None,
        },
    };
    let adaptive = match scene.adaptive {
        None => {
            // Passes are made one by one as they are submitted: a 2^20-spp render has millions.
            for pass in 0..plan.passes.len() {
                if !run.submit_pass(backend, &plan.dispatches(pass), plan.passes[pass].1) {
                    break;
                }
            }
            None
        }
        Some(settings) => Some(sample_adaptively(&mut run, backend, &plan, &settings)),
    };
    run.drain(backend);
    let traced = run.start.elapsed();
    let mut output = run.output;
    output.traced = traced;
    let [x0, x1, y0, y1] = scene.crop;
    let layout = &plan.layout;
    let crop = |layer: Vec<[f32; 4]>| crop_rows(layer, frame.width, scene.crop);
    // What needs the layers beyond the image's sums reads them before `accumulation`, which
    // may move the buffer out (the CPU path's does).
    let aov_sums = match scene.aovs {
        true => {
            let offset = layout.aov_offset() as usize;
            Some(backend.read_slots(offset..offset + layout.aov_len())?)
        }
        false => None,
    };
    let sums = backend.accumulation()?;
    let errors = adaptive.as_ref().map(|(_, split)| {
        let estimates =
            crate::adaptive::squared_error_estimates(&sums, split, frame.width, scene.crop);
        crop_rows(estimates, frame.width, scene.crop)
    });
    // The crop window's pixels alone (the whole image unless `render.crop` narrows it).
    let accumulation = crop(sums);
    output.image = Image::from_accumulation(x1 - x0, y1 - y0, &accumulation);
    output.sample_counts = sample_counts(&accumulation);
    if let Some(sums) = aov_sums {
        let (normal_depth, albedo) = sums.split_at(layout.pixels);
        let (normal_depth, albedo) = (crop(normal_depth.to_vec()), crop(albedo.to_vec()));
        output.aovs = Some(Aovs::from_sums(&normal_depth, &albedo, &accumulation));
    }
    if let (Some(settings), Some(errors), Some((decisions, _))) =
        (&scene.adaptive, errors, adaptive)
    {
        let counts = &output.sample_counts;
        let mut report = AdaptiveReport::new(settings, &errors, counts, scene.frame.spp, decisions);
        report.stopped_early = output.stopped.is_some() || output.deadline_reached;
        output.adaptive = Some(report);
    }
    let stopped = output.stopped.is_some() || output.deadline_reached;
    if stopped || scene.adaptive.is_some() {
        // Pixels of an unfinished pass, or that adaptive sampling kept going, carry more
        // samples than the rest; the image stays a per-pixel mean, so it is still correct.
        use rayon::prelude::*;
        let counts = || output.sample_counts.par_iter().copied();
        output.samples_per_pixel = counts().min().unwrap_or(0);
        output.max_samples_per_pixel = counts().max().unwrap_or(0);
        output.pixels_without_samples = counts().filter(|&n| n == 0).count();
        // The passes in flight when the signal came finished after it: the image holds theirs.
        if let Some(Error::Interrupted { done, .. }) = &mut output.stopped {
            *done = output.samples_per_pixel;
        }
    } else {
        output.max_samples_per_pixel = output.samples_per_pixel;
    }
    output.kernel_time = backend.kernel_time();
    output.elapsed = run.start.elapsed();
    Ok(output)
}

/// Adaptive sampling (`adaptive.rs`): the samples run in segments between splits at powers of
/// two, `[0, m/2)`, `[m/2, m)`, `[m, 2m)`, … (`m` the first decision,
/// `AdaptiveSettings::first_decision`), each in passes of at most the plan's samples. At each
/// split the finished passes are read back and kept as the next halves' first; from `m` on,
/// each split is a decision, and the next segment runs in steps (`adaptive::step_after`, a
/// quarter) over a list of the pixels whose goal is beyond the step's start. The segments, quarters and decisions depend on
/// sample counts alone, not on a backend's budgets, so the GPU and the CPU path decide alike.
/// Returns the decisions made and every pixel's sums at its last split (the first of the halves
/// its error estimate compares).
fn sample_adaptively(
    run: &mut Run<'_, '_>,
    backend: &mut dyn Backend,
    plan: &RenderPlan,
    settings: &AdaptiveSettings,
) -> (u32, Vec<[f32; 4]>) {
    let scene = run.scene;
    let frame = &scene.frame;
    let spp = frame.spp;
    let first = settings.first_decision();
    let per_pass = plan.passes[0].1;
    let batches_per_pass = plan.batch_count() as u64 / plan.passes.len() as u64;
    // The uniform render's batches in quarters of segments: an upper bound on an adaptive one's.
    run.total = spp.div_ceil(per_pass.min((first / 8).max(1))) as u64 * batches_per_pass;
    let mut active = ActivePixels::new(frame.width, frame.height, scene.crop, spp.min(first));
    let mut split = vec![[0.0f32; 4]; plan.layout.image_len()];
    let (mut start, mut end, mut listed, mut decisions) = (0, (first / 2).max(1), 0, 0);
    'segments: while start < spp {
        let end_here = end.min(spp);
        // Before the first decision every pixel takes the whole segment; after, the list
        // shrinks by quarters as pixels reach their goals.
        let quarter = if decisions == 0 {
            end_here - start
        } else {
            crate::adaptive::step_after(start)
        };
        for from in (start..end_here).step_by(quarter as usize) {
            if decisions > 0 {
                let list = active.list_beyond(from);
                if list.is_empty() {
                    break 'segments;
                }
                if list.len() as u32 != listed {
                    if let Err(e) = backend.set_pixel_list(&list) {
                        run.output.stopped = Some(e);
                        break 'segments;
                    }
                    listed = list.len() as u32;
                }
            }
            let count = quarter.min(end_here - from);
            for pass in (from..from + count).step_by(per_pass as usize) {
                let samples = per_pass.min(from + count - pass);
                let dispatches = plan.dispatches_of(pass, samples, listed);
                if !run.submit_pass(backend, &dispatches, samples) {
                    break 'segments;
                }
            }
        }
        start = end_here;
        if start >= spp {
            break;
        }
        run.drain(backend);
        if run.output.stopped.is_some() {
            break;
        }
        let sums = match backend.read_slots(0..plan.layout.image_len()) {
            Ok(sums) => sums,
            Err(e) => {
                run.output.stopped = Some(e);
                break;
            }
        };
        if start >= first {
            let estimates =
                crate::adaptive::squared_error_estimates(&sums, &split, frame.width, scene.crop);
            decisions += 1;
            if active.decide(&estimates, settings.noise_target, start, spp) == 0 {
                break;
            }
        }
        // The pixels that go on compare their next segment with everything before it.
        for pixel in active.list_beyond(start) {
            split[pixel as usize] = sums[pixel as usize];
        }
        end = 2 * start;
    }
    if run.output.stopped.is_none() && !run.output.deadline_reached {
        run.finished = run.total;
        run.progress.advance(run.total, run.total);
    }
    (decisions, split)
}

/// A render in progress: what the batches in flight will complete, and the output so far.
struct Run<'p, 's> {
    scene: &'p FlatScene,
    progress: &'p mut dyn Progress,
    cancel: &'p AtomicBool,
    deadline: Option<Instant>,
    snapshots: Option<Snapshots<'s>>,
    start: Instant,
    last_snapshot: Instant,
    dispatches_per_batch: usize,
    /// Batches of the whole render (an upper bound for an adaptive one), for the progress.
    total: u64,
    finished: u64,
    /// The samples each batch in flight completes, and its dispatches, oldest first.
    completions: VecDeque<(u32, u64)>,
    output: RenderOutput,
}

impl Run<'_, '_> {
    /// Submits the dispatches of a pass of `samples` samples in batches; false once the
    /// render stops (an error, a cancel, the deadline), which `output` then says.
    fn submit_pass(
        &mut self,
        backend: &mut dyn Backend,
        dispatches: &[GpuPass],
        samples: u32,
    ) -> bool {
        let per_batch = self.dispatches_per_batch;
        let count = dispatches.len().div_ceil(per_batch);
        for (i, batch) in dispatches.chunks(per_batch).enumerate() {
            // The samples a batch completes: its pass's, at the pass's last batch.
            let completes = if i + 1 == count { samples } else { 0 };
            if !self.submit_batch(backend, batch, completes) {
                return false;
            }
        }
        true
    }

    fn submit_batch(
        &mut self,
        backend: &mut dyn Backend,
        batch: &[GpuPass],
        completes: u32,
    ) -> bool {
        while backend.in_flight() >= BATCHES_IN_FLIGHT {
            if !self.finish_one(backend) {
                return false;
            }
        }
        let frame = &self.scene.frame;
        if let Some(snapshots) = self.snapshots.as_mut()
            && self.last_snapshot.elapsed() >= snapshots.every
            && self.output.batches > 0
        {
            let written = backend.snapshot().and_then(|accumulation| {
                let accumulation = crop_rows(accumulation, frame.width, self.scene.crop);
                let [x0, x1, y0, y1] = self.scene.crop;
                (snapshots.write)(&Image::from_accumulation(x1 - x0, y1 - y0, &accumulation))
            });
            if let Err(e) = written {
                self.output.stopped = Some(e);
                return false;
            }
            self.output.snapshots += 1;
            self.last_snapshot = Instant::now();
        }
        if self.cancel.load(Ordering::Relaxed) {
            self.output.stopped = Some(Error::Interrupted {
                done: self.output.samples_per_pixel,
                total: frame.spp,
            });
            return false;
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            self.output.deadline_reached = true;
            return false;
        }
        if let Err(e) = backend.submit(batch) {
            self.output.stopped = Some(e);
            return false;
        }
        self.completions.push_back((completes, batch.len() as u64));
        true
    }

    /// Waits for the oldest batch in flight; false (and `output.stopped`) if it failed.
    fn finish_one(&mut self, backend: &mut dyn Backend) -> bool {
        let (completes, dispatches) = self.completions.pop_front().unwrap_or_default();
        match backend.finish() {
            Ok(status) => {
                let output = &mut self.output;
                output.rays += status.rays;
                output.truncated_paths += status.truncated;
                output.status_flags |= status.flags;
                output.samples_per_pixel += completes;
                output.dispatches += dispatches;
                output.batches += 1;
                self.finished += 1;
                self.progress.advance(self.finished, self.total);
                true
            }
            Err(e) => {
                self.output.stopped.get_or_insert(e);
                false
            }
        }
    }

    /// Waits for every batch in flight (until one fails).
    fn drain(&mut self, backend: &mut dyn Backend) {
        while backend.in_flight() > 0 {
            if !self.finish_one(backend) {
                break;
            }
        }
    }
}

/// The samples of each pixel of an accumulation, written (as [`Image::from_accumulation`]
/// writes) only where there are some.
fn sample_counts(accumulation: &[[f32; 4]]) -> Vec<u32> {
    use rayon::prelude::*;
    let mut counts = vec![0; accumulation.len()];
    counts
        .par_iter_mut()
        .zip(accumulation)
        .filter(|(_, a)| a[3] > 0.0)
        .for_each(|(n, a)| *n = a[3] as u32);
    counts
}

/// The pixels of `crop` (columns `crop[0]..crop[1]`, rows `crop[2]..crop[3]`) of an image
/// `width` pixels wide, row by row.
fn crop_rows<T: Copy>(pixels: Vec<T>, width: u32, crop: [u32; 4]) -> Vec<T> {
    let [x0, x1, y0, y1] = crop.map(|c| c as usize);
    if (x0, y0) == (0, 0) && x1 == width as usize && pixels.len() == x1 * y1 {
        return pixels;
    }
    pixels
        .chunks(width as usize)
        .skip(y0)
        .take(y1 - y0)
        .flat_map(|row| row[x0..x1].iter().copied())
        .collect()
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
    if flags & STATUS_WAVE_OVERFLOW != 0 {
        reasons.push(
            "a wavefront path vertex emitted more shadow rays than its planned slots (a planning \
             bug: render with --gpu-kernels megakernel and report it)",
        );
    }
    (!reasons.is_empty()).then(|| reasons.join("; "))
}
