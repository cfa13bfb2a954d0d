//! Packets: up to sixteen coherent rays (a pixel's samples, a few neighbouring pixels' camera
//! rays) traced through the wide BVH together. The packet descends as one: each node's eight
//! children are tested once against the interval that holds every ray of the packet (the box
//! of their origins, the range of their reciprocal directions per axis), instead of once per
//! ray. Where the interval hits a node's packed leaves, each ray tests their octets (a few more
//! leaves than its own box test would have let through: the octet test rejects a missed
//! triangle about as fast as the box test would have), with its own nearest hit so far. On a
//! CPU with AVX-512 both queries test the triangles of the leaves reached instead, one at a
//! time against every ray of the packet (`RayLanes`; a closest-hit ray with its own nearest
//! hit as its limit, by the octet test's rule): each ray's result is the same, and a triangle
//! takes one test where sixteen rays took sixteen.
//!
//! Each ray's result is the one-ray traversal's: the interval test is conservative in f32 (the
//! slab test's subtractions and products round monotonically, so the products at the
//! interval's ends bound every ray's own, and min and max keep those bounds), so the packet
//! reaches every leaf any of its rays would, and the primitive tests are the one-ray traversal's
//! (a hit they find is a true hit). Only the order leaves are met in differs: at
//! an exact tie (a ray through the edge two triangles share) another primitive may win at the
//! same distance.
//!
//! A packet whose rays point both ways along an axis (a reciprocal range that spans zero) has
//! no useful interval: its rays are traced one by one.

use super::*;
use crate::accel::octet::{NearestLanes, RayLanes};

/// Rays in a packet at most: a 4x4 block of camera rays, as Embree's 16-wide packets take
/// them. The interval test costs the same for any count, so more rays share each node's test;
/// coherent rays' intervals grow little from eight to sixteen (their any-hit queries ran 11%
/// faster, closest hits 8%: docs/embree.md).
pub const PACKET: usize = 16;

// The any-hit query keeps a bit per ray in a `u32`, its full mask `(1 << rays) - 1`.
const _: () = assert!(PACKET < u32::BITS as usize);

/// The interval holding every ray of a packet: per axis, the origins' range and the
/// reciprocal directions' range.
#[derive(Clone, Copy, Debug)]
struct Interval {
    origin_lo: [f32; 3],
    origin_hi: [f32; 3],
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
}

impl Interval {
    /// The interval of `rays`, or `None` when along some axis they point both ways.
    fn of(rays: &[RayQuery]) -> Option<Interval> {
        let mut interval = Interval {
            origin_lo: [f32::INFINITY; 3],
            origin_hi: [f32::NEG_INFINITY; 3],
            inv_lo: [f32::INFINITY; 3],
            inv_hi: [f32::NEG_INFINITY; 3],
        };
        for ray in rays {
            for axis in 0..3 {
                let (o, i) = (ray.origin[axis], ray.inv_direction[axis]);
                interval.origin_lo[axis] = interval.origin_lo[axis].min(o);
                interval.origin_hi[axis] = interval.origin_hi[axis].max(o);
                interval.inv_lo[axis] = interval.inv_lo[axis].min(i);
                interval.inv_hi[axis] = interval.inv_hi[axis].max(i);
            }
        }
        let one_way = (0..3).all(|axis| interval.inv_lo[axis] > 0.0 || interval.inv_hi[axis] < 0.0);
        one_way.then_some(interval)
    }

    /// Every ray leaves the same point.
    fn shared_origin(&self) -> bool {
        self.origin_lo == self.origin_hi
    }
}

/// The bounds of `(plane - o) * inv` over o in `[origin_lo, origin_hi]` and inv in
/// `[inv_lo, inv_hi]`: the four products at the ends (the product is monotonic in each factor,
/// and so is its rounding).
#[inline(always)]
fn plane_range(plane: f32, origin_lo: f32, origin_hi: f32, inv_lo: f32, inv_hi: f32) -> (f32, f32) {
    let (near, far) = (plane - origin_hi, plane - origin_lo);
    let (a, b) = (near * inv_lo, near * inv_hi);
    let (c, d) = (far * inv_lo, far * inv_hi);
    (min(min(a, b), min(c, d)), max(max(a, b), max(c, d)))
}

