//! The compressed wide BVH (CWBVH: eight children per 80-byte node, child boxes quantised to
//! 8 bits per plane; Ylitie, Karras and Laine, HPG 2017), made by obvhs from a BVH2 of the
//! scene's primitives, and its closest-hit and any-hit traversal. The GPU reads 80 bytes per visited node instead of
//! the BVH2's 64 for two children, and visits a third as many nodes.
//! Twin: `wgsl/traverse_cwbvh.wgsl`, the same traversal step by step.
//!
//! Child boxes are dequantised (`p + q * 2^e`, exact for the product, one rounding for the sum)
//! and tested with the BVH2's slab test, `intersect::intersect_box`: the BVH2's boxes were
//! widened by 16 ULPs before obvhs quantised them outward, which covers the one rounding.

use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;

use super::intersect::{Hit, RayQuery, intersect_box, intersect_primitive};
use super::planes::{closest_plane, plane_occludes};
use super::{Primitives, swept_bounds, widen};
use crate::layout::{CWBVH_STACK_SIZE, FEATURES_ALL, GpuCwNode, GpuPrimitive, NONE, T_FAR};

/// A CWBVH and the bounded primitives in the order its leaves index them, planes after them.
pub struct CwGeometry {
    /// The CWBVH nodes, root first (one empty node for an empty scene).
    pub nodes: Vec<GpuCwNode>,
    /// Bounded primitives in the order the leaves index them, then the planes.
    pub prims: Vec<GpuPrimitive>,
    /// For each primitive it was built from, its index in `prims`.
    position_of: Vec<u32>,
    /// Index in `prims` of the first plane.
    pub plane_start: u32,
    /// Planes at the end of `prims`.
    pub plane_count: u32,
    /// 0 when nothing moves; else where the velocity records start in `prims` (in this
    /// order; the same index as in the scene's BVH2 order).
    pub motion_base: u32,
}

/// Builds the CWBVH of `geometry`'s bounded primitives: obvhs's converter collapses a BVH2 of
/// one primitive per leaf into nodes of up to eight children and leaves of up to three
/// primitives, children ordered for each ray octant. That BVH2 is the scene's own with each
/// leaf's primitives split into a median tree along their centroids' widest axis (a few
/// levels: obvhs's leaves hold up to 8), not a second build. Fails if the tree is deeper than
/// the traversal stack.
pub fn build(geometry: Primitives<'_>) -> Result<CwGeometry, String> {
    let bounded = &geometry.prims[..geometry.plane_start as usize];
    // Each primitive's box over the shutter, widened as the BVH2's are.
    let boxes: Vec<Aabb> = bounded
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let velocity = geometry.offset(i as u32, 1.0);
            let mut b = swept_bounds(p, velocity, geometry.shutter);
            widen(&mut b);
            b
        })
        .collect();
    let bvh = single_primitive_leaves(geometry.bvh, &boxes);
    // `primitive_indices` of the result are positions in `bounded`.
    let cw = obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh, 3, true, false);
    let mut nodes: Vec<GpuCwNode> = cw.nodes.iter().map(|n| bytemuck::cast(*n)).collect();
    if nodes.is_empty() {
        // An empty node (no children) ends every traversal at once; the GPU needs one.
        nodes.push(GpuCwNode::default());
    }
    let depth = tree_depth(&nodes);
    if depth > CWBVH_STACK_SIZE as usize {
        return Err(format!(
            "the CWBVH is {depth} levels deep, more than its traversal stack of {CWBVH_STACK_SIZE}"
        ));
    }
    if cw.primitive_indices.len() != geometry.plane_start as usize {
        return Err(format!(
            "the CWBVH holds {} primitives of {}",
            cw.primitive_indices.len(),
            geometry.plane_start
        ));
    }
    let planes = geometry.plane_start..geometry.plane_start + geometry.plane_count;
    let order: Vec<u32> = cw.primitive_indices.iter().copied().chain(planes).collect();
    let mut prims: Vec<GpuPrimitive> = order.iter().map(|&i| geometry.prims[i as usize]).collect();
    // The velocity records follow in the same order (the planes do not move).
    if geometry.motion_base != 0 {
        let base = geometry.motion_base;
        prims.extend(
            cw.primitive_indices
                .iter()
                .map(|&i| geometry.prims[(base + i) as usize]),
        );
    }
    let mut position_of = vec![NONE; order.len()];
    for (position, &i) in order.iter().enumerate() {
        position_of[i as usize] = position as u32;
    }
    let plane_start = cw.primitive_indices.len() as u32;
    Ok(CwGeometry {
        nodes,
        prims,
        position_of,
        plane_start,
        plane_count: geometry.plane_count,
        motion_base: geometry.motion_base,
    })
}

