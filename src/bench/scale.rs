//! The scale benchmark: the same camera rays on meshes from a thousand to ten million
//! triangles, so users see how build time, throughput and memory grow with the scene.
//!
//! Below the full mesh, the sizes are prefixes of its triangle list (spatially coherent pieces of
//! it); above, copies of it on a grid beside the first, which the camera keeps looking at.
//!
//! Each path traces as the renderer traces camera rays: the CPU through the wide BVH in packets
//! of eight rays, the GPU through the CWBVH; both through the BVH2 where a scene's CWBVH is
//! refused (deeper than the traversal's stack), as the renderer falls back.

use std::path::Path;
use std::time::{Duration, Instant};

use glam::Vec3;
use plotters::prelude::*;
use serde::Serialize;

use super::Spread;
use super::rays::{Bvh, Checksum, Pinhole, Query, coherent_rays, trace_cpu};
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::trace::GpuTracer;
use crate::layout::{GpuBvhNode, GpuCwNode, GpuNormals, GpuPrimitive};
use crate::pack::{FlatScene, flatten};
use crate::plot::{Figure, log_log_panel};
use crate::scene::mesh::TriangleMesh;
use crate::scene::mesh_file::load_mesh;
use crate::scene::{Scene, Shape};

/// Triangle counts measured by default: prefixes of the mesh, then 4 and 12 copies of it.
pub const PREFIXES: [usize; 6] = [1_000, 4_000, 16_000, 64_000, 256_000, 1 << 40];
/// Copies of the whole mesh measured by default.
pub const COPIES: [usize; 2] = [4, 12];

