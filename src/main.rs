//! The `chambre` command line: render, check, info. Errors become one message and exit code 1;
//! an interrupted render writes what it computed and exits with 130.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, bail};
use clap::{Parser, Subcommand, ValueEnum};

use chambre::accel::flatten;
use chambre::camera::Focus;
use chambre::camera::report::camera_report;
use chambre::cpu::CpuRenderer;
use chambre::gpu::{GpuContext, GpuRenderer, describe_adapters};
use chambre::output::write_image;
use chambre::render::{Progress, RenderOutput, describe_status_flags, render};
use chambre::scene::Scene;
use chambre::{Error, Result};

#[derive(Parser)]
#[command(
    name = "chambre",
    version,
    about = "A GPU ray tracer built around the optics of the view camera"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (.png: sRGB 8-bit; .exr: linear float).
    Render {
        scene: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        /// Samples per pixel (overrides render.spp).
        #[arg(long)]
        spp: Option<u32>,
        #[arg(long)]
        width: Option<u32>,
        #[arg(long)]
        height: Option<u32>,
        #[arg(long)]
        seed: Option<u32>,
        #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
        backend: BackendChoice,
        /// Pixel sample pattern (overrides render.pixel_sampler).
        #[arg(long, value_enum)]
        pixel_sampler: Option<SamplerChoice>,
        /// Lens sample pattern (overrides camera.lens_sampler).
        #[arg(long, value_enum)]
        lens_sampler: Option<SamplerChoice>,
        /// Override any scene field, e.g. --set camera.f_number=2.8 (also -D).
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Print what the camera does: field of view, plane of sharp focus, hinge and Scheimpflug
    /// lines, depth of field, and the equivalent raster projection matrix.
    Camera {
        scene: PathBuf,
        /// Circle of confusion in mm for the depth of field (default: film diagonal / 1500).
        #[arg(long)]
        coc: Option<f64>,
        /// Far clipping distance of the raster projection, in scene units.
        #[arg(long, default_value_t = 1000.0)]
        far: f64,
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Parse and validate a scene without rendering.
    Check {
        scene: PathBuf,
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// List the GPU adapters found and their relevant limits.
    Info,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SamplerChoice {
    Random,
    Stratified,
    Poisson,
    Interleaved,
    Sobol,
}

impl SamplerChoice {
    fn name(self) -> &'static str {
        match self {
            SamplerChoice::Random => "random",
            SamplerChoice::Stratified => "stratified",
            SamplerChoice::Poisson => "poisson",
            SamplerChoice::Interleaved => "interleaved",
            SamplerChoice::Sobol => "sobol",
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendChoice {
    /// The GPU when an adapter exists (lavapipe included), else the CPU.
    Auto,
    Gpu,
    Cpu,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render {
            scene,
            output,
            spp,
            width,
            height,
            seed,
            backend,
            pixel_sampler,
            lens_sampler,
            set,
        } => {
            let mut overrides = Vec::new();
            let fields = [
                ("render.spp", spp),
                ("render.width", width),
                ("render.height", height),
                ("render.seed", seed),
            ];
            for (key, value) in fields {
                if let Some(v) = value {
                    overrides.push(format!("{key}={v}"));
                }
            }
            let samplers = [
                ("render.pixel_sampler", pixel_sampler),
                ("camera.lens_sampler", lens_sampler),
            ];
            for (key, value) in samplers {
                if let Some(v) = value {
                    overrides.push(format!("{key}={}", v.name()));
                }
            }
            overrides.extend(set);
            run_render(&scene, &output, backend, &overrides)
        }
        Command::Check { scene, set } => run_check(&scene, &set),
        Command::Camera {
            scene,
            coc,
            far,
            set,
        } => run_camera(&scene, coc, far, &set),
        Command::Info => run_info(),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load(path: &std::path::Path, overrides: &[String]) -> Result<Scene> {
    Scene::load(path, overrides)
}

fn run_check(path: &std::path::Path, overrides: &[String]) -> anyhow::Result<ExitCode> {
    let scene = load(path, overrides)?;
    let flat = flatten(&scene);
    let camera = &scene.camera;
    let fov = camera.field_of_view_deg();
    println!(
        "{}: ok: {}x{} at {} spp, {} shapes ({} triangles), {} lights, {} materials",
        path.display(),
        scene.render.width,
        scene.render.height,
        scene.render.spp,
        scene.shapes.len(),
        scene.triangle_count(),
        scene.lights.len(),
        scene.materials.len()
    );
    println!(
        "camera: f = {:.2} mm, film at {:.3} mm, field of view {:.2} x {:.2} deg, {}",
        camera.focal_length_mm,
        camera.film_distance_mm,
        fov[0],
        fov[1],
        if camera.is_pinhole() {
            "pinhole".to_string()
        } else {
            format!("f/{}", camera.f_number)
        }
    );
    if let Focus::Points(_) = camera.focus {
        let m = &camera.movements;
        println!(
            "focus_points: solved lens tilt {:.4} deg, lens swing {:.4} deg, film distance {:.4} mm",
            m.lens_tilt, m.lens_swing, camera.film_distance_mm
        );
    }
    println!(
        "BVH: {} nodes, depth {}, built in {:.1} ms",
        flat.nodes.len(),
        flat.bvh_depth,
        flat.build_time.as_secs_f64() * 1e3
    );
    Ok(ExitCode::SUCCESS)
}

fn run_camera(
    path: &std::path::Path,
    coc: Option<f64>,
    far: f64,
    overrides: &[String],
) -> anyhow::Result<ExitCode> {
    let scene = load(path, overrides)?;
    let camera = &scene.camera;
    let coc = coc.unwrap_or_else(|| camera.film_mm[0].hypot(camera.film_mm[1]) / 1500.0);
    if !(coc.is_finite() && coc > 0.0) {
        bail!("--coc must be a positive number of millimetres, got {coc}");
    }
    if !(far.is_finite() && far > 0.0) {
        bail!("--far must be a positive distance, got {far}");
    }
    print!("{}", camera_report(camera, coc, far));
    Ok(ExitCode::SUCCESS)
}

fn run_info() -> anyhow::Result<ExitCode> {
    let adapters = describe_adapters();
    if adapters.is_empty() {
        println!("no GPU adapter found (Vulkan, Metal or DX12); renders fall back to the CPU");
    }
    for a in adapters {
        println!("{a}");
    }
    Ok(ExitCode::SUCCESS)
}

/// A progress bar with ETA on a terminal; a log line every 10% otherwise.
fn progress_reporter() -> Box<dyn Progress> {
    if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(0).with_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% {elapsed_precise} ETA {eta}",
            )
            .expect("valid template"),
        );
        Box::new(move |done: u64, total: u64| {
            bar.set_length(total);
            bar.set_position(done);
            if done == total {
                bar.finish_and_clear();
            }
        })
    } else {
        let mut last_decile = 0;
        Box::new(move |done: u64, total: u64| {
            let decile = done * 10 / total.max(1);
            if decile > last_decile {
                last_decile = decile;
                eprintln!("progress: {}% ({done}/{total} tiles)", decile * 10);
            }
        })
    }
}

fn run_render(
    path: &std::path::Path,
    output_path: &std::path::Path,
    choice: BackendChoice,
    overrides: &[String],
) -> anyhow::Result<ExitCode> {
    let scene = load(path, overrides)?;
    let flat = flatten(&scene);
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .context("installing the Ctrl-C handler")?;
    let mut progress = progress_reporter();
    let gpu = match choice {
        BackendChoice::Cpu => None,
        BackendChoice::Gpu => Some(GpuContext::new()?),
        BackendChoice::Auto => match GpuContext::new() {
            Ok(context) => Some(context),
            Err(e) => {
                eprintln!("notice: {e}; rendering on the CPU");
                None
            }
        },
    };
    let (output, backend_name) = match gpu {
        Some(context) => {
            let mut renderer = GpuRenderer::new(context, &flat)?;
            let name = format!("GPU: {}", renderer.adapter_description());
            (
                render(&flat, &mut renderer, progress.as_mut(), &cancel)?,
                name,
            )
        }
        None => {
            let mut renderer = CpuRenderer::new(&flat);
            let name = format!("CPU: {} threads", rayon::current_num_threads());
            (
                render(&flat, &mut renderer, progress.as_mut(), &cancel)?,
                name,
            )
        }
    };
    finish(output, output_path, &backend_name)
}

fn finish(output: RenderOutput, path: &std::path::Path, backend: &str) -> anyhow::Result<ExitCode> {
    let bad = output.image.non_finite_count();
    if bad > 0 {
        bail!(
            "{bad} pixels are not finite numbers: refusing to write {}",
            path.display()
        );
    }
    if output.samples_per_pixel > 0 {
        write_image(&output.image, path)?;
    }
    eprintln!(
        "{}: {}x{}, {} spp in {:.2} s, {:.2} Mrays/s ({} rays) on {backend}",
        path.display(),
        output.image.width,
        output.image.height,
        output.samples_per_pixel,
        output.elapsed.as_secs_f64(),
        output.rays_per_second() / 1e6,
        output.rays
    );
    if output.truncated_paths > 0 {
        eprintln!(
            "note: {} mirror paths were cut off at max_depth",
            output.truncated_paths
        );
    }
    if let Some(reason) = describe_status_flags(output.status_flags) {
        bail!("the render kernel reported a problem: {reason}");
    }
    match output.stopped {
        None => Ok(ExitCode::SUCCESS),
        Some(e @ Error::Interrupted { .. }) => {
            eprintln!("error: {e}; wrote the partial image");
            Ok(ExitCode::from(130))
        }
        Some(e) => bail!(
            "{e}; wrote the partial image ({} spp)",
            output.samples_per_pixel
        ),
    }
}
