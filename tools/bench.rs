//! Reproduces every figure of BENCHMARKS.md: for each sample scene, triangles, BVH build time,
//! and frame time and rays/s on the GPU path and the CPU path (median of N runs, one warm-up).
//! Usage: chambre-bench [RUNS]

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use chambre::accel::flatten;
use chambre::cpu::CpuRenderer;
use chambre::gpu::{GpuContext, GpuRenderer};
use chambre::render::{RenderOutput, render};
use chambre::scene::Scene;

const SCENES: [&str; 6] = [
    "spheres",
    "bunny",
    "mirrors",
    "area_light",
    "thin_lens",
    "phong",
];

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
    Ok(())
}