/// One scene size's figures.
#[derive(Clone, Debug, Serialize)]
pub struct ScaleResult {
    /// Triangles of the scene.
    pub triangles: usize,
    /// Bytes of primitives no leaf indexes at the end of the GPU's primitive array.
    pub padding_bytes: usize,
    /// The BVH2 build by obvhs (ms).
    pub build_ms: f64,
    /// The CWBVH made from the BVH2, and the CPU's wide BVH from that (ms).
    pub wide_build_ms: f64,
    /// What the CPU path traced.
    pub cpu_bvh: Bvh,
    /// What the GPU path traced.
    pub gpu_bvh: Bvh,
    /// Nodes of the BVH the GPU traced.
    pub bvh_nodes: usize,
    /// Bytes of the arrays the GPU's traversal reads (nodes and primitives, normals included).
    pub scene_bytes: usize,
    /// The process's peak resident memory so far (Linux `VmHWM`), where the system says.
    pub peak_rss_bytes: Option<u64>,
    /// Closest-hit Mrays/s of the CPU path over the timed runs.
    pub cpu_mrays_per_s: Spread,
    /// `None` with the reason in `gpu_refused` when the GPU does not take the scene.
    pub gpu_mrays_per_s: Option<Spread>,
    /// Why the GPU did not take the scene, when it did not.
    pub gpu_refused: Option<String>,
    /// What the CPU path's closest-hit rays found.
    pub checksum: Checksum,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct ScaleReport {
    /// The mesh file.
    pub mesh: String,
    /// The camera of the rays (one per pixel).
    pub camera: Pinhole,
    /// Rays per measurement.
    pub rays: usize,
    /// One entry per size, smallest first.
    pub results: Vec<ScaleResult>,
}

/// A scene of `meshes` and nothing else, for the renderer's own build and traversal.
fn meshes_scene(meshes: Vec<TriangleMesh>) -> Result<FlatScene> {
    let text = "[render]\nwidth = 1\nheight = 1\n[camera]\nposition = [0.0, 0.0, 1.0]\n\
                look_at = [0.0, 0.0, 0.0]\nfilm = [24.0, 24.0]\n[[materials]]\nname = \"m\"\n\
                model = \"lambert\"\n";
    let mut scene = Scene::from_str(Path::new("scale.toml"), text, &[])?;
    scene.shapes = meshes
        .into_iter()
        .map(|mesh| Shape::Mesh { mesh, material: 0 })
        .collect();
    Ok(flatten(&scene))
}

/// The first `n` triangles of `mesh`.
fn prefix(mesh: &TriangleMesh, n: usize) -> TriangleMesh {
    TriangleMesh {
        positions: mesh.positions.clone(),
        normals: None,
        triangles: mesh.triangles[..n.min(mesh.triangles.len())].to_vec(),
        ..TriangleMesh::default()
    }
}

/// `count` copies of `mesh` on a grid in x and z, `spacing` mesh widths apart (1.1: a tenth of
/// a width between them), the first in place.
fn copies(mesh: &TriangleMesh, count: usize, spacing: f32) -> Vec<TriangleMesh> {
    let lo = mesh.positions.iter().fold(Vec3::MAX, |a, &p| a.min(p));
    let hi = mesh.positions.iter().fold(Vec3::MIN, |a, &p| a.max(p));
    let step = spacing * (hi - lo);
    let columns = (count as f64).sqrt().ceil() as usize;
    (0..count)
        .map(|i| {
            let offset = Vec3::new(
                (i % columns) as f32 * step.x,
                0.0,
                -((i / columns) as f32) * step.z,
            );
            TriangleMesh {
                positions: mesh.positions.iter().map(|&p| p + offset).collect(),
                normals: None,
                triangles: mesh.triangles.clone(),
                ..TriangleMesh::default()
            }
        })
        .collect()
}

fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn mrays(runs: u32, rays: usize, mut trace: impl FnMut() -> Result<Duration>) -> Result<Spread> {
    trace()?;
    let samples: Vec<f64> = (0..runs.max(1))
        .map(|_| trace().map(|t| rays as f64 / t.as_secs_f64() / 1e6))
        .collect::<Result<_>>()?;
    Ok(Spread::of(&samples))
}

fn measure(
    meshes: Vec<TriangleMesh>,
    camera: &Pinhole,
    runs: u32,
    gpu: Option<&Result<GpuContext>>,
    padding_bytes: usize,
) -> Result<ScaleResult> {
    let scene = meshes_scene(meshes)?;
    let start = Instant::now();
    let padded = match padding_bytes {
        0 => None,
        bytes => scene.cwbvh().ok().map(|cw| cw.padded(bytes)),
    };
    let cwbvh = padded.as_ref().or(scene.cwbvh().ok());
    let cpu_bvh = match scene.wide() {
        Ok(_) => Bvh::Packets,
        Err(_) => Bvh::Bvh2,
    };
    let wide_build_ms = start.elapsed().as_secs_f64() * 1e3;
    let rays = coherent_rays(camera, 1, 1);
    let checksum = Checksum::of(&trace_cpu(&scene, cpu_bvh, &rays, Query::ClosestHit)?);
    let cpu_mrays_per_s = mrays(runs, rays.len(), || {
        let start = Instant::now();
        trace_cpu(&scene, cpu_bvh, &rays, Query::ClosestHit)?;
        Ok(start.elapsed())
    })?;
    let (mut gpu_mrays_per_s, mut gpu_refused) = (None, None);
    if let Some(context) = gpu {
        match super::usable(context).and_then(|c| GpuTracer::new(c.clone(), &scene, cwbvh, &rays)) {
            Ok(tracer) => {
                gpu_mrays_per_s = Some(mrays(runs, rays.len(), || tracer.trace(Query::ClosestHit))?)
            }
            Err(e) => gpu_refused = Some(e.to_string()),
        }
    }
    let (gpu_bvh, bvh_nodes, node_bytes) = match cwbvh {
        Some(cw) => (
            Bvh::Cwbvh,
            cw.nodes.len(),
            cw.nodes.len() * size_of::<GpuCwNode>(),
        ),
        None => (
            Bvh::Bvh2,
            scene.nodes.len(),
            scene.nodes.len() * size_of::<GpuBvhNode>(),
        ),
    };
    Ok(ScaleResult {
        triangles: scene.triangle_count,
        padding_bytes,
        build_ms: scene.build_time.as_secs_f64() * 1e3,
        wide_build_ms,
        cpu_bvh,
        gpu_bvh,
        bvh_nodes,
        scene_bytes: node_bytes
            + padding_bytes
            + scene.prims.len() * size_of::<GpuPrimitive>()
            + scene.normals.len() * size_of::<GpuNormals>(),
        peak_rss_bytes: peak_rss_bytes(),
        cpu_mrays_per_s,
        gpu_mrays_per_s,
        gpu_refused,
        checksum,
    })
}

/// How the copies and padded rows of `run` are laid out.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Copies stand this many mesh widths apart (1.1 by default; farther, no camera ray
    /// reaches the others).
    pub spacing: f32,
    /// The whole mesh once more for each of these, its GPU primitive array padded by this many
    /// MiB that no ray reads: what a buffer's size costs apart from the rays' work.
    pub padding_mib: Vec<usize>,
}

