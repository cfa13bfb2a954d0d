//! `chambre converge`: the speed–accuracy trade of one scene, measured. A reference image
//! (given, or rendered on the CPU path at many samples with Sobol patterns and another seed),
//! then the scene at 1, 2, 4, … samples per pixel for each sample pattern and backend, each run's
//! time, rays and error against the reference: RMSE and relative MSE of linear radiance, and
//! FLIP (NVIDIA's perceptual difference, through `nv-flip`) of the sRGB images. A CSV with a
//! row per run and a log-log plot of error against samples and against time, with each curve's
//! fitted convergence slope (-0.5 for plain Monte Carlo).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use plotters::prelude::*;

use crate::bench::rays::Backend;
use crate::cpu::CpuRenderer;
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuRenderer};
use crate::metrics::{flip, log_log_slope, rel_mse, rmse};
use crate::pack::flatten;
use crate::plot::{Figure, Series, log_log_panel};
use crate::render::{Image, RenderOutput, render};
use crate::sampler::SamplerName;
use crate::scene::Scene;

/// Measure how a scene's error against a reference falls with samples per pixel and with time,
/// for each sample pattern and backend.
#[derive(Clone, Debug)]
pub struct ConvergeSettings {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Reference image: a linear EXR of the scene's size (default: rendered on the CPU path at
    /// `reference_spp` with Sobol patterns and another seed).
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference.
    pub reference_spp: u32,
    /// The largest sample count: runs at 1, 2, 4, … up to it.
    pub max_spp: u32,
    /// Sample patterns to compare, each used for the pixel and the lens samples.
    pub samplers: Vec<SamplerName>,
    /// Also render adaptively (`render.noise_target`) at each of these targets, with `max_spp` as
    /// the most samples a pixel takes: one more curve per pattern and backend, and a table of
    /// the time uniform sampling needs for the same RMSE.
    pub noise_targets: Vec<f64>,
    /// The adaptive renders' `render.min_spp` (default: the scene's, or 16).
    pub min_spp: Option<u32>,
    /// Renders of each run: its times are their medians (the images are the same).
    pub runs: usize,
    /// Backends to measure, side by side.
    pub backends: Vec<Backend>,
    /// Override any scene field, e.g. --set render.width=200 (also -D).
    pub set: Vec<String>,
}

/// One render and its error against the reference.
#[derive(Clone, Debug)]
pub struct Run {
    /// Where it rendered: the CPU path or the GPU.
    pub backend: Backend,
    /// The pattern of its pixel and lens samples.
    pub sampler: SamplerName,
    /// Samples per pixel: every pixel's, or the most an adaptive render gives one.
    pub spp: u32,
    /// The adaptive render's target; none for uniform sampling.
    pub noise_target: Option<f64>,
    /// Samples per pixel on average.
    pub mean_spp: f64,
    /// Wall time of the render (ms), the median over `--runs` renders.
    pub wall_ms: f64,
    /// GPU kernel time, where the adapter has timestamp queries.
    pub kernel_ms: Option<f64>,
    /// Rays traced: camera, shadow and mirror rays.
    pub rays: u64,
    /// Root mean square error against the reference ([`rmse`]).
    pub rmse: f64,
    /// Relative MSE against the reference ([`rel_mse`]).
    pub rel_mse: f64,
    /// Mean FLIP error against the reference ([`flip`]).
    pub flip: f64,
}

fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut values: Vec<f64> = values.collect();
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Renders `scene` with `overrides` on `backend` (`gpu`: its context).
fn render_once(
    scene: &Path,
    overrides: &[String],
    gpu: Option<&GpuContext>,
) -> Result<RenderOutput> {
    let flat = flatten(&Scene::load(scene, overrides)?);
    let cancel = AtomicBool::new(false);
    let output = match gpu {
        None => render(&flat, &mut CpuRenderer::new(&flat), &mut |_, _| {}, &cancel)?,
        Some(context) => render(
            &flat,
            &mut GpuRenderer::new(context.clone(), &flat)?,
            &mut |_, _| {},
            &cancel,
        )?,
    };
    match output.stopped {
        Some(e) => Err(e),
        None => Ok(output),
    }
}

