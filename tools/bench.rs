//! Reproduces every figure of BENCHMARKS.md: for each sample scene, triangles, BVH build time,
//! and frame time and rays/s on the GPU path and the CPU path (median of N runs, one warm-up);
//! then the lens samplers' error against samples and time on a depth-of-field scene.
//! Usage: chambre-bench [RUNS]

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use chambre::accel::flatten;
use chambre::cpu::CpuRenderer;
use chambre::gpu::{GpuContext, GpuRenderer};
use chambre::render::{RenderOutput, render};
use chambre::scene::Scene;

const SCENES: [&str; 9] = [
    "spheres",
    "bunny",
    "mirrors",
    "area_light",
    "thin_lens",
    "phong",
    "architecture",
    "tabletop",
    "miniature",
];

const SAMPLERS: [&str; 5] = ["random", "stratified", "poisson", "interleaved", "sobol"];

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(5);
    let adapter = GpuContext::new()
        .map(|c| c.adapter_description)
        .unwrap_or_else(|e| format!("none ({e})"));
    println!("adapter: {adapter}");
    println!(
        "cores: {}, runs: {runs} (median, after one warm-up)",
        rayon::current_num_threads()
    );
    println!(
        "| scene | size x spp | triangles | BVH build ms | GPU ms | GPU Mrays/s | CPU ms | CPU Mrays/s | GPU/CPU time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for name in SCENES {
        let scene = Scene::load(std::path::Path::new(&format!("scenes/{name}.toml")), &[])?;
        let mut builds = Vec::new();
        for _ in 0..runs {
            builds.push(flatten(&scene).build_time);
        }
        let flat = flatten(&scene);
        let cancel = AtomicBool::new(false);
        let time = |out: &RenderOutput| (out.elapsed, out.rays);
        let mut cpu = Vec::new();
        let mut gpu = Vec::new();
        let mut rays = 0;
        for run in 0..=runs {
            let mut renderer = CpuRenderer::new(&flat);
            let (t, r) = time(&render(&flat, &mut renderer, &mut |_, _| {}, &cancel)?);
            rays = r;
            if run > 0 {
                cpu.push(t);
            }
            if let Ok(context) = GpuContext::new() {
                let mut renderer = GpuRenderer::new(context, &flat)?;
                let (t, _) = time(&render(&flat, &mut renderer, &mut |_, _| {}, &cancel)?);
                if run > 0 {
                    gpu.push(t);
                }
            }
        }
        let cpu_t = median(cpu);
        let mrays = |t: Duration| rays as f64 / t.as_secs_f64() / 1e6;
        let (gpu_ms, gpu_mrays, ratio) = if gpu.is_empty() {
            ("-".into(), "-".into(), "-".into())
        } else {
            let g = median(gpu);
            (
                format!("{:.1}", g.as_secs_f64() * 1e3),
                format!("{:.2}", mrays(g)),
                format!("{:.2}", g.as_secs_f64() / cpu_t.as_secs_f64()),
            )
        };
        let f = &flat.frame;
        println!(
            "| {name} | {}x{} x {} | {} | {:.2} | {gpu_ms} | {gpu_mrays} | {:.1} | {:.2} | {ratio} |",
            f.width,
            f.height,
            f.spp,
            flat.triangle_count,
            median(builds).as_secs_f64() * 1e3,
            cpu_t.as_secs_f64() * 1e3,
            mrays(cpu_t)
        );
    }
    sampler_study()?;
    Ok(())
}

fn render_cpu(path: &str, overrides: &[String]) -> anyhow::Result<RenderOutput> {
    let scene = Scene::load(std::path::Path::new(path), overrides)?;
    let flat = flatten(&scene);
    let mut renderer = CpuRenderer::new(&flat);
    Ok(render(
        &flat,
        &mut renderer,
        &mut |_, _| {},
        &AtomicBool::new(false),
    )?)
}

/// RMSE of the bokeh scene (hexagonal aperture, wide open) against a 4096-spp reference, for
/// each lens sampler and sample count, with the CPU time. Pixel sampler: stratified throughout.
fn sampler_study() -> anyhow::Result<()> {
    let path = "scenes/bokeh.toml";
    let size = ["render.width=120", "render.height=80", "render.seed=1"];
    let with = |extra: &[String]| -> Vec<String> {
        size.iter()
            .map(|s| s.to_string())
            .chain(extra.iter().cloned())
            .collect()
    };
    let reference = render_cpu(
        path,
        &with(&["render.spp=4096".into(), "camera.lens_sampler=sobol".into()]),
    )?;
    println!();
    println!(
        "lens samplers on {path} at 120x80 (RMSE of linear radiance against 4096 spp sobol; CPU ms)"
    );
    println!("| lens sampler | 4 spp | 16 spp | 64 spp | 256 spp |");
    println!("|---|---|---|---|---|");
    for sampler in SAMPLERS {
        let mut cells = Vec::new();
        for spp in [4, 16, 64, 256] {
            let output = render_cpu(
                path,
                &with(&[
                    format!("render.spp={spp}"),
                    format!("camera.lens_sampler={sampler}"),
                    "render.seed=2".into(),
                ]),
            )?;
            let squared: f64 = output
                .image
                .pixels
                .iter()
                .zip(&reference.image.pixels)
                .map(|(a, b)| (*a - *b).length_squared() as f64 / 3.0)
                .sum();
            let rmse = (squared / output.image.pixels.len() as f64).sqrt();
            cells.push(format!(
                "{rmse:.4} ({:.0} ms)",
                output.elapsed.as_secs_f64() * 1e3
            ));
        }
        println!("| {sampler} | {} |", cells.join(" | "));
    }
    Ok(())
}
