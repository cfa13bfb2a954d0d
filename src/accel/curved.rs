//! Exact ray intersection with the curved surfaces a scene declares besides spheres:
//! ellipsoids, open cylinders and tori, each in its own frame (the semi-axes along its axes,
//! the axis of a cylinder or torus along its y) turned into the world's by an orientation.
//! Twin: `wgsl/curved.wgsl`.
//!
//! - Ellipsoids and cylinders are quadrics: a t^2 + 2 b t + c = 0, solved without cancellation
//!   (the discriminant b^2 - a c from a cross product, as `intersect_sphere` does, and the
//!   second root as c / q).
//! - A torus is a quartic in t. Its roots are isolated, not taken from Ferrari's formula (which
//!   loses every digit in f32 near double roots): the roots of F'' split the ray's span inside
//!   the torus's bounding sphere where F' is monotone, the roots of F' found there split it
//!   where F is monotone, and each sign change of F is a root, found by Newton's method kept
//!   inside its bracket. The quartic is set up in units of R + r from where the ray enters the
//!   bounding sphere, so its coefficients are of order one whatever the torus's size and the
//!   ray's length. Each root is then polished on the torus's signed distance, which rounds at
//!   the scale of the coordinates where the quartic rounds at that of (R + r)^2.
//! - Each hit is rejected when it is no farther than the bound on its own error (it may lie
//!   behind the origin: the ray's own surface, left from an offset origin), as the triangle
//!   test does.
//! - The shading point is the ray's point re-projected onto the surface (as pbrt-v4 does for
//!   its quadrics), so its error is a few ULPs of the shape's size, whatever the ray's length.
//! - A shape may be turned about its centre (a cylinder's base): the ray is taken into the
//!   shape's own frame (`ray_in_frame`), where the tests above run, and the shading point back
//!   out (`point_to_world`); a rotation preserves lengths, so t is the same in both frames.

use glam::{Quat, Vec3};

use super::ray::{Hit, MISS, RayQuery, SurfacePoint, gamma};
use crate::layout::{
    GpuPrimitive, PRIM_CYLINDER, PRIM_ELLIPSOID, TORUS_MARGIN, TORUS_POLISH_REACH,
    TORUS_POLISH_STEPS, TORUS_ROOT_STEPS,
};

/// A curved primitive's orientation: the unit quaternion that turns its own frame (the axis of
/// a cylinder or torus along y, an ellipsoid's semi-axes along x, y, z) into the world's, about
/// `p0`. Its x, y, z are in `p2` and w's bits in `normals` (a word only triangles use
/// otherwise): see `layout::GpuPrimitive`.
pub fn orientation(prim: &GpuPrimitive) -> Quat {
    Quat::from_xyzw(
        prim.p2[0],
        prim.p2[1],
        prim.p2[2],
        f32::from_bits(prim.normals),
    )
}

/// Bound on the rounding of a vector v turned by a unit quaternion (glam's
/// v (w^2 - |q|^2) + 2 (q . v) q + 2 w (q x v): terms of at most 4 |v| together, each rounded
/// a few times, and the quaternion's own rounding to f32), per component. An identity
/// orientation turns exactly (its q is zero).
fn rotation_error(length: f32) -> f32 {
    gamma(32) * length
}

/// A ray in a curved shape's own frame (`ray_in_frame`): all the curved tests read.
#[derive(Clone, Copy, Debug)]
pub struct FrameRay {
    /// The origin, relative to the shape's centre (a cylinder's base), in its frame.
    pub origin: Vec3,
    /// The direction, in its frame.
    pub direction: Vec3,
}