/// The reference: read from `path` (a linear EXR of the scene's size), or rendered.
fn reference(args: &ConvergeSettings, width: u32, height: u32, seed: u32) -> Result<Image> {
    if let Some(path) = &args.reference {
        let fail = |message: String| Error::File {
            path: path.clone(),
            message,
        };
        let read = read_linear(path).map_err(fail)?;
        if (read.width, read.height) != (width, height) {
            return Err(fail(format!(
                "the reference is {}x{}, the scene {width}x{height}",
                read.width, read.height
            )));
        }
        // A NaN would make every error NaN; a negative radiance is no reference either.
        if let Some(i) = read
            .pixels
            .iter()
            .position(|p| !(p.is_finite() && p.min_element() >= 0.0))
        {
            return Err(fail(format!(
                "pixel ({}, {}) is {} (a reference's radiance is finite and non-negative)",
                i as u32 % width,
                i as u32 / width,
                read.pixels[i]
            )));
        }
        return Ok(read);
    }
    let mut overrides = args.set.clone();
    overrides.extend([
        format!("render.spp={}", args.reference_spp),
        "render.pixel_sampler=sobol".into(),
        "camera.lens_sampler=sobol".into(),
        // Another seed than the runs': their error must not correlate with the reference's.
        format!("render.seed={}", seed.wrapping_add(1_000_003)),
    ]);
    Ok(render_once(&args.scene, &overrides, None)?.image)
}

/// A linear image: an EXR or a PFM (chambre's own outputs); an 8-bit image is refused, its
/// values being display codes, not radiance.
fn read_linear(path: &std::path::Path) -> std::result::Result<Image, String> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("pfm") => {
            let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
            crate::output::read_pfm(&bytes)
        }
        Some("exr") => {
            let read = image::open(path).map_err(|e| e.to_string())?.into_rgb32f();
            Ok(Image {
                width: read.width(),
                height: read.height(),
                pixels: read.pixels().map(|p| glam::Vec3::from(p.0)).collect(),
            })
        }
        _ => Err(
            "a reference is a linear image: an EXR or a PFM (a PNG's values are display \
                  codes, not radiance)"
                .into(),
        ),
    }
}

/// The whole study: every run, in the order rendered.
pub struct Study {
    /// For each backend and pattern: the uniform runs by increasing samples, then the
    /// adaptive ones by `--noise-targets`.
    pub runs: Vec<Run>,
    /// Where the reference came from: its file, or how it was rendered.
    pub reference_note: String,
    /// The GPU adapter's description, or `none` when no run used the GPU.
    pub adapter: String,
}

/// Runs the study `args` describe: the reference (read or rendered), then every run, each
/// rendered `--runs` times.
pub fn run(args: &ConvergeSettings) -> Result<Study> {
    let scene = Scene::load(&args.scene, &args.set)?;
    let (width, height, seed) = (scene.render.width, scene.render.height, scene.render.seed);
    let reference_image = reference(args, width, height, seed)?;
    let reference_note = match &args.reference {
        Some(path) => format!("reference {}", path.display()),
        None => format!(
            "reference rendered on the CPU path at {} spp, sobol patterns, seed {}",
            args.reference_spp,
            seed.wrapping_add(1_000_003)
        ),
    };
    let gpu = if args.backends.contains(&Backend::Gpu) {
        Some(GpuContext::new()?)
    } else {
        None
    };
    let adapter = gpu
        .as_ref()
        .map_or("none".into(), |c| c.adapter_description.clone());
    let counts: Vec<u32> = std::iter::successors(Some(1u32), |&n| n.checked_mul(2))
        .take_while(|&n| n <= args.max_spp.max(1))
        .collect();
    let mut runs = Vec::new();
    for &backend in &args.backends {
        let context = if backend == Backend::Gpu {
            gpu.as_ref()
        } else {
            None
        };
        for &sampler in &args.samplers {
            let uniform = counts.iter().map(|&spp| (spp, None));
            let adaptive = args.noise_targets.iter().map(|&t| (args.max_spp, Some(t)));
            for (spp, noise_target) in uniform.chain(adaptive) {
                let mut overrides = args.set.clone();
                overrides.extend([
                    format!("render.spp={spp}"),
                    format!("render.pixel_sampler={}", sampler.name()),
                    format!("camera.lens_sampler={}", sampler.name()),
                ]);
                if let Some(target) = noise_target {
                    overrides.push(format!("render.noise_target={target:?}"));
                    if let Some(n) = args.min_spp {
                        overrides.push(format!("render.min_spp={n}"));
                    }
                }
                let mut outputs = (0..args.runs.max(1))
                    .map(|_| render_once(&args.scene, &overrides, context))
                    .collect::<Result<Vec<_>>>()?;
                let wall_ms = median(outputs.iter().map(|o| o.elapsed.as_secs_f64() * 1e3));
                let kernel_ms = outputs
                    .iter()
                    .map(|o| o.kernel_time.map(|t| t.as_secs_f64() * 1e3))
                    .collect::<Option<Vec<f64>>>()
                    .map(|times| median(times.into_iter()));
                let output = outputs.pop().expect("one render at least");
                let counts = &output.sample_counts;
                runs.push(Run {
                    backend,
                    sampler,
                    spp,
                    noise_target,
                    mean_spp: counts.iter().map(|&n| n as f64).sum::<f64>()
                        / counts.len().max(1) as f64,
                    wall_ms,
                    kernel_ms,
                    rays: output.rays,
                    rmse: rmse(&output.image, &reference_image),
                    rel_mse: rel_mse(&output.image, &reference_image),
                    flip: flip(&output.image, &reference_image),
                });
            }
        }
    }
    Ok(Study {
        runs,
        reference_note,
        adapter,
    })
}

