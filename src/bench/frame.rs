//! The frame benchmark: each sample scene rendered whole on each backend, side by side; each
//! with the code specialised to the scene's features and with the general code, so the
//! specialisation's speed-up is measured in the same run.

use std::sync::atomic::AtomicBool;

use serde::Serialize;

use super::Spread;
use crate::cpu::CpuRenderer;
use crate::error::Result;
use crate::gpu::kernels::ShaderChecks;
use crate::gpu::render::{PathKernels, RendererOptions};
use crate::gpu::{GpuContext, GpuRenderer};
use crate::layout::{FEATURES_ALL, INTEGRATOR_PATH};
use crate::pack::{FlatScene, flatten};
use crate::render::{RayBudgets, RenderOutput, render};
use crate::scene::Scene;

/// The sample scenes, at their own resolution and spp.
pub const SCENES: [&str; 11] = [
    "dragon",
    "cornell_direct",
    "spheres",
    "bunny",
    "mirrors",
    "area_light",
    "thin_lens",
    "phong",
    "architecture",
    "tabletop",
    "miniature",
];

/// One way of rendering a frame, and its figures.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRun {
    /// `cpu`, `gpu-mega` (the megakernel) or `gpu-wave` (the wavefront render), code
    /// specialised to the scene's features; with `-general`, the code with every feature;
    /// `gpu-mega-rpiN` (specialised, at most N rays per invocation).
    pub backend: String,
    /// Wall-clock time of the whole render over the timed runs (ms), the image's read-back
    /// included.
    pub frame_ms: Spread,
    /// Wall-clock time until the last pass finished on the device (ms): the frame without its
    /// read-back.
    pub traced_ms: Spread,
    /// Rays traced: the same for every way but where a plan splits light samples into more
    /// windows, each retracing its paths.
    pub rays: u64,
    /// GPU kernel time from timestamp queries, where the adapter has them.
    pub kernel_ms: Option<Spread>,
    /// Millions of rays per second at the median frame time.
    pub mrays_per_s: f64,
}

/// One scene's figures.
#[derive(Clone, Debug, Serialize)]
pub struct FrameResult {
    /// The scene's name in `scenes/`.
    pub scene: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Triangles of the scene's meshes.
    pub triangles: usize,
    /// `layout::FEATURE_*` bits of the scene (the specialised kernel's).
    pub features: u32,
    /// One entry per way of rendering it.
    pub runs: Vec<FrameRun>,
    /// Where a wavefront frame's device time goes, kernel by kernel (empty when not measured).
    pub stages: Vec<StageShare>,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct FrameReport {
    /// One entry per scene.
    pub results: Vec<FrameResult>,
}

/// How one run renders: the backend and the feature set its code was built for.
#[derive(Clone, Copy)]
pub(super) enum Way {
    Cpu {
        features: u32,
    },
    Gpu {
        features: u32,
        /// Budgets other than the adapter's.
        budgets: Option<RayBudgets>,
        /// The megakernel, or the wavefront render's kernels.
        kernels: PathKernels,
        /// wgpu's run-time checks the kernels are built with.
        checks: ShaderChecks,
    },
}

/// A renderer built for a way, kept between the frames it renders (as a viewer keeps its scene
/// loaded and its kernels built; every render starts from a cleared accumulation).
pub(super) enum WayRenderer<'a> {
    Cpu(CpuRenderer<'a>),
    Gpu(Box<GpuRenderer>),
}

impl<'a> WayRenderer<'a> {
    pub(super) fn new(scene: &'a FlatScene, way: Way, gpu: Option<&GpuContext>) -> Result<Self> {
        Ok(match way {
            Way::Cpu { features } => {
                WayRenderer::Cpu(CpuRenderer::new(scene).with_features(features)?)
            }
            Way::Gpu {
                features,
                budgets,
                kernels,
                checks,
            } => {
                let context = gpu
                    .expect("a GPU way is only planned with a GPU context")
                    .clone();
                let options = RendererOptions {
                    features,
                    kernels,
                    budgets,
                    checks,
                };
                WayRenderer::Gpu(Box::new(GpuRenderer::with_options(
                    context, scene, options,
                )?))
            }
        })
    }

