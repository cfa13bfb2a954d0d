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
use crate::output::srgb_encode;
use crate::pack::flatten;
use crate::plot::{Series, log_log_panel};
use crate::render::{Image, RenderOutput, render};
use crate::sampler::SamplerName;
use crate::scene::Scene;

#[derive(Debug, clap::Args)]
pub struct ConvergeArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Reference image: a linear EXR of the scene's size (default: rendered on the CPU path at
    /// --reference-spp with Sobol patterns and another seed).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference.
    #[arg(long, default_value_t = 1024)]
    pub reference_spp: u32,
    /// The largest sample count: runs at 1, 2, 4, … up to it.
    #[arg(long, default_value_t = 64)]
    pub max_spp: u32,
    /// Sample patterns to compare, each used for the pixel and the lens samples.
    #[arg(long, value_enum, value_delimiter = ',',
          default_values_t = [SamplerName::Random, SamplerName::Stratified, SamplerName::Sobol])]
    pub samplers: Vec<SamplerName>,
    /// Backends to measure, side by side.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Backend::Cpu])]
    pub backends: Vec<Backend>,
    /// The CSV to write: one row per run, the command and machine in `#` comments.
    #[arg(long, default_value = "converge.csv")]
    pub csv: PathBuf,
    /// Also write the log-log plot (SVG) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Override any scene field, e.g. --set render.width=200 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// One render and its error against the reference.
#[derive(Clone, Debug)]
pub struct Run {
    pub backend: Backend,
    pub sampler: SamplerName,
    pub spp: u32,
    pub wall_ms: f64,
    /// GPU kernel time, where the adapter has timestamp queries.
    pub kernel_ms: Option<f64>,
    pub rays: u64,
    pub rmse: f64,
    pub rel_mse: f64,
    pub flip: f64,
}

/// Root mean square error of linear radiance over pixels and channels.
pub fn rmse(image: &Image, reference: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| (*p - *q).length_squared() as f64)
        .sum();
    (sum / (3 * image.pixels.len()) as f64).sqrt()
}

/// Relative MSE, mean of (x - r)^2 / (r^2 + 0.01) over pixels and channels (the 0.01 keeps dark
/// pixels from dominating; Rousselle et al.'s definition, which Mitsuba's tools use).
pub fn rel_mse(image: &Image, reference: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| {
            let (p, q) = (p.as_dvec3(), q.as_dvec3());
            ((p - q) * (p - q) / (q * q + 0.01)).element_sum()
        })
        .sum();
    sum / (3 * image.pixels.len()) as f64
}

