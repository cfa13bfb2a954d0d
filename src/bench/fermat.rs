//! The Fermat comparison: the raster preview's reflections on a curved mirror (a sphere, a
//! torus or Bézier patches; `docs/fermat.md`) against the ray tracer's, by the subdivision of the
//! reflected triangles. For each subdivision: the preview's frame time; how far reflected
//! features land from where the ray tracer puts them, in pixels; and FLIP over the mirror's
//! pixels against a ray-traced reference. Once: the ray-traced frame time at 1 sample per
//! pixel on the same device.
//!
//! Features are points along every edge of the reflected triangles: their corners, and eight
//! points between that no subdivision makes vertices (there a straight reflected edge departs
//! from the true curved one). The ray tracer's position of a feature X is the projection of
//! its true reflection point (`true_reflection`: Alhazen's point on a sphere, f64) where the
//! ray tracer sees that light path; the preview's is where its rasteriser draws X: the
//! projection of the barycentric mix, over the sub-triangle holding X, of the GPU's Fermat
//! points of that sub-triangle's corners (a reflected triangle is drawn flat between its
//! corners' points).

use std::path::Path;

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};
use serde::Serialize;

use super::Spread;
use super::frame::{Way, render_once};
use crate::accel::intersect::RayQuery;
use crate::accel::traverse::closest_hit;
use crate::error::{Error, Location, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::ShaderChecks;
use crate::gpu::render::PathKernels;
use crate::layout::{FEATURES_ALL, NONE, T_FAR};
use crate::pack::{FlatScene, flatten};
use crate::preview::reflections::fermat::{
    Solver, alhazen_sphere, drawn_in_preview, on_cylinder, on_patch, on_torus_half,
    reflection_error, seen_from_outside,
};
use crate::preview::{
    Detail, MirrorSurface, Reflector, clip_matrix, grid_point, reflectors, sub_triangle, tessellate,
};
use crate::preview::{PreviewOptions, PreviewRenderer, StageTimes, extent_and_far};
use crate::render::Image;
use crate::scene::Scene;
use crate::scene::parametric::Sphere;

/// Points along each edge of the reflected triangles, besides its corner.
const POINTS_PER_EDGE: u32 = 8;
/// Where the points sit in each 1/POINTS_PER_EDGE of an edge: off every grid of step 1/2^k,
/// so that no subdivision makes them vertices (where the preview is exact by construction).
const POINT_OFFSET: f32 = 0.382;

/// The figures of one subdivision.
#[derive(Clone, Debug, Serialize)]
pub struct FermatRow {
    /// Pieces each reflected triangle's edge is cut into.
    pub subdivision: u32,
    /// The main pass's triangles (curved shapes cut within the tolerance).
    pub triangles: usize,
    /// Coarse shapes: curved shapes that stray further than the tolerance at their finest.
    pub coarse_shapes: usize,
    /// Reflected triangles a frame, summed over the mirror's searches (what the cull considers).
    pub reflected_triangles: usize,
    /// Of those, the ones drawn (the cull's lists).
    pub reflected_drawn: usize,
    /// The preview's frame time (Fermat solves, main and reflection passes), milliseconds.
    pub preview_ms: Spread,
    /// The ray-traced GPU frame's time (finished on the device, as the preview's) over the
    /// preview's, round by round: a ray-traced frame against the median of the preview frames
    /// timed just after it.
    pub speedup: Spread,
    /// Features whose true reflection is in the frame.
    pub features: usize,
    /// Of those, the ones the preview draws (every corner of their sub-triangle converged).
    pub drawn: usize,
    /// Distance from the ray tracer's position of the drawn corners (vertices of the scene's
    /// triangles), pixels: largest; `None` where no corner is drawn (the eye inside the
    /// mirror, or the mirror out of the frame).
    pub corner_max_px: Option<f64>,
    /// Distance from the ray tracer's position of every drawn feature, pixels: median; `None`
    /// where none is drawn.
    pub displacement_median_px: Option<f64>,
    /// 99th percentile.
    pub displacement_p99_px: Option<f64>,
    /// Largest.
    pub displacement_max_px: Option<f64>,
    /// Mean FLIP over the mirror's pixels against the ray-traced reference.
    pub flip_reflector: Option<f64>,
    /// Where a preview frame's time goes: each stage submitted and waited for alone, medians
    /// of `--frames` frames drawn after the timed ones (`PreviewRenderer::stage_times`).
    pub stages: StageTimes,
}

/// The comparison's report.
#[derive(Clone, Debug, Serialize)]
pub struct FermatReport {
    /// The scene file.
    pub scene: String,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// The Fermat search's steps at most.
    pub steps: u32,
    /// How far (pixels) the preview's triangles may stray from a curved shape.
    pub tolerance_px: f64,
    /// With self-reflections: the tolerance (pixels) the mirror's own reflected triangles are
    /// cut for; `None` without.
    pub self_reflections: Option<f64>,
    /// The ray-traced frame at 1 sample per pixel on the GPU (the preview's device), until
    /// its last pass finished on the device (as the preview's frames are timed: the image not
    /// read back), milliseconds: every round's, of every subdivision.
    pub ray_traced_gpu_ms: Spread,
    /// The same frames with the image read back and made (`RenderOutput::elapsed`).
    pub ray_traced_gpu_read_ms: Spread,
    /// Of each GPU frame, its kernels' time by the device's timestamps; `None` where the
    /// adapter has no timestamps or is a CPU.
    pub ray_traced_gpu_kernel_ms: Option<Spread>,
    /// The ray-traced frame on the CPU path, the image made.
    pub ray_traced_cpu_ms: Spread,
    /// Samples per pixel of the ray-traced reference the FLIP column compares with.
    pub reference_spp: u32,
    /// One row per subdivision.
    pub rows: Vec<FermatRow>,
}

/// What the comparison is asked.
pub struct FermatConfig<'a> {
    /// The scene: its first curved mirror is the reflector measured.
    pub scene: &'a Path,
    /// Overrides of the scene's fields (`--set`), e.g. a smaller image.
    pub overrides: &'a [String],
    /// Subdivisions to compare.
    pub subdivisions: &'a [u32],
    /// The Fermat search's steps at most.
    pub steps: u32,
    /// Rounds timed after a warm-up: the CPU path's ray-traced frames, and per subdivision a
    /// GPU ray-traced frame then `frames` preview frames each.
    pub runs: u32,
    /// Timed preview frames per round after a warm-up (a preview frame is short, and
    /// lavapipe's first few after a pipeline is built are slower).
    pub frames: u32,
    /// Samples per pixel of the ray-traced reference.
    pub reference_spp: u32,
    /// Searches solved in one dispatch at most (`PreviewOptions::searches_per_dispatch`).
    pub searches_per_dispatch: Option<usize>,
    /// How far (pixels) the preview's triangles may stray from a curved shape
    /// (`PreviewOptions::tolerance_px`).
    pub tolerance_px: f64,
    /// Mirrors that can see themselves reflect their own triangles, cut for this tolerance
    /// (`PreviewOptions::self_reflections`).
    pub self_reflections: Option<f64>,
}