/// `ray` in the own frame of a shape centred at `center` and turned by `orientation`, the centre
/// at the origin.
pub fn ray_in_frame(ray: &RayQuery, center: Vec3, orientation: Quat) -> FrameRay {
    let origin = ray.origin - center;
    // An identity orientation would turn exactly; most shapes are unturned, and skipping the
    // turns keeps their frames as fast as before there were orientations (`bench frame` on the
    // curved-mirror scenes; on lavapipe the same branch measured slower than turning always,
    // so the WGSL twin turns always, to the same values).
    if orientation.xyz() == Vec3::ZERO {
        return FrameRay {
            origin,
            direction: ray.direction,
        };
    }
    let inverse = orientation.conjugate();
    FrameRay {
        origin: inverse * origin,
        direction: inverse * ray.direction,
    }
}

/// A shading point and outward normal found in a shape's own frame (`ray_in_frame`, the centre
/// at the origin) in the world's: the error bound grows by the rounding of both rotations (the
/// ray's into the frame and the point's out of it; none for the identity) and of the
/// translation.
fn point_to_world(
    (local, outward): (SurfacePoint, Vec3),
    center: Vec3,
    orientation: Quat,
) -> (SurfacePoint, Vec3) {
    if orientation.xyz() == Vec3::ZERO {
        let position = center + local.position;
        let point = SurfacePoint {
            position,
            error: local.error + gamma(1) * position.abs(),
        };
        return (point, outward);
    }
    let offset = orientation * local.position;
    let position = center + offset;
    // A bound per component turned is at most the bound's length in each.
    let turned = local.error.length() + rotation_error(2.0 * offset.length());
    let point = SurfacePoint {
        position,
        error: Vec3::splat(turned) + gamma(1) * position.abs(),
    };
    (point, orientation * outward)
}

/// The roots of a t^2 + 2 b t + c = 0 given its reduced discriminant b^2 - a c (computed by
/// the caller without cancellation), in increasing order, and a bound on their absolute error:
/// q = -(b + sign(b) sqrt(disc)) has no cancellation, the roots are q / a and c / q; `c_size`
/// bounds the terms of c.
fn quadratic_roots(a: f32, b: f32, c: f32, discriminant: f32, c_size: f32) -> Option<[f32; 3]> {
    if discriminant < 0.0 || a == 0.0 {
        return None;
    }
    let root = discriminant.sqrt();
    let q = if b >= 0.0 { -b - root } else { -b + root };
    if q == 0.0 {
        return None;
    }
    let (t0, t1) = (q / a, c / q);
    let error = gamma(8) * (c_size / q.abs() + q.abs() / a);
    Some([t0.min(t1), t0.max(t1), error])
}

/// The ellipsoid with semi-axes `radii` along the axes of `ray`'s frame, centred at its origin
/// (`ray_in_frame`): in coordinates scaled by 1 / radii it is the unit sphere, and t is the
/// same in both.
pub fn intersect_ellipsoid(ray: &FrameRay, radii: Vec3, t_max: f32) -> Hit {
    let f = ray.origin / radii;
    let e = ray.direction / radii;
    let a = e.dot(e);
    let f2 = f.dot(f);
    let discriminant = a - f.cross(e).length_squared();
    let Some([near, far, error]) = quadratic_roots(a, f.dot(e), f2 - 1.0, discriminant, f2 + 1.0)
    else {
        return MISS;
    };
    let t = if near > error { near } else { far };
    if t <= error || t >= t_max {
        return MISS;
    }
    hit_at(t)
}

/// The open cylinder of `radius` around the y axis of `ray`'s frame, from its origin (the base
/// circle's centre, `ray_in_frame`) `height` up.
pub fn intersect_cylinder(ray: &FrameRay, radius: f32, height: f32, t_max: f32) -> Hit {
    let f = ray.origin;
    let d = ray.direction;
    let a = d.x * d.x + d.z * d.z;
    let f2 = f.x * f.x + f.z * f.z;
    let cross = f.x * d.z - f.z * d.x;
    let discriminant = a * radius * radius - cross * cross;
    let c_size = f2 + radius * radius;
    let b = f.x * d.x + f.z * d.z;
    let Some([near, far, error]) =
        quadratic_roots(a, b, f2 - radius * radius, discriminant, c_size)
    else {
        return MISS;
    };
    for t in [near, far] {
        let y = f.y + t * d.y;
        if t > error && t < t_max && (0.0..=height).contains(&y) {
            return hit_at(t);
        }
    }
    MISS
}

