// Exact ray intersection with ellipsoids, open cylinders and tori, and their shading points.
// Mirrors: src/accel/curved.rs (the method and its error bounds are explained there).

// Twin of `layout::leaving_rays_skip`: whether rays leaving a primitive (from its outside,
// for a curved one) may skip it.
fn leaving_rays_skip(kind: u32, outside: bool) -> bool {
    switch kind {
        case PRIM_SPHERE, PRIM_ELLIPSOID: { return outside; }
        case PRIM_CYLINDER, PRIM_TORUS: { return false; }
        default: { return true; }
    }
}

// The roots of a t^2 + 2 b t + c = 0 in increasing order and a bound on their error
// (x, y, z); found = false where there are none.
struct QuadraticRoots {
    found: bool,
    roots: vec3<f32>,
}

fn quadratic_roots(a: f32, b: f32, c: f32, discriminant: f32, c_size: f32) -> QuadraticRoots {
    if (discriminant < 0.0 || a == 0.0) {
        return QuadraticRoots(false, vec3<f32>(0.0));
    }
    let root = sqrt(discriminant);
    let q = select(-b + root, -b - root, b >= 0.0);
    if (q == 0.0) {
        return QuadraticRoots(false, vec3<f32>(0.0));
    }
    let t0 = q / a;
    let t1 = c / q;
    let error = gamma(8.0) * (c_size / abs(q) + abs(q) / a);
    return QuadraticRoots(true, vec3<f32>(min(t0, t1), max(t0, t1), error));
}

// The curved tests take the ray in the shape's own frame (`ray_in_frame`).
fn intersect_ellipsoid(ray: FrameRay, radii: vec3<f32>, t_max: f32) -> Hit {
    let f = ray.origin / radii;
    let e = ray.direction / radii;
    let a = dot(e, e);
    let f2 = dot(f, f);
    let fe = cross(f, e);
    let found = quadratic_roots(a, dot(f, e), f2 - 1.0, a - dot(fe, fe), f2 + 1.0);
    if (!found.found) {
        return miss();
    }
    let error = found.roots.z;
    let t = select(found.roots.y, found.roots.x, found.roots.x > error);
    if (t <= error || t >= t_max) {
        return miss();
    }
    return Hit(t, 0.0, 0.0);
}

fn intersect_cylinder(ray: FrameRay, radius: f32, height: f32, t_max: f32) -> Hit {
    let f = ray.origin;
    let d = ray.direction;
    let a = d.x * d.x + d.z * d.z;
    let f2 = f.x * f.x + f.z * f.z;
    let cross_y = f.x * d.z - f.z * d.x;
    let discriminant = a * radius * radius - cross_y * cross_y;
    let c_size = f2 + radius * radius;
    let b = f.x * d.x + f.z * d.z;
    let found = quadratic_roots(a, b, f2 - radius * radius, discriminant, c_size);
    if (!found.found) {
        return miss();
    }
    for (var k = 0; k < 2; k += 1) {
        let t = select(found.roots.y, found.roots.x, k == 0);
        let y = f.y + t * d.y;
        if (t > found.roots.z && t < t_max && y >= 0.0 && y <= height) {
            return Hit(t, 0.0, 0.0);
        }
    }
    return miss();
}

// (value, derivative) of c[0] + c[1] x + ... + c[4] x^4, by Horner's rule.
fn polynomial(c: array<f32, 5>, x: f32) -> vec2<f32> {
    var value = c[4];
    var derivative = 0.0;
    derivative = derivative * x + value;
    value = value * x + c[3];
    derivative = derivative * x + value;
    value = value * x + c[2];
    derivative = derivative * x + value;
    value = value * x + c[1];
    derivative = derivative * x + value;
    value = value * x + c[0];
    return vec2<f32>(value, derivative);
}

