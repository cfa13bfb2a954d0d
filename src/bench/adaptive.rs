//! `chambre bench adaptive`: adaptive sampling (`--noise-target`) against uniform sampling of
//! the same pattern, at equal samples spent and at equal wall time, by relative MSE against a
//! converged reference, on scene files and on held-out scenes generated from a seed
//! ([`held_out_scene`]: boxes, an area light, soft shadows, apertures, mirrors that no test or
//! tuning of adaptive sampling was written against).
//!
//! For each scene, pattern and target: the adaptive render (its wall time the median of
//! `--runs`), then uniform renders at the adaptive render's mean samples per pixel (equal
//! samples) and at the samples its time buys (from the last uniform render's time per sample,
//! twice); the residual difference in time is corrected along the power law through the two
//! uniform renders ([`at_time`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use serde::Serialize;

use crate::cpu::CpuRenderer;
use crate::error::Result;
use crate::math::rng::Rng;
use crate::metrics::rel_mse;
use crate::pack::flatten;
use crate::render::{Image, RenderOutput, render};
use crate::sampler::SamplerName;
use crate::scene::Scene;

/// The kinds of held-out scenes ([`held_out_scene`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HeldOutKind {
    /// A box of random proportions and colours, two to four boxes and spheres on its floor, a
    /// ceiling light of random size and place, one light sample, direct light: the penumbrae
    /// carry the noise.
    SoftShadows,
    /// The same with a thin lens: a random f-number (1.4 to 4), aperture (a disk or 5 to 9
    /// blades) and focus depth in a box a few centimetres wide, so the blur is pixels wide.
    Defocus,
    /// The same with a mirror (a quad on a wall or a sphere) and three bounces.
    Mirror,
}

impl HeldOutKind {
    /// The name `--generated` and the reports use.
    pub fn name(self) -> &'static str {
        match self {
            HeldOutKind::SoftShadows => "soft_shadows",
            HeldOutKind::Defocus => "defocus",
            HeldOutKind::Mirror => "mirror",
        }
    }

    /// Every kind.
    pub const ALL: [HeldOutKind; 3] = [
        HeldOutKind::SoftShadows,
        HeldOutKind::Defocus,
        HeldOutKind::Mirror,
    ];
}

/// A held-out scene: its kind and seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeldOut {
    /// What it stresses.
    pub kind: HeldOutKind,
    /// The seed of its geometry, materials, light and camera (and of its render).
    pub seed: u32,
}

/// `KIND:SEED` (e.g. `defocus:3`) as `--generated` takes it.
pub fn parse_held_out(text: &str) -> std::result::Result<HeldOut, String> {
    let (kind, seed) = text
        .split_once(':')
        .ok_or_else(|| format!("`{text}`: expected KIND:SEED, e.g. soft_shadows:1"))?;
    let kind = HeldOutKind::ALL
        .into_iter()
        .find(|k| k.name() == kind)
        .ok_or_else(|| format!("`{kind}`: the kinds are soft_shadows, defocus and mirror"))?;
    let seed = seed
        .parse::<u32>()
        .map_err(|e| format!("`{seed}`: the seed must be a u32 ({e})"))?;
    Ok(HeldOut { kind, seed })
}

/// Uniform random numbers in `[lo, hi)` from one stream.
struct Draw(Rng);

impl Draw {
    fn between(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.0.next_f32()
    }

    fn colour(&mut self, lo: f32, hi: f32) -> [f32; 3] {
        [
            self.between(lo, hi),
            self.between(lo, hi),
            self.between(lo, hi),
        ]
    }

    fn below(&mut self, n: u32) -> u32 {
        self.0.next_u32() % n
    }
}

fn v3(v: [f32; 3]) -> String {
    format!("[{:.4}, {:.4}, {:.4}]", v[0], v[1], v[2])
}

