//! Eight primitives against one ray at once: the watertight test of
//! `intersect::intersect_triangle` on a `TriangleOctet`, `intersect::intersect_quad` on a
//! `QuadOctet`, the primitives stored lane by lane, in AVX2 where the CPU has it. The CPU's wide
//! BVH (`wide`) packs the static triangles, and the static quads, of each node's leaves into
//! octets and tests them when the node's test finds one of those leaves hit, instead of pushing
//! each leaf and testing its one to three primitives one by one.
//!
//! The AVX2 tests perform the scalar tests' operations in the scalar tests' order, lane by lane
//! (no fused multiply-add: neither is compiled with FMA), so each lane's result is the scalar
//! test's, bit for bit; `tests` checks it on random rays and primitives, edges and extremes
//! included. No GPU twin: the GPU tests a leaf's primitives one by one (its lanes are rays).

use glam::Vec3;

use super::intersect::{Hit, RayQuery, gamma, intersect_quad, intersect_triangle};
use crate::layout::GpuPrimitive;

/// Lanes of an octet.
pub const LANES: usize = 8;

/// Up to eight triangles, `v[vertex][axis][lane]`, in the vertex order `pack` stores
/// (lexicographic, which the watertight test needs), and which primitives they are.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub struct TriangleOctet {
    v: [[[f32; LANES]; 3]; 3],
    /// Per lane: the triangle's slot in the wide BVH's primitives.
    pub slot: [u32; LANES],
    /// Bit per lane: the lane holds a triangle (empty lanes repeat lane 0's, so they stay
    /// finite, and are masked out).
    pub lanes: u32,
    /// Bit per lane of the node whose leaves the triangles come from: the leaves in this octet.
    pub leaves: u32,
}

impl TriangleOctet {
    /// The octet of `triangles` (at most eight: (slot, primitive, the node lane of its leaf)).
    pub fn pack(triangles: &[(u32, &GpuPrimitive, u32)]) -> TriangleOctet {
        assert!(!triangles.is_empty() && triangles.len() <= LANES);
        let mut octet = TriangleOctet::default();
        for lane in 0..LANES {
            let (slot, prim, leaf_lane) = triangles[if lane < triangles.len() { lane } else { 0 }];
            for (vertex, p) in [prim.p0, prim.p1, prim.p2].iter().enumerate() {
                for (row, &coordinate) in octet.v[vertex].iter_mut().zip(p) {
                    row[lane] = coordinate;
                }
            }
            octet.slot[lane] = slot;
            if lane < triangles.len() {
                octet.lanes |= 1 << lane;
                octet.leaves |= 1 << leaf_lane;
            }
        }
        octet
    }

    /// Bit per lane holding primitive slot `skip` (none for `NONE`).
    #[inline(always)]
    pub fn skipping(&self, skip: u32) -> u32 {
        lanes_holding(&self.slot, skip)
    }

    fn vertex(&self, vertex: usize, lane: usize) -> Vec3 {
        let v = &self.v[vertex];
        Vec3::new(v[0][lane], v[1][lane], v[2][lane])
    }