/// Runs the comparison on `context`'s device.
pub fn run(config: &FermatConfig, context: &GpuContext) -> Result<FermatReport> {
    let load = |extra: Option<String>| {
        let overrides: Vec<String> = config.overrides.iter().cloned().chain(extra).collect();
        Scene::load(config.scene, &overrides)
    };
    let scene = load(None)?;
    let flat = flatten(&scene);
    let reflector = first_mirror(config.scene, &flat)?;
    let (width, height) = (flat.frame.width, flat.frame.height);
    let one_spp = load(Some("render.spp=1".into()))?;
    let one_spp = flatten(&one_spp);
    let features = flat.features();
    // A ray-traced frame's times: finished on the device, with its image read back, and its
    // kernels' by timestamps where the adapter has them and is not a CPU (lavapipe's, between
    // the preview's frames, read 0.04 ms of a 67 ms frame; alone, in `bench frame`, they agree
    // with the frame's time).
    let timestamps = !context.is_cpu_adapter;
    let ray_traced_ms = |way| -> Result<TracedTimes> {
        let traced = render_once(&one_spp, way, Some(context))?;
        let ms = |t: std::time::Duration| t.as_secs_f64() * 1e3;
        Ok(TracedTimes {
            traced: ms(traced.traced),
            read: ms(traced.elapsed),
            kernels: traced.kernel_time.filter(|_| timestamps).map(ms),
        })
    };
    let on_gpu = Way::Gpu {
        features,
        budgets: None,
        kernels: PathKernels::for_adapter(context.is_cpu_adapter),
        checks: ShaderChecks::default(),
    };
    let mut cpu_ms = Vec::new();
    for run in 0..=config.runs.max(1) {
        let cpu = ray_traced_ms(Way::Cpu { features })?.read;
        if run > 0 {
            cpu_ms.push(cpu);
        }
    }
    // Warm-up: lavapipe's first frames after a pipeline is built are slower.
    ray_traced_ms(on_gpu)?;
    let mut gpu_times = Vec::new();
    let reference = load(Some(format!("render.spp={}", config.reference_spp)))?;
    let reference = render_once(&flatten(&reference), Way::Cpu { features }, None)?.image;
    let clip = clip_matrix(&scene.camera, extent_and_far(&scene, &flat).1);
    let mask = reflector_mask(&flat, &clip, &reflector);
    let mut rows = Vec::new();
    for &subdivision in config.subdivisions {
        let options = PreviewOptions {
            tolerance_px: config.tolerance_px,
            subdivision: Some(subdivision),
            steps: config.steps,
            searches_per_dispatch: config.searches_per_dispatch,
            shadows: false,
            area_shadow_samples: 1,
            self_reflections: config.self_reflections,
        };
        let renderer = PreviewRenderer::new(context, &scene, &flat, options)?;
        renderer.draw()?;
        // Each round times a ray-traced frame and then the preview's frames, moments apart:
        // their ratio is that of one spell of this machine's load, which drifts between spells
        // by more than the difference measured.
        let mut times = Vec::new();
        let mut ratios = Vec::new();
        for _ in 0..config.runs.max(1) {
            let traced = ray_traced_ms(on_gpu)?;
            let round = renderer.timed_frames(config.frames)?;
            let round_ms: Vec<f64> = round.iter().map(|t| t.as_secs_f64() * 1e3).collect();
            ratios.push(traced.traced / Spread::of(&round_ms).median);
            gpu_times.push(traced);
            times.extend(round);
        }
        let frame = renderer.frame(&times)?;
        let stages = renderer.stage_times(config.frames)?;
        let placed = displacements(context, &scene, &flat, &reflector, &clip, options)?;
        let placement = Placement::of(&placed);
        rows.push(FermatRow {
            subdivision,
            triangles: frame.triangles,
            coarse_shapes: frame.coarse_shapes,
            reflected_triangles: frame.reflected_triangles,
            reflected_drawn: frame.reflected_drawn,
            preview_ms: Spread::of(&frame.frame_times_ms),
            speedup: Spread::of(&ratios),
            features: placed.len(),
            drawn: placement.drawn.len(),
            corner_max_px: placement.corner_max_px,
            displacement_median_px: placement.quantile(0.5),
            displacement_p99_px: placement.quantile(0.99),
            displacement_max_px: placement.quantile(1.0),
            flip_reflector: masked_flip(&frame.image, &reference, &mask),
            stages,
        });
    }
    if gpu_times.is_empty() {
        // No subdivision asked: the ray-traced frame is timed alone.
        gpu_times.push(ray_traced_ms(on_gpu)?);
    }
    let spread =
        |of: fn(&TracedTimes) -> f64| Spread::of(&gpu_times.iter().map(of).collect::<Vec<_>>());
    let kernel_ms: Vec<f64> = gpu_times.iter().filter_map(|t| t.kernels).collect();
    Ok(FermatReport {
        scene: config.scene.display().to_string(),
        width,
        height,
        steps: config.steps,
        tolerance_px: config.tolerance_px,
        self_reflections: config.self_reflections,
        ray_traced_gpu_ms: spread(|t| t.traced),
        ray_traced_gpu_read_ms: spread(|t| t.read),
        ray_traced_gpu_kernel_ms: (kernel_ms.len() == gpu_times.len())
            .then(|| Spread::of(&kernel_ms)),
        ray_traced_cpu_ms: Spread::of(&cpu_ms),
        reference_spp: config.reference_spp,
        rows,
    })
}

