//! The `chambre` command line: render, check, camera, info. Errors become one message and exit
//! code 1; a render stopped by SIGINT, SIGTERM or SIGHUP writes what it computed and exits with
//! 130 (the handler cannot tell the three apart, so they share the code of Ctrl-C).

use std::fmt::Write as _;
use std::io::{ErrorKind, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};

use chambre::camera::Focus;
use chambre::camera::report::{camera_report, camera_summary};
use chambre::cpu::CpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::gpu::{GpuContext, GpuRenderer, describe_adapters};
use chambre::output::{Display, ImageFormat, OutputTarget, Protected, ToneMap};
use chambre::pack::{FlatScene, flatten};
use chambre::render::{
    Backend, Progress, RenderOutput, describe_status_flags, render, render_until,
};
use chambre::scene::Scene;
use chambre::shard::{Manifest, Shard};
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
    Render(RenderArgs),
    /// Print what the camera does: field of view, plane of sharp focus, hinge and Scheimpflug
    /// lines, depth of field, and the equivalent raster projection matrix.
    Camera {
        /// Scene file (TOML; see docs/scene-format.md).
        scene: PathBuf,
        /// Circle of confusion in mm for the depth of field (default: film diagonal / 1500).
        #[arg(long)]
        coc: Option<f64>,
        /// Far clipping distance of the raster projection, in scene units; beyond the near plane.
        #[arg(long, default_value_t = 1000.0)]
        far: f64,
        /// Override any scene field, e.g. --set camera.lens_tilt=5 (also -D).
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Parse and validate a scene without rendering.
    Check {
        /// Scene file (TOML; see docs/scene-format.md).
        scene: PathBuf,
        /// Override any scene field, e.g. --set render.spp=64 (also -D).
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Draw a scene fast with the GPU's raster pipeline through the view camera's projection
    /// (film tilt, swing and shift as the ray tracer has them; curved mirrors reflect by
    /// Fermat's principle; shadows by shadow maps with --shadows; no other reflections or
    /// depth of field) and report the frame time.
    Preview {
        /// Scene file (TOML or glTF; see docs/scene-format.md).
        scene: PathBuf,
        /// Image to write: .png, .exr or .pfm (required without --window).
        #[arg(short, long, required_unless_present = "window")]
        output: Option<PathBuf>,
        /// Replace the image even where it is a write-protected file (refused otherwise).
        #[arg(long, requires = "output")]
        force: bool,
        /// Timed frames after a warm-up; the median is reported.
        #[arg(long, value_parser = chambre::bench::positive(), default_value_t = 5)]
        frames: u32,
        /// Open a window to compose the shot: arrows tilt and swing the film, i/k and j/l
        /// shift it, a/d pan and w/x pitch the camera, r resets, s saves the scene, q quits;
        /// a drag with the left button turns the camera, with the right button the film, and
        /// the wheel shifts the film.
        #[arg(long)]
        window: bool,
        /// With --window: keys to replay after the first frame, then close (e.g. "up,up,l,s"):
        /// up, down, left, right, escape, or one character.
        #[arg(long, value_delimiter = ',', requires = "window")]
        keys: Vec<String>,
        /// With --window: write the last frame shown here when the window closes.
        #[arg(long, requires = "window")]
        screenshot: Option<PathBuf>,
        /// With --window: where `s` saves the composed scene (default: beside the scene,
        /// NAME.composed.toml, so its relative mesh paths still hold).
        #[arg(long, requires = "window")]
        save: Option<PathBuf>,
        /// Curved mirrors' Fermat reflections: pieces each reflected triangle's edge is cut
        /// into (default: enough that none is longer than 1/16 of the scene's radius).
        #[arg(long, value_parser = chambre::bench::positive())]
        subdivision: Option<u32>,
        /// Curved mirrors' Fermat reflections: the search's steps at most (1 to 1000).
        #[arg(long, value_parser = chambre::bench::fermat_steps(), default_value_t = chambre::preview::PreviewOptions::default().steps)]
        fermat_steps: u32,
        /// How far (pixels on the film) the triangles of a curved shape (sphere, torus,
        /// ellipsoid, cylinder, Bézier patch) may stray from it: each is cut as coarsely as
        /// that allows, for the camera that sees it.
        #[arg(long, value_parser = chambre::bench::tolerance_px, default_value_t = chambre::preview::DEFAULT_TOLERANCE_PX)]
        tessellation_tolerance: f64,
        /// Shadows from every light, by shadow maps (1024 texels square, smaller beyond four
        /// lights; drawn once; hard, as from a point: an area light's from its centre).
        #[arg(long)]
        shadows: bool,
        /// With --shadows: an area light's shadow maps stand at the centres of N x N strata of
        /// it (N² cubes), for soft shadows; 1 is its centre.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8), default_value_t = 1, requires = "shadows")]
        area_shadow_samples: u32,
        /// Curved mirrors that can see themselves (a torus, a teapot) reflect their own
        /// triangles, cut for this tolerance (pixels on the film; the flag alone: 2), at the
        /// cost of their Fermat solves (a teapot's 32 patches each solve every vertex).
        #[arg(long, value_parser = chambre::bench::tolerance_px, num_args = 0..=1, default_missing_value = chambre::preview::SELF_REFLECTION_TOLERANCE_PX)]
        self_reflections: Option<f64>,
        /// Override any scene field, e.g. --set camera.film_tilt=10 (also -D).
        #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// List the GPU adapters found and their relevant limits.
    Info,
    /// Put the shards of a render (`render --shard I/N`) back together, bit-identical to one
    /// render of the whole image.
    Merge {
        /// Every shard's manifest (`*.shard-I-of-N.json`).
        #[arg(required = true)]
        manifests: Vec<PathBuf>,
        /// The image to write (.png, .exr or .pfm).
        #[arg(short, long)]
        output: PathBuf,
        /// Replace the output even where it is a write-protected file (refused otherwise).
        #[arg(long)]
        force: bool,
    },
    /// Measure: the figures of BENCHMARKS.md, as a table and optionally JSON.
    #[command(subcommand)]
    Bench(chambre::bench::BenchCommand),
    /// The speed–accuracy trade of a scene: error against a reference (RMSE, relative MSE,
    /// FLIP) at 1, 2, 4, … samples per pixel for each sample pattern and backend, as a CSV and a
    /// log-log plot with each curve's convergence slope.
    Converge(chambre::converge::ConvergeArgs),
    /// Write a scene for another renderer: `--mitsuba OUT.xml`, Mitsuba 3's XML with meshes as
    /// PLY files beside it; what Mitsuba cannot express is refused by name (docs/mitsuba.md).
    Export(chambre::export::ExportArgs),
}

/// `eprintln!` that cannot panic: when stderr is closed (`chambre render ... 2>&1 | head -c1`)
/// there is nowhere left to report to, and a render must still write its image.
macro_rules! note {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Image to write: .png (sRGB, 8 bits, clamped) or .exr (linear floats).
    #[arg(short, long)]
    output: PathBuf,
    /// Samples per pixel (overrides render.spp).
    #[arg(long)]
    spp: Option<u32>,
    /// Image width in pixels (overrides render.width); given alone, the height follows the
    /// film's aspect.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (overrides render.height); given alone, the width follows the
    /// film's aspect.
    #[arg(long)]
    height: Option<u32>,
    /// Seed of every random number of the render (overrides render.seed).
    #[arg(long)]
    seed: Option<u32>,
    /// Where to render.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    backend: BackendChoice,
    /// How the GPU runs the paths: `auto` (the wavefront render on a real GPU, the megakernel
    /// on a CPU adapter such as lavapipe), `megakernel` or `wavefront`.
    #[arg(long, value_enum, default_value_t = KernelChoice::Auto)]
    gpu_kernels: KernelChoice,
    /// Worker threads of the CPU path (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Pixel sample pattern (overrides render.pixel_sampler).
    #[arg(long, value_enum)]
    pixel_sampler: Option<chambre::sampler::SamplerName>,
    /// Lens sample pattern (overrides camera.lens_sampler).
    #[arg(long, value_enum)]
    lens_sampler: Option<chambre::sampler::SamplerName>,
    /// Override any scene field, e.g. --set camera.f_number=2.8 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Print statistics: rays, wall, kernel and host time, dispatches and batches, the BVH,
    /// and the features the code was specialised to.
    #[arg(long)]
    stats: bool,
    /// Exposure of an 8-bit image in stops: linear values are scaled by 2^EV before tone
    /// mapping (float formats keep the radiance as rendered).
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        value_name = "EV"
    )]
    exposure: f32,
    /// How an 8-bit image maps radiance to [0, 1].
    #[arg(long, value_enum, default_value_t = ToneMap::Clamp)]
    tonemap: ToneMap,
    /// Also write OUT.json: the command, scene hash, seed, samples reached, backend and
    /// timings, to reproduce the image.
    #[arg(long)]
    sidecar: bool,
    /// A fast preview: a quarter of each image side and a sixteenth of the samples (after
    /// the other flags).
    #[arg(long)]
    quick: bool,
    /// Render only this window of the image, as fractions in [0, 1] (pbrt's crop window;
    /// overrides render.crop); the image written is the window.
    #[arg(long, value_delimiter = ',', value_name = "X0,X1,Y0,Y1")]
    crop: Option<Vec<f64>>,
    /// Also write these layers into the EXR image, as named channels: depth (depth.Z), normal
    /// (normal.X/Y/Z), albedo (albedo.R/G/B) of each camera ray's first hit, averaged over the
    /// pixel's samples, and samples (samples.Y), the samples each pixel received.
    #[arg(long, value_enum, value_delimiter = ',', value_name = "AOV,...")]
    aov: Vec<chambre::output::Aov>,
    /// Also write the samples each pixel received as an image (.exr or .pfm: the count in
    /// every channel), to see where they went.
    #[arg(long, value_name = "FILE")]
    sample_counts: Option<PathBuf>,
    /// Stop after this many seconds (the batches in flight finish) and write the image with
    /// the samples each pixel received: a time instead of a sample count (`--spp` is then the
    /// most taken).
    #[arg(long, value_name = "SECONDS")]
    time_budget: Option<f64>,
    /// Adaptive sampling: keep sampling only the pixels whose estimated error (the difference of
    /// two half-images over the root of the intensity, as Cycles' noise threshold) is above X,
    /// until all meet it or --spp (then the maximum) is reached (overrides render.noise_target;
    /// e.g. 0.01).
    #[arg(long, value_name = "X")]
    noise_target: Option<f64>,
    /// Samples every pixel receives before adaptive sampling's first decision (overrides
    /// render.min_spp; default 16, or --spp when smaller).
    #[arg(long, value_name = "N")]
    min_spp: Option<u32>,
    /// Also write the image every SECONDS during the render (the same path, replaced whole
    /// each time), to look at it and stop the render when it is good enough.
    #[arg(long, value_name = "SECONDS")]
    progressive: Option<f64>,
    /// Render shard I of N (a band of rows) for `chambre merge`: writes OUT's stem with
    /// `.shard-I-of-N.exr` and `.json`. `auto/N` takes I from JOB_COMPLETION_INDEX,
    /// SLURM_ARRAY_TASK_ID or AWS_BATCH_JOB_ARRAY_INDEX.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Replace the files the render writes even where they are write-protected (without it, an
    /// existing write-protected image, sidecar, sample-count image or shard file is refused
    /// before the render starts).
    #[arg(long)]
    force: bool,
}

