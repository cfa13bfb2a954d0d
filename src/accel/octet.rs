//! Eight primitives against one ray at once: the watertight test of
//! `intersect::intersect_triangle` on a `TriangleOctet`, `intersect::intersect_quad` on a
//! `QuadOctet`, the primitives stored lane by lane, in AVX2 where the CPU has it. The CPU's wide
//! BVH (`wide`) packs the static triangles, and the static quads, of each node's leaves into
//! octets and tests them when the node's test finds one of those leaves hit, instead of pushing
//! each leaf and testing its one to three primitives one by one.
//!
//! A packet's any-hit query turns the lanes around where the CPU has AVX-512: one triangle of
//! an octet against sixteen rays ([`RayLanes`]), only the triangles of the leaves its interval
//! reached, as Embree's 16-wide packets test theirs.
//!
//! The AVX2 and AVX-512 tests perform the scalar tests' operations in the scalar tests' order,
//! lane by lane (no fused multiply-add: none is compiled with FMA), so each lane's result is
//! the scalar test's, bit for bit; `tests` checks it on random rays and primitives, edges and
//! extremes included. No GPU twin: the GPU tests a leaf's primitives one by one (its lanes are
//! rays).

use glam::Vec3;

use super::intersect::{Hit, MISS, RayQuery, gamma, intersect_quad, intersect_triangle};
use crate::layout::{GpuPrimitive, NONE};

/// Lanes of an octet.
pub const LANES: usize = 8;

/// Up to eight primitives of one kind, stored lane by lane (`R`: the kind's rows and tests),
/// and which primitives they are.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub struct Octet<R> {
    rows: R,
    /// Per lane: the primitive's slot in the wide BVH's primitives.
    pub slot: [u32; LANES],
    /// Bit per lane: the lane holds a primitive (empty lanes repeat lane 0's, so they stay
    /// finite, and are masked out).
    pub lanes: u32,
    /// Bit per lane of the node whose leaves the primitives come from: the leaves in this
    /// octet.
    pub leaves: u32,
    /// Per lane of that node: the bits of this octet's lanes that hold its leaf's primitives.
    leaf_lanes: [u8; LANES],
}

/// Eight triangles for the watertight test.
pub type TriangleOctet = Octet<TriangleRows>;
/// Eight quads for `intersect_quad`.
pub type QuadOctet = Octet<QuadRows>;

/// A kind of primitive an octet holds: how one is stored in a lane, the scalar test of one
/// lane, and the same test on eight lanes in AVX2.
pub trait Rows: Copy + Default {
    /// Stores `prim` in lane `lane`.
    fn store(&mut self, lane: usize, prim: &GpuPrimitive);
    /// The scalar test of lane `lane`.
    fn test(&self, lane: usize, ray: &RayQuery, t_max: f32) -> Hit;
    /// The scalar test's operations on the lanes of `lanes`, eight at once: a bit per lane
    /// hit before `t_max`, and what `H` keeps of the hits.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    unsafe fn test_avx2<H: LaneHits>(&self, ray: &RayQuery, t_max: f32, lanes: u32) -> (u32, H);
}

/// What an octet's test reports besides its bit per hit lane: each lane's hit (a closest-hit
/// query), or nothing (an any-hit query needs the bits alone; writing eight hits it never
/// reads cost each of its octet tests about a fifth of its instructions).
pub trait LaneHits: Copy {
    /// What a test that hit no lane reports.
    const MISSES: Self;

    /// What the scalar tests' hits report.
    fn from_hits(hits: [Hit; LANES]) -> Self;

    /// What the AVX2 test's lanes report, from their t, b1 and b2 vectors.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    unsafe fn from_lanes(
        t: std::arch::x86_64::__m256,
        b1: std::arch::x86_64::__m256,
        b2: std::arch::x86_64::__m256,
    ) -> Self;
}

impl LaneHits for [Hit; LANES] {
    const MISSES: Self = [MISS; LANES];

    fn from_hits(hits: [Hit; LANES]) -> Self {
        hits
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn from_lanes(
        t: std::arch::x86_64::__m256,
        b1: std::arch::x86_64::__m256,
        b2: std::arch::x86_64::__m256,
    ) -> Self {
        hit_lanes(t, b1, b2)
    }
}

impl LaneHits for () {
    const MISSES: Self = ();

    fn from_hits(_: [Hit; LANES]) -> Self {}

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn from_lanes(
        _: std::arch::x86_64::__m256,
        _: std::arch::x86_64::__m256,
        _: std::arch::x86_64::__m256,
    ) -> Self {
    }
}

impl<R: Rows> Octet<R> {
    /// The octet of `prims` (at most eight: (slot, primitive, the node lane of its leaf)).
    pub fn pack(prims: &[(u32, &GpuPrimitive, u32)]) -> Octet<R> {
        assert!(!prims.is_empty() && prims.len() <= LANES);
        let mut octet = Octet::<R>::default();
        for lane in 0..LANES {
            let (slot, prim, leaf_lane) = prims[if lane < prims.len() { lane } else { 0 }];
            octet.rows.store(lane, prim);
            octet.slot[lane] = slot;
            if lane < prims.len() {
                octet.lanes |= 1 << lane;
                octet.leaves |= 1 << leaf_lane;
                octet.leaf_lanes[leaf_lane as usize] |= 1 << lane;
            }
        }
        octet
    }

