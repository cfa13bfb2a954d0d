//! The frame benchmark: each sample scene rendered whole on each backend, side by side; each
//! with the code specialised to the scene's features and with the general code, so the
//! specialisation's speed-up is measured in the same run.

use std::sync::atomic::AtomicBool;

use serde::Serialize;

use super::Spread;
use crate::cpu::CpuRenderer;
use crate::error::Result;
use crate::gpu::render::PathKernels;
use crate::gpu::{GpuContext, GpuRenderer};
use crate::layout::FEATURES_ALL;
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
    /// Wall-clock time of the whole render over the timed runs (ms).
    pub frame_ms: Spread,
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
    },
}

pub(super) fn render_once(
    scene: &FlatScene,
    way: Way,
    gpu: Option<&GpuContext>,
) -> Result<RenderOutput> {
    let cancel = AtomicBool::new(false);
    match way {
        Way::Cpu { features } => {
            let mut renderer = CpuRenderer::new(scene).with_features(features)?;
            render(scene, &mut renderer, &mut |_, _| {}, &cancel)
        }
        Way::Gpu {
            features,
            budgets,
            kernels,
        } => {
            let context = gpu
                .expect("a GPU way is only planned with a GPU context")
                .clone();
            let mut renderer = match budgets {
                Some(budgets) => {
                    GpuRenderer::with_budgets(context, scene, features, kernels, budgets)?
                }
                None => GpuRenderer::with_kernels(context, scene, features, kernels)?,
            };
            render(scene, &mut renderer, &mut |_, _| {}, &cancel)
        }
    }
}

/// Renders each scene of `scenes` (names in `scenes/`) with each backend of `backends`
/// interleaved run by run, after one warm-up run each; on the GPU too when `gpu` is given, and
/// there once more for each of `rays_per_invocation` (dispatch shapes: the budgets' largest
/// number of rays one invocation traces). `overrides` apply to every scene.
pub fn run(
    scenes: &[String],
    overrides: &[String],
    gpu: Option<&GpuContext>,
    rays_per_invocation: &[u64],
    runs: u32,
) -> Result<FrameReport> {
    let mut results = Vec::new();
    for name in scenes {
        let scene = Scene::load(&super::sample_scene(name), overrides)?;
        let flat = flatten(&scene);
        let mut ways: Vec<(String, Way)> = vec![
            (
                "cpu".into(),
                Way::Cpu {
                    features: flat.features(),
                },
            ),
            (
                "cpu-general".into(),
                Way::Cpu {
                    features: FEATURES_ALL,
                },
            ),
        ];
        if let Some(context) = gpu {
            let adapters = RayBudgets::for_adapter(context.is_cpu_adapter);
            for (name, kernels) in [
                ("gpu-mega", PathKernels::Megakernel),
                ("gpu-wave", PathKernels::Wavefront),
            ] {
                for (suffix, features) in [("", flat.features()), ("-general", FEATURES_ALL)] {
                    ways.push((
                        format!("{name}{suffix}"),
                        Way::Gpu {
                            features,
                            budgets: None,
                            kernels,
                        },
                    ));
                }
            }
            for &n in rays_per_invocation {
                // A fixed shape: N rays per invocation whatever the image size.
                let budgets = RayBudgets {
                    per_invocation: n,
                    min_invocations_per_dispatch: 0,
                    ..adapters
                };
                ways.push((
                    format!("gpu-mega-rpi{n}"),
                    Way::Gpu {
                        features: flat.features(),
                        budgets: Some(budgets),
                        kernels: PathKernels::Megakernel,
                    },
                ));
            }
        }
        let mut frame_ms = vec![Vec::new(); ways.len()];
        let mut kernel_ms = vec![Vec::new(); ways.len()];
        // Per way: a plan with more light windows retraces each path once per window.
        let mut rays = vec![0; ways.len()];
        for run in 0..=runs.max(1) {
            for (i, &(_, way)) in ways.iter().enumerate() {
                let output = render_once(&flat, way, gpu)?;
                if let Some(e) = output.stopped {
                    return Err(e);
                }
                rays[i] = output.rays;
                if run > 0 {
                    frame_ms[i].push(output.elapsed.as_secs_f64() * 1e3);
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
                    kernel_ms: (!kernel_ms[i].is_empty()).then(|| Spread::of(&kernel_ms[i])),
                    mrays_per_s: rays[i] as f64 / frame.median / 1e3,
                }
            })
            .collect();
        let f = &flat.frame;
        results.push(FrameResult {
            scene: name.clone(),
            width: f.width,
            height: f.height,
            spp: f.spp,
            triangles: flat.triangle_count,
            features: flat.features(),
            runs,
        });
    }
    Ok(FrameReport { results })
}

impl FrameReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = String::from(
            "frame: each sample scene at its own size and spp; median (min–max) ms of the timed \
             runs, interleaved; `cpu`, `gpu-mega` (the megakernel) and `gpu-wave` (the wavefront \
             render) run code specialised to the scene's features, `-general` the code with \
             every feature, `gpu-mega-rpiN` the megakernel at N rays per invocation; ratios are \
             speed-ups\n\n",
        );
        out += "| scene | size x spp | triangles | features | backend | frame ms | kernel ms | Mrays/s | vs CPU | vs general |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|\n";
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
                    "| {} | {}x{} x {} | {} | {:#x} | {} | {:.1} ({:.1}–{:.1}) | {} | {:.2} | {} | {} |\n",
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
                    x.kernel_ms
                        .map_or("-".into(), |k| format!("{:.1}", k.median)),
                    x.mrays_per_s,
                    ratio(cpu),
                    ratio(general_of(&x.backend)),
                );
            }
        }
        out
    }
}