// The root of `poly` in (lo, hi) where it changes sign there (x), found = y > 0: Newton's
// method kept inside the bracket.
fn bracketed_root(poly: array<f32, 5>, lo_in: f32, hi_in: f32) -> vec2<f32> {
    let f_lo = polynomial(poly, lo_in).x;
    let f_hi = polynomial(poly, hi_in).x;
    if (!(hi_in > lo_in && f_lo * f_hi < 0.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    var lo = lo_in;
    var hi = hi_in;
    var x = 0.5 * (lo + hi);
    for (var step = 0u; step < TORUS_ROOT_STEPS; step += 1u) {
        let p = polynomial(poly, x);
        if (p.x == 0.0) {
            return vec2<f32>(x, 1.0);
        }
        if ((p.x < 0.0) == (f_lo < 0.0)) {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - p.x / p.y;
        var next = 0.5 * (lo + hi);
        if (newton > lo && newton < hi) {
            next = newton;
        }
        if (next == x) {
            break;
        }
        x = next;
    }
    return vec2<f32>(x, 1.0);
}

// The quartic's root polished by Newton steps on the torus's signed distance, no farther than
// TORUS_POLISH_REACH times its error bound from it (see the Rust twin).
fn polish_torus_root(f: vec3<f32>, d: vec3<f32>, major: f32, minor: f32, along: f32, error: f32) -> f32 {
    var x = along;
    for (var step = 0u; step < TORUS_POLISH_STEPS; step += 1u) {
        let p = f + x * d;
        let rho = sqrt(p.x * p.x + p.z * p.z);
        if (rho == 0.0) {
            break;
        }
        let w = vec3<f32>(p.x * (1.0 - major / rho), p.y, p.z * (1.0 - major / rho));
        let distance = length(w);
        let slope = dot(w, d) / distance;
        if (distance == 0.0 || slope == 0.0) {
            break;
        }
        let next = x - (distance - minor) / slope;
        if (!(abs(next - along) <= TORUS_POLISH_REACH * error)) {
            break;
        }
        x = next;
    }
    return x;
}

fn intersect_torus(ray: FrameRay, major: f32, minor: f32, t_max: f32) -> Hit {
    let reach = major + minor;
    let f = ray.origin;
    let len = length(ray.direction);
    let d = ray.direction / len;
    let along = dot(f, d);
    let perpendicular = f - along * d;
    let bound = reach * (1.0 + gamma(4.0));
    let discriminant = bound * bound - dot(perpendicular, perpendicular);
    if (discriminant < 0.0) {
        return miss();
    }
    let half_chord = sqrt(discriminant);
    let enter = -along - half_chord;
    let exit = -along + half_chord;
    let t_limit = t_max * len;
    if (exit <= 0.0 || enter >= t_limit) {
        return miss();
    }
    // Start and end beyond the bounding sphere, which the equator touches (see the Rust twin).
    let margin = TORUS_MARGIN * reach;
    let start = max(enter - margin, 0.0);
    let scale = 1.0 / reach;
    let o = (f + start * d) * scale;
    let major_s = major * scale;
    let minor_s = minor * scale;
    // The quartic F(o + s d) (see TorusQuartic::new).
    let b = dot(o, d);
    let e = dot(o, o) + (major_s - minor_s) * (major_s + minor_s);
    let h2 = d.x * d.x + d.z * d.z;
    let h1 = o.x * d.x + o.z * d.z;
    let h0 = o.x * o.x + o.z * o.z;
    let k = 4.0 * major_s * major_s;
    let c = array<f32, 5>(e * e - k * h0, 4.0 * b * e - 2.0 * k * h1, 4.0 * b * b + 2.0 * e - k * h2, 4.0 * b, 1.0);
    let size = array<f32, 5>(e * e + k * h0, 4.0 * abs(b * e) + 2.0 * k * abs(h1),
                             4.0 * b * b + 2.0 * abs(e) + k * h2, 4.0 * abs(b), 1.0);
    let span = (min(exit + margin, t_limit) - start) * scale;
    let derivative = array<f32, 5>(c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4], 0.0);
    // F''/2 = 6 c4 s^2 + 3 c3 s + c2: its roots bound where F' is monotone.
    var splits = vec2<f32>(0.0);
    let inflections = quadratic_roots(6.0 * c[4], 1.5 * c[3], c[2], 2.25 * c[3] * c[3] - 6.0 * c[4] * c[2], abs(c[2]));
    if (inflections.found) {
        splits = inflections.roots.xy;
    }
    // Where F' vanishes (monotone_roots): F is monotone between consecutive ones.
    var pieces = array<f32, 4>(0.0, span, span, span);
    var piece_count = 1u;
    for (var k2 = 0u; k2 < 2u; k2 += 1u) {
        let split = splits[k2];
        if (split > 0.0 && split < span && split > pieces[piece_count - 1u]) {
            pieces[piece_count] = split;
            piece_count += 1u;
        }
    }
    pieces[piece_count] = span;
    var ends = array<f32, 4>(span, span, span, span);
    var count = 0u;
    for (var i = 0u; i < piece_count; i += 1u) {
        let flat_point = bracketed_root(derivative, pieces[i], pieces[i + 1u]);
        if (flat_point.y > 0.0) {
            ends[count] = flat_point.x;
            count += 1u;
        }
    }
    for (var i = 0u; i <= count; i += 1u) {
        var lo = 0.0;
        if (i > 0u) {
            lo = ends[i - 1u];
        }
        let root = bracketed_root(c, lo, ends[i]);
        if (root.y > 0.0) {
            let s = root.x;
            let error = gamma(16.0) * polynomial(size, s).x / abs(polynomial(c, s).y);
            if (s > error) {
                let distance = polish_torus_root(f, d, major, minor, start + s * reach, error * reach);
                let t = distance / len;
                if (t < t_max) {
                    return Hit(t, 0.0, 0.0);
                }
            }
        }
    }
    return miss();
}

// A curved primitive's orientation (src/accel/curved.rs `orientation`): x, y, z in p2, w's
// bits in the normals word.
fn prim_orientation(prim: GpuPrimitive) -> vec4<f32> {
    return vec4<f32>(prim.p2, bitcast<f32>(prim.normals));
}

// A ray in a curved shape's own frame: all the curved tests read.
struct FrameRay {
    origin: vec3<f32>,
    direction: vec3<f32>,
}

// The ray in the shape's own frame, its centre at the origin (`ray_in_frame`). An identity
// orientation turns exactly; turning always measured faster on lavapipe than skipping it for
// the identity, as the Rust twin does (2-4% of the curved-mirror scenes' frames).
fn ray_in_frame(ray: RayQuery, center: vec3<f32>, q: vec4<f32>) -> FrameRay {
    return FrameRay(turn(conjugate(q), ray.origin - center), turn(conjugate(q), ray.direction));
}

// The shading point found in the own frame taken to the world's (`curved_surface_point`,
// `point_to_world`).
fn curved_surface_point(ray: RayQuery, t: f32, prim: GpuPrimitive) -> CurvedPoint {
    let q = prim_orientation(prim);
    let turned = any(q.xyz != vec3<f32>(0.0));
    let local = ray_in_frame(ray, prim.p0, q);
    var found: CurvedPoint;
    if (prim.kind == PRIM_ELLIPSOID) {
        found = ellipsoid_surface_point(local, t, prim.p1);
    } else if (prim.kind == PRIM_CYLINDER) {
        found = cylinder_surface_point(local, t, prim.p1.x);
        // Its height is the ray's, whose origin was turned into the frame.
        if (turned) {
            found.point.error.y += gamma(32.0) * length(local.origin);
        }
    } else {
        found = torus_surface_point(local, t, prim.p1.x, prim.p1.y);
    }
    if (!turned) {
        let position = prim.p0 + found.point.position;
        return CurvedPoint(SurfacePoint(position, found.point.error + gamma(1.0) * abs(position)), found.outward);
    }
    let offset = turn(q, found.point.position);
    let position = prim.p0 + offset;
    // A bound per component turned is at most the bound's length in each; both rotations round.
    let error = vec3<f32>(length(found.point.error) + gamma(32.0) * (2.0 * length(offset)));
    return CurvedPoint(SurfacePoint(position, error + gamma(1.0) * abs(position)), turn(q, found.outward));
}

fn ellipsoid_surface_point(ray: FrameRay, t: f32, radii: vec3<f32>) -> CurvedPoint {
    let unit = normalize((ray.origin + t * ray.direction) / radii);
    let position = radii * unit;
    let outward = normalize(unit / radii);
    return CurvedPoint(SurfacePoint(position, gamma(6.0) * abs(position)), outward);
}

fn cylinder_surface_point(ray: FrameRay, t: f32, radius: f32) -> CurvedPoint {
    let along = t * ray.direction;
    let local = ray.origin + along;
    let outward = normalize(vec3<f32>(local.x, 0.0, local.z));
    let position = vec3<f32>(radius * outward.x, local.y, radius * outward.z);
    let height_error = gamma(3.0) * (abs(ray.origin.y) + abs(along.y));
    return CurvedPoint(SurfacePoint(position, vec3<f32>(gamma(5.0) * radius, height_error, gamma(5.0) * radius)), outward);
}

fn torus_surface_point(ray: FrameRay, t: f32, major: f32, minor: f32) -> CurvedPoint {
    let local = ray.origin + t * ray.direction;
    let horizontal = vec3<f32>(local.x, 0.0, local.z);
    let horizontal_length = length(horizontal);
    var around = vec3<f32>(1.0, 0.0, 0.0);
    if (horizontal_length > 0.0) {
        around = horizontal / horizontal_length;
    }
    let ring = major * around;
    let outward = normalize(local - ring);
    let position = ring + minor * outward;
    return CurvedPoint(SurfacePoint(position, vec3<f32>(gamma(6.0) * (major + minor))), outward);
}