impl RenderArgs {
    /// The scene overrides the flags stand for, `--set` last. A width or height given alone
    /// gets its partner from the film's aspect, with a note saying so.
    fn overrides(&self) -> Result<Vec<String>> {
        let mut overrides = Vec::new();
        let (width, height) = self.image_size()?;
        let (spp, width, height) = match self.quick {
            true => self.quick_settings(self.spp, width, height)?,
            false => (self.spp, width, height),
        };
        let fields = [
            ("render.spp", spp),
            ("render.width", width),
            ("render.height", height),
            ("render.seed", self.seed),
            ("render.min_spp", self.min_spp),
        ];
        for (key, value) in fields {
            if let Some(v) = value {
                overrides.push(format!("{key}={v}"));
            }
        }
        let samplers = [
            ("render.pixel_sampler", self.pixel_sampler),
            ("camera.lens_sampler", self.lens_sampler),
        ];
        for (key, value) in samplers {
            if let Some(v) = value {
                overrides.push(format!("{key}={}", v.name()));
            }
        }
        if let Some(target) = self.noise_target {
            overrides.push(format!("render.noise_target={target:?}"));
        }
        if let Some(window) = &self.crop {
            let values: Vec<String> = window.iter().map(|v| v.to_string()).collect();
            overrides.push(format!("render.crop=[{}]", values.join(", ")));
        }
        overrides.extend(self.set.iter().cloned());
        Ok(overrides)
    }

