//! `chambre preview`: the raster preview, one frame written or a window to compose the shot.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use chambre::output::{OutputTarget, Protected};
use chambre::pack::flatten;

use super::args::{fermat_steps, positive, tolerance_px};
use super::load_and_note;

/// `chambre preview`'s arguments.
#[derive(Args)]
pub struct PreviewArgs {
    /// Scene file (TOML or glTF; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Image to write: .png, .exr or .pfm (required without --window).
    #[arg(short, long, required_unless_present = "window")]
    pub output: Option<PathBuf>,
    /// Replace the image even where it is a write-protected file (refused otherwise).
    #[arg(long, requires = "output")]
    pub force: bool,
    /// Timed frames after a warm-up; the median is reported.
    #[arg(long, value_parser = positive(), default_value_t = 5)]
    pub frames: u32,
    /// Open a window to compose the shot: arrows tilt and swing the film, i/k and j/l
    /// shift it, a/d pan and w/x pitch the camera, r resets, s saves the scene, q quits;
    /// a drag with the left button turns the camera, with the right button the film, and
    /// the wheel shifts the film.
    #[arg(long)]
    pub window: bool,
    /// With --window: keys to replay after the first frame, then close (e.g. "up,up,l,s"):
    /// up, down, left, right, escape, or one character.
    #[arg(long, value_delimiter = ',', requires = "window")]
    pub keys: Vec<String>,
    /// With --window: write the last frame shown here when the window closes.
    #[arg(long, requires = "window")]
    pub screenshot: Option<PathBuf>,
    /// With --window: where `s` saves the composed scene (default: beside the scene,
    /// NAME.composed.toml, so its relative mesh paths still hold).
    #[arg(long, requires = "window")]
    pub save: Option<PathBuf>,
    /// Curved mirrors' Fermat reflections: pieces each reflected triangle's edge is cut
    /// into (default: enough that none is longer than 1/16 of the scene's radius).
    #[arg(long, value_parser = positive())]
    pub subdivision: Option<u32>,
    /// Curved mirrors' Fermat reflections: the search's steps at most (1 to 1000).
    #[arg(long, value_parser = fermat_steps(), default_value_t = chambre::preview::PreviewOptions::default().steps)]
    pub fermat_steps: u32,
    /// How far (pixels on the film) the triangles of a curved shape (sphere, torus,
    /// ellipsoid, cylinder, Bézier patch) may stray from it: each is cut as coarsely as
    /// that allows, for the camera that sees it.
    #[arg(long, value_parser = tolerance_px, default_value_t = chambre::preview::DEFAULT_TOLERANCE_PX)]
    pub tessellation_tolerance: f64,
    /// Shadows from every light, by shadow maps (1024 texels square, smaller beyond four
    /// lights; drawn once; hard, as from a point: an area light's from its centre).
    #[arg(long)]
    pub shadows: bool,
    /// With --shadows: an area light's shadow maps stand at the centres of N x N strata of
    /// it (N² cubes), for soft shadows; 1 is its centre.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8), default_value_t = 1, requires = "shadows")]
    pub area_shadow_samples: u32,
    /// Curved mirrors that can see themselves (a torus, a teapot) reflect their own
    /// triangles, cut for this tolerance (pixels on the film; the flag alone: 2), at the
    /// cost of their Fermat solves (a teapot's 32 patches each solve every vertex).
    #[arg(long, value_parser = tolerance_px, num_args = 0..=1, default_missing_value = chambre::preview::SELF_REFLECTION_TOLERANCE_PX)]
    pub self_reflections: Option<f64>,
    /// Override any scene field, e.g. --set camera.film_tilt=10 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `chambre preview`: a frame written, or the window with `--window`.
pub fn run(args: &PreviewArgs) -> anyhow::Result<ExitCode> {
    let options = chambre::preview::PreviewOptions {
        tolerance_px: args.tessellation_tolerance,
        subdivision: args.subdivision,
        steps: args.fermat_steps,
        shadows: args.shadows,
        area_shadow_samples: args.area_shadow_samples,
        self_reflections: args.self_reflections,
        ..Default::default()
    };
    match (args.window, &args.output) {
        (true, _) => run_window(
            &args.scene,
            &args.set,
            &args.keys,
            args.screenshot.clone(),
            args.save.clone(),
            options,
        ),
        (false, Some(output)) => {
            let target = (output.as_path(), Protected::replaced_if(args.force));
            run_preview(&args.scene, target, args.frames, &args.set, options)
        }
        (false, None) => unreachable!("clap requires --output without --window"),
    }
}

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

/// `chambre preview`: the raster preview, written atomically, with its frame time.
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
