//! `chambre bench`: its subcommands with their arguments, each turned into its benchmark's
//! settings and run (`chambre::bench`); the report printed, and written as JSON if asked.

use std::path::PathBuf;

use chambre::Error;
use chambre::bench::rays::{Backend, Bvh, Pinhole, Query, RaySetName, RaysConfig};
use chambre::bench::{
    Machine, adaptive, build, fermat, finish, frame, motion, precision, preview, rays, samplers,
    scale, usable,
};
use chambre::gpu::GpuContext;
use chambre::gpu::kernels::ShaderChecks;
use chambre::gpu::render::PathKernels;
use chambre::sampler::SamplerName;

use super::args::{at_least_one, at_least_one_width, fermat_steps, named, positive, tolerance_px};

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
    /// Adaptive sampling (`--noise-target`) against uniform sampling of the same pattern at
    /// equal samples and at equal wall time (relative MSE against a converged reference), CPU
    /// path, on scene files and held-out scenes generated from a seed.
    Adaptive(AdaptiveArgs),
}

/// Arguments of `chambre bench adaptive`.
#[derive(Debug, clap::Args)]
pub struct AdaptiveArgs {
    /// Scene files to measure.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<PathBuf>,
    /// Held-out scenes generated from a seed, as KIND:SEED (kinds: soft_shadows, defocus,
    /// mirror), e.g. soft_shadows:1,defocus:1.
    #[arg(long, value_delimiter = ',', value_parser = adaptive::parse_held_out)]
    pub generated: Vec<adaptive::HeldOut>,
    /// Width and height of the held-out scenes (pixels).
    #[arg(long, value_parser = positive(), default_value_t = 96)]
    pub size: u32,
    /// Pixel and lens sample patterns to measure.
    #[arg(long, value_parser = named::<SamplerName>(), value_delimiter = ',',
          default_values_t = [SamplerName::Stratified, SamplerName::Sobol])]
    pub samplers: Vec<SamplerName>,
    /// Noise targets.
    #[arg(long, value_delimiter = ',', default_values_t = [0.05, 0.02, 0.01])]
    pub targets: Vec<f64>,
    /// The adaptive renders' most samples per pixel (`render.spp`).
    #[arg(long, value_parser = positive(), default_value_t = 16384)]
    pub spp: u32,
    /// The adaptive renders' `render.min_spp` (default: the scene's, or 16).
    #[arg(long)]
    pub min_spp: Option<u32>,
    /// Samples per pixel of each scene's reference (Sobol, another seed).
    #[arg(long, value_parser = positive(), default_value_t = 16384)]
    pub reference_spp: u32,
    /// Renders of each timed run: their median time is kept (the images are the same).
    #[arg(long, value_parser = at_least_one, default_value_t = 3)]
    pub runs: usize,
    /// Samples per pixel of the overhead measurement: adaptive sampling with a target no pixel
    /// meets against uniform sampling of the same samples (0: none).
    #[arg(long, default_value_t = 256)]
    pub overhead_spp: u32,
    /// Override any scene field, e.g. --set render.width=128 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
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
    #[arg(long, value_parser = fermat_steps(), default_value_t = chambre::preview::PreviewOptions::default().steps)]
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
    #[arg(long, value_parser = tolerance_px, default_value_t = chambre::preview::DEFAULT_TOLERANCE_PX)]
    pub tessellation_tolerance: f64,
    /// A torus or teapot reflects itself, its own triangles cut for this tolerance (pixels on
    /// the film; the flag alone: the preview's default, `preview::SELF_REFLECTION_TOLERANCE_PX`).
    #[arg(long, value_parser = tolerance_px, num_args = 0..=1, default_missing_value = chambre::preview::SELF_REFLECTION_TOLERANCE_PX)]
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
    #[arg(long, value_parser = named::<Backend>(), value_delimiter = ',', default_values_t = [Backend::Cpu, Backend::Gpu])]
    pub backends: Vec<Backend>,
}

impl Backends {
    /// Whether the GPU is among the backends.
    pub fn gpu(&self) -> bool {
        self.backends.contains(&Backend::Gpu)
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
    #[arg(long, value_parser = named::<ShaderChecks>(), value_delimiter = ',')]
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
    /// Ray sets to trace, in this order.
    #[arg(long, value_parser = named::<RaySetName>(), value_delimiter = ',', default_values_t = [RaySetName::Coherent, RaySetName::Incoherent])]
    pub rays: Vec<RaySetName>,
    /// Queries to ask of each set, in this order.
    #[arg(long, value_parser = named::<Query>(), value_delimiter = ',', default_values_t = [Query::ClosestHit, Query::AnyHit])]
    pub queries: Vec<Query>,
    /// Acceleration structures to traverse, side by side (`wide` on the CPU only).
    #[arg(long, value_parser = named::<Bvh>(), value_delimiter = ',', default_values_t = [Bvh::Bvh2, Bvh::Cwbvh, Bvh::Wide, Bvh::Packets, Bvh::Stream])]
    pub bvh: Vec<Bvh>,
    /// wgpu's run-time checks of the GPU kernels, side by side (default: chambre's).
    #[arg(long, value_parser = named::<ShaderChecks>(), value_delimiter = ',')]
    pub shader_checks: Vec<ShaderChecks>,
    /// Trace nothing: write the mesh's triangles and both ray sets into this directory, raw
    /// little-endian, for another ray tracer to trace the very same rays
    /// (`tools/bench_embree.sh`; the files are described in `docs/embree.md`).
    #[arg(long, value_name = "DIR")]
    pub write_rays: Option<PathBuf>,
    /// Backends to measure.
    #[command(flatten)]
    pub backends: Backends,
    /// Where the report goes.
    #[command(flatten)]
    pub output: Output,
}

/// Runs `command`; returns the Markdown report and writes the JSON one if asked.
pub fn run(command: &BenchCommand) -> chambre::Result<String> {
    // One device for the whole benchmark: every GPU run shares it.
    let context = GpuContext::new();
    let run = Run {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        machine: Machine::here(&context),
        context: &context,
    };
    match command {
        BenchCommand::Rays(args) => bench_rays(args, &run),
        BenchCommand::Build(args) => bench_build(args, &run),
        BenchCommand::Frame(args) => bench_frame(args, &run),
        BenchCommand::Scale(args) => bench_scale(args, &run),
        BenchCommand::Precision(args) => bench_precision(args, &run),
        BenchCommand::Motion(args) => bench_motion(args, &run),
        BenchCommand::Fermat(args) => bench_fermat(args, &run),
        BenchCommand::Preview(args) => bench_preview(args, &run),
        BenchCommand::Samplers(args) => bench_samplers(args, &run),
        BenchCommand::Adaptive(args) => bench_adaptive(args, &run),
    }
}

/// What every benchmark's report starts with, and the device they share.
struct Run<'a> {
    /// The command line that ran it.
    command: String,
    /// Where and when it ran.
    machine: Machine,
    /// The GPU, or why there is none.
    context: &'a chambre::Result<GpuContext>,
}

