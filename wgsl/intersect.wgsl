// Ray/primitive intersection: watertight triangles, robust spheres, quads, planes, slabs,
// shading points with error bounds, and pbrt-v4's error-bounded origin offset.
// Mirrors: src/accel/intersect.rs (references there); closest_plane and plane_occludes,
// src/accel/traverse.rs. Those two read the bindings `frame` and `prims`.

const MIN_DIRECTION: f32 = 1.0e-20;
// 1 + 2*gamma(3) widened 2x for WGSL's 2.5-ULP division (see the Rust twin).
const SLAB_FAR_SCALE: f32 = 1.0000007152557373;

struct RayQuery {
    origin: vec3<f32>,
    direction: vec3<f32>,
    inv_direction: vec3<f32>,
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>,
    // The time (seconds) the ray is traced at: moving primitives are where they are then.
    time: f32,
}

// For spheres, b1 is the bound on t's relative error (see intersect_sphere).
struct Hit {
    t: f32,
    b1: f32,
    b2: f32,
}

// A hit and the primitive it is on (NONE: none).
struct PrimHit {
    prim: u32,
    hit: Hit,
}

fn miss() -> Hit {
    return Hit(T_FAR, 0.0, 0.0);
}

fn safe_reciprocal(d: f32) -> f32 {
    if (d >= 0.0 && d < MIN_DIRECTION) {
        return 1.0 / MIN_DIRECTION;
    }
    if (d < 0.0 && d > -MIN_DIRECTION) {
        return -1.0 / MIN_DIRECTION;
    }
    return 1.0 / d;
}

