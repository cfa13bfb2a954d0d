//! How accurate chambre's f32 hits are: the same camera rays traced by both paths in f32 and by
//! an f64 oracle, on a mesh moved far from the origin and scaled from tiny to huge.
//!
//! The oracle is independent of the renderer: the mesh's vertices transformed in f64, the
//! camera rays made in f64, and every ray tested against every triangle (Möller–Trumbore in
//! f64). The f32 paths get the scene as a user's file would give it (`scale`, `translate`) and
//! the f64 rays rounded to f32. So the errors below are everything a user sees: the scene's
//! and the rays' rounding to f32 as well as the intersection arithmetic.

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use super::rays::{Bvh, Query, RaySet, trace_cpu};
use crate::camera::generate_ray_f64;
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::trace::GpuTracer;
use crate::layout::T_FAR;
use crate::math::rng::Rng;
use crate::pack::{FlatScene, flatten};
use crate::sampler::{PatternSource, sample_2d};
use crate::scene::Scene;
use crate::scene::mesh_file::load_mesh;

/// One placement of the mesh: `world = scale * file + offset` (the offset along (1, 1, 1)).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Placement {
    /// Offset added to every coordinate (scene units).
    pub offset: f64,
    /// Uniform scale of the file's coordinates.
    pub scale: f64,
}

/// The default placements: far from the origin at unit scale, then tiny and huge.
pub const PLACEMENTS: [Placement; 7] = [
    Placement {
        offset: 0.0,
        scale: 1.0,
    },
    Placement {
        offset: 1e2,
        scale: 1.0,
    },
    Placement {
        offset: 1e4,
        scale: 1.0,
    },
    Placement {
        offset: 1e6,
        scale: 1.0,
    },
    Placement {
        offset: 0.0,
        scale: 1e-4,
    },
    Placement {
        offset: 0.0,
        scale: 1e4,
    },
    Placement {
        offset: 1e4,
        scale: 1e-2,
    },
];

/// Errors of one path against the oracle.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PathErrors {
    /// Rays the path and the oracle disagree on hitting (silhouette rays).
    pub hit_disagreements: usize,
    /// Median of |t - t_oracle| / t_oracle over rays both hit.
    pub median_relative_t: f64,
    /// Largest |t - t_oracle| / t_oracle.
    pub max_relative_t: f64,
    /// Hit point distance from the oracle's, over the mesh's size.
    pub median_point_error: f64,
    /// Largest hit point distance from the oracle's, over the mesh's size.
    pub max_point_error: f64,
}

/// One placement's figures.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionResult {
    /// Where the mesh was, at what scale.
    pub placement: Placement,
    /// Camera rays traced.
    pub rays: usize,
    /// Rays that hit the mesh according to the oracle.
    pub oracle_hits: usize,
    /// The CPU path's hits against the oracle.
    pub cpu: PathErrors,
    /// The GPU's hits against the oracle, when it ran.
    pub gpu: Option<PathErrors>,
    /// The pixel values of a render of the placement (`pixel_run`) against the oracle's.
    pub cpu_pixels: PixelErrors,
    /// The GPU render's pixels against the oracle's, when it ran.
    pub gpu_pixels: Option<PixelErrors>,
}

/// Pixel values of one path's render against the f64 oracle's.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PixelErrors {
    /// Pixels lit in both renders.
    pub lit: usize,
    /// Pixels lit in one render and black (a miss, a shadow, a surface facing away) in the
    /// other: silhouettes, shadow edges and terminators that rounding moves.
    pub disagreements: usize,
    /// Relative error of the lit pixels: median, 99th percentile, largest.
    pub median_relative: f64,
    /// 99th percentile of the lit pixels' relative error.
    pub p99_relative: f64,
    /// Largest relative error of a lit pixel.
    pub max_relative: f64,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionReport {
    /// The mesh file.
    pub mesh: PathBuf,
    /// The mesh's largest extent in file units (at scale 1).
    pub mesh_size: f64,
    /// The camera's height above the mesh's centre, in mesh sizes.
    pub camera_height: f64,
    /// One entry per placement.
    pub results: Vec<PrecisionResult>,
    /// The camera's own rays at the extremes of its settings, near and far from the origin.
    pub cameras: Vec<CameraResult>,
}

