//! The CPU reference path: the same stages as the GPU kernel, in Rust, on all cores.
//! Twin: `wgsl/render.wgsl` (the per-pixel sample loop, the scratch sum of a pass split into
//! light windows, and the accumulation).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::error::Result;
use crate::integrator::{LightWindow, SampleStats, trace_sample};
use crate::layout::{FEATURES_ALL, GpuPass};
use crate::pack::FlatScene;
use crate::render::{Backend, DispatchStatus, RayBudgets};

pub struct CpuRenderer<'a> {
    scene: &'a FlatScene,
    accumulation: Vec<[f32; 4]>,
    /// Sums of a pass whose light windows are not all done (allocated on first use).
    scratch: Vec<Vec3>,
    cancel: Option<&'a AtomicBool>,
    /// Status of each batch run and not yet collected by `finish`.
    finished: VecDeque<DispatchStatus>,
    /// The integrator instance for the scene's features (`layout::FEATURE_*`).
    trace: TraceSample,
    features: u32,
    budgets: RayBudgets,
}

/// `integrator::trace_sample` for one feature set.
type TraceSample = fn(&FlatScene, u32, u32, u32, LightWindow, &mut SampleStats) -> glam::Vec3;

macro_rules! instances {
    ($($features:literal)*) => {
        [$(trace_sample::<$features> as TraceSample),*]
    };
}

/// `trace_sample` compiled for each of the 64 feature sets, indexed by the set.
const TRACE_SAMPLE: [TraceSample; 64] = instances!(
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31
    32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61
    62 63
);
const _: () = assert!(TRACE_SAMPLE.len() == FEATURES_ALL as usize + 1);

/// Pixels of a row one work item renders: small enough to balance a band of few wide rows over
/// the threads, large enough to amortise the scheduling.
const SEGMENT: u32 = 64;

impl<'a> CpuRenderer<'a> {
    pub fn new(scene: &'a FlatScene) -> Self {
        let pixels = scene.frame.width as usize * scene.frame.height as usize;
        CpuRenderer {
            scene,
            accumulation: vec![[0.0; 4]; pixels],
            scratch: Vec::new(),
            cancel: None,
            finished: VecDeque::new(),
            trace: TRACE_SAMPLE[scene.features() as usize],
            features: scene.features(),
            budgets: RayBudgets::DEFAULT,
        }
    }

    /// The integrator compiled for `features` (`FEATURES_ALL`: the general one), which must
    /// include every feature of the scene.
    pub fn with_features(mut self, features: u32) -> Result<Self> {
        let missing = self.scene.features() & !features;
        if missing != 0 {
            return Err(crate::error::Error::Gpu(format!(
                "an integrator without features {missing:#x} cannot render this scene"
            )));
        }
        self.trace = TRACE_SAMPLE[(features & FEATURES_ALL) as usize];
        self.features = features;
        Ok(self)
    }

    /// Plans renders with `budgets` instead of [`RayBudgets::DEFAULT`] (tests split small
    /// renders with small ones).
    pub fn with_budgets(mut self, budgets: RayBudgets) -> Self {
        self.budgets = budgets;
        self
    }

    /// The `layout::FEATURE_*` bits the integrator was compiled for.
    pub fn features(&self) -> u32 {
        self.features
    }

    /// Row segments not yet started when `cancel` is set are skipped, so a stop takes effect
    /// within a segment, not a whole dispatch (one can take minutes with many light samples).
    /// A skipped segment adds nothing, not even to its pixels' sample counts, so every pixel
    /// stays a mean.
    pub fn with_cancel(mut self, cancel: &'a AtomicBool) -> Self {
        self.cancel = Some(cancel);
        self
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Runs one dispatch: every sample of `pass` for its rows, in parallel over row segments.
    pub fn run_dispatch(&mut self, pass: &GpuPass) -> DispatchStatus {
        let scene = self.scene;
        let width = scene.frame.width;
        let window = LightWindow::of_pass(pass);
        let segments: Vec<(u32, u32, u32)> = (pass.tile_y..pass.tile_y + pass.tile_height)
            .flat_map(|y| {
                let end = pass.tile_x + pass.tile_width;
                (pass.tile_x..end)
                    .step_by(SEGMENT as usize)
                    .map(move |x| (y, x, (x + SEGMENT).min(end)))
            })
            .collect();
        let rendered: Vec<(u32, u32, Vec<Vec3>, SampleStats)> = segments
            .into_par_iter()
            .filter(|_| !self.cancelled())
            .map(|(y, x0, x1)| {
                let mut stats = SampleStats::default();
                let sums = (x0..x1)
                    .map(|x| {
                        let mut sum = Vec3::ZERO;
                        for s in 0..pass.sample_count {
                            let sample = pass.sample_start + s;
                            sum += (self.trace)(scene, x, y, sample, window, &mut stats);
                        }
                        sum
                    })
                    .collect();
                (y, x0, sums, stats)
            })
            .collect();
        if pass.commit == 0 && self.scratch.is_empty() {
            self.scratch = vec![Vec3::ZERO; self.accumulation.len()];
        }
        let mut status = DispatchStatus::default();
        for (y, x0, sums, stats) in rendered {
            let start = (y * width + x0) as usize;
            for (i, mut sum) in sums.into_iter().enumerate() {
                let pixel = start + i;
                if !window.is_first() {
                    sum += self.scratch[pixel];
                }
                if pass.commit != 0 {
                    let acc = &mut self.accumulation[pixel];
                    let add = [sum.x, sum.y, sum.z, pass.sample_count as f32];
                    for c in 0..4 {
                        acc[c] += add[c];
                    }
                } else {
                    self.scratch[pixel] = sum;
                }
            }
            status.rays += stats.rays;
            status.truncated += stats.truncated;
            status.flags |= stats.flags;
        }
        status
    }
}

impl Backend for CpuRenderer<'_> {
    fn budgets(&self) -> RayBudgets {
        self.budgets
    }

    fn submit(&mut self, dispatches: &[GpuPass]) -> Result<()> {
        let mut status = DispatchStatus::default();
        for pass in dispatches {
            let s = self.run_dispatch(pass);
            status.rays += s.rays;
            status.truncated += s.truncated;
            status.flags |= s.flags;
        }
        self.finished.push_back(status);
        Ok(())
    }

    fn finish(&mut self) -> Result<DispatchStatus> {
        Ok(self.finished.pop_front().unwrap_or_default())
    }

    fn in_flight(&self) -> usize {
        self.finished.len()
    }

    /// Moves the accumulation out (it is read once, at the end): a copy of a 16384^2 image
    /// would cost 4 GiB and seconds after a Ctrl-C.
    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(std::mem::take(&mut self.accumulation))
    }

    fn snapshot(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(self.accumulation.clone())
    }
}