    /// Renders the scene once more.
    pub(super) fn render(&mut self, scene: &FlatScene) -> Result<RenderOutput> {
        let cancel = AtomicBool::new(false);
        let backend: &mut dyn crate::render::Backend = match self {
            WayRenderer::Cpu(renderer) => renderer,
            WayRenderer::Gpu(renderer) => renderer.as_mut(),
        };
        render(scene, backend, &mut |_, _| {}, &cancel)
    }
}

/// Renders `scene` once with a renderer built for `way`.
pub(super) fn render_once(
    scene: &FlatScene,
    way: Way,
    gpu: Option<&GpuContext>,
) -> Result<RenderOutput> {
    WayRenderer::new(scene, way, gpu)?.render(scene)
}

/// What `run` measures.
pub struct FrameConfig<'a> {
    /// Scenes of `scenes/`, by name.
    pub scenes: &'a [String],
    /// Overrides applied to every scene.
    pub overrides: &'a [String],
    /// Render on the CPU path too (the reference of the `vs CPU` ratios).
    pub cpu: bool,
    /// The GPU to render on, if any.
    pub gpu: Option<&'a GpuContext>,
    /// The GPU's ways of running paths to measure.
    pub kernels: &'a [PathKernels],
    /// Also the code with every feature (the specialisation's speed-up).
    pub general: bool,
    /// wgpu's run-time checks of the GPU kernels, each a way of its own (empty: chambre's).
    pub checks: &'a [ShaderChecks],
    /// The megakernel once more for each N: at most N rays per invocation.
    pub rays_per_invocation: &'a [u64],
    /// Timed runs after one warm-up.
    pub runs: u32,
}

impl FrameConfig<'_> {
    /// The ways each scene is rendered, named as the report names them.
    fn ways(&self, scene: &FlatScene) -> Vec<(String, Way)> {
        let mut ways = Vec::new();
        let feature_sets: &[(&str, u32)] = match self.general {
            true => &[("", 0), ("-general", FEATURES_ALL)],
            false => &[("", 0)],
        };
        let features = |set: u32| if set == 0 { scene.features() } else { set };
        if self.cpu {
            for &(suffix, set) in feature_sets {
                let features = features(set);
                ways.push((format!("cpu{suffix}"), Way::Cpu { features }));
            }
        }
        let Some(context) = self.gpu else {
            return ways;
        };
        let checks = match self.checks.is_empty() {
            true => &[ShaderChecks::default()][..],
            false => self.checks,
        };
        // The megakernel renders Whitted's integrator only.
        let path_traced = scene.frame.integrator == INTEGRATOR_PATH;
        for &kernels in self.kernels {
            if path_traced && kernels == PathKernels::Megakernel {
                continue;
            }
            for &check in checks {
                let check_suffix = match check == ShaderChecks::default() {
                    true => String::new(),
                    false => format!("-checks-{}", check.name()),
                };
                for &(suffix, set) in feature_sets {
                    let way = Way::Gpu {
                        features: features(set),
                        budgets: None,
                        kernels,
                        checks: check,
                    };
                    let name = format!("{}{check_suffix}{suffix}", gpu_way_name(kernels));
                    ways.push((name, way));
                }
            }
        }
        let adapters = RayBudgets::for_adapter(context.is_cpu_adapter);
        for &n in self.rays_per_invocation.iter().filter(|_| !path_traced) {
            // A fixed shape: N rays per invocation whatever the image size.
            let budgets = RayBudgets {
                per_invocation: n,
                min_invocations_per_dispatch: 0,
                ..adapters
            };
            let way = Way::Gpu {
                features: scene.features(),
                budgets: Some(budgets),
                kernels: PathKernels::Megakernel,
                checks: ShaderChecks::default(),
            };
            ways.push((format!("gpu-mega-rpi{n}"), way));
        }
        ways
    }
}