    /// Bit per lane holding primitive slot `skip` (none for `NONE`): one vector comparison
    /// where `avx2` says the CPU has AVX2 (the lane loop compiles to eight scalar ones).
    #[inline(always)]
    pub fn skipping(&self, skip: u32, avx2: bool) -> u32 {
        // No slot is `NONE`: camera rays skip nothing and need not look.
        if skip == NONE {
            return 0;
        }
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only where the CPU has AVX2.
            return unsafe { self.skipping_avx2(skip) };
        }
        let _ = avx2;
        let mut mask = 0;
        for (lane, &slot) in self.slot.iter().enumerate() {
            mask |= ((slot == skip) as u32) << lane;
        }
        mask
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn skipping_avx2(&self, skip: u32) -> u32 {
        use std::arch::x86_64::*;
        // SAFETY: `slot` is eight u32s.
        let slots = unsafe { _mm256_loadu_si256(self.slot.as_ptr().cast()) };
        let equal = _mm256_cmpeq_epi32(slots, _mm256_set1_epi32(skip as i32));
        _mm256_movemask_ps(_mm256_castsi256_ps(equal)) as u32
    }

    /// The scalar test on the lanes of `lanes` (lanes holding a primitive): a bit per lane hit
    /// before `t_max` (at most `T_FAR`, the distance of a miss), and what `H` keeps of the
    /// hits; in AVX2 where `avx2` says the CPU has it. The lanes of leaves whose boxes the ray
    /// missed may be asked too: a hit there is a true hit, and leaving them out costs more than
    /// it saves.
    #[inline(always)]
    pub fn hits<H: LaneHits>(
        &self,
        ray: &RayQuery,
        t_max: f32,
        lanes: u32,
        avx2: bool,
    ) -> (u32, H) {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only where the CPU has AVX2.
            return unsafe { self.rows.test_avx2(ray, t_max, lanes) };
        }
        let _ = avx2;
        self.hits_scalar(ray, t_max, lanes)
    }

    /// The scalar test lane by lane: what the AVX2 test must equal.
    #[inline(always)]
    fn hits_scalar<H: LaneHits>(&self, ray: &RayQuery, t_max: f32, mut lanes: u32) -> (u32, H) {
        let mut hits = [MISS; LANES];
        let mut mask = 0;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            hits[lane] = self.rows.test(lane, ray, t_max);
            mask |= ((hits[lane].t < t_max) as u32) << lane;
        }
        (mask, H::from_hits(hits))
    }
}

/// Rays a packet tests against one triangle at once, in AVX-512's sixteen lanes.
pub const RAY_LANES: usize = 16;

/// Up to sixteen rays that share the watertight test's axes (`kx`, `ky`, `kz`), stored lane by
/// lane: a packet's rays as [`TriangleOctet::blocked_rays`] tests them against one triangle
/// at a time (Embree's packets' way: a lane per ray), where the octet tests take one ray
/// against eight triangles. Lanes past the rays repeat the first ray, so they stay finite.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct RayLanes {
    /// The origins' coordinates along `kx`, `ky` and `kz`.
    origin: [[f32; RAY_LANES]; 3],
    /// The shear constants (`RayQuery::shear`).
    shear: [[f32; RAY_LANES]; 3],
    /// The rays' `kx`, `ky` and `kz`, shared.
    axes: [usize; 3],
}

impl RayLanes {
    /// The lanes of `rays`, or `None` when there are more than sixteen or their axes differ
    /// (a packet across a diagonal of the directions, where the largest component changes).
    pub fn of(rays: &[RayQuery]) -> Option<RayLanes> {
        let first = rays.first()?;
        let axes = [first.kx, first.ky, first.kz];
        let shared = rays.iter().all(|ray| [ray.kx, ray.ky, ray.kz] == axes);
        if rays.len() > RAY_LANES || !shared {
            return None;
        }
        let mut lanes = RayLanes {
            origin: [[0.0; RAY_LANES]; 3],
            shear: [[0.0; RAY_LANES]; 3],
            axes,
        };
        for lane in 0..RAY_LANES {
            let ray = rays.get(lane).unwrap_or(first);
            for (row, &axis) in axes.iter().enumerate() {
                lanes.origin[row][lane] = ray.origin[axis];
                lanes.shear[row][lane] = ray.shear[row];
            }
        }
        Some(lanes)
    }
}

/// Each ray's nearest hit so far in a packet whose triangles are tested in ray lanes
/// ([`TriangleOctet::nearest_rays`]): distance, surface coordinates and slot, ray by ray.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct NearestLanes {
    /// Distances (the limit of each ray's search: its query's `t_max` before a hit).
    pub t: [f32; RAY_LANES],
    /// Surface coordinates, as `Hit::b1`.
    pub b1: [f32; RAY_LANES],
    /// Surface coordinates, as `Hit::b2`.
    pub b2: [f32; RAY_LANES],
    /// Slots in the wide BVH's primitives (`NONE` before a hit).
    pub slot: [u32; RAY_LANES],
}

impl NearestLanes {
    /// Every ray still looking before `t_max`, with nothing found.
    pub fn before(t_max: f32) -> NearestLanes {
        NearestLanes {
            t: [t_max; RAY_LANES],
            b1: [0.0; RAY_LANES],
            b2: [0.0; RAY_LANES],
            slot: [NONE; RAY_LANES],
        }
    }

    /// Ray `ray`'s nearest hit so far.
    pub fn hit(&self, ray: usize) -> Hit {
        Hit {
            t: self.t[ray],
            b1: self.b1[ray],
            b2: self.b2[ray],
        }
    }
}

