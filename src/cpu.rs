//! The CPU reference path: the same stages as the GPU kernel, in Rust, on all cores.
//! Twin: `wgsl/render.wgsl` (the per-pixel sample loop, the scratch sum of a pass split into
//! light windows, and the accumulation).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::error::Result;
use crate::integrator::{FirstHit, LightWindow, SampleStats, trace_pixel};
use crate::layout::{FEATURES_ALL, GpuPass};
use crate::pack::FlatScene;
use crate::render::{AccumulationLayout, Backend, DispatchStatus, RayBudgets};

/// The CPU path's [`Backend`]: runs each batch's dispatches on all cores as it is submitted,
/// with the same integrator, sample patterns and accumulation layout as the GPU kernel.
pub struct CpuRenderer<'a> {
    scene: &'a FlatScene,
    /// Laid out as the GPU's (`render::AccumulationLayout`): the image's sums, then the AOV
    /// layers when asked for, then the scratch sums of a pass split into light windows, which
    /// grow the buffer on first use.
    accumulation: Vec<[f32; 4]>,
    /// The pixels a listed dispatch samples (`Backend::set_pixel_list`).
    pixel_list: Vec<u32>,
    cancel: Option<&'a AtomicBool>,
    /// Status of each batch run and not yet collected by `finish`.
    finished: VecDeque<DispatchStatus>,
    /// The integrator instance for the scene's features (`layout::FEATURE_*`).
    trace: TracePixel,
    features: u32,
    budgets: RayBudgets,
}

/// `integrator::trace_pixel` for one feature set.
type TracePixel = fn(
    &FlatScene,
    u32,
    u32,
    std::ops::Range<u32>,
    LightWindow,
    &mut SampleStats,
    &mut dyn FnMut(Vec3, &FirstHit),
);

macro_rules! instances {
    ($($features:literal)*) => {
        [$(trace_pixel::<$features> as TracePixel),*]
    };
}

/// `trace_pixel` compiled for each of the 256 feature sets, indexed by the set.
const TRACE_PIXEL: [TracePixel; 256] = instances!(
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33
    34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63 64
    65 66 67 68 69 70 71 72 73 74 75 76 77 78 79 80 81 82 83 84 85 86 87 88 89 90 91 92 93 94 95
    96 97 98 99 100 101 102 103 104 105 106 107 108 109 110 111 112 113 114 115 116 117 118 119
    120 121 122 123 124 125 126 127 128 129 130 131 132 133 134 135 136 137 138 139 140 141 142 143
    144 145 146 147 148 149 150 151 152 153 154 155 156 157 158 159 160 161 162 163 164 165 166 167
    168 169 170 171 172 173 174 175 176 177 178 179 180 181 182 183 184 185 186 187 188 189 190 191
    192 193 194 195 196 197 198 199 200 201 202 203 204 205 206 207 208 209 210 211 212 213 214 215
    216 217 218 219 220 221 222 223 224 225 226 227 228 229 230 231 232 233 234 235 236 237 238 239
    240 241 242 243 244 245 246 247 248 249 250 251 252 253 254 255
);
const _: () = assert!(TRACE_PIXEL.len() == FEATURES_ALL as usize + 1);

/// What one dispatch adds to one pixel: radiance, and the AOVs' (normal, depth) and albedo.
#[derive(Clone, Copy, Debug, Default)]
struct PixelSums {
    pixel: u32,
    radiance: Vec3,
    normal_depth: glam::Vec4,
    albedo: Vec3,
}

/// Pixels of a row one work item renders: small enough to balance a band of few wide rows over
/// the threads, large enough to amortise the scheduling.
const SEGMENT: u32 = 64;