fn ray_query_new(origin: vec3<f32>, direction: vec3<f32>) -> RayQuery {
    let a = abs(direction);
    var kz = 2u;
    if (a.x > a.y) {
        if (a.x > a.z) { kz = 0u; }
    } else if (a.y > a.z) {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if (direction[kz] < 0.0) {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    let dz = direction[kz];
    let inv = vec3<f32>(safe_reciprocal(direction.x), safe_reciprocal(direction.y), safe_reciprocal(direction.z));
    return RayQuery(origin, direction, inv, kx, ky, kz,
        vec3<f32>(-direction[kx] / dz, -direction[ky] / dz, 1.0 / dz), 0.0);
}

fn ray_at_time(ray: RayQuery, time: f32) -> RayQuery {
    var timed = ray;
    timed.time = time;
    return timed;
}

// The ray in the frame of a primitive that has moved by `offset` (origin moved by -offset).
fn ray_relative_to(ray: RayQuery, offset: vec3<f32>) -> RayQuery {
    var relative = ray;
    relative.origin = ray.origin - offset;
    return relative;
}

// How far bounded primitive `id` has moved at `time`: zero in a static scene. Its velocity is
// the record `prims[frame.motion_base + id]`. Twin: accel::Primitives::offset.
fn prim_offset(id: u32, time: f32) -> vec3<f32> {
    if (frame.motion_base == 0u) {
        return vec3<f32>(0.0);
    }
    return prims[frame.motion_base + id].p0 * time;
}

// Bounded primitive `id` tested where it is at the ray's time.
fn intersect_at_time(ray: RayQuery, id: u32, t_max: f32) -> Hit {
    return intersect_primitive(ray_relative_to(ray, prim_offset(id, ray.time)), prims[id], t_max);
}

fn intersect_triangle(ray: RayQuery, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, t_max: f32) -> Hit {
    // Translate to the ray origin, permute so z is the dominant axis, shear onto +z.
    let a = v0 - ray.origin;
    let b = v1 - ray.origin;
    let c = v2 - ray.origin;
    let s = ray.shear;
    let p0 = vec2<f32>(a[ray.kx] + s.x * a[ray.kz], a[ray.ky] + s.y * a[ray.kz]);
    let p1 = vec2<f32>(b[ray.kx] + s.x * b[ray.kz], b[ray.ky] + s.y * b[ray.kz]);
    let p2 = vec2<f32>(c[ray.kx] + s.x * c[ray.kz], c[ray.ky] + s.y * c[ray.kz]);
    // Each edge from its lexicographically smaller vertex: the vertices are stored in that
    // order (see lexicographic_order in the Rust twin), so shared edges round alike.
    let e0 = p1.x * p2.y - p1.y * p2.x;
    let e1 = -(p0.x * p2.y - p0.y * p2.x);
    let e2 = p0.x * p1.y - p0.y * p1.x;
    if ((e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0)) {
        return miss();
    }
    let det = e0 + e1 + e2;
    if (det == 0.0) {
        return miss();
    }
    // Scaled distance, compared against t_max * det to avoid the division until a hit.
    let z = vec3<f32>(s.z * a[ray.kz], s.z * b[ray.kz], s.z * c[ray.kz]);
    let t_scaled = e0 * z.x + e1 * z.y + e2 * z.z;
    if (det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det)) {
        return miss();
    }
    if (det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det)) {
        return miss();
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if (t <= triangle_t_error(p0, p1, p2, z, vec3<f32>(e0, e1, e2), inv_det)) {
        return miss();
    }
    return Hit(t, e1 * inv_det, e2 * inv_det);
}

fn max_abs(v: vec3<f32>) -> f32 {
    let a = abs(v);
    return max(max(a.x, a.y), a.z);
}

// pbrt-v4's bound on the error of t (deltaT); hits no farther are the ray's own surface.
fn triangle_t_error(p0: vec2<f32>, p1: vec2<f32>, p2: vec2<f32>, z: vec3<f32>, e: vec3<f32>, inv_det: f32) -> f32 {
    let max_x = max_abs(vec3<f32>(p0.x, p1.x, p2.x));
    let max_y = max_abs(vec3<f32>(p0.y, p1.y, p2.y));
    let max_z = max_abs(z);
    let max_e = max_abs(e);
    let delta_x = gamma(5.0) * (max_x + max_z);
    let delta_y = gamma(5.0) * (max_y + max_z);
    let delta_z = gamma(3.0) * max_z;
    let delta_e = 2.0 * (gamma(2.0) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    return 3.0 * (gamma(3.0) * max_e * max_z + delta_e * max_z + delta_z * max_e) * abs(inv_det);
}

// pbrt-v4's gamma(n) with a whole ULP per operation (WGSL leaves the rounding direction open).
fn gamma(n: f32) -> f32 {
    let n_eps = n * 1.1920928955078125e-7;
    return n_eps / (1.0 - n_eps);
}

// origin_power = |c|^2 - r^2, rounded once from f64 on the CPU.
fn intersect_sphere(ray: RayQuery, center: vec3<f32>, radius: f32, origin_power: f32, t_max: f32) -> Hit {
    let f = ray.origin - center;
    let b = dot(f, ray.direction);
    // r^2 - |f - (f.d) d|^2 instead of b^2 - (|f|^2 - r^2): no cancellation far from the sphere.
    let perpendicular = f - b * ray.direction;
    let r2 = radius * radius;
    let p2 = dot(perpendicular, perpendicular);
    let discriminant = r2 - p2;
    if (discriminant < 0.0) {
        return miss();
    }
    let root = sqrt(discriminant);
    var q = -b + root;
    if (b >= 0.0) {
        q = -b - root;
    }
    if (q == 0.0) {
        return miss();
    }
    // |o - c|^2 - r^2 directly or expanded as |o|^2 - 2 o.c + (|c|^2 - r^2), whichever is
    // better conditioned (see the Rust twin).
    let f2 = dot(f, f);
    let direct_size = f2 + r2;
    let o = ray.origin;
    let oc = abs(o * center);
    let expanded_size = dot(o, o) + 2.0 * (oc.x + oc.y + oc.z) + abs(origin_power);
    var c = f2 - r2;
    var c_size = direct_size;
    if (direct_size > expanded_size) {
        c = dot(o, o) - 2.0 * dot(o, center) + origin_power;
        c_size = expanded_size;
    }
    let t0 = min(c / q, q);
    let t1 = max(c / q, q);
    var t = t1;
    if (t0 > 0.0) {
        t = t0;
    }
    if (t <= 0.0 || t >= t_max) {
        return miss();
    }
    let f_length = sqrt(f2);
    let discriminant_error = gamma(8.0) * (r2 + p2 + 2.0 * sqrt(p2) * f_length);
    let root_error = discriminant_error / (root + sqrt(discriminant_error));
    let q_relative = (gamma(4.0) * f_length + root_error) / abs(q);
    var c_relative = 0.0;
    if (t != q) {
        c_relative = gamma(6.0) * c_size / abs(c);
    }
    return Hit(t, q_relative + c_relative + gamma(2.0), 0.0);
}

fn intersect_quad(ray: RayQuery, corner: vec3<f32>, edge_u: vec3<f32>, edge_v: vec3<f32>, t_max: f32) -> Hit {
    let n = cross(edge_u, edge_v);
    let denom = dot(n, ray.direction);
    if (denom == 0.0) {
        return miss();
    }
    let t = dot(corner - ray.origin, n) / denom;
    if (t <= 0.0 || t >= t_max) {
        return miss();
    }
    let q = ray.origin + t * ray.direction - corner;
    let nn = dot(n, n);
    let u = dot(cross(q, edge_v), n) / nn;
    let v = dot(cross(edge_u, q), n) / nn;
    if (u < 0.0 || u > 1.0 || v < 0.0 || v > 1.0) {
        return miss();
    }
    return Hit(t, u, v);
}

fn intersect_plane(ray: RayQuery, point: vec3<f32>, normal: vec3<f32>, t_max: f32) -> Hit {
    let denom = dot(normal, ray.direction);
    if (denom == 0.0) {
        return miss();
    }
    let t = dot(point - ray.origin, normal) / denom;
    if (t <= 0.0 || t >= t_max) {
        return miss();
    }
    return Hit(t, 0.0, 0.0);
}

fn intersect_primitive(ray: RayQuery, prim: GpuPrimitive, t_max: f32) -> Hit {
    switch prim.kind {
        case PRIM_TRIANGLE: {
            if (FEATURE_TRIANGLES) {
                return intersect_triangle(ray, prim.p0, prim.p1, prim.p2, t_max);
            }
            return miss();
        }
        case PRIM_SPHERE: { return intersect_sphere(ray, prim.p0, prim.p1.x, prim.p1.y, t_max); }
        case PRIM_QUAD: { return intersect_quad(ray, prim.p0, prim.p1, prim.p2, t_max); }
        case PRIM_PLANE: { return intersect_plane(ray, prim.p0, prim.p1, t_max); }
        // Curved shapes are tested in their own frame (`ray_in_frame`).
        case PRIM_ELLIPSOID: {
            if (FEATURE_CURVED) {
                return intersect_ellipsoid(ray_in_frame(ray, prim.p0, prim_orientation(prim)), prim.p1, t_max);
            }
            return miss();
        }
        case PRIM_CYLINDER: {
            if (FEATURE_CURVED) {
                return intersect_cylinder(ray_in_frame(ray, prim.p0, prim_orientation(prim)), prim.p1.x, prim.p1.y, t_max);
            }
            return miss();
        }
        case PRIM_TORUS: {
            if (FEATURE_CURVED) {
                return intersect_torus(ray_in_frame(ray, prim.p0, prim_orientation(prim)), prim.p1.x, prim.p1.y, t_max);
            }
            return miss();
        }
        default: { return miss(); }
    }
}

// The unbounded planes (after every BVH's primitives), by brute force: the closest hit before
// `best`'s, and whether one occludes; every traversal ends with them.
fn closest_plane(ray: RayQuery, skip: u32, best_in: PrimHit) -> PrimHit {
    var best = best_in;
    for (var id = frame.plane_start; FEATURE_PLANES && id < frame.plane_start + frame.plane_count; id += 1u) {
        if (id != skip) {
            let hit = intersect_primitive(ray, prims[id], best.hit.t);
            if (hit.t < best.hit.t) {
                best = PrimHit(id, hit);
            }
        }
    }
    return best;
}

fn plane_occludes(ray: RayQuery, skip_a: u32, skip_b: u32, t_max: f32) -> bool {
    for (var id = frame.plane_start; FEATURE_PLANES && id < frame.plane_start + frame.plane_count; id += 1u) {
        if (id != skip_a && id != skip_b && intersect_primitive(ray, prims[id], t_max).t < t_max) {
            return true;
        }
    }
    return false;
}

fn intersect_box(ray: RayQuery, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> f32 {
    let t1 = (bmin - ray.origin) * ray.inv_direction;
    let t2 = (bmax - ray.origin) * ray.inv_direction;
    let lo = min(t1, t2);
    let hi = max(t1, t2);
    let t_near = max(max(lo.x, lo.y), lo.z);
    let t_far = min(min(hi.x, hi.y), hi.z) * SLAB_FAR_SCALE;
    if (t_far >= t_near && t_far >= 0.0 && t_near < t_max) {
        return t_near;
    }
    return T_FAR;
}

// pbrt-v4's ShadowEpsilon: shadow rays stop this fraction short of the light point (Rust twin).
const SHADOW_EPSILON: f32 = 1.0e-4;

fn shadow_ray_length(distance: f32) -> f32 {
    return distance * (1.0 - SHADOW_EPSILON);
}

// A shading point and the per-component bound on its distance from the true surface point.
struct SurfacePoint {
    position: vec3<f32>,
    error: vec3<f32>,
}

// v0 + b1 (v1 - v0) + b2 (v2 - v0); bounds as in the Rust twin.
fn triangle_point(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, b1: f32, b2: f32) -> SurfacePoint {
    let along1 = b1 * (v1 - v0);
    let along2 = b2 * (v2 - v0);
    let position = v0 + (along1 + along2);
    return SurfacePoint(position, gamma(3.0) * (abs(along1) + abs(along2)) + gamma(1.0) * abs(position));
}

fn quad_point(corner: vec3<f32>, edge_u: vec3<f32>, edge_v: vec3<f32>, u: f32, v: f32) -> SurfacePoint {
    let along_u = u * edge_u;
    let along_v = v * edge_v;
    let position = corner + (along_u + along_v);
    return SurfacePoint(position, gamma(2.0) * (abs(along_u) + abs(along_v)) + gamma(1.0) * abs(position));
}

fn plane_point(ray: RayQuery, t: f32, point: vec3<f32>, normal: vec3<f32>) -> SurfacePoint {
    let raw = ray.origin + t * ray.direction;
    let from_point = raw - point;
    let position = raw - dot(from_point, normal) * normal;
    let size = abs(from_point);
    return SurfacePoint(position, vec3<f32>(gamma(5.0) * max(max(size.x, size.y), size.z)) + gamma(1.0) * abs(position));
}

// A point on a curved primitive and the surface's outward normal there.
struct CurvedPoint {
    point: SurfacePoint,
    outward: vec3<f32>,
}

// The ray's point or the re-projection onto the sphere, whichever has the smaller error bound.
fn sphere_surface_point(ray: RayQuery, hit: Hit, center: vec3<f32>, radius: f32) -> CurvedPoint {
    let along = hit.t * ray.direction;
    let on_ray = ray.origin + along;
    let outward = normalize((ray.origin - center) + along);
    let t_error = hit.t * hit.b1;
    let on_ray_error = gamma(1.0) * (abs(on_ray) + abs(along)) + t_error * abs(ray.direction);
    let scaled_normal = radius * outward;
    let projected = center + scaled_normal;
    let projected_error = gamma(4.0) * abs(scaled_normal) + gamma(1.0) * abs(projected);
    let normal_size = abs(outward);
    if (dot(normal_size, on_ray_error) < dot(normal_size, projected_error)) {
        return CurvedPoint(SurfacePoint(on_ray, on_ray_error), outward);
    }
    return CurvedPoint(SurfacePoint(projected, projected_error), outward);
}

fn next_float_up(v: f32) -> f32 {
    if (v == 0.0) {
        return bitcast<f32>(1u);
    }
    if (v > 0.0) {
        return bitcast<f32>(bitcast<u32>(v) + 1u);
    }
    return bitcast<f32>(bitcast<u32>(v) - 1u);
}

fn round_away(v: f32, sign: f32) -> f32 {
    if (sign > 0.0) {
        return next_float_up(v);
    }
    if (sign < 0.0) {
        return -next_float_up(-v);
    }
    return v;
}

// pbrt-v4's OffsetRayOrigin: off the surface by the error bound projected on n, one ULP more.
fn offset_ray_origin(position: vec3<f32>, error: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let offset = dot(abs(n), error) * n;
    let moved = position + offset;
    return vec3<f32>(round_away(moved.x, offset.x), round_away(moved.y, offset.y), round_away(moved.z, offset.z));
}