impl TriangleOctet {
    /// The rays of `active` (a bit per ray of `rays`) that the triangles of this octet's
    /// leaves in `leaves` (bits of the node's lanes) block before `t_max`, a triangle at a
    /// time against every ray; only the leaves asked are tested.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub unsafe fn blocked_rays(
        &self,
        leaves: u32,
        rays: &RayLanes,
        mut active: u32,
        t_max: f32,
    ) -> u32 {
        let mut asked = self.asked_lanes(leaves);
        let mut blocked = 0;
        while asked != 0 && active != 0 {
            let lane = asked.trailing_zeros() as usize;
            asked &= asked - 1;
            // SAFETY: the CPU has AVX-512F, as this function's caller must check.
            let hit = unsafe { self.rows.blocks_rays(lane, rays, active, t_max) };
            blocked |= hit;
            active &= !hit;
        }
        blocked
    }

    /// Each ray of `active` tests the triangles of this octet's leaves in `leaves` (bits of
    /// the node's lanes), updating `nearest`: the octet tests' rule ray by ray, every lane
    /// tested against the ray's nearest hit as the octet began, the lanes taken in order and
    /// a hit kept where it is nearer than the nearest so far. So each ray finds what its
    /// octet tests find, bit for bit. Returns the rays whose nearest hit changed.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub unsafe fn nearest_rays(
        &self,
        leaves: u32,
        rays: &RayLanes,
        active: u32,
        nearest: &mut NearestLanes,
    ) -> u32 {
        use std::arch::x86_64::*;
        let mut asked = self.asked_lanes(leaves);
        // SAFETY: each row holds sixteen f32s or u32s.
        let (limit, mut b1, mut b2, mut slot) = unsafe {
            (
                _mm512_loadu_ps(nearest.t.as_ptr()),
                _mm512_loadu_ps(nearest.b1.as_ptr()),
                _mm512_loadu_ps(nearest.b2.as_ptr()),
                _mm512_loadu_si512(nearest.slot.as_ptr().cast()),
            )
        };
        let mut t = limit;
        let mut changed = 0u32;
        while asked != 0 {
            let lane = asked.trailing_zeros() as usize;
            asked &= asked - 1;
            // SAFETY: the CPU has AVX-512F, as this function's caller must check.
            let found = unsafe { self.rows.ray_lanes_test::<true>(lane, rays, active, limit) };
            let nearer =
                (found.hit & u32::from(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(found.t, t))) as u16;
            t = _mm512_mask_blend_ps(nearer, t, found.t);
            b1 = _mm512_mask_blend_ps(nearer, b1, found.b1);
            b2 = _mm512_mask_blend_ps(nearer, b2, found.b2);
            let lane_slot = _mm512_set1_epi32(self.slot[lane] as i32);
            slot = _mm512_mask_blend_epi32(nearer, slot, lane_slot);
            changed |= u32::from(nearer);
        }
        // SAFETY: as above.
        unsafe {
            _mm512_storeu_ps(nearest.t.as_mut_ptr(), t);
            _mm512_storeu_ps(nearest.b1.as_mut_ptr(), b1);
            _mm512_storeu_ps(nearest.b2.as_mut_ptr(), b2);
            _mm512_storeu_si512(nearest.slot.as_mut_ptr().cast(), slot);
        }
        changed
    }

    /// The lanes that hold the triangles of this octet's leaves in `leaves` (bits of the
    /// node's lanes).
    fn asked_lanes(&self, leaves: u32) -> u32 {
        let mut asked = 0u32;
        let mut wanted = leaves & self.leaves;
        while wanted != 0 {
            asked |= u32::from(self.leaf_lanes[wanted.trailing_zeros() as usize]);
            wanted &= wanted - 1;
        }
        asked
    }
}

/// Triangles, `v[vertex][axis][lane]`, in the vertex order `pack` stores (lexicographic, which
/// the watertight test needs).
#[derive(Clone, Copy, Debug, Default)]
pub struct TriangleRows {
    v: [[[f32; LANES]; 3]; 3],
}

impl TriangleRows {
    fn vertex(&self, vertex: usize, lane: usize) -> Vec3 {
        let v = &self.v[vertex];
        Vec3::new(v[0][lane], v[1][lane], v[2][lane])
    }
}

impl Rows for TriangleRows {
    fn store(&mut self, lane: usize, prim: &GpuPrimitive) {
        store_rows(&mut self.v, lane, [prim.p0, prim.p1, prim.p2]);
    }

    #[inline(always)]
    fn test(&self, lane: usize, ray: &RayQuery, t_max: f32) -> Hit {
        let [v0, v1, v2] = [0, 1, 2].map(|vertex| self.vertex(vertex, lane));
        intersect_triangle(ray, v0, v1, v2, t_max)
    }