/// The mesh in f64 world coordinates, as triangles.
fn oracle_triangles(mesh: &Path, p: Placement) -> Result<Vec<[DVec3; 3]>> {
    let m = load_mesh(mesh).map_err(|message| Error::File {
        path: mesh.to_path_buf(),
        message,
    })?;
    let world = |i: u32| m.positions[i as usize].as_dvec3() * p.scale + DVec3::splat(p.offset);
    Ok(m.triangles.iter().map(|t| t.map(world)).collect())
}

/// Möller–Trumbore in f64: the distance along `d` (unit) from `o`, if the ray hits.
fn intersect_f64(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let t = e2.dot(q) * inv;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// The closest f64 hit of each ray, by brute force.
fn oracle(triangles: &[[DVec3; 3]], rays: &[(DVec3, DVec3)]) -> Vec<Option<f64>> {
    rays.par_iter()
        .map(|&(o, d)| {
            triangles
                .iter()
                .filter_map(|&t| intersect_f64(o, d, t))
                .min_by(f64::total_cmp)
        })
        .collect()
}

/// Camera rays in f64: a pinhole `2.5 * size` in front of the mesh's centre (+z) and `height *
/// size` above it, looking along -z, 40° vertical field of view, `n x n` pixels, one jittered
/// ray each.
fn camera_rays(lo: DVec3, hi: DVec3, height: f64, n: u32) -> Vec<(DVec3, DVec3)> {
    let centre = (lo + hi) / 2.0;
    let size = (hi - lo).max_element();
    let origin = centre + DVec3::new(0.0, height * size, 2.5 * size);
    let half = 20f64.to_radians().tan();
    let mut rays = Vec::with_capacity((n * n) as usize);
    for y in 0..n {
        for x in 0..n {
            let [jx, jy] = Rng::new(1, y * n + x, 0).next_2d();
            let sx = (2.0 * (x as f64 + jx as f64) / n as f64 - 1.0) * half;
            let sy = (1.0 - 2.0 * (y as f64 + jy as f64) / n as f64) * half;
            rays.push((origin, DVec3::new(sx, sy, -1.0).normalize()));
        }
    }
    rays
}

/// The render whose pixels are compared with the oracle's: the mesh placed as for the rays,
/// seen by a pinhole at the rays' camera (40° vertical field of view, `n x n` pixels, one
/// random sample each), Lambert grey 0.8 with flat normals, lit by one point light a mesh size
/// to the side and two above the mesh's centre (its intensity grows with the size squared,
/// so the irradiance does not depend on the scale); no ambient, background or bounce.
/// Returns the scene and the light's position and intensity in f64.
fn pixel_scene(
    mesh: &Path,
    p: Placement,
    lo: DVec3,
    hi: DVec3,
    height: f64,
    n: u32,
) -> Result<(Scene, DVec3, f64)> {
    let absolute = std::path::absolute(mesh).map_err(|e| Error::io(mesh, e))?;
    let centre = (lo + hi) / 2.0;
    let size = (hi - lo).max_element();
    let eye = centre + DVec3::new(0.0, height * size, 2.5 * size);
    let light = centre + DVec3::new(size, 2.0 * size, 1.5 * size);
    let v = |d: DVec3| format!("[{:e}, {:e}, {:e}]", d.x, d.y, d.z);
    let text = format!(
        "[render]\nwidth = {n}\nheight = {n}\nspp = 1\nmax_depth = 0\npixel_sampler = \"random\"\n\
         [camera]\nposition = {}\nlook_at = {}\nvertical_fov = 40.0\nfilm = [24.0, 24.0]\n\
         [[materials]]\nname = \"m\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.8, 0.8]\n\
         [[shapes]]\ntype = \"mesh\"\nfile = {}\nmaterial = \"m\"\nsmooth = false\n\
         scale = {:e}\ntranslate = [{:e}, {:e}, {:e}]\n\
         [[lights]]\ntype = \"point\"\nposition = {}\nintensity = [{:e}, {:e}, {:e}]\n",
        v(eye),
        v(eye - DVec3::Z * size),
        toml::Value::String(absolute.to_string_lossy().into_owned()),
        p.scale,
        p.offset,
        p.offset,
        p.offset,
        v(light),
        size * size,
        size * size,
        size * size,
    );
    let scene = Scene::from_str(Path::new("precision-pixels.toml"), &text, &[])?;
    Ok((scene, light, size * size))
}

/// The oracle's pixel values of `scene` (as `pixel_scene` makes it), from the triangles in
/// f64: each pixel's sample point drawn as the renderer draws it (`sampler::sample_2d`), its
/// ray made in f64 (`camera::generate_ray_f64`), the closest hit and the shadow ray by brute
/// force, and Lambert's `0.8 / pi * I * cos / r^2` (0 where nothing is hit or lit).
fn oracle_pixels(
    scene: &Scene,
    flat: &FlatScene,
    triangles: &[[DVec3; 3]],
    light: DVec3,
    intensity: f64,
) -> Vec<f64> {
    let frame = &flat.frame;
    let (w, h) = (frame.width, frame.height);
    let camera = &scene.camera;
    (0..w * h)
        .into_par_iter()
        .map(|pixel| {
            let (x, y) = (pixel % w, pixel / w);
            let mut rng = Rng::new(frame.seed, pixel, 0);
            let source = PatternSource::pixel(frame);
            let mut flags = 0;
            let jitter = sample_2d(
                frame,
                &flat.sample_table,
                source,
                x,
                y,
                0,
                &mut rng,
                &mut flags,
            );
            let film = DVec2::new(
                ((x as f64 + jitter[0] as f64) / w as f64 - 0.5) * camera.film_mm[0],
                (0.5 - (y as f64 + jitter[1] as f64) / h as f64) * camera.film_mm[1],
            );
            let (o, d) = generate_ray_f64(camera, film, DVec2::ZERO);
            let closest = triangles
                .iter()
                .enumerate()
                .filter_map(|(i, &t)| Some((intersect_f64(o, d, t)?, i)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((t, hit)) = closest else {
                return 0.0;
            };
            let [a, b, c] = triangles[hit];
            let p = o + d * t;
            let mut normal = (b - a).cross(c - a).normalize();
            if normal.dot(d) > 0.0 {
                normal = -normal;
            }
            let to_light = light - p;
            let distance = to_light.length();
            let wi = to_light / distance;
            let cos = normal.dot(wi);
            let shadowed = triangles.iter().enumerate().any(|(i, &t)| {
                i != hit
                    && intersect_f64(p, wi, t)
                        .is_some_and(|s| s > 1e-9 * distance && s < distance * (1.0 - 1e-9))
            });
            if cos <= 0.0 || shadowed {
                return 0.0;
            }
            0.8 / std::f64::consts::PI * intensity * cos / (distance * distance)
        })
        .collect()
}

/// One path's rendered pixels against the oracle's.
fn pixel_errors(rendered: &[glam::Vec3], exact: &[f64]) -> PixelErrors {
    let mut relative = Vec::new();
    let mut disagreements = 0;
    for (value, &exact) in rendered.iter().zip(exact) {
        match (value.x > 0.0, exact > 0.0) {
            (true, true) => relative.push((value.x as f64 - exact).abs() / exact),
            (false, false) => {}
            _ => disagreements += 1,
        }
    }
    relative.sort_by(f64::total_cmp);
    let at = |q: f64| {
        relative
            .get(((relative.len() as f64 * q) as usize).min(relative.len().saturating_sub(1)))
            .copied()
            .unwrap_or(0.0)
    };
    PixelErrors {
        lit: relative.len(),
        disagreements,
        median_relative: at(0.5),
        p99_relative: at(0.99),
        max_relative: relative.last().copied().unwrap_or(0.0),
    }
}

/// The pixel values of the placement's render on the CPU path, and on the GPU when given,
/// against the oracle's.
fn pixel_run(
    mesh: &Path,
    p: Placement,
    (lo, hi): (DVec3, DVec3),
    height: f64,
    n: u32,
    gpu: Option<&GpuContext>,
) -> Result<(PixelErrors, Option<PixelErrors>)> {
    let (scene, light, intensity) = pixel_scene(mesh, p, lo, hi, height, n)?;
    let flat = flatten(&scene);
    let exact = oracle_pixels(&scene, &flat, &oracle_triangles(mesh, p)?, light, intensity);
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let render_on = |backend: &mut dyn crate::render::Backend| -> Result<Vec<glam::Vec3>> {
        let output = crate::render::render(&flat, backend, &mut |_, _| {}, &cancel)?;
        match output.stopped {
            Some(e) => Err(e),
            None => Ok(output.image.pixels),
        }
    };
    let cpu = render_on(&mut crate::cpu::CpuRenderer::new(&flat))?;
    let gpu = match gpu {
        None => None,
        Some(context) => {
            let mut renderer = crate::gpu::GpuRenderer::new(context.clone(), &flat)?;
            Some(pixel_errors(&render_on(&mut renderer)?, &exact))
        }
    };
    Ok((pixel_errors(&cpu, &exact), gpu))
}

/// The mesh placed as a scene file would place it.
fn placed_scene(mesh: &Path, p: Placement) -> Result<FlatScene> {
    let absolute = std::path::absolute(mesh).map_err(|e| Error::io(mesh, e))?;
    let text = format!(
        "[render]\nwidth = 1\nheight = 1\n[camera]\nposition = [0.0, 0.0, 1.0]\n\
         look_at = [0.0, 0.0, 0.0]\nfilm = [24.0, 24.0]\n[[materials]]\nname = \"m\"\n\
         model = \"lambert\"\n[[shapes]]\ntype = \"mesh\"\nfile = {}\nmaterial = \"m\"\n\
         scale = {:e}\ntranslate = [{:e}, {:e}, {:e}]\n",
        toml::Value::String(absolute.to_string_lossy().into_owned()),
        p.scale,
        p.offset,
        p.offset,
        p.offset
    );
    Ok(flatten(&Scene::from_str(
        Path::new("precision.toml"),
        &text,
        &[],
    )?))
}

fn errors(
    distances: &[f32],
    rays: &[(DVec3, DVec3)],
    exact: &[Option<f64>],
    size: f64,
) -> PathErrors {
    let mut relative_t = Vec::new();
    let mut point = Vec::new();
    let mut disagreements = 0;
    for ((&t32, &(o, d)), &t64) in distances.iter().zip(rays).zip(exact) {
        match (t32 < T_FAR, t64) {
            (true, Some(t64)) => {
                relative_t.push((t32 as f64 - t64).abs() / t64);
                // The f32 ray as the path traced it, its hit point in f64.
                let (o32, d32) = (o.as_vec3().as_dvec3(), d.as_vec3().as_dvec3());
                point.push((o32 + d32 * t32 as f64 - (o + d * t64)).length() / size);
            }
            (false, None) => {}
            _ => disagreements += 1,
        }
    }
    let median_max = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (
            v.get(v.len() / 2).copied().unwrap_or(0.0),
            v.last().copied().unwrap_or(0.0),
        )
    };
    let (median_relative_t, max_relative_t) = median_max(&mut relative_t);
    let (median_point_error, max_point_error) = median_max(&mut point);
    PathErrors {
        hit_disagreements: disagreements,
        median_relative_t,
        max_relative_t,
        median_point_error,
        max_point_error,
    }
}

/// Traces `n x n` camera rays at each placement on the CPU path, on the GPU when given, and by
/// the oracle; the camera `camera_height` mesh sizes above the mesh's centre (a flat mesh seen
/// from just above its plane makes grazing rays).
pub fn run(
    mesh: &Path,
    placements: &[Placement],
    n: u32,
    camera_height: f64,
    gpu: Option<&GpuContext>,
) -> Result<PrecisionReport> {
    let unit = oracle_triangles(mesh, PLACEMENTS[0])?;
    let (lo, hi) = unit.iter().flatten().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    );
    let mesh_size = (hi - lo).max_element();
    let mut results = Vec::new();
    for &p in placements {
        let triangles = oracle_triangles(mesh, p)?;
        let place = |v: DVec3| v * p.scale + DVec3::splat(p.offset);
        let rays = camera_rays(place(lo), place(hi), camera_height, n);
        let exact = oracle(&triangles, &rays);
        let set = RaySet {
            origins: rays.iter().map(|r| r.0.as_vec3()).collect(),
            directions: rays.iter().map(|r| r.1.as_vec3()).collect(),
            image_width: 0,
        };
        let scene = placed_scene(mesh, p)?;
        let size = mesh_size * p.scale;
        let cpu = errors(
            &trace_cpu(&scene, Bvh::Bvh2, &set, Query::ClosestHit)?,
            &rays,
            &exact,
            size,
        );
        let gpu_hits = match gpu {
            None => None,
            Some(context) => {
                let cw = scene.cwbvh().map_err(Error::Gpu)?;
                let tracer = GpuTracer::new(context.clone(), &scene, Some(cw), &set)?;
                tracer.trace(Query::ClosestHit)?;
                Some(errors(&tracer.distances()?, &rays, &exact, size))
            }
        };
        let placed = (place(lo), place(hi));
        let (cpu_pixels, gpu_pixels) = pixel_run(mesh, p, placed, camera_height, n, gpu)?;
        results.push(PrecisionResult {
            placement: p,
            rays: rays.len(),
            oracle_hits: exact.iter().filter(|t| t.is_some()).count(),
            cpu,
            gpu: gpu_hits,
            cpu_pixels,
            gpu_pixels,
        });
    }
    Ok(PrecisionReport {
        mesh: mesh.to_path_buf(),
        mesh_size,
        camera_height,
        results,
        cameras: camera_run(&[0.0, 1e4, 1e6], 32)?,
    })
}

impl PrecisionReport {
    /// The report as Markdown tables.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "precision: {} ({:.3} units across), camera rays from {} mesh sizes above its \
             centre against an f64 brute-force oracle; t error relative to the oracle's \
             distance, hit point error relative to the mesh's size; median / max\n\n",
            self.mesh.display(),
            self.mesh_size,
            self.camera_height
        );
        out += "| offset | scale | rays | oracle hits | path | hit/miss disagreements | t error | hit point error |\n";
        out += "|---|---|---|---|---|---|---|---|\n";
        for r in &self.results {
            let paths = [("cpu", Some(r.cpu)), ("gpu", r.gpu)];
            for (name, e) in paths {
                let Some(e) = e else { continue };
                out += &format!(
                    "| {:e} | {:e} | {} | {} | {name} | {} | {:.1e} / {:.1e} | {:.1e} / {:.1e} |\n",
                    r.placement.offset,
                    r.placement.scale,
                    r.rays,
                    r.oracle_hits,
                    e.hit_disagreements,
                    e.median_relative_t,
                    e.max_relative_t,
                    e.median_point_error,
                    e.max_point_error
                );
            }
        }
        out += &format!(
            "\nPixel values: the placement rendered at {n}x{n}, 1 spp (Lambert, one point \
             light, flat normals), each path's image against the f64 oracle's pixels; relative \
             error of the pixels lit in both: median / 99th percentile / max\n\n",
            n = (self.results.first().map_or(0, |r| r.rays) as f64).sqrt() as u32
        );
        out +=
            "| offset | scale | path | lit pixels | lit/black disagreements | relative error |\n";
        out += "|---|---|---|---|---|---|\n";
        for r in &self.results {
            for (name, e) in [("cpu", Some(r.cpu_pixels)), ("gpu", r.gpu_pixels)] {
                let Some(e) = e else { continue };
                out += &format!(
                    "| {:e} | {:e} | {name} | {} | {} | {:.1e} / {:.1e} / {:.1e} |\n",
                    r.placement.offset,
                    r.placement.scale,
                    e.lit,
                    e.disagreements,
                    e.median_relative,
                    e.p99_relative,
                    e.max_relative
                );
            }
        }
        out += "\n";
        out += &camera_markdown(&self.cameras);
        out
    }
}