/// The report's name of a GPU way of running paths.
fn gpu_way_name(kernels: PathKernels) -> &'static str {
    match kernels {
        PathKernels::Megakernel => "gpu-mega",
        PathKernels::Wavefront => "gpu-wave",
    }
}

/// Renders each scene with each way of `config` interleaved run by run, after one warm-up run
/// each, each way with one renderer for all its runs; then, on a GPU with timestamps, once more
/// with the wavefront render's stages timed one by one (where its time goes).
pub fn run(config: &FrameConfig<'_>) -> Result<FrameReport> {
    let mut results = Vec::new();
    for name in config.scenes {
        let scene = Scene::load(&super::sample_scene(name), config.overrides)?;
        let flat = flatten(&scene);
        let ways = config.ways(&flat);
        let mut renderers = ways
            .iter()
            .map(|&(_, way)| WayRenderer::new(&flat, way, config.gpu))
            .collect::<Result<Vec<_>>>()?;
        let mut frame_ms = vec![Vec::new(); ways.len()];
        let mut traced_ms = vec![Vec::new(); ways.len()];
        let mut kernel_ms = vec![Vec::new(); ways.len()];
        // Per way: a plan with more light windows retraces each path once per window.
        let mut rays = vec![0; ways.len()];
        for run in 0..=config.runs.max(1) {
            for (i, renderer) in renderers.iter_mut().enumerate() {
                // A GPU left idle while the CPU ways ran has lowered its clocks: an untimed
                // frame just before each timed one brings them (and its caches) back, or the
                // first GPU way after a CPU way runs up to 4x slower than the rest.
                if let WayRenderer::Gpu(_) = renderer {
                    renderer.render(&flat)?;
                }
                let output = renderer.render(&flat)?;
                if let Some(e) = output.stopped {
                    return Err(e);
                }
                rays[i] = output.rays;
                if run > 0 {
                    frame_ms[i].push(output.elapsed.as_secs_f64() * 1e3);
                    traced_ms[i].push(output.traced.as_secs_f64() * 1e3);
                    if let Some(k) = output.kernel_time {
                        kernel_ms[i].push(k.as_secs_f64() * 1e3);
                    }
                }
            }
        }
        let runs = ways
            .iter()
            .enumerate()
            .map(|(i, (backend, _))| {
                let frame = Spread::of(&frame_ms[i]);
                FrameRun {
                    backend: backend.clone(),
                    rays: rays[i],
                    frame_ms: frame,
                    traced_ms: Spread::of(&traced_ms[i]),
                    kernel_ms: (!kernel_ms[i].is_empty()).then(|| Spread::of(&kernel_ms[i])),
                    mrays_per_s: rays[i] as f64 / frame.median / 1e3,
                }
            })
            .collect();
        let stages = match config.gpu {
            Some(context) if config.kernels.contains(&PathKernels::Wavefront) => {
                profile_wavefront(&flat, context)?
            }
            _ => Vec::new(),
        };
        let f = &flat.frame;
        results.push(FrameResult {
            scene: name.clone(),
            width: f.width,
            height: f.height,
            spp: f.spp,
            triangles: flat.triangle_count,
            features: flat.features(),
            runs,
            stages,
        });
    }
    Ok(FrameReport { results })
}

