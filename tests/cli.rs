//! The `chambre` command line end to end: overrides and sampler flags reach the render, EXR
//! keeps the linear floats, `chambre camera` reports, bad input exits non-zero with its place,
//! an interrupted render keeps what it computed, and the newer flags (adaptive sampling, AgX,
//! the preview) work end to end.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use std::sync::atomic::{AtomicBool, Ordering};

use chambre::cpu::CpuRenderer;
use chambre::pack::flatten;
use chambre::render::render;
use chambre::scene::Scene;

fn chambre() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_chambre"));
    command.current_dir(env!("CARGO_MANIFEST_DIR"));
    command
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

#[test]
fn render_writes_the_linear_exr_the_library_computes_with_every_override() {
    let out = scratch("spheres.exr");
    let status = chambre()
        .args(["render", "scenes/spheres.toml", "-o"])
        .arg(&out)
        .args([
            "--backend",
            "cpu",
            "--spp",
            "3",
            "--width",
            "48",
            "--height",
            "32",
        ])
        .args([
            "--seed",
            "7",
            "--pixel-sampler",
            "sobol",
            "-D",
            "render.ambient=[0.2, 0.2, 0.2]",
        ])
        .status()
        .unwrap();
    assert!(status.success());
    // The same render through the library.
    let overrides: Vec<String> = [
        "render.spp=3",
        "render.width=48",
        "render.height=32",
        "render.seed=7",
        "render.pixel_sampler=sobol",
        "render.ambient=[0.2, 0.2, 0.2]",
    ]
    .map(String::from)
    .to_vec();
    let scene = Scene::load(&scene_path("spheres.toml"), &overrides).unwrap();
    let expected = common::render_cpu(&flatten(&scene));
    let written = image::open(&out).unwrap().into_rgb32f();
    assert_eq!((written.width(), written.height()), (48, 32));
    for (p, q) in written.pixels().zip(&expected.pixels) {
        assert_eq!(
            p.0,
            q.to_array(),
            "EXR must hold the linear radiance unchanged"
        );
    }
    // A linear EXR keeps values a PNG would clamp (the lit spheres exceed 1 somewhere or not;
    // either way nothing is negative or non-finite).
    assert!(
        written
            .pixels()
            .all(|p| p.0.iter().all(|c| c.is_finite() && *c >= 0.0))
    );
}