/// A camera at the extremes, as scene-file `[camera]` lines (position and look_at are added).
pub const CAMERA_CASES: [(&str, &str); 7] = [
    (
        "f/8",
        "focal_length = 50.0\nf_number = 8.0\nfocus_distance = 5.0",
    ),
    (
        "f/0.7",
        "focal_length = 50.0\nf_number = 0.7\nfocus_distance = 5.0",
    ),
    (
        "f/1e6",
        "focal_length = 50.0\nf_number = 1e6\nfocus_distance = 5.0",
    ),
    (
        "lens tilt 60, swing 45",
        "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 5.0\nlens_tilt = 60.0\nlens_swing = 45.0",
    ),
    (
        "film tilt 60, shift 20 mm",
        "focal_length = 90.0\nf_number = 5.6\nfocus_distance = 5.0\nfilm_tilt = 60.0\nfilm_shift = [0.0, 20.0]",
    ),
    (
        "macro, focus 0.06",
        "focal_length = 50.0\nf_number = 2.8\nfocus_distance = 0.06",
    ),
    (
        "telephoto 1200 mm",
        "focal_length = 1200.0\nf_number = 8.0\nfocus_distance = 1000.0",
    ),
];

/// f32 camera rays against their f64 twin for one camera.
#[derive(Clone, Debug, Serialize)]
pub struct CameraResult {
    /// The camera settings, in words.
    pub case: String,
    /// Offset added to every coordinate of the camera and its subject (scene units).
    pub offset: f64,
    /// Rays compared.
    pub rays: usize,
    /// Angle between the f32 and the f64 direction, radians.
    pub median_angle: f64,
    /// Largest angle between the f32 and the f64 direction, radians.
    pub max_angle: f64,
    /// Distance between the f32 and the f64 origin, over the distance from the camera to its
    /// subject (the look-at point).
    pub max_origin_error: f64,
}