/// The scene's first curved mirror, or an error naming the scene's shapes.
fn first_mirror(scene: &std::path::Path, flat: &FlatScene) -> Result<Reflector> {
    reflectors(flat)
        .into_iter()
        .next()
        .ok_or_else(|| Error::Scene {
            location: Location {
                file: scene.to_path_buf(),
                line: 0,
                column: 0,
                field: "shapes".into(),
            },
            message: "the Fermat comparison needs a sphere, torus, ellipsoid, cylinder or Bezier \
                      shape with a mirror material"
                .into(),
        })
}

/// Where the preview put the reflected features against the ray tracer: each drawn one's
/// displacement in pixels, sorted, and the largest at a corner of the mirror's triangles.
struct Placement {
    drawn: Vec<f64>,
    corner_max_px: Option<f64>,
}

impl Placement {
    /// From `(at a corner, displacement if drawn)` per feature.
    fn of(placed: &[(bool, Option<f64>)]) -> Placement {
        let corner_max_px = placed
            .iter()
            .filter(|(corner, _)| *corner)
            .filter_map(|(_, d)| *d)
            .max_by(f64::total_cmp);
        let mut drawn: Vec<f64> = placed.iter().filter_map(|(_, d)| *d).collect();
        drawn.sort_by(f64::total_cmp);
        Placement {
            drawn,
            corner_max_px,
        }
    }

