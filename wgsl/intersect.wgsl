// Ray/primitive intersection: watertight triangles, robust spheres, quads, planes, slabs,
// and the integer-ULP origin offset.
// Mirrors: src/accel/intersect.rs (references there).

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
}

struct Hit {
    t: f32,
    b1: f32,
    b2: f32,
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
        vec3<f32>(-direction[kx] / dz, -direction[ky] / dz, 1.0 / dz));
}

fn lexicographic_less(a: vec3<f32>, b: vec3<f32>) -> bool {
    return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)));
}

fn edge_function(p: vec2<f32>, q: vec2<f32>, vp: vec3<f32>, vq: vec3<f32>) -> f32 {
    if (lexicographic_less(vq, vp)) {
        return -(q.x * p.y - q.y * p.x);
    }
    return p.x * q.y - p.y * q.x;
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
    let e0 = edge_function(p1, p2, v1, v2);
    let e1 = edge_function(p2, p0, v2, v0);
    let e2 = edge_function(p0, p1, v0, v1);
    if ((e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0)) {
        return miss();
    }
    let det = e0 + e1 + e2;
    if (det == 0.0) {
        return miss();
    }
    // Scaled distance, compared against t_max * det to avoid the division until a hit.
    let t_scaled = e0 * (s.z * a[ray.kz]) + e1 * (s.z * b[ray.kz]) + e2 * (s.z * c[ray.kz]);
    if (det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det)) {
        return miss();
    }
    if (det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det)) {
        return miss();
    }
    let inv_det = 1.0 / det;
    return Hit(t_scaled * inv_det, e1 * inv_det, e2 * inv_det);
}

fn intersect_sphere(ray: RayQuery, center: vec3<f32>, radius: f32, t_max: f32) -> Hit {
    let f = ray.origin - center;
    let b = dot(f, ray.direction);
    // r^2 - |f - (f.d) d|^2 instead of b^2 - (|f|^2 - r^2): no cancellation far from the sphere.
    let perpendicular = f - b * ray.direction;
    let discriminant = radius * radius - dot(perpendicular, perpendicular);
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
    let c = dot(f, f) - radius * radius;
    let t0 = min(c / q, q);
    let t1 = max(c / q, q);
    var t = t1;
    if (t0 > 0.0) {
        t = t0;
    }
    if (t <= 0.0 || t >= t_max) {
        return miss();
    }
    return Hit(t, 0.0, 0.0);
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
        case PRIM_SPHERE: { return intersect_sphere(ray, prim.p0, prim.p1.x, t_max); }
        case PRIM_QUAD: { return intersect_quad(ray, prim.p0, prim.p1, prim.p2, t_max); }
        case PRIM_PLANE: { return intersect_plane(ray, prim.p0, prim.p1, t_max); }
        default: { return miss(); }
    }
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

fn offset_component(p: f32, n: f32) -> f32 {
    let of_i = i32(256.0 * n);
    var delta = of_i;
    if (p < 0.0) {
        delta = -of_i;
    }
    let moved = bitcast<f32>(bitcast<i32>(p) + delta);
    if (abs(p) < 1.0 / 32.0) {
        return p + (1.0 / 65536.0) * n;
    }
    return moved;
}

fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}
