//! `chambre bench`: every figure of `BENCHMARKS.md`, as a Markdown table and as JSON.
//!
//! - [`rays`]: a mesh and a pinhole camera; coherent camera rays and incoherent rays, closest
//!   hit and any hit, Mrays/s with a checksum (hits, sum of hit distances) that another ray
//!   tracer can reproduce on the same rays.
//! - [`build`]: every obvhs build preset on a mesh: time, nodes, depth, SAH cost, memory.
//! - [`frame`]: the sample scenes on each backend, and the GPU kernel specialised to the scene
//!   against the general one.
//! - [`samplers`]: the lens sample patterns' error against samples and time.
//! - [`scale`]: the same rays on meshes from a thousand to ten million triangles.
//! - [`precision`]: f32 hits and pixels of both paths against an f64 oracle.
//! - [`motion`]: motion blur's BVH, swept over the shutter or per time slice.
//!
//! Timings are medians (with min and max) of several runs after a warm-up, measured side by side
//! in one process: machines here are noisy, so only ratios within one run are compared.

pub mod build;
pub mod fermat;
pub mod frame;
pub mod motion;
pub mod precision;
pub mod preview;
pub mod rays;
pub mod samplers;
pub mod scale;

use std::path::PathBuf;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::ShaderChecks;
use crate::gpu::render::PathKernels;
use rays::{Backend, Bvh, Pinhole, RaysConfig};

/// `chambre bench` and its parts.
#[derive(Debug, clap::Subcommand)]
pub enum BenchCommand {
    /// Trace the same coherent and incoherent rays on a mesh: closest hit and any hit, Mrays/s
    /// and a checksum (hits, sum of hit distances) another ray tracer can reproduce.
    Rays(RaysArgs),
    /// Build the BVH of a mesh with every obvhs preset: time, nodes, depth, SAH cost, memory.
    Build(BuildArgs),
    /// Render the sample scenes on each backend, and on the GPU with the kernel specialised to
    /// each scene against the general kernel.
    Frame(FrameArgs),
    /// The lens sample patterns' RMSE against a converged reference, by sample count.
    Samplers(SamplersArgs),
    /// The same camera rays on meshes from a thousand to ten million triangles: build time,
    /// Mrays/s and memory, with a log-log plot.
    Scale(ScaleArgs),
    /// How accurate the f32 hits of both paths are against an f64 oracle, with the mesh far
    /// from the origin, tiny and huge.
    Precision(PrecisionArgs),
    /// Motion blur's BVH: one over boxes swept over the whole shutter against one per time
    /// slice; build time and Mrays/s of the same timed rays, CPU path.
    Motion(MotionArgs),
    /// Fermat reflections in the raster preview against the ray tracer on a curved mirror: frame
    /// times, displacement of reflected features in pixels and FLIP, by subdivision.
    Fermat(FermatArgs),
    /// The raster preview without and with shadows: frame times, the shadow maps' drawing and
    /// FLIP against the ray tracer.
    Preview(PreviewArgs),
}

/// The sample scene named `name`: its file in `scenes/`.
pub fn sample_scene(name: &str) -> PathBuf {
    PathBuf::from("scenes").join(format!("{name}.toml"))
}