    /// The displacement below which a fraction `q` of the drawn features lie.
    fn quantile(&self, q: f64) -> Option<f64> {
        let last = self.drawn.len().checked_sub(1)?;
        self.drawn.get((last as f64 * q).round() as usize).copied()
    }
}

/// A ray-traced frame's times, milliseconds (`FermatReport`).
struct TracedTimes {
    /// Until its last pass finished on the device.
    traced: f64,
    /// With its image read back and made.
    read: f64,
    /// Its kernels, by timestamps.
    kernels: Option<f64>,
}

/// Pixel position (x right, y down, pixel centres at +0.5) of world point `p`, if in front.
fn project(clip: &DMat4, p: DVec3, width: u32, height: u32) -> Option<DVec2> {
    let c = *clip * p.extend(1.0);
    (c.w > 0.0).then(|| {
        DVec2::new(
            (c.x / c.w + 1.0) / 2.0 * width as f64,
            (1.0 - c.y / c.w) / 2.0 * height as f64,
        )
    })
}

/// For every feature whose true reflection lands in the frame: whether it is a corner of a
/// scene triangle, and its distance in pixels from where the preview draws it (`None` where
/// the preview does not draw it).
fn displacements(
    context: &GpuContext,
    scene: &Scene,
    flat: &FlatScene,
    reflector: &Reflector,
    clip: &DMat4,
    options: PreviewOptions,
) -> Result<Vec<(bool, Option<f64>)>> {
    let (width, height) = (flat.frame.width, flat.frame.height);
    let eye = crate::preview::eye_of(&scene.camera);
    let n = options.subdivision.unwrap_or(1).max(1);
    // Each feature: its position and its sub-triangle's corners with the weights mixing them.
    let mut features = Vec::new();
    let mut corners = Vec::new();
    let (extent, _) = extent_and_far(scene, flat);
    let detail = Detail::new(*clip, (width, height), options.tolerance_px);
    for t in tessellate(flat, extent, &detail).chunks_exact(3) {
        if t[0].reflector != 0 {
            continue;
        }
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec3::from(v.position));
        for (from, to) in [(0, 1), (1, 2), (2, 0)] {
            for k in 0..=POINTS_PER_EDGE {
                // k = 0: the corner; then the points between.
                let s = match k {
                    0 => 0.0,
                    k => (k as f32 - 1.0 + POINT_OFFSET) / POINTS_PER_EDGE as f32,
                };
                let mut w = [0.0f32; 3];
                w[from] += 1.0 - s;
                w[to] += s;
                let (sub, weights) = sub_triangle(w[1], w[2], n);
                let point = |corner| grid_point([a, b, c], corner, n);
                features.push((a * w[0] + b * w[1] + c * w[2], weights, k == 0));
                corners.extend(sub.map(point));
            }
        }
    }
    let eye64 = eye.as_dvec3();
    let mut out = Vec::new();
    for &surface in &reflector.searches {
        let found = crate::preview::reflections::kernel::reflections(
            context,
            surface,
            eye,
            &corners,
            options.steps,
        )?;
        for (k, (x, weights, corner)) in features.iter().enumerate() {
            let x = x.as_dvec3();
            let Some(truth) = true_reflection(&surface, eye64, x)
                .filter(|&p| light_path_is_clear(flat, eye64, p, x))
            else {
                continue;
            };
            let Some(truth_px) = project(clip, truth, width, height)
                .filter(|p| p.x >= 0.0 && p.y >= 0.0 && p.x < width as f64 && p.y < height as f64)
            else {
                continue;
            };
            let corners_found = &found[3 * k..3 * k + 3];
            let all_drawn = corners_found
                .iter()
                .zip(&corners[3 * k..3 * k + 3])
                .all(|(r, v)| {
                    let p = Vec3::from(r.point).as_dvec3();
                    let n = Vec3::from(r.normal).as_dvec3();
                    drawn_in_preview(p, n, eye64, v.as_dvec3())
                })
                && surface
                    .anchors([0, 1, 2].map(|c| glam::Vec2::from(corners_found[c].uv).as_dvec2()));
            let drawn_at = corners_found
                .iter()
                .zip(weights)
                .map(|(r, &w)| Vec3::from(r.point).as_dvec3() * w as f64)
                .sum::<DVec3>();
            out.push((
                *corner,
                all_drawn
                    .then(|| project(clip, drawn_at, width, height))
                    .flatten()
                    .map(|p| p.distance(truth_px)),
            ));
        }
    }
    Ok(out)
}