    /// `--quick`: a quarter of each side (the height rounded from the width, so the aspect
    /// holds) and a sixteenth of the samples, of the values the flags or the scene give.
    fn quick_settings(
        &self,
        spp: Option<u32>,
        width: Option<u32>,
        height: Option<u32>,
    ) -> Result<(Option<u32>, Option<u32>, Option<u32>)> {
        let render = load(&self.scene, &self.set)?.render;
        let (spp, width, height) = (
            spp.unwrap_or(render.spp),
            width.unwrap_or(render.width),
            height.unwrap_or(render.height),
        );
        let quick_width = width.div_ceil(4).max(1);
        let quick_height =
            ((quick_width as f64 * height as f64 / width as f64).round() as u32).max(1);
        let quick_spp = (spp / 16).max(1);
        note!("note: --quick renders {quick_width}x{quick_height} at {quick_spp} spp");
        Ok((Some(quick_spp), Some(quick_width), Some(quick_height)))
    }

    /// `--width` and `--height` as given, or one of them with the other from the film's aspect.
    fn image_size(&self) -> Result<(Option<u32>, Option<u32>)> {
        let (width, height) = (self.width, self.height);
        if width.is_some() == height.is_some() {
            return Ok((width, height));
        }
        let film = load(&self.scene, &self.set)?.camera.film_mm;
        let aspect = film[0] / film[1];
        let fit = |v: f64| (v.round() as u32).max(1);
        let size = match (width, height) {
            (Some(w), _) => (w, fit(w as f64 / aspect)),
            (_, Some(h)) => (fit(h as f64 * aspect), h),
            _ => unreachable!("exactly one side is given"),
        };
        note!(
            "note: {}x{} pixels keep the film's {} x {} mm aspect",
            size.0,
            size.1,
            film[0],
            film[1]
        );
        Ok((Some(size.0), Some(size.1)))
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendChoice {
    /// A real GPU when it accepts the scene, else the CPU path, with a notice.
    Auto,
    /// The GPU adapter, whatever it is (lavapipe included); a refusal is an error.
    Gpu,
    /// chambre's CPU path.
    Cpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum KernelChoice {
    /// The adapter's best: the wavefront render on a real GPU, the megakernel on a CPU adapter.
    Auto,
    /// One kernel traces each sample's path whole.
    Megakernel,
    /// A kernel per stage of a path vertex, paths and shadow rays in queues.
    Wavefront,
}

impl KernelChoice {
    fn for_adapter(self, context: &GpuContext) -> PathKernels {
        match self {
            KernelChoice::Auto => PathKernels::for_adapter(context.is_cpu_adapter),
            KernelChoice::Megakernel => PathKernels::Megakernel,
            KernelChoice::Wavefront => PathKernels::Wavefront,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(&args),
        Command::Check { scene, set } => run_check(&scene, &set),
        Command::Bench(command) => run_bench(&command),
        Command::Converge(args) => run_converge(&args),
        Command::Export(args) => run_export(&args),
        Command::Camera {
            scene,
            coc,
            far,
            set,
        } => run_camera(&scene, coc, far, &set),
        Command::Preview {
            scene,
            output,
            force,
            frames,
            window,
            keys,
            screenshot,
            save,
            subdivision,
            fermat_steps,
            tessellation_tolerance,
            shadows,
            area_shadow_samples,
            self_reflections,
            set,
        } => {
            let options = chambre::preview::PreviewOptions {
                tolerance_px: tessellation_tolerance,
                subdivision,
                steps: fermat_steps,
                shadows,
                area_shadow_samples,
                self_reflections,
                ..Default::default()
            };
            match (window, output) {
                (true, _) => run_window(&scene, &set, &keys, screenshot, save, options),
                (false, Some(output)) => {
                    let target = (output.as_path(), Protected::replaced_if(force));
                    run_preview(&scene, target, frames, &set, options)
                }
                (false, None) => unreachable!("clap requires --output without --window"),
            }
        }
        Command::Info => run_info(),
        Command::Merge {
            manifests,
            output,
            force,
        } => run_merge(&manifests, &output, Protected::replaced_if(force)),
    };
    match result {
        Ok(code) => code,
        // Whoever read stdout stopped reading (`chambre check x | head -c1`): not a failure.
        Err(e) if e.is::<StdoutClosed>() => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// stdout's reader closed it before the report was out; the command ends quietly.
#[derive(Debug)]
struct StdoutClosed;

impl std::fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stdout was closed by its reader")
    }
}

impl std::error::Error for StdoutClosed {}

/// Writes a command's report to stdout: a closed pipe becomes [`StdoutClosed`], any other
/// failure (`> /dev/full`) an error.
fn print(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Err(StdoutClosed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("writing to stdout")),
    }
}

fn load(path: &Path, overrides: &[String]) -> Result<Scene> {
    Scene::load(path, overrides)
}

/// Loads the scene a command works on, and says what loading left out (a glTF's textures).
fn load_and_note(path: &Path, overrides: &[String]) -> Result<Scene> {
    let scene = load(path, overrides)?;
    for w in scene.warnings() {
        note!("warning: {w}");
    }
    for n in scene.notes() {
        note!("note: {n}");
    }
    Ok(scene)
}

fn run_converge(args: &chambre::converge::ConvergeArgs) -> anyhow::Result<ExitCode> {
    use chambre::output::OutputTarget;
    // Every output is checked before the first render, and written whole or not at all.
    let (plots, protected) = (args.plots(), Protected::replaced_if(args.force));
    OutputTarget::prepare_beside_with(&args.csv, protected)?;
    for plot in &plots {
        OutputTarget::prepare_beside_with(plot, protected)?;
    }
    let study = chambre::converge::run(args)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    OutputTarget::write_beside(&args.csv, study.to_csv(&command).as_bytes())?;
    for plot in &plots {
        let bytes = chambre::plot::figure_bytes(&study, plot)
            .map_err(|e| anyhow::anyhow!("{}: {e}", plot.display()))?;
        OutputTarget::write_beside(plot, &bytes)?;
    }
    let written: Vec<String> = std::iter::once(&args.csv)
        .chain(&plots)
        .map(|p| p.display().to_string())
        .collect();
    note!("wrote {}", written.join(", "));
    print(&study.to_markdown())?;
    Ok(ExitCode::SUCCESS)
}

fn run_export(args: &chambre::export::ExportArgs) -> anyhow::Result<ExitCode> {
    let scene = load_and_note(&args.scene, &args.set)?;
    let export = chambre::export::run(&scene, args)?;
    for n in &export.notes {
        note!("note: {n}");
    }
    let files = export.files.len();
    print(&format!(
        "{}: Mitsuba 3 scene (integrator `{}`, sampler `{}`), {files} {} beside it\n",
        args.mitsuba.display(),
        export.integrator,
        export.sampler,
        if files == 1 { "file" } else { "files" }
    ))?;
    Ok(ExitCode::SUCCESS)
}

fn run_bench(command: &chambre::bench::BenchCommand) -> anyhow::Result<ExitCode> {
    print(&chambre::bench::run(command)?)?;
    Ok(ExitCode::SUCCESS)
}

fn run_check(path: &Path, overrides: &[String]) -> anyhow::Result<ExitCode> {
    let scene = load_and_note(path, overrides)?;
    let flat = flatten(&scene);
    let camera = &scene.camera;
    let mut text = String::new();
    writeln!(
        text,
        "{}: ok: {}x{} at {} spp, {} shapes ({} triangles), {} lights, {} materials",
        path.display(),
        scene.render.width,
        scene.render.height,
        scene.render.spp,
        scene.shapes.len(),
        scene.triangle_count(),
        scene.lights.len(),
        scene.materials.len()
    )?;
    writeln!(text, "{}", camera_summary(camera))?;
    if let Focus::Points(_) = camera.focus {
        let m = &camera.movements;
        writeln!(
            text,
            "focus_points: solved lens tilt {:.4} deg, lens swing {:.4} deg, film distance {:.4} mm",
            m.lens_tilt, m.lens_swing, camera.film_distance_mm
        )?;
    }
    writeln!(
        text,
        "BVH: {} nodes, depth {}, built in {:.1} ms",
        flat.nodes.len(),
        flat.bvh_depth,
        flat.build_time.as_secs_f64() * 1e3
    )?;
    print(&text)?;
    Ok(ExitCode::SUCCESS)
}

fn run_camera(
    path: &Path,
    coc: Option<f64>,
    far: f64,
    overrides: &[String],
) -> anyhow::Result<ExitCode> {
    let scene = load_and_note(path, overrides)?;
    let camera = &scene.camera;
    let coc = coc.unwrap_or_else(|| camera.film_mm[0].hypot(camera.film_mm[1]) / 1500.0);
    if !(coc.is_finite() && coc > 0.0) {
        bail!("--coc must be a positive number of millimetres, got {coc}");
    }
    if !(far.is_finite() && far > 0.0) {
        bail!("--far must be a positive distance, got {far}");
    }
    // The near plane is the lens-to-film distance; a far plane not beyond it makes the
    // projection matrix degenerate (a zero or negative depth range).
    let near = camera.raster_projection(far).frustum.near;
    if far <= near {
        bail!(
            "--far {far} must lie beyond the near plane of the raster projection, at {near:.8} \
             scene units (the lens-to-film distance)"
        );
    }
    print(&camera_report(camera, coc, far))?;
    Ok(ExitCode::SUCCESS)
}

fn run_info() -> anyhow::Result<ExitCode> {
    let adapters = describe_adapters();
    let mut text = String::new();
    if adapters.is_empty() {
        text.push_str(
            "no GPU adapter found (Vulkan, Metal or DX12); renders fall back to the CPU\n",
        );
    }
    for a in adapters {
        writeln!(text, "{a}")?;
    }
    print(&text)?;
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
                note!("progress: {}% ({done}/{total} batches)", decile * 10);
            }
        })
    }
}