/// Mean FLIP error of the two images shown as sRGB 8-bit (clamped), at FLIP's default viewing
/// distance (67 pixels per degree): 0 for identical images, 1 at most.
pub fn flip(image: &Image, reference: &Image) -> f64 {
    let rgb8 = |i: &Image| {
        let bytes: Vec<u8> = i
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(srgb_encode))
            .collect();
        nv_flip::FlipImageRgb8::with_data(i.width, i.height, &bytes)
    };
    let map = nv_flip::flip(
        rgb8(reference),
        rgb8(image),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

/// Least-squares slope of log(error) against log(x): -0.5 for error falling as 1/sqrt(x).
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
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
fn reference(args: &ConvergeArgs, width: u32, height: u32, seed: u32) -> Result<Image> {
    if let Some(path) = &args.reference {
        let read = image::open(path)
            .map_err(|e| Error::File {
                path: path.clone(),
                message: e.to_string(),
            })?
            .into_rgb32f();
        if (read.width(), read.height()) != (width, height) {
            return Err(Error::File {
                path: path.clone(),
                message: format!(
                    "the reference is {}x{}, the scene {width}x{height}",
                    read.width(),
                    read.height()
                ),
            });
        }
        let pixels = read.pixels().map(|p| glam::Vec3::from(p.0)).collect();
        return Ok(Image {
            width,
            height,
            pixels,
        });
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

/// The whole study: every run, in the order rendered.
pub struct Study {
    pub runs: Vec<Run>,
    pub reference_note: String,
    pub adapter: String,
}

pub fn run(args: &ConvergeArgs) -> Result<Study> {
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
            for &spp in &counts {
                let mut overrides = args.set.clone();
                overrides.extend([
                    format!("render.spp={spp}"),
                    format!("render.pixel_sampler={}", sampler.name()),
                    format!("camera.lens_sampler={}", sampler.name()),
                ]);
                let output = render_once(&args.scene, &overrides, context)?;
                runs.push(Run {
                    backend,
                    sampler,
                    spp,
                    wall_ms: output.elapsed.as_secs_f64() * 1e3,
                    kernel_ms: output.kernel_time.map(|t| t.as_secs_f64() * 1e3),
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
        out += "backend,sampler,spp,wall_ms,kernel_ms,rays,rmse,rel_mse,flip\n";
        for r in &self.runs {
            let _ = writeln!(
                out,
                "{},{},{},{:.3},{},{},{:.6e},{:.6e},{:.6e}",
                backend_name(r.backend),
                r.sampler.name(),
                r.spp,
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

    /// Each curve's fitted RMSE slope against samples, by (backend, sampler), in run order.
    pub fn slopes(&self) -> Vec<(Backend, SamplerName, f64)> {
        let mut curves: Vec<(Backend, SamplerName)> = Vec::new();
        for r in &self.runs {
            if !curves.contains(&(r.backend, r.sampler)) {
                curves.push((r.backend, r.sampler));
            }
        }
        curves
            .into_iter()
            .map(|(b, s)| (b, s, log_log_slope(&self.curve(b, s, |r| r.spp as f64))))
            .collect()
    }

    fn curve(
        &self,
        backend: Backend,
        sampler: SamplerName,
        x: impl Fn(&Run) -> f64,
    ) -> Vec<(f64, f64)> {
        self.runs
            .iter()
            .filter(|r| r.backend == backend && r.sampler == sampler)
            .map(|r| (x(r), r.rmse))
            .collect()
    }

    /// Two log-log panels, RMSE against samples per pixel and against wall time; one curve per
    /// backend and sample pattern, its fitted slope in the legend. Returns the SVG text.
    pub fn plot_svg(&self) -> std::result::Result<String, String> {
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
            .map(|(b, s, slope)| format!("{} {} (slope {slope:.2})", backend_name(*b), s.name()))
            .collect();
        let by_spp: Vec<Vec<(f64, f64)>> = slopes
            .iter()
            .map(|(b, s, _)| self.curve(*b, *s, |r| r.spp as f64))
            .collect();
        let by_time: Vec<Vec<(f64, f64)>> = slopes
            .iter()
            .map(|(b, s, _)| self.curve(*b, *s, |r| r.wall_ms.max(1e-3)))
            .collect();
        let range = |curves: &[Vec<(f64, f64)>]| {
            let xs = curves.iter().flatten().map(|p| p.0);
            let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
            (lo * 0.7)..(hi * 1.4)
        };
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (1100, 460)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| fail(&e))?;
            let (left, right) = root.split_horizontally(550);
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
            root.present().map_err(|e| fail(&e))?;
        }
        Ok(svg)
    }

    /// A summary for the terminal: each curve's slope, and its last run's error and time.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("{}\n\n", self.reference_note);
        out += "| backend | sampler | RMSE slope | spp | RMSE | relMSE | FLIP | wall ms |\n";
        out += "|---|---|---|---|---|---|---|---|\n";
        for (backend, sampler, slope) in self.slopes() {
            let last = self
                .runs
                .iter()
                .rfind(|r| r.backend == backend && r.sampler == sampler)
                .expect("a curve has runs");
            let _ = writeln!(
                out,
                "| {} | {} | {slope:.2} | {} | {:.4e} | {:.4e} | {:.4} | {:.1} |",
                backend_name(backend),
                sampler.name(),
                last.spp,
                last.rmse,
                last.rel_mse,
                last.flip,
                last.wall_ms
            );
        }
        out
    }
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
