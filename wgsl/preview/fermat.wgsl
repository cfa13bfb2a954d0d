// Reflections on a sphere, torus, Bézier patch, ellipsoid or cylinder by Fermat's principle:
// one invocation finds, for one scene vertex V and the eye E, the point P of the reflector
// where E -> P -> V has extremal length, by the search on a triangle in the (u, v) plane (see
// src/preview/reflections/fermat.rs for the method), in f32, step for step as its twin; the
// search's constants come from src/layout.rs.
// Mirrors: src/preview/reflections/fermat.rs (the Reflector impls, TorusSearch, on_patch,
// on_cylinder, initial_triangle, replaced_corner, Solver::solve, sampled_start, solve_on_patch,
// anchored_on_patch, anchored_on_torus_half), src/scene/parametric.rs (Sphere, Sphere::facing,
// Torus, BezierPatch, Ellipsoid, Cylinder: the surfaces' points, tangents and normals).

// Steps at most: Roger and Holzschuch's 5 unless the pipeline overrides it (`preview::reflections::kernel::FermatPass`).
override FERMAT_STEPS: u32 = 5u;
// The reflector's kind (`REFLECTOR_SPHERE`, ...): a pipeline per kind, so that each carries
// only its own surface's code (`preview::reflections::kernel::FermatPass`).
override REFLECTOR_KIND: u32 = 0u;
// Whether a patch's own points are searched again where Roger and Holzschuch's corners find nothing (with
// self-reflections: `preview::reflections::kernel::FermatPass`).
override OWN_POINTS_SEARCHED_AGAIN: bool = false;
// The search stops when its triangle's longest side in (u, v), or its last step, is below this.
// In f32 the gradients' rounding keeps a converged search jittering about 1e-7 (u, v near 0.5
// are 6e-8 apart): at 1e-7, 2,215 of a teapot's 10,048 searches ran all 12 steps; at 1e-6 they
// take 18% fewer steps and their points lie as near f64's (99% within 1.3e-6 of the teapot's
// 1-unit height, 1e-4 px; measured with `chambre bench fermat`, docs/fermat.md).
const FERMAT_MIN_SIZE: f32 = 1e-6;
// The invocation's search (its row of the dispatch, `global_invocation_id.y`): the surface
// functions below read `reflectors[search]`, the same element across a workgroup, rather than
// a private copy of it per invocation.
var<private> search: u32;
const TAU: f32 = 6.283185307179586;

// The parametrisation's frame for one vertex: a sphere's faces E and V, x toward the
// bisector, y (the poles' axis) the normal of the plane through E, V and the centre (an
// ellipsoid's the same in its unit sphere's coordinates); the others' is their own axes.
struct Frame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
}

fn facing(e: vec3<f32>, v: vec3<f32>) -> Frame {
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
    return Frame(x, y, cross(x, y));
}