fn quad(corner: [f32; 3], edge_u: [f32; 3], edge_v: [f32; 3], material: &str) -> String {
    format!(
        "[[shapes]]\ntype = \"quad\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"{material}\"\n\n",
        v3(corner),
        v3(edge_u),
        v3(edge_v)
    )
}

fn material(name: &str, diffuse: [f32; 3]) -> String {
    format!(
        "[[materials]]\nname = \"{name}\"\nmodel = \"lambert\"\ndiffuse = {}\n\n",
        v3(diffuse)
    )
}

/// The TOML of held-out scene `kind` number `seed`, `size` pixels square: a box `W x H x D`
/// (1.6 to 2.6 units each way, open towards the camera) with a white floor, ceiling and back
/// and random side walls, two to four random boxes (rotated) and spheres on its floor, and a
/// ceiling light 15-50% of the ceiling's width and depth at a random place, one light sample
/// per hit. `Defocus` adds a thin lens and `Mirror` a mirror (see [`HeldOutKind`]). The same
/// `(kind, seed, size)` always gives the same text.
pub fn held_out_scene(kind: HeldOutKind, seed: u32, size: u32) -> String {
    let mut draw = Draw(Rng::new(seed, 0x4e1d, kind as u32));
    let (w, h, d) = (
        draw.between(1.6, 2.6),
        draw.between(1.6, 2.4),
        draw.between(1.6, 2.6),
    );
    let max_depth = if kind == HeldOutKind::Mirror { 3 } else { 0 };
    let mut text = format!(
        "# Held-out scene {} {seed} (chambre::bench::adaptive::held_out_scene).\n\
         [render]\nwidth = {size}\nheight = {size}\nspp = 64\nmax_depth = {max_depth}\n\
         seed = {seed}\n\n",
        kind.name()
    );
    if kind == HeldOutKind::Defocus {
        // A box a few centimetres wide, so a 35 mm lens at f/1.4-4 blurs it by pixels.
        text += &format!(
            "[scene]\nmeters_per_unit = {:.4}\n\n",
            draw.between(0.03, 0.08)
        );
    }
    let distance = 1.6 * w.max(h);
    let position = [
        draw.between(-0.1, 0.1) * w,
        h * draw.between(0.4, 0.6),
        0.5 * d + distance,
    ];
    let look_at = [0.0, 0.5 * h, 0.0];
    text += &format!(
        "[camera]\nposition = {}\nlook_at = {}\nfocal_length = 35.0\nfilm = [24.0, 24.0]\n",
        v3(position),
        v3(look_at)
    );
    // Objects on the floor, away from the walls.
    let objects = 2 + draw.below(3);
    let mut centres = Vec::new();
    let mut shapes = String::new();
    for i in 0..objects {
        let centre = [
            draw.between(-0.5 * w + 0.4, 0.5 * w - 0.4),
            0.0,
            draw.between(-0.5 * d + 0.4, 0.5 * d - 0.6),
        ];
        let name = format!("object{i}");
        if draw.below(2) == 0 {
            let radius = draw.between(0.15, 0.4);
            shapes += &format!(
                "[[shapes]]\ntype = \"sphere\"\ncenter = {}\nradius = {radius:.4}\nmaterial = \"{name}\"\n\n",
                v3([centre[0], radius, centre[2]])
            );
            centres.push([centre[0], radius, centre[2]]);
        } else {
            let (sx, sz, height) = (
                draw.between(0.2, 0.6),
                draw.between(0.2, 0.6),
                draw.between(0.3, 1.2),
            );
            shapes += &rotated_box(centre, [sx, height, sz], draw.between(0.0, 1.5), &name);
            centres.push([centre[0], 0.5 * height, centre[2]]);
        }
    }
    if kind == HeldOutKind::Defocus {
        let focus = centres[draw.below(centres.len() as u32) as usize];
        let to_focus = (0..3)
            .map(|a| (focus[a] - position[a]).powi(2))
            .sum::<f32>()
            .sqrt();
        let blades = match draw.below(3) {
            0 => 0,
            _ => 5 + draw.below(5),
        };
        text += &format!(
            "f_number = {:.3}\nfocus_distance = {to_focus:.4}\naperture_blades = {blades}\n\
             aperture_rotation = {:.2}\n",
            draw.between(1.4, 4.0),
            draw.between(0.0, 90.0)
        );
    }
    text += "\n";
    text += &material("white", [0.73, 0.73, 0.73]);
    text += &material("left", draw.colour(0.05, 0.75));
    text += &material("right", draw.colour(0.05, 0.75));
    for i in 0..objects {
        text += &material(&format!("object{i}"), draw.colour(0.2, 0.9));
    }
    let (x0, x1, z0) = (-0.5 * w, 0.5 * w, -0.5 * d);
    text += &quad([x0, 0.0, z0], [0.0, 0.0, d], [w, 0.0, 0.0], "white");
    text += &quad([x0, h, z0], [w, 0.0, 0.0], [0.0, 0.0, d], "white");
    text += &quad([x0, 0.0, z0], [w, 0.0, 0.0], [0.0, h, 0.0], "white");
    text += &quad([x0, 0.0, z0], [0.0, h, 0.0], [0.0, 0.0, d], "left");
    text += &quad([x1, 0.0, z0], [0.0, 0.0, d], [0.0, h, 0.0], "right");
    text += &shapes;
    if kind == HeldOutKind::Mirror {
        text += &mirror(&mut draw, [w, h, d]);
    }
    let (lw, ld) = (draw.between(0.15, 0.5) * w, draw.between(0.15, 0.5) * d);
    let (cx, cz) = (
        draw.between(x0 + 0.5 * lw + 0.05, x1 - 0.5 * lw - 0.05),
        draw.between(z0 + 0.5 * ld + 0.05, -z0 - 0.5 * ld - 0.05),
    );
    // About the same power whatever the light's size.
    let power = 6.5 / (lw * ld);
    let tint = [1.0, draw.between(0.7, 1.0), draw.between(0.3, 1.0)];
    text += &format!(
        "[[lights]]\ntype = \"area\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nradiance = {}\nsamples = 1\n",
        v3([cx - 0.5 * lw, h - 0.01, cz - 0.5 * ld]),
        v3([lw, 0.0, 0.0]),
        v3([0.0, 0.0, ld]),
        v3(tint.map(|t| t * power))
    );
    text
}

