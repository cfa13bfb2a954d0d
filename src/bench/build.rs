//! The BVH build benchmark: every obvhs preset on one mesh, with build time, node count, depth,
//! SAH cost and memory.

use std::path::{Path, PathBuf};

use obvhs::aabb::Aabb;
use serde::Serialize;

use super::Spread;
use crate::accel::build::{PRESETS, build_bvh_with, expected_traversal_iterations, tree_depth};
use crate::error::{Error, Result};
use crate::layout::{BVH_STACK_SIZE, GpuBvhNode};
use crate::scene::mesh_file::load_mesh;

/// One preset's figures.
#[derive(Clone, Debug, Serialize)]
pub struct BuildResult {
    /// The obvhs preset's name.
    pub preset: &'static str,
    /// Build time over the timed runs (ms).
    pub build_ms: Spread,
    /// Nodes of the BVH.
    pub nodes: usize,
    /// Longest root-to-leaf path (nodes).
    pub depth: usize,
    /// SAH cost with unit traversal and intersection costs: the expected loop iterations of a
    /// ray through the root box (`accel::build::expected_traversal_iterations`).
    pub sah_cost: f32,
    /// The uploaded BVH: nodes (`GpuBvhNode`) and the primitive order (4 bytes each).
    pub memory_bytes: usize,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct BuildReport {
    /// The mesh file.
    pub mesh: PathBuf,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Threads the builds could use (rayon's pool).
    pub threads: usize,
    /// One entry per preset.
    pub results: Vec<BuildResult>,
}

/// The boxes of a mesh's triangles.
pub fn triangle_boxes(mesh: &Path) -> Result<Vec<Aabb>> {
    let mesh = load_mesh(mesh).map_err(|message| Error::File {
        path: mesh.to_path_buf(),
        message,
    })?;
    Ok(mesh
        .triangles
        .iter()
        .map(|t| Aabb::from_points(&t.map(|i| mesh.positions[i as usize].into())))
        .collect())
}

/// Builds the mesh's BVH with every preset, `runs` times after a warm-up.
pub fn run(mesh: &Path, runs: u32) -> Result<BuildReport> {
    let boxes = triangle_boxes(mesh)?;
    let mut results = Vec::new();
    for (preset, params) in PRESETS {
        let (bvh, _) = build_bvh_with(&boxes, params, BVH_STACK_SIZE as usize);
        let times: Vec<f64> = (0..runs.max(1))
            .map(|_| build_bvh_with(&boxes, params, BVH_STACK_SIZE as usize).1)
            .map(|t| t.as_secs_f64() * 1e3)
            .collect();
        results.push(BuildResult {
            preset,
            build_ms: Spread::of(&times),
            nodes: bvh.nodes.len(),
            depth: tree_depth(&bvh.nodes),
            sah_cost: expected_traversal_iterations(&bvh.nodes),
            memory_bytes: bvh.nodes.len() * size_of::<GpuBvhNode>()
                + bvh.primitive_indices.len() * 4,
        });
    }
    Ok(BuildReport {
        mesh: mesh.to_path_buf(),
        triangles: boxes.len(),
        threads: rayon::current_num_threads(),
        results,
    })
}

impl BuildReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "build: {} ({} triangles), obvhs presets, {} threads; median (min–max) of the \
             timed runs\n\n",
            self.mesh.display(),
            self.triangles,
            self.threads
        );
        out += "| preset | build ms | nodes | depth | SAH cost | BVH MiB |\n";
        out += "|---|---|---|---|---|---|\n";
        for r in &self.results {
            out += &format!(
                "| {} | {:.1} ({:.1}–{:.1}) | {} | {} | {:.1} | {:.1} |\n",
                r.preset,
                r.build_ms.median,
                r.build_ms.min,
                r.build_ms.max,
                r.nodes,
                r.depth,
                r.sah_cost,
                r.memory_bytes as f64 / (1 << 20) as f64
            );
        }
        out
    }
}