fn backend_name(backend: Backend) -> &'static str {
    match backend {
        Backend::Cpu => "cpu",
        Backend::Gpu => "gpu",
    }
}

impl Study {
    /// The CSV: `#` comment lines (command, version, date, adapter, reference), a header, a row
    /// per run.
    pub fn to_csv(&self, command: &str) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "# {command}");
        let _ = writeln!(
            out,
            "# chambre {}, {}, adapter: {}",
            env!("CARGO_PKG_VERSION"),
            crate::provenance::utc_date(),
            self.adapter
        );
        let _ = writeln!(out, "# {}", self.reference_note);
        out += "backend,sampler,mode,spp,mean_spp,noise_target,wall_ms,kernel_ms,rays,rmse,\
                rel_mse,flip\n";
        for r in &self.runs {
            let _ = writeln!(
                out,
                "{},{},{},{},{:.3},{},{:.3},{},{},{:.6e},{:.6e},{:.6e}",
                backend_name(r.backend),
                r.sampler.name(),
                r.curve().mode(),
                r.spp,
                r.mean_spp,
                r.noise_target.map_or(String::new(), |t| format!("{t}")),
                r.wall_ms,
                r.kernel_ms.map_or(String::new(), |k| format!("{k:.3}")),
                r.rays,
                r.rmse,
                r.rel_mse,
                r.flip
            );
        }
        out
    }

    /// Each curve's fitted RMSE slope against (mean) samples per pixel, in run order.
    pub fn slopes(&self) -> Vec<(Curve, f64)> {
        let mut curves: Vec<Curve> = Vec::new();
        for r in &self.runs {
            if !curves.contains(&r.curve()) {
                curves.push(r.curve());
            }
        }
        curves
            .into_iter()
            .map(|c| (c, log_log_slope(&self.curve(c, |r| r.mean_spp))))
            .collect()
    }

    /// The (x, RMSE) points of `curve`.
    fn curve(&self, curve: Curve, x: impl Fn(&Run) -> f64) -> Vec<(f64, f64)> {
        self.runs
            .iter()
            .filter(|r| r.curve() == curve)
            .map(|r| (x(r), r.rmse))
            .collect()
    }

    /// Each uniform curve against the first uniform curve of its backend (the first sampler
    /// asked for, `random` in the studies of `BENCHMARKS.md`) at equal time: the RMSE of both,
    /// interpolated log-log along their runs, at the wall time of the first curve's last run
    /// (or this curve's, if shorter). `None` where the curves' times do not overlap there, and
    /// for the first curve itself.
    pub fn equal_time_ratios(&self) -> Vec<(Curve, Option<EqualTime>)> {
        let uniform: Vec<Curve> = self
            .slopes()
            .into_iter()
            .map(|(c, _)| c)
            .filter(|c| !c.adaptive)
            .collect();
        let at_equal_time = |curve: Curve| -> Option<EqualTime> {
            let first = uniform.iter().find(|c| c.backend == curve.backend)?;
            if *first == curve {
                return None;
            }
            let mine = self.curve(curve, |r| r.wall_ms);
            let theirs = self.curve(*first, |r| r.wall_ms);
            let wall_ms = mine.last()?.0.min(theirs.last()?.0);
            Some(EqualTime {
                wall_ms,
                rmse: log_log_at(&mine, wall_ms)?,
                first_rmse: log_log_at(&theirs, wall_ms)?,
            })
        };
        uniform.iter().map(|&c| (c, at_equal_time(c))).collect()
    }

    /// For each adaptive run, the uniform runs of its backend and pattern at the same RMSE:
    /// their wall time and FLIP, interpolated log-log between the two uniform runs around it
    /// (none when the adaptive run's RMSE is beyond the uniform curve).
    pub fn adaptive_gains(&self) -> Vec<AdaptiveGain<'_>> {
        self.runs
            .iter()
            .filter(|r| r.noise_target.is_some())
            .map(|run| {
                let uniform: Vec<&Run> = self
                    .runs
                    .iter()
                    .filter(|u| {
                        u.noise_target.is_none()
                            && (u.backend, u.sampler) == (run.backend, run.sampler)
                    })
                    .collect();
                let at_same_rmse = at_same_error(&uniform, run.rmse, |r| r.rmse);
                let at_same_flip = at_same_error(&uniform, run.flip, |r| r.flip);
                AdaptiveGain {
                    run,
                    uniform_wall_ms: at_same_rmse.map(|u| u.wall_ms),
                    uniform_flip: at_same_rmse.map(|u| u.flip),
                    uniform_wall_ms_same_flip: at_same_flip.map(|u| u.wall_ms),
                    uniform_rmse_same_flip: at_same_flip.map(|u| u.rmse),
                }
            })
            .collect()
    }

    /// Two log-log panels, RMSE against samples per pixel and against wall time; one curve per
    /// backend, sample pattern and mode, its fitted slope in the legend.
    fn draw_panels<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), String> {
        let fail = |e: &dyn std::fmt::Display| e.to_string();
        let colours = [
            BLUE,
            RED,
            GREEN,
            MAGENTA,
            CYAN,
            BLACK,
            RGBColor(230, 120, 0),
        ];
        let slopes = self.slopes();
        let labels: Vec<String> = slopes
            .iter()
            .map(|(c, slope)| match slope.is_finite() {
                true => format!("{} (slope {slope:.2})", c.label()),
                false => c.label(),
            })
            .collect();
        let by_spp: Vec<Vec<(f64, f64)>> = slopes
            .iter()
            .map(|(c, _)| self.curve(*c, |r| r.mean_spp))
            .collect();
        let by_time: Vec<Vec<(f64, f64)>> = slopes
            .iter()
            .map(|(c, _)| self.curve(*c, |r| r.wall_ms.max(1e-3)))
            .collect();
        let range = |curves: &[Vec<(f64, f64)>]| {
            let xs = curves.iter().flatten().map(|p| p.0);
            let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
            (lo * 0.7)..(hi * 1.4)
        };
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (left, right) = root.split_horizontally(root.dim_in_pixel().0 / 2);
        for (area, curves, x_desc, title) in [
            (&left, &by_spp, "samples per pixel", "RMSE against samples"),
            (&right, &by_time, "wall time, ms", "RMSE against time"),
        ] {
            let borrowed: Vec<Series> = curves
                .iter()
                .enumerate()
                .map(|(i, c)| (labels[i].as_str(), c.as_slice(), colours[i % colours.len()]))
                .collect();
            log_log_panel(area, title, x_desc, "RMSE", &borrowed, range(curves))
                .map_err(|e| fail(&e))?;
        }
        Ok(())
    }

    /// A summary for the terminal: each curve's slope, and its last run's error and time; then
    /// each adaptive run against uniform sampling at the same RMSE.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("{}\n\n", self.reference_note);
        out += "| curve | RMSE slope | spp | RMSE | relMSE | FLIP | wall ms |\n";
        out += "|---|---|---|---|---|---|---|\n";
        for (curve, slope) in self.slopes() {
            let last = self
                .runs
                .iter()
                .rfind(|r| r.curve() == curve)
                .expect("a curve has runs");
            let _ = writeln!(
                out,
                "| {} | {slope:.2} | {:.1} | {:.4e} | {:.4e} | {:.4} | {:.1} |",
                curve.label(),
                last.mean_spp,
                last.rmse,
                last.rel_mse,
                last.flip,
                last.wall_ms
            );
        }
        let equal_time: Vec<(Curve, EqualTime)> = self
            .equal_time_ratios()
            .into_iter()
            .filter_map(|(c, e)| Some((c, e?)))
            .collect();
        if !equal_time.is_empty() {
            out += "\nAt equal time against the first pattern of each backend (both curves \
                    interpolated log-log at the shorter of their last runs' times):\n\n";
            out += "| curve | wall ms | RMSE | first pattern's RMSE | ratio |\n";
            out += "|---|---|---|---|---|\n";
            for (curve, e) in equal_time {
                let _ = writeln!(
                    out,
                    "| {} | {:.1} | {:.4e} | {:.4e} | {:.2}x |",
                    curve.label(),
                    e.wall_ms,
                    e.rmse,
                    e.first_rmse,
                    e.rmse / e.first_rmse
                );
            }
        }
        let gains = self.adaptive_gains();
        if gains.is_empty() {
            return out;
        }
        out += "\nAdaptive against uniform sampling at the same RMSE (uniform interpolated log-log \
                between its runs):\n\n";
        out += "| curve | noise target | mean spp | RMSE | FLIP | wall ms | uniform wall ms | \
                time ratio | uniform FLIP | time ratio at equal FLIP | uniform RMSE at equal FLIP |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|---|\n";
        for gain in gains {
            let r = gain.run;
            let (uniform_ms, ratio, uniform_flip) = match (gain.uniform_wall_ms, gain.uniform_flip)
            {
                (Some(ms), Some(flip)) => (
                    format!("{ms:.1}"),
                    format!("{:.2}x", r.wall_ms / ms),
                    format!("{flip:.3e}"),
                ),
                _ => ("beyond the uniform runs".into(), "-".into(), "-".into()),
            };
            let flip_ratio = gain
                .uniform_wall_ms_same_flip
                .map_or("-".into(), |ms| format!("{:.2}x", r.wall_ms / ms));
            let flip_rmse = gain
                .uniform_rmse_same_flip
                .map_or("-".into(), |e| format!("{e:.3e}"));
            let _ = writeln!(
                out,
                "| {} | {} | {:.1} | {:.4e} | {:.3e} | {:.1} | {uniform_ms} | {ratio} | \
                 {uniform_flip} | {flip_ratio} | {flip_rmse} |",
                r.curve().label(),
                r.noise_target.unwrap_or_default(),
                r.mean_spp,
                r.rmse,
                r.flip,
                r.wall_ms,
            );
        }
        out
    }
}