/// A held-out scene's mirror in a box of `w x h x d`: its material, and a panel just in front
/// of a side wall or the back wall, or a mirror sphere.
fn mirror(draw: &mut Draw, [w, h, d]: [f32; 3]) -> String {
    let (x0, z0) = (-0.5 * w, -0.5 * d);
    let reflectance = draw.between(0.7, 0.95);
    let mut text = format!(
        "[[materials]]\nname = \"mirror\"\nmodel = \"mirror\"\nmirror = {}\n\n",
        v3([reflectance; 3])
    );
    text += &match draw.below(3) {
        // A panel on a side wall or on the back wall, just in front of it.
        0 => {
            let (y, z) = (draw.between(0.1, 0.4) * h, draw.between(0.1, 0.4) * d);
            quad(
                [x0 + 0.01, y, z0 + z],
                [0.0, draw.between(0.4, 0.55) * h, 0.0],
                [0.0, 0.0, draw.between(0.4, 0.55) * d],
                "mirror",
            )
        }
        1 => {
            let (x, y) = (draw.between(0.1, 0.4) * w, draw.between(0.1, 0.4) * h);
            quad(
                [x0 + x, y, z0 + 0.01],
                [draw.between(0.4, 0.55) * w, 0.0, 0.0],
                [0.0, draw.between(0.4, 0.55) * h, 0.0],
                "mirror",
            )
        }
        _ => {
            let radius = draw.between(0.2, 0.35);
            format!(
                "[[shapes]]\ntype = \"sphere\"\ncenter = {}\nradius = {radius:.4}\nmaterial = \"mirror\"\n\n",
                v3([
                    draw.between(-0.5 * w + 0.4, 0.5 * w - 0.4),
                    draw.between(radius, 0.6 * h),
                    draw.between(-0.5 * d + 0.4, 0.0),
                ])
            )
        }
    };
    text
}

