//! The acceleration stage: boxes and primitives. The bounded primitives (triangles, spheres,
//! quads) go into one obvhs BVH2 (`build`, with a depth bound) and are then reordered by the
//! BVH's `primitive_indices`, so a leaf's `first_index` indexes the primitive array directly on
//! both paths. Infinite planes cannot be bounded and follow the BVH's primitives, tested by
//! brute force. Node boxes are widened by a few ULPs once here, which makes obvhs's CPU slab
//! test and the WGSL one conservative against rounding alike. `intersect` tests rays against
//! primitives and boxes, `traverse` walks the BVH (`wide`: the CPU's 8-wide BVH); `pack` turns a whole scene into the arrays
//! the kernels read.

pub mod build;
pub mod curved;
pub mod cwbvh;
pub mod intersect;
pub mod octet;
pub mod pages;
pub mod planes;
pub mod ray;
pub mod traverse;
pub mod wide;

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

use build::{build_bvh, expected_traversal_iterations, tree_depth};
use curved::orientation;

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
    /// Texture coordinates of textured triangles, at their normals' index; empty when no
    /// triangle has any.
    pub texcoords: Vec<GpuTexCoords>,
    /// Index in `prims` of the first plane: the number of bounded primitives.
    pub plane_start: u32,
    /// Planes at the end of `prims`.
    pub plane_count: u32,
    /// 0 when nothing moves; else where the velocity records start in `prims` (after the
    /// planes): `prims[motion_base + i].p0` is primitive `i`'s velocity.
    pub motion_base: u32,
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
    /// 0 when nothing moves; else where the velocity records start in `prims`.
    pub motion_base: u32,
    /// [open, close] (seconds): the boxes bound each primitive over this interval.
    pub shutter: [f32; 2],
}

impl Primitives<'_> {
    /// The planes' indices in `prims`.
    pub fn planes(&self) -> std::ops::Range<u32> {
        self.plane_start..self.plane_start + self.plane_count
    }

    /// How far primitive `id` has moved at `time` (zero in a static scene).
    pub fn offset(&self, id: u32, time: f32) -> Vec3 {
        if self.motion_base == 0 {
            return Vec3::ZERO;
        }
        Vec3::from(self.prims[(self.motion_base + id) as usize].p0) * time
    }
}

/// How the bounded primitives move: each one's velocity in the order given (empty when nothing
/// moves), and the shutter interval [open, close] the BVH's boxes must cover.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Motion {
    /// Scene units a second, per bounded primitive.
    pub velocities: Vec<Vec3>,
    /// Seconds.
    pub shutter: [f32; 2],
}

/// The box of `p` over the shutter: its boxes at the shutter's ends joined (a translation
/// sweeps a box's corners along straight lines, so the two ends bound every time between).
pub(crate) fn swept_bounds(p: &GpuPrimitive, velocity: Vec3, shutter: [f32; 2]) -> Aabb {
    if velocity == Vec3::ZERO {
        return primitive_bounds(p);
    }
    let at = |t: f32| {
        let d = (velocity * t).to_array();
        let add = |a: [f32; 3]| [a[0] + d[0], a[1] + d[1], a[2] + d[2]];
        let moved = match p.kind {
            PRIM_TRIANGLE => GpuPrimitive {
                p0: add(p.p0),
                p1: add(p.p1),
                p2: add(p.p2),
                ..*p
            },
            _ => GpuPrimitive {
                p0: add(p.p0),
                ..*p
            },
        };
        primitive_bounds(&moved)
    };
    at(shutter[0]).union(&at(shutter[1]))
}

/// Relative widening of node boxes: 16 ULPs of the box's largest coordinate.
const BOX_WIDENING: f32 = 16.0 * f32::EPSILON;

/// What a triangle carries at its vertices beside their positions, each when it has it. A
/// triangle with either gets one index (`GpuPrimitive::normals`) into both arrays; zero normals
/// stand for a textured triangle's missing ones (a zero interpolated normal shades flat).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    /// Vertex normals (smooth shading).
    pub normals: Option<GpuNormals>,
    /// Texture coordinates (a textured material).
    pub texcoords: Option<GpuTexCoords>,
}

