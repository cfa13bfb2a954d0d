//! Closest-hit and any-hit queries on the CPU: obvhs's BVH2 traversal with our primitive tests,
//! then the unbounded planes by brute force; [`Tracer`] picks between it and the wide BVH.
//! Twin: `wgsl/traverse.wgsl`, which mirrors obvhs's `Bvh2::ray_traverse_dynamic` node order.

use super::Primitives;
use super::intersect::{Hit, RayQuery, intersect_primitive};
use super::planes::{closest_plane, plane_occludes};
use super::wide::WideBvh;
use crate::layout::NONE;

/// What the CPU path traverses: the scene's wide BVH (`accel::wide`, 1.4–1.6x faster than the
/// BVH2 on the dragon's rays, `BENCHMARKS.md`), or the BVH2 where the scene has none (a tree
/// deeper than the CWBVH's stack). Both find the same hits.
#[derive(Clone, Copy)]
pub enum Tracer<'a> {
    /// The wide BVH.
    Wide(&'a WideBvh),
    /// obvhs's BVH2.
    Bvh2(Primitives<'a>),
}

impl Tracer<'_> {
    /// [`closest_hit`] through the tracer's BVH.
    #[inline]
    pub fn closest_hit<const F: u32>(
        &self,
        ray: &RayQuery,
        skip: u32,
        t_max: f32,
    ) -> Option<(u32, Hit)> {
        match self {
            Tracer::Wide(wide) => wide.closest_hit::<F>(ray, skip, t_max),
            Tracer::Bvh2(geometry) => closest_hit::<F>(*geometry, ray, skip, t_max),
        }
    }

    /// The closest hit along each of `rays` (at most `wide::PACKET`) before `t_max`, with no
    /// primitive skipped, into `hits`: traced as one packet through the wide BVH, one by one
    /// through the BVH2.
    pub fn closest_hits<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        hits: &mut [Option<(u32, Hit)>],
    ) {
        match self {
            Tracer::Wide(wide) => wide.closest_hits::<F>(rays, t_max, hits),
            Tracer::Bvh2(geometry) => {
                for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
                    *hit = closest_hit::<F>(*geometry, ray, NONE, t_max);
                }
            }
        }
    }

    /// [`occluded`] through the tracer's BVH.
    #[inline]
    pub fn occluded<const F: u32>(
        &self,
        ray: &RayQuery,
        skip_a: u32,
        skip_b: u32,
        t_max: f32,
    ) -> bool {
        match self {
            Tracer::Wide(wide) => wide.occluded::<F>(ray, skip_a, skip_b, t_max),
            Tracer::Bvh2(geometry) => occluded::<F>(*geometry, ray, skip_a, skip_b, t_max),
        }
    }
}

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
                let moved = ray.relative_to(geometry.offset(id as u32, ray.time));
                let hit = intersect_primitive::<F>(&moved, &geometry.prims[id], r.tmax);
                if hit.t < r.tmax {
                    best = hit;
                    best_prim = id as u32;
                    hit.t
                } else {
                    f32::INFINITY
                }
            });
    }
    closest_plane::<F>(
        geometry.prims,
        geometry.planes(),
        ray,
        skip,
        &mut best,
        &mut best_prim,
    );
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
                let moved = ray.relative_to(geometry.offset(id as u32, ray.time));
                intersect_primitive::<F>(&moved, &geometry.prims[id], r.tmax).t
            });
        if !missed {
            return true;
        }
    }
    plane_occludes::<F>(
        geometry.prims,
        geometry.planes(),
        ray,
        skip_a,
        skip_b,
        t_max,
    )
}