/// The five visible faces (the base left out) of a box of `size` standing on the floor at
/// `centre`, turned by `angle` radians about the vertical.
fn rotated_box(centre: [f32; 3], size: [f32; 3], angle: f32, material: &str) -> String {
    let (s, c) = angle.sin_cos();
    let turn = |v: [f32; 3]| [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]];
    let at = |v: [f32; 3]| {
        let t = turn(v);
        [centre[0] + t[0], centre[1] + t[1], centre[2] + t[2]]
    };
    let [sx, sy, sz] = size;
    let (hx, hz) = (0.5 * sx, 0.5 * sz);
    let (x, y, z) = (
        turn([sx, 0.0, 0.0]),
        turn([0.0, sy, 0.0]),
        turn([0.0, 0.0, sz]),
    );
    [
        quad(at([-hx, sy, -hz]), z, x, material),
        quad(at([-hx, 0.0, hz]), x, y, material),
        quad(at([-hx, 0.0, -hz]), y, x, material),
        quad(at([-hx, 0.0, -hz]), z, y, material),
        quad(at([hx, 0.0, -hz]), y, z, material),
    ]
    .concat()
}

/// Where a measured scene comes from.
#[derive(Clone, Debug)]
pub enum SceneSource {
    /// A scene file.
    File(PathBuf),
    /// A held-out scene, `size` pixels square.
    HeldOut(HeldOut, u32),
}

impl SceneSource {
    /// The scene with `overrides`.
    pub fn load(&self, overrides: &[String]) -> Result<Scene> {
        match self {
            SceneSource::File(path) => Scene::load(path, overrides),
            SceneSource::HeldOut(scene, size) => Scene::from_str(
                Path::new(&self.name()),
                &held_out_scene(scene.kind, scene.seed, *size),
                overrides,
            ),
        }
    }

    /// The file's path, or `KIND:SEED`.
    pub fn name(&self) -> String {
        match self {
            SceneSource::File(path) => path.display().to_string(),
            SceneSource::HeldOut(scene, _) => format!("{}:{}", scene.kind.name(), scene.seed),
        }
    }
}

/// Renders `source` with `overrides` on the CPU path.
pub fn render_cpu(source: &SceneSource, overrides: &[String]) -> Result<RenderOutput> {
    let flat = flatten(&source.load(overrides)?);
    let output = render(
        &flat,
        &mut CpuRenderer::new(&flat),
        &mut |_, _| {},
        &AtomicBool::new(false),
    )?;
    match output.stopped {
        Some(e) => Err(e),
        None => Ok(output),
    }
}

/// The converged reference of `source`: `spp` samples per pixel of Sobol patterns with another
/// seed than the measured renders' (their errors must not correlate with its own).
pub fn reference(source: &SceneSource, set: &[String], spp: u32) -> Result<Image> {
    let seed = source.load(set)?.render.seed;
    let mut overrides = set.to_vec();
    overrides.extend([
        format!("render.spp={spp}"),
        "render.pixel_sampler=sobol".into(),
        "camera.lens_sampler=sobol".into(),
        format!("render.seed={}", seed.wrapping_add(1_000_003)),
    ]);
    Ok(render_cpu(source, &overrides)?.image)
}

/// The overrides of a render with `sampler` for the pixel and lens samples at `spp`.
pub fn pattern_overrides(set: &[String], sampler: SamplerName, spp: u32) -> Vec<String> {
    let mut overrides = set.to_vec();
    overrides.extend([
        format!("render.spp={spp}"),
        format!("render.pixel_sampler={}", sampler.name()),
        format!("camera.lens_sampler={}", sampler.name()),
    ]);
    overrides
}