/// The torus around the y axis of `ray`'s frame, centred at its origin (`ray_in_frame`): the
/// circle of radius `major` swept by a disc of radius `minor` < `major`,
/// F(p) = (|p|^2 + R^2 - r^2)^2 - 4 R^2 (p_x^2 + p_z^2) = 0.
pub fn intersect_torus(ray: &FrameRay, major: f32, minor: f32, t_max: f32) -> Hit {
    let reach = major + minor;
    let f = ray.origin;
    let length = ray.direction.length();
    let d = ray.direction / length;
    // The bounding sphere, widened by a few ULPs so that rounding never cuts the torus.
    let along = f.dot(d);
    let perpendicular = f - along * d;
    let bound = reach * (1.0 + gamma(4));
    let discriminant = bound * bound - perpendicular.dot(perpendicular);
    if discriminant < 0.0 {
        return MISS;
    }
    let half_chord = discriminant.sqrt();
    let (enter, exit) = (-along - half_chord, -along + half_chord);
    let t_limit = t_max * length;
    if exit <= 0.0 || enter >= t_limit {
        return MISS;
    }
    // The torus's equator touches the bounding sphere: start and end `TORUS_MARGIN` of R + r
    // beyond it, so that a hit there is not lost to rounding (nor taken for the ray's own
    // surface, which only a start at the origin can be).
    let margin = TORUS_MARGIN * reach;
    let start = (enter - margin).max(0.0);
    let scale = 1.0 / reach;
    let quartic = TorusQuartic::new((f + start * d) * scale, d, major * scale, minor * scale);
    let span = ((exit + margin).min(t_limit) - start) * scale;
    for (s, error) in quartic.roots(span) {
        let distance = polish_torus_root(f, d, major, minor, start + s * reach, error * reach);
        let t = distance / length;
        if t < t_max {
            return hit_at(t);
        }
    }
    MISS
}

/// The root `along` (distance along the unit `d` from `f`, the ray's origin less the centre)
/// polished by Newton steps on the torus's signed distance sqrt((rho - R)^2 + y^2) - r. The
/// quartic's value is rounded at the scale of (R + r)^2, a distance of about (R + r)^2 / r
/// ULPs: near a double root or on a thin torus its root was off by up to 5e-4 of R (measured);
/// the distance is rounded at the scale of the coordinates. A step that would take the root
/// farther than `TORUS_POLISH_REACH` times its own error bound `error` from the quartic's is not taken (the
/// distance's Newton step could leave for another root).
fn polish_torus_root(f: Vec3, d: Vec3, major: f32, minor: f32, along: f32, error: f32) -> f32 {
    let mut x = along;
    for _ in 0..TORUS_POLISH_STEPS {
        let p = f + x * d;
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        if rho == 0.0 {
            break;
        }
        // From the nearest point of the ring (the circle of radius R) to p.
        let w = Vec3::new(p.x * (1.0 - major / rho), p.y, p.z * (1.0 - major / rho));
        let distance = w.length();
        let slope = w.dot(d) / distance;
        if distance == 0.0 || slope == 0.0 {
            break;
        }
        let next = x - (distance - minor) / slope;
        let moved = (next - along).abs();
        if moved.is_nan() || moved > TORUS_POLISH_REACH * error {
            break;
        }
        x = next;
    }
    x
}

fn hit_at(t: f32) -> Hit {
    Hit {
        t,
        b1: 0.0,
        b2: 0.0,
    }
}

/// F(o + s d) for a torus of radii (R, r) in units of R + r, d a unit vector, as the quartic
/// c[0] + c[1] s + ... + c[4] s^4, and the sizes of its coefficients' terms (for error bounds).
struct TorusQuartic {
    c: [f32; 5],
    size: [f32; 5],
}