/// Builds the BVH over `bounded` (each with its vertex attributes), puts the primitives in
/// BVH order, and appends `planes`.
pub fn build_geometry(
    bounded: Vec<(GpuPrimitive, VertexAttributes)>,
    planes: Vec<GpuPrimitive>,
    motion: &Motion,
) -> Geometry {
    let velocity = |i: usize| motion.velocities.get(i).copied().unwrap_or(Vec3::ZERO);
    let aabbs: Vec<Aabb> = bounded
        .iter()
        .enumerate()
        .map(|(i, (p, _))| swept_bounds(p, velocity(i), motion.shutter))
        .collect();
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
    let mut texcoords = Vec::new();
    let any_texcoords = bounded.iter().any(|(_, a)| a.texcoords.is_some());
    for &old in order {
        let (mut p, attributes) = bounded[old as usize];
        if attributes != VertexAttributes::default() {
            p.normals = normals.len() as u32;
            normals.push(attributes.normals.unwrap_or_default());
            if any_texcoords {
                texcoords.push(attributes.texcoords.unwrap_or_default());
            }
        }
        prims.push(p);
    }
    let plane_start = prims.len() as u32;
    prims.extend(&planes);
    // The velocity records, in BVH order, after the planes.
    let motion_base = if motion.velocities.is_empty() {
        0
    } else {
        let base = prims.len() as u32;
        prims.extend(order.iter().map(|&old| GpuPrimitive {
            p0: velocity(old as usize).to_array(),
            kind: NONE,
            ..Default::default()
        }));
        base
    };

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
        texcoords,
        plane_start,
        plane_count: planes.len() as u32,
        motion_base,
        new_index: new_position,
        bvh_depth,
        traversal_iterations,
        build_time,
    }
}

/// The box around primitive `p` (planes excepted: they are unbounded).
pub(crate) fn primitive_bounds(p: &GpuPrimitive) -> Aabb {
    let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3A::from);
    match p.kind {
        PRIM_SPHERE => Aabb::new(a - Vec3A::splat(b.x), a + Vec3A::splat(b.x)),
        PRIM_ELLIPSOID | PRIM_CYLINDER | PRIM_TORUS => curved_bounds(p.kind, a, b, orientation(p)),
        PRIM_QUAD => Aabb::from_points(&[a, a + b, a + c, a + b + c]),
        _ => Aabb::from_points(&[a, b, c]),
    }
}

/// The box around every one of `prims`, widened as the BVH's node boxes are, so that a ray's
/// hit on one of them is never outside it; none where there is none or one is a plane
/// (unbounded).
pub(crate) fn widened_bounds<'a>(
    prims: impl IntoIterator<Item = &'a GpuPrimitive>,
) -> Option<[Vec3; 2]> {
    let mut union: Option<Aabb> = None;
    for p in prims {
        if p.kind == PRIM_PLANE {
            return None;
        }
        let b = primitive_bounds(p);
        union = Some(union.map_or(b, |u| u.union(&b)));
    }
    let mut aabb = union?;
    widen(&mut aabb);
    Some([aabb.min.into(), aabb.max.into()])
}

/// The box around an ellipsoid, cylinder or torus (`kind`, with `p0` and `p1` as
/// `GpuPrimitive` gives them) turned by `turn`: the tight box of the turned shape, each
/// half-extent widened by a few ULPs for the rotation's rounding. With the world's x, y, z
/// seen in the shape's frame as the rows of M (M = R^T):
/// an ellipsoid's half-extent along axis i is |M_i ⊙ radii|; a cylinder's, around its axis's
/// middle, h/2 |a_i| + r sqrt(1 - a_i^2) with a = R y its axis; a torus's R sqrt(1 - a_i^2) + r.
fn curved_bounds(kind: u32, p0: Vec3A, p1: Vec3A, turn: glam::Quat) -> Aabb {
    let rows = glam::Mat3A::from_quat(turn).transpose();
    let rows = [rows.x_axis, rows.y_axis, rows.z_axis];
    // sqrt(1 - a_i^2): the length of the world axis's part across the shape's axis.
    let across = |i: usize| (1.0 - rows[i].y * rows[i].y).max(0.0).sqrt();
    let (middle, half): (Vec3A, [f32; 3]) = match kind {
        PRIM_ELLIPSOID => (p0, [0, 1, 2].map(|i| (rows[i] * p1).length())),
        PRIM_CYLINDER => (
            p0 + Vec3A::from(turn * glam::Vec3::new(0.0, p1.y / 2.0, 0.0)),
            [0, 1, 2].map(|i| p1.y / 2.0 * rows[i].y.abs() + p1.x * across(i)),
        ),
        _ => (p0, [0, 1, 2].map(|i| p1.x * across(i) + p1.y)),
    };
    let half = Vec3A::from(half) * (1.0 + ROTATION_BOUNDS_WIDENING);
    Aabb::new(middle - half, middle + half)
}

/// Relative widening of a turned curved shape's box: the rotation matrix's and the extents'
/// rounding, a few ULPs, generously.
const ROTATION_BOUNDS_WIDENING: f32 = 64.0 * f32::EPSILON;

fn widen(aabb: &mut Aabb) {
    let scale = aabb.min.abs().max(aabb.max.abs()).max_element();
    let margin = Vec3A::splat(scale * BOX_WIDENING + f32::MIN_POSITIVE);
    aabb.min -= margin;
    aabb.max += margin;
}