fn run_render(args: &RenderArgs) -> anyhow::Result<ExitCode> {
    if let Some(threads) = args.threads {
        if threads == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("starting the CPU path's threads")?;
    }
    let (path, output_path, choice, stats) = (&args.scene, &args.output, args.backend, args.stats);
    if !args.exposure.is_finite() {
        bail!(
            "--exposure must be a finite number of stops, got {}",
            args.exposure
        );
    }
    let overrides = args.overrides()?;
    let mut scene = load_and_note(path, &overrides)?;
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(|e| anyhow::anyhow!("--shard {e}"))?;
    let shard_paths = shard.map(|s| s.paths(output_path));
    let full_crop = scene.render.crop;
    if let Some(shard) = shard {
        scene.render.crop = shard.rows(full_crop);
    }
    let output_path = shard_paths
        .as_ref()
        .map_or(output_path.as_path(), |(image, _)| image);
    // Before any render time is spent: a path that cannot take the image fails now.
    let protected = Protected::replaced_if(args.force);
    let target = OutputTarget::prepare_with(output_path, protected)?.with_display(Display {
        exposure_ev: args.exposure,
        tone_map: args.tonemap,
    });
    let counts_target = match &args.sample_counts {
        Some(path) => {
            let target = OutputTarget::prepare_with(path, protected)?;
            if !target.format().is_linear() {
                bail!(
                    "--sample-counts {}: use .exr or .pfm (counts are not colours)",
                    path.display()
                );
            }
            Some(target)
        }
        None => None,
    };
    let sidecar_path = args.sidecar.then(|| sidecar_path(output_path));
    for beside in sidecar_path
        .iter()
        .chain(shard_paths.as_ref().map(|(_, m)| m))
    {
        OutputTarget::prepare_beside_with(beside, protected)?;
    }
    if !args.aov.is_empty() {
        if target.format() != chambre::output::ImageFormat::Exr {
            bail!("--aov writes layers into an EXR: give -o an .exr path");
        }
        if shard.is_some() {
            bail!("--aov with --shard: shards merge the image only, not its AOV layers");
        }
    }
    let mut flat = flatten(&scene);
    flat.aovs = args.aov.iter().any(|a| a.needs_first_hits());
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    // With ctrlc's `termination` feature this also catches SIGTERM and SIGHUP, what `kill` and
    // batch schedulers send, so they too stop the render and keep its image.
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .context("installing the SIGINT/SIGTERM/SIGHUP handler")?;
    let mut progress = progress_reporter();
    // With a time budget the render stops, successfully, at the deadline.
    let deadline = match args.time_budget {
        Some(seconds) if !(seconds.is_finite() && seconds > 0.0) => {
            bail!("--time-budget must be a positive number of seconds, got {seconds}")
        }
        Some(seconds) => Some(Instant::now() + Duration::from_secs_f64(seconds)),
        None => None,
    };
    let every = match args.progressive {
        Some(seconds) if !(seconds.is_finite() && seconds > 0.0) => {
            bail!("--progressive must be a positive number of seconds, got {seconds}")
        }
        Some(seconds) => Some(Duration::from_secs_f64(seconds)),
        None => None,
    };
    let run = |backend: &mut dyn Backend, progress: &mut dyn Progress| match (every, deadline) {
        (Some(every), deadline) => {
            let mut write = |image: &chambre::render::Image| target.write(image);
            let snapshots = chambre::render::Snapshots {
                every,
                write: &mut write,
            };
            chambre::render::render_with_snapshots(
                &flat, backend, progress, &cancel, deadline, snapshots,
            )
        }
        (None, Some(deadline)) => render_until(&flat, backend, progress, &cancel, deadline),
        (None, None) => render(&flat, backend, progress, &cancel),
    };
    let (output, backend_name, features) = match gpu_renderer(choice, args.gpu_kernels, &flat)? {
        Some(mut renderer) => {
            let name = format!(
                "GPU: {} ({:?})",
                renderer.adapter_description(),
                renderer.path_kernels()
            );
            let features = renderer.features();
            (run(&mut renderer, progress.as_mut())?, name, features)
        }
        None => {
            let mut renderer = CpuRenderer::new(&flat).with_cancel(&cancel);
            let threads = rayon::current_num_threads();
            let name = format!(
                "CPU: {threads} thread{}",
                if threads == 1 { "" } else { "s" }
            );
            let features = renderer.features();
            (run(&mut renderer, progress.as_mut())?, name, features)
        }
    };
    if stats {
        note!("{}", render_stats(&output, &flat, features));
    }
    let sidecar = sidecar_path.map(|sidecar_path| {
        let record = sidecar_record(args, &scene, &overrides, &output, &backend_name);
        (sidecar_path, record)
    });
    let written = output.max_samples_per_pixel > 0;
    if let Some(target) = &counts_target {
        let (w, h) = (output.image.width, output.image.height);
        target.write(&chambre::render::Image::of_counts(
            w,
            h,
            &output.sample_counts,
        ))?;
    }
    let manifest = match (shard, &shard_paths) {
        (Some(shard), Some((image, _))) => Some(shard_manifest(
            shard, args, &scene, full_crop, image, &overrides, &output,
        )),
        _ => None,
    };
    let channels = chambre::output::aov_channels(&output, &args.aov)
        .map_err(|e| anyhow::anyhow!("{}: {e}", output_path.display()))?;
    let code = finish(output, &target, &backend_name, &channels)?;
    if let (Some(manifest), Some((_, manifest_path)), true) = (manifest, &shard_paths, written) {
        let text = serde_json::to_string_pretty(&manifest).context("encoding the manifest")?;
        OutputTarget::write_beside(manifest_path, (text + "\n").as_bytes())?;
    }
    if let Some((sidecar_path, record)) = sidecar.filter(|_| written) {
        let text = serde_json::to_string_pretty(&record).context("encoding the sidecar")?;
        OutputTarget::write_beside(&sidecar_path, (text + "\n").as_bytes())?;
    }
    Ok(code)
}