/// The slab test of [`node_hits`] on the interval: a bit per child that some ray of the
/// packet may hit before `t_max` (every child one of them hits is among them), and the least
/// entry distance of any ray into each. Lane loops the compiler vectorises.
#[inline(always)]
fn interval_hits(node: &WideNode, interval: &Interval, t_max: f32) -> (u32, [f32; LANES]) {
    let mut near = [0.0; LANES];
    let mut mask = 0;
    for (lane, near) in near.iter_mut().enumerate() {
        let mut t_near = f32::NEG_INFINITY;
        let mut t_far = f32::INFINITY;
        for axis in 0..3 {
            let ends = |plane: f32| {
                plane_range(
                    plane,
                    interval.origin_lo[axis],
                    interval.origin_hi[axis],
                    interval.inv_lo[axis],
                    interval.inv_hi[axis],
                )
            };
            let (lo_min, lo_max) = ends(node.planes[axis][lane]);
            let (hi_min, hi_max) = ends(node.planes[3 + axis][lane]);
            // A ray's min(t1, t2) is at least the least of both; its max(t1, t2) at most the
            // greatest.
            t_near = max(t_near, min(lo_min, hi_min));
            t_far = min(t_far, max(lo_max, hi_max));
        }
        *near = t_near;
        mask |= (slab_hit(t_near, t_far, t_max) as u32) << lane;
    }
    (mask & node.valid, near)
}

/// [`interval_hits`] in AVX2 intrinsics (the same bounds); with `SHARED` (every ray leaves
/// the same point, as a pinhole camera's do) two products per plane instead of four.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn interval_hits_avx2<const SHARED: bool>(
    node: &WideNode,
    interval: &Interval,
    t_max: f32,
) -> (u32, [f32; LANES]) {
    use std::arch::x86_64::*;
    let mut t_near = _mm256_set1_ps(f32::NEG_INFINITY);
    let mut t_far = _mm256_set1_ps(f32::INFINITY);
    for axis in 0..3 {
        let o_lo = _mm256_set1_ps(interval.origin_lo[axis]);
        let o_hi = _mm256_set1_ps(interval.origin_hi[axis]);
        let i_lo = _mm256_set1_ps(interval.inv_lo[axis]);
        let i_hi = _mm256_set1_ps(interval.inv_hi[axis]);
        let ends = |plane: __m256| {
            let near = _mm256_sub_ps(plane, o_hi);
            let (a, b) = (_mm256_mul_ps(near, i_lo), _mm256_mul_ps(near, i_hi));
            if SHARED {
                return (_mm256_min_ps(a, b), _mm256_max_ps(a, b));
            }
            let far = _mm256_sub_ps(plane, o_lo);
            let (c, d) = (_mm256_mul_ps(far, i_lo), _mm256_mul_ps(far, i_hi));
            (
                _mm256_min_ps(_mm256_min_ps(a, b), _mm256_min_ps(c, d)),
                _mm256_max_ps(_mm256_max_ps(a, b), _mm256_max_ps(c, d)),
            )
        };
        // SAFETY: the planes' rows are eight f32s each.
        let (lo, hi) = unsafe {
            (
                _mm256_loadu_ps(node.planes[axis].as_ptr()),
                _mm256_loadu_ps(node.planes[3 + axis].as_ptr()),
            )
        };
        let (lo_min, lo_max) = ends(lo);
        let (hi_min, hi_max) = ends(hi);
        t_near = _mm256_max_ps(_mm256_min_ps(lo_min, hi_min), t_near);
        t_far = _mm256_min_ps(_mm256_max_ps(lo_max, hi_max), t_far);
    }
    slab_hits_avx2(t_near, t_far, t_max, node.valid)
}

/// The interval test of the build in use.
#[inline(always)]
fn test_interval(
    node: &WideNode,
    interval: &Interval,
    t_max: f32,
    avx2: bool,
) -> (u32, [f32; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: `avx2` is true only where the CPU has AVX2.
        return unsafe {
            match interval.shared_origin() {
                true => interval_hits_avx2::<true>(node, interval, t_max),
                false => interval_hits_avx2::<false>(node, interval, t_max),
            }
        };
    }
    let _ = avx2;
    interval_hits(node, interval, t_max)
}