    /// `intersect_triangle` on the lanes of `lanes` (a subset of `self.lanes`): a bit per lane
    /// hit before `t_max` (at most `T_FAR`, the distance of a miss), and the hits. The lanes
    /// of leaves whose boxes the ray missed may be asked too: a hit there is a true hit, and
    /// leaving them out costs more than it saves.
    #[inline(always)]
    pub fn hits(&self, ray: &RayQuery, t_max: f32, lanes: u32, avx2: bool) -> (u32, [Hit; LANES]) {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only where the CPU has AVX2.
            return unsafe { self.hits_avx2(ray, t_max, lanes) };
        }
        let _ = avx2;
        self.hits_scalar(ray, t_max, lanes)
    }

    /// The scalar test lane by lane: what the AVX2 test must equal.
    #[inline(always)]
    fn hits_scalar(&self, ray: &RayQuery, t_max: f32, mut lanes: u32) -> (u32, [Hit; LANES]) {
        let mut hits = [super::intersect::MISS; LANES];
        let mut mask = 0;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let [v0, v1, v2] = [0, 1, 2].map(|vertex| self.vertex(vertex, lane));
            hits[lane] = intersect_triangle(ray, v0, v1, v2, t_max);
            mask |= ((hits[lane].t < t_max) as u32) << lane;
        }
        (mask, hits)
    }

    /// The watertight test on eight lanes in AVX2 intrinsics, each operation the scalar
    /// test's (see `intersect_triangle` and `triangle_t_error`, whose names it keeps).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn hits_avx2(&self, ray: &RayQuery, t_max: f32, lanes: u32) -> (u32, [Hit; LANES]) {
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
        // One vertex translated to the ray origin and sheared: (x, y, scaled z).
        let shear = |vertex: usize| {
            let o = ray.origin;
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
            return (0, [super::intersect::MISS; LANES]);
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
        let add = |a, b| _mm256_add_ps(a, b);
        let splat = |x| _mm256_set1_ps(x);
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
        let error = mul(
            mul(
                splat(3.0),
                add(
                    add(mul(mul(splat(gamma(3)), max_e), max_z), mul(delta_e, max_z)),
                    mul(delta_z, max_e),
                ),
            ),
            abs(inv_det),
        );
        let too_near = _mm256_cmp_ps::<_CMP_LE_OQ>(t, error);
        let missed = or3(mixed_signs, flat, _mm256_or_ps(behind_or_far, too_near));
        let hit = _mm256_andnot_ps(missed, lt(t, _mm256_set1_ps(t_max)));
        let mask = _mm256_movemask_ps(hit) as u32 & lanes;
        let mut lanes = [[0.0f32; LANES]; 3];
        // SAFETY: each row holds eight f32s.
        unsafe {
            _mm256_storeu_ps(lanes[0].as_mut_ptr(), t);
            _mm256_storeu_ps(lanes[1].as_mut_ptr(), mul(e1, inv_det));
            _mm256_storeu_ps(lanes[2].as_mut_ptr(), mul(e2, inv_det));
        }
        let hits = std::array::from_fn(|lane| Hit {
            t: lanes[0][lane],
            b1: lanes[1][lane],
            b2: lanes[2][lane],
        });
        (mask, hits)
    }
}

/// Up to eight quads (parallelograms), `corner`, `edge_u`, `edge_v` and their normal
/// `n = edge_u × edge_v` with its square length lane by lane: n and n · n are computed once
/// here, with `intersect_quad`'s operations, so the test finds the very values it would.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub struct QuadOctet {
    /// corner, edge_u, edge_v, n: `rows[vector][axis][lane]`.
    rows: [[[f32; LANES]; 3]; 4],
    /// n · n per lane.
    nn: [f32; LANES],
    /// Per lane: the quad's slot in the wide BVH's primitives.
    pub slot: [u32; LANES],
    /// Bit per lane: the lane holds a quad (empty lanes repeat lane 0's).
    pub lanes: u32,
    /// Bit per lane of the node whose leaves the quads come from: the leaves in this octet.
    pub leaves: u32,
}

impl QuadOctet {
    /// The octet of `quads` (at most eight: (slot, primitive, the node lane of its leaf)).
    pub fn pack(quads: &[(u32, &GpuPrimitive, u32)]) -> QuadOctet {
        assert!(!quads.is_empty() && quads.len() <= LANES);
        let mut octet = QuadOctet::default();
        for lane in 0..LANES {
            let (slot, prim, leaf_lane) = quads[if lane < quads.len() { lane } else { 0 }];
            let (edge_u, edge_v) = (Vec3::from(prim.p1), Vec3::from(prim.p2));
            let n = edge_u.cross(edge_v);
            for (vector, p) in [prim.p0, prim.p1, prim.p2, n.into()].iter().enumerate() {
                for (row, &coordinate) in octet.rows[vector].iter_mut().zip(p) {
                    row[lane] = coordinate;
                }
            }
            octet.nn[lane] = n.dot(n);
            octet.slot[lane] = slot;
            if lane < quads.len() {
                octet.lanes |= 1 << lane;
                octet.leaves |= 1 << leaf_lane;
            }
        }
        octet
    }

    /// Bit per lane holding primitive slot `skip` (none for `NONE`).
    #[inline(always)]
    pub fn skipping(&self, skip: u32) -> u32 {
        lanes_holding(&self.slot, skip)
    }