fn frame_for(eye: vec3<f32>, vertex: vec3<f32>) -> Frame {
    if (REFLECTOR_KIND == REFLECTOR_SPHERE) {
        return facing(eye - reflectors[search].center, vertex - reflectors[search].center);
    }
    if (REFLECTOR_KIND == REFLECTOR_ELLIPSOID) {
        // The unit sphere's frame facing E and V mapped into it (`Ellipsoid::facing`).
        let radii = reflectors[search].radii.xyz;
        return facing((eye - reflectors[search].center) / radii, (vertex - reflectors[search].center) / radii);
    }
    return Frame(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
}

// f(u, v) and its tangents f_u, f_v: `Sphere`, `Torus`, `Ellipsoid`, `Cylinder` and
// `BezierPatch` in src/preview/reflections/fermat.rs, in the frame f (u around y).
struct SurfacePoint {
    p: vec3<f32>,
    fu: vec3<f32>,
    fv: vec3<f32>,
}

fn surface(f: Frame, uv: vec2<f32>) -> SurfacePoint {
    if (REFLECTOR_KIND == REFLECTOR_PATCH) {
        return patch_surface(uv);
    }
    let su = sin(uv.x);
    let cu = cos(uv.x);
    let sv = sin(uv.y);
    let cv = cos(uv.y);
    let around = cu * f.x + su * f.z;
    let along = -su * f.x + cu * f.z;
    if (REFLECTOR_KIND == REFLECTOR_TORUS) {
        let r = reflectors[search].minor;
        let ring = reflectors[search].radius + r * cv;
        return SurfacePoint(reflectors[search].center + ring * around + r * sv * f.y, ring * along,
            r * (-sv * around + cv * f.y));
    }
    if (REFLECTOR_KIND == REFLECTOR_CYLINDER) {
        let r = reflectors[search].radius;
        return SurfacePoint(reflectors[search].center + r * around + uv.y * f.y, r * along, f.y);
    }
    if (REFLECTOR_KIND == REFLECTOR_ELLIPSOID) {
        let a = reflectors[search].radii.xyz;
        return SurfacePoint(reflectors[search].center + a * (sv * around + cv * f.y), a * (sv * along),
            a * (cv * around - sv * f.y));
    }
    let r = reflectors[search].radius;
    return SurfacePoint(reflectors[search].center + r * (sv * around + cv * f.y), r * sv * along,
        r * (cv * around - sv * f.y));
}

// The cubic Bernstein polynomials at t (xyzw: B_0..B_3) and their derivatives.
struct Bernstein {
    b: vec4<f32>,
    d: vec4<f32>,
}

fn bernstein(t: f32) -> Bernstein {
    let s = 1.0 - t;
    return Bernstein(vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t),
        vec4<f32>(-3.0 * s * s, 3.0 * s * s - 6.0 * t * s, 6.0 * t * s - 3.0 * t * t,
        3.0 * t * t));
}

// The point and tangents at (u, v): Σ B_i(u) B_j(v) P_ij and its derivatives, each row of
// control points first summed over j (once with B_j(v), once with B_j'(v)), so that every
// control point is read once.
fn patch_surface(uv: vec2<f32>) -> SurfacePoint {
    let bu = bernstein(uv.x);
    let bv = bernstein(uv.y);
    var p = vec3<f32>(0.0);
    var fu = vec3<f32>(0.0);
    var fv = vec3<f32>(0.0);
    for (var i = 0u; i < 4u; i += 1u) {
        var row = vec3<f32>(0.0);
        var row_dv = vec3<f32>(0.0);
        for (var j = 0u; j < 4u; j += 1u) {
            let point = reflectors[search].control[4u * i + j].xyz;
            row += bv.b[j] * point;
            row_dv += bv.d[j] * point;
        }
        p += bu.b[i] * row;
        fu += bu.d[i] * row;
        fv += bu.b[i] * row_dv;
    }
    return SurfacePoint(p, fu, fv);
}

// A patch has no inside: O a patch-size behind its centre, against the normal there.
fn patch_inside() -> vec3<f32> {
    let centre = patch_surface(vec2<f32>(0.5));
    let size = length(reflectors[search].control[15].xyz - reflectors[search].control[0].xyz);
    return centre.p - size * normalize(cross(centre.fu, centre.fv));
}

// Where the segment from `outside` to O crosses the patch: Newton steps on
// f(u, v) = O + t (outside - O) from the patch's centre, clamped to the patch, until a step
// moves less than PATCH_CROSSING_DONE. Run for each vertex; the eye's crossing, the same for
// every vertex, the CPU finds once a frame (`GpuReflector::eye_uv`). O is found here too:
// read from storage inside the Newton loop, it cost lavapipe more than the evaluation it
// saves (BENCHMARKS.md, 2026-11-25).
fn patch_crossing(outside: vec3<f32>) -> vec2<f32> {
    let o = patch_inside();
    let d = outside - o;
    var uvt = vec3<f32>(0.5);
    for (var k = 0u; k < 8u; k += 1u) {
        let s = patch_surface(uvt.xy);
        let r = s.p - (o + uvt.z * d);
        // Cramer's rule on the columns f_u, f_v, -d.
        let c = -d;
        let det = dot(s.fu, cross(s.fv, c));
        if (det == 0.0) {
            break;
        }
        let step = vec3<f32>(dot(r, cross(s.fv, c)), dot(s.fu, cross(r, c)),
            dot(s.fu, cross(s.fv, r))) / det;
        let next = clamp(uvt - step, vec3<f32>(0.0), vec3<f32>(1.0));
        let moved = length(next - uvt);
        uvt = next;
        if (moved < PATCH_CROSSING_DONE) {
            break;
        }
    }
    return uvt.xy;
}

