//! The motion-blur BVH benchmark: one BVH over boxes swept over the whole shutter (what chambre
//! renders with) against K BVHs, each swept over a K-th of it, a ray taking the one of its time
//! slice. The same camera rays at random times on a moving mesh, closest hit on the CPU path:
//! build time, Mrays/s, and a checksum that must not depend on K (the geometry at a given time
//! is the same whichever BVH finds it).

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::Spread;
use crate::accel::intersect::RayQuery;
use crate::accel::traverse::closest_hit;
use crate::error::{Error, Result};
use crate::layout::{FEATURES_ALL, NONE, T_FAR};
use crate::math::rng::Rng;
use crate::pack::{FlatScene, flatten};
use crate::scene::Scene;

/// One slicing's figures.
#[derive(Clone, Debug, Serialize)]
pub struct MotionResult {
    /// Time slices, each with a BVH swept over it (1: the whole shutter).
    pub slices: u32,
    /// Building every slice's BVH (ms).
    pub build_ms: Spread,
    /// Closest-hit throughput over the timed runs.
    pub mrays_per_s: Spread,
    /// Rays that hit, and the sum of their hit distances: the same for every slicing.
    pub hits: usize,
    /// Sum of the hit distances.
    pub t_sum: f64,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct MotionReport {
    /// The mesh file.
    pub mesh: PathBuf,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// How far the mesh moves while the shutter is open, in mesh sizes.
    pub travel: f64,
    /// Camera rays per run.
    pub rays: usize,
    /// One entry per slicing.
    pub results: Vec<MotionResult>,
}

/// The mesh moving at `velocity` (scene units a second) along x, with the shutter open over
/// `shutter` (the camera is not used: the rays are made here).
fn moving_scene(mesh: &Path, velocity: f64, shutter: [f64; 2]) -> Result<Scene> {
    let absolute = std::path::absolute(mesh).map_err(|e| Error::io(mesh, e))?;
    let text = format!(
        "[render]\nwidth = 1\nheight = 1\n[camera]\nposition = [0.0, 0.0, 1.0]\n\
         look_at = [0.0, 0.0, 0.0]\nfilm = [24.0, 24.0]\nshutter = [{:?}, {:?}]\n\
         [[materials]]\nname = \"m\"\nmodel = \"lambert\"\n[[shapes]]\ntype = \"mesh\"\n\
         file = {}\nmaterial = \"m\"\nvelocity = [{velocity:?}, 0.0, 0.0]\n",
        shutter[0],
        shutter[1],
        toml::Value::String(absolute.to_string_lossy().into_owned()),
    );
    Scene::from_str(Path::new("motion.toml"), &text, &[])
}

/// `n x n` rays from 2.5 mesh sizes in front of the mesh's box (at its start) along -z, 40°
/// field of view, each at a random time in [0, 1).
fn timed_rays(lo: Vec3, hi: Vec3, travel: f32, n: u32) -> Vec<RayQuery> {
    let size = (hi - lo).max_element();
    // Centred on the middle of the mesh's path.
    let centre = (lo + hi) / 2.0 + Vec3::new(travel * size / 2.0, 0.0, 0.0);
    let origin = centre + Vec3::new(0.0, 0.0, 2.5 * size);
    let half = 20f32.to_radians().tan();
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let mut rng = Rng::new(7, i, 0);
            let [jx, jy] = rng.next_2d();
            let time = rng.next_f32();
            let sx = (2.0 * (x as f32 + jx) / n as f32 - 1.0) * half;
            let sy = (1.0 - 2.0 * (y as f32 + jy) / n as f32) * half;
            RayQuery::new(origin, Vec3::new(sx, sy, -1.0).normalize()).at_time(time)
        })
        .collect()
}