    fn vector(&self, vector: usize, lane: usize) -> Vec3 {
        let v = &self.rows[vector];
        Vec3::new(v[0][lane], v[1][lane], v[2][lane])
    }

    /// `intersect_quad` on the lanes of `lanes`, as [`TriangleOctet::hits`].
    #[inline(always)]
    pub fn hits(&self, ray: &RayQuery, t_max: f32, lanes: u32, avx2: bool) -> (u32, [Hit; LANES]) {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only where the CPU has AVX2.
            return unsafe { self.hits_avx2(ray, t_max, lanes) };
        }
        let _ = avx2;
        self.hits_scalar(ray, t_max, lanes)
    }

    /// The scalar test lane by lane: what the AVX2 test must equal.
    #[inline(always)]
    fn hits_scalar(&self, ray: &RayQuery, t_max: f32, mut lanes: u32) -> (u32, [Hit; LANES]) {
        let mut hits = [super::intersect::MISS; LANES];
        let mut mask = 0;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let [corner, edge_u, edge_v] = [0, 1, 2].map(|vector| self.vector(vector, lane));
            hits[lane] = intersect_quad(ray, corner, edge_u, edge_v, t_max);
            mask |= ((hits[lane].t < t_max) as u32) << lane;
        }
        (mask, hits)
    }

    /// `intersect_quad` on eight lanes in AVX2 intrinsics, each operation the scalar test's
    /// (glam's `dot` is (x x' + y y') + z z'; its `cross` x = y z' − y' z, and so on).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn hits_avx2(&self, ray: &RayQuery, t_max: f32, lanes: u32) -> (u32, [Hit; LANES]) {
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
            return (0, [super::intersect::MISS; LANES]);
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
        let mut rows = [[0.0f32; LANES]; 3];
        // SAFETY: each row holds eight f32s.
        unsafe {
            _mm256_storeu_ps(rows[0].as_mut_ptr(), t);
            _mm256_storeu_ps(rows[1].as_mut_ptr(), u);
            _mm256_storeu_ps(rows[2].as_mut_ptr(), v);
        }
        let hits = std::array::from_fn(|lane| Hit {
            t: rows[0][lane],
            b1: rows[1][lane],
            b2: rows[2][lane],
        });
        (mask, hits)
    }
}