// n normalised, or zero where it is zero (a patch's degenerate corner), as glam's.
fn normalize_or_zero(n: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), normalize(n), length(n) > 0.0);
}

// The outward unit normal at (u, v) of the closed forms (all kinds but a patch: `normal_at`).
fn surface_normal(f: Frame, uv: vec2<f32>) -> vec3<f32> {
    let around = cos(uv.x) * f.x + sin(uv.x) * f.z;
    if (REFLECTOR_KIND == REFLECTOR_TORUS) {
        return cos(uv.y) * around + sin(uv.y) * f.y;
    }
    if (REFLECTOR_KIND == REFLECTOR_CYLINDER) {
        return around;
    }
    let unit = sin(uv.y) * around + cos(uv.y) * f.y;
    if (REFLECTOR_KIND == REFLECTOR_ELLIPSOID) {
        // The gradient of |(x - c) / a|^2: (x - c) / a^2, with x - c = a * unit.
        return normalize(unit / reflectors[search].radii.xyz);
    }
    return unit;
}

// The outward unit normal at (u, v), where `s` is the surface there: a patch's from the
// tangents already evaluated, rather than evaluating the patch again.
fn normal_at(f: Frame, uv: vec2<f32>, s: SurfacePoint) -> vec3<f32> {
    if (REFLECTOR_KIND == REFLECTOR_PATCH) {
        return normalize_or_zero(cross(s.fu, s.fv));
    }
    return surface_normal(f, uv);
}

// Where the segment from `outside` (|outside| > 1) to `inside` (|inside| < 1) crosses the unit
// sphere about the origin (`unit_sphere_crossing` in src/preview/reflections/fermat.rs).
fn unit_sphere_crossing(outside: vec3<f32>, inside: vec3<f32>) -> vec3<f32> {
    let w = inside - outside;
    let a = dot(w, w);
    let b = dot(outside, w);
    let c = dot(outside, outside) - 1.0;
    let q = -b + sqrt(max(b * b - a * c, 0.0));
    return outside + (c / q) * w;
}

// The parameters where the segment from `outside` to the point O inside the reflector crosses
// it: O FERMAT_INSIDE of the sphere's or ellipsoid's radius from the centre toward the
// bisector of E and V (the frame's x; in the ellipsoid's unit sphere's coordinates), the point
// of the torus's tube circle at `outside`'s azimuth, or the cylinder's axis point at
// `outside`'s height.
fn crossing(f: Frame, outside: vec3<f32>) -> vec2<f32> {
    if (REFLECTOR_KIND == REFLECTOR_PATCH) {
        return patch_crossing(outside);
    }
    let d = outside - reflectors[search].center;
    if (REFLECTOR_KIND == REFLECTOR_SPHERE || REFLECTOR_KIND == REFLECTOR_ELLIPSOID) {
        // In the unit sphere's coordinates (the frame's too): d over the radius, or the radii.
        let radii = select(vec3<f32>(reflectors[search].radius), reflectors[search].radii.xyz,
            REFLECTOR_KIND == REFLECTOR_ELLIPSOID);
        let n = normalize(unit_sphere_crossing(d / radii, FERMAT_INSIDE * f.x));
        return vec2<f32>(atan2(dot(n, f.z), dot(n, f.x)), acos(clamp(dot(n, f.y), -1.0, 1.0)));
    }
    let u = atan2(dot(d, f.z), dot(d, f.x));
    if (REFLECTOR_KIND == REFLECTOR_TORUS) {
        let flat = vec3<f32>(d.x, 0.0, d.z);
        let radial = select(vec3<f32>(1.0, 0.0, 0.0), normalize(flat), length(flat) > 0.0);
        let w = d - reflectors[search].radius * radial;
        return vec2<f32>(u, atan2(w.y, dot(w, vec3<f32>(cos(u), 0.0, sin(u)))));
    }
    return vec2<f32>(u, d.y);
}