    /// The watertight test on eight lanes in AVX2 intrinsics, each operation the scalar
    /// test's (see `intersect_triangle` and `triangle_t_error`, whose names it keeps).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn test_avx2<H: LaneHits>(&self, ray: &RayQuery, t_max: f32, lanes: u32) -> (u32, H) {
        use std::arch::x86_64::*;
        let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
        let s = ray.shear;
        let (sx, sy, sz) = (
            _mm256_set1_ps(s.x),
            _mm256_set1_ps(s.y),
            _mm256_set1_ps(s.z),
        );
        let load = |row: &[f32; LANES]| {
            // SAFETY: a row is eight f32s.
            unsafe { _mm256_loadu_ps(row.as_ptr()) }
        };
        // The origin as an array: a `Vec3` indexed by a run-time axis is a three-way branch.
        let o = ray.origin.to_array();
        // One vertex translated to the ray origin and sheared: (x, y, scaled z).
        let shear = |vertex: usize| {
            let v = &self.v[vertex];
            let a_kx = _mm256_sub_ps(load(&v[kx]), _mm256_set1_ps(o[kx]));
            let a_ky = _mm256_sub_ps(load(&v[ky]), _mm256_set1_ps(o[ky]));
            let a_kz = _mm256_sub_ps(load(&v[kz]), _mm256_set1_ps(o[kz]));
            (
                _mm256_add_ps(a_kx, _mm256_mul_ps(sx, a_kz)),
                _mm256_add_ps(a_ky, _mm256_mul_ps(sy, a_kz)),
                _mm256_mul_ps(sz, a_kz),
            )
        };
        let (p0x, p0y, z0) = shear(0);
        let (p1x, p1y, z1) = shear(1);
        let (p2x, p2y, z2) = shear(2);
        let cross = |ax, ay, bx, by| _mm256_sub_ps(_mm256_mul_ps(ax, by), _mm256_mul_ps(ay, bx));
        let sign = _mm256_set1_ps(-0.0);
        let e0 = cross(p1x, p1y, p2x, p2y);
        let e1 = _mm256_xor_ps(cross(p0x, p0y, p2x, p2y), sign);
        let e2 = cross(p0x, p0y, p1x, p1y);
        let zero = _mm256_setzero_ps();
        let lt = |a, b| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b);
        let gt = |a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b);
        let or3 = |a, b, c| _mm256_or_ps(_mm256_or_ps(a, b), c);
        let mixed_signs = _mm256_and_ps(
            or3(lt(e0, zero), lt(e1, zero), lt(e2, zero)),
            or3(gt(e0, zero), gt(e1, zero), gt(e2, zero)),
        );
        let det = _mm256_add_ps(_mm256_add_ps(e0, e1), e2);
        let flat = _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero);
        // Most octets a ray tests miss here, in every lane: stop before the division.
        if _mm256_movemask_ps(_mm256_or_ps(mixed_signs, flat)) as u32 & lanes == lanes {
            return (0, H::MISSES);
        }
        let t_scaled = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(e0, z0), _mm256_mul_ps(e1, z1)),
            _mm256_mul_ps(e2, z2),
        );
        let t_max_det = _mm256_mul_ps(_mm256_set1_ps(t_max), det);
        let behind_or_far = _mm256_or_ps(
            _mm256_and_ps(
                lt(det, zero),
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(t_scaled, zero),
                    lt(t_scaled, t_max_det),
                ),
            ),
            _mm256_and_ps(
                gt(det, zero),
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(t_scaled, zero),
                    gt(t_scaled, t_max_det),
                ),
            ),
        );
        let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
        let t = _mm256_mul_ps(t_scaled, inv_det);
        // `triangle_t_error`: `f32::max` and `_mm256_max_ps` differ only on NaN, which no
        // finite lane meets (a NaN lane fails `t < t_max` below either way).
        let abs = |a| _mm256_andnot_ps(sign, a);
        let max3 = |a, b, c| _mm256_max_ps(_mm256_max_ps(abs(a), abs(b)), abs(c));
        let max_x = max3(p0x, p1x, p2x);
        let max_y = max3(p0y, p1y, p2y);
        let max_z = max3(z0, z1, z2);
        let max_e = max3(e0, e1, e2);
        let mul = |a, b| _mm256_mul_ps(a, b);
        let (add, splat) = (|a, b| _mm256_add_ps(a, b), |x| _mm256_set1_ps(x));
        let error = t_error_lanes([max_x, max_y, max_z, max_e], abs(inv_det), mul, add, splat);
        let too_near = _mm256_cmp_ps::<_CMP_LE_OQ>(t, error);
        let missed = or3(mixed_signs, flat, _mm256_or_ps(behind_or_far, too_near));
        let hit = _mm256_andnot_ps(missed, lt(t, _mm256_set1_ps(t_max)));
        let mask = _mm256_movemask_ps(hit) as u32 & lanes;
        // SAFETY: the CPU has AVX2, as this function's caller must check.
        (mask, unsafe {
            H::from_lanes(t, mul(e1, inv_det), mul(e2, inv_det))
        })
    }
}

/// The watertight test of one triangle on sixteen rays (`TriangleRows::ray_lanes_test`): a
/// bit per ray hit before its limit, and each ray's distance and surface coordinates there.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct RayLanesHits {
    hit: u32,
    t: std::arch::x86_64::__m512,
    b1: std::arch::x86_64::__m512,
    b2: std::arch::x86_64::__m512,
}