/// `1.5 n x n` rays per camera case, lens points spread over the aperture, with the camera at the
/// origin and `offset` away along (1, 1, 1): each f32 ray (`camera::generate_ray`) against its
/// f64 twin (`camera::generate_ray_f64`).
pub fn camera_run(offsets: &[f64], n: u32) -> Result<Vec<CameraResult>> {
    use crate::camera::{film_position_mm, generate_ray, generate_ray_f64};
    use glam::{DVec2, Vec2};
    let mut results = Vec::new();
    for &offset in offsets {
        for (case, fields) in CAMERA_CASES {
            let o = offset;
            // The film's 3:2 aspect.
            let w = n * 3 / 2;
            let text = format!(
                "[render]\nwidth = {w}\nheight = {n}\n[camera]\nposition = [{:e}, {:e}, {:e}]\n\
                 look_at = [{:e}, {:e}, {:e}]\nfilm = [36.0, 24.0]\n{fields}\n[[materials]]\n\
                 name = \"m\"\nmodel = \"lambert\"\n[[shapes]]\ntype = \"sphere\"\n\
                 center = [{:e}, {:e}, {:e}]\nradius = 1.0\nmaterial = \"m\"\n",
                o,
                o + 0.5,
                o + 5.0,
                o,
                o,
                o,
                o,
                o,
                o
            );
            let scene = Scene::from_str(Path::new("camera.toml"), &text, &[])?;
            let spec = &scene.camera;
            let gpu = spec.to_gpu(0);
            let subject = (spec.look_at - spec.position).length();
            let radius = spec.lens_radius_mm();
            let (mut angles, mut origins) = (Vec::new(), Vec::new());
            for y in 0..n {
                for x in 0..w {
                    let [jx, jy] = Rng::new(3, y * w + x, 0).next_2d();
                    let raster = Vec2::new(x as f32 + jx, y as f32 + jy);
                    let film = film_position_mm(&gpu, w, n, raster);
                    // A lens point on a ring at 0.9 of the radius, its angle from the pixel.
                    let a = std::f64::consts::TAU * jx as f64;
                    let lens64 = DVec2::new(a.cos(), a.sin()) * 0.9 * radius;
                    let ray = generate_ray(&gpu, film, lens64.as_vec2());
                    let (origin, direction) =
                        generate_ray_f64(spec, film.as_dvec2(), lens64.as_vec2().as_dvec2());
                    angles.push(ray.direction.as_dvec3().angle_between(direction));
                    origins.push((ray.origin.as_dvec3() - origin).length() / subject);
                }
            }
            angles.sort_by(f64::total_cmp);
            origins.sort_by(f64::total_cmp);
            results.push(CameraResult {
                case: case.to_string(),
                offset,
                rays: angles.len(),
                median_angle: angles[angles.len() / 2],
                max_angle: angles[angles.len() - 1],
                max_origin_error: origins[origins.len() - 1],
            });
        }
    }
    Ok(results)
}

/// The camera results as a Markdown table.
pub fn camera_markdown(results: &[CameraResult]) -> String {
    let mut out = String::from(
        "camera rays: f32 (`generate_ray`) against f64 (`generate_ray_f64`), subject 5 units \
         away; direction angle error in radians, origin error over the subject distance\n\n\
         | camera | offset | rays | angle median | angle max | origin max |\n\
         |---|---|---|---|---|---|\n",
    );
    for r in results {
        out += &format!(
            "| {} | {:e} | {} | {:.1e} | {:.1e} | {:.1e} |\n",
            r.case, r.offset, r.rays, r.median_angle, r.max_angle, r.max_origin_error
        );
    }
    out
}