/// `--integrator path --max-depth 2` renders what the library path traces with those fields,
/// and says how many paths the cut stopped.
#[test]
fn the_path_tracer_from_the_command_line() {
    let out = scratch("cornell_path.exr");
    let run = chambre()
        .args(["render", "scenes/cornell_box.toml", "-o"])
        .arg(&out)
        .args([
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--width",
            "24",
            "--height",
            "24",
        ])
        .args(["--integrator", "path", "--max-depth", "2"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("paths were cut off at max_depth"),
        "{stderr}"
    );
    let overrides: Vec<String> = [
        "render.spp=2",
        "render.width=24",
        "render.height=24",
        "render.max_depth=2",
        "render.integrator=path",
    ]
    .map(String::from)
    .to_vec();
    let scene = Scene::load(&scene_path("cornell_box.toml"), &overrides).unwrap();
    let expected = common::render_cpu(&flatten(&scene));
    let written = image::open(&out).unwrap().into_rgb32f();
    for (p, q) in written.pixels().zip(&expected.pixels) {
        assert_eq!(p.0, q.to_array());
    }
}

#[test]
fn camera_reports_the_solved_tilt_hinge_and_frustum() {
    let output = chambre()
        .args(["camera", "scenes/tabletop.toml", "--coc", "0.03"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    for needle in [
        "solved lens tilt",
        "plane of sharp focus",
        "hinge line",
        "Scheimpflug line",
        "near limit",
        "projection * view",
    ] {
        assert!(text.contains(needle), "missing `{needle}` in\n{text}");
    }
}

#[test]
fn bad_input_exits_non_zero_naming_file_line_and_field() {
    let path = scratch("bad.toml");
    let text = std::fs::read_to_string(scene_path("spheres.toml"))
        .unwrap()
        .replace("[camera]\n", "[camera]\nlens_tilt = \"steep\"\n");
    std::fs::write(&path, text).unwrap();
    let output = chambre().args(["check"]).arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(1));
    let message = String::from_utf8(output.stderr).unwrap();
    assert!(message.contains("bad.toml:"), "{message}");
    assert!(message.contains("lens_tilt"), "{message}");
    assert!(!message.contains("panicked"), "{message}");
    let output = chambre()
        .args([
            "render",
            "scenes/spheres.toml",
            "-o",
            "/tmp/x.png",
            "--lens-sampler",
            "halton",
        ])
        .output()
        .unwrap();
    assert_eq!(
        output.status.code(),
        Some(2),
        "clap rejects unknown sampler names"
    );
}

#[test]
fn an_interrupted_render_keeps_the_samples_it_finished() {
    // One band; the spp is split into several sample passes, one batch each.
    let overrides: Vec<String> = ["render.spp=256", "render.width=72", "render.height=48"]
        .map(String::from)
        .to_vec();
    let scene = Scene::load(&scene_path("spheres.toml"), &overrides).unwrap();
    let flat = flatten(&scene);
    let mut cpu = CpuRenderer::new(&flat);
    let cancel = AtomicBool::new(false);
    // Stop when the first pass has finished: the batches already in flight finish too.
    let output = render(
        &flat,
        &mut cpu,
        &mut |done, _| {
            if done == 1 {
                cancel.store(true, Ordering::Relaxed)
            }
        },
        &cancel,
    )
    .unwrap();
    assert!(matches!(
        output.stopped,
        Some(chambre::Error::Interrupted { .. })
    ));
    let plan = chambre::render::plan_passes(&flat, &chambre::render::RayBudgets::DEFAULT);
    assert!(plan.passes.len() > 1);
    assert_eq!(plan.light_windows.len(), 1);
    assert_eq!(
        plan.dispatches(0).len(),
        1,
        "one dispatch, so one batch, per pass"
    );
    assert_eq!(
        output.samples_per_pixel,
        chambre::render::BATCHES_IN_FLIGHT as u32 * plan.passes[0].1
    );
    assert_eq!(output.image.non_finite_count(), 0);
    let lit = output
        .image
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count();
    assert!(
        lit > output.image.pixels.len() / 2,
        "the partial image holds the finished samples"
    );
}

/// Adaptive sampling, tone mapping and the preview from the command line, end to end:
/// adaptive sampling reports what it reached and writes the counts; AgX writes a PNG;
/// `preview` writes its image and its frame time.
#[test]
fn adaptive_sampling_agx_and_the_preview_from_the_command_line() {
    drop(common::gpu_context());
    let dir = scratch("flags");
    std::fs::create_dir_all(&dir).unwrap();
    let (image, counts) = (dir.join("adaptive.exr"), dir.join("counts.pfm"));
    let output = chambre()
        .args(["render", "--backend", "cpu", "--spp", "32", "--width", "48"])
        .args([
            "--noise-target",
            "0.1",
            "--min-spp",
            "16",
            "--sample-counts",
        ])
        .arg(&counts)
        .arg("-o")
        .arg(&image)
        .arg(scene_path("area_light.toml"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("adaptive sampling: estimated relative error")
            && stderr.contains("against the noise target 0.1 (met"),
        "{stderr}"
    );
    assert!(image.exists() && counts.exists());
    let agx = dir.join("agx.png");
    let output = chambre()
        .args([
            "render",
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--width",
            "48",
            "--tonemap",
            "agx",
        ])
        .arg("-o")
        .arg(&agx)
        .arg(scene_path("area_light.toml"))
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let png = image::open(&agx).unwrap().into_rgb8();
    assert!(
        png.pixels().any(|p| p.0 != [0, 0, 0]),
        "an AgX image with something in it"
    );
    let preview = dir.join("preview.png");
    let output = chambre()
        .args(["preview", "--frames", "2", "-o"])
        .arg(&preview)
        .arg(scene_path("spheres.toml"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("ms a frame") && stderr.contains("no shadows"),
        "{stderr}"
    );
    assert_eq!(image::open(&preview).unwrap().width(), 480);
}

/// `preview --self-reflections` alone cuts the teapot's own reflected triangles for the default
/// tolerance (`preview::SELF_REFLECTION_TOLERANCE_PX`, the same count as naming it), a finer
/// tolerance gives more, and without the flag the teapot reflects none of its own. On a mirror
/// sphere, which cannot see itself, the flag is said to change nothing.
#[test]
fn self_reflections_from_the_command_line() {
    let preview = |scene: &str, extra: &[&str]| -> String {
        let output = chambre()
            .args(["preview", "--frames", "1", "--subdivision", "1"])
            .args(["-D", "render.width=96", "-D", "render.height=72", "-o"])
            .arg(scratch("mirror.png"))
            .arg(scene_path(scene))
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr).to_string();
        assert!(output.status.success(), "{stderr}");
        stderr
    };
    let reflected = |extra: &[&str]| -> u64 {
        let stderr = preview("fermat_teapot.toml", extra);
        assert!(!stderr.contains("changes nothing"), "{stderr}");
        let words: Vec<&str> = stderr.split_whitespace().collect();
        let at = words
            .iter()
            .position(|w| *w == "reflected")
            .expect("a reflected count");
        words[at - 1].parse().unwrap()
    };
    let without = reflected(&[]);
    let default = reflected(&["--self-reflections"]);
    let named = reflected(&[
        "--self-reflections",
        chambre::preview::SELF_REFLECTION_TOLERANCE_PX,
    ]);
    let finer = reflected(&["--self-reflections", "0.5"]);
    eprintln!("reflected triangles: {without} without, {default} with, {finer} finer");
    assert_eq!(default, named);
    assert!(
        without < default && default < finer,
        "{without}, {default}, {finer}"
    );
    let sphere = preview("fermat_sphere.toml", &["--self-reflections"]);
    assert!(
        sphere.contains("--self-reflections changes nothing here"),
        "{sphere}"
    );
}