impl TriangleRows {
    /// The watertight test of the triangle in lane `lane` on sixteen rays at once, each
    /// operation the scalar test's (the AVX2 test's, lanes being rays instead of triangles),
    /// each ray with its own limit in `t_max`: a bit per ray of `active` hit before its limit,
    /// and with `HITS` their distances and surface coordinates (an any-hit query needs none).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn ray_lanes_test<const HITS: bool>(
        &self,
        lane: usize,
        rays: &RayLanes,
        active: u32,
        t_max: std::arch::x86_64::__m512,
    ) -> RayLanesHits {
        use std::arch::x86_64::*;
        let load = |row: &[f32; RAY_LANES]| {
            // SAFETY: a row is sixteen f32s.
            unsafe { _mm512_loadu_ps(row.as_ptr()) }
        };
        let [ox, oy, oz] = rays.origin.each_ref().map(load);
        let [sx, sy, sz] = rays.shear.each_ref().map(load);
        let [kx, ky, kz] = rays.axes;
        let (mul, add, sub) = (_mm512_mul_ps, _mm512_add_ps, _mm512_sub_ps);
        let splat = |x| _mm512_set1_ps(x);
        // One vertex translated to each ray's origin and sheared: (x, y, scaled z).
        let shear = |vertex: usize| {
            let v = &self.v[vertex];
            let a_kx = sub(splat(v[kx][lane]), ox);
            let a_ky = sub(splat(v[ky][lane]), oy);
            let a_kz = sub(splat(v[kz][lane]), oz);
            (
                add(a_kx, mul(sx, a_kz)),
                add(a_ky, mul(sy, a_kz)),
                mul(sz, a_kz),
            )
        };
        let (p0x, p0y, z0) = shear(0);
        let (p1x, p1y, z1) = shear(1);
        let (p2x, p2y, z2) = shear(2);
        let cross = |ax, ay, bx, by| sub(mul(ax, by), mul(ay, bx));
        let e0 = cross(p1x, p1y, p2x, p2y);
        // The sign flipped as an integer: AVX-512F has no float xor.
        let negate = |a| {
            _mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(a),
                _mm512_set1_epi32(i32::MIN),
            ))
        };
        let e1 = negate(cross(p0x, p0y, p2x, p2y));
        let e2 = cross(p0x, p0y, p1x, p1y);
        let zero = _mm512_setzero_ps();
        let lt = |a, b| u32::from(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b));
        let gt = |a, b| u32::from(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b));
        let le = |a, b| u32::from(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b));
        let ge = |a, b| u32::from(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, b));
        let mixed_signs = (lt(e0, zero) | lt(e1, zero) | lt(e2, zero))
            & (gt(e0, zero) | gt(e1, zero) | gt(e2, zero));
        let det = add(add(e0, e1), e2);
        let flat = u32::from(_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(det, zero));
        // Most triangles a packet tests miss every ray here: stop before the division.
        if (mixed_signs | flat) & active == active {
            return RayLanesHits {
                hit: 0,
                t: zero,
                b1: zero,
                b2: zero,
            };
        }
        let t_scaled = add(add(mul(e0, z0), mul(e1, z1)), mul(e2, z2));
        let t_max_det = mul(t_max, det);
        let behind_or_far = (lt(det, zero) & (ge(t_scaled, zero) | lt(t_scaled, t_max_det)))
            | (gt(det, zero) & (le(t_scaled, zero) | gt(t_scaled, t_max_det)));
        let inv_det = _mm512_div_ps(splat(1.0), det);
        let t = mul(t_scaled, inv_det);
        // `triangle_t_error`, as in `test_avx2`.
        let abs = _mm512_abs_ps;
        let max3 = |a, b, c| _mm512_max_ps(_mm512_max_ps(abs(a), abs(b)), abs(c));
        let max_x = max3(p0x, p1x, p2x);
        let max_y = max3(p0y, p1y, p2y);
        let max_z = max3(z0, z1, z2);
        let max_e = max3(e0, e1, e2);
        let (mul, add) = (|a, b| mul(a, b), |a, b| add(a, b));
        let error = t_error_lanes([max_x, max_y, max_z, max_e], abs(inv_det), mul, add, splat);
        let missed = mixed_signs | flat | behind_or_far | le(t, error);
        let hit = lt(t, t_max) & !missed & active;
        match HITS {
            true => RayLanesHits {
                hit,
                t,
                b1: mul(e1, inv_det),
                b2: mul(e2, inv_det),
            },
            false => RayLanesHits {
                hit,
                t,
                b1: zero,
                b2: zero,
            },
        }
    }

    /// The rays of `active` the triangle in lane `lane` blocks before `t_max`
    /// ([`TriangleRows::ray_lanes_test`] with one limit for all).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn blocks_rays(&self, lane: usize, rays: &RayLanes, active: u32, t_max: f32) -> u32 {
        let t_max = std::arch::x86_64::_mm512_set1_ps(t_max);
        // SAFETY: the CPU has AVX-512F, as this function's caller must check.
        unsafe { self.ray_lanes_test::<false>(lane, rays, active, t_max).hit }
    }
}

/// `triangle_t_error` on lanes of any width (`V`: an AVX2 or AVX-512 vector, with its `mul`,
/// `add` and `splat`), each operation the scalar one's: the error bound on a hit's distance
/// from the largest magnitudes of the sheared vertices' x, y and z and of the edge functions,
/// times `|1 / det|`. Inlined into the vector tests, which compile it with their features.
#[inline(always)]
fn t_error_lanes<V: Copy>(
    [max_x, max_y, max_z, max_e]: [V; 4],
    abs_inv_det: V,
    mul: impl Fn(V, V) -> V,
    add: impl Fn(V, V) -> V,
    splat: impl Fn(f32) -> V,
) -> V {
    let delta_x = mul(splat(gamma(5)), add(max_x, max_z));
    let delta_y = mul(splat(gamma(5)), add(max_y, max_z));
    let delta_z = mul(splat(gamma(3)), max_z);
    let delta_e = mul(
        splat(2.0),
        add(
            add(mul(mul(splat(gamma(2)), max_x), max_y), mul(delta_y, max_x)),
            mul(delta_x, max_y),
        ),
    );
    mul(
        mul(
            splat(3.0),
            add(
                add(mul(mul(splat(gamma(3)), max_e), max_z), mul(delta_e, max_z)),
                mul(delta_z, max_e),
            ),
        ),
        abs_inv_det,
    )
}

/// Quads (parallelograms): `corner`, `edge_u`, `edge_v` and their normal `n = edge_u × edge_v`,
/// `rows[vector][axis][lane]`, and n's square length: n and n · n are computed once here, with
/// `intersect_quad`'s operations, so the test finds the very values it would.
#[derive(Clone, Copy, Debug, Default)]
pub struct QuadRows {
    rows: [[[f32; LANES]; 3]; 4],
    nn: [f32; LANES],
}

impl QuadRows {
    fn vector(&self, vector: usize, lane: usize) -> Vec3 {
        let v = &self.rows[vector];
        Vec3::new(v[0][lane], v[1][lane], v[2][lane])
    }
}

impl Rows for QuadRows {
    fn store(&mut self, lane: usize, prim: &GpuPrimitive) {
        let n = Vec3::from(prim.p1).cross(Vec3::from(prim.p2));
        store_rows(&mut self.rows, lane, [prim.p0, prim.p1, prim.p2, n.into()]);
        self.nn[lane] = n.dot(n);
    }

