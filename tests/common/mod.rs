//! Shared helpers of the integration tests: render a scene on both paths, compare images.
#![allow(dead_code)]

use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::AtomicBool;

use chambre::cpu::CpuRenderer;
use chambre::gpu::{GpuContext, GpuRenderer};
use chambre::pack::{FlatScene, flatten};
use chambre::render::{Backend, Image, RenderOutput, render};
use chambre::scene::Scene;

/// The test binary's GPU context (one device shared by its tests, as an application would:
/// NVIDIA's driver hung when 16 tests each made their own at once), or a test failure. GPU
/// tests never skip silently: without an adapter they fail, unless CHAMBRE_SKIP_GPU=1 is set by
/// hand (and CHAMBRE_REQUIRE_GPU=1, which the test script sets, forbids even that).
pub fn gpu_context() -> Option<GpuContext> {
    static CONTEXT: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    match CONTEXT.get_or_init(|| GpuContext::new().map_err(|e| e.to_string())) {
        Ok(context) => Some(context.clone()),
        Err(e) => {
            let required = std::env::var("CHAMBRE_REQUIRE_GPU").is_ok_and(|v| v == "1");
            let skip = std::env::var("CHAMBRE_SKIP_GPU").is_ok_and(|v| v == "1");
            if skip && !required {
                eprintln!("SKIPPED (CHAMBRE_SKIP_GPU=1): {e}");
                return None;
            }
            panic!(
                "no GPU adapter ({e}); install lavapipe (tools/test.sh does) or set CHAMBRE_SKIP_GPU=1"
            );
        }
    }
}

pub fn load(path: &str, overrides: &[&str]) -> Scene {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    Scene::load(&full, &overrides).unwrap_or_else(|e| panic!("{e}"))
}

pub fn render_cpu(flat: &FlatScene) -> Image {
    let mut renderer = CpuRenderer::new(flat);
    let output =
        render(flat, &mut renderer, &mut |_, _| {}, &AtomicBool::new(false)).expect("CPU render");
    assert!(output.stopped.is_none());
    output.image
}

pub fn render_gpu(flat: &FlatScene) -> Option<Image> {
    let (image, flags, _) = render_gpu_with_flags(flat)?;
    assert_eq!(flags, 0, "kernel status flags");
    Some(image)
}

/// The GPU image, the kernel's status flags, and whether the adapter is lavapipe (whose loop
/// limit, `layout::STATUS_LOOP_LIMIT`, real GPUs do not have).
pub fn render_gpu_with_flags(flat: &FlatScene) -> Option<(Image, u32, bool)> {
    let context = gpu_context()?;
    let lavapipe = context.adapter_name.contains("llvmpipe");
    let mut renderer = GpuRenderer::new(context, flat).unwrap_or_else(|e| panic!("{e}"));
    let output = render_through(flat, &mut renderer);
    if let Some(e) = output.stopped {
        panic!("GPU render stopped: {e}");
    }
    Some((output.image, output.status_flags, lavapipe))
}

/// `flat` rendered whole through `backend`: no progress shown, never interrupted; a render that
/// fails fails the test.
pub fn render_through(flat: &FlatScene, backend: &mut dyn Backend) -> RenderOutput {
    render(flat, backend, &mut |_, _| {}, &AtomicBool::new(false))
        .unwrap_or_else(|e| panic!("render: {e}"))
}

/// [`render_through`], which must also end cleanly: not stopped, no kernel status flag.
pub fn render_clean(flat: &FlatScene, backend: &mut dyn Backend) -> RenderOutput {
    let output = render_through(flat, backend);
    assert!(output.stopped.is_none(), "stopped: {:?}", output.stopped);
    assert_eq!(output.status_flags, 0, "kernel status flags");
    output
}

/// The scene rendered on the CPU and, where an adapter is, on the GPU (in CI a GPU test fails
/// without one: `gpu_context`), each with its path's name.
pub fn both(scene: &Scene) -> Vec<(&'static str, Image)> {
    let flat = flatten(scene);
    let mut images = vec![("CPU", render_cpu(&flat))];
    if let Some(gpu) = render_gpu(&flat) {
        images.push(("GPU", gpu));
    }
    images
}

pub fn render_both(path: &str, overrides: &[&str]) -> Option<(Image, Image)> {
    let flat = flatten(&load(path, overrides));
    let gpu = render_gpu(&flat)?;
    Some((render_cpu(&flat), gpu))
}

/// How many pixels of `a` and `b` differ at all (both the same size).
pub fn differing_pixels(a: &Image, b: &Image) -> usize {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(x, y)| x != y)
        .count()
}

/// Agreement figures: fraction of pixels whose every channel is within `relative` (relative to
/// the larger value, with a 1e-6 absolute floor), and the mean absolute difference.
pub fn agreement(a: &Image, b: &Image, relative: f32) -> (f64, f64) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut within = 0usize;
    let mut sum_abs = 0f64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let diff = (*p - *q).abs();
        let scale = p.abs().max(q.abs());
        if (0..3).all(|c| diff[c] <= relative * scale[c] + 1e-6) {
            within += 1;
        }
        sum_abs += (diff.x + diff.y + diff.z) as f64 / 3.0;
    }
    let n = a.pixels.len() as f64;
    (within as f64 / n, sum_abs / n)
}

