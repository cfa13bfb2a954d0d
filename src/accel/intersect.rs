//! Ray/primitive intersection, written for robustness rather than taken from obvhs.
//! Twin: `wgsl/intersect.wgsl`.
//!
//! - Triangles: the watertight test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//!   Intersection", JCGT 2(1), 2013 (as in pbrt-v4), with each edge function evaluated in a
//!   canonical vertex order so that two triangles sharing an edge compute the very same value
//!   even where a compiler fuses multiply-adds. <https://jcgt.org/published/0002/01/05/>
//!   Hits no farther than pbrt-v4's bound on t's error are rejected (they may lie behind the
//!   origin).
//! - Spheres: the cancellation-free quadratic of Haines et al., "Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7, with the constant term |o - c|^2 - r^2
//!   taken from whichever of two forms loses less to cancellation (see `intersect_sphere`), and
//!   a bound on the relative error of t carried to the shading point.
//! - Boxes: slab test with reciprocals kept finite for zero direction components and a widened
//!   far distance (pbrt-v4's 1 + 2*gamma(3)), so rounding never culls a box the ray touches.
//! - Secondary-ray origins: pbrt-v4's `OffsetRayOrigin` (Pharr, Jakob and Humphreys, Physically
//!   Based Rendering 4th ed., section 6.8.6): each shading point carries a per-component bound on
//!   its own rounding error, and the new ray starts that far off the surface along the normal,
//!   rounded away from it. The offset scales with the error actually made, so it holds at any
//!   scene scale and for spheres whose radius dwarfs the scene around them.

use glam::Vec3;

pub(crate) use super::ray::MISS;
pub use super::ray::{Hit, RayQuery, SLAB_FAR_SCALE, SurfacePoint, gamma};

use super::curved::{
    intersect_cylinder, intersect_ellipsoid, intersect_torus, orientation, ray_in_frame,
};
use crate::layout::{
    FEATURE_CURVED, FEATURE_TRIANGLES, GpuPrimitive, PRIM_CYLINDER, PRIM_ELLIPSOID, PRIM_PLANE,
    PRIM_QUAD, PRIM_SPHERE, PRIM_TORUS, PRIM_TRIANGLE, T_FAR, has,
};

/// The order of a triangle's vertices that `intersect_triangle` needs for watertightness:
/// lexicographic in (x, y, z). Stored so (by `pack`), every edge's function is evaluated from
/// its smaller vertex in both triangles that share it, with the same rounding, and the test
/// needs no comparison per ray.
pub fn lexicographic_order(v: [Vec3; 3]) -> [usize; 3] {
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| {
        let (p, q) = (v[i], v[j]);
        p.x.total_cmp(&q.x)
            .then(p.y.total_cmp(&q.y))
            .then(p.z.total_cmp(&q.z))
    });
    order
}

/// The watertight test of Woop, Benthin and Wald, for vertices in `lexicographic_order`
/// (any order gives a correct test; that order makes shared edges watertight).
pub fn intersect_triangle(ray: &RayQuery, v0: Vec3, v1: Vec3, v2: Vec3, t_max: f32) -> Hit {
    // Translate to the ray origin, permute so z is the dominant axis, shear onto +z.
    let a = v0 - ray.origin;
    let b = v1 - ray.origin;
    let c = v2 - ray.origin;
    let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
    let s = ray.shear;
    let p0 = [a[kx] + s.x * a[kz], a[ky] + s.y * a[kz]];
    let p1 = [b[kx] + s.x * b[kz], b[ky] + s.y * b[kz]];
    let p2 = [c[kx] + s.x * c[kz], c[ky] + s.y * c[kz]];
    // 2-D cross products of the sheared vertices, each edge from its lexicographically smaller
    // vertex (v0 < v1 < v2, see `lexicographic_order`): a shared edge rounds alike in both of
    // its triangles, so no ray slips between them.
    let e0 = p1[0] * p2[1] - p1[1] * p2[0];
    let e1 = -(p0[0] * p2[1] - p0[1] * p2[0]);
    let e2 = p0[0] * p1[1] - p0[1] * p1[0];
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return MISS;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return MISS;
    }
    // Scaled distance, compared against t_max * det to avoid the division until a hit.
    let z = [s.z * a[kz], s.z * b[kz], s.z * c[kz]];
    let t_scaled = e0 * z[0] + e1 * z[1] + e2 * z[2];
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return MISS;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return MISS;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if t <= triangle_t_error([p0, p1, p2], z, [e0, e1, e2], inv_det) {
        return MISS;
    }
    Hit {
        t,
        b1: e1 * inv_det,
        b2: e2 * inv_det,
    }
}