/// Whether the ray tracer sees the path E → P → X: the eye's ray toward P first meets the
/// scene at P (a torus hides parts of itself), and nothing stands between P and X (to 1e-3 of
/// each leg's length: Bézier patches are traced as a mesh, within 3e-4 of their size of the
/// surface; the f64 point and the f32 hit differ by rounding on the others).
fn light_path_is_clear(flat: &FlatScene, eye: DVec3, p: DVec3, x: DVec3) -> bool {
    let first_hit = |from: DVec3, to: DVec3| {
        let ray = RayQuery::new(from.as_vec3(), (to - from).normalize().as_vec3());
        closest_hit::<FEATURES_ALL>(flat.primitives(), &ray, NONE, T_FAR)
            .map_or(f64::INFINITY, |(_, hit)| hit.t as f64)
    };
    let (seen, reflected) = (p.distance(eye), x.distance(p));
    (first_hit(eye, p) - seen).abs() < 1e-3 * seen
        && first_hit(p + (x - p) * 1e-3, x) > reflected * (1.0 - 2e-3)
}

/// Where the ray tracer sees `x` reflected on `surface` from `eye`, if it does (seen from
/// outside). On a sphere: Alhazen's point, solved independently in f64. A torus can show a
/// point several times; the truth is the stationary point the preview's search heads for, the
/// f64 search run to convergence (`TRUTH_STEPS`, the law of reflection to 1e-9 rad), on the
/// search's half: its displacement is the preview's own error. Images the searches never find
/// show in the FLIP.
fn true_reflection(surface: &MirrorSurface, eye: DVec3, x: DVec3) -> Option<DVec3> {
    let (point, normal) = match *surface {
        MirrorSurface::Sphere { center, radius } => {
            let sphere = Sphere::new(center.as_dvec3(), radius as f64);
            let p = alhazen_sphere(&sphere, eye, x);
            (p, (p - sphere.center) / sphere.radius)
        }
        MirrorSurface::Torus(search) => {
            let (p, n, uv) = converged(&search, eye, x)?;
            if !on_torus_half(uv, search.half) {
                return None;
            }
            (p, n)
        }
        MirrorSurface::Patch(patch) => {
            let (p, n, uv) = converged(&patch, eye, x)?;
            if !on_patch(uv) {
                return None;
            }
            (p, n)
        }
        MirrorSurface::Ellipsoid(e) => {
            let (p, n, _) = converged(&e.facing(eye, x), eye, x)?;
            (p, n)
        }
        MirrorSurface::Cylinder { cylinder, height } => {
            let (p, n, uv) = converged(&cylinder, eye, x)?;
            if !on_cylinder(uv.y, height) {
                return None;
            }
            (p, n)
        }
    };
    seen_from_outside(point, normal, eye, x).then_some(point)
}

/// The point, normal and parameters where the f64 search on `surface` converges (the law of
/// reflection to 1e-9 rad), if it does.
fn converged(
    surface: &impl crate::preview::reflections::fermat::Reflector,
    eye: DVec3,
    x: DVec3,
) -> Option<(DVec3, DVec3, DVec2)> {
    let solver = Solver {
        max_steps: TRUTH_STEPS,
        min_size: 1e-12,
    };
    let uv = solver.solve(surface, eye, x).uv;
    let (p, n) = (surface.point(uv), surface.outward_normal(uv));
    (reflection_error(p, n, eye, x) <= 1e-9).then_some((p, n, uv))
}

/// Steps of the f64 search that finds a torus's true reflections (`true_reflection`).
const TRUTH_STEPS: u32 = 60;