/// What a shard's manifest says of its band.
fn shard_manifest(
    shard: Shard,
    args: &RenderArgs,
    scene: &Scene,
    full_crop: [u32; 4],
    image: &Path,
    overrides: &[String],
    output: &RenderOutput,
) -> Manifest {
    let mut identity = std::fs::read(&args.scene).unwrap_or_default();
    for o in overrides {
        identity.extend_from_slice(o.as_bytes());
    }
    let [x0, x1, _, _] = full_crop;
    Manifest {
        shard,
        width: scene.render.width,
        height: scene.render.height,
        band: [x0, x1, scene.render.crop[2], scene.render.crop[3]],
        image: image
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned()),
        render_hash: format!("{:016x}", chambre::provenance::fnv1a64(&identity)),
        spp_min: output.samples_per_pixel,
        spp_max: output.max_samples_per_pixel,
    }
}

/// `chambre preview`: the raster preview, written atomically, with its frame time.
/// Tells the user what the preview of `scene` drawn with `options` cannot show.
fn note_what_the_preview_leaves_out(
    scene: &chambre::scene::Scene,
    flat: &chambre::pack::FlatScene,
    options: &chambre::preview::PreviewOptions,
) {
    let shadows = options.shadows.then_some(options.area_shadow_samples);
    for omission in chambre::preview::omissions(scene, shadows) {
        note!("note: {omission}");
    }
    if options.self_reflections.is_some()
        && let Some(note) = chambre::preview::self_reflections_note(flat)
    {
        note!("note: {note}");
    }
}