/// Writes `name` (an OBJ) and a scene rendering it under a directional light into a scratch
/// directory; returns the scene path.
pub fn deep_mesh_scene(name: &str, obj: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-deep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{name}.obj")), obj).unwrap();
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(
        &scene,
        format!(
            r#"[render]
width = 24
height = 24
spp = 1
[camera]
position = [0.5, 0.2, 3.0]
look_at = [0.5, 0.0, 0.0]
film = [24.0, 24.0]
[[materials]]
name = "white"
model = "lambert"
[[shapes]]
type = "mesh"
file = "{name}.obj"
material = "white"
smooth = false
[[lights]]
type = "directional"
direction = [0.3, -0.2, -1.0]
irradiance = [1.0, 1.0, 1.0]
"#
        ),
    )
    .unwrap();
    scene
}

/// A fan disc of 3,000 triangles around one vertex.
pub fn fan_disc() -> String {
    let n = 3000;
    let mut obj = String::from("v 0 0 0\n");
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        obj += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    for i in 0..n {
        obj += &format!("f 1 {} {}\n", 2 + i, 2 + (i + 1) % n);
    }
    obj
}

/// 400 nested triangles from the origin, each 2% longer than the last and a little behind it.
pub fn nested_slivers() -> String {
    let mut obj = String::new();
    for i in 0..400 {
        let l = 1.02f64.powi(i);
        let z = -1e-3 * i as f64;
        obj += &format!("v 0 0 {z}\nv {l} 0 {z}\nv {l} {} {z}\n", l * 0.3);
    }
    for i in 0..400 {
        obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    obj
}

/// Gradient energy of rows `rows` and columns `columns` (fractions of the height and width) of
/// a luminance image: mean squared gradient over the squared mean. Blur lowers it (unlike total
/// variation, which a blurred edge keeps, or gradient over variance, which a blurred periodic
/// pattern keeps).
pub fn sharpness(image: &Image, rows: (f64, f64), columns: (f64, f64)) -> f64 {
    let (w, h) = (image.width as usize, image.height as usize);
    let lum = |x: usize, y: usize| {
        let p = image.pixels[y * w + x];
        (0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z) as f64
    };
    let span = |(a, b): (f64, f64), n: usize| (a * n as f64) as usize..(b * n as f64) as usize - 1;
    let (mut sum, mut grad2, mut n) = (0.0, 0.0, 0.0);
    for y in span(rows, h) {
        for x in span(columns, w) {
            let v = lum(x, y);
            sum += v;
            grad2 += (lum(x + 1, y) - v).powi(2) + (lum(x, y + 1) - v).powi(2);
            n += 1.0;
        }
    }
    grad2 / n / (sum / n).powi(2)
}

/// The mean of all channels over the 8 x 8 block (`bx`, `by`) of `image`.
pub fn block_mean(image: &Image, bx: u32, by: u32) -> f64 {
    let mut sum = 0.0f64;
    for y in by * 8..by * 8 + 8 {
        for x in bx * 8..bx * 8 + 8 {
            let p = image.pixels[(y * image.width + x) as usize];
            sum += p.x as f64 + p.y as f64 + p.z as f64;
        }
    }
    sum / 192.0
}

/// Two unbiased estimates of one image agree block by block (8 x 8 blocks) to sampling error:
/// within `relative` of the larger block mean, plus 1e-3.
pub fn assert_blocks_agree(a: &Image, b: &Image, relative: f64, names: [&str; 2]) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    for by in 0..a.height / 8 {
        for bx in 0..a.width / 8 {
            let (p, q) = (block_mean(a, bx, by), block_mean(b, bx, by));
            assert!(
                (p - q).abs() <= relative * p.max(q) + 1e-3,
                "block ({bx}, {by}): {} {p:.5}, {} {q:.5}",
                names[0],
                names[1]
            );
        }
    }
}

/// Asserts that `flat`'s area-light samples are split into several light windows and that the
/// CPU render, window by window, equals [`render_unsplit`]'s to 1e-5 in every pixel; returns the
/// windowed render.
pub fn assert_windows_sum_to_unsplit(flat: &FlatScene) -> Image {
    let plan = chambre::render::plan_passes(flat, &chambre::render::RayBudgets::DEFAULT);
    assert!(
        plan.light_windows.len() > 1,
        "the light samples must be split"
    );
    let windowed = render_cpu(flat);
    let whole = render_unsplit(flat);
    let (within, mean_abs) = agreement(&windowed, &whole, 1e-5);
    assert!(
        within == 1.0,
        "{within} of pixels within 1e-5, mean |diff| {mean_abs:.2e}"
    );
    windowed
}

/// `flat`'s image on the CPU path with every light sample of a camera sample in one call
/// (`LightWindow::ALL`), whatever light windows the render's plan would split them into.
fn render_unsplit(flat: &FlatScene) -> Image {
    let (width, height, spp) = (flat.frame.width, flat.frame.height, flat.frame.spp);
    let pixels = (0..width * height)
        .map(|i| {
            let mut stats = Default::default();
            let sum: glam::Vec3 = (0..spp)
                .map(|s| {
                    chambre::integrator::trace_sample::<{ chambre::layout::FEATURES_ALL }>(
                        flat,
                        i % width,
                        i / width,
                        s,
                        chambre::integrator::LightWindow::ALL,
                        &mut stats,
                        &mut Default::default(),
                    )
                })
                .sum();
            sum / spp as f32
        })
        .collect();
    Image {
        width,
        height,
        pixels,
    }
}
