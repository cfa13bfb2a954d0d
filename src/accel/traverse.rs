//! Closest-hit and any-hit queries on the CPU: obvhs's BVH2 traversal with our primitive tests,
//! then the unbounded planes by brute force.
//! Twin: `wgsl/traverse.wgsl`, which mirrors obvhs's `Bvh2::ray_traverse_dynamic` node order.

use super::Primitives;
use super::intersect::{Hit, RayQuery, intersect_primitive};
use crate::layout::{FEATURE_PLANES, NONE, T_FAR, has};

/// Closest intersection along `ray` before `t_max`, ignoring primitive `skip` (the planar
/// primitive a secondary ray leaves, which it can never hit again). Returns (primitive, hit).
/// `F` is the scene's `layout::FEATURE_*` set: without `FEATURE_PLANES` the plane loop is
/// compiled out.
pub fn closest_hit<const F: u32>(
    geometry: Primitives<'_>,
    ray: &RayQuery,
    skip: u32,
    t_max: f32,
) -> Option<(u32, Hit)> {
    let mut best = Hit {
        t: t_max,
        b1: 0.0,
        b2: 0.0,
    };
    let mut best_prim = NONE;
    if !geometry.bvh.nodes.is_empty() {
        let mut record = obvhs::ray::RayHit::none();
        geometry
            .bvh
            .ray_traverse(ray.to_obvhs(t_max), &mut record, |r, id| {
                if id as u32 == skip {
                    return f32::INFINITY;
                }
                let hit = intersect_primitive::<F>(ray, &geometry.prims[id], r.tmax);
                if hit.t < r.tmax {
                    best = hit;
                    best_prim = id as u32;
                    hit.t
                } else {
                    f32::INFINITY
                }
            });
    }
    let plane_count = if has(F, FEATURE_PLANES) {
        geometry.plane_count
    } else {
        0
    };
    let planes = geometry.plane_start..geometry.plane_start + plane_count;
    for id in planes {
        if id == skip {
            continue;
        }
        let hit = intersect_primitive::<F>(ray, &geometry.prims[id as usize], best.t);
        if hit.t < best.t {
            best = hit;
            best_prim = id;
        }
    }
    (best_prim != NONE).then_some((best_prim, best))
}

/// Whether anything but `skip_a` and `skip_b` lies along `ray` before `t_max`.
pub fn occluded<const F: u32>(
    geometry: Primitives<'_>,
    ray: &RayQuery,
    skip_a: u32,
    skip_b: u32,
    t_max: f32,
) -> bool {
    if !geometry.bvh.nodes.is_empty() {
        let missed = geometry
            .bvh
            .ray_traverse_miss(ray.to_obvhs(t_max), |r, id| {
                if id as u32 == skip_a || id as u32 == skip_b {
                    return f32::INFINITY;
                }
                intersect_primitive::<F>(ray, &geometry.prims[id], r.tmax).t
            });
        if !missed {
            return true;
        }
    }
    let plane_count = if has(F, FEATURE_PLANES) {
        geometry.plane_count
    } else {
        0
    };
    let planes = geometry.plane_start..geometry.plane_start + plane_count;
    planes
        .filter(|&id| id != skip_a && id != skip_b)
        .any(|id| intersect_primitive::<F>(ray, &geometry.prims[id as usize], t_max).t < T_FAR)
}
