//! A ray as the intersection tests take it, and what they return: the per-ray constants of the
//! watertight triangle test and the slab test ([`RayQuery`]), a hit ([`Hit`]), a shading point
//! with its error bound ([`SurfacePoint`]), and the rounding-error bound [`gamma`] every test
//! uses; rays in bulk ([`RaySet`]) and what is asked of them ([`Query`]), as the ray benchmark
//! traces them on either path. The tests themselves are in `intersect` (flat primitives) and
//! `curved`.
//! Twin: `wgsl/intersect.wgsl` (its `Ray`, `Hit` and `gamma`).

use glam::{Vec3, Vec3A};
use serde::Serialize;

use crate::layout::T_FAR;
use crate::named::named_enum;

/// Smallest direction magnitude used for the slab reciprocals: with coordinates below 1e9
/// (validated), products stay far below f32::MAX.
const MIN_DIRECTION: f32 = 1.0e-20;
/// pbrt-v4's 1 + 2*gamma(3), widened 2x for WGSL's 2.5-ULP division.
pub const SLAB_FAR_SCALE: f32 = 1.0 + 4.0 * 3.0 * f32::EPSILON * 0.5;

/// Per-ray constants of the watertight triangle test and the slab test.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayQuery {
    /// Ray origin (scene units).
    pub origin: Vec3,
    /// Ray direction; hit distances `t` are multiples of its length.
    pub direction: Vec3,
    /// Per-component reciprocals of `direction`, kept finite (at most 1e20 in magnitude).
    pub inv_direction: Vec3,
    /// The watertight test's first sheared axis: the one after `kz` (swapped with `ky` when the
    /// direction's `kz` component is negative, to keep the winding).
    pub kx: usize,
    /// The watertight test's second sheared axis.
    pub ky: usize,
    /// The axis of the direction's largest component.
    pub kz: usize,
    /// Shear constants (-d_kx / d_kz, -d_ky / d_kz, 1 / d_kz) that make the direction +z.
    pub shear: Vec3,
    /// The time (seconds) the ray is traced at: moving primitives are where they are then.
    pub time: f32,
}

/// 1 / d per component, a component below `MIN_DIRECTION` in magnitude taken as
/// ±`MIN_DIRECTION` (+ for a zero of either sign), so the slab test never meets an infinity;
/// one vector division. Twin: `safe_reciprocal` in wgsl/intersect.wgsl, per component.
fn safe_reciprocals(d: Vec3) -> Vec3 {
    let d = Vec3A::from(d);
    let least = Vec3A::select(
        d.cmplt(Vec3A::ZERO),
        Vec3A::splat(-MIN_DIRECTION),
        Vec3A::splat(MIN_DIRECTION),
    );
    let safe = Vec3A::select(d.abs().cmplt(Vec3A::splat(MIN_DIRECTION)), least, d);
    (Vec3A::ONE / safe).into()
}

impl RayQuery {
    /// The per-ray constants of the ray from `origin` along `direction`.
    // Without branches: a bounce's or a shadow ray's largest axis and sign are a coin toss
    // for a branch predictor, and a miss cost about as much as the rest of the set-up.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        let abs = direction.abs();
        let x_over_y = abs.x > abs.y;
        let x_largest = x_over_y && abs.x > abs.z;
        let y_largest = !x_over_y && abs.y > abs.z;
        // x -> 0, y -> 1, else z -> 2: ties go to the later axis, as nested comparisons do.
        let kz = 2 - 2 * x_largest as usize - y_largest as usize;
        let d = direction.to_array();
        let dz = d[kz];
        let after = [1, 2, 0];
        let (next, last) = (after[kz], after[after[kz]]);
        // A negative kz component swaps kx and ky, to keep the winding.
        let (kx, ky) = match dz < 0.0 {
            true => (last, next),
            false => (next, last),
        };
        // Each as one vector division: the same correctly rounded quotients as one by one.
        let shear = Vec3A::new(-d[kx], -d[ky], 1.0) / Vec3A::splat(dz);
        RayQuery {
            origin,
            direction,
            inv_direction: safe_reciprocals(direction),
            kx,
            ky,
            kz,
            shear: shear.into(),
            time: 0.0,
        }
    }

    /// The ray traced at `time`.
    pub fn at_time(self, time: f32) -> Self {
        RayQuery { time, ..self }
    }

    /// The ray in the frame of a primitive that has moved by `offset`: its origin moved by
    /// `-offset`, so testing the primitive where it was built tests it where it is.
    pub fn relative_to(&self, offset: Vec3) -> Self {
        RayQuery {
            origin: self.origin - offset,
            ..*self
        }
    }

    /// The same ray as obvhs expects it, with our finite reciprocals.
    pub fn to_obvhs(&self, t_max: f32) -> obvhs::ray::Ray {
        obvhs::ray::Ray {
            origin: Vec3A::from(self.origin),
            direction: Vec3A::from(self.direction),
            inv_direction: Vec3A::from(self.inv_direction),
            tmin: 0.0,
            tmax: t_max,
        }
    }
}