/// pbrt-v4's bound on the error of the watertight test's t (`Triangle::Intersect`, deltaT),
/// from the sheared vertices `p`, their scaled z and the edge functions. A hit no farther than
/// this may lie behind the origin: it is the ray's own surface (a secondary ray leaving a
/// triangle whose origin offset is below the t error of a steep test), so it is rejected.
fn triangle_t_error(p: [[f32; 2]; 3], z: [f32; 3], e: [f32; 3], inv_det: f32) -> f32 {
    let max_of = |v: [f32; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
    let max_x = max_of([p[0][0], p[1][0], p[2][0]]);
    let max_y = max_of([p[0][1], p[1][1], p[2][1]]);
    let max_z = max_of(z);
    let max_e = max_of(e);
    let delta_x = gamma(5) * (max_x + max_z);
    let delta_y = gamma(5) * (max_y + max_z);
    let delta_z = gamma(3) * max_z;
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs()
}

/// `|c|^2 - r^2`, the power of the world origin with respect to a sphere, computed in f64 from
/// the f32 centre and radius the kernels see: the exact value, rounded once. It lets
/// `intersect_sphere` evaluate |o - c|^2 - r^2 without cancellation when the ray starts near
/// the origin and the sphere is huge (a planet under a scene: o - c rounds to ULPs of r).
pub fn sphere_origin_power(center: Vec3, radius: f32) -> f32 {
    (center.as_dvec3().length_squared() - (radius as f64) * (radius as f64)) as f32
}

/// The sphere of centre `center`, radius `radius` and `origin_power` = |c|^2 - r^2. The hit
/// carries in `b1` a bound on the relative error of `t`, from which `sphere_surface_point`
/// bounds the hit point's error.
pub fn intersect_sphere(
    ray: &RayQuery,
    center: Vec3,
    radius: f32,
    origin_power: f32,
    t_max: f32,
) -> Hit {
    let f = ray.origin - center;
    let b = f.dot(ray.direction);
    // r^2 - |f - (f.d) d|^2 instead of b^2 - (|f|^2 - r^2): no cancellation far from the sphere.
    let perpendicular = f - b * ray.direction;
    let r2 = radius * radius;
    let p2 = perpendicular.dot(perpendicular);
    let discriminant = r2 - p2;
    if discriminant < 0.0 {
        return MISS;
    }
    let root = discriminant.sqrt();
    let q = if b >= 0.0 { -b - root } else { -b + root };
    if q == 0.0 {
        return MISS;
    }
    // |o - c|^2 - r^2 in two forms; each one's error bound is gamma(6) times its terms' sizes.
    // Direct: cheap, but `f` is rounded to ULPs of |o - c|, so a ray starting near a huge
    // sphere loses every digit. Expanded, |o|^2 - 2 o.c + (|c|^2 - r^2): exact terms near the
    // origin, but cancels when o and c are both far out. Take the better-conditioned one.
    let f2 = f.dot(f);
    let direct_size = f2 + r2;
    let expanded_size = ray.origin.dot(ray.origin)
        + 2.0 * (ray.origin * center).abs().element_sum()
        + origin_power.abs();
    let (c, c_size) = if direct_size <= expanded_size {
        (f2 - r2, direct_size)
    } else {
        (
            ray.origin.dot(ray.origin) - 2.0 * ray.origin.dot(center) + origin_power,
            expanded_size,
        )
    };
    let t0 = (c / q).min(q);
    let t1 = (c / q).max(q);
    let t = if t0 > 0.0 { t0 } else { t1 };
    if t <= 0.0 || t >= t_max {
        return MISS;
    }
    // |q| = |b| + root (same signs). b inherits f's rounding; the discriminant's error turns
    // into root's through d(sqrt x) = dx / (2 sqrt x), capped by sqrt(dx) where root ~ 0.
    let f_length = f2.sqrt();
    let discriminant_error = gamma(8) * (r2 + p2 + 2.0 * p2.sqrt() * f_length);
    let root_error = discriminant_error / (root + discriminant_error.sqrt());
    let q_relative = (gamma(4) * f_length + root_error) / q.abs();
    let c_relative = if t == q {
        0.0
    } else {
        gamma(6) * c_size / c.abs()
    };
    Hit {
        t,
        b1: q_relative + c_relative + gamma(2),
        b2: 0.0,
    }
}

/// Intersect the parallelogram `corner + u edge_u + v edge_v` (u, v in [0, 1]) before `t_max`, from
/// either side; `b1`, `b2` of the hit are (u, v).
pub fn intersect_quad(ray: &RayQuery, corner: Vec3, edge_u: Vec3, edge_v: Vec3, t_max: f32) -> Hit {
    let n = edge_u.cross(edge_v);
    let denom = n.dot(ray.direction);
    if denom == 0.0 {
        return MISS;
    }
    let t = (corner - ray.origin).dot(n) / denom;
    if t <= 0.0 || t >= t_max {
        return MISS;
    }
    let q = ray.origin + t * ray.direction - corner;
    let nn = n.dot(n);
    let u = q.cross(edge_v).dot(n) / nn;
    let v = edge_u.cross(q).dot(n) / nn;
    if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
        return MISS;
    }
    Hit { t, b1: u, b2: v }
}