/// Bit per lane whose slot is `skip`.
#[inline(always)]
fn lanes_holding(slot: &[u32; LANES], skip: u32) -> u32 {
    let mut mask = 0;
    for (lane, &s) in slot.iter().enumerate() {
        mask |= ((s == skip) as u32) << lane;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{PRIM_TRIANGLE, T_FAR};
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

    /// Each lane of the AVX2 test returns the scalar test's hit, bit for bit, on random rays
    /// through random triangles: near and far, thin, degenerate (a repeated vertex, a line),
    /// seen edge on, with vertices shared by neighbouring lanes (rays through common edges),
    /// at scales from 1e-6 to 1e6, with the hit limit before, at and after the hits.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_octet_equals_the_scalar_test_lane_by_lane() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: only the scalar octet test runs");
            return;
        }
        let mut rng = Rng::new(5, 0, 0);
        let mut unit = move || rng.next_f32();
        let mut point = move || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut hits, mut compared) = (0, 0);
        for round in 0..8000 {
            let scale = 10f32.powi((round % 13) - 6);
            let shared = [point() * scale, point() * scale];
            let prims: Vec<GpuPrimitive> = (0..LANES)
                .map(|lane| {
                    let mut v = [point() * scale, point() * scale, point() * scale];
                    match lane {
                        // Fans around one edge: rays near it meet two triangles.
                        0 | 1 => (v[0], v[1]) = (shared[0], shared[1]),
                        2 => v[2] = v[1],
                        3 => v[2] = v[0] + (v[1] - v[0]) * 0.5,
                        4 => v[2] = v[0] + (v[1] - v[0]) * 1e-7 + v[2] * 1e-7,
                        _ => {}
                    }
                    triangle(v)
                })
                .collect();
            let packed: Vec<_> = prims
                .iter()
                .enumerate()
                .map(|(i, p)| (i as u32, p, 0))
                .collect();
            let octet = TriangleOctet::pack(&packed[..1 + round as usize % LANES]);
            // Aim inside a lane's triangle, on its edge, at its vertex, or just beside it.
            let lane = round as usize % LANES;
            let [v0, v1, v2] = [0, 1, 2].map(|vertex| octet.vertex(vertex, lane));
            let (a, b) = (0.5 * (point().x + 1.0), 0.5 * (point().y + 1.0));
            let (a, b) = match round % 4 {
                0 => (a * (1.0 - b), b),
                1 => (a, 0.0),
                2 => (0.0, 0.0),
                _ => (a * (1.0 - b), b + 1e-6),
            };
            let target = v0 + (v1 - v0) * a + (v2 - v0) * b;
            let distance = 1.0 + 10.0 * (point().x + 1.0);
            let origin = target + point().normalize_or(Vec3::X) * scale * distance;
            let mut direction = target - origin;
            if round % 17 == 0 {
                direction.x = 0.0;
            }
            let ray = RayQuery::new(origin, direction);
            let t_max = [T_FAR, 2.0, 1.0, 0.5][round as usize / 4 % 4];
            // SAFETY: the CPU has AVX2 (checked above).
            // Every lane, or some (as a skipped primitive leaves out).
            let lanes = octet.lanes & [u32::MAX, 0b1011_0101][round as usize / 16 % 2];
            let (mask, found) = unsafe { octet.hits_avx2(&ray, t_max, lanes) };
            let (expected_mask, expected) = octet.hits_scalar(&ray, t_max, lanes);
            assert_eq!(mask, expected_mask, "round {round}: hit lanes");
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
        assert!(compared > 2000, "{compared} hits compared");
    }

    /// As above for quads: each lane of the AVX2 test returns `intersect_quad`'s hit, bit for
    /// bit, on rays aimed inside random quads, on their edges and corners and just beside
    /// them, for flat quads (parallel edges, a zero edge) too, at scales from 1e-6 to 1e6.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_quad_octet_equals_the_scalar_test_lane_by_lane() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: only the scalar octet test runs");
            return;
        }
        let mut rng = Rng::new(7, 0, 0);
        let mut unit = move || rng.next_f32();
        let mut point = move || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut hits, mut compared) = (0, 0);
        for round in 0..8000 {
            let scale = 10f32.powi((round % 13) - 6);
            let prims: Vec<GpuPrimitive> = (0..LANES)
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
                        kind: crate::layout::PRIM_QUAD,
                        p0: corner.into(),
                        p1: edge_u.into(),
                        p2: edge_v.into(),
                        ..Default::default()
                    }
                })
                .collect();
            let packed: Vec<_> = prims
                .iter()
                .enumerate()
                .map(|(i, p)| (i as u32, p, 0))
                .collect();
            let octet = QuadOctet::pack(&packed[..1 + round as usize % LANES]);
            let lane = round as usize % LANES;
            let [corner, edge_u, edge_v] = [0, 1, 2].map(|vector| octet.vector(vector, lane));
            let (a, b) = (0.5 * (point().x + 1.0), 0.5 * (point().y + 1.0));
            let (a, b) = match round % 4 {
                0 => (a, b),
                1 => (a, 1.0),
                2 => (0.0, 0.0),
                _ => (a, b * 1e-6 - 1e-7),
            };
            let target = corner + edge_u * a + edge_v * b;
            let distance = 1.0 + 10.0 * (point().x + 1.0);
            let origin = target + point().normalize_or(Vec3::X) * scale * distance;
            let ray = RayQuery::new(origin, target - origin);
            let t_max = [T_FAR, 2.0, 1.0, 0.5][round as usize / 4 % 4];
            let lanes = octet.lanes & [u32::MAX, 0b1011_0101][round as usize / 16 % 2];
            // SAFETY: the CPU has AVX2 (checked above).
            let (mask, found) = unsafe { octet.hits_avx2(&ray, t_max, lanes) };
            let (expected_mask, expected) = octet.hits_scalar(&ray, t_max, lanes);
            assert_eq!(mask, expected_mask, "round {round}: hit lanes");
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
        assert!(hits > 1500 && hits < 7800, "{hits} rounds with a hit");
        assert!(compared > 1500, "{compared} hits compared");
    }
}
