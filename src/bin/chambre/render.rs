//! `chambre render`: a scene rendered on the GPU or the CPU path into an image, with what the
//! render reports (statistics, sidecar, sample counts, AOVs, shards).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};

use chambre::cpu::CpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::gpu::{GpuContext, GpuRenderer};
use chambre::output::{Aov, Display, ImageFormat, OutputTarget, Protected, ToneMap, same_path};
use chambre::pack::{FlatScene, flatten};
use chambre::render::{
    Backend, Progress, RenderOutput, describe_status_flags, render, render_until,
};
use chambre::sampler::SamplerName;
use chambre::scene::{Integrator, Scene};
use chambre::shard::Shard;
use chambre::{Error, Result};

use super::args::named;
use super::{load, load_and_note};

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Image to write: .png (sRGB, 8 bits, clamped) or .exr (linear floats).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Samples per pixel (overrides render.spp).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Image width in pixels (overrides render.width); given alone, the height follows the
    /// film's aspect.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (overrides render.height); given alone, the width follows the
    /// film's aspect.
    #[arg(long)]
    pub height: Option<u32>,
    /// Seed of every random number of the render (overrides render.seed).
    #[arg(long)]
    pub seed: Option<u32>,
    /// Where to render.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// How the GPU runs the paths: `auto` (the wavefront render on a real GPU, the megakernel
    /// on a CPU adapter such as lavapipe), `megakernel` or `wavefront`.
    #[arg(long, value_enum, default_value_t = KernelChoice::Auto)]
    pub gpu_kernels: KernelChoice,
    /// Worker threads of the CPU path (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// The light transport (overrides render.integrator).
    #[arg(long, value_parser = named::<Integrator>())]
    pub integrator: Option<Integrator>,
    /// Bounces: Whitted's mirror bounces, the path tracer's of any kind (overrides
    /// render.max_depth).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Pixel sample pattern (overrides render.pixel_sampler).
    #[arg(long, value_parser = named::<SamplerName>())]
    pub pixel_sampler: Option<SamplerName>,
    /// Lens sample pattern (overrides camera.lens_sampler).
    #[arg(long, value_parser = named::<SamplerName>())]
    pub lens_sampler: Option<SamplerName>,
    /// Override any scene field, e.g. --set camera.f_number=2.8 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print statistics: rays, wall, kernel and host time, dispatches and batches, the BVH,
    /// and the features the code was specialised to.
    #[arg(long)]
    pub stats: bool,
    /// Exposure of an 8-bit image in stops: linear values are scaled by 2^EV before tone
    /// mapping (float formats keep the radiance as rendered).
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        value_name = "EV"
    )]
    pub exposure: f32,
    /// How an 8-bit image maps radiance to [0, 1].
    #[arg(long, value_parser = named::<ToneMap>(), default_value_t = ToneMap::Clamp)]
    pub tonemap: ToneMap,
    /// Also write OUT.json: the command, scene hash, seed, samples reached, backend and
    /// timings, to reproduce the image.
    #[arg(long)]
    pub sidecar: bool,
    /// A fast preview: a quarter of each image side and a sixteenth of the samples (after
    /// the other flags).
    #[arg(long)]
    pub quick: bool,
    /// Render only this window of the image, as fractions in [0, 1] (pbrt's crop window;
    /// overrides render.crop); the image written is the window.
    #[arg(long, value_delimiter = ',', value_name = "X0,X1,Y0,Y1")]
    pub crop: Option<Vec<f64>>,
    /// Also write these layers into the EXR image, as named channels: depth (depth.Z), normal
    /// (normal.X/Y/Z), albedo (albedo.R/G/B) of each camera ray's first hit, averaged over the
    /// pixel's samples, and samples (samples.Y), the samples each pixel received.
    #[arg(long, value_parser = named::<Aov>(), value_delimiter = ',', value_name = "AOV,...")]
    pub aov: Vec<Aov>,
    /// Also write the samples each pixel received as an image (.exr or .pfm: the count in
    /// every channel), to see where they went.
    #[arg(long, value_name = "FILE")]
    pub sample_counts: Option<PathBuf>,
    /// Stop after this many seconds (the batches in flight finish) and write the image with
    /// the samples each pixel received: a time instead of a sample count (`--spp` is then the
    /// most taken).
    #[arg(long, value_name = "SECONDS")]
    pub time_budget: Option<f64>,
    /// Adaptive sampling: put the samples where they reduce the image's error most, until its
    /// estimated relative error (the root of its relative MSE, from two halves of each pixel's
    /// samples) is below X or --spp (then the most a pixel takes) is reached (overrides
    /// render.noise_target; e.g. 0.02).
    #[arg(long, value_name = "X")]
    pub noise_target: Option<f64>,
    /// Samples every pixel receives before adaptive sampling's first decision (overrides
    /// render.min_spp; default 16, or --spp when smaller).
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    /// Also write the image every SECONDS during the render (the same path, replaced whole
    /// each time), to look at it and stop the render when it is good enough.
    #[arg(long, value_name = "SECONDS")]
    pub progressive: Option<f64>,
    /// Render shard I of N (a band of rows) for `chambre merge`: writes OUT's stem with
    /// `.shard-I-of-N.exr` and `.json`. `auto/N` takes I from JOB_COMPLETION_INDEX,
    /// SLURM_ARRAY_TASK_ID or AWS_BATCH_JOB_ARRAY_INDEX.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Replace the files the render writes even where they are write-protected (without it, an
    /// existing write-protected image, sidecar, sample-count image or shard file is refused
    /// before the render starts).
    #[arg(long)]
    pub force: bool,
}