/// Mean samples per pixel of a render.
pub fn mean_spp(output: &RenderOutput) -> f64 {
    let counts = &output.sample_counts;
    counts.iter().map(|&n| n as f64).sum::<f64>() / counts.len().max(1) as f64
}

/// One adaptive render against uniform sampling of its pattern.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptiveRow {
    /// The scene file or `KIND:SEED`.
    pub scene: String,
    /// The pixel and lens pattern.
    pub sampler: &'static str,
    /// The noise target.
    pub target: f64,
    /// The adaptive render's mean samples per pixel.
    pub adaptive_spp: f64,
    /// Its decisions.
    pub decisions: u32,
    /// Its estimate of the image's relative error (`AdaptiveReport::image_error`), to set
    /// beside the root of its relative MSE against the reference.
    pub estimated_error: f64,
    /// Its wall time (ms, median of the runs).
    pub adaptive_ms: f64,
    /// Its relative MSE against the reference.
    pub adaptive_rel_mse: f64,
    /// Uniform sampling at the adaptive render's mean samples (rounded): its spp.
    pub equal_samples_spp: u32,
    /// ... its wall time (ms).
    pub equal_samples_ms: f64,
    /// ... its relative MSE.
    pub equal_samples_rel_mse: f64,
    /// Uniform sampling at the samples the adaptive render's time buys: its spp.
    pub equal_time_spp: u32,
    /// ... its wall time (ms).
    pub equal_time_ms: f64,
    /// ... its relative MSE.
    pub equal_time_rel_mse: f64,
    /// Uniform sampling's relative MSE at the adaptive render's wall time (the equal-time
    /// render's, corrected for the residual difference in time).
    pub uniform_rel_mse_at_adaptive_time: f64,
}

impl AdaptiveRow {
    /// Adaptive's relative MSE over uniform's at equal samples.
    pub fn ratio_equal_samples(&self) -> f64 {
        self.adaptive_rel_mse / self.equal_samples_rel_mse
    }

    /// Adaptive's relative MSE over uniform's at equal time.
    pub fn ratio_equal_time(&self) -> f64 {
        self.adaptive_rel_mse / self.uniform_rel_mse_at_adaptive_time
    }

    /// Adaptive's time per sample over uniform's (at equal samples): its overheads.
    pub fn time_per_sample_ratio(&self) -> f64 {
        (self.adaptive_ms / self.adaptive_spp)
            / (self.equal_samples_ms / self.equal_samples_spp as f64)
    }
}

/// Adaptive sampling's overhead at equal work: an adaptive render whose target no pixel meets
/// (every pixel takes every sample, with the decisions, read-backs and passes over pixel lists,
/// and the progressive patterns) against a uniform render of the same samples.
#[derive(Clone, Debug, Serialize)]
pub struct OverheadRow {
    /// The scene file or `KIND:SEED`.
    pub scene: String,
    /// The pixel and lens pattern.
    pub sampler: &'static str,
    /// Samples per pixel of the uniform render, and the most of the adaptive one's.
    pub spp: u32,
    /// The adaptive render's mean samples per pixel: `spp` but in pixels whose whole
    /// neighbourhood is exact (black), which stop at the first decision.
    pub adaptive_spp: f64,
    /// The adaptive render's wall time (ms, median of the runs).
    pub adaptive_ms: f64,
    /// The uniform render's.
    pub uniform_ms: f64,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptiveReport {
    /// Samples per pixel of each scene's reference.
    pub reference_spp: u32,
    /// The adaptive renders' most samples per pixel.
    pub spp: u32,
    /// One row per scene, pattern and target.
    pub rows: Vec<AdaptiveRow>,
    /// One row per scene and pattern.
    pub overheads: Vec<OverheadRow>,
}

/// What to measure (`chambre bench adaptive`'s arguments, resolved).
pub struct Study<'a> {
    /// The scenes.
    pub scenes: &'a [SceneSource],
    /// The pixel and lens patterns.
    pub samplers: &'a [SamplerName],
    /// The noise targets.
    pub targets: &'a [f64],
    /// The adaptive renders' most samples per pixel.
    pub spp: u32,
    /// Their `render.min_spp`, where given.
    pub min_spp: Option<u32>,
    /// Samples per pixel of the references.
    pub reference_spp: u32,
    /// Renders of each timed run (their median time is kept).
    pub runs: usize,
    /// Samples per pixel of the overhead measurement ([`OverheadRow`]); 0 leaves it out.
    pub overhead_spp: u32,
    /// Overrides of every render.
    pub set: &'a [String],
}