    #[inline(always)]
    fn test(&self, lane: usize, ray: &RayQuery, t_max: f32) -> Hit {
        let [corner, edge_u, edge_v] = [0, 1, 2].map(|vector| self.vector(vector, lane));
        intersect_quad(ray, corner, edge_u, edge_v, t_max)
    }

    /// `intersect_quad` on eight lanes in AVX2 intrinsics, each operation the scalar test's
    /// (glam's `dot` is (x x' + y y') + z z'; its `cross` x = y z' − y' z, and so on).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn test_avx2<H: LaneHits>(&self, ray: &RayQuery, t_max: f32, lanes: u32) -> (u32, H) {
        use std::arch::x86_64::*;
        type V3 = [__m256; 3];
        let load = |row: &[f32; LANES]| {
            // SAFETY: a row is eight f32s.
            unsafe { _mm256_loadu_ps(row.as_ptr()) }
        };
        let vector = |i: usize| -> V3 { std::array::from_fn(|axis| load(&self.rows[i][axis])) };
        let splat3 = |v: Vec3| -> V3 { std::array::from_fn(|axis| _mm256_set1_ps(v[axis])) };
        let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
        let dot = |a: V3, b: V3| add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]));
        let cross = |a: V3, b: V3| -> V3 {
            [
                sub(mul(a[1], b[2]), mul(b[1], a[2])),
                sub(mul(a[2], b[0]), mul(b[2], a[0])),
                sub(mul(a[0], b[1]), mul(b[0], a[1])),
            ]
        };
        let (corner, edge_u, edge_v, n) = (vector(0), vector(1), vector(2), vector(3));
        let (origin, direction) = (splat3(ray.origin), splat3(ray.direction));
        let zero = _mm256_setzero_ps();
        let denom = dot(n, direction);
        let to_corner: V3 = std::array::from_fn(|axis| sub(corner[axis], origin[axis]));
        let t = _mm256_div_ps(dot(to_corner, n), denom);
        let in_range = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(denom, zero),
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(t, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(t_max)),
            ),
        );
        // Most quads a ray tests miss their plane's span here: stop before the rest.
        if _mm256_movemask_ps(in_range) as u32 & lanes == 0 {
            return (0, H::MISSES);
        }
        let q: V3 = std::array::from_fn(|axis| {
            sub(add(origin[axis], mul(t, direction[axis])), corner[axis])
        });
        let nn = load(&self.nn);
        let u = _mm256_div_ps(dot(cross(q, edge_v), n), nn);
        let v = _mm256_div_ps(dot(cross(edge_u, q), n), nn);
        let one = _mm256_set1_ps(1.0);
        let inside = |x| {
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(x, zero),
                _mm256_cmp_ps::<_CMP_LE_OQ>(x, one),
            )
        };
        let hit = _mm256_and_ps(in_range, _mm256_and_ps(inside(u), inside(v)));
        let mask = _mm256_movemask_ps(hit) as u32 & lanes;
        // SAFETY: the CPU has AVX2, as this function's caller must check.
        (mask, unsafe { H::from_lanes(t, u, v) })
    }
}

/// Stores the vectors `points` in lane `lane` of `rows` (`rows[vector][axis][lane]`).
fn store_rows<const N: usize>(
    rows: &mut [[[f32; LANES]; 3]; N],
    lane: usize,
    points: [[f32; 3]; N],
) {
    for (vector, point) in rows.iter_mut().zip(points) {
        for (row, coordinate) in vector.iter_mut().zip(point) {
            row[lane] = coordinate;
        }
    }
}

/// Eight lanes' hits from their t, b1 and b2 vectors.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn hit_lanes(
    t: std::arch::x86_64::__m256,
    b1: std::arch::x86_64::__m256,
    b2: std::arch::x86_64::__m256,
) -> [Hit; LANES] {
    use std::arch::x86_64::_mm256_storeu_ps;
    let mut rows = [[0.0f32; LANES]; 3];
    // SAFETY: each row holds eight f32s.
    unsafe {
        _mm256_storeu_ps(rows[0].as_mut_ptr(), t);
        _mm256_storeu_ps(rows[1].as_mut_ptr(), b1);
        _mm256_storeu_ps(rows[2].as_mut_ptr(), b2);
    }
    std::array::from_fn(|lane| Hit {
        t: rows[0][lane],
        b1: rows[1][lane],
        b2: rows[2][lane],
    })
}