/// Traces every ray through the BVH of its time slice; (hits, sum of t).
fn trace(slices: &[FlatScene], rays: &[RayQuery]) -> (usize, f64) {
    let k = slices.len();
    rays.par_iter()
        .map(|ray| {
            let slice = ((ray.time * k as f32) as usize).min(k - 1);
            let scene = &slices[slice];
            match closest_hit::<FEATURES_ALL>(scene.primitives(), ray, NONE, T_FAR) {
                Some((_, hit)) => (1, hit.t as f64),
                None => (0, 0.0),
            }
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Measures each slicing of `slices`: `runs` timed builds and traces after a warm-up.
pub fn run(mesh: &Path, travel: f64, slices: &[u32], n: u32, runs: u32) -> Result<MotionReport> {
    let still = flatten(&moving_scene(mesh, travel, [0.0, 0.0])?);
    let bounded = &still.prims[..still.frame.plane_start as usize];
    let (lo, hi) = bounded.iter().flat_map(|p| [p.p0, p.p1, p.p2]).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), v| (lo.min(Vec3::from(v)), hi.max(Vec3::from(v))),
    );
    let size = (hi - lo).max_element() as f64;
    // Velocity in scene units a second: `travel` mesh sizes over the one-second shutter.
    let speed = travel * size;
    let rays = timed_rays(lo, hi, travel as f32, n);
    let slices: Vec<u32> = slices.iter().map(|&k| k.max(1)).collect();
    let build = |k: u32| -> Result<Vec<FlatScene>> {
        (0..k)
            .map(|i| {
                let shutter = [i as f64 / k as f64, (i + 1) as f64 / k as f64];
                Ok(flatten(&moving_scene(mesh, speed, shutter)?))
            })
            .collect()
    };
    // Builds, then traces interleaved run by run across the slicings (a noisy machine drifts).
    let mut built = Vec::new();
    let mut build_ms = vec![Vec::new(); slices.len()];
    for (i, &k) in slices.iter().enumerate() {
        built.push(build(k)?);
        for _ in 0..runs.max(1) {
            let start = Instant::now();
            built[i] = build(k)?;
            build_ms[i].push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let checksums: Vec<(usize, f64)> = built.iter().map(|b| trace(b, &rays)).collect();
    let mut mrays = vec![Vec::new(); slices.len()];
    for _ in 0..runs.max(1) {
        for (i, b) in built.iter().enumerate() {
            let start = Instant::now();
            let (hits, _) = trace(b, &rays);
            mrays[i].push(rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6);
            assert_eq!(hits, checksums[i].0, "the same rays hit on every run");
        }
    }
    let results = slices
        .iter()
        .enumerate()
        .map(|(i, &k)| MotionResult {
            slices: k,
            build_ms: Spread::of(&build_ms[i]),
            mrays_per_s: Spread::of(&mrays[i]),
            hits: checksums[i].0,
            t_sum: checksums[i].1,
        })
        .collect();
    Ok(MotionReport {
        mesh: mesh.to_path_buf(),
        triangles: bounded.len(),
        travel,
        rays: rays.len(),
        results,
    })
}

impl MotionReport {
    /// The table for the terminal.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "motion blur BVH: {} ({} triangles) moving {} of its size over the shutter, {} \
             rays at random times, CPU path, closest hit; K BVHs each swept over a K-th of the \
             shutter against one over all of it\n\n",
            self.mesh.display(),
            self.triangles,
            self.travel,
            self.rays
        );
        out += "| slices | build ms | Mrays/s | vs 1 slice | hits | sum of t |\n";
        out += "|---|---|---|---|---|---|\n";
        let base = self.results.first().map_or(1.0, |r| r.mrays_per_s.median);
        for r in &self.results {
            out += &format!(
                "| {} | {:.1} ({:.1}–{:.1}) | {:.2} ({:.2}–{:.2}) | {:.2}x | {} | {:.6e} |\n",
                r.slices,
                r.build_ms.median,
                r.build_ms.min,
                r.build_ms.max,
                r.mrays_per_s.median,
                r.mrays_per_s.min,
                r.mrays_per_s.max,
                r.mrays_per_s.median / base,
                r.hits,
                r.t_sum
            );
        }
        out
    }
}