/// `runs` renders; the last output and the median wall time (ms).
fn timed(source: &SceneSource, overrides: &[String], runs: usize) -> Result<(RenderOutput, f64)> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs.max(1) {
        let output = render_cpu(source, overrides)?;
        times.push(output.elapsed.as_secs_f64() * 1e3);
        last = Some(output);
    }
    times.sort_by(f64::total_cmp);
    Ok((last.expect("one run at least"), times[times.len() / 2]))
}

/// The sample count nearest `spp` (within 5%) whose stratified grid is no more than 4:1:
/// uniform stratified sampling at a prime count, e.g. 163, has a 1 x 163 grid, stratified along
/// one axis only, where a user would have asked for 160 (a 10 x 16 grid).
pub fn fair_spp(spp: u32) -> u32 {
    let spp = spp.max(1);
    let square_enough = |n: u32| {
        let columns = crate::math::sampling::strata_columns(n);
        4 * columns * columns >= n
    };
    let reach = spp / 20;
    (0..=reach)
        .flat_map(|d| [spp - d.min(spp - 1), spp + d])
        .find(|&n| square_enough(n))
        .unwrap_or(spp)
}

/// Uniform sampling's relative MSE at `ms`, from its render at equal time `(spp, ms, relMSE)`:
/// the residual difference in time corrected along the power law through it and the render at
/// equal samples `(spp, relMSE)`, where the two counts are 20% apart or more (closer, their
/// slope is noise) and the slope is a convergence's (between -3 and 0).
fn at_time(equal_samples: (u32, f64), equal_time: (u32, f64, f64), ms: f64) -> f64 {
    let (spp, time, rel_mse) = equal_time;
    let (a, b) = (equal_samples.0 as f64, spp as f64);
    if (a / b - 1.0).abs() < 0.2 {
        return rel_mse;
    }
    let slope = ((equal_samples.1 / rel_mse).ln() / (a / b).ln()).clamp(-3.0, 0.0);
    rel_mse * (ms / time).powf(slope)
}