// The torus's inner equator (v = pi) across the hole from `x`'s azimuth
// (`Torus::across_the_hole`).
fn across_the_hole(x: vec3<f32>) -> vec2<f32> {
    let d = x - reflectors[search].center;
    return vec2<f32>(atan2(d.z, d.x) + 0.5 * TAU, 0.5 * TAU);
}

fn fermat_gradient(f: Frame, eye: vec3<f32>, vertex: vec3<f32>, uv: vec2<f32>) -> vec2<f32> {
    let s = surface(f, uv);
    let pull = normalize(eye - s.p) + normalize(vertex - s.p);
    return vec2<f32>(-dot(s.fu, pull), -dot(s.fv, pull));
}

// The search's triangle. Its corners are three variables, not an array: a private array
// indexed at run time (the corner a step replaces) is kept in memory, each lane's element
// gathered and scattered apart, where three variables stay in registers.
struct Triangle {
    a: vec2<f32>,
    b: vec2<f32>,
    c: vec2<f32>,
}

// The triangle with corner k replaced by p.
fn with_corner(t: Triangle, k: u32, p: vec2<f32>) -> Triangle {
    return Triangle(select(t.a, p, k == 0u), select(t.b, p, k == 1u), select(t.c, p, k == 2u));
}

// Twice the area of the corners with corner k replaced by p, against its longest side squared.
fn flat_with(corners: Triangle, k: u32, p: vec2<f32>) -> bool {
    let t = with_corner(corners, k, p);
    let longest = max(max(dot(t.b - t.a, t.b - t.a), dot(t.c - t.b, t.c - t.b)),
        dot(t.a - t.c, t.a - t.c));
    let e0 = t.b - t.a;
    let e1 = t.c - t.a;
    return abs(e0.x * e1.y - e0.y * e1.x) < FERMAT_FLAT * longest;
}

// The corner p replaces: the farthest from it, or the next farthest where that would leave a
// flat triangle (src/preview/reflections/fermat.rs `replaced_corner`; ties go to the later corner on both sides).
fn replaced_corner(corners: Triangle, p: vec2<f32>) -> u32 {
    let d = vec3<f32>(length(corners.a - p), length(corners.b - p), length(corners.c - p));
    var first = 0u;
    if (d.y >= d.x) {
        first = 1u;
    }
    if (d.z >= max(d.x, d.y)) {
        first = 2u;
    }
    // The other two, the later one taken on a tie.
    let low = select(0u, 1u, first == 0u);
    let high = select(2u, 1u, first == 2u);
    let high_is_farther = select(select(d.x, d.y, high == 1u), d.z, high == 2u)
        >= select(d.x, d.y, low == 1u);
    let second = select(low, high, high_is_farther);
    let third = 3u - first - second;
    if (!flat_with(corners, first, p)) {
        return first;
    }
    if (!flat_with(corners, second, p)) {
        return second;
    }
    if (!flat_with(corners, third, p)) {
        return third;
    }
    return first;
}

// Where a search ended: its parameters, the steps it took, and whether its step system went
// singular.
struct Search {
    best: vec2<f32>,
    steps: u32,
    degenerate: u32,
}

