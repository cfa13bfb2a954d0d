//! The `chambre` command line at its edges: output paths that cannot take the image fail before
//! the render, writes are atomic and every write error is an error, SIGINT and SIGTERM stop a
//! long render promptly and keep its samples, a closed stdout or stderr is not a panic, a far
//! plane before the near plane is refused, `--backend auto` survives a GPU refusal,
//! non-finite pixels are written and reported, and counts of 0 (runs, frames, sizes,
//! subdivisions) are refused before anything runs.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;

use chambre::cpu::CpuRenderer;
use chambre::layout::GpuPass;
use chambre::output::{NON_FINITE_PNG, OutputTarget};
use chambre::pack::flatten;
use chambre::render::{Backend, Image, RayBudgets, render};

mod common;

fn chambre() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_chambre"));
    command.current_dir(env!("CARGO_MANIFEST_DIR"));
    command
}

/// A fresh, empty directory for one test.
fn scratch_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-edges-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn stderr_of(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A 48x32 CPU render of the sample scene into `out`, with extra arguments.
/// `chambre render scenes/spheres.toml --backend cpu -o OUT EXTRA...` at the scene's size.
fn render_spheres_on_cpu(out: &Path, extra: &[&str]) -> Output {
    chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu", "-o"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn small_render(out: &Path, extra: &[&str]) -> Output {
    small_render_with(out, "cpu", extra)
}

fn small_render_on(out: &Path, backend: &str) -> Output {
    small_render_with(out, backend, &[])
}

fn small_render_with(out: &Path, backend: &str, extra: &[&str]) -> Output {
    chambre()
        .args(["render", "scenes/spheres.toml", "--backend", backend])
        .args(["--width", "48", "--height", "32", "--spp", "2", "-o"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn an_output_path_that_cannot_take_the_image_fails_before_the_render() {
    let dir = scratch_dir("precheck");
    std::fs::write(dir.join("file.png"), b"not a directory").unwrap();
    std::os::unix::fs::symlink("/dev/full", dir.join("full.png")).unwrap();
    let before = entries(&dir);
    let cases = [
        ("missing/out.png", "directory"),
        ("file.png/out.png", "is not a directory"),
        ("out.ppm", "unknown image format `.ppm`"),
        ("out.bmp", "unknown image format `.bmp`"),
        ("out", "no file extension"),
        ("full.png", "not a regular file"),
        (".", "no file extension"),
    ];
    for (name, reason) in cases {
        let target = dir.join(name);
        let output = small_render(&target, &[]);
        let message = stderr_of(&output);
        assert_eq!(output.status.code(), Some(1), "{name}: {message}");
        assert!(message.contains(&*target.to_string_lossy()), "{message}");
        assert!(message.contains(reason), "{name}: {message}");
        assert!(
            !message.contains("progress:") && !message.contains("spp in"),
            "{name}: rendered before checking the output: {message}"
        );
    }
    assert_eq!(entries(&dir), before, "a refused output creates nothing");
    // Two outputs at one path, or a layer asked twice: refused before the render too.
    let image = dir.join("same.exr");
    let counts = dir.join("./same.exr");
    let refusals: [(&[&str], &str); 2] = [
        (
            &["--sample-counts", &*counts.to_string_lossy()],
            "the image's own path",
        ),
        (&["--aov", "depth,depth"], "--aov depth: given twice"),
    ];
    for (extra, reason) in refusals {
        let output = small_render(&image, extra);
        let message = stderr_of(&output);
        assert_eq!(output.status.code(), Some(1), "{message}");
        assert!(message.contains(reason), "{message}");
        assert!(
            !message.contains("spp in"),
            "rendered before refusing: {message}"
        );
    }
    assert_eq!(entries(&dir), before, "a refused output creates nothing");
}

/// An existing, write-protected file among a command's outputs is refused before any work, as
/// `cp` refuses to overwrite one, naming the file and `--force`; `--force` replaces it. The mode
/// bits decide, so this holds when the tests run as root, whom the system lets write any file.
#[test]
fn write_protected_outputs_are_refused_before_the_work_unless_forced() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch_dir("protected");
    let kept = b"a file its owner made read-only".to_vec();
    let protect = |name: &str, mode: u32| {
        let path = dir.join(name);
        std::fs::write(&path, &kept).unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).unwrap();
        path
    };
    let at = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let image = protect("out.png", 0o444);
    let sidecar = protect("side.png.json", 0o444);
    let counts = protect("counts.exr", 0o400);
    let manifest = protect("band.shard-1-of-2.json", 0o444);
    let merged = protect("merged.png", 0o444);
    let csv = protect("study.csv", 0o444);
    let plot = protect("plotted.svg", 0o444);
    let preview = protect("preview.png", 0o444);
    let xml = protect("scene.xml", 0o444);
    let render = [
        "render",
        "scenes/spheres.toml",
        "--backend",
        "cpu",
        "--spp",
        "1",
    ];
    let cases: Vec<(Vec<String>, &PathBuf)> = vec![
        (vec!["-o".into(), at("out.png")], &image),
        (
            vec!["-o".into(), at("side.png"), "--sidecar".into()],
            &sidecar,
        ),
        (
            vec![
                "-o".into(),
                at("a.exr"),
                "--sample-counts".into(),
                at("counts.exr"),
            ],
            &counts,
        ),
        (
            vec!["-o".into(), at("band.exr"), "--shard".into(), "1/2".into()],
            &manifest,
        ),
    ];
    let mut commands: Vec<(Vec<String>, &PathBuf)> = cases
        .into_iter()
        .map(|(args, file)| {
            let mut all: Vec<String> = render.iter().map(|a| a.to_string()).collect();
            all.extend(args);
            (all, file)
        })
        .collect();
    let strings = |args: &[&str]| args.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    commands.push((
        strings(&["merge", "missing.json", "-o", &at("merged.png")]),
        &merged,
    ));
    let study = [
        "converge",
        "scenes/spheres.toml",
        "--max-spp",
        "1",
        "--reference-spp",
        "1",
    ];
    let mut csv_args = strings(&study);
    csv_args.extend(strings(&["--csv", &at("study.csv")]));
    commands.push((csv_args, &csv));
    let mut plot_args = strings(&study);
    plot_args.extend(strings(&["--csv", &at("plotted.csv")]));
    commands.push((plot_args, &plot));
    commands.push((
        strings(&["preview", "scenes/spheres.toml", "-o", &at("preview.png")]),
        &preview,
    ));
    let export = strings(&[
        "export",
        "scenes/spheres.toml",
        "--approximate",
        "--mitsuba",
        &at("scene.xml"),
    ]);
    commands.push((export.clone(), &xml));
    let before = entries(&dir);
    for (args, file) in &commands {
        let output = chambre().args(args).output().unwrap();
        let message = stderr_of(&output);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {message}");
        for part in [
            file.to_string_lossy().as_ref(),
            "write-protected",
            "--force",
        ] {
            assert!(
                message.contains(part),
                "{args:?}: `{part}` not in {message}"
            );
        }
        assert!(
            !message.contains("spp in"),
            "{args:?} rendered first: {message}"
        );
        assert_eq!(std::fs::read(file).unwrap(), kept, "{args:?}");
    }
    assert_eq!(entries(&dir), before, "a refused command writes nothing");
    // A file its group or others may write is not protected from its owner's renders.
    let shared = protect("shared.png", 0o664);
    assert!(small_render(&shared, &[]).status.success());
    // --force replaces it, with a new file of the ordinary mode.
    for (args, file) in &commands[..1] {
        let output = chambre().args(args).arg("--force").output().unwrap();
        assert!(output.status.success(), "{args:?}: {}", stderr_of(&output));
        assert_eq!(image::open(file).unwrap().width(), 480);
        let mode = std::fs::metadata(file).unwrap().permissions().mode();
        assert_ne!(mode & 0o200, 0, "{mode:o}");
    }
    let output = chambre()
        .args(&commands[1].0)
        .arg("--force")
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert!(
        std::fs::read_to_string(&sidecar)
            .unwrap()
            .contains("\"seed\"")
    );
    let output = chambre().args(&export).arg("--force").output().unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert!(std::fs::read_to_string(&xml).unwrap().contains("<scene"));
}

#[test]
fn a_failed_write_keeps_the_previous_image_and_a_good_one_replaces_it() {
    let dir = scratch_dir("atomic");
    let target = dir.join("out.exr");
    let previous = b"the previous image, which a failed write must not touch".repeat(100);
    std::fs::write(&target, &previous).unwrap();
    // Files of this process tree may not exceed 16 blocks (8 or 16 KiB), far below the 18 KiB
    // of the EXR; with SIGXFSZ ignored the write fails with EFBIG instead of killing chambre.
    let output = Command::new("sh")
        .args(["-c", r#"trap "" XFSZ; ulimit -f 16; exec "$0" "$@""#])
        .arg(env!("CARGO_BIN_EXE_chambre"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args(["--width", "48", "--height", "32", "--spp", "2", "-o"])
        .arg(&target)
        .output()
        .unwrap();
    let message = stderr_of(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(message.contains("out.exr: cannot write: "), "{message}");
    assert_eq!(std::fs::read(&target).unwrap(), previous);
    assert_eq!(entries(&dir), ["out.exr"], "no temporary file is left");

    let output = small_render(&target, &[]);
    assert!(output.status.success(), "{}", stderr_of(&output));
    let written = image::open(&target).unwrap().into_rgb32f();
    assert_eq!((written.width(), written.height()), (48, 32));
    assert_eq!(entries(&dir), ["out.exr"]);
}

/// Waits for `child` at most `limit`; a hang is a test failure, not a stuck suite.
fn wait_at_most(child: &mut Child, limit: Duration) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!("chambre did not stop within {limit:?} of the signal");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Starts a CPU render that would take most of an hour, sends `signal` once it is under way,
/// and checks it stops with code 130 and writes a readable image holding samples.
fn signal_stops_a_long_render_and_keeps_its_samples(signal: &str) {
    let dir = scratch_dir(signal);
    let target = dir.join("long.png");
    let mut child = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args(["--width", "384", "--height", "256", "--spp", "100000", "-o"])
        .arg(&target)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Loading takes milliseconds and a row of 128 pixels x 8 samples about one; two seconds
    // leave many rows rendered even on a loaded machine.
    std::thread::sleep(Duration::from_secs(2));
    let kill = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(kill.success());
    let status = wait_at_most(&mut child, Duration::from_secs(20));
    let mut message = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut message).unwrap();
    assert_eq!(status.code(), Some(130), "{message}");
    assert!(message.contains("render interrupted"), "{message}");
    assert!(message.contains("wrote the partial image"), "{message}");
    let written = image::open(&target).unwrap().into_rgb8();
    assert_eq!((written.width(), written.height()), (384, 256));
    assert!(
        written.pixels().any(|p| p.0 != [0, 0, 0]),
        "the partial image holds the samples taken"
    );
    assert_eq!(entries(&dir), ["long.png"]);
}

#[test]
fn sigint_stops_a_long_render_and_keeps_its_samples() {
    signal_stops_a_long_render_and_keeps_its_samples("INT");
}

#[test]
fn sigterm_stops_a_long_render_and_keeps_its_samples() {
    signal_stops_a_long_render_and_keeps_its_samples("TERM");
}

/// Waits for `child` as `wait_at_most` does, and returns with its status the most memory it
/// held at once (its peak resident set, from the kernel's accounting at its exit).
fn wait_with_peak_memory(child: &mut Child, limit: Duration) -> (i32, u64) {
    let start = Instant::now();
    let pid = child.id() as libc::pid_t;
    loop {
        let mut status = 0;
        // SAFETY: `rusage` is plain data that wait4 fills; `pid` is our own child, reaped here
        // (std's `Child` is not waited on afterwards).
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        let reaped = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        assert!(reaped >= 0, "wait4: {}", std::io::Error::last_os_error());
        if reaped == pid {
            assert!(
                libc::WIFEXITED(status),
                "chambre ended by a signal: {status:#x}"
            );
            // ru_maxrss is in KiB on Linux.
            return (libc::WEXITSTATUS(status), usage.ru_maxrss as u64 * 1024);
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!("chambre did not stop within {limit:?} of the signal");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A huge render stopped early writes its image without touching memory for the pixels that
/// have no sample: it holds at most the rows it sampled, not the 8192^2 image's 2 GiB of sums,
/// means and counts (touched whole, they made a 16384^2 render take 13 s from SIGINT to its
/// image on 2 cores; `docs/robustness.md`). The memory is the property tested, not the time;
/// the time limit is only there so that a hang fails.
#[test]
fn a_huge_render_stopped_early_holds_memory_for_its_samples_alone() {
    let dir = scratch_dir("huge");
    let target = dir.join("huge.exr");
    let mut child = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args([
            "-D",
            "camera.film=[24.0, 24.0]",
            "--width",
            "8192",
            "--height",
            "8192",
        ])
        .args(["--spp", "1048576", "-o"])
        .arg(&target)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Loading takes milliseconds; two seconds render a few dozen to a few hundred rows.
    std::thread::sleep(Duration::from_secs(2));
    assert!(
        Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap()
            .success()
    );
    let (code, peak) = wait_with_peak_memory(&mut child, Duration::from_secs(300));
    let mut message = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut message).unwrap();
    assert_eq!(code, 130, "{message}");
    assert!(message.contains("wrote the partial image"), "{message}");
    let unsampled: u64 = message
        .split(" pixels without a sample")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count of pixels without a sample in {message}"));
    let pixels = 8192 * 8192;
    assert!(
        unsampled > pixels / 2,
        "most pixels were still to sample: {message}"
    );
    // What the sampled rows take (16 bytes of sums, 12 of mean, 4 of count a pixel, and the
    // encoded EXR's 12 more), with 256 MiB for the rest of the process; a whole image's would
    // be 2 GiB of sums, means and counts.
    let sampled = pixels - unsampled;
    let bound = sampled * (16 + 12 + 4 + 12) + (256 << 20);
    assert!(
        peak < bound,
        "peak memory {} MiB for {sampled} sampled pixels (bound {} MiB)",
        peak >> 20,
        bound >> 20
    );
    let mut reader = image::ImageReader::open(&target).unwrap();
    reader.no_limits();
    let written = reader.decode().unwrap().into_rgb32f();
    assert_eq!(written.dimensions(), (8192, 8192));
    let first_rows = written.pixels().take(8192 * 8);
    assert!(
        first_rows.filter(|p| p.0 != [0.0; 3]).count() > 8192,
        "the first rows hold their samples"
    );
}

/// `spheres` at 192 x 128 pixels and 4 spp in one pass, with budgets small enough that a
/// dispatch covers 8 rows and a batch one dispatch: 16 batches.
fn eight_row_batches() -> (chambre::pack::FlatScene, RayBudgets) {
    let scene = common::load(
        "scenes/spheres.toml",
        &["render.width=192", "render.height=128", "render.spp=4"],
    );
    let flat = flatten(&scene);
    let rays_per_row = 192 * 4 * chambre::render::RayBound::of(&flat).per_sample();
    let budgets = RayBudgets {
        per_dispatch: 8 * rays_per_row,
        per_batch: 8 * rays_per_row,
        ..RayBudgets::DEFAULT
    };
    (flat, budgets)
}

#[test]
fn a_render_stopped_between_batches_reports_the_samples_each_pixel_holds() {
    // Stop when the first batch has finished: the batches in flight by then
    // (BATCHES_IN_FLIGHT of them) finish too, the other rows get nothing.
    let (flat, budgets) = eight_row_batches();
    let plan = chambre::render::plan_passes(&flat, &budgets);
    assert_eq!((plan.passes.len(), plan.bands.len()), (1, 16));
    let cancel = AtomicBool::new(false);
    let mut cpu = CpuRenderer::new(&flat)
        .with_cancel(&cancel)
        .with_budgets(budgets);
    let output = render(
        &flat,
        &mut cpu,
        &mut |done, _| cancel.store(done == 1, Ordering::Relaxed),
        &cancel,
    )
    .unwrap();
    assert!(output.stopped.is_some());
    assert_eq!(output.samples_per_pixel, 0);
    assert_eq!(output.max_samples_per_pixel, 4);
    let rendered_rows = 8 * chambre::render::BATCHES_IN_FLIGHT;
    assert_eq!(output.pixels_without_samples, 192 * (128 - rendered_rows));
    // A stop before the first batch: no pixel has a sample.
    let mut cpu = CpuRenderer::new(&flat);
    let output = render(&flat, &mut cpu, &mut |_, _| {}, &AtomicBool::new(true)).unwrap();
    assert_eq!(output.max_samples_per_pixel, 0);
    assert_eq!(output.pixels_without_samples, 192 * 128);
}

#[test]
fn a_cancelled_cpu_renderer_adds_no_row_to_the_accumulation() {
    let scene = common::load(
        "scenes/spheres.toml",
        &["render.width=48", "render.height=32", "render.spp=2"],
    );
    let flat = flatten(&scene);
    let cancel = AtomicBool::new(true);
    let mut cpu = CpuRenderer::new(&flat).with_cancel(&cancel);
    let pass = GpuPass {
        tile_width: 48,
        tile_height: 32,
        sample_count: 2,
        light_sample_count: u32::MAX,
        commit: 1,
        ..Default::default()
    };
    let status = cpu.run_dispatch(&pass);
    assert_eq!(status.rays, 0);
    assert!(cpu.accumulation().unwrap().iter().all(|a| *a == [0.0; 4]));
    cancel.store(false, Ordering::Relaxed);
    let mut cpu = CpuRenderer::new(&flat).with_cancel(&cancel);
    assert!(cpu.run_dispatch(&pass).rays > 0);
    assert!(cpu.accumulation().unwrap().iter().all(|a| a[3] == 2.0));
}

/// A pipe whose reader is already gone: writing to it fails with EPIPE every time.
fn closed_pipe() -> std::io::PipeWriter {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    writer
}

#[test]
fn a_closed_stdout_or_stderr_is_not_a_panic() {
    for args in [
        &["check", "scenes/tabletop.toml"][..],
        &["camera", "scenes/tabletop.toml"],
        &["info"],
    ] {
        let output = chambre().args(args).stdout(closed_pipe()).output().unwrap();
        let message = stderr_of(&output);
        assert!(output.status.success(), "{args:?}: {message}");
        assert!(
            !message.contains("panicked") && !message.contains("error"),
            "{args:?} exits quietly: {message}"
        );
    }
    // A full disk behind `>` is an error, not a quiet exit.
    let output = chambre()
        .args(["check", "scenes/tabletop.toml"])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr_of(&output).contains("writing to stdout"));
    // A render whose log reader went away still writes its image.
    let target = scratch_dir("stderr").join("out.png");
    let status = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args(["--width", "48", "--height", "32", "--spp", "2", "-o"])
        .arg(&target)
        .stderr(closed_pipe())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(image::open(&target).unwrap().width(), 48);
}

#[test]
fn a_far_plane_not_beyond_the_near_plane_is_refused_naming_both() {
    let report = chambre()
        .args(["camera", "scenes/spheres.toml"])
        .output()
        .unwrap();
    let text = String::from_utf8(report.stdout).unwrap();
    let near = text
        .split("near ")
        .nth(1)
        .and_then(|rest| rest.split(',').next())
        .unwrap_or_else(|| panic!("no frustum near in\n{text}"));
    let far = near.parse::<f64>().unwrap() / 2.0;
    for far in [far.to_string(), near.to_string()] {
        let output = chambre()
            .args(["camera", "scenes/spheres.toml", "--far", &far])
            .output()
            .unwrap();
        let message = stderr_of(&output);
        assert_eq!(output.status.code(), Some(1), "{message}");
        assert!(message.contains(&format!("--far {}", far.parse::<f64>().unwrap())));
        assert!(message.contains(&format!("near plane of the raster projection, at {near}")));
        assert!(output.stdout.is_empty(), "no degenerate matrix is printed");
    }
}

#[test]
fn auto_backend_falls_back_to_the_cpu_when_the_gpu_refuses_the_scene() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let cpu_adapter = context.is_cpu_adapter;
    // An accumulation buffer (16 bytes a pixel) one row over the adapter's binding limit.
    let limit = context.device.limits().max_storage_buffer_binding_size;
    let width = 4096u64;
    let height = (limit / 16).div_ceil(width) + 1;
    assert!(
        height <= 16384,
        "the adapter's binding limit ({limit} bytes) is beyond any image chambre renders"
    );
    let dir = scratch_dir("auto");
    let scene = dir.join("empty.toml");
    std::fs::write(
        &scene,
        format!(
            "[render]\nwidth = {width}\nheight = {height}\nspp = 1\nbackground = [0.2, 0.3, 0.4]\n\
             [camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             film = [{}, {}]\n",
            width as f64 / 100.0,
            height as f64 / 100.0
        ),
    )
    .unwrap();
    let target = dir.join("empty.png");
    let render_on = |backend: &str| {
        chambre()
            .arg("render")
            .arg(&scene)
            .args(["--backend", backend, "-o"])
            .arg(&target)
            .output()
            .unwrap()
    };
    let gpu = render_on("gpu");
    assert_eq!(gpu.status.code(), Some(1));
    assert!(stderr_of(&gpu).contains("max_storage_buffer_binding_size"));
    assert!(!target.exists());
    let auto = render_on("auto");
    let message = stderr_of(&auto);
    assert!(auto.status.success(), "{message}");
    let notices: Vec<&str> = message
        .lines()
        .filter(|l| l.starts_with("notice:"))
        .collect();
    assert_eq!(notices.len(), 1, "{message}");
    // On lavapipe `auto` prefers the CPU path before it asks the adapter for anything; on a
    // real GPU it is the refusal that sends the render to the CPU.
    if cpu_adapter {
        assert!(notices[0].contains("runs on the CPU"), "{message}");
    } else {
        assert!(notices[0].contains("max_storage_buffer_binding_size"));
        assert!(notices[0].ends_with("rendering on the CPU"));
    }
    assert!(message.contains("on CPU"));
    let written = image::open(&target).unwrap().into_rgb8();
    assert_eq!(
        (written.width() as u64, written.height() as u64),
        (width, height)
    );
}

/// Validation bounds intensities (1e20), but not distances: a point light 1e-10 from a sphere
/// of radius 1e-9 gives irradiances of 1e40, beyond f32, on the pixels nearest the light.
const TINY_SCENE: &str = r#"[render]
width = 48
height = 32
spp = 2
[camera]
position = [0.0, 0.0, 4e-9]
look_at = [0.0, 0.0, 0.0]
[[materials]]
name = "white"
model = "lambert"
[[shapes]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1e-9
material = "white"
[[lights]]
type = "point"
position = [0.0, 0.0, 1.1e-9]
intensity = [1e20, 1e20, 1e20]
"#;

#[test]
fn non_finite_pixels_are_written_and_counted_and_the_exit_is_an_error() {
    let dir = scratch_dir("nonfinite");
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, TINY_SCENE).unwrap();
    for name in ["inf.exr", "inf.png"] {
        let target = dir.join(name);
        let output = chambre()
            .args(["render", "--backend", "cpu", "-o"])
            .arg(&target)
            .arg(&scene)
            .output()
            .unwrap();
        let message = stderr_of(&output);
        assert_eq!(output.status.code(), Some(1), "{message}");
        let reported: usize = message
            .lines()
            .find_map(|l| {
                l.strip_prefix("error: ")?
                    .split_once(" pixels are not finite")
            })
            .and_then(|(n, _)| n.parse().ok())
            .unwrap_or_else(|| panic!("no count in {message}"));
        assert!(reported > 0);
        let written = image::open(&target).unwrap();
        let in_file = if name.ends_with(".exr") {
            assert!(message.contains("kept as inf/NaN in the EXR"), "{message}");
            let floats = written.into_rgb32f();
            floats
                .pixels()
                .filter(|p| p.0.iter().any(|c| !c.is_finite()))
                .count()
        } else {
            assert!(
                message.contains("written as magenta in the PNG"),
                "{message}"
            );
            let bytes = written.into_rgb8();
            bytes.pixels().filter(|p| p.0 == NON_FINITE_PNG).count()
        };
        assert_eq!(in_file, reported, "{name}");
    }
}

#[test]
fn the_written_exr_keeps_inf_and_nan_and_the_png_marks_them() {
    let pixels = vec![
        Vec3::new(0.5, 0.25, 1.0),
        Vec3::new(f32::INFINITY, 0.0, 0.0),
        Vec3::new(0.0, f32::NAN, 0.0),
        Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
    ];
    let image = Image {
        width: 2,
        height: 2,
        pixels: pixels.clone(),
    };
    let dir = scratch_dir("library");
    let exr = OutputTarget::prepare(&dir.join("x.exr")).unwrap();
    exr.write(&image).unwrap();
    let floats = image::open(dir.join("x.exr")).unwrap().into_rgb32f();
    for (read, expected) in floats.pixels().zip(&pixels) {
        for (r, e) in read.0.iter().zip(expected.to_array()) {
            assert!(r == &e || (r.is_nan() && e.is_nan()), "{r} != {e}");
        }
    }
    let png = OutputTarget::prepare(&dir.join("x.png")).unwrap();
    png.write(&image).unwrap();
    let bytes = image::open(dir.join("x.png")).unwrap().into_rgb8();
    let read: Vec<[u8; 3]> = bytes.pixels().map(|p| p.0).collect();
    assert_eq!(read[0], [188, 137, 255]);
    assert_eq!(&read[1..], [NON_FINITE_PNG; 3]);
}

/// `--stats` reports where the time and rays went: the same ray count as the summary line, the
/// dispatches and batches, the BVH, and the features the code was specialised to.
#[test]
fn stats_report_rays_time_dispatches_bvh_and_features() {
    let target = scratch_dir("stats").join("stats.exr");
    let output = small_render(&target, &["--stats"]);
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    let stat = |prefix: &str| -> String {
        message
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` in {message}"))
            .to_string()
    };
    let rays: u64 = stat("stats: ")
        .trim_start_matches("stats: ")
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(message.contains(&format!("({rays} rays)")), "{message}");
    assert!(
        stat("stats: wall").contains("kernel time not measured"),
        "CPU path"
    );
    assert!(stat("stats: BVH").contains("expected loop iterations per ray"));
    // spheres.toml: mirrors, a point light, a plane (0x2a).
    assert!(stat("stats: code specialised").contains("0x2a (MIRRORS, PUNCTUAL_LIGHTS, PLANES)"));
    let counts: Vec<u64> = message
        .lines()
        .find(|l| l.contains(" dispatches in "))
        .unwrap_or_else(|| panic!("no dispatch count in {message}"))
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    let (dispatches, batches) = (counts[0], counts[1]);
    assert!(
        dispatches >= batches && batches >= 1,
        "{dispatches} {batches}"
    );
}

/// `--backend auto` renders on the GPU when it is a real one, and on chambre's faster CPU path
/// when the only adapter is a CPU implementation of the API (lavapipe), saying why.
#[test]
fn auto_backend_prefers_the_cpu_path_to_a_cpu_adapter() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let target = scratch_dir("auto-cpu").join("spheres.png");
    let output = small_render_on(&target, "auto");
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    if context.is_cpu_adapter {
        assert!(
            message.contains("runs on the CPU; chambre's CPU path is faster"),
            "{message}"
        );
        assert!(message.contains("on CPU: "), "{message}");
    } else {
        assert!(message.contains("on GPU: "), "{message}");
    }
    // `--backend gpu` still uses the adapter, whatever it is.
    let forced = small_render_on(&target, "gpu");
    assert!(
        stderr_of(&forced).contains("on GPU: "),
        "{}",
        stderr_of(&forced)
    );
}

/// `--width` alone takes its height from the film's aspect (and says so), `--height` alone
/// its width; `--threads` sets the CPU path's threads, and 0 is refused.
#[test]
fn one_image_side_keeps_the_film_aspect_and_threads_are_chosen() {
    let dir = scratch_dir("size");
    let render = |extra: &[&str], name: &str| {
        let target = dir.join(name);
        (
            render_spheres_on_cpu(&target, &[&["--spp", "1"], extra].concat()),
            target,
        )
    };
    // spheres.toml: a 36 x 24 mm film.
    let (output, target) = render(&["--width", "200", "--threads", "1"], "w.png");
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    assert!(
        message.contains("200x133 pixels keep the film's 36 x 24 mm aspect"),
        "{message}"
    );
    assert!(
        message.contains("on CPU: 1 thread\n") || message.ends_with("on CPU: 1 thread"),
        "{message}"
    );
    assert_eq!(image::image_dimensions(&target).unwrap(), (200, 133));
    let (output, target) = render(&["--height", "77"], "h.png");
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(image::image_dimensions(&target).unwrap(), (116, 77));
    let (output, _) = render(&["--threads", "0"], "t.png");
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr_of(&output).contains("--threads must be at least 1"));
    // A side whose partner rounds by half a pixel (30 / (4/3) = 22.5 -> 23): the aspect the
    // note promises is the one the render accepts.
    let target = dir.join("half.png");
    let output = chambre()
        .args(["render", "scenes/fermat_sphere.toml", "--backend", "cpu"])
        .args(["--spp", "1", "--width", "30", "-o"])
        .arg(&target)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(image::image_dimensions(&target).unwrap(), (30, 23));
    // A film `--set` to another aspect than the scene's own image size: the one side given
    // takes the film's aspect (the scene's size, which would not match it, gives way).
    let (output, target) = render(&["--width", "60", "--set", "camera.film=[20, 40]"], "f.png");
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(image::image_dimensions(&target).unwrap(), (60, 120));
    // An orthographic camera's window, likewise.
    let target = dir.join("window.png");
    let output = chambre()
        .args([
            "render",
            "scenes/elevation.toml",
            "--backend",
            "cpu",
            "--spp",
            "1",
        ])
        .args([
            "--height",
            "20",
            "--set",
            "camera.window=[40.0, 10.0]",
            "-o",
        ])
        .arg(&target)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(image::image_dimensions(&target).unwrap(), (80, 20));
    // `--quick` quarters the size `--set` gives, and says so truly.
    let target = dir.join("quick.png");
    let output = render_spheres_on_cpu(
        &target,
        &[
            "--quick",
            "--set",
            "render.width=72",
            "--set",
            "render.height=48",
        ],
    );
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    assert!(message.contains("--quick renders 18x12"), "{message}");
    assert_eq!(image::image_dimensions(&target).unwrap(), (18, 12));
}

/// `--time-budget` and `--progressive` beyond what a clock can count are refused by name, not
/// a panic; a budget too short for one sample writes nothing and says so with an error exit,
/// leaving no stale image looking like the render's.
#[test]
fn budgets_at_the_extremes_are_refused_or_fail_plainly() {
    let dir = scratch_dir("budget_extremes");
    let target = dir.join("b.pfm");
    for (flag, value) in [
        ("--time-budget", "1e300"),
        ("--time-budget", "1.8e19"),
        ("--progressive", "1e20"),
    ] {
        let output = render_spheres_on_cpu(&target, &[flag, value]);
        assert_eq!(output.status.code(), Some(1), "{flag} {value}");
        let message = stderr_of(&output);
        assert!(
            message.contains(flag) && message.contains("at most"),
            "{message}"
        );
    }
    let output = render_spheres_on_cpu(&target, &["--noise-target", "nan"]);
    assert_eq!(output.status.code(), Some(1));
    let message = stderr_of(&output);
    assert!(message.contains("render.noise_target"), "{message}");
    let output = render_spheres_on_cpu(&target, &["--time-budget", "1e-9"]);
    let message = stderr_of(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains("before any pixel had a sample"),
        "{message}"
    );
    assert!(!target.exists());
}

/// `--sidecar` writes OUT.json beside the image with what reproduces it; `.pfm` writes the same
/// floats as `.exr`.
#[test]
fn a_sidecar_records_the_render_and_pfm_keeps_the_floats() {
    let dir = scratch_dir("sidecar");
    let exr = dir.join("s.exr");
    let output = small_render(&exr, &["--sidecar", "--seed", "9"]);
    assert!(output.status.success(), "{}", stderr_of(&output));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.exr.json")).unwrap()).unwrap();
    assert_eq!(record["seed"], 9);
    assert_eq!(
        (record["width"].as_u64(), record["height"].as_u64()),
        (Some(48), Some(32))
    );
    assert_eq!(
        (record["spp_min"].as_u64(), record["spp_max"].as_u64()),
        (Some(2), Some(2))
    );
    assert_eq!(record["status"], "complete");
    assert!(record["rays"].as_u64().unwrap() > 0);
    let scene = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spheres.toml"));
    assert_eq!(
        record["scene_hash"],
        format!("{:016x}", chambre::provenance::fnv1a64(&scene.unwrap()))
    );
    assert!(
        record["overrides"]
            .as_array()
            .unwrap()
            .iter()
            .any(|o| o == "render.seed=9")
    );
    // The same render as a PFM: the EXR's floats, bottom row first.
    let pfm = dir.join("s.pfm");
    let output = small_render(&pfm, &["--seed", "9"]);
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert!(!dir.join("s.pfm.json").exists(), "no sidecar unless asked");
    let bytes = std::fs::read(&pfm).unwrap();
    let header = b"PF\n48 32\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let floats: Vec<f32> = bytes[header.len()..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let exr = image::open(&exr).unwrap().into_rgb32f();
    for y in 0..32u32 {
        for x in 0..48u32 {
            let i = (((31 - y) * 48 + x) * 3) as usize;
            assert_eq!(&floats[i..i + 3], &exr.get_pixel(x, y).0, "pixel {x},{y}");
        }
    }
}

/// `--quick` renders a quarter of each side at a sixteenth of the samples of whatever the
/// scene and the other flags ask.
#[test]
fn quick_renders_a_smaller_cheaper_preview() {
    let dir = scratch_dir("quick");
    let run = |extra: &[&str], name: &str| {
        let target = dir.join(name);
        let output = render_spheres_on_cpu(&target, &[&["--quick"], extra].concat());
        assert!(output.status.success(), "{}", stderr_of(&output));
        (
            stderr_of(&output),
            image::image_dimensions(&target).unwrap(),
        )
    };
    // spheres.toml: 480x320 at 16 spp.
    let (message, size) = run(&[], "a.png");
    assert_eq!(size, (120, 80));
    assert!(
        message.contains("--quick renders 120x80 at 1 spp"),
        "{message}"
    );
    let (message, size) = run(&["--spp", "64", "--width", "200"], "b.png");
    assert_eq!(size, (50, 33));
    assert!(message.contains("at 4 spp"), "{message}");
}

/// Three shards merged are the single render, bit for bit; a missing or foreign shard is an
/// error naming its manifest; `auto/N` takes the index from the batch engine's variable.
#[test]
fn shards_merge_into_the_single_render_bit_for_bit() {
    let dir = scratch_dir("shards");
    let full = dir.join("full.exr");
    assert!(small_render(&full, &[]).status.success());
    let render_shard = |shard: &str, env: Option<(&str, &str)>| {
        let mut command = chambre();
        command
            .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
            .args([
                "--width", "48", "--height", "32", "--spp", "2", "--shard", shard, "-o",
            ])
            .arg(dir.join("out.exr"));
        for name in chambre::shard::INDEX_VARIABLES {
            command.env_remove(name);
        }
        if let Some((name, value)) = env {
            command.env(name, value);
        }
        let output = command.output().unwrap();
        assert!(output.status.success(), "{}", stderr_of(&output));
    };
    render_shard("0/3", None);
    render_shard("auto/3", Some(("SLURM_ARRAY_TASK_ID", "1")));
    render_shard("auto/3", Some(("JOB_COMPLETION_INDEX", "2")));
    let manifests: Vec<PathBuf> = (0..3)
        .map(|i| dir.join(format!("out.shard-{i}-of-3.json")))
        .collect();
    let merged = dir.join("merged.exr");
    let output = chambre()
        .arg("merge")
        .args(&manifests)
        .arg("-o")
        .arg(&merged)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let read = |path: &PathBuf| image::open(path).unwrap().into_rgb32f();
    let (a, b) = (read(&full), read(&merged));
    assert_eq!(a.dimensions(), b.dimensions());
    assert!(
        a.as_raw()
            .iter()
            .zip(b.as_raw())
            .all(|(x, y)| x.to_bits() == y.to_bits()),
        "the merged image differs from the single render"
    );
    // Two of three shards: refused, naming a manifest.
    let output = chambre()
        .arg("merge")
        .args(&manifests[..2])
        .arg("-o")
        .arg(dir.join("partial.exr"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr_of(&output).contains("2 manifests given for a render of 3 shards"));
    assert!(!dir.join("partial.exr").exists());
    let merge = |inputs: &[PathBuf], out: &Path| {
        chambre()
            .arg("merge")
            .args(inputs)
            .arg("-o")
            .arg(out)
            .output()
            .unwrap()
    };
    // Given in any order (`ls -t`, `find`): the same image.
    let reversed: Vec<PathBuf> = manifests.iter().rev().cloned().collect();
    let output = merge(&reversed, &dir.join("reversed.exr"));
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(read(&dir.join("reversed.exr")).as_raw(), b.as_raw());
    // Writing over one of its own inputs: refused before anything is written.
    let band_1 = dir.join("out.shard-1-of-3.exr");
    let before = std::fs::read(&band_1).unwrap();
    let output = merge(&manifests, &band_1);
    assert_eq!(output.status.code(), Some(1), "{}", stderr_of(&output));
    assert!(stderr_of(&output).contains("an input of the merge"));
    assert_eq!(std::fs::read(&band_1).unwrap(), before);
    // A band replaced by another of the same size: refused, naming the band.
    // (Shards 1 and 2 are 11 rows each.)
    let band_2 = dir.join("out.shard-2-of-3.exr");
    std::fs::copy(&band_2, &band_1).unwrap();
    let output = merge(&manifests, &dir.join("swapped.exr"));
    assert_eq!(output.status.code(), Some(1));
    let message = stderr_of(&output);
    assert!(
        message.contains("out.shard-1-of-3.exr") && message.contains("hash"),
        "{message}"
    );
    // A shard that holds fewer samples (stopped by a signal or a time budget, as its manifest
    // says): merged, with a note saying the bands differ.
    render_shard_with(&dir, "1/3", "2");
    let manifest_1 = &manifests[1];
    let mut stopped: chambre::shard::Manifest =
        serde_json::from_str(&std::fs::read_to_string(manifest_1).unwrap()).unwrap();
    (stopped.spp_min, stopped.spp_max) = (1, 2);
    std::fs::write(manifest_1, serde_json::to_string(&stopped).unwrap()).unwrap();
    let output = merge(&manifests, &dir.join("uneven.exr"));
    assert!(output.status.success(), "{}", stderr_of(&output));
    let message = stderr_of(&output);
    assert!(
        message.contains("the bands hold 1 to 2 samples per pixel"),
        "{message}"
    );
    assert!(message.contains("shard 1: 1 to 2 spp"), "{message}");
    // More shards than rows: refused before rendering, not a panic.
    let output = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args([
            "--width", "6", "--height", "4", "--spp", "1", "--shard", "0/5", "-o",
        ])
        .arg(dir.join("thin.exr"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let message = stderr_of(&output);
    assert!(message.contains("5 shards of 4 rows"), "{message}");
}

/// Shard `shard` of spheres.toml at 48x32 and `spp` into `dir/out.exr`'s shard files.
fn render_shard_with(dir: &Path, shard: &str, spp: &str) {
    let output = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu"])
        .args(["--width", "48", "--height", "32", "--spp", spp])
        .args(["--shard", shard, "-o"])
        .arg(dir.join("out.exr"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
}

/// A band over the image crate's default decoding limit (512 MiB; a quarter of a 16384^2 render
/// is 768 MiB) merges like any other.
#[test]
fn a_band_larger_than_512_mib_merges() {
    let dir = scratch_dir("big-band");
    let (width, height) = (8192u32, 5500u32);
    let mut pixels: Vec<Vec3> = bytemuck::zeroed_vec((width * height) as usize);
    pixels[0] = Vec3::new(0.25, 0.5, 0.75);
    let band = Image {
        width,
        height,
        pixels,
    };
    assert!(band.pixels.len() * 12 > 512 << 20);
    let image = dir.join("big.shard-0-of-1.exr");
    OutputTarget::prepare(&image).unwrap().write(&band).unwrap();
    let manifest = chambre::shard::Manifest {
        shard: chambre::shard::Shard { index: 0, count: 1 },
        width,
        height,
        band: [0, width, 0, height],
        image: "big.shard-0-of-1.exr".into(),
        render_hash: "0".into(),
        spp_min: 1,
        spp_max: 1,
        band_hash: chambre::shard::band_hash(band.pixels.iter().map(|p| p.to_array())),
    };
    let manifest_path = dir.join("big.shard-0-of-1.json");
    std::fs::write(&manifest_path, serde_json::to_string(&manifest).unwrap()).unwrap();
    let merged = chambre::shard::merge(&[manifest_path]).unwrap().image;
    assert_eq!((merged.width, merged.height), (width, height));
    assert_eq!(merged.pixels[0], band.pixels[0]);
    assert_eq!(merged.pixels[1], Vec3::ZERO);
}

/// `--time-budget` stops a render that would take hours once the time is spent, successfully,
/// with an image of the samples taken and a note saying how many; a budget longer than the
/// render changes nothing.
#[test]
fn a_time_budget_stops_the_render_and_keeps_its_samples() {
    let dir = scratch_dir("budget");
    let target = dir.join("budget.exr");
    let started = std::time::Instant::now();
    let output = render_spheres_on_cpu(&target, &["--spp", "1000000", "--time-budget", "1.5"]);
    let took = started.elapsed().as_secs_f64();
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    assert!(took < 30.0, "a 1.5 s budget took {took} s");
    assert!(
        message.contains("note: the time budget was spent"),
        "{message}"
    );
    let image = image::open(&target).unwrap().into_rgb32f();
    assert_eq!(image.dimensions(), (480, 320));
    assert!(image.pixels().filter(|p| p.0[0] > 0.0).count() > 480 * 320 / 2);
    let output = small_render(&dir.join("short.exr"), &["--time-budget", "600"]);
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    assert!(!message.contains("time budget"), "{message}");
    assert!(message.contains(", 2 spp in "), "{message}");
}

/// `--sample-counts` writes the samples each pixel received: the requested spp everywhere on a
/// finished render, fewer (and the same as the message's range) on one stopped by its budget;
/// an 8-bit format is refused before the render.
#[test]
fn sample_counts_show_where_the_samples_went() {
    let dir = scratch_dir("counts");
    let counts = dir.join("counts.exr");
    let output = small_render(
        &dir.join("image.exr"),
        &["--sample-counts", counts.to_str().unwrap()],
    );
    assert!(output.status.success(), "{}", stderr_of(&output));
    let read = |path: &PathBuf| image::open(path).unwrap().into_rgb32f();
    let image = read(&counts);
    assert_eq!(image.dimensions(), (48, 32));
    assert!(image.pixels().all(|p| p.0 == [2.0; 3]), "2 spp everywhere");
    let budget = dir.join("budget.exr");
    let output = render_spheres_on_cpu(
        &dir.join("budget-image.exr"),
        &[
            "--spp",
            "1000000",
            "--time-budget",
            "0.5",
            "--sample-counts",
            budget.to_str().unwrap(),
        ],
    );
    assert!(output.status.success(), "{}", stderr_of(&output));
    let counts: Vec<f32> = read(&budget).pixels().map(|p| p.0[0]).collect();
    let max = counts.iter().copied().fold(0.0, f32::max);
    assert!(max > 0.0 && max < 1_000_000.0, "{max}");
    let output = small_render(&dir.join("x.exr"), &["--sample-counts", "counts.png"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr_of(&output).contains("use .exr or .pfm"));
}

/// `--progressive` writes the image during the render: the file is there, whole, before the
/// render ends, and the final note counts the writes; a non-positive interval is refused.
#[test]
fn progressive_writes_the_image_during_the_render() {
    let dir = scratch_dir("progressive");
    let target = dir.join("progressive.exr");
    let mut child = chambre()
        .args(["render", "scenes/spheres.toml", "--backend", "cpu", "-o"])
        .arg(&target)
        // A small image keeps each batch short (a batch never spans passes), so snapshots come
        // every 0.2 s even on a loaded machine.
        .args(["--width", "96", "--height", "64", "--spp", "1000000"])
        .args(["--time-budget", "3", "--progressive", "0.2"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !target.exists() && started.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let seen_during = child.try_wait().unwrap().is_none();
    assert!(
        target.exists() && seen_during,
        "no image before the render ended"
    );
    let early = image::open(&target).unwrap().into_rgb32f();
    assert_eq!(early.dimensions(), (96, 64));
    let output = child.wait_with_output().unwrap();
    let message = stderr_of(&output);
    assert!(output.status.success(), "{message}");
    let writes: u32 = message
        .split("was also written ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{message}"));
    assert!(writes >= 2, "{message}");
    let output = small_render(&dir.join("refused.exr"), &["--progressive", "0"]);
    assert!(!output.status.success());
    assert!(stderr_of(&output).contains("--progressive must be a positive number"));
}

/// A progressive write that fails stops the render with its error and keeps the samples.
#[test]
fn a_failing_progressive_write_stops_the_render_with_its_error() {
    let (flat, budgets) = eight_row_batches();
    let mut cpu = CpuRenderer::new(&flat).with_budgets(budgets);
    let mut write = |_: &Image| -> chambre::error::Result<()> {
        Err(chambre::error::Error::Gpu("disk full (a test)".into()))
    };
    let output = chambre::render::render_with_snapshots(
        &flat,
        &mut cpu,
        &mut |_, _| {},
        &AtomicBool::new(false),
        None,
        chambre::render::Snapshots {
            every: Duration::ZERO,
            write: &mut write,
        },
    )
    .unwrap();
    let stopped = output.stopped.map(|e| e.to_string()).unwrap_or_default();
    assert!(stopped.contains("disk full (a test)"), "{stopped}");
    assert_eq!(output.snapshots, 0);
    assert!(output.max_samples_per_pixel == 4 && output.pixels_without_samples > 0);
}

/// A count of 0 would measure nothing (NaN rates), or be taken silently as 1 (a subdivision, a
/// run): every such flag of `preview`, `bench` and `converge` refuses it, naming the flag,
/// before any scene is loaded or GPU opened; so is a Fermat step count over 1000.
#[test]
fn counts_of_zero_are_refused_with_the_flag_named() {
    // Past lavapipe's silent loop cut's reach, Fermat steps are refused too (1..=1000); a
    // tessellation tolerance must be a finite number of pixels above 0.
    let too_many_steps = [
        "preview",
        "scenes/fermat_sphere.toml",
        "-o",
        "x.png",
        "--fermat-steps",
        "100000",
    ];
    let cases: [&[&str]; 13] = [
        &too_many_steps,
        &[
            "preview",
            "scenes/fermat_sphere.toml",
            "-o",
            "x.png",
            "--tessellation-tolerance",
            "0",
        ],
        &[
            "preview",
            "scenes/fermat_sphere.toml",
            "-o",
            "x.png",
            "--tessellation-tolerance",
            "inf",
        ],
        &["bench", "fermat", "--tessellation-tolerance", "nan"],
        &[
            "preview",
            "scenes/fermat_sphere.toml",
            "-o",
            "x.png",
            "--subdivision",
            "0",
        ],
        &[
            "preview",
            "scenes/fermat_sphere.toml",
            "-o",
            "x.png",
            "--frames",
            "0",
        ],
        &[
            "preview",
            "scenes/fermat_sphere.toml",
            "-o",
            "x.png",
            "--fermat-steps",
            "0",
        ],
        &["bench", "fermat", "--subdivisions", "1,0"],
        &["bench", "rays", "--width", "0"],
        &["bench", "scale", "--prefixes", "1000,0"],
        &["bench", "scale", "--copies", "0"],
        &["bench", "motion", "--slices", "0"],
        &["converge", "scenes/bokeh.toml", "--runs", "0"],
    ];
    for args in cases {
        let output = chambre().args(args).output().unwrap();
        let flag = args.iter().rev().nth(1).unwrap();
        assert_eq!(
            output.status.code(),
            Some(2),
            "{args:?}: {}",
            stderr_of(&output)
        );
        let stderr = stderr_of(&output);
        assert!(
            stderr.contains("invalid value '") && stderr.contains(flag),
            "{args:?}: {stderr}"
        );
    }
}

/// A camera inside a sphere (a sky dome): the sphere reaches the eye's plane, so no grid keeps
/// its triangles within the tolerance of it; the preview draws it at its finest and says so.
#[test]
fn a_curved_shape_no_grid_can_hold_within_the_tolerance_is_reported() {
    if common::gpu_context().is_none() {
        return;
    }
    let dir = scratch_dir("dome");
    let scene = dir.join("dome.toml");
    std::fs::write(
        &scene,
        "[render]\nwidth = 36\nheight = 24\nambient = [1.0, 1.0, 1.0]\n\
         [camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n\
         [[materials]]\nname = \"sky\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 10.0\n\
         material = \"sky\"\n",
    )
    .unwrap();
    let output = chambre()
        .args(["preview", scene.to_str().unwrap(), "-o"])
        .arg(dir.join("dome.png"))
        .env("XDG_RUNTIME_DIR", "/tmp")
        .output()
        .unwrap();
    let stderr = stderr_of(&output);
    assert!(output.status.success(), "{stderr}");
    let [around, across] = chambre::preview::ROUND_QUADS[1];
    assert!(
        stderr.contains("1 curved shape(s) stray further than 0.5 px")
            && stderr.contains(&format!("{} triangles", 2 * around * across)),
        "{stderr}"
    );
}