/// Runs `study`.
pub fn run(study: &Study<'_>) -> Result<AdaptiveReport> {
    let (mut rows, mut overheads) = (Vec::new(), Vec::new());
    for source in study.scenes {
        let reference = reference(source, study.set, study.reference_spp)?;
        for &sampler in study.samplers {
            if study.overhead_spp > 0 {
                let spp = study.overhead_spp;
                let uniform = pattern_overrides(study.set, sampler, spp);
                let mut adaptive = uniform.clone();
                // No pixel meets it: every pixel takes every sample.
                adaptive.push("render.noise_target=1e-30".into());
                if let Some(n) = study.min_spp {
                    adaptive.push(format!("render.min_spp={}", n.min(spp)));
                }
                let (adaptive, adaptive_ms) = timed(source, &adaptive, study.runs)?;
                overheads.push(OverheadRow {
                    scene: source.name(),
                    sampler: sampler.name(),
                    spp,
                    adaptive_spp: mean_spp(&adaptive),
                    adaptive_ms,
                    uniform_ms: timed(source, &uniform, study.runs)?.1,
                });
            }
            for &target in study.targets {
                let mut overrides = pattern_overrides(study.set, sampler, study.spp);
                overrides.push(format!("render.noise_target={target:?}"));
                if let Some(n) = study.min_spp {
                    overrides.push(format!("render.min_spp={n}"));
                }
                let (adaptive, adaptive_ms) = timed(source, &overrides, study.runs)?;
                let adaptive_spp = mean_spp(&adaptive);
                let report = adaptive.adaptive.as_ref();
                let equal_samples_spp = fair_spp(adaptive_spp.round() as u32);
                // Uniform sampling at `spp`: its relative MSE and wall time.
                let uniform = |spp: u32| -> Result<(f64, f64)> {
                    let overrides = pattern_overrides(study.set, sampler, spp);
                    let (output, ms) = timed(source, &overrides, study.runs)?;
                    Ok((rel_mse(&output.image, &reference), ms))
                };
                let (equal_samples_rel_mse, equal_samples_ms) = uniform(equal_samples_spp)?;
                // The samples the adaptive render's time buys, from the time per sample of the
                // last uniform render; twice, as time per sample changes with the count.
                let (mut equal_time_spp, mut equal_time_ms, mut equal_time_rel_mse) =
                    (equal_samples_spp, equal_samples_ms, equal_samples_rel_mse);
                for _ in 0..2 {
                    let spp = equal_time_spp as f64 * adaptive_ms / equal_time_ms;
                    let spp = fair_spp(spp.round() as u32);
                    if spp.abs_diff(equal_time_spp) as f64 <= 0.03 * equal_time_spp as f64 {
                        break;
                    }
                    (equal_time_rel_mse, equal_time_ms) = uniform(spp)?;
                    equal_time_spp = spp;
                }
                rows.push(AdaptiveRow {
                    scene: source.name(),
                    sampler: sampler.name(),
                    target,
                    adaptive_spp,
                    decisions: report.map_or(0, |r| r.decisions),
                    estimated_error: report.map_or(f64::NAN, |r| r.image_error as f64),
                    adaptive_ms,
                    adaptive_rel_mse: rel_mse(&adaptive.image, &reference),
                    equal_samples_spp,
                    equal_samples_ms,
                    equal_samples_rel_mse,
                    equal_time_spp,
                    equal_time_ms,
                    equal_time_rel_mse,
                    uniform_rel_mse_at_adaptive_time: at_time(
                        (equal_samples_spp, equal_samples_rel_mse),
                        (equal_time_spp, equal_time_ms, equal_time_rel_mse),
                        adaptive_ms,
                    ),
                });
            }
        }
    }
    Ok(AdaptiveReport {
        reference_spp: study.reference_spp,
        spp: study.spp,
        rows,
        overheads,
    })
}