/// The pixels whose centre's camera ray first meets the reflector (the CPU ray tracer's
/// closest hit is one of its primitives).
fn reflector_mask(flat: &FlatScene, clip: &DMat4, reflector: &Reflector) -> Vec<bool> {
    let (width, height) = (flat.frame.width, flat.frame.height);
    let mut on_reflector = vec![false; flat.prims.len()];
    for &p in &reflector.prims {
        on_reflector[p] = true;
    }
    let inverse = clip.inverse();
    let unproject = |x: f64, y: f64, z: f64| {
        let p = inverse * DVec4::new(x, y, z, 1.0);
        p.truncate() / p.w
    };
    (0..height)
        .flat_map(|py| (0..width).map(move |px| (px, py)))
        .map(|(px, py)| {
            let x = (px as f64 + 0.5) / width as f64 * 2.0 - 1.0;
            let y = 1.0 - (py as f64 + 0.5) / height as f64 * 2.0;
            let (near, far) = (unproject(x, y, 0.0), unproject(x, y, 1.0));
            let ray = RayQuery::new(near.as_vec3(), (far - near).normalize().as_vec3());
            closest_hit::<FEATURES_ALL>(flat.primitives(), &ray, NONE, T_FAR)
                .is_some_and(|(prim, _)| on_reflector[prim as usize])
        })
        .collect()
}

/// Mean FLIP of `image` against `reference` over the pixels of `mask`; `None` where the mask
/// is empty (the mirror out of the frame).
fn masked_flip(image: &Image, reference: &Image, mask: &[bool]) -> Option<f64> {
    let map = crate::metrics::flip_map(image, reference);
    let (sum, count) = map
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0, 0usize), |(s, c), (v, _)| (s + *v as f64, c + 1));
    (count > 0).then(|| sum / count as f64)
}

impl FermatReport {
    /// The report as Markdown tables.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "Fermat reflections against the ray tracer: {} ({}x{}), at most {} steps, curved \
             shapes within {} px{}\n\n\
             Ray-traced frame, 1 spp (medians of runs): GPU {:.2} ms finished on the device, \
             as the preview's frames below are timed ({:.2} ms with the image read back{}), \
             CPU {:.2} ms\n\n\
             | subdivision | triangles | reflected triangles (drawn) | preview (ms) | \
             ray-traced GPU / preview (median of rounds) | \
             features drawn | corners: max (px) | all features: median (px) | p99 (px) | \
             max (px) | FLIP of the mirror's pixels vs {} spp |\n\
             |---|---|---|---|---|---|---|---|---|---|---|\n",
            self.scene,
            self.width,
            self.height,
            self.steps,
            self.tolerance_px,
            self.self_reflections.map_or(String::new(), |px| format!(
                ", self-reflections within {px} px"
            )),
            self.ray_traced_gpu_ms.median,
            self.ray_traced_gpu_read_ms.median,
            self.ray_traced_gpu_kernel_ms
                .as_ref()
                .map_or(String::new(), |k| format!(
                    "; its kernels {:.2} ms by timestamps",
                    k.median
                )),
            self.ray_traced_cpu_ms.median,
            self.reference_spp
        );
        let figure =
            |d: Option<f64>, digits: usize| d.map_or("-".into(), |d| format!("{d:.digits$}"));
        let px = |d: Option<f64>| figure(d, 3);
        for r in &self.rows {
            out += &format!(
                "| {} | {} | {} ({}) | {:.2} | {:.1}x | {}/{} | {} | {} | {} | {} | {} |\n",
                r.subdivision,
                r.triangles,
                r.reflected_triangles,
                r.reflected_drawn,
                r.preview_ms.median,
                r.speedup.median,
                r.drawn,
                r.features,
                px(r.corner_max_px),
                px(r.displacement_median_px),
                px(r.displacement_p99_px),
                px(r.displacement_max_px),
                figure(r.flip_reflector, 4)
            );
        }
        if !self.rows.is_empty() {
            out += "\nWhere a preview frame goes (each stage submitted and waited for alone, \
                    medians; each includes a submission's round trip, which a frame pays \
                    once):\n\n\
                    | subdivision | Fermat solves (ms) | cull (ms) | main pass (ms) | \
                    reflection pass (ms) |\n|---|---|---|---|---|\n";
            for r in &self.rows {
                let t = r.stages;
                out += &format!(
                    "| {} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
                    r.subdivision, t.solve_ms, t.cull_ms, t.main_ms, t.reflect_ms
                );
            }
        }
        out
    }
}