impl WideBvh {
    /// The closest hit along each of `rays` (at most [`PACKET`]) before `t_max`, as
    /// [`WideBvh::closest_hit`] finds it with no primitive skipped, into `hits`.
    pub fn closest_hits<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        hits: &mut [Option<(u32, Hit)>],
    ) {
        assert!(rays.len() <= PACKET && hits.len() == rays.len());
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: `avx512` is set only where the CPU reports AVX2 and AVX-512F.
            return unsafe { closest_hits_avx512::<F>(self, rays, t_max, hits) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where the CPU reports AVX2.
            return unsafe { closest_hits_avx2::<F>(self, rays, t_max, hits) };
        }
        closest_hits_inline::<F, false>(self, rays, t_max, hits)
    }

    /// Whether anything lies along each of `rays` (at most [`PACKET`]) before `t_max`, as
    /// [`WideBvh::occluded`] says with no primitive skipped, into `blocked`.
    pub fn occluded_packet<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        blocked: &mut [bool],
    ) {
        assert!(rays.len() <= PACKET && blocked.len() == rays.len());
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: `avx512` is set only where the CPU reports AVX2 and AVX-512F.
            return unsafe { occluded_packet_avx512::<F>(self, rays, t_max, blocked) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `closest_hits`.
            return unsafe { occluded_packet_avx2::<F>(self, rays, t_max, blocked) };
        }
        occluded_packet_inline::<F, false>(self, rays, t_max, blocked)
    }
}

/// The closest-hit query of a packet. With `RAY_LANES` (compiled for AVX-512F only) a packed
/// leaf's triangles are tested one at a time against every ray, where its rays share the
/// watertight test's axes, by the octet tests' rule (`TriangleOctet::nearest_rays`); otherwise
/// each ray tests the octets.
#[inline(always)]
fn closest_hits_inline<const F: u32, const RAY_LANES: bool>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    hits: &mut [Option<(u32, Hit)>],
) {
    let Some(interval) = Interval::of(rays) else {
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = closest_hit_inline::<F>(bvh, ray, NONE, t_max);
        }
        return;
    };
    let miss = Hit {
        t: t_max,
        b1: 0.0,
        b2: 0.0,
    };
    let mut best = [miss; PACKET];
    let mut best_slot = [NONE; PACKET];
    let lanes = if RAY_LANES { RayLanes::of(rays) } else { None };
    let all = (1u32 << rays.len()) - 1;
    // The farthest any ray still looks: a node beyond it holds nothing nearer for any of them.
    let mut reach = t_max;
    let mut stack = Stack::at_root(&bvh.nodes);
    while let Some((code, t_near)) = stack.pop() {
        if t_near >= reach {
            continue;
        }
        if code & LEAF != 0 {
            for (r, ray) in rays.iter().enumerate() {
                if t_near >= best[r].t {
                    continue;
                }
                for slot in leaf_slots(code) {
                    let moved = bvh.ray_for(ray, slot);
                    let hit =
                        intersect_primitive::<F>(&moved, &bvh.prims[slot as usize], best[r].t);
                    if hit.t < best[r].t {
                        best[r] = hit;
                        best_slot[r] = slot;
                    }
                }
            }
            reach = farthest(&best[..rays.len()]);
            continue;
        }
        let node = &bvh.nodes[code as usize];
        let (mask, near) = test_interval(node, &interval, reach, bvh.avx2);
        if mask & node.packed != 0 {
            let leaves = mask & node.packed;
            #[cfg(target_arch = "x86_64")]
            if let Some(lanes) = &lanes
                && has(F, FEATURE_TRIANGLES)
            {
                let mut nearest = NearestLanes::before(t_max);
                for r in 0..rays.len() {
                    (nearest.t[r], nearest.b1[r], nearest.b2[r]) =
                        (best[r].t, best[r].b1, best[r].b2);
                    nearest.slot[r] = best_slot[r];
                }
                let mut changed = 0;
                for octet in bvh.triangles_in(node, leaves) {
                    // SAFETY: `RAY_LANES` is set only where the CPU has AVX-512F.
                    changed |= unsafe { octet.nearest_rays(leaves, lanes, all, &mut nearest) };
                }
                while changed != 0 {
                    let r = changed.trailing_zeros() as usize;
                    changed &= changed - 1;
                    (best[r], best_slot[r]) = (nearest.hit(r), nearest.slot[r]);
                }
            }
            for (r, ray) in rays.iter().enumerate() {
                let (best, best_slot) = (&mut best[r], &mut best_slot[r]);
                if has(F, FEATURE_TRIANGLES) && lanes.is_none() {
                    let triangles = bvh.triangles_in(node, leaves);
                    nearest_in(triangles, ray, NONE, best, best_slot, bvh.avx2);
                }
                if node.quad_count != 0 {
                    let quads = bvh.quads_in(node, leaves);
                    nearest_in(quads, ray, NONE, best, best_slot, bvh.avx2);
                }
            }
            reach = farthest(&best[..rays.len()]);
        }
        stack.push_nearest_last(&bvh.nodes, node, mask & !node.packed, &near);
    }
    for (r, ray) in rays.iter().enumerate() {
        let (best, best_slot) = (&mut best[r], &mut best_slot[r]);
        closest_plane::<F>(&bvh.prims, bvh.planes(), ray, NONE, best, best_slot);
        hits[r] = (*best_slot != NONE).then(|| (bvh.ids[*best_slot as usize], *best));
    }
}