impl TorusQuartic {
    /// With G(s) = |o + s d|^2 + R^2 - r^2 = s^2 + 2 b s + e and H(s) = p_x^2 + p_z^2 =
    /// h2 s^2 + 2 h1 s + h0: F = G^2 - 4 R^2 H.
    fn new(o: Vec3, d: Vec3, major: f32, minor: f32) -> Self {
        let b = o.dot(d);
        let e = o.dot(o) + (major - minor) * (major + minor);
        let h2 = d.x * d.x + d.z * d.z;
        let h1 = o.x * d.x + o.z * d.z;
        let h0 = o.x * o.x + o.z * o.z;
        let k = 4.0 * major * major;
        TorusQuartic {
            c: [
                e * e - k * h0,
                4.0 * b * e - 2.0 * k * h1,
                4.0 * b * b + 2.0 * e - k * h2,
                4.0 * b,
                1.0,
            ],
            size: [
                e * e + k * h0,
                4.0 * (b * e).abs() + 2.0 * k * h1.abs(),
                4.0 * b * b + 2.0 * e.abs() + k * h2,
                4.0 * b.abs(),
                1.0,
            ],
        }
    }

    /// The roots in (0, span), in increasing order, each with the bound on its own error and
    /// farther from 0 than it (a root within it is the surface the ray leaves from).
    fn roots(&self, span: f32) -> impl Iterator<Item = (f32, f32)> + '_ {
        let c = &self.c;
        let derivative = [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4], 0.0];
        // F''/2 = 6 c4 s^2 + 3 c3 s + c2: its roots bound where F' is monotone.
        let inflections = quadratic_roots(
            6.0 * c[4],
            1.5 * c[3],
            c[2],
            2.25 * c[3] * c[3] - 6.0 * c[4] * c[2],
            c[2].abs(),
        )
        .map_or([0.0; 2], |[r0, r1, _]| [r0, r1]);
        // Where F' vanishes: F is monotone between consecutive ones.
        let mut ends = [span; 4];
        let mut count = 0;
        for root in monotone_roots(&derivative, inflections, span)
            .into_iter()
            .flatten()
        {
            ends[count] = root;
            count += 1;
        }
        (0..=count).filter_map(move |i| {
            let lo = if i == 0 { 0.0 } else { ends[i - 1] };
            let root = bracketed_root(c, lo, ends[i])?;
            let error = gamma(16) * polynomial(&self.size, root).0 / polynomial(c, root).1.abs();
            (root > error).then_some((root, error))
        })
    }
}

/// The roots of `poly` in (0, span) between consecutive `splits` (points where its derivative
/// vanishes, in any order; those outside (0, span) ignored): at most one per piece, where it
/// is monotone. In increasing order.
fn monotone_roots(poly: &[f32; 5], splits: [f32; 2], span: f32) -> [Option<f32>; 3] {
    let (s0, s1) = (splits[0].min(splits[1]), splits[0].max(splits[1]));
    let mut ends = [0.0, span, span, span];
    let mut count = 1;
    for s in [s0, s1] {
        if s > 0.0 && s < span && s > ends[count - 1] {
            ends[count] = s;
            count += 1;
        }
    }
    ends[count] = span;
    let mut roots = [None; 3];
    for i in 0..count {
        roots[i] = bracketed_root(poly, ends[i], ends[i + 1]);
    }
    roots
}

/// (value, derivative) of c[0] + c[1] x + ... + c[4] x^4, by Horner's rule.
fn polynomial(c: &[f32; 5], x: f32) -> (f32, f32) {
    let mut value = c[4];
    let mut derivative = 0.0;
    for k in (0..4).rev() {
        derivative = derivative * x + value;
        value = value * x + c[k];
    }
    (value, derivative)
}