impl AdaptiveReport {
    /// The table: each adaptive render, uniform sampling at its samples and at its time, and
    /// the ratios of relative MSE (adaptive over uniform: below 1, adaptive wins).
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "Adaptive sampling against uniform sampling of the same pattern, CPU path; relative MSE \
             against a {} spp Sobol reference of another seed; adaptive renders at most {} spp; \
             wall times the median of the runs; uniform's relative MSE at the adaptive render's \
             time from its render at the samples that time buys, corrected for the residual \
             difference in time along the power law through its two renders.\n\n",
            self.reference_spp, self.spp
        );
        out += "| scene | pattern | target | adaptive spp | decisions | estimated error | \
                sqrt relMSE | adaptive ms | adaptive relMSE | uniform spp, equal samples | relMSE | \
                ratio | uniform spp, equal time | ms | relMSE at adaptive's time | **ratio, equal \
                time** | time per sample, adaptive / uniform |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.rows {
            out += &format!(
                "| {} | {} | {} | {:.1} | {} | {:.4} | {:.4} | {:.0} | {:.3e} | {} | {:.3e} | {:.2}x \
                 | {} | {:.0} | {:.3e} | **{:.2}x** | {:.2} |\n",
                r.scene,
                r.sampler,
                r.target,
                r.adaptive_spp,
                r.decisions,
                r.estimated_error,
                r.adaptive_rel_mse.sqrt(),
                r.adaptive_ms,
                r.adaptive_rel_mse,
                r.equal_samples_spp,
                r.equal_samples_rel_mse,
                r.ratio_equal_samples(),
                r.equal_time_spp,
                r.equal_time_ms,
                r.uniform_rel_mse_at_adaptive_time,
                r.ratio_equal_time(),
                r.time_per_sample_ratio(),
            );
        }
        if !self.overheads.is_empty() {
            out += "\nAdaptive sampling's overhead at equal work: a render whose target no pixel \
                    meets (every pixel takes every sample, with the decisions, read-backs, passes \
                    over pixel lists and progressive patterns) against a uniform render of the \
                    same samples (but in pixels whose whole neighbourhood is black, which stop at the first \
                    decision); the ratio is of time per sample.\n\n| scene | pattern | spp | \
                    adaptive spp | adaptive ms | uniform ms | ratio per sample |\n\
                    |---|---|---|---|---|---|---|\n";
            for o in &self.overheads {
                out += &format!(
                    "| {} | {} | {} | {:.1} | {:.0} | {:.0} | {:.2}x |\n",
                    o.scene,
                    o.sampler,
                    o.spp,
                    o.adaptive_spp,
                    o.adaptive_ms,
                    o.uniform_ms,
                    (o.adaptive_ms / o.adaptive_spp) / (o.uniform_ms / o.spp as f64)
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_out_scenes_are_deterministic_valid_and_differ_by_seed() {
        for kind in HeldOutKind::ALL {
            let a = held_out_scene(kind, 1, 32);
            assert_eq!(a, held_out_scene(kind, 1, 32));
            assert_ne!(a, held_out_scene(kind, 2, 32));
            let source = SceneSource::HeldOut(HeldOut { kind, seed: 1 }, 32);
            let scene = source
                .load(&[])
                .unwrap_or_else(|e| panic!("{kind:?}: {e}\n{a}"));
            assert_eq!(scene.lights.len(), 1);
            assert_eq!(scene.camera.is_pinhole(), kind != HeldOutKind::Defocus);
        }
    }

    #[test]
    fn held_out_names_parse() {
        assert_eq!(
            parse_held_out("defocus:7"),
            Ok(HeldOut {
                kind: HeldOutKind::Defocus,
                seed: 7
            })
        );
        assert!(parse_held_out("defocus").is_err());
        assert!(parse_held_out("sunset:1").is_err());
        assert!(parse_held_out("mirror:-1").is_err());
    }

    #[test]
    fn fair_counts_have_grids_of_at_most_four_to_one() {
        assert_eq!(fair_spp(163), 162, "9 x 18");
        assert_eq!(fair_spp(160), 160);
        assert_eq!(fair_spp(7), 7, "no 4:1 count within 5%");
        assert_eq!(fair_spp(0), 1);
        assert_eq!(fair_spp(1), 1);
    }

    #[test]
    fn the_time_correction_follows_the_power_law_of_the_two_renders() {
        // relMSE = 3 spp^-1.5, time = spp ms: at 100 ms, 3 * 100^-1.5.
        let f = |spp: f64| 3.0 * spp.powf(-1.5);
        let corrected = at_time((50, f(50.0)), (90, 90.0, f(90.0)), 100.0);
        assert!(
            (corrected - f(100.0)).abs() < 1e-12 * f(100.0),
            "{corrected}"
        );
        // Counts too close for a slope: no correction.
        assert_eq!(at_time((85, 1.0), (90, 90.0, 2.0), 100.0), 2.0);
        // A slope no convergence has is clamped.
        let steep = at_time((10, 1e6), (90, 90.0, 1.0), 180.0);
        assert!((steep - 0.125).abs() < 1e-12, "{steep}");
    }
}