impl Figure for Study {
    fn size(&self) -> (u32, u32) {
        (1100, 460)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), String> {
        self.draw_panels(root)
    }
}

/// One curve of a study: a backend, a pattern, uniform or adaptive sampling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Curve {
    /// Where its runs rendered.
    pub backend: Backend,
    /// Its runs' sample pattern.
    pub sampler: SamplerName,
    /// Its runs sample adaptively (`--noise-targets`), one run per target.
    pub adaptive: bool,
}

impl Curve {
    /// `adaptive` or `uniform`, as the CSV's `mode` column writes it.
    pub fn mode(&self) -> &'static str {
        if self.adaptive { "adaptive" } else { "uniform" }
    }

    /// The curve's name in legends and tables, e.g. `cpu sobol adaptive`.
    pub fn label(&self) -> String {
        let name = format!("{} {}", backend_name(self.backend), self.sampler.name());
        if self.adaptive {
            name + " adaptive"
        } else {
            name
        }
    }
}

impl Run {
    /// The curve the run belongs to.
    pub fn curve(&self) -> Curve {
        Curve {
            backend: self.backend,
            sampler: self.sampler,
            adaptive: self.noise_target.is_some(),
        }
    }
}

/// An adaptive run and what uniform sampling needs for its RMSE (`Study::adaptive_gains`).
pub struct AdaptiveGain<'a> {
    /// The adaptive run.
    pub run: &'a Run,
    /// The uniform runs' wall time (ms) at the adaptive run's RMSE; none beyond their range.
    pub uniform_wall_ms: Option<f64>,
    /// The uniform runs' FLIP at the adaptive run's RMSE.
    pub uniform_flip: Option<f64>,
    /// The uniform runs' wall time at the adaptive run's FLIP.
    pub uniform_wall_ms_same_flip: Option<f64>,
    /// The uniform runs' RMSE at the adaptive run's FLIP: above the adaptive run's, uniform
    /// sampling needs more time for an image worse by both measures.
    pub uniform_rmse_same_flip: Option<f64>,
}