impl Run<'_> {
    /// The report with its header line, written as JSON where `output` asks.
    fn finish<T: serde::Serialize>(
        &self,
        markdown: String,
        report: &T,
        output: &Output,
    ) -> chambre::Result<String> {
        finish(
            &self.command,
            &self.machine,
            markdown,
            report,
            output.json.as_deref(),
        )
    }
}

/// `chambre bench rays`.
fn bench_rays(args: &RaysArgs, run: &Run) -> chambre::Result<String> {
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
        sets: args.rays.clone(),
        queries: args.queries.clone(),
        bvhs: args.bvh.clone(),
        shader_checks: args.shader_checks.clone(),
    };
    if let Some(dir) = &args.write_rays {
        return rays::write_rays(&config, dir);
    }
    let gpu = args
        .backends
        .gpu()
        .then(|| usable(run.context))
        .transpose()?;
    let report = rays::run(&config, &args.backends.backends, gpu)?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench build`.
fn bench_build(args: &BuildArgs, run: &Run) -> chambre::Result<String> {
    let report = build::run(&args.mesh, args.runs)?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench frame`.
fn bench_frame(args: &FrameArgs, run: &Run) -> chambre::Result<String> {
    let scenes = if args.scenes.is_empty() {
        frame::SCENES.iter().map(|s| s.to_string()).collect()
    } else {
        args.scenes.clone()
    };
    let gpu = args
        .backends
        .gpu()
        .then(|| usable(run.context))
        .transpose()?;
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
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench scale`.
fn bench_scale(args: &ScaleArgs, run: &Run) -> chambre::Result<String> {
    let camera = Pinhole {
        width: args.size,
        height: args.size,
        ..Pinhole::DRAGON
    };
    // A GPU that refuses is recorded per size, not an error.
    let gpu = args.backends.gpu().then_some(run.context);
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
            chambre::plot::figure_bytes(&report, path).map_err(|message| Error::Output {
                path: path.clone(),
                message,
            })?;
        chambre::output::OutputTarget::write_beside(path, &bytes)?;
    }
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench precision`.
fn bench_precision(args: &PrecisionArgs, run: &Run) -> chambre::Result<String> {
    let gpu = args
        .backends
        .gpu()
        .then(|| usable(run.context))
        .transpose()?;
    let report = precision::run(
        &args.mesh,
        &precision::PLACEMENTS,
        args.size,
        args.camera_height,
        gpu,
    )?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench motion`.
fn bench_motion(args: &MotionArgs, run: &Run) -> chambre::Result<String> {
    let report = motion::run(&args.mesh, args.travel, &args.slices, args.size, args.runs)?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench fermat`.
fn bench_fermat(args: &FermatArgs, run: &Run) -> chambre::Result<String> {
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
    let report = fermat::run(&config, usable(run.context)?)?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench preview`.
fn bench_preview(args: &PreviewArgs, run: &Run) -> chambre::Result<String> {
    let report = preview::run(
        usable(run.context)?,
        &args.scenes,
        &args.set,
        args.frames,
        args.reference_spp,
        args.area_shadow_samples,
    )?;
    run.finish(report.to_markdown(), &report, &args.output)
}

/// `chambre bench samplers`.
fn bench_samplers(args: &SamplersArgs, run: &Run) -> chambre::Result<String> {
    let report = samplers::run(args.reference_spp)?;
    run.finish(report.to_markdown(), &report, &args.output)
}

fn vec3(v: &[f32]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

/// `chambre bench adaptive`.
fn bench_adaptive(args: &AdaptiveArgs, run: &Run) -> chambre::Result<String> {
    let mut scenes: Vec<adaptive::SceneSource> = args
        .scenes
        .iter()
        .map(|p| adaptive::SceneSource::File(p.clone()))
        .collect();
    scenes.extend(
        args.generated
            .iter()
            .map(|&g| adaptive::SceneSource::HeldOut(g, args.size)),
    );
    let report = adaptive::run(&adaptive::Study {
        scenes: &scenes,
        samplers: &args.samplers,
        targets: &args.targets,
        spp: args.spp,
        min_spp: args.min_spp,
        reference_spp: args.reference_spp,
        runs: args.runs,
        overhead_spp: args.overhead_spp,
        set: &args.set,
    })?;
    run.finish(report.to_markdown(), &report, &args.output)
}