// Roger and Holzschuch's search from initial corners A and B (`fermat::Solver::solve`): the gradients of d
// at A, B and C, the point where their linear interpolation vanishes replacing a corner, until
// the triangle or the step is small or the steps run out.
fn search_from(f: Frame, eye: vec3<f32>, vertex: vec3<f32>, a: vec2<f32>, b_start: vec2<f32>)
    -> Search {
    var b0 = b_start;
    // An azimuthal u (all but a patch's) is unwrapped so that AB takes the short way round.
    if (REFLECTOR_KIND != REFLECTOR_PATCH) {
        b0.x += TAU * round((a.x - b0.x) / TAU);
    }
    let side = b0 - a;
    var corners = Triangle(a, a + vec2<f32>(FERMAT_SPREAD, 0.0),
        a + vec2<f32>(FERMAT_SPREAD, FERMAT_SPREAD));
    if (length(side) > FERMAT_SPREAD) {
        corners = Triangle(a, b0, (a + b0) / 2.0 + vec2<f32>(-side.y, side.x) * FERMAT_C_OFFSET);
    }
    // Each step replaces one corner: the other two keep their gradients.
    var ga = fermat_gradient(f, eye, vertex, corners.a);
    var gb = fermat_gradient(f, eye, vertex, corners.b);
    var gc = fermat_gradient(f, eye, vertex, corners.c);
    var best = corners.a;
    var moved = 3.0e38;
    for (var step = 0u; step < FERMAT_STEPS; step += 1u) {
        let size = max(max(length(corners.a - corners.b), length(corners.b - corners.c)),
            length(corners.c - corners.a));
        if (min(size, moved) < FERMAT_MIN_SIZE) {
            return Search(best, step, 0u);
        }
        let m0 = gb - ga;
        let m1 = gc - ga;
        let det = m0.x * m1.y - m1.x * m0.y;
        if (det == 0.0) {
            return Search(best, step, 1u);
        }
        let alpha = (-ga.x * m1.y + m1.x * ga.y) / det;
        let beta = (-m0.x * ga.y + ga.x * m0.y) / det;
        let p = (1.0 - alpha - beta) * corners.a + alpha * corners.b + beta * corners.c;
        let replaced = replaced_corner(corners, p);
        corners = with_corner(corners, replaced, p);
        let g = fermat_gradient(f, eye, vertex, p);
        ga = select(ga, g, replaced == 0u);
        gb = select(gb, g, replaced == 1u);
        gc = select(gc, g, replaced == 2u);
        moved = length(p - best);
        best = p;
        // A patch's search a square's width beyond it has left it (`beyond_reach`).
        if (REFLECTOR_KIND == REFLECTOR_PATCH
            && (min(p.x, p.y) < -PATCH_REACH || max(p.x, p.y) > 1.0 + PATCH_REACH)) {
            return Search(best, step + 1u, 0u);
        }
    }
    return Search(best, FERMAT_STEPS, 0u);
}

// A search's point and normal in the world, and whether the preview draws it there.
struct Found {
    point: vec3<f32>,
    normal: vec3<f32>,
    own_point: vec3<f32>,
    shown: bool,
}

// What search `found` found for `vertex` (own frame; `world_vertex` the same in the world's).
fn found_at(f: Frame, found: Search, world_vertex: vec3<f32>) -> Found {
    let q = reflectors[search].orientation;
    let c = reflectors[search].center;
    let best = found.best;
    let s = surface(f, best);
    let own_point = s.p;
    let point = c + turn(q, own_point - c);
    var normal = turn(q, normal_at(f, best, s));
    // A patch's reflection beyond the seam band around its square is none of its own: a zero
    // normal, never seen from outside, so the preview leaves it out (`PATCH_SEAM`).
    // Within the band it lies on the patch's smooth continuation toward its neighbour, and the
    // cull draws it as a corner of a triangle anchored on the patch.
    if (REFLECTOR_KIND == REFLECTOR_PATCH
        && (min(best.x, best.y) < -PATCH_SEAM || max(best.x, best.y) > 1.0 + PATCH_SEAM)) {
        normal = vec3<f32>(0.0);
    }
    // So is a cylinder's beyond its height (`fermat::on_cylinder`): its ends have no neighbour.
    let margin = PATCH_MARGIN;
    let h = reflectors[search].height;
    if (REFLECTOR_KIND == REFLECTOR_CYLINDER
        && (best.y < -margin * h || best.y > (1.0 + margin) * h)) {
        normal = vec3<f32>(0.0);
    }
    let shown = reflection_shows(point, normal, reflectors[search].eye, world_vertex);
    return Found(point, normal, own_point, shown);
}

// The point of a SAMPLED_START_GRID x SAMPLED_START_GRID grid of a patch's parameters where
// the law of reflection fails least for `vertex` seen from `eye` (`fermat::sampled_start`).
fn sampled_start(f: Frame, eye: vec3<f32>, vertex: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(0.0);
    var least = 4.0;
    let side = SAMPLED_START_GRID;
    for (var k = 0u; k < side * side; k += 1u) {
        let uv = vec2<f32>(f32(k % side), f32(k / side)) / f32(side - 1u);
        let s = surface(f, uv);
        let p = s.p;
        let n = normal_at(f, uv, s);
        let bisector = normalize(normalize(eye - p) + normalize(vertex - p));
        let error = 1.0 - dot(n, bisector);
        if (error < least) {
            least = error;
            best = uv;
        }
    }
    return best;
}