impl CwGeometry {
    /// A copy whose primitive array ends with `bytes` of primitives no leaf indexes: the same
    /// tree and traversals over a larger buffer (`bench scale --pad-mib`, which tells the cost
    /// of a buffer's size from that of the rays' work).
    pub fn padded(&self, bytes: usize) -> CwGeometry {
        let extra = bytes.div_ceil(size_of::<GpuPrimitive>());
        let mut prims = self.prims.clone();
        prims.resize(prims.len() + extra, GpuPrimitive::default());
        CwGeometry {
            nodes: self.nodes.clone(),
            prims,
            position_of: self.position_of.clone(),
            ..*self
        }
    }

    /// The planes' indices in `prims`.
    pub fn planes(&self) -> std::ops::Range<u32> {
        self.plane_start..self.plane_start + self.plane_count
    }

    /// How far primitive `id` has moved at `time` (zero in a static scene).
    pub fn offset(&self, id: u32, time: f32) -> glam::Vec3 {
        if self.motion_base == 0 {
            return glam::Vec3::ZERO;
        }
        glam::Vec3::from(self.prims[(self.motion_base + id) as usize].p0) * time
    }

    /// The index in `prims` of primitive `index` of the primitives it was built from (`NONE`
    /// stays `NONE`): what a light's `prim` becomes for the GPU.
    pub fn new_index(&self, index: u32) -> u32 {
        if index == NONE {
            NONE
        } else {
            self.position_of[index as usize]
        }
    }
}

/// `bvh` (whose leaves index the primitives of `boxes` directly) with every leaf of several
/// primitives replaced by a median tree of one-primitive leaves; `primitive_indices` of the
/// result are positions in `boxes`.
fn single_primitive_leaves(bvh: &Bvh2, boxes: &[Aabb]) -> Bvh2 {
    enum Work {
        Node(usize),
        Slots(usize, usize),
    }
    let mut indices: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![Bvh2Node::default(); bvh.nodes.len().min(1)];
    let mut stack = vec![(Work::Node(0), 0usize)];
    if bvh.nodes.is_empty() {
        stack.clear();
    }
    while let Some((work, at)) = stack.pop() {
        let (first, count) = match work {
            Work::Node(i) => {
                let node = &bvh.nodes[i];
                if node.prim_count == 0 {
                    let children = nodes.len();
                    nodes.extend([Bvh2Node::default(); 2]);
                    nodes[at] = Bvh2Node::new(node.aabb, 0, children as u32);
                    let left = node.first_index as usize;
                    stack.push((Work::Node(left), children));
                    stack.push((Work::Node(left + 1), children + 1));
                    continue;
                }
                (node.first_index as usize, node.prim_count as usize)
            }
            Work::Slots(first, count) => (first, count),
        };
        let slots = &mut indices[first..first + count];
        let aabb = slots
            .iter()
            .fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if count == 1 {
            nodes[at] = Bvh2Node::new(aabb, 1, first as u32);
            continue;
        }
        let mut centroids = Aabb::empty();
        for &i in slots.iter() {
            centroids.extend(boxes[i as usize].center());
        }
        let axis = centroids.largest_axis();
        slots.sort_by(|&a, &b| {
            let (a, b) = (
                boxes[a as usize].center_axis(axis),
                boxes[b as usize].center_axis(axis),
            );
            a.total_cmp(&b)
        });
        let children = nodes.len();
        nodes.extend([Bvh2Node::default(); 2]);
        nodes[at] = Bvh2Node::new(aabb, 0, children as u32);
        let half = count / 2;
        stack.push((Work::Slots(first, half), children));
        stack.push((Work::Slots(first + half, count - half), children + 1));
    }
    Bvh2 {
        nodes,
        primitive_indices: indices,
        ..Default::default()
    }
}