/// Intersect the infinite plane through `point` with normal `normal` before `t_max`, from either
/// side.
pub fn intersect_plane(ray: &RayQuery, point: Vec3, normal: Vec3, t_max: f32) -> Hit {
    let denom = normal.dot(ray.direction);
    if denom == 0.0 {
        return MISS;
    }
    let t = (point - ray.origin).dot(normal) / denom;
    if t <= 0.0 || t >= t_max {
        return MISS;
    }
    Hit {
        t,
        b1: 0.0,
        b2: 0.0,
    }
}

/// Intersect any primitive; `t == T_FAR` means a miss.
/// `F` is the scene's `layout::FEATURE_*` set: without `FEATURE_TRIANGLES` the triangle test
/// is compiled out, without `FEATURE_CURVED` the ellipsoid's, cylinder's and torus's, as in the
/// specialised kernel.
pub fn intersect_primitive<const F: u32>(ray: &RayQuery, prim: &GpuPrimitive, t_max: f32) -> Hit {
    let p0 = Vec3::from(prim.p0);
    let p1 = Vec3::from(prim.p1);
    let p2 = Vec3::from(prim.p2);
    match prim.kind {
        PRIM_TRIANGLE if has(F, FEATURE_TRIANGLES) => intersect_triangle(ray, p0, p1, p2, t_max),
        PRIM_SPHERE => intersect_sphere(ray, p0, p1.x, p1.y, t_max),
        PRIM_QUAD => intersect_quad(ray, p0, p1, p2, t_max),
        PRIM_PLANE => intersect_plane(ray, p0, p1, t_max),
        // Curved shapes are tested in their own frame (`curved::ray_in_frame`).
        PRIM_ELLIPSOID if has(F, FEATURE_CURVED) => {
            intersect_ellipsoid(&ray_in_frame(ray, p0, orientation(prim)), p1, t_max)
        }
        PRIM_CYLINDER if has(F, FEATURE_CURVED) => {
            intersect_cylinder(&ray_in_frame(ray, p0, orientation(prim)), p1.x, p1.y, t_max)
        }
        PRIM_TORUS if has(F, FEATURE_CURVED) => {
            intersect_torus(&ray_in_frame(ray, p0, orientation(prim)), p1.x, p1.y, t_max)
        }
        _ => MISS,
    }
}

/// Slab test against a box. Returns the entry distance, or `T_FAR` for a miss. Mirrors obvhs's
/// `Aabb::intersect_ray`, plus the widened far distance.
pub fn intersect_box(ray: &RayQuery, min: Vec3, max: Vec3, t_max: f32) -> f32 {
    let t1 = (min - ray.origin) * ray.inv_direction;
    let t2 = (max - ray.origin) * ray.inv_direction;
    let t_near = t1.min(t2).max_element();
    let t_far = t1.max(t2).min_element() * SLAB_FAR_SCALE;
    if t_far >= t_near && t_far >= 0.0 && t_near < t_max {
        t_near
    } else {
        T_FAR
    }
}

/// pbrt-v4's `ShadowEpsilon`: the fraction of its length by which a shadow ray toward a light
/// point stops short, so that a surface through that point (a point light on a wall, an area
/// light flush with a ceiling, whose hits round to either side of the light's distance) does
/// not shadow it.
pub const SHADOW_EPSILON: f32 = 1.0e-4;

/// Length of a shadow ray toward a light point `distance` away.
pub fn shadow_ray_length(distance: f32) -> f32 {
    distance * (1.0 - SHADOW_EPSILON)
}