/// A hit: distance and, for triangles and quads, surface coordinates (b1, b2). For spheres,
/// `b1` is instead a bound on the relative error of `t` (see `intersect_sphere`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of its direction's length; `T_FAR` for a miss.
    pub t: f32,
    /// Triangle: barycentric of the second vertex; quad: position along `edge_u` in [0, 1]; sphere:
    /// relative error bound of `t`.
    pub b1: f32,
    /// Triangle: barycentric of the third vertex; quad: position along `edge_v` in [0, 1].
    pub b2: f32,
}

pub(crate) const MISS: Hit = Hit {
    t: T_FAR,
    b1: 0.0,
    b2: 0.0,
};

/// Rounding-error bound for `n` operations in arithmetic whose rounding direction is
/// unspecified (WGSL): pbrt-v4's gamma(n) with a whole ULP per operation, not half. The CPU path
/// uses the same bounds so both paths offset rays identically.
pub const fn gamma(n: u32) -> f32 {
    let n_eps = n as f32 * f32::EPSILON;
    n_eps / (1.0 - n_eps)
}

/// A shading point and the per-component bound on its distance from the true surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The computed point (scene units).
    pub position: Vec3,
    /// Per-component bound on `position`'s distance from the exact point.
    pub error: Vec3,
}

/// Rays as structure of arrays.
#[derive(Clone, Debug, Default)]
pub struct RaySet {
    /// Ray origins (scene units).
    pub origins: Vec<Vec3>,
    /// Unit ray directions, one per origin.
    pub directions: Vec<Vec3>,
    /// The camera's rays: each frame's rays are its pixels, in rows of this width (0: the
    /// rays are no image's).
    pub image_width: u32,
}

impl RaySet {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.origins.len()
    }

    /// Whether there are no rays.
    pub fn is_empty(&self) -> bool {
        self.origins.is_empty()
    }
}

named_enum! {
    /// Closest hit or any hit.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "snake_case")]
    pub enum Query {
        /// The nearest hit along each ray, with its distance.
        ClosestHit = "closest",
        /// Whether anything lies along each ray (shadow rays).
        AnyHit = "any",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule of `safe_reciprocal` in wgsl/intersect.wgsl, one component at a time.
    fn safe_reciprocal(d: f32) -> f32 {
        if (0.0..MIN_DIRECTION).contains(&d) {
            1.0 / MIN_DIRECTION
        } else if d < 0.0 && d > -MIN_DIRECTION {
            -1.0 / MIN_DIRECTION
        } else {
            1.0 / d
        }
    }

    /// The vector reciprocals are the WGSL rule's, bit for bit, at the extremes too: zeros of
    /// both signs, the smallest subnormal, values either side of `MIN_DIRECTION`, the largest
    /// floats, infinities and NaN.
    #[test]
    fn safe_reciprocals_follow_the_kernels_rule() {
        let mut values = vec![
            0.0,
            f32::from_bits(1),
            1e-30,
            MIN_DIRECTION,
            f32::from_bits(MIN_DIRECTION.to_bits() - 1),
            f32::from_bits(MIN_DIRECTION.to_bits() + 1),
            1e-7,
            0.5,
            1.0,
            3.0,
            f32::MAX,
            f32::INFINITY,
        ];
        values.extend(values.clone().iter().map(|v| -v));
        values.push(f32::NAN);
        for &x in &values {
            for &y in &values {
                let d = Vec3::new(x, y, 1.0);
                let got = safe_reciprocals(d);
                for axis in 0..3 {
                    let want = safe_reciprocal(d[axis]);
                    assert!(
                        got[axis].to_bits() == want.to_bits()
                            || (got[axis].is_nan() && want.is_nan()),
                        "1/{} gave {}, the rule {want}",
                        d[axis],
                        got[axis]
                    );
                }
            }
        }
    }

    /// The branchless choice of the watertight test's axes is the nested comparisons' (as
    /// `wgsl/intersect.wgsl` makes it), for every ordering of the components' magnitudes, ties,
    /// zeros of both signs and both signs of the largest.
    #[test]
    fn the_sheared_axes_are_the_nested_comparisons() {
        let nested = |d: Vec3| {
            let abs = d.abs();
            let kz = if abs.x > abs.y {
                if abs.x > abs.z { 0 } else { 2 }
            } else if abs.y > abs.z {
                1
            } else {
                2
            };
            let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
            if d[kz] < 0.0 {
                std::mem::swap(&mut kx, &mut ky);
            }
            (kx, ky, kz)
        };
        let values = [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.0, -2.0, 1e-30, -1e30];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let d = Vec3::new(x, y, z);
                    let ray = RayQuery::new(Vec3::ZERO, d);
                    assert_eq!((ray.kx, ray.ky, ray.kz), nested(d), "{d}");
                }
            }
        }
    }
}