/// Levels of the longest root-to-leaf path of node groups.
fn tree_depth(nodes: &[GpuCwNode]) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((index, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let node = &nodes[index];
        let inner = (node.e_imask >> 24).count_ones() as usize;
        for child in 0..inner {
            stack.push((node.child_base as usize + child, depth + 1));
        }
    }
    deepest
}

/// Byte `i` (0..8) of a pair of little-endian words.
fn byte(words: [u32; 2], i: u32) -> u32 {
    (words[(i / 4) as usize] >> ((i % 4) * 8)) & 0xff
}

/// obvhs's `ray_get_octant_inv4`: for each of the four bytes, 7 minus the ray's octant.
fn octant_inv4(direction: Vec3) -> u32 {
    let x = if direction.x < 0.0 { 0 } else { 0x0404_0404 };
    let y = if direction.y < 0.0 { 0 } else { 0x0202_0202 };
    let z = if direction.z < 0.0 { 0 } else { 0x0101_0101 };
    x | y | z
}

/// The hit mask of a node's children: for an inner child hit, bit `24 + its traversal rank`
/// (nearest first for the ray's octant); for a leaf hit, its primitives' bits (0..24) from
/// `prim_base`. obvhs's `CwBvhNode::get_child_and_index_bits`, per child.
fn child_hits(ray: &RayQuery, node: &GpuCwNode, oct_inv4: u32, t_max: f32) -> u32 {
    let scale = |shift: u32| f32::from_bits(((node.e_imask >> shift) & 0xff) << 23);
    let e = Vec3::new(scale(0), scale(8), scale(16));
    let p = Vec3::from(node.p);
    let mut mask = 0;
    for child in 0..8 {
        let meta = byte(node.child_meta, child);
        if meta == 0 {
            continue;
        }
        let q = |words: [u32; 2]| byte(words, child) as f32;
        let lo = p + e * Vec3::new(q(node.q_lo_x), q(node.q_lo_y), q(node.q_lo_z));
        let hi = p + e * Vec3::new(q(node.q_hi_x), q(node.q_hi_y), q(node.q_hi_z));
        if intersect_box(ray, lo, hi, t_max) >= T_FAR {
            continue;
        }
        let inner = meta & (meta << 1) & 0x10 != 0;
        if inner {
            let rank = (meta ^ (oct_inv4 & 0xff)) & 0x1f;
            mask |= 1 << rank;
        } else {
            let count_bits = meta >> 5;
            mask |= count_bits << (meta & 0x1f);
        }
    }
    mask
}