fn run_preview(
    path: &Path,
    (output, protected): (&Path, Protected),
    frames: u32,
    overrides: &[String],
    options: chambre::preview::PreviewOptions,
) -> anyhow::Result<ExitCode> {
    let target = OutputTarget::prepare_with(output, protected)?;
    let scene = load_and_note(path, overrides)?;
    let flat = flatten(&scene);
    note_what_the_preview_leaves_out(&scene, &flat, &options);
    let context = chambre::gpu::GpuContext::new()?;
    let frame = chambre::preview::draw_with(&context, &scene, &flat, frames, options)?;
    target.write(&frame.image)?;
    if frame.coarse_shapes > 0 {
        let note = chambre::preview::coarse_note(frame.coarse_shapes, options.tolerance_px);
        note!("{note}");
    }
    let reflected = match frame.reflected_triangles {
        0 => String::new(),
        n => format!(" and {n} reflected ({} drawn)", frame.reflected_drawn),
    };
    let shadows = match frame.shadow_maps {
        (0, ..) => String::new(),
        (maps, side, time) => format!(
            ", {maps} shadow map(s) of {side}x{side} drawn once in {:.2} ms",
            time.as_secs_f64() * 1e3
        ),
    };
    let curved = match frame.curved_shapes {
        0 => String::new(),
        n => format!(
            " ({n} curved shape(s) cut for a tolerance of {} px)",
            options.tolerance_px
        ),
    };
    note!(
        "{}: {}x{}, {} triangles{curved}{reflected} in {:.2} ms a frame (median of {frames}, drawn and \
         finished on the device, read-back excluded{shadows}) on {}",
        output.display(),
        frame.image.width,
        frame.image.height,
        frame.triangles,
        frame.frame_time.as_secs_f64() * 1e3,
        context.adapter_description
    );
    Ok(ExitCode::SUCCESS)
}

