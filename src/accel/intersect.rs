//! Ray/primitive intersection, written for robustness rather than taken from obvhs.
//! Twin: `wgsl/intersect.wgsl`.
//!
//! - Triangles: the watertight test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//!   Intersection", JCGT 2(1), 2013 (as in pbrt-v4), with each edge function evaluated in a
//!   canonical vertex order so that two triangles sharing an edge compute the very same value
//!   even where a compiler fuses multiply-adds. <https://jcgt.org/published/0002/01/05/>
//! - Spheres: the cancellation-free quadratic of Haines et al., "Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7.
//! - Boxes: slab test with reciprocals kept finite for zero direction components and a widened
//!   far distance (pbrt-v4's 1 + 2*gamma(3)), so rounding never culls a box the ray touches.
//! - Secondary-ray origins: Wachter and Binder, "A Fast and Robust Method for Avoiding
//!   Self-Intersection", Ray Tracing Gems ch. 6: an offset of a few ULPs that scales with the
//!   position, valid at any scene scale, instead of a fixed epsilon.

use glam::{Vec3, Vec3A};

use crate::layout::{GpuPrimitive, PRIM_PLANE, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE, T_FAR};

/// Smallest direction magnitude used for the slab reciprocals: with coordinates below 1e9
/// (validated), products stay far below f32::MAX.
const MIN_DIRECTION: f32 = 1.0e-20;
/// pbrt-v4's 1 + 2*gamma(3), widened 2x for WGSL's 2.5-ULP division.
pub const SLAB_FAR_SCALE: f32 = 1.0 + 4.0 * 3.0 * f32::EPSILON * 0.5;

/// Per-ray constants of the watertight triangle test and the slab test.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    pub origin: Vec3,
    pub direction: Vec3,
    pub inv_direction: Vec3,
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub shear: Vec3,
}

fn safe_reciprocal(d: f32) -> f32 {
    if (0.0..MIN_DIRECTION).contains(&d) {
        1.0 / MIN_DIRECTION
    } else if d < 0.0 && d > -MIN_DIRECTION {
        -1.0 / MIN_DIRECTION
    } else {
        1.0 / d
    }
}

impl RayQuery {
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        let abs = direction.abs();
        let kz = if abs.x > abs.y {
            if abs.x > abs.z { 0 } else { 2 }
        } else if abs.y > abs.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if direction[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = direction[kz];
        RayQuery {
            origin,
            direction,
            inv_direction: Vec3::new(
                safe_reciprocal(direction.x),
                safe_reciprocal(direction.y),
                safe_reciprocal(direction.z),
            ),
            kx,
            ky,
            kz,
            shear: Vec3::new(-direction[kx] / dz, -direction[ky] / dz, 1.0 / dz),
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

/// A hit: distance and, for triangles and quads, surface coordinates (b1, b2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

const MISS: Hit = Hit {
    t: T_FAR,
    b1: 0.0,
    b2: 0.0,
};

fn lexicographic_less(a: Vec3, b: Vec3) -> bool {
    a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)))
}

/// 2-D cross product of the sheared vertices `p`, `q` of 3-D vertices `vp`, `vq`, always
/// evaluated with the lexicographically smaller vertex first, so that a shared edge gets the
/// same rounding in both of its triangles.
fn edge_function(p: [f32; 2], q: [f32; 2], vp: Vec3, vq: Vec3) -> f32 {
    if lexicographic_less(vq, vp) {
        -(q[0] * p[1] - q[1] * p[0])
    } else {
        p[0] * q[1] - p[1] * q[0]
    }
}

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
    let e0 = edge_function(p1, p2, v1, v2);
    let e1 = edge_function(p2, p0, v2, v0);
    let e2 = edge_function(p0, p1, v0, v1);
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return MISS;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return MISS;
    }
    // Scaled distance, compared against t_max * det to avoid the division until a hit.
    let t_scaled = e0 * (s.z * a[kz]) + e1 * (s.z * b[kz]) + e2 * (s.z * c[kz]);
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return MISS;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return MISS;
    }
    let inv_det = 1.0 / det;
    Hit {
        t: t_scaled * inv_det,
        b1: e1 * inv_det,
        b2: e2 * inv_det,
    }
}

pub fn intersect_sphere(ray: &RayQuery, center: Vec3, radius: f32, t_max: f32) -> Hit {
    let f = ray.origin - center;
    let b = f.dot(ray.direction);
    // r^2 - |f - (f.d) d|^2 instead of b^2 - (|f|^2 - r^2): no cancellation far from the sphere.
    let perpendicular = f - b * ray.direction;
    let discriminant = radius * radius - perpendicular.dot(perpendicular);
    if discriminant < 0.0 {
        return MISS;
    }
    let root = discriminant.sqrt();
    let q = if b >= 0.0 { -b - root } else { -b + root };
    if q == 0.0 {
        return MISS;
    }
    let c = f.dot(f) - radius * radius;
    let t0 = (c / q).min(q);
    let t1 = (c / q).max(q);
    let t = if t0 > 0.0 { t0 } else { t1 };
    if t <= 0.0 || t >= t_max {
        return MISS;
    }
    Hit {
        t,
        b1: 0.0,
        b2: 0.0,
    }
}

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
pub fn intersect_primitive(ray: &RayQuery, prim: &GpuPrimitive, t_max: f32) -> Hit {
    let p0 = Vec3::from(prim.p0);
    let p1 = Vec3::from(prim.p1);
    let p2 = Vec3::from(prim.p2);
    match prim.kind {
        PRIM_TRIANGLE => intersect_triangle(ray, p0, p1, p2, t_max),
        PRIM_SPHERE => intersect_sphere(ray, p0, p1.x, t_max),
        PRIM_QUAD => intersect_quad(ray, p0, p1, p2, t_max),
        PRIM_PLANE => intersect_plane(ray, p0, p1, t_max),
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

/// Ray Tracing Gems ch. 6: move `p` off its surface along `n` (unit, pointing to the side the
/// new ray leaves on) by a few ULPs of `p` itself, or by a fixed amount near the origin where
/// ULPs are tiny.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let offset = |p: f32, n: f32| -> f32 {
        let of_i = (INT_SCALE * n) as i32;
        let moved =
            f32::from_bits(
                (p.to_bits() as i32).wrapping_add(if p < 0.0 { -of_i } else { of_i }) as u32,
            );
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            moved
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}