/// The uniform runs where an error measure reaches a value (`at_same_error`).
#[derive(Clone, Copy, Debug)]
struct Interpolated {
    wall_ms: f64,
    flip: f64,
    rmse: f64,
}

/// The wall time, FLIP and RMSE of the uniform runs (by increasing samples) where `error`
/// reaches `value`: interpolated between the two runs around it (log-log, FLIP linearly); none
/// beyond them.
fn at_same_error(
    uniform: &[&Run],
    value: f64,
    error: impl Fn(&Run) -> f64,
) -> Option<Interpolated> {
    uniform.windows(2).find_map(|pair| {
        let (a, b) = (pair[0], pair[1]);
        let (ea, eb) = (error(a), error(b));
        if !(ea.min(eb)..=ea.max(eb)).contains(&value) || ea == eb {
            return None;
        }
        let t = (value.ln() - ea.ln()) / (eb.ln() - ea.ln());
        let log_lerp = |x: f64, y: f64| (x.ln() + t * (y.ln() - x.ln())).exp();
        Some(Interpolated {
            wall_ms: log_lerp(a.wall_ms, b.wall_ms),
            flip: a.flip + t * (b.flip - a.flip),
            rmse: log_lerp(a.rmse, b.rmse),
        })
    })
}

/// Two curves' RMSE at the same wall time (`Study::equal_time_ratios`).
#[derive(Clone, Copy, Debug)]
pub struct EqualTime {
    /// The time compared at (ms).
    pub wall_ms: f64,
    /// This curve's RMSE then.
    pub rmse: f64,
    /// The first curve's RMSE then.
    pub first_rmse: f64,
}

