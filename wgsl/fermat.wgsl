// Reflections on a sphere by Fermat's principle: one invocation finds, for one scene vertex V
// and the eye E, the point P of the sphere where E -> P -> V has extremal length, by the seed's
// search on a triangle in the (u, v) plane (see src/fermat.rs for the method), in f32.
// Mirrors: src/fermat.rs (Sphere::facing, initial_triangle, replaced_corner, Solver::solve),
// step for step; the search's constants come from src/layout.rs.

// Steps at most: the seed's 5 unless the pipeline overrides it (`gpu::fermat::FermatPass`).
override FERMAT_STEPS: u32 = 5u;
const FERMAT_MIN_SIZE: f32 = 1e-7;
const TAU: f32 = 6.283185307179586;

// The sphere's parametrisation frame facing E and V: x toward the bisector, y (the poles' axis)
// the normal of the plane through E, V and the centre.
struct Facing {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
}

fn facing(e: vec3<f32>, v: vec3<f32>) -> Facing {
    let en = normalize(e);
    var x = en + normalize(v);
    x = select(en, normalize(x), length(x) > 0.0);
    let n = cross(e, v);
    var y: vec3<f32>;
    if (length(n) > 1e-6 * length(e) * length(v)) {
        y = normalize(n);
    } else {
        // glam's any_orthonormal_vector (Frisvad's construction, as the Rust twin uses).
        let sign = select(-1.0, 1.0, x.z >= 0.0);
        let a = -1.0 / (sign + x.z);
        let b = x.x * x.y * a;
        y = vec3<f32>(b, sign + x.y * x.y * a, -x.y);
    }
    return Facing(x, y, cross(x, y));
}

fn sphere_point(f: Facing, uv: vec2<f32>) -> vec3<f32> {
    let su = sin(uv.x);
    let cu = cos(uv.x);
    let sv = sin(uv.y);
    let cv = cos(uv.y);
    return reflector.center + reflector.radius * (sv * (cu * f.x + su * f.z) + cv * f.y);
}

fn sphere_parameters(f: Facing, d: vec3<f32>) -> vec2<f32> {
    let n = normalize(d);
    return vec2<f32>(atan2(dot(n, f.z), dot(n, f.x)), acos(clamp(dot(n, f.y), -1.0, 1.0)));
}

fn fermat_gradient(f: Facing, eye: vec3<f32>, vertex: vec3<f32>, uv: vec2<f32>) -> vec2<f32> {
    let su = sin(uv.x);
    let cu = cos(uv.x);
    let sv = sin(uv.y);
    let cv = cos(uv.y);
    let p = reflector.center + reflector.radius * (sv * (cu * f.x + su * f.z) + cv * f.y);
    let fu = reflector.radius * sv * (-su * f.x + cu * f.z);
    let fv = reflector.radius * (cv * (cu * f.x + su * f.z) - sv * f.y);
    let pull = normalize(eye - p) + normalize(vertex - p);
    return vec2<f32>(-dot(fu, pull), -dot(fv, pull));
}

// Twice the area of the corners with corner k replaced by p, against its longest side squared.
fn flat_with(corners: array<vec2<f32>, 3>, k: u32, p: vec2<f32>) -> bool {
    var t = corners;
    t[k] = p;
    let longest = max(max(dot(t[1] - t[0], t[1] - t[0]), dot(t[2] - t[1], t[2] - t[1])),
        dot(t[0] - t[2], t[0] - t[2]));
    let e0 = t[1] - t[0];
    let e1 = t[2] - t[0];
    return abs(e0.x * e1.y - e0.y * e1.x) < FERMAT_FLAT * longest;
}

// The corner p replaces: the farthest from it, or the next farthest where that would leave a
// flat triangle (src/fermat.rs `replaced_corner`; ties go to the later corner on both sides).
fn replaced_corner(corners: array<vec2<f32>, 3>, p: vec2<f32>) -> u32 {
    var taken = array<bool, 3>(false, false, false);
    var farthest = 0u;
    for (var rank = 0u; rank < 3u; rank += 1u) {
        var pick = 0u;
        var far = -1.0;
        for (var k = 0u; k < 3u; k += 1u) {
            let d = length(corners[k] - p);
            if (!taken[k] && d >= far) {
                far = d;
                pick = k;
            }
        }
        taken[pick] = true;
        if (rank == 0u) {
            farthest = pick;
        }
        if (!flat_with(corners, pick, p)) {
            return pick;
        }
    }
    return farthest;
}

@compute @workgroup_size(64, 1, 1)
fn fermat(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= reflector.count) {
        return;
    }
    let eye = reflector.eye;
    let vertex = fermat_vertices[i].xyz;
    let f = facing(eye - reflector.center, vertex - reflector.center);
    // The initial triangle: A and B where E -> O and V -> O cross the sphere, C off AB.
    let a0 = sphere_parameters(f, eye - reflector.center);
    var b0 = sphere_parameters(f, vertex - reflector.center);
    b0.x += TAU * round((a0.x - b0.x) / TAU);
    let side = b0 - a0;
    var corners: array<vec2<f32>, 3>;
    corners[0] = a0;
    if (length(side) > FERMAT_SPREAD) {
        corners[1] = b0;
        corners[2] = (a0 + b0) / 2.0 + vec2<f32>(-side.y, side.x) * FERMAT_C_OFFSET;
    } else {
        corners[1] = a0 + vec2<f32>(FERMAT_SPREAD, 0.0);
        corners[2] = a0 + vec2<f32>(FERMAT_SPREAD, FERMAT_SPREAD);
    }
    var best = corners[0];
    var moved = 3.0e38;
    var steps = FERMAT_STEPS;
    var degenerate = 0u;
    for (var step = 0u; step < FERMAT_STEPS; step += 1u) {
        let size = max(max(length(corners[0] - corners[1]), length(corners[1] - corners[2])),
            length(corners[2] - corners[0]));
        if (min(size, moved) < FERMAT_MIN_SIZE) {
            steps = step;
            break;
        }
        let ga = fermat_gradient(f, eye, vertex, corners[0]);
        let gb = fermat_gradient(f, eye, vertex, corners[1]);
        let gc = fermat_gradient(f, eye, vertex, corners[2]);
        let m0 = gb - ga;
        let m1 = gc - ga;
        let det = m0.x * m1.y - m1.x * m0.y;
        if (det == 0.0) {
            steps = step;
            degenerate = 1u;
            break;
        }
        let alpha = (-ga.x * m1.y + m1.x * ga.y) / det;
        let beta = (-m0.x * ga.y + ga.x * m0.y) / det;
        let p = (1.0 - alpha - beta) * corners[0] + alpha * corners[1] + beta * corners[2];
        corners[replaced_corner(corners, p)] = p;
        moved = length(p - best);
        best = p;
    }
    let point = sphere_point(f, best);
    reflections[i] = GpuReflection(point, steps, best, length(vertex - point), degenerate);
}
