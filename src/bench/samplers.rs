//! The lens-sampler study: RMSE against a converged reference, for each lens sample pattern
//! and sample count, with the CPU time, on the depth-of-field scene `scenes/bokeh.toml`.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use serde::Serialize;

use crate::cpu::CpuRenderer;
use crate::error::Result;
use crate::pack::flatten;
use crate::render::{RenderOutput, render};
use crate::scene::Scene;

const SCENE: &str = "scenes/bokeh.toml";
const SIZE: [&str; 2] = ["render.width=120", "render.height=80"];
/// The lens sample patterns compared.
pub const SAMPLERS: [&str; 5] = ["random", "stratified", "poisson", "interleaved", "sobol"];
/// Samples per pixel each pattern is measured at.
pub const SAMPLE_COUNTS: [u32; 4] = [4, 16, 64, 256];

/// One lens sampler at one sample count.
#[derive(Clone, Debug, Serialize)]
pub struct SamplerResult {
    /// The lens sampler's name.
    pub sampler: &'static str,
    /// Samples per pixel.
    pub spp: u32,
    /// RMSE of linear radiance against the reference.
    pub rmse: f64,
    /// Time of the render on the CPU path (ms).
    pub cpu_ms: f64,
}

/// The whole study's report.
#[derive(Clone, Debug, Serialize)]
pub struct SamplersReport {
    /// The scene file rendered.
    pub scene: &'static str,
    /// Samples per pixel of the reference image.
    pub reference_spp: u32,
    /// One entry per sampler and sample count.
    pub results: Vec<SamplerResult>,
}

fn render_cpu(overrides: &[String]) -> Result<RenderOutput> {
    let mut all: Vec<String> = SIZE.iter().map(|s| s.to_string()).collect();
    all.extend_from_slice(overrides);
    let scene = Scene::load(Path::new(SCENE), &all)?;
    let flat = flatten(&scene);
    render(
        &flat,
        &mut CpuRenderer::new(&flat),
        &mut |_, _| {},
        &AtomicBool::new(false),
    )
}

/// RMSE of linear radiance (per channel) between two images of the same size.
pub fn rmse(a: &crate::render::Image, b: &crate::render::Image) -> f64 {
    let squared: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (*p - *q).length_squared() as f64 / 3.0)
        .sum();
    (squared / a.pixels.len() as f64).sqrt()
}

/// Renders the reference (`reference_spp`, Sobol, seed 1), then every sampler at every count
/// (stratified pixels, seed 2).
pub fn run(reference_spp: u32) -> Result<SamplersReport> {
    let reference = render_cpu(&[
        format!("render.spp={reference_spp}"),
        "camera.lens_sampler=sobol".into(),
        "render.seed=1".into(),
    ])?;
    let mut results = Vec::new();
    for sampler in SAMPLERS {
        for spp in SAMPLE_COUNTS {
            let output = render_cpu(&[
                format!("render.spp={spp}"),
                format!("camera.lens_sampler={sampler}"),
                "render.seed=2".into(),
            ])?;
            results.push(SamplerResult {
                sampler,
                spp,
                rmse: rmse(&output.image, &reference.image),
                cpu_ms: output.elapsed.as_secs_f64() * 1e3,
            });
        }
    }
    Ok(SamplersReport {
        scene: SCENE,
        reference_spp,
        results,
    })
}

impl SamplersReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "samplers: {} at 120x80, pixel sampler stratified, seed 2; RMSE of linear radiance \
             against {} spp (sobol, seed 1); CPU ms in parentheses\n\n",
            self.scene, self.reference_spp
        );
        out += "| lens sampler |";
        for spp in SAMPLE_COUNTS {
            out += &format!(" {spp} spp |");
        }
        out += "\n|---|---|---|---|---|\n";
        for sampler in SAMPLERS {
            out += &format!("| {sampler} |");
            for r in self.results.iter().filter(|r| r.sampler == sampler) {
                out += &format!(" {:.4} ({:.0} ms) |", r.rmse, r.cpu_ms);
            }
            out += "\n";
        }
        out
    }
}
