//! The acceleration stage: boxes and primitives. The bounded primitives (triangles, spheres,
//! quads) go into one obvhs BVH2 (`build`, with a depth bound) and are then reordered by the
//! BVH's `primitive_indices`, so a leaf's `first_index` indexes the primitive array directly on
//! both paths. Infinite planes cannot be bounded and follow the BVH's primitives, tested by
//! brute force. Node boxes are widened by a few ULPs once here, which makes obvhs's CPU slab
//! test and the WGSL one conservative against rounding alike. `intersect` tests rays against
//! primitives and boxes, `traverse` walks the BVH; `pack` turns a whole scene into the arrays
//! the kernels read.

pub mod build;
pub mod cwbvh;
pub mod intersect;
pub mod traverse;

use std::time::Duration;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

use build::{build_bvh, expected_traversal_iterations, tree_depth};

use crate::layout::*;

/// The primitives in BVH order, the BVH over them, and the unbounded planes after them.
pub struct Geometry {
    /// obvhs BVH over `prims[..plane_start]`; leaves index `prims` directly.
    pub bvh: Bvh2,
    /// The BVH's nodes as the GPU reads them.
    pub nodes: Vec<GpuBvhNode>,
    /// Bounded primitives in BVH order, then the planes.
    pub prims: Vec<GpuPrimitive>,
    /// Vertex normals of smooth triangles, indexed by `GpuPrimitive::normals`.
    pub normals: Vec<GpuNormals>,
    /// Index in `prims` of the first plane: the number of bounded primitives.
    pub plane_start: u32,
    /// Planes at the end of `prims`.
    pub plane_count: u32,
    /// For each bounded primitive as given, its index in `prims`.
    pub new_index: Vec<u32>,
    /// Longest root-to-leaf path (nodes); bounds the traversal stack.
    pub bvh_depth: usize,
    /// Expected loop iterations of one traversal (`build::expected_traversal_iterations`),
    /// planes included.
    pub traversal_iterations: f32,
    /// Wall-clock time of the BVH build.
    pub build_time: Duration,
}

/// What a traversal reads: the BVH, the primitives its leaves index, and the planes.
#[derive(Clone, Copy)]
pub struct Primitives<'a> {
    /// obvhs BVH over `prims[..plane_start]`; leaves index `prims` directly.
    pub bvh: &'a Bvh2,
    /// Bounded primitives in BVH order, then the planes.
    pub prims: &'a [GpuPrimitive],
    /// The planes are `prims[plane_start .. plane_start + plane_count]`.
    pub plane_start: u32,
    /// Planes at the end of `prims`.
    pub plane_count: u32,
}

impl Primitives<'_> {
    /// The planes' indices in `prims`.
    pub fn planes(&self) -> std::ops::Range<u32> {
        self.plane_start..self.plane_start + self.plane_count
    }
}

/// Relative widening of node boxes: 16 ULPs of the box's largest coordinate.
const BOX_WIDENING: f32 = 16.0 * f32::EPSILON;

/// Builds the BVH over `bounded` (each with its vertex normals, if any), puts the primitives in
/// BVH order, and appends `planes`.
pub fn build_geometry(
    bounded: Vec<(GpuPrimitive, Option<GpuNormals>)>,
    planes: Vec<GpuPrimitive>,
) -> Geometry {
    let aabbs: Vec<Aabb> = bounded.iter().map(|(p, _)| primitive_bounds(p)).collect();
    // The GPU's traversal stack bounds the depth (see `build`).
    let (mut bvh, build_time) = build_bvh(&aabbs, BVH_STACK_SIZE as usize);
    for node in &mut bvh.nodes {
        widen(&mut node.aabb);
    }

    // Reorder primitives so leaves index them directly; remap the area lights' quads.
    let order = &bvh.primitive_indices;
    let mut new_position = vec![0u32; bounded.len()];
    for (new, &old) in order.iter().enumerate() {
        new_position[old as usize] = new as u32;
    }
    let mut prims = Vec::with_capacity(bounded.len() + planes.len());
    let mut normals = Vec::new();
    for &old in order {
        let (mut p, n) = bounded[old as usize];
        if let Some(n) = n {
            p.normals = normals.len() as u32;
            normals.push(n);
        }
        prims.push(p);
    }
    let plane_start = prims.len() as u32;
    prims.extend(&planes);

    let nodes: Vec<GpuBvhNode> = bvh
        .nodes
        .iter()
        .map(|n| GpuBvhNode {
            min: n.aabb.min.to_array(),
            prim_count: n.prim_count,
            max: n.aabb.max.to_array(),
            first_index: n.first_index,
        })
        .collect();
    let bvh_depth = tree_depth(&bvh.nodes);
    let traversal_iterations = expected_traversal_iterations(&bvh.nodes) + planes.len() as f32;
    // obvhs sizes its CPU traversal stack from this field.
    bvh.max_depth = bvh.max_depth.max(bvh_depth + 1);
    Geometry {
        bvh,
        nodes,
        prims,
        normals,
        plane_start,
        plane_count: planes.len() as u32,
        new_index: new_position,
        bvh_depth,
        traversal_iterations,
        build_time,
    }
}

fn primitive_bounds(p: &GpuPrimitive) -> Aabb {
    let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3A::from);
    match p.kind {
        PRIM_SPHERE => Aabb::new(a - Vec3A::splat(b.x), a + Vec3A::splat(b.x)),
        PRIM_QUAD => Aabb::from_points(&[a, a + b, a + c, a + b + c]),
        _ => Aabb::from_points(&[a, b, c]),
    }
}

fn widen(aabb: &mut Aabb) {
    let scale = aabb.min.abs().max(aabb.max.abs()).max_element();
    let margin = Vec3A::splat(scale * BOX_WIDENING + f32::MIN_POSITIVE);
    aabb.min -= margin;
    aabb.max += margin;
}