/// One render of `scene` by the wavefront render with its stages timed one by one (after a
/// warm-up render): each kernel's device time. Empty where the adapter has no timestamps.
fn profile_wavefront(scene: &FlatScene, context: &GpuContext) -> Result<Vec<StageShare>> {
    let cancel = AtomicBool::new(false);
    let mut renderer = GpuRenderer::with_kernels(
        context.clone(),
        scene,
        scene.features(),
        PathKernels::Wavefront,
    )?;
    render(scene, &mut renderer, &mut |_, _| {}, &cancel)?;
    renderer.profile_stages();
    let output = render(scene, &mut renderer, &mut |_, _| {}, &cancel)?;
    if let Some(e) = output.stopped {
        return Err(e);
    }
    let times = renderer.stage_times().unwrap_or_default();
    Ok(times
        .into_iter()
        .filter(|(_, t)| t.stages + t.untimed > 0)
        .map(|(kernel, t)| StageShare {
            kernel: kernel.to_string(),
            ms: t.time.as_secs_f64() * 1e3,
            stages: t.stages,
            untimed: t.untimed,
        })
        .collect())
}

/// A kernel's device time in a profiled wavefront render.
#[derive(Clone, Debug, Serialize)]
pub struct StageShare {
    /// The kernel's name (`gpu::kernels`).
    pub kernel: String,
    /// Its stages' device time, summed (ms).
    pub ms: f64,
    /// Its stages timed.
    pub stages: u64,
    /// Its stages not timed (beyond a batch's room for timestamps).
    pub untimed: u64,
}

impl FrameReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = String::from(
            "frame: each sample scene at its own size and spp; median (min–max) ms of the timed \
             runs, interleaved (the frame with its image read back; `traced`: until its last \
             pass finished on the device); `cpu`, `gpu-mega` (the megakernel) and `gpu-wave` (the \
             wavefront render) run code specialised to the scene's features, `-general` the code \
             with every feature, `gpu-mega-rpiN` the megakernel at N rays per invocation; ratios \
             are speed-ups\n\n",
        );
        out += "| scene | size x spp | triangles | features | backend | frame ms | traced ms | kernel ms | Mrays/s | vs CPU | vs general |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.results {
            let cpu = r.runs.iter().find(|x| x.backend == "cpu");
            let general_of = |backend: &str| {
                let name = format!("{backend}-general");
                r.runs.iter().find(|x| x.backend == name)
            };
            for x in &r.runs {
                let ratio = |other: Option<&FrameRun>| {
                    other.map_or("-".into(), |o| {
                        format!("{:.2}x", o.frame_ms.median / x.frame_ms.median)
                    })
                };
                out += &format!(
                    "| {} | {}x{} x {} | {} | {:#x} | {} | {:.1} ({:.1}–{:.1}) | {:.1} | {} | {:.2} | {} | {} |\n",
                    r.scene,
                    r.width,
                    r.height,
                    r.spp,
                    r.triangles,
                    r.features,
                    x.backend,
                    x.frame_ms.median,
                    x.frame_ms.min,
                    x.frame_ms.max,
                    x.traced_ms.median,
                    x.kernel_ms
                        .map_or("-".into(), |k| format!("{:.1}", k.median)),
                    x.mrays_per_s,
                    ratio(cpu),
                    ratio(general_of(&x.backend)),
                );
            }
        }
        out += &self.stages_markdown();
        out
    }

    /// Where each scene's wavefront frame spends its device time, kernel by kernel.
    fn stages_markdown(&self) -> String {
        let measured: Vec<&FrameResult> = self
            .results
            .iter()
            .filter(|r| !r.stages.is_empty())
            .collect();
        if measured.is_empty() {
            return String::new();
        }
        let mut out = String::from(
            "\nwavefront stages: device ms of each kernel in one render with every stage in a \
             compute pass of its own and timed (stages timed / not timed, where a batch had no \
             room for more timestamps)\n\n| scene | kernel | ms | share | stages |\n|---|---|---|---|---|\n",
        );
        for r in measured {
            let total: f64 = r.stages.iter().map(|s| s.ms).sum();
            for stage in &r.stages {
                out += &format!(
                    "| {} | {} | {:.2} | {:.0}% | {} / {} |\n",
                    r.scene,
                    stage.kernel,
                    stage.ms,
                    100.0 * stage.ms / total.max(1e-12),
                    stage.stages,
                    stage.untimed
                );
            }
        }
        out
    }
}