/// The farthest of the rays' nearest hits so far.
fn farthest(best: &[Hit]) -> f32 {
    best.iter()
        .fold(f32::NEG_INFINITY, |far, hit| max(far, hit.t))
}

/// The any-hit query of a packet. With `RAY_LANES` (compiled for AVX-512F only) a packed
/// leaf's triangles are tested one at a time against every ray still looking, where its rays
/// share the watertight test's axes; otherwise each ray tests the octets. Children are visited
/// nearest first, as the closest-hit query visits them: a packet of camera rays meets the
/// surface facing it sooner (5% more of the dragon's coherent any hits a second on Zen 2, five
/// alternating rounds, than in the children's order).
#[inline(always)]
fn occluded_packet_inline<const F: u32, const RAY_LANES: bool>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    blocked: &mut [bool],
) {
    let Some(interval) = Interval::of(rays) else {
        for (ray, blocked) in rays.iter().zip(blocked.iter_mut()) {
            *blocked = occluded_inline::<F>(bvh, ray, [NONE; 2], t_max);
        }
        return;
    };
    let lanes = if RAY_LANES { RayLanes::of(rays) } else { None };
    let all = (1u32 << rays.len()) - 1;
    // Bit per ray: something lies along it.
    let mut done = 0u32;
    let mut stack = Stack::at_root(&bvh.nodes);
    let mut visit = stack.pop().map(|(code, _)| code);
    while done != all {
        let Some(code) = visit else {
            break;
        };
        if code & LEAF != 0 {
            for (r, ray) in rays.iter().enumerate() {
                if done & (1 << r) != 0 {
                    continue;
                }
                let hits = leaf_slots(code).any(|slot| {
                    let moved = bvh.ray_for(ray, slot);
                    intersect_primitive::<F>(&moved, &bvh.prims[slot as usize], t_max).t < t_max
                });
                done |= (hits as u32) << r;
            }
            visit = stack.pop().map(|(code, _)| code);
            continue;
        }
        let node = &bvh.nodes[code as usize];
        let (mask, near) = test_interval(node, &interval, t_max, bvh.avx2);
        if mask & node.packed != 0 {
            let leaves = mask & node.packed;
            #[cfg(target_arch = "x86_64")]
            if let Some(lanes) = &lanes
                && has(F, FEATURE_TRIANGLES)
            {
                for octet in bvh.triangles_in(node, leaves) {
                    // SAFETY: `RAY_LANES` is set only where the CPU has AVX-512F.
                    done |= unsafe { octet.blocked_rays(leaves, lanes, all & !done, t_max) };
                }
            }
            // With the triangles tested in lanes, only quads are left for the rays one by one.
            let one_by_one = lanes.is_none() || node.quad_count != 0;
            for (r, ray) in rays.iter().enumerate() {
                if !one_by_one || done & (1 << r) != 0 {
                    continue;
                }
                let triangles = has(F, FEATURE_TRIANGLES)
                    && lanes.is_none()
                    && any_in(
                        bvh.triangles_in(node, leaves),
                        ray,
                        [NONE; 2],
                        t_max,
                        bvh.avx2,
                    );
                let quads = bvh.quads_in(node, leaves);
                let hits = triangles || any_in(quads, ray, [NONE; 2], t_max, bvh.avx2);
                done |= (hits as u32) << r;
            }
        }
        stack.push_nearest_last(&bvh.nodes, node, mask & !node.packed, &near);
        visit = stack.pop().map(|(code, _)| code);
    }
    for (r, ray) in rays.iter().enumerate() {
        blocked[r] = done & (1 << r) != 0
            || plane_occludes::<F>(&bvh.prims, bvh.planes(), ray, NONE, NONE, t_max);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn closest_hits_avx2<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    hits: &mut [Option<(u32, Hit)>],
) {
    closest_hits_inline::<F, false>(bvh, rays, t_max, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f")]
fn closest_hits_avx512<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    hits: &mut [Option<(u32, Hit)>],
) {
    closest_hits_inline::<F, true>(bvh, rays, t_max, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn occluded_packet_avx2<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    blocked: &mut [bool],
) {
    occluded_packet_inline::<F, false>(bvh, rays, t_max, blocked)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f")]
fn occluded_packet_avx512<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    blocked: &mut [bool],
) {
    occluded_packet_inline::<F, true>(bvh, rays, t_max, blocked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::rays::{
        Pinhole, RaySet, bounds, coherent_rays, incoherent_rays, packet_order,
    };
    use crate::layout::{FEATURES_ALL, T_FAR};
    use crate::math::rng::Rng;
    use crate::pack::{FlatScene, flatten};
    use crate::scene::sample_scene;

    fn scene(name: &str) -> FlatScene {
        flatten(&sample_scene(name, &[]))
    }

    /// A camera 2.5 sizes from the scene's centre along `axis`, looking at it, 48x32 rays.
    fn camera_rays(flat: &FlatScene, axis: Vec3) -> RaySet {
        let (lo, hi) = bounds(flat);
        let centre = 0.5 * (lo + hi);
        let position = centre + 2.5 * (hi - lo).length() * axis.normalize();
        let camera = Pinhole {
            position: position.to_array(),
            look_at: centre.to_array(),
            up: [0.0, 1.0, 0.0],
            vertical_fov_deg: 20.0,
            width: 48,
            height: 32,
        };
        coherent_rays(&camera, 1, 5)
    }

    /// `rays` with each origin moved by up to `spread` along each axis (a lens's rays).
    fn spread_origins(rays: &RaySet, spread: f32) -> RaySet {
        let mut moved = rays.clone();
        for (i, origin) in moved.origins.iter_mut().enumerate() {
            let mut rng = Rng::new(3, i as u32, 0);
            let [a, b] = rng.next_2d();
            let [c, _] = rng.next_2d();
            *origin += spread * (2.0 * Vec3::new(a, b, c) - 1.0);
        }
        moved
    }

    /// Each ray of every packet of `rays` (taken in `packet_order`, the last packet of each
    /// chunk cut to `PACKET - 3` rays so that short packets run too) finds what it finds alone:
    /// the same distance, the same primitive but at a tie, the same occlusion. Returns the hits
    /// and the packets whose rays pointed one way (traced as packets, not one by one).
    fn check(name: &str, bvh: &WideBvh, rays: &RaySet) -> (usize, usize) {
        let order = packet_order(rays);
        let (mut hits, mut ties, mut one_way) = (0, 0, 0);
        let mut start = 0;
        while start < order.len() {
            let len = match (start / PACKET) % 5 {
                4 => PACKET - 3,
                _ => PACKET,
            };
            let packet = &order[start..(start + len).min(order.len())];
            start += packet.len();
            let queries: Vec<RayQuery> = packet
                .iter()
                .map(|&i| RayQuery::new(rays.origins[i as usize], rays.directions[i as usize]))
                .collect();
            one_way += Interval::of(&queries).is_some() as usize;
            let mut found = vec![None; queries.len()];
            bvh.closest_hits::<FEATURES_ALL>(&queries, T_FAR, &mut found);
            for (k, ray) in queries.iter().enumerate() {
                let alone = bvh.closest_hit::<FEATURES_ALL>(ray, NONE, T_FAR);
                let t = |h: Option<(u32, Hit)>| h.map(|(_, hit)| hit.t);
                assert_eq!(t(found[k]), t(alone), "{name}: ray {}", packet[k]);
                hits += alone.is_some() as usize;
                ties += (found[k].map(|h| h.0) != alone.map(|h| h.0)) as usize;
            }
            // Shadow rays as long as the nearest hit, and a little longer.
            for scale in [1.0, 1.01] {
                let t_max = found.iter().flatten().fold(0.0f32, |m, h| m.max(h.1.t)) * scale;
                let t_max = if t_max > 0.0 { t_max } else { T_FAR };
                let mut blocked = vec![false; queries.len()];
                bvh.occluded_packet::<FEATURES_ALL>(&queries, t_max, &mut blocked);
                for (k, ray) in queries.iter().enumerate() {
                    let alone = bvh.occluded::<FEATURES_ALL>(ray, NONE, NONE, t_max);
                    assert_eq!(blocked[k], alone, "{name}: shadow ray {}", packet[k]);
                }
            }
        }
        assert!(ties <= 4, "{name}: {ties} ties");
        (hits, one_way)
    }

    /// Every build of the traversal the CPU has: AVX-512's ray lanes, AVX2's octets, and the
    /// portable one.
    fn check_builds(name: &str, flat: &FlatScene, rays: &RaySet) -> (usize, usize) {
        let wide = flat.wide().unwrap();
        let build =
            || WideBvh::build(flat.cwbvh().unwrap(), &flat.prims, flat.frame.motion_base).unwrap();
        let found = check(name, wide, rays);
        let mut octets = build();
        octets.avx512 = false;
        assert_eq!(check(name, &octets, rays), found, "{name}: AVX2");
        same_packet_hits(name, wide, &octets, rays);
        let mut portable = build();
        (portable.avx2, portable.avx512) = (false, false);
        assert_eq!(check(name, &portable, rays), found, "{name}: portable");
        found
    }

    /// The closest hits of every packet of `rays` in two builds of the traversal are the same,
    /// bit for bit and primitive for primitive: ray lanes follow the octet tests' rule.
    fn same_packet_hits(name: &str, a: &WideBvh, b: &WideBvh, rays: &RaySet) {
        let order = packet_order(rays);
        for packet in order.chunks(PACKET) {
            let queries: Vec<RayQuery> = packet
                .iter()
                .map(|&i| RayQuery::new(rays.origins[i as usize], rays.directions[i as usize]))
                .collect();
            let (mut found_a, mut found_b) = (vec![None; packet.len()], vec![None; packet.len()]);
            a.closest_hits::<FEATURES_ALL>(&queries, T_FAR, &mut found_a);
            b.closest_hits::<FEATURES_ALL>(&queries, T_FAR, &mut found_b);
            assert_eq!(found_a, found_b, "{name}: packet of rays {packet:?}");
        }
    }

    #[test]
    fn a_packet_finds_what_its_rays_find_one_by_one() {
        for name in ["bunny.toml", "tabletop.toml", "cornell_direct.toml"] {
            let flat = scene(name);
            let rays = camera_rays(&flat, Vec3::new(0.3, 0.4, 1.0));
            let (hits, one_way) = check_builds(name, &flat, &rays);
            // The camera's packets point one way (traced as packets), and most rays hit.
            assert!(
                one_way * PACKET > rays.len() / 2,
                "{name}: {one_way} packets"
            );
            assert!(hits > rays.len() / 10, "{name}: {hits} hits");
            // Origins apart: the interval of origins (not the shared-origin test).
            let spread = 0.01 * {
                let (lo, hi) = bounds(&flat);
                (hi - lo).length()
            };
            check_builds(name, &flat, &spread_origins(&rays, spread));
            // Looking down the z axis: the directions' x and y change sign at the middle
            // column and row, so packets there fall back, and those beside them hold
            // reciprocals of the smallest components (hundreds) in their intervals.
            let axial = camera_rays(&flat, Vec3::Z);
            let (_, one_way) = check_builds(name, &flat, &axial);
            assert!(
                one_way < axial.len() / PACKET,
                "{name}: every packet one way"
            );
            // Rays every way: most packets fall back to one ray at a time.
            let (lo, hi) = bounds(&flat);
            check_builds(name, &flat, &incoherent_rays(lo, hi, 1500, 7));
        }
    }
}
