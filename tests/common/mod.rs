//! Shared helpers of the integration tests: render a scene on both paths, compare images.
#![allow(dead_code)]

use std::path::Path;
use std::sync::atomic::AtomicBool;

use chambre::cpu::CpuRenderer;
use chambre::gpu::{GpuContext, GpuRenderer};
use chambre::pack::{FlatScene, flatten};
use chambre::render::{Image, render};
use chambre::scene::Scene;

/// A GPU context, or a test failure. GPU tests never skip silently: without an adapter they
/// fail, unless CHAMBRE_SKIP_GPU=1 is set by hand (and CHAMBRE_REQUIRE_GPU=1, which the test
/// script sets, forbids even that).
pub fn gpu_context() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(context) => Some(context),
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
    let output =
        render(flat, &mut renderer, &mut |_, _| {}, &AtomicBool::new(false)).expect("GPU render");
    if let Some(e) = output.stopped {
        panic!("GPU render stopped: {e}");
    }
    Some((output.image, output.status_flags, lavapipe))
}

pub fn render_both(path: &str, overrides: &[&str]) -> Option<(Image, Image)> {
    let flat = flatten(&load(path, overrides));
    let gpu = render_gpu(&flat)?;
    Some((render_cpu(&flat), gpu))
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