impl<'a> CpuRenderer<'a> {
    /// A renderer of `scene` with the integrator for its features, [`RayBudgets::DEFAULT`] and
    /// no cancel flag.
    pub fn new(scene: &'a FlatScene) -> Self {
        let layout = AccumulationLayout::of(scene, false);
        // The wide BVH, made now rather than by the first sample traced.
        scene.tracer();
        CpuRenderer {
            scene,
            accumulation: vec![[0.0; 4]; layout.len()],
            pixel_list: Vec::new(),
            cancel: None,
            finished: VecDeque::new(),
            trace: TRACE_PIXEL[scene.features() as usize],
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
        self.trace = TRACE_PIXEL[(features & FEATURES_ALL) as usize];
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

    /// The layout of the image's sums (the scratch part is the passes' business).
    fn layout(&self) -> AccumulationLayout {
        AccumulationLayout::of(self.scene, false)
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// The pixel at `column` of row `row` of a dispatch's band: the image's, or the listed one
    /// (none past the list's end). Twin of `pass_pixel` in render.wgsl.
    fn pass_pixel(&self, pass: &GpuPass, row: u32, column: u32) -> Option<u32> {
        if pass.listed_pixels == 0 {
            let width = self.scene.frame.width;
            return Some((pass.tile_y + row) * width + pass.tile_x + column);
        }
        let entry = (pass.tile_y + row) * pass.tile_width + column;
        (entry < pass.listed_pixels).then(|| self.pixel_list[entry as usize])
    }

    /// Runs one dispatch: every sample of `pass` for its pixels, in parallel over row segments.
    pub fn run_dispatch(&mut self, pass: &GpuPass) -> DispatchStatus {
        let scene = self.scene;
        let window = LightWindow::of_pass(pass);
        let segments: Vec<(u32, u32, u32)> = (0..pass.tile_height)
            .flat_map(|row| {
                (0..pass.tile_width)
                    .step_by(SEGMENT as usize)
                    .map(move |c| (row, c, (c + SEGMENT).min(pass.tile_width)))
            })
            .collect();
        let rendered: Vec<(Vec<PixelSums>, SampleStats)> = segments
            .into_par_iter()
            .filter(|_| !self.cancelled())
            .map(|(row, c0, c1)| {
                let mut stats = SampleStats::default();
                let sums = (c0..c1)
                    .map_while(|column| self.pass_pixel(pass, row, column))
                    .map(|pixel| {
                        let (x, y) = (pixel % scene.frame.width, pixel / scene.frame.width);
                        let mut sums = PixelSums {
                            pixel,
                            ..Default::default()
                        };
                        let samples = pass.sample_start..pass.sample_start + pass.sample_count;
                        (self.trace)(scene, x, y, samples, window, &mut stats, &mut |r, hit| {
                            sums.radiance += r;
                            sums.normal_depth += hit.normal.extend(hit.depth);
                            sums.albedo += hit.albedo;
                        });
                        sums
                    })
                    .collect();
                (sums, stats)
            })
            .collect();
        let pixels = (scene.frame.width * scene.frame.height) as usize;
        let split = pass.commit == 0 || !window.is_first();
        let last = if split { pass.scratch_offset } else { 0 };
        let aovs = pass.aov_offset
            + if pass.aov_offset != 0 {
                pixels as u32
            } else {
                0
            };
        let needed = last.max(aovs) as usize + pixels;
        if self.accumulation.len() < needed {
            self.accumulation.resize(needed, [0.0; 4]);
        }
        let mut status = DispatchStatus::default();
        let add = |slot: &mut [f32; 4], value: [f32; 4]| {
            for c in 0..4 {
                slot[c] += value[c];
            }
        };
        for (sums, stats) in rendered {
            for PixelSums {
                pixel,
                mut radiance,
                normal_depth,
                albedo,
            } in sums
            {
                let scratch = (pass.scratch_offset + pixel) as usize;
                if !window.is_first() {
                    radiance += Vec3::from_slice(&self.accumulation[scratch][..3]);
                }
                if pass.commit != 0 {
                    let slot = pixel as usize;
                    let samples = pass.sample_count as f32;
                    add(
                        &mut self.accumulation[slot],
                        radiance.extend(samples).into(),
                    );
                    // Every light window retraces the same camera paths: the committing one
                    // adds the AOVs.
                    if pass.aov_offset != 0 {
                        let slot = (pass.aov_offset + pixel) as usize;
                        add(&mut self.accumulation[slot], normal_depth.into());
                        let slot = slot + pixels;
                        add(&mut self.accumulation[slot], albedo.extend(0.0).into());
                    }
                } else {
                    self.accumulation[scratch] = radiance.extend(0.0).into();
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
        Ok(self
            .layout()
            .image_sums(std::mem::take(&mut self.accumulation)))
    }

    fn snapshot(&mut self) -> Result<Vec<[f32; 4]>> {
        let layout = self.layout();
        Ok(layout.image_sums(self.accumulation[..layout.image_len()].to_vec()))
    }

    fn read_slots(&mut self, slots: std::ops::Range<usize>) -> Result<Vec<[f32; 4]>> {
        Ok(self.accumulation[slots].to_vec())
    }

    fn set_pixel_list(&mut self, pixels: &[u32]) -> Result<()> {
        self.pixel_list = pixels.to_vec();
        Ok(())
    }

    /// A new buffer: `accumulation` may have moved the last render's out.
    fn clear(&mut self) -> Result<()> {
        self.accumulation = vec![[0.0; 4]; self.layout().len()];
        self.pixel_list.clear();
        Ok(())
    }
}