// The AVX2 tests exist only on x86-64: there is nothing to compare elsewhere.
#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::layout::{PRIM_QUAD, PRIM_TRIANGLE, T_FAR};
    use crate::math::rng::Rng;

    fn triangle(v: [Vec3; 3]) -> GpuPrimitive {
        let order = super::super::intersect::lexicographic_order(v);
        GpuPrimitive {
            kind: PRIM_TRIANGLE,
            p0: v[order[0]].into(),
            p1: v[order[1]].into(),
            p2: v[order[2]].into(),
            ..Default::default()
        }
    }

    /// Draws 8,000 octets of `R` (`primitives(point, scale)`: eight primitives, `point` a
    /// uniform point of [-1, 1]^3) of one to eight lanes at scales from 1e-6 to 1e6, and a ray
    /// at each, from 1 to 21 scales away, at the point `aim(rows, lane, round, a, b)` of a lane's
    /// primitive (a, b uniform in [0, 1]); every sixteenth round asks only some lanes (as a
    /// skipped primitive leaves out), and the hit limit is beyond, at and before the aimed
    /// point. Asserts that each lane of the AVX2 test returns the scalar test's hit bit for bit,
    /// and that at least `min_compared` hits were compared.
    fn avx2_equals_scalar<R: Rows>(
        seed: u32,
        mut primitives: impl FnMut(&mut dyn FnMut() -> Vec3, f32) -> Vec<GpuPrimitive>,
        aim: impl Fn(&R, usize, u32, f32, f32) -> Vec3,
        min_compared: usize,
    ) {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: only the scalar octet test runs");
            return;
        }
        let mut rng = Rng::new(seed, 0, 0);
        let mut unit = move || rng.next_f32();
        let mut point = move || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut hits, mut compared) = (0, 0);
        for round in 0..8000u32 {
            let scale = 10f32.powi((round % 13) as i32 - 6);
            let prims = primitives(&mut point, scale);
            let packed: Vec<_> = (0..LANES).map(|i| (i as u32, &prims[i], 0)).collect();
            let octet = Octet::<R>::pack(&packed[..1 + round as usize % LANES]);
            let (a, b) = (0.5 * (point().x + 1.0), 0.5 * (point().y + 1.0));
            let target = aim(&octet.rows, round as usize % LANES, round, a, b);
            let distance = 1.0 + 10.0 * (point().x + 1.0);
            let origin = target + point().normalize_or(Vec3::X) * scale * distance;
            let mut direction = target - origin;
            if round % 17 == 0 {
                direction.x = 0.0;
            }
            let ray = RayQuery::new(origin, direction);
            let t_max = [T_FAR, 2.0, 1.0, 0.5][round as usize / 4 % 4];
            let lanes = octet.lanes & [u32::MAX, 0b1011_0101][round as usize / 16 % 2];
            // SAFETY: the CPU has AVX2 (checked above).
            let (mask, found) = unsafe { octet.rows.test_avx2::<[Hit; LANES]>(&ray, t_max, lanes) };
            let (expected_mask, expected) = octet.hits_scalar::<[Hit; LANES]>(&ray, t_max, lanes);
            assert_eq!(mask, expected_mask, "round {round}: hit lanes");
            // SAFETY: as above.
            let (any_mask, ()) = unsafe { octet.rows.test_avx2::<()>(&ray, t_max, lanes) };
            assert_eq!(
                any_mask, expected_mask,
                "round {round}: hit lanes, mask alone"
            );
            for lane in 0..LANES {
                if expected_mask & (1 << lane) != 0 {
                    compared += 1;
                    let bits = |h: Hit| [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()];
                    assert_eq!(
                        bits(found[lane]),
                        bits(expected[lane]),
                        "round {round} lane {lane}"
                    );
                }
            }
            hits += (mask != 0) as usize;
        }
        // The draws must exercise hits and misses alike.
        assert!(hits > 1500 && hits < 7800, "{hits} rounds with a hit");
        assert!(compared > min_compared, "{compared} hits compared");
    }

    /// Eight triangles near and far, thin, degenerate (a repeated vertex, a line), seen edge
    /// on, with an edge shared by two lanes (rays through it meet both).
    fn triangles(point: &mut dyn FnMut() -> Vec3, scale: f32) -> Vec<GpuPrimitive> {
        let shared = [point() * scale, point() * scale];
        (0..LANES)
            .map(|lane| {
                let mut v = [point() * scale, point() * scale, point() * scale];
                match lane {
                    0 | 1 => (v[0], v[1]) = (shared[0], shared[1]),
                    2 => v[2] = v[1],
                    3 => v[2] = v[0] + (v[1] - v[0]) * 0.5,
                    4 => v[2] = v[0] + (v[1] - v[0]) * 1e-7 + v[2] * 1e-7,
                    _ => {}
                }
                triangle(v)
            })
            .collect()
    }

    /// A point inside lane `lane`'s triangle, on its edge, at its vertex, or just beside it,
    /// by `round`.
    fn aim_at_triangle(rows: &TriangleRows, lane: usize, round: u32, a: f32, b: f32) -> Vec3 {
        let [v0, v1, v2] = [0, 1, 2].map(|vertex| rows.vertex(vertex, lane));
        let (a, b) = match round % 4 {
            0 => (a * (1.0 - b), b),
            1 => (a, 0.0),
            2 => (0.0, 0.0),
            _ => (a * (1.0 - b), b + 1e-6),
        };
        v0 + (v1 - v0) * a + (v2 - v0) * b
    }

    #[test]
    fn the_avx2_triangle_test_equals_the_scalar_test_lane_by_lane() {
        avx2_equals_scalar(5, triangles, aim_at_triangle, 2000);
    }

    /// The AVX-512 test of one triangle against up to sixteen rays (`RayLanes`), on 6,000
    /// octets drawn as in the AVX2 test: rays aimed at points of one lane's triangle from
    /// origins one to twenty-one scales away, apart or shared, some rays not asked, hit limits
    /// beyond, at and before the aimed points. Each ray's bit must be the scalar test's, for
    /// every lane, `blocked_rays` must report the rays some asked leaf blocks, and
    /// `nearest_rays` each ray's nearest hit by the octet tests' rule, bit for bit.
    #[test]
    fn the_avx512_ray_lanes_equal_the_scalar_test_ray_by_ray() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            eprintln!("no AVX-512F on this CPU: packets test their rays against octets");
            return;
        }
        let mut rng = Rng::new(11, 0, 0);
        let mut unit = move || rng.next_f32();
        let mut point = move || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut blocked_rays, mut compared, mut shared_axes) = (0, 0, 0);
        let mut nearest_hits = 0;
        for round in 0..6000u32 {
            let scale = 10f32.powi((round % 13) as i32 - 6);
            let prims = triangles(&mut point, scale);
            // Lane i holds leaf i % 3 of its node: leaves of one to three triangles.
            let packed: Vec<_> = (0..LANES)
                .map(|i| (i as u32, &prims[i], i as u32 % 3))
                .collect();
            let octet = TriangleOctet::pack(&packed[..1 + round as usize % LANES]);
            let aimed = round as usize / 8 % octet.lanes.count_ones() as usize;
            let count = 1 + round as usize % RAY_LANES;
            let origin = aim_at_triangle(&octet.rows, aimed, round, 0.5, 0.25)
                + point().normalize_or(Vec3::X) * scale * (1.0 + 10.0 * (point().x + 1.0));
            let rays: Vec<RayQuery> = (0..count as u32)
                .map(|k| {
                    let (a, b) = (0.5 * (point().x + 1.0), 0.5 * (point().y + 1.0));
                    let target = aim_at_triangle(&octet.rows, aimed, round + k, a, b);
                    let apart = if round % 3 == 0 {
                        Vec3::ZERO
                    } else {
                        point() * scale * 0.05
                    };
                    RayQuery::new(origin + apart, target - origin - apart)
                })
                .collect();
            let Some(lanes) = RayLanes::of(&rays) else {
                continue;
            };
            shared_axes += 1;
            let t_max = [T_FAR, 2.0, 1.0, 0.5][round as usize / 4 % 4];
            let all = (1u32 << count) - 1;
            let active = all & [u32::MAX, 0b1011_0101_1100_1110][round as usize / 16 % 2];
            let mut expected_blocked = 0;
            for lane in 0..LANES {
                if octet.lanes & (1 << lane) == 0 {
                    continue;
                }
                let expected = rays.iter().enumerate().fold(0, |bits, (k, ray)| {
                    let hit = octet.rows.test(lane, ray, t_max).t < t_max;
                    bits | (((active >> k) & 1 == 1 && hit) as u32) << k
                });
                // SAFETY: the CPU has AVX-512F (checked above).
                let found = unsafe { octet.rows.blocks_rays(lane, &lanes, active, t_max) };
                assert_eq!(found, expected, "round {round} lane {lane}");
                compared += count;
                if octet.leaf_lanes[1] & (1 << lane) != 0 {
                    expected_blocked |= expected;
                }
            }
            // SAFETY: as above.
            let blocked = unsafe { octet.blocked_rays(0b10, &lanes, active, t_max) };
            assert_eq!(blocked, expected_blocked, "round {round}: leaf 1");
            blocked_rays += blocked.count_ones();
            // The nearest hits in leaves 0 and 1, each ray with its own limit: the octet
            // tests' rule (every lane against the limit, nearer hits kept in lane order).
            let mut nearest = NearestLanes::before(T_FAR);
            for k in 0..count {
                nearest.t[k] = [T_FAR, 2.0, 1.0, 0.5][(round as usize + k) % 4];
            }
            let limits = nearest.t;
            // SAFETY: as above.
            let changed = unsafe { octet.nearest_rays(0b11, &lanes, active, &mut nearest) };
            for (k, ray) in rays.iter().enumerate() {
                let (mut best, mut slot) = (MISS, NONE);
                best.t = limits[k];
                for lane in 0..LANES {
                    let asked = octet.leaf_lanes[0] | octet.leaf_lanes[1];
                    let hit = octet.rows.test(lane, ray, limits[k]);
                    if (active >> k) & 1 == 1
                        && asked & (1 << lane) != 0
                        && hit.t < limits[k]
                        && hit.t < best.t
                    {
                        (best, slot) = (hit, octet.slot[lane]);
                    }
                }
                let bits = |h: Hit| [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()];
                assert_eq!(bits(nearest.hit(k)), bits(best), "round {round}: ray {k}");
                assert_eq!(nearest.slot[k], slot, "round {round}: ray {k}");
                assert_eq!(
                    (changed >> k) & 1 == 1,
                    slot != NONE,
                    "round {round}: ray {k}"
                );
                nearest_hits += (slot != NONE) as u32;
            }
        }
        // Most rounds' rays share their axes (some aim across a diagonal), and the draws
        // must exercise hits and misses alike.
        assert!(shared_axes > 4500, "{shared_axes} rounds with shared axes");
        assert!(compared > 150_000, "{compared} rays compared");
        assert!(
            blocked_rays > 2000 && blocked_rays < 30_000,
            "{blocked_rays} rays blocked by leaf 1"
        );
        assert!(
            nearest_hits > 4000 && nearest_hits < 60_000,
            "{nearest_hits} nearest hits in leaves 0 and 1"
        );
    }

    /// Quads, flat ones too (parallel edges, a zero edge, nearly parallel); rays aimed inside
    /// a lane's quad, on its far edge, at its corner, and just beside it.
    #[test]
    fn the_avx2_quad_test_equals_the_scalar_test_lane_by_lane() {
        let primitives = |point: &mut dyn FnMut() -> Vec3, scale: f32| {
            (0..LANES)
                .map(|lane| {
                    let (corner, mut edge_u, mut edge_v) =
                        (point() * scale, point() * scale, point() * scale);
                    match lane {
                        2 => edge_v = edge_u * 0.5,
                        3 => edge_u = Vec3::ZERO,
                        4 => edge_v = edge_u * 1e-7 + edge_v * 1e-7,
                        _ => {}
                    }
                    GpuPrimitive {
                        kind: PRIM_QUAD,
                        p0: corner.into(),
                        p1: edge_u.into(),
                        p2: edge_v.into(),
                        ..Default::default()
                    }
                })
                .collect()
        };
        let aim = |rows: &QuadRows, lane: usize, round: u32, a: f32, b: f32| {
            let [corner, edge_u, edge_v] = [0, 1, 2].map(|vector| rows.vector(vector, lane));
            let (a, b) = match round % 4 {
                0 => (a, b),
                1 => (a, 1.0),
                2 => (0.0, 0.0),
                _ => (a, b * 1e-6 - 1e-7),
            };
            corner + edge_u * a + edge_v * b
        };
        avx2_equals_scalar(7, primitives, aim, 1500);
    }
}