/// Measures every prefix and copy count of `mesh` (smallest first, so the peak memory column
/// grows with the scene) with `camera`'s rays, one frame.
pub fn run(
    mesh: &Path,
    camera: &Pinhole,
    prefixes: &[usize],
    copy_counts: &[usize],
    layout: Layout,
    runs: u32,
    gpu: Option<&Result<GpuContext>>,
) -> Result<ScaleReport> {
    let full = load_mesh(mesh).map_err(|message| Error::File {
        path: mesh.to_path_buf(),
        message,
    })?;
    let mut results = Vec::new();
    for &n in prefixes {
        results.push(measure(vec![prefix(&full, n)], camera, runs, gpu, 0)?);
    }
    for &count in copy_counts {
        let meshes = copies(&full, count, layout.spacing);
        results.push(measure(meshes, camera, runs, gpu, 0)?);
    }
    for &mib in &layout.padding_mib {
        let whole = vec![prefix(&full, usize::MAX)];
        results.push(measure(whole, camera, runs, gpu, mib << 20)?);
    }
    Ok(ScaleReport {
        mesh: mesh.display().to_string(),
        camera: *camera,
        rays: camera.width as usize * camera.height as usize,
        results,
    })
}

impl ScaleReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "scale: {} (prefixes of its triangles, then copies beside it), {} coherent \
             closest-hit rays of the camera, BVH preset medium; Mrays/s median of the runs; \
             the GPU's BVH nodes and arrays\n\n",
            self.mesh, self.rays
        );
        out += "| triangles | padding MiB | build ms | wide BVHs ms | BVH nodes | scene MiB | peak RSS MiB | CPU BVH | CPU Mrays/s | GPU BVH | GPU Mrays/s | hits |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        for r in &self.results {
            let gpu = match (&r.gpu_mrays_per_s, &r.gpu_refused) {
                (Some(s), _) => format!("{:.2}", s.median),
                (None, Some(_)) => "refused (binding limit)".into(),
                (None, None) => "-".into(),
            };
            out += &format!(
                "| {} | {} | {:.1} | {:.1} | {} | {:.1} | {} | {} | {:.2} | {} | {gpu} | {} |\n",
                r.triangles,
                r.padding_bytes >> 20,
                r.build_ms,
                r.wide_build_ms,
                r.bvh_nodes,
                mib(r.scene_bytes as u64),
                r.peak_rss_bytes
                    .map_or("-".into(), |b| format!("{:.0}", mib(b))),
                r.cpu_bvh.label(),
                r.cpu_mrays_per_s.median,
                r.gpu_bvh.label(),
                r.checksum.hits
            );
        }
        out
    }
}

/// A log-log plot: build time and Mrays/s against triangles.
impl Figure for ScaleReport {
    fn size(&self) -> (u32, u32) {
        (1000, 420)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), String> {
        let fail = |e: &dyn std::fmt::Display| e.to_string();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (left, right) = root.split_horizontally(500);
        let triangles: Vec<f64> = self.results.iter().map(|r| r.triangles as f64).collect();
        let x_range = (triangles[0] * 0.7)..(triangles[triangles.len() - 1] * 1.4);
        let build: Vec<(f64, f64)> = self
            .results
            .iter()
            .map(|r| (r.triangles as f64, r.build_ms.max(1e-3)))
            .collect();
        let wide: Vec<(f64, f64)> = self
            .results
            .iter()
            .map(|r| (r.triangles as f64, r.wide_build_ms.max(1e-3)))
            .collect();
        let cpu: Vec<(f64, f64)> = self
            .results
            .iter()
            .map(|r| (r.triangles as f64, r.cpu_mrays_per_s.median))
            .collect();
        let gpu: Vec<(f64, f64)> = self
            .results
            .iter()
            .filter_map(|r| Some((r.triangles as f64, r.gpu_mrays_per_s?.median)))
            .collect();
        log_log_panel(
            &left,
            "BVH build time",
            "triangles",
            "ms",
            &[
                ("BVH2 (obvhs, medium preset)", &build, BLUE),
                ("CWBVH and wide BVH from it", &wide, GREEN),
            ],
            x_range.clone(),
        )?;
        log_log_panel(
            &right,
            "closest-hit throughput",
            "triangles",
            "Mrays/s",
            &[
                ("CPU path (wide BVH, packets)", &cpu, BLUE),
                ("GPU path (CWBVH)", &gpu, RED),
            ],
            x_range,
        )
    }
}