@compute @workgroup_size(64, 1, 1)
fn fermat(@builtin(global_invocation_id) id: vec3<u32>) {
    // One row of the dispatch per search; a pipeline solves its kind's searches only.
    search = id.y;
    let i = id.x;
    if (reflectors[search].kind != REFLECTOR_KIND || i >= reflectors[search].count) {
        return;
    }
    // The search runs in the reflector's own frame (a turned torus, ellipsoid or cylinder;
    // others have the identity orientation): E and V are taken into it, P and its normal out.
    let q = reflectors[search].orientation;
    let c = reflectors[search].center;
    let eye = c + turn(conjugate(q), reflectors[search].eye - c);
    let vertex = c + turn(conjugate(q), fermat_vertices[i].xyz - c);
    let world_vertex = fermat_vertices[i].xyz;
    let f = frame_for(eye, vertex);
    // The initial corners: A and B where E -> O and V -> O cross the reflector (C off AB); the
    // search of a torus's inner half starts across the hole (`TorusSearch::initial_corners`).
    var a0: vec2<f32>;
    var b0: vec2<f32>;
    if (REFLECTOR_KIND == REFLECTOR_TORUS && reflectors[search].torus_half != 0u) {
        a0 = across_the_hole(eye);
        b0 = across_the_hole(vertex);
    } else {
        // A patch's A is the same for every vertex: found once a frame on the CPU; its B
        // depends on the vertex and the patch only: found once for these vertices by
        // `fermat_start`.
        if (REFLECTOR_KIND == REFLECTOR_PATCH) {
            a0 = reflectors[search].eye_uv;
            b0 = fermat_starts[id.y * reflectors[search].count + i];
        } else {
            a0 = crossing(f, eye);
            b0 = crossing(f, vertex);
        }
    }
    var result = search_from(f, eye, vertex, a0, b0);
    var found = found_at(f, result, world_vertex);
    // A teapot's own point that Roger and Holzschuch's corners do not lead to a reflection on this patch
    // searches again from the patch's point that fails the law of reflection least
    // (`fermat::solve_on_patch`): a point of the mirror sees its other patches from close by,
    // where the segment V -> O seldom crosses them near the reflection.
    let own = reflectors[search].mirror != 0u
        && u32(fermat_vertices[i].w) == reflectors[search].mirror;
    if (OWN_POINTS_SEARCHED_AGAIN && REFLECTOR_KIND == REFLECTOR_PATCH && own && !found.shown) {
        let start = sampled_start(f, eye, vertex);
        let side = vec2<f32>(SAMPLED_START_SIDE, 0.5 * SAMPLED_START_SIDE);
        let again = search_from(f, eye, vertex, start, start + side);
        let found_again = found_at(f, again, world_vertex);
        if (found_again.shown) {
            result = again;
            found = found_again;
        }
    }
    reflections[id.y * reflectors[search].count + i] = GpuReflection(found.point, result.steps,
        found.normal, u32(found.shown), result.best, length(vertex - found.own_point),
        result.degenerate);
}

// A patch's corner B for one vertex of one search (x the vertex, y the search): where the
// segment from the vertex to O crosses the patch. Neither depends on the eye, so the preview
// runs this once for a set of vertices (`preview::reflections::kernel::FermatPass::solve`) and `fermat` reads
// the starts every frame: these Newton steps were the larger part of a teapot's solve
// (docs/fermat.md). The rows of other kinds are left alone; `fermat` computes their B itself
// (a sphere's and an ellipsoid's from the eye's frame; a torus's or cylinder's closed form).
@compute @workgroup_size(64, 1, 1)
fn fermat_start(@builtin(global_invocation_id) id: vec3<u32>) {
    search = id.y;
    let i = id.x;
    if (reflectors[search].kind != REFLECTOR_PATCH || i >= reflectors[search].count) {
        return;
    }
    // A patch's orientation is the identity (its control points are turned at load), so the
    // vertex is already in its frame.
    fermat_starts[id.y * reflectors[search].count + i] = patch_crossing(fermat_vertices[i].xyz);
}