/// v0 + b1 (v1 - v0) + b2 (v2 - v0): on the triangle's plane whatever the barycentrics'
/// rounding, and, unlike pbrt-v4's b0 v0 + b1 v1 + b2 v2 (error gamma(7) sum |b_i v_i|), only
/// the final sum is rounded at the scale of the coordinates, which matters far from the origin.
/// Errors: edges, products and their sum (gamma(3) of the two terms), then that final sum.
pub fn triangle_point(v: [Vec3; 3], b1: f32, b2: f32) -> SurfacePoint {
    let along = [b1 * (v[1] - v[0]), b2 * (v[2] - v[0])];
    let position = v[0] + (along[0] + along[1]);
    SurfacePoint {
        position,
        error: gamma(3) * (along[0].abs() + along[1].abs()) + gamma(1) * position.abs(),
    }
}

/// corner + (u edge_u + v edge_v): the same form and bound as `triangle_point`.
pub fn quad_point(corner: Vec3, edge_u: Vec3, edge_v: Vec3, u: f32, v: f32) -> SurfacePoint {
    let (along_u, along_v) = (u * edge_u, v * edge_v);
    let position = corner + (along_u + along_v);
    SurfacePoint {
        position,
        error: gamma(2) * (along_u.abs() + along_v.abs()) + gamma(1) * position.abs(),
    }
}

/// The ray's point at `t`, projected onto the plane through `point` with unit `normal`. The
/// distance s to the plane comes from the small difference raw - point (gamma(5) of its size,
/// on every component since the projection mixes them), then s n is subtracted.
pub fn plane_point(ray: &RayQuery, t: f32, point: Vec3, normal: Vec3) -> SurfacePoint {
    let raw = ray.origin + t * ray.direction;
    let from_point = raw - point;
    let position = raw - from_point.dot(normal) * normal;
    SurfacePoint {
        position,
        error: Vec3::splat(gamma(5) * from_point.abs().max_element()) + gamma(1) * position.abs(),
    }
}

/// The hit point of `intersect_sphere` and its outward normal. Two candidates: the ray's point
/// o + t d, whose error is that of t times |d| plus the rounding of o + t d, and the re-projection
/// c + r n (pbrt-v4), whose error is ULPs of |c| + r. The smaller bound wins: re-projection for
/// spheres seen from afar, the ray's point for a huge sphere under a small scene, where c + r n
/// could not even represent the point to within ULPs of r.
pub fn sphere_surface_point(
    ray: &RayQuery,
    hit: Hit,
    center: Vec3,
    radius: f32,
) -> (SurfacePoint, Vec3) {
    let along = hit.t * ray.direction;
    let on_ray = ray.origin + along;
    // From the centre along the ray: rounded at the scale of |o - c|, not of |c|, so the normal
    // stays accurate for a small sphere far from the origin.
    let outward = ((ray.origin - center) + along).normalize();
    let t_error = hit.t * hit.b1;
    let on_ray_error = gamma(1) * (on_ray.abs() + along.abs()) + t_error * ray.direction.abs();
    // The normal's length is 1 within gamma(3); r n adds one rounding, c + r n another.
    let scaled_normal = radius * outward;
    let projected = center + scaled_normal;
    let projected_error = gamma(4) * scaled_normal.abs() + gamma(1) * projected.abs();
    let normal_size = outward.abs();
    let point = if normal_size.dot(on_ray_error) < normal_size.dot(projected_error) {
        SurfacePoint {
            position: on_ray,
            error: on_ray_error,
        }
    } else {
        SurfacePoint {
            position: projected,
            error: projected_error,
        }
    };
    (point, outward)
}

/// pbrt-v4's `OffsetRayOrigin`: move `position` off its surface along `n` (unit, pointing to
/// the side the new ray leaves on) by the projection of its per-component `error` bound on `n`,
/// then one more ULP away, so that the rounding of the addition cannot undo the offset.
#[inline]
pub fn offset_ray_origin(position: Vec3, error: Vec3, n: Vec3) -> Vec3 {
    let offset = n.abs().dot(error) * n;
    let moved = position + offset;
    Vec3::new(
        round_away(moved.x, offset.x),
        round_away(moved.y, offset.y),
        round_away(moved.z, offset.z),
    )
}

/// The neighbouring float of `v` in the direction of `sign`'s sign; `v` if `sign` is zero.
fn round_away(v: f32, sign: f32) -> f32 {
    if sign > 0.0 {
        next_float_up(v)
    } else if sign < 0.0 {
        -next_float_up(-v)
    } else {
        v
    }
}

/// The next float above the finite `v`, by integer steps on its bits (as the WGSL twin must).
fn next_float_up(v: f32) -> f32 {
    if v == 0.0 {
        f32::from_bits(1)
    } else if v > 0.0 {
        f32::from_bits(v.to_bits() + 1)
    } else {
        f32::from_bits(v.to_bits() - 1)
    }
}