/// Arguments of `chambre bench preview`.
#[derive(Debug, clap::Args)]
pub struct PreviewArgs {
    /// Scenes of `scenes/`, by name.
    #[arg(long, value_delimiter = ',', default_values_t = ["tabletop".to_string(), "spheres".to_string(), "bunny".to_string(), "architecture".to_string(), "cornell_direct".to_string()])]
    pub scenes: Vec<String>,
    /// Timed frames each way after a warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 21)]
    pub frames: u32,
    /// Samples per pixel of the ray-traced reference for FLIP.
    #[arg(long, value_parser = positive(), default_value_t = 64)]
    pub reference_spp: u32,
    /// Where a scene has area lights, a third preview with their shadow maps at N x N points
    /// of each (1: none).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8), default_value_t = 3)]
    pub area_shadow_samples: u32,
    /// Override any scene field, e.g. --set render.width=640 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Arguments of `chambre bench fermat`.
#[derive(Debug, clap::Args)]
pub struct FermatArgs {
    /// Scene with a curved mirror: a sphere, torus, ellipsoid, cylinder or Bézier shape (the
    /// first is measured).
    #[arg(long, default_value = "scenes/fermat_sphere.toml")]
    pub scene: PathBuf,
    /// Subdivisions of the reflected triangles to compare.
    #[arg(long, value_parser = positive(), value_delimiter = ',', default_values_t = [1, 2, 4, 8, 16, 32])]
    pub subdivisions: Vec<u32>,
    /// The Fermat search's steps at most (1 to 1000).
    #[arg(long, value_parser = fermat_steps(), default_value_t = crate::preview::PreviewOptions::default().steps)]
    pub steps: u32,
    /// Rounds timed after a warm-up: per subdivision, a GPU ray-traced frame then --frames
    /// preview frames (the speed-up is the median of the rounds' ratios); and as many CPU
    /// ray-traced frames.
    #[arg(long, value_parser = positive(), default_value_t = 5)]
    pub runs: u32,
    /// Timed preview frames per round, after a warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 21)]
    pub frames: u32,
    /// Samples per pixel of the ray-traced reference for FLIP.
    #[arg(long, value_parser = positive(), default_value_t = 256)]
    pub reference_spp: u32,
    /// Searches (surfaces: a teapot's 32 patches) solved and culled in one dispatch at most;
    /// by default as many as the bindings hold. 1 measures the preview as it ran before it
    /// batched them.
    #[arg(long, value_parser = at_least_one)]
    pub searches_per_dispatch: Option<usize>,
    /// How far (pixels on the film) the preview's triangles may stray from a curved shape.
    #[arg(long, value_parser = tolerance_px, default_value_t = crate::preview::DEFAULT_TOLERANCE_PX)]
    pub tessellation_tolerance: f64,
    /// A torus or teapot reflects itself, its own triangles cut for this tolerance (pixels on
    /// the film; the flag alone: the preview's default, `preview::SELF_REFLECTION_TOLERANCE_PX`).
    #[arg(long, value_parser = tolerance_px, num_args = 0..=1, default_missing_value = crate::preview::SELF_REFLECTION_TOLERANCE_PX)]
    pub self_reflections: Option<f64>,
    /// Override any scene field, e.g. --set render.width=640 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Arguments of `chambre bench motion`.
#[derive(Debug, clap::Args)]
pub struct MotionArgs {
    /// Mesh file (OBJ, PLY or glTF, optionally .gz).
    #[arg(long, default_value = "scenes/meshes/bunny-npm-lowres.obj")]
    pub mesh: PathBuf,
    /// How far the mesh moves while the shutter is open, in mesh sizes.
    #[arg(long, default_value_t = 0.3)]
    pub travel: f64,
    /// Time slices to compare, each with its own BVH (1: one BVH over the whole shutter).
    #[arg(long, value_parser = positive(), value_delimiter = ',', default_values_t = [1, 2, 4, 8, 16])]
    pub slices: Vec<u32>,
    /// Camera rays: SIZE x SIZE.
    #[arg(long, value_parser = positive(), default_value_t = 256)]
    pub size: u32,
    /// Timed runs after one warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 3)]
    pub runs: u32,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Arguments of `chambre bench precision`.
#[derive(Debug, clap::Args)]
pub struct PrecisionArgs {
    /// Mesh file (OBJ or PLY, optionally .gz).
    #[arg(long, default_value = "scenes/meshes/bunny-npm-lowres.obj")]
    pub mesh: PathBuf,
    /// Camera rays per placement: SIZE x SIZE.
    #[arg(long, value_parser = positive(), default_value_t = 64)]
    pub size: u32,
    /// The camera's height above the mesh's centre, in mesh sizes (it looks along -z from 2.5
    /// sizes away): a small height over a flat mesh in the xz plane makes grazing rays.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub camera_height: f64,
    /// Backends whose hits are compared with the oracle.
    #[command(flatten)]
    pub backends: Backends,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Where a report goes besides the table on stdout.
#[derive(Debug, clap::Args)]
pub struct Output {
    /// Also write the report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The backends a benchmark measures side by side.
#[derive(Debug, clap::Args)]
pub struct Backends {
    /// Backends to measure, side by side.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Backend::Cpu, Backend::Gpu])]
    pub backends: Vec<Backend>,
}

impl Backends {
    /// Whether the GPU is among the backends.
    pub fn gpu(&self) -> bool {
        self.backends.contains(&Backend::Gpu)
    }
}

/// The parser of a `u32` count given on the command line that must be at least 1 (clap says
/// which flag and why, and exits non-zero).
pub fn positive() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

/// The parser of `--fermat-steps` and `bench fermat --steps`: 1 to
/// [`crate::preview::reflections::kernel::MAX_FERMAT_STEPS`].
pub fn fermat_steps() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32)
        .range(1..=i64::from(crate::preview::reflections::kernel::MAX_FERMAT_STEPS))
}

/// A spacing of copies in mesh widths: at least 1, so that they do not overlap.
pub fn at_least_one_width(text: &str) -> std::result::Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 1.0 => Ok(v),
        Ok(_) => Err("must be a finite number of widths, at least 1".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// A count given on the command line that must be at least 1 (a size, a number of runs or
/// copies): 0 would measure nothing and report NaN, or be taken silently as 1.
pub fn at_least_one(text: &str) -> std::result::Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

/// The parser of `--tessellation-tolerance`: a finite number of pixels above 0 (0 would ask
/// every curved shape for its finest grid, and say each strays too far).
pub fn tolerance_px(text: &str) -> std::result::Result<f64, String> {
    match text.parse::<f64>() {
        Ok(px) if px.is_finite() && px > 0.0 => Ok(px),
        Ok(_) => Err("must be a number of pixels above 0".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// The benchmarks' default mesh: 871k triangles, large enough to fill a GPU.
const DRAGON_MESH: &str = "scenes/meshes/dragon_vrip.obj.gz";

/// Arguments of `chambre bench scale`.
#[derive(Debug, clap::Args)]
pub struct ScaleArgs {
    /// Mesh whose prefixes and copies make the sizes.
    #[arg(long, default_value = DRAGON_MESH)]
    pub mesh: PathBuf,
    /// Triangle counts taken from the mesh (larger than the mesh: the whole mesh).
    #[arg(long, value_parser = at_least_one, value_delimiter = ',', default_values_t = scale::PREFIXES)]
    pub prefixes: Vec<usize>,
    /// Copies of the whole mesh side by side.
    #[arg(long, value_parser = at_least_one, value_delimiter = ',', default_values_t = scale::COPIES)]
    pub copies: Vec<usize>,
    /// Image size of the camera rays (one per pixel; the rays benchmark's camera).
    #[arg(long, value_parser = positive(), default_value_t = 512)]
    pub size: u32,
    /// Copies stand this many mesh widths apart (farther, no camera ray reaches the others).
    #[arg(long, default_value_t = 1.1, value_parser = at_least_one_width)]
    pub copy_spacing: f32,
    /// The whole mesh once more for each N, its GPU primitive array padded by N MiB that no ray
    /// reads: what the buffer's size costs apart from the rays' work.
    #[arg(long, value_delimiter = ',')]
    pub pad_mib: Vec<usize>,
    /// Timed runs after one warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 3)]
    pub runs: u32,
    /// Backends to measure.
    #[command(flatten)]
    pub backends: Backends,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
    /// Write the log-log plot (SVG) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Arguments of `chambre bench samplers`.
#[derive(Debug, clap::Args)]
pub struct SamplersArgs {
    /// Samples per pixel of the reference image.
    #[arg(long, value_parser = positive(), default_value_t = 4096)]
    pub reference_spp: u32,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Arguments of `chambre bench build`.
#[derive(Debug, clap::Args)]
pub struct BuildArgs {
    /// Mesh file (OBJ or PLY, optionally .gz).
    #[arg(long, default_value = DRAGON_MESH)]
    pub mesh: PathBuf,
    /// Timed runs after one warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 5)]
    pub runs: u32,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// A GPU way of running paths, as `bench frame --gpu-kernels` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GpuKernels {
    /// One kernel traces each sample's path whole.
    Megakernel,
    /// A kernel per stage of a path vertex.
    Wavefront,
}

impl From<GpuKernels> for PathKernels {
    fn from(kernels: GpuKernels) -> PathKernels {
        match kernels {
            GpuKernels::Megakernel => PathKernels::Megakernel,
            GpuKernels::Wavefront => PathKernels::Wavefront,
        }
    }
}

/// Arguments of `chambre bench frame`.
#[derive(Debug, clap::Args)]
pub struct FrameArgs {
    /// Scenes of `scenes/`, by name (default: every sample scene).
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Timed runs after one warm-up, interleaved across backends.
    #[arg(long, value_parser = positive(), default_value_t = 3)]
    pub runs: u32,
    /// Also render on the GPU with the megakernel at most N rays per invocation whatever the
    /// image size, for each N given: the dispatch shapes behind `RayBudgets::for_adapter`.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), value_delimiter = ',')]
    pub gpu_rays_per_invocation: Vec<u64>,
    /// The GPU's ways of running paths to measure, side by side.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [GpuKernels::Megakernel, GpuKernels::Wavefront])]
    pub gpu_kernels: Vec<GpuKernels>,
    /// Leave out the code with every feature (measured by default: the specialisation's
    /// speed-up).
    #[arg(long)]
    pub no_general: bool,
    /// wgpu's run-time checks of the GPU kernels, side by side (default: chambre's).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub shader_checks: Vec<ShaderChecks>,
    /// Override a field of every scene, e.g. --set camera.shutter=[0.0,1.0] (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Backends to measure.
    #[command(flatten)]
    pub backends: Backends,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Arguments of `chambre bench rays`.
#[derive(Debug, clap::Args)]
pub struct RaysArgs {
    /// Mesh file (OBJ or PLY, optionally .gz).
    #[arg(long, default_value = DRAGON_MESH)]
    pub mesh: PathBuf,
    /// Camera position.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true,
          default_values_t = Pinhole::DRAGON.position)]
    pub position: Vec<f32>,
    /// Point the camera looks at.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true,
          default_values_t = Pinhole::DRAGON.look_at)]
    pub look_at: Vec<f32>,
    /// Camera up vector.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true,
          default_values_t = Pinhole::DRAGON.up)]
    pub up: Vec<f32>,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = Pinhole::DRAGON.vertical_fov_deg)]
    pub vertical_fov: f32,
    /// Image width in pixels: one camera ray per pixel and frame.
    #[arg(long, value_parser = positive(), default_value_t = Pinhole::DRAGON.width)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, value_parser = positive(), default_value_t = Pinhole::DRAGON.height)]
    pub height: u32,
    /// Coherent frames (one jittered ray per pixel each); the incoherent set has as many rays.
    #[arg(long, value_parser = positive(), default_value_t = 8)]
    pub frames: u32,
    /// Timed runs after one warm-up.
    #[arg(long, value_parser = positive(), default_value_t = 5)]
    pub runs: u32,
    /// Seed of the pixel jitter and of the incoherent rays.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Acceleration structures to traverse, side by side (`wide` on the CPU only).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Bvh::Bvh2, Bvh::Cwbvh, Bvh::Wide, Bvh::Packets])]
    pub bvh: Vec<Bvh>,
    /// wgpu's run-time checks of the GPU kernels, side by side (default: chambre's).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub shader_checks: Vec<ShaderChecks>,
    /// Backends to measure.
    #[command(flatten)]
    pub backends: Backends,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// A benchmark's report with where it ran, as written to JSON.
#[derive(Debug, Serialize)]
pub struct Report<'a, T: Serialize> {
    /// The command line that ran the benchmark.
    pub command: &'a str,
    /// Where and when it ran.
    pub machine: &'a Machine,
    /// The benchmark's own report.
    pub report: &'a T,
}

/// Runs `command`; returns the Markdown report and writes the JSON one if asked.
pub fn run(command: &BenchCommand) -> Result<String> {
    let command_line = std::env::args().collect::<Vec<_>>().join(" ");
    // One device for the whole benchmark: every GPU run shares it.
    let context = GpuContext::new();
    let machine = Machine::here(&context);
    match command {
        BenchCommand::Rays(args) => {
            let config = RaysConfig {
                mesh: args.mesh.clone(),
                camera: Pinhole {
                    position: vec3(&args.position),
                    look_at: vec3(&args.look_at),
                    up: vec3(&args.up),
                    vertical_fov_deg: args.vertical_fov,
                    width: args.width,
                    height: args.height,
                },
                frames: args.frames,
                runs: args.runs,
                seed: args.seed,
                bvhs: args.bvh.clone(),
                shader_checks: args.shader_checks.clone(),
            };
            let gpu = args.backends.gpu().then(|| usable(&context)).transpose()?;
            let report = rays::run(&config, &args.backends.backends, gpu)?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Build(args) => {
            let report = build::run(&args.mesh, args.runs)?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Frame(args) => {
            let scenes = if args.scenes.is_empty() {
                frame::SCENES.iter().map(|s| s.to_string()).collect()
            } else {
                args.scenes.clone()
            };
            let gpu = args.backends.gpu().then(|| usable(&context)).transpose()?;
            let kernels: Vec<PathKernels> = args.gpu_kernels.iter().map(|&k| k.into()).collect();
            let report = frame::run(&frame::FrameConfig {
                scenes: &scenes,
                overrides: &args.set,
                cpu: args.backends.backends.contains(&Backend::Cpu),
                gpu,
                kernels: &kernels,
                general: !args.no_general,
                checks: &args.shader_checks,
                rays_per_invocation: &args.gpu_rays_per_invocation,
                runs: args.runs,
            })?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Scale(args) => {
            let camera = Pinhole {
                width: args.size,
                height: args.size,
                ..Pinhole::DRAGON
            };
            // A GPU that refuses is recorded per size, not an error.
            let gpu = args.backends.gpu().then_some(&context);
            let report = scale::run(
                &args.mesh,
                &camera,
                &args.prefixes,
                &args.copies,
                scale::Layout {
                    spacing: args.copy_spacing,
                    padding_mib: args.pad_mib.clone(),
                },
                args.runs,
                gpu,
            )?;
            if let Some(path) = &args.plot {
                let bytes =
                    crate::plot::figure_bytes(&report, path).map_err(|message| Error::Output {
                        path: path.clone(),
                        message,
                    })?;
                crate::output::OutputTarget::write_beside(path, &bytes)?;
            }
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Precision(args) => {
            let gpu = args.backends.gpu().then(|| usable(&context)).transpose()?;
            let report = precision::run(
                &args.mesh,
                &precision::PLACEMENTS,
                args.size,
                args.camera_height,
                gpu,
            )?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Motion(args) => {
            let report = motion::run(&args.mesh, args.travel, &args.slices, args.size, args.runs)?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Fermat(args) => {
            let config = fermat::FermatConfig {
                scene: &args.scene,
                overrides: &args.set,
                subdivisions: &args.subdivisions,
                steps: args.steps,
                runs: args.runs,
                frames: args.frames,
                reference_spp: args.reference_spp,
                searches_per_dispatch: args.searches_per_dispatch,
                tolerance_px: args.tessellation_tolerance,
                self_reflections: args.self_reflections,
            };
            let report = fermat::run(&config, usable(&context)?)?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Preview(args) => {
            let report = preview::run(
                usable(&context)?,
                &args.scenes,
                &args.set,
                args.frames,
                args.reference_spp,
                args.area_shadow_samples,
            )?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
        BenchCommand::Samplers(args) => {
            let report = samplers::run(args.reference_spp)?;
            finish(
                &command_line,
                &machine,
                report.to_markdown(),
                &report,
                &args.output,
            )
        }
    }
}

/// The Markdown report with its header line; the JSON one written where asked.
fn finish<T: Serialize>(
    command: &str,
    machine: &Machine,
    markdown: String,
    report: &T,
    output: &Output,
) -> Result<String> {
    let text = format!("{}\n{markdown}", machine.to_markdown(command));
    if let Some(path) = &output.json {
        write_json(
            path,
            &Report {
                command,
                machine,
                report,
            },
        )?;
    }
    Ok(text)
}

/// The benchmark's GPU context, or why there is none (a benchmark asked to measure the GPU
/// fails without one).
fn usable(context: &Result<GpuContext>) -> Result<&GpuContext> {
    context.as_ref().map_err(|e| match e {
        Error::NoAdapter(why) => Error::NoAdapter(why.clone()),
        other => Error::NoAdapter(other.to_string()),
    })
}

fn vec3(v: &[f32]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

fn write_json<T: Serialize>(path: &std::path::Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Output {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(|e| Error::io(path, e))
}

/// Median, minimum and maximum of repeated measurements.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// Median (the upper one of an even count).
    pub median: f64,
    /// Smallest measurement.
    pub min: f64,
    /// Largest measurement.
    pub max: f64,
}

impl Spread {
    /// The spread of `samples` (at least one).
    pub fn of(samples: &[f64]) -> Spread {
        assert!(!samples.is_empty(), "a spread of no measurement");
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        Spread {
            median: sorted[sorted.len() / 2],
            min: sorted[0],
            max: sorted[sorted.len() - 1],
        }
    }
}

/// Where and when a benchmark ran: what a figure needs to be compared with another.
#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    /// The crate version that ran.
    pub chambre_version: String,
    /// Date of the run (UTC), YYYY-MM-DD.
    pub date_utc: String,
    /// Threads of the CPU path (rayon's pool).
    pub cpu_threads: usize,
    /// The GPU adapter, or why there is none.
    pub adapter: String,
}

impl Machine {
    /// One line for a report: the command and where and when it ran.
    pub fn to_markdown(&self, command: &str) -> String {
        format!(
            "`{command}` — chambre {}, {}, {} CPU threads, adapter: {}\n",
            self.chambre_version, self.date_utc, self.cpu_threads, self.adapter
        )
    }

    /// This machine, now, with the adapter of `gpu` (or why there is none).
    pub fn here(gpu: &Result<GpuContext>) -> Machine {
        Machine {
            chambre_version: env!("CARGO_PKG_VERSION").to_string(),
            date_utc: crate::provenance::utc_date(),
            cpu_threads: rayon::current_num_threads(),
            adapter: match gpu {
                Ok(c) => c.adapter_description.clone(),
                Err(e) => format!("none ({e})"),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_the_median_min_and_max() {
        let s = Spread::of(&[3.0, 1.0, 2.0, 10.0, 4.0]);
        assert_eq!((s.median, s.min, s.max), (3.0, 1.0, 10.0));
    }
}