// The reflection of `vertex` at `point` (outward normal `n`) is drawn: E and V both see P from
// outside the mirror and the law of reflection holds at P to REFLECTION_TOLERANCE. (A search
// whose triangle shrank below f32's resolution reports its step system singular; its point
// still counts if the law holds there.) CPU twin: `fermat::drawn_in_preview`.
fn reflection_shows(point: vec3<f32>, n: vec3<f32>, eye: vec3<f32>, vertex: vec3<f32>) -> bool {
    let to_eye = normalize(eye - point);
    let to_vertex = normalize(vertex - point);
    let half = to_eye + to_vertex;
    return dot(n, to_eye) > 0.0 && dot(n, to_vertex) > 0.0
        && length(cross(n, normalize(half))) < REFLECTION_TOLERANCE;
}

// One reflected triangle of one search per invocation (x the triangle, y the search): its three
// vertices' indices for the search, (row) x (distinct vertices) + the vertex, written to
// `shown_indices` and counted into the one indexed indirect draw of all the searches (a draw per
// search cost lavapipe about 10 us each, a teapot's 32 about 5% of its frame; indexed, the
// vertex stage runs once for a vertex the triangles around it share, not once a corner), when
// all three vertices' reflections show on the search's surface (`fermat`
// marked each, `GpuReflection::shown`), and where the triangle lies on the searched mirror
// itself, only when the search draws its mirror's own triangles (`sees_itself`: a torus, a
// teapot's patches, with self-reflections on) and each corner stands clear of its reflection
// point (SELF_REFLECTION_CLEARANCE; CPU twin `fermat::self_reflection_clear`). Runs after
// `fermat` has solved the vertices; the preview draws only the listed triangles, so the vertex
// stage no longer runs for the many whose reflection is not on a surface (most of a teapot
// patch's). The list's order varies from run to run; the reflections' depth test makes the
// image independent of it. The count starts at 0 (cleared before the dispatch).
@compute @workgroup_size(64, 1, 1)
fn fermat_cull(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    let s = id.y;
    let triangles = arrayLength(&reflected_triangles);
    if (t == 0u && s == 0u) {
        draw_args.instance_count = 1u;
    }
    search = s;
    if (t >= triangles) {
        return;
    }
    let triangle = reflected_triangles[t];
    let own = triangle.w == reflectors[search].mirror;
    if (own && reflectors[search].sees_itself == 0u) {
        return;
    }
    let eye = reflectors[search].eye;
    let kind = reflectors[search].kind;
    let inner_half = reflectors[search].torus_half != 0u;
    var anchored = kind != REFLECTOR_PATCH && kind != REFLECTOR_TORUS;
    for (var k = 0u; k < 3u; k += 1u) {
        let r = reflections[s * reflectors[search].count + vertex_solves[triangle[k]]];
        if (r.shown == 0u
            || (own && r.depth <= SELF_REFLECTION_CLEARANCE * distance(r.point, eye))) {
            return;
        }
        if (kind == REFLECTOR_PATCH) {
            anchored = anchored || (min(r.uv.x, r.uv.y) >= -PATCH_MARGIN
                && max(r.uv.x, r.uv.y) <= 1.0 + PATCH_MARGIN);
        } else if (kind == REFLECTOR_TORUS) {
            anchored = anchored || ((cos(r.uv.y) < 0.0) == inner_half);
        }
    }
    // A patch draws the triangles with a corner on it; one wholly in its seam band is its
    // neighbour's (`fermat::anchored_on_patch`). A torus's search draws those with a corner
    // on its half (`fermat::anchored_on_torus_half`).
    if (!anchored) {
        return;
    }
    let first = atomicAdd(&draw_args.index_count, 3u);
    let row = s * arrayLength(&vertex_solves);
    shown_indices[first] = row + triangle.x;
    shown_indices[first + 1u] = row + triangle.y;
    shown_indices[first + 2u] = row + triangle.z;
}