/// `chambre preview --window`: the interactive preview until the window closes.
fn run_window(
    path: &Path,
    overrides: &[String],
    keys: &[String],
    screenshot: Option<PathBuf>,
    save: Option<PathBuf>,
    drawing: chambre::preview::PreviewOptions,
) -> anyhow::Result<ExitCode> {
    let keys = keys
        .iter()
        .map(|k| {
            chambre::preview::window::ComposeKey::parse(k).ok_or_else(|| {
                anyhow::anyhow!(
                    "--keys: `{k}` is not a key (up, down, left, right, escape, or one character)"
                )
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        anyhow::bail!(
            "--window composes a TOML scene, saving the composition into a copy of it; {} is not \
             one",
            path.display()
        );
    }
    let save = save.unwrap_or_else(|| path.with_extension("composed.toml"));
    let scene = load_and_note(path, overrides)?;
    let flat = flatten(&scene);
    note_what_the_preview_leaves_out(&scene, &flat, &drawing);
    let options = chambre::preview::window::WindowOptions {
        keys,
        screenshot: screenshot.clone(),
        save,
        drawing,
    };
    let report = chambre::preview::window::run(path, overrides, &scene, &flat, options)?;
    note!(
        "{} frames shown; composition: {}",
        report.frames,
        report.overrides.join(" ")
    );
    if let Some(screenshot) = screenshot {
        note!("{}: the last frame shown", screenshot.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `chambre merge`: the shards' bands stacked into one image, written atomically.
fn run_merge(
    manifests: &[PathBuf],
    output: &Path,
    protected: Protected,
) -> anyhow::Result<ExitCode> {
    let target = OutputTarget::prepare_with(output, protected)?;
    let image = chambre::shard::merge(manifests)?;
    target.write(&image)?;
    note!(
        "{}: {}x{} from {} shards",
        output.display(),
        image.width,
        image.height,
        manifests.len()
    );
    Ok(ExitCode::SUCCESS)
}

/// `OUT.json` beside `OUT` (the image's own extension kept, so `a.png` and `a.exr` do not
/// share one).
fn sidecar_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".json");
    PathBuf::from(name)
}

/// What `--sidecar` records of a render.
fn sidecar_record(
    args: &RenderArgs,
    scene: &Scene,
    overrides: &[String],
    output: &RenderOutput,
    backend: &str,
) -> chambre::provenance::Sidecar {
    use chambre::provenance::{Sidecar, fnv1a64, utc_date};
    let scene_bytes = std::fs::read(&args.scene).unwrap_or_default();
    Sidecar {
        chambre_version: env!("CARGO_PKG_VERSION"),
        date_utc: utc_date(),
        command: std::env::args().collect(),
        scene: args.scene.display().to_string(),
        scene_hash: format!("{:016x}", fnv1a64(&scene_bytes)),
        overrides: overrides.to_vec(),
        seed: scene.render.seed,
        width: output.image.width,
        height: output.image.height,
        spp_requested: scene.render.spp,
        spp_min: output.samples_per_pixel,
        spp_max: output.max_samples_per_pixel,
        backend: backend.to_string(),
        wall_seconds: output.elapsed.as_secs_f64(),
        kernel_seconds: output.kernel_time.map(|k| k.as_secs_f64()),
        rays: output.rays,
        status: match &output.stopped {
            None => "complete".into(),
            Some(e) => e.to_string(),
        },
    }
}

/// `--stats`: where the time and the rays went.
fn render_stats(output: &RenderOutput, flat: &FlatScene, features: u32) -> String {
    let wall = output.elapsed.as_secs_f64();
    let kernels = match output.kernel_time {
        Some(k) => format!(
            "kernels {:.3} s (timestamps), host and waits {:.3} s",
            k.as_secs_f64(),
            (wall - k.as_secs_f64()).max(0.0)
        ),
        None => "kernel time not measured (no timestamp queries here)".to_string(),
    };
    let named: Vec<&str> = chambre::layout::FEATURES
        .iter()
        .filter(|(_, bit)| features & bit != 0)
        .map(|(name, _)| name.trim_start_matches("FEATURE_"))
        .collect();
    format!(
        "stats: {} rays ({:.2} Mrays/s), {} paths cut at max_depth\n\
         stats: wall {wall:.3} s; {kernels}\n\
         stats: {} dispatches in {} batches\n\
         stats: BVH {} nodes, depth {}, {:.1} expected loop iterations per ray, built in {:.1} ms; \
         {} primitives ({} triangles)\n\
         stats: code specialised to features {features:#x} ({})",
        output.rays,
        output.rays_per_second() / 1e6,
        output.truncated_paths,
        output.dispatches,
        output.batches,
        flat.nodes.len(),
        flat.bvh_depth,
        flat.traversal_iterations,
        flat.build_time.as_secs_f64() * 1e3,
        flat.prims.len(),
        flat.triangle_count,
        named.join(", ")
    )
}

/// The GPU renderer the choice asks for. `auto` takes the CPU, with a notice, when the only
/// adapter is a CPU implementation of the API (chambre's own CPU path is 2.5-5x faster than
/// lavapipe: BENCHMARKS.md), and whenever the GPU refuses: no adapter, a buffer over a binding
/// limit.
fn gpu_renderer(
    choice: BackendChoice,
    kernels: KernelChoice,
    flat: &FlatScene,
) -> Result<Option<GpuRenderer>> {
    let renderer = |context: GpuContext| {
        let kernels = kernels.for_adapter(&context);
        GpuRenderer::with_kernels(context, flat, flat.features(), kernels)
    };
    match choice {
        BackendChoice::Cpu => Ok(None),
        BackendChoice::Gpu => GpuContext::new().and_then(renderer).map(Some),
        BackendChoice::Auto => {
            let context = match GpuContext::new() {
                Ok(context) if context.is_cpu_adapter => {
                    note!(
                        "notice: the only GPU adapter, {}, runs on the CPU; chambre's CPU path is \
                         faster here, so it renders (--backend gpu uses the adapter)",
                        context.adapter_name
                    );
                    return Ok(None);
                }
                Ok(context) => context,
                Err(e) => {
                    note!("notice: {e}; rendering on the CPU");
                    return Ok(None);
                }
            };
            match renderer(context) {
                Ok(renderer) => Ok(Some(renderer)),
                Err(e) => {
                    note!("notice: {e}; rendering on the CPU");
                    Ok(None)
                }
            }
        }
    }
}

/// Writes what the render computed, reports it, and picks the exit code: 1 when anything went
/// wrong (the image is still written), else 130 when the render was stopped by a signal.
/// Writes the image (with `channels`, the AOV layers, when there are any) and reports.
fn finish(
    output: RenderOutput,
    target: &OutputTarget,
    backend: &str,
    channels: &[(String, Vec<f32>)],
) -> anyhow::Result<ExitCode> {
    let path = target.path().display();
    let written = output.max_samples_per_pixel > 0;
    if written {
        target.write_with_channels(&output.image, channels)?;
    }
    let kernel = output.kernel_time.map_or(String::new(), |k| {
        format!(" (kernels {:.2} s)", k.as_secs_f64())
    });
    note!(
        "{path}: {}x{}, {} in {:.2} s{kernel}, {:.2} Mrays/s ({} rays) on {backend}",
        output.image.width,
        output.image.height,
        describe_samples(&output),
        output.elapsed.as_secs_f64(),
        output.rays_per_second() / 1e6,
        output.rays
    );
    if output.snapshots > 0 {
        note!(
            "note: {path} was also written {} times during the render (--progressive)",
            output.snapshots
        );
    }
    if let Some(adaptive) = &output.adaptive {
        note!("{}", adaptive.summary());
    }
    if output.deadline_reached {
        note!(
            "note: the time budget was spent after {:.2} s: {} per pixel",
            output.elapsed.as_secs_f64(),
            describe_samples(&output)
        );
    }
    if output.truncated_paths > 0 {
        note!(
            "note: {} mirror paths were cut off at max_depth",
            output.truncated_paths
        );
    }
    let mut failed = false;
    let non_finite = output.image.non_finite_count();
    if non_finite > 0 {
        let shown = match (written, target.format()) {
            (false, _) => "",
            (true, ImageFormat::Png) => "; written as magenta in the PNG",
            (true, ImageFormat::Exr) => "; kept as inf/NaN in the EXR",
            (true, ImageFormat::Pfm) => "; kept as inf/NaN in the PFM",
        };
        note!("error: {non_finite} pixels are not finite numbers{shown}");
        failed = true;
    }
    if let Some(reason) = describe_status_flags(output.status_flags) {
        note!("error: the render kernel reported a problem: {reason}");
        failed = true;
    }
    let outcome = match written {
        true => "wrote the partial image",
        false => "wrote nothing: no pixel had a sample yet",
    };
    match &output.stopped {
        None => {}
        // Its sample count is that of the passes begun; the line above says what the image holds.
        Some(Error::Interrupted { total, .. }) => {
            note!("error: render interrupted before its {total} spp were taken; {outcome}")
        }
        Some(e) => {
            note!("error: {e}; {outcome}");
            failed = true;
        }
    }
    Ok(match (failed, &output.stopped) {
        (true, _) => ExitCode::FAILURE,
        (false, Some(Error::Interrupted { .. })) => ExitCode::from(130),
        (false, _) => ExitCode::SUCCESS,
    })
}

/// "16 spp", or for a stopped render exactly what the image holds.
fn describe_samples(output: &RenderOutput) -> String {
    let (min, max) = (output.samples_per_pixel, output.max_samples_per_pixel);
    let spread = match min == max {
        true => format!("{min} spp"),
        false => format!("{min} to {max} spp per pixel"),
    };
    match output.pixels_without_samples {
        0 => spread,
        n if max == 0 => format!("no samples ({n} pixels), not written"),
        n => format!("{spread}, {n} pixels without a sample (written as black)"),
    }
}