/// The y of the polyline `points` (sorted by x) at `x`, interpolated log-log; none outside it.
fn log_log_at(points: &[(f64, f64)], x: f64) -> Option<f64> {
    points.windows(2).find_map(|pair| {
        let ((xa, ya), (xb, yb)) = (pair[0], pair[1]);
        if !(xa.min(xb)..=xa.max(xb)).contains(&x) || xa == xb {
            return None;
        }
        let t = (x.ln() - xa.ln()) / (xb.ln() - xa.ln());
        Some((ya.ln() + t * (yb.ln() - ya.ln())).exp())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn flat(value: f32, n: usize) -> Image {
        Image {
            width: n as u32,
            height: 1,
            pixels: vec![Vec3::splat(value); n],
        }
    }

    #[test]
    fn errors_of_constant_images_are_analytic() {
        let (a, r) = (flat(1.5, 4), flat(1.0, 4));
        assert!((rmse(&a, &r) - 0.5).abs() < 1e-12);
        assert!((rel_mse(&a, &r) - 0.25 / 1.01).abs() < 1e-12);
        assert_eq!(rmse(&r, &r), 0.0);
        assert_eq!(flip(&flat(0.3, 16), &flat(0.3, 16)), 0.0);
        assert!(flip(&flat(1.0, 16), &flat(0.0, 16)) > 0.5);
    }

    #[test]
    fn log_log_interpolation_follows_a_power_law_and_stays_inside() {
        let points: Vec<(f64, f64)> = [1.0, 4.0, 16.0]
            .map(|x: f64| (x, 3.0 * x.powf(-0.5)))
            .into();
        let y = log_log_at(&points, 8.0).unwrap();
        assert!((y - 3.0 * 8f64.powf(-0.5)).abs() < 1e-12, "{y}");
        assert_eq!(log_log_at(&points, 0.5), None);
        assert_eq!(log_log_at(&points, 17.0), None);
    }

    #[test]
    fn the_slope_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> = (0..6)
            .map(|i| {
                let x = 2f64.powi(i);
                (x, 3.0 * x.powf(-0.5))
            })
            .collect();
        assert!((log_log_slope(&points) + 0.5).abs() < 1e-12);
    }
}
