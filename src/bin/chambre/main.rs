//! The `chambre` command line: render, preview, check, camera, info, merge, bench, converge,
//! export, each in its own file beside this one with its arguments. Errors become one message
//! and exit code 1; a render stopped by SIGINT, SIGTERM or SIGHUP writes what it computed and exits with
//! 130 (the handler cannot tell the three apart, so they share the code of Ctrl-C).

use std::fmt::Write as _;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use clap::{Parser, Subcommand};

use chambre::Result;
use chambre::camera::Focus;
use chambre::camera::lens::{LensSystem, Prescription};
use chambre::camera::report::{camera_report, camera_summary, lens_report};
use chambre::gpu::describe_adapters;
use chambre::pack::flatten;
use chambre::scene::Scene;
use render::RenderArgs;

/// `eprintln!` that cannot panic: when stderr is closed (`chambre render ... 2>&1 | head -c1`)
/// there is nowhere left to report to, and a render must still write its image.
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

mod args;
mod bench;
mod converge;
mod export;
mod preview;
mod render;
mod shard;

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
    /// Print what a lens prescription does (pbrt's tabular format; docs/lens.md): focal length,
    /// focal distances, principal points, pupils and the image circle at an f-number.
    Lens {
        /// Prescription file (radius, thickness, index, aperture per surface, in mm).
        file: PathBuf,
        /// The f-number to stop the lens to (default: the widest it opens to).
        #[arg(long)]
        f_number: Option<f64>,
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
    Preview(preview::PreviewArgs),
    /// List the GPU adapters found and their relevant limits.
    Info,
    /// Put the shards of a render (`render --shard I/N`) back together, bit-identical to one
    /// render of the whole image.
    Merge(shard::MergeArgs),
    /// Measure: the figures of BENCHMARKS.md, as a table and optionally JSON.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// The speed–accuracy trade of a scene: error against a reference (RMSE, relative MSE,
    /// FLIP) at 1, 2, 4, … samples per pixel for each sample pattern and backend, as a CSV and a
    /// log-log plot with each curve's convergence slope.
    Converge(converge::ConvergeArgs),
    /// Write a scene for another renderer: `--mitsuba OUT.xml`, Mitsuba 3's XML with meshes as
    /// PLY files beside it; what Mitsuba cannot express is refused by name (docs/mitsuba.md).
    Export(export::ExportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Check { scene, set } => run_check(&scene, &set),
        Command::Bench(command) => run_bench(&command),
        Command::Converge(args) => converge::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Camera {
            scene,
            coc,
            far,
            set,
        } => run_camera(&scene, coc, far, &set),
        Command::Lens { file, f_number } => run_lens(&file, f_number),
        Command::Preview(args) => preview::run(&args),
        Command::Info => run_info(),
        Command::Merge(args) => shard::run_merge(&args),
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

fn run_bench(command: &bench::BenchCommand) -> anyhow::Result<ExitCode> {
    print(&bench::run(command)?)?;
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
    if !flat.textures.is_empty() {
        writeln!(
            text,
            "textures: {}, {:.1} MiB of texels",
            flat.textures.len(),
            flat.texels.len() as f64 * 4.0 / (1 << 20) as f64
        )?;
    }
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

fn run_lens(path: &Path, f_number: Option<f64>) -> anyhow::Result<ExitCode> {
    let prescription = Prescription::read(path)?;
    let lens = LensSystem::new(&prescription, f_number)
        .map_err(|message| anyhow::anyhow!("{}: {message}", path.display()))?;
    print(&lens_report(&lens))?;
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