impl RenderArgs {
    /// `--set`, then the scene overrides the flags stand for: the flags come after because
    /// they are worked out from the scene as `--set` leaves it (`--quick`'s quarter of its
    /// size, a side's partner from its film). A width or height given alone gets its partner
    /// from the film's aspect, with a note saying so.
    fn overrides(&self) -> Result<Vec<String>> {
        let mut overrides = self.set.clone();
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
            ("render.max_depth", self.max_depth),
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
        if let Some(integrator) = self.integrator {
            overrides.push(format!("render.integrator={integrator}"));
        }
        if let Some(target) = self.noise_target {
            // TOML writes a NaN or an infinity in its own words; the field's check says why
            // neither is a target.
            let value = match target {
                t if t.is_nan() => "nan".to_string(),
                t if t.is_infinite() => format!("{}inf", if t < 0.0 { "-" } else { "" }),
                t => format!("{t:?}"),
            };
            overrides.push(format!("render.noise_target={value}"));
        }
        if let Some(window) = &self.crop {
            let values: Vec<String> = window.iter().map(|v| v.to_string()).collect();
            overrides.push(format!("render.crop=[{}]", values.join(", ")));
        }
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
        let film = Scene::frame_given(&self.scene, &self.set)?;
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
pub enum BackendChoice {
    /// A real GPU when it accepts the scene, else the CPU path, with a notice.
    Auto,
    /// The GPU adapter, whatever it is (lavapipe included); a refusal is an error.
    Gpu,
    /// chambre's CPU path.
    Cpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KernelChoice {
    /// The adapter's best: the wavefront render on a real GPU, the megakernel on a CPU adapter.
    Auto,
    /// One kernel traces each sample's path whole.
    Megakernel,
    /// A kernel per stage of a path vertex, paths and shadow rays in queues.
    Wavefront,
}

impl KernelChoice {
    fn for_scene(self, scene: &FlatScene, context: &GpuContext) -> PathKernels {
        match self {
            KernelChoice::Auto => PathKernels::for_scene(scene, context.is_cpu_adapter),
            KernelChoice::Megakernel => PathKernels::Megakernel,
            KernelChoice::Wavefront => PathKernels::Wavefront,
        }
    }
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

pub fn run(args: &RenderArgs) -> anyhow::Result<ExitCode> {
    start_threads(args.threads)?;
    if !args.exposure.is_finite() {
        bail!(
            "--exposure must be a finite number of stops, got {}",
            args.exposure
        );
    }
    let overrides = args.overrides()?;
    let mut scene = load_and_note(&args.scene, &overrides)?;
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(|e| anyhow::anyhow!("--shard {e}"))?;
    let full_crop = scene.render.crop;
    if let Some(shard) = shard {
        scene.render.crop = shard.rows(full_crop);
        let [.., y0, y1] = scene.render.crop;
        if y0 == y1 {
            let rows = full_crop[3] - full_crop[2];
            bail!(
                "--shard {}/{}: {} shards of {rows} rows leave this one no row; split into at most {rows}",
                shard.index,
                shard.count,
                shard.count
            );
        }
    }
    // Before any render time is spent: a path that cannot take a file fails now.
    let outputs = Outputs::prepare(args, shard)?;
    let mut flat = flatten(&scene);
    flat.aovs = args.aov.iter().any(|a| a.needs_first_hits());
    let (output, backend_name, features) = render_scene(args, &flat, &outputs.image)?;
    if args.stats {
        note!("{}", render_stats(&output, &flat, features));
    }
    let written = output.max_samples_per_pixel > 0;
    let sidecar = outputs.sidecar.as_ref().map(|path| {
        let record = sidecar_record(args, &scene, &overrides, &output, &backend_name);
        (path, record)
    });
    if let Some(target) = &outputs.counts {
        let (w, h) = (output.image.width, output.image.height);
        target.write(&chambre::render::Image::of_counts(
            w,
            h,
            &output.sample_counts,
        ))?;
    }
    let manifest = match (shard, &outputs.shard) {
        (Some(shard), Some((image, _))) => Some(super::shard::shard_manifest(
            shard,
            &args.scene,
            &scene,
            full_crop,
            image,
            &overrides,
            &output,
        )),
        _ => None,
    };
    let channels = chambre::output::aov_channels(&output, &args.aov)
        .map_err(|e| anyhow::anyhow!("{}: {e}", outputs.image.path().display()))?;
    let code = finish(output, &outputs.image, &backend_name, &channels)?;
    if let (Some(manifest), Some((_, manifest_path)), true) = (manifest, &outputs.shard, written) {
        let text = serde_json::to_string_pretty(&manifest).context("encoding the manifest")?;
        OutputTarget::write_beside(manifest_path, (text + "\n").as_bytes())?;
    }
    if let Some((sidecar_path, record)) = sidecar.filter(|_| written) {
        let text = serde_json::to_string_pretty(&record).context("encoding the sidecar")?;
        OutputTarget::write_beside(sidecar_path, (text + "\n").as_bytes())?;
    }
    Ok(code)
}

/// `--threads`: the CPU path's pool of that many threads (rayon's default: one per core).
fn start_threads(threads: Option<usize>) -> anyhow::Result<()> {
    if let Some(threads) = threads {
        if threads == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("starting the CPU path's threads")?;
    }
    Ok(())
}

/// Every file a render writes, each checked writable before the render starts.
struct Outputs {
    /// The image (a shard's band when rendering a shard).
    image: OutputTarget,
    /// `--sample-counts`.
    counts: Option<OutputTarget>,
    /// `--sidecar`: `OUT.json`.
    sidecar: Option<PathBuf>,
    /// `--shard`: the band's image and its manifest.
    shard: Option<(PathBuf, PathBuf)>,
}

impl Outputs {
    fn prepare(args: &RenderArgs, shard: Option<Shard>) -> anyhow::Result<Outputs> {
        let shard_paths = shard.map(|s| s.paths(&args.output));
        let image_path = shard_paths
            .as_ref()
            .map_or(args.output.as_path(), |(image, _)| image);
        let protected = Protected::replaced_if(args.force);
        let image = OutputTarget::prepare_with(image_path, protected)?.with_display(Display {
            exposure_ev: args.exposure,
            tone_map: args.tonemap,
        });
        let counts = match &args.sample_counts {
            Some(path) if same_path(path, image_path) => bail!(
                "--sample-counts {}: is the image's own path; the counts would replace it",
                path.display()
            ),
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
        let sidecar = args.sidecar.then(|| sidecar_path(image_path));
        for beside in sidecar.iter().chain(shard_paths.as_ref().map(|(_, m)| m)) {
            OutputTarget::prepare_beside_with(beside, protected)?;
        }
        let mut aovs = args.aov.iter().enumerate();
        if let Some((_, aov)) = aovs.find(|&(i, aov)| args.aov[..i].contains(aov)) {
            bail!(
                "--aov {}: given twice (each layer is written once)",
                aov.name()
            );
        }
        if !args.aov.is_empty() {
            if image.format() != ImageFormat::Exr {
                bail!("--aov writes layers into an EXR: give -o an .exr path");
            }
            if shard.is_some() {
                bail!("--aov with --shard: shards merge the image only, not its AOV layers");
            }
        }
        Ok(Outputs {
            image,
            counts,
            sidecar,
            shard: shard_paths,
        })
    }
}

/// Renders `flat` on the backend `args` chooses, until its samples are taken, its time budget
/// is spent or a signal stops it (`--progressive` writing the image as it goes). Returns the
/// output, the backend's name and the features its code was specialised to.
fn render_scene(
    args: &RenderArgs,
    flat: &FlatScene,
    target: &OutputTarget,
) -> anyhow::Result<(RenderOutput, String, u32)> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    // With ctrlc's `termination` feature this also catches SIGTERM and SIGHUP, what `kill` and
    // batch schedulers send, so they too stop the render and keep its image.
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .context("installing the SIGINT/SIGTERM/SIGHUP handler")?;
    let mut progress = progress_reporter();
    // With a time budget the render stops, successfully, at the deadline.
    let deadline = seconds_flag("--time-budget", args.time_budget)?.map(|d| Instant::now() + d);
    let every = seconds_flag("--progressive", args.progressive)?;
    let run = |backend: &mut dyn Backend, progress: &mut dyn Progress| match (every, deadline) {
        (Some(every), deadline) => {
            let mut write = |image: &chambre::render::Image| target.write(image);
            let snapshots = chambre::render::Snapshots {
                every,
                write: &mut write,
            };
            chambre::render::render_with_snapshots(
                flat, backend, progress, &cancel, deadline, snapshots,
            )
        }
        (None, Some(deadline)) => render_until(flat, backend, progress, &cancel, deadline),
        (None, None) => render(flat, backend, progress, &cancel),
    };
    Ok(match gpu_renderer(args.backend, args.gpu_kernels, flat)? {
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
            let mut renderer = CpuRenderer::new(flat).with_cancel(&cancel);
            let threads = rayon::current_num_threads();
            let name = format!(
                "CPU: {threads} thread{}",
                if threads == 1 { "" } else { "s" }
            );
            let features = renderer.features();
            (run(&mut renderer, progress.as_mut())?, name, features)
        }
    })
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
        let kernels = kernels.for_scene(flat, &context);
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
        format!(" (kernels {:.3} s)", k.as_secs_f64())
    });
    note!(
        "{path}: {}x{}, {} in {:.3} s{kernel}, {:.2} Mrays/s ({} rays) on {backend}",
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
    let mut failed = false;
    if output.deadline_reached && written {
        note!(
            "note: the time budget was spent after {:.2} s: {}",
            output.elapsed.as_secs_f64(),
            describe_samples(&output)
        );
    } else if output.deadline_reached {
        // A budget too short for one sample leaves no image: a success would leave whatever
        // file was there before looking like this render's.
        note!(
            "error: the time budget was spent after {:.2} s, before any pixel had a sample; \
             {path} was not written",
            output.elapsed.as_secs_f64()
        );
        failed = true;
    }
    if output.truncated_paths > 0 {
        note!(
            "note: {} paths were cut off at max_depth while they still reflected",
            output.truncated_paths
        );
    }
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

/// The longest `--time-budget` or `--progressive` interval: about 31 years, far within what
/// a clock's instant can be moved by.
const MAX_SECONDS_FLAG: f64 = 1e9;

/// A flag's positive, finite number of seconds (at most [`MAX_SECONDS_FLAG`]) as a duration.
fn seconds_flag(flag: &str, seconds: Option<f64>) -> anyhow::Result<Option<Duration>> {
    match seconds {
        Some(s) if !(s.is_finite() && s > 0.0 && s <= MAX_SECONDS_FLAG) => bail!(
            "{flag} must be a positive number of seconds, at most {MAX_SECONDS_FLAG:e}, got {s}"
        ),
        Some(s) => Ok(Some(Duration::from_secs_f64(s))),
        None => Ok(None),
    }
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
