//! The unbounded planes, which no BVH holds: every traversal (BVH2, wide, compressed) ends by
//! testing them by brute force. Twin: `closest_plane` and `plane_occludes` in
//! `wgsl/intersect.wgsl`.

use super::intersect::{Hit, RayQuery, intersect_primitive};
use crate::layout::{FEATURE_PLANES, GpuPrimitive, has};

/// The planes `planes` of `prims` (none without `FEATURE_PLANES`), by brute force: replaces
/// `best` and `best_prim` with a closer hit. Every traversal ends with them.
pub fn closest_plane<const F: u32>(
    prims: &[GpuPrimitive],
    planes: std::ops::Range<u32>,
    ray: &RayQuery,
    skip: u32,
    best: &mut Hit,
    best_prim: &mut u32,
) {
    let planes = if has(F, FEATURE_PLANES) { planes } else { 0..0 };
    for id in planes.filter(|&id| id != skip) {
        let hit = intersect_primitive::<F>(ray, &prims[id as usize], best.t);
        if hit.t < best.t {
            *best = hit;
            *best_prim = id;
        }
    }
}

/// Whether one of the planes `planes` of `prims` but `skip_a` and `skip_b` lies along `ray`
/// before `t_max` (none without `FEATURE_PLANES`).
pub fn plane_occludes<const F: u32>(
    prims: &[GpuPrimitive],
    planes: std::ops::Range<u32>,
    ray: &RayQuery,
    skip_a: u32,
    skip_b: u32,
    t_max: f32,
) -> bool {
    let planes = if has(F, FEATURE_PLANES) { planes } else { 0..0 };
    planes
        .filter(|&id| id != skip_a && id != skip_b)
        .any(|id| intersect_primitive::<F>(ray, &prims[id as usize], t_max).t < t_max)
}