/// The root of `poly` in (lo, hi) where it changes sign there (none otherwise), by Newton's
/// method kept inside the bracket (bisecting where a step would leave it). The caller makes
/// `poly` monotone on the bracket, so there is at most one root.
fn bracketed_root(poly: &[f32; 5], lo: f32, hi: f32) -> Option<f32> {
    let (f_lo, f_hi) = (polynomial(poly, lo).0, polynomial(poly, hi).0);
    if !(hi > lo && f_lo * f_hi < 0.0) {
        return None;
    }
    let (mut lo, mut hi) = (lo, hi);
    let mut x = 0.5 * (lo + hi);
    for _ in 0..TORUS_ROOT_STEPS {
        let (value, slope) = polynomial(poly, x);
        if value == 0.0 {
            return Some(x);
        }
        if (value < 0.0) == (f_lo < 0.0) {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - value / slope;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if next == x {
            break;
        }
        x = next;
    }
    Some(x)
}

/// The shading point and outward normal where `ray` meets the ellipsoid, cylinder or torus
/// `prim` at `t`: found in the shape's own frame and taken back to the world's.
pub fn curved_surface_point(ray: &RayQuery, t: f32, prim: &GpuPrimitive) -> (SurfacePoint, Vec3) {
    let (center, turn) = (Vec3::from(prim.p0), orientation(prim));
    let local = ray_in_frame(ray, center, turn);
    let p1 = Vec3::from(prim.p1);
    let found = match prim.kind {
        PRIM_ELLIPSOID => ellipsoid_surface_point(&local, t, p1),
        PRIM_CYLINDER => {
            let (mut point, outward) = cylinder_surface_point(&local, t, p1.x);
            // Its height is the ray's, whose origin was turned into the frame.
            if turn.xyz() != Vec3::ZERO {
                point.error.y += rotation_error(local.origin.length());
            }
            (point, outward)
        }
        _ => torus_surface_point(&local, t, p1.x, p1.y),
    };
    point_to_world(found, center, turn)
}

/// The hit point of `intersect_ellipsoid` and its outward normal, in the ray's frame: the
/// ray's point, scaled to the unit sphere, normalised and scaled back, so it lies on the
/// ellipsoid within a few ULPs of its semi-axes.
pub fn ellipsoid_surface_point(ray: &FrameRay, t: f32, radii: Vec3) -> (SurfacePoint, Vec3) {
    let unit = ((ray.origin + t * ray.direction) / radii).normalize();
    let position = radii * unit;
    let outward = (unit / radii).normalize();
    let point = SurfacePoint {
        position,
        error: gamma(6) * position.abs(),
    };
    (point, outward)
}

/// The hit point of `intersect_cylinder` and its outward normal, in the ray's frame: the
/// ray's point moved radially onto the cylinder; its height is the ray's.
pub fn cylinder_surface_point(ray: &FrameRay, t: f32, radius: f32) -> (SurfacePoint, Vec3) {
    let along = t * ray.direction;
    let local = ray.origin + along;
    let outward = Vec3::new(local.x, 0.0, local.z).normalize();
    let position = Vec3::new(radius * outward.x, local.y, radius * outward.z);
    // The origin's own rounding (its difference from the base) included.
    let height_error = gamma(3) * (ray.origin.y.abs() + along.y.abs());
    let point = SurfacePoint {
        position,
        error: Vec3::new(gamma(5) * radius, height_error, gamma(5) * radius),
    };
    (point, outward)
}

/// The hit point of `intersect_torus` and its outward normal, in the ray's frame: the nearest
/// point of the ring (the circle of radius R) to the ray's point, plus r along the direction
/// to that point.
pub fn torus_surface_point(ray: &FrameRay, t: f32, major: f32, minor: f32) -> (SurfacePoint, Vec3) {
    let local = ray.origin + t * ray.direction;
    let horizontal = Vec3::new(local.x, 0.0, local.z);
    // On the axis (impossible on the surface, as r < R) any direction of the ring will do.
    let around = horizontal.try_normalize().unwrap_or(Vec3::X);
    let ring = major * around;
    let outward = (local - ring).normalize();
    let position = ring + minor * outward;
    let point = SurfacePoint {
        position,
        error: Vec3::splat(gamma(6) * (major + minor)),
    };
    (point, outward)
}