/// The traversal, calling `leaf(id, t_max)` for each primitive of each leaf the ray reaches
/// before the current `t_max`; `leaf` returns the new `t_max` (lower on a closer hit) or
/// `None` to stop. Returns the nodes visited, or `None` if the stack overflowed (never for a
/// tree `build` accepted).
fn traverse(
    nodes: &[GpuCwNode],
    ray: &RayQuery,
    t_max_in: f32,
    mut leaf: impl FnMut(u32, f32) -> Option<f32>,
) -> Option<u32> {
    let mut visited = 0;
    let oct_inv4 = octant_inv4(ray.direction);
    let mut t_max = t_max_in;
    let mut stack = [[0u32; 2]; CWBVH_STACK_SIZE as usize];
    let mut stack_size = 0;
    // (child_base, hit bits 24..32 | inner mask 0..8): the root as the one child of a group.
    let mut current = [0u32, 0x8000_0000];
    loop {
        let mut prims = [0u32, 0];
        if current[1] & 0xff00_0000 != 0 {
            let hits = current[1];
            let bit = 31 - hits.leading_zeros();
            current[1] &= !(1 << bit);
            if current[1] & 0xff00_0000 != 0 {
                if stack_size == stack.len() {
                    return None;
                }
                stack[stack_size] = current;
                stack_size += 1;
            }
            let slot = (bit - 24) ^ (oct_inv4 & 0xff);
            let rank_in_base = (hits & !(u32::MAX << slot)).count_ones();
            let node = &nodes[(current[0] + rank_in_base) as usize];
            visited += 1;
            let mask = child_hits(ray, node, oct_inv4, t_max);
            current = [node.child_base, (mask & 0xff00_0000) | (node.e_imask >> 24)];
            prims = [node.prim_base, mask & 0x00ff_ffff];
        }
        while prims[1] != 0 {
            let bit = 31 - prims[1].leading_zeros();
            prims[1] &= !(1 << bit);
            match leaf(prims[0] + bit, t_max) {
                Some(t) => t_max = t,
                None => return Some(visited),
            }
        }
        if current[1] & 0xff00_0000 == 0 {
            if stack_size == 0 {
                return Some(visited);
            }
            stack_size -= 1;
            current = stack[stack_size];
        }
    }
}

/// Closest intersection along `ray` before `t_max`: (index into `geometry.prims`, hit).
/// `crate::accel::traverse::closest_hit` over the CWBVH, every feature compiled in.
pub fn closest_hit(geometry: &CwGeometry, ray: &RayQuery, t_max: f32) -> Option<(u32, Hit)> {
    closest_hit_counted(geometry, ray, t_max).0
}

/// What one traversal reads: nodes visited and primitives tested (planes included).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Nodes visited.
    pub nodes: u32,
    /// Primitives tested, planes included.
    pub prims: u32,
}

/// [`closest_hit`] and what it read (the GPU's kernel visits the same nodes in the same order).
pub fn closest_hit_counted(
    geometry: &CwGeometry,
    ray: &RayQuery,
    t_max: f32,
) -> (Option<(u32, Hit)>, Counts) {
    let mut counts = Counts {
        nodes: 0,
        prims: geometry.plane_count,
    };
    let mut best = Hit {
        t: t_max,
        b1: 0.0,
        b2: 0.0,
    };
    let mut best_prim = NONE;
    let visited = traverse(&geometry.nodes, ray, t_max, |id, t| {
        counts.prims += 1;
        let moved = ray.relative_to(geometry.offset(id, ray.time));
        let hit = intersect_primitive::<FEATURES_ALL>(&moved, &geometry.prims[id as usize], t);
        if hit.t < t {
            best = hit;
            best_prim = id;
        }
        Some(best.t)
    });
    counts.nodes = visited.expect("build() bounds the depth by the stack");
    closest_plane::<FEATURES_ALL>(
        &geometry.prims,
        geometry.planes(),
        ray,
        NONE,
        &mut best,
        &mut best_prim,
    );
    ((best_prim != NONE).then_some((best_prim, best)), counts)
}

/// Whether anything lies along `ray` before `t_max`.
pub fn occluded(geometry: &CwGeometry, ray: &RayQuery, t_max: f32) -> bool {
    let mut blocked = false;
    let visited = traverse(&geometry.nodes, ray, t_max, |id, t| {
        let prim = &geometry.prims[id as usize];
        let moved = ray.relative_to(geometry.offset(id, ray.time));
        blocked = intersect_primitive::<FEATURES_ALL>(&moved, prim, t).t < t;
        (!blocked).then_some(t)
    });
    visited.expect("build() bounds the depth by the stack");
    blocked
        || plane_occludes::<FEATURES_ALL>(
            &geometry.prims,
            geometry.planes(),
            ray,
            NONE,
            NONE,
            t_max,
        )
}
