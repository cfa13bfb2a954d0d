//! The search for reflections on smooth curved mirrors by Fermat's principle: for an eye E
//! and a scene vertex V, the point P = f(u, v) of a parametric reflector where the path E → P → V
//! has extremal length d(u, v) = |E − f| + |V − f|. The search runs in the (u, v) plane on a
//! triangle A, B, C: the gradients of d at its corners,
//!
//! ```text
//! ∂d/∂u = −f_u · (unit(E − f) + unit(V − f)),   ∂d/∂v = −f_v · (unit(E − f) + unit(V − f)),
//! ```
//!
//! interpolated linearly, vanish at P = (1 − α − β) A + α B + β C with
//! (1 − α − β) G_A + α G_B + β G_C = 0 (α, β outside [0, 1] extrapolate); P replaces the corner
//! farthest from it (the next farthest where that would leave the triangle flat), until the
//! triangle or the step is small or the steps run out. The first two corners
//! are where the segments E → O and V → O cross the reflector (O inside it); the third makes a
//! triangle that is not flat (a quarter of AB off its middle). A sphere is parametrised with its
//! poles on the normal of the plane through E, V and its centre (`Sphere::facing`): the
//! reflection lies on that plane's great circle, the equator, where the parametrisation is
//! regular. This is the CPU version (f64); `wgsl/preview/fermat.wgsl` is the GPU's (the `fermat`
//! kernel, `preview::reflections::kernel`), which searches on the sphere, ellipsoid, cylinder,
//! torus and bicubic Bézier patch alike. The surfaces and their evaluation are the scene's
//! (`scene::parametric`); this module adds what the search needs of each ([`Reflector`]: its
//! inside point, where a segment crosses it, where the search starts and gives up). The
//! ellipsoid, cylinder and torus are given in their own frame turned by an orientation: their
//! parameters are the own frame's, so a search on a turned shape takes the steps it takes on
//! the unturned one (docs/fermat.md).

use glam::{DVec2, DVec3};

use crate::layout::{
    FERMAT_C_OFFSET, FERMAT_FLAT, FERMAT_INSIDE, FERMAT_SPREAD, PATCH_CROSSING_DONE,
};
use crate::scene::parametric::{
    BezierPatch, Cylinder, Ellipsoid, ParametricSurface, Sphere, Torus,
};

/// A parametric surface a reflection is searched on: where the search starts and where it
/// gives up.
pub trait Reflector: ParametricSurface {
    /// The point O inside the reflector that the initial corner for `outside` aims at (a
    /// sphere's or ellipsoid's, `FERMAT_INSIDE` of the way from its centre toward the bisector
    /// of E and V; the point of a cylinder's axis or a torus's tube circle nearest to
    /// `outside`; a patch-size behind a patch's centre).
    fn inside(&self, outside: DVec3) -> DVec3;
    /// The parameters of the surface point where the segment from `outside` to
    /// `inside(outside)` crosses the surface.
    fn crossing(&self, outside: DVec3) -> DVec2;
    /// The initial corners A and B for the reflection of `vertex` seen from `eye`: Roger and Holzschuch's
    /// crossings of E → O and V → O, unless the surface knows better.
    fn initial_corners(&self, eye: DVec3, vertex: DVec3) -> (DVec2, DVec2) {
        (self.crossing(eye), self.crossing(vertex))
    }
    /// Whether a search that reached `uv` has left the surface for good (a patch's square far
    /// behind it): it stops there, without a reflection on this surface.
    fn beyond_reach(&self, _uv: DVec2) -> bool {
        false
    }
}

/// Where the segment from `outside` (|outside| > 1) to `inside` (|inside| < 1) crosses the
/// unit sphere about the origin: the nearer root of |d + t w|² = 1, w = inside − outside, in the
/// form without cancellation (d · w < 0 there, so q > 0).
fn unit_sphere_crossing(outside: DVec3, inside: DVec3) -> DVec3 {
    let w = inside - outside;
    let (a, b, c) = (w.dot(w), outside.dot(w), outside.dot(outside) - 1.0);
    let q = -b + (b * b - a * c).max(0.0).sqrt();
    outside + (c / q) * w
}

impl Reflector for Sphere {
    /// `FERMAT_INSIDE` of the radius from the centre along the frame's x axis: for a sphere
    /// facing E and V ([`Sphere::facing`]), toward their bisector.
    fn inside(&self, _outside: DVec3) -> DVec3 {
        self.center + f64::from(FERMAT_INSIDE) * self.radius * self.frame[0]
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        let to_unit = |x: DVec3| (x - self.center) / self.radius;
        self.parameters_of(unit_sphere_crossing(
            to_unit(outside),
            to_unit(self.inside(outside)),
        ))
    }
}

impl Reflector for Ellipsoid {
    /// As a sphere's, in the unit sphere's coordinates.
    fn inside(&self, _outside: DVec3) -> DVec3 {
        let o = f64::from(FERMAT_INSIDE) * self.frame[0];
        self.center + self.orientation * (self.radii * o)
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        // The map to the unit sphere keeps segments and where they cross.
        let to_unit = |x: DVec3| self.to_own(x) / self.radii;
        self.unit_sphere().parameters_of(unit_sphere_crossing(
            to_unit(outside),
            to_unit(self.inside(outside)),
        ))
    }
}

impl Reflector for Cylinder {
    fn inside(&self, outside: DVec3) -> DVec3 {
        self.center + self.orientation * DVec3::new(0.0, self.to_own(outside).y, 0.0)
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        let d = self.to_own(outside);
        DVec2::new(d.z.atan2(d.x), d.y)
    }
}

/// The direction, in `torus`'s own frame, of the tube circle's point below or above
/// `outside`'s azimuth.
fn tube_direction(torus: &Torus, outside: DVec3) -> DVec3 {
    let d = torus.to_own(outside);
    DVec3::new(d.x, 0.0, d.z).normalize_or(DVec3::X)
}

/// The parameters of `torus`'s inner equator (v = π) across the hole from `x`'s azimuth.
fn across_the_hole(torus: &Torus, x: DVec3) -> DVec2 {
    let d = torus.to_own(x);
    DVec2::new(d.z.atan2(d.x) + std::f64::consts::PI, std::f64::consts::PI)
}

impl Reflector for Torus {
    fn inside(&self, outside: DVec3) -> DVec3 {
        self.center + self.orientation * (self.major * tube_direction(self, outside))
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        let d = self.to_own(outside);
        let u = d.z.atan2(d.x);
        let w = d - self.major * tube_direction(self, outside);
        let radial = DVec3::new(u.cos(), 0.0, u.sin());
        DVec2::new(u, w.y.atan2(w.dot(radial)))
    }
}

/// The half of a torus one of its two searches shows the images on. A point can show on a
/// torus more than once, and Roger and Holzschuch's crossings lead the search to the images on the outer
/// half only: never, for instance, to the image of a floor point inside the hole, which the
/// eye sees in the far inner wall, nor to a point of the torus itself, whose own crossing is
/// the point (P = V). So a torus is searched twice, as a teapot's patches are searched each,
/// and each search draws the reflected triangles anchored on its half
/// (`anchored_on_torus_half`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TorusHalf {
    /// cos v ≥ 0, facing away from the axis: searched from Roger and Holzschuch's crossings.
    Outer,
    /// cos v < 0, the wall of the hole: searched from across the hole, where what a point
    /// sees of the inner wall lies: both corners on the inner equator, across from E's and
    /// V's azimuths.
    Inner,
}

/// A torus searched for the images on one of its halves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorusSearch {
    /// The torus.
    pub torus: Torus,
    /// The half whose images the search shows.
    pub half: TorusHalf,
}

impl ParametricSurface for TorusSearch {
    fn point(&self, uv: DVec2) -> DVec3 {
        self.torus.point(uv)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        self.torus.tangents(uv)
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        self.torus.outward_normal(uv)
    }

    fn u_period(&self) -> Option<f64> {
        self.torus.u_period()
    }
}

impl Reflector for TorusSearch {
    fn inside(&self, outside: DVec3) -> DVec3 {
        self.torus.inside(outside)
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        self.torus.crossing(outside)
    }

    fn initial_corners(&self, eye: DVec3, vertex: DVec3) -> (DVec2, DVec2) {
        match self.half {
            TorusHalf::Outer => (self.crossing(eye), self.crossing(vertex)),
            TorusHalf::Inner => (
                across_the_hole(&self.torus, eye),
                across_the_hole(&self.torus, vertex),
            ),
        }
    }
}

/// Whether a torus's parameters `uv` lie on `half` of it.
pub fn on_torus_half(uv: DVec2, half: TorusHalf) -> bool {
    (uv.y.cos() >= 0.0) == (half == TorusHalf::Outer)
}

/// Whether a torus's search of `half` draws a reflected triangle whose corners' reflections
/// show at parameters `uvs`: one corner at least on its half (the CPU twin of `fermat_cull`'s
/// test). The torus goes on smoothly across the two circles where the halves meet, so a
/// triangle across them is drawn by both searches (where each finds its corners), one wholly
/// on a half by that half's alone.
pub fn anchored_on_torus_half(uvs: [DVec2; 3], half: TorusHalf) -> bool {
    uvs.into_iter().any(|uv| on_torus_half(uv, half))
}

/// Whether parameters `uv` lie on a Bézier patch: in its square, widened by `PATCH_MARGIN`.
pub fn on_patch(uv: DVec2) -> bool {
    let margin = f64::from(crate::layout::PATCH_MARGIN);
    uv.min_element() >= -margin && uv.max_element() <= 1.0 + margin
}

/// Whether a patch's search draws a reflected triangle whose corners' reflections show at
/// parameters `uvs`: one corner at least on the patch itself, the others perhaps in its seam
/// band (the CPU twin of `fermat_cull`'s test): a triangle across a seam is drawn by both
/// patches, one wholly beyond by the neighbour alone.
pub fn anchored_on_patch(uvs: [DVec2; 3]) -> bool {
    uvs.into_iter().any(on_patch)
}

/// Whether the height `v` of a point of a cylinder lies on one `height` tall: in [0, height],
/// widened by `PATCH_MARGIN` of it.
pub fn on_cylinder(v: f64, height: f64) -> bool {
    let margin = f64::from(crate::layout::PATCH_MARGIN) * height;
    (-margin..=height + margin).contains(&v)
}

impl Reflector for BezierPatch {
    /// A patch has no inside: O is taken a patch-size behind its centre, against the normal.
    fn inside(&self, _outside: DVec3) -> DVec3 {
        let centre = DVec2::splat(0.5);
        let size = (self.points[3][3] - self.points[0][0]).length();
        self.point(centre) - size * self.outward_normal(centre)
    }

    /// Where the segment from `outside` to O crosses the patch, by a few Newton steps on
    /// f(u, v) = O + t (outside − O) from the patch's centre (clamped to the patch), ending
    /// once a step moves less than `PATCH_CROSSING_DONE`.
    fn crossing(&self, outside: DVec3) -> DVec2 {
        let o = self.inside(outside);
        let d = outside - o;
        let mut uvt = DVec3::new(0.5, 0.5, 0.5);
        for _ in 0..8 {
            let uv = uvt.truncate();
            let r = self.point(uv) - (o + uvt.z * d);
            let (fu, fv) = self.tangents(uv);
            let jacobian = glam::DMat3::from_cols(fu, fv, -d);
            if jacobian.determinant().abs() < 1e-300 {
                break;
            }
            let next = (uvt - jacobian.inverse() * r).clamp(DVec3::ZERO, DVec3::ONE);
            let moved = (next - uvt).length();
            uvt = next;
            if moved < f64::from(PATCH_CROSSING_DONE) {
                break;
            }
        }
        uvt.truncate()
    }

    /// A patch's reflections lie in its square: a search a square's width beyond it (the
    /// patch's cubic continued past its edges) has gone to another patch's reflection or to
    /// none. Most searches on a teapot's 32 patches are of this kind, and stopping them saves
    /// most of the preview's Fermat work.
    fn beyond_reach(&self, uv: DVec2) -> bool {
        let reach = f64::from(crate::layout::PATCH_REACH);
        uv.min_element() < -reach || uv.max_element() > 1.0 + reach
    }
}

/// The solver's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solver {
    /// Steps at most (Roger and Holzschuch's 4–5).
    pub max_steps: u32,
    /// The search stops when the triangle's longest side in (u, v) is below this, or its last
    /// step moved less (the triangle keeps a far corner where it would otherwise go flat).
    pub min_size: f64,
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            max_steps: 5,
            min_size: 1e-9,
        }
    }
}

/// A solution: the parameters found and how the search went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// The reflection point's parameters.
    pub uv: DVec2,
    /// Steps taken.
    pub steps: u32,
    /// The step system was singular (the three gradients aligned): the search stopped there.
    pub degenerate: bool,
    /// The search left the surface for good (`Reflector::beyond_reach`) and stopped there.
    pub left_surface: bool,
}

/// The gradient of d(u, v) = |E − f| + |V − f|.
pub fn gradient(reflector: &impl Reflector, eye: DVec3, vertex: DVec3, uv: DVec2) -> DVec2 {
    let f = reflector.point(uv);
    let (fu, fv) = reflector.tangents(uv);
    let pull = (eye - f).normalize() + (vertex - f).normalize();
    DVec2::new(-fu.dot(pull), -fv.dot(pull))
}

/// Roger and Holzschuch's initial triangle: A and B where E → O and V → O cross the reflector (or where
/// the surface starts instead, `Reflector::initial_corners`: a torus's inner half across the
/// hole), C off the middle of AB by `FERMAT_C_OFFSET` of its length, so the triangle is not
/// flat (or a triangle of side `FERMAT_SPREAD` at A when A and B coincide).
pub fn initial_triangle(reflector: &impl Reflector, eye: DVec3, vertex: DVec3) -> [DVec2; 3] {
    let (a, mut b) = reflector.initial_corners(eye, vertex);
    // A periodic u (an azimuth) is unwrapped so that the side AB takes the short way round.
    if let Some(period) = reflector.u_period() {
        b.x += period * ((a.x - b.x) / period).round();
    }
    let side = b - a;
    let spread = f64::from(FERMAT_SPREAD);
    if side.length() > spread {
        [
            a,
            b,
            (a + b) / 2.0 + side.perp() * f64::from(FERMAT_C_OFFSET),
        ]
    } else {
        [
            a,
            a + DVec2::new(spread, 0.0),
            a + DVec2::new(spread, spread),
        ]
    }
}

/// The corner a step's new point `p` replaces: the farthest from it (Roger and Holzschuch's rule), or the
/// next farthest where replacing that one would leave a flat triangle (`FERMAT_FLAT`).
pub fn replaced_corner(corners: &[DVec2; 3], p: DVec2) -> usize {
    let mut by_distance = [0, 1, 2];
    // Farthest first; among equals the later corner, as the kernel's `>=` scan picks it.
    by_distance.sort_by(|&i, &j| {
        (corners[j] - p)
            .length()
            .total_cmp(&(corners[i] - p).length())
            .then(j.cmp(&i))
    });
    let flat = |k: usize| {
        let mut t = *corners;
        t[k] = p;
        let longest = (0..3)
            .map(|i| (t[i] - t[(i + 1) % 3]).length_squared())
            .fold(0.0, f64::max);
        (t[1] - t[0]).perp_dot(t[2] - t[0]).abs() < f64::from(FERMAT_FLAT) * longest
    };
    by_distance
        .into_iter()
        .find(|&k| !flat(k))
        .unwrap_or(by_distance[0])
}

impl Solver {
    /// Searches the reflection of `vertex` seen from `eye` on `reflector`.
    pub fn solve(&self, reflector: &impl Reflector, eye: DVec3, vertex: DVec3) -> Solution {
        let mut corners = initial_triangle(reflector, eye, vertex);
        // Each step replaces one corner: the other two keep their gradients.
        let mut gradients = corners.map(|c| gradient(reflector, eye, vertex, c));
        let (mut best, mut moved) = (corners[0], f64::INFINITY);
        for step in 0..self.max_steps {
            let size = (0..3)
                .map(|i| (corners[i] - corners[(i + 1) % 3]).length())
                .fold(0.0, f64::max);
            if size.min(moved) < self.min_size {
                return Solution {
                    uv: best,
                    steps: step,
                    degenerate: false,
                    left_surface: false,
                };
            }
            let [ga, gb, gc] = gradients;
            // α (G_B − G_A) + β (G_C − G_A) = −G_A.
            let (m0, m1) = (gb - ga, gc - ga);
            let det = m0.x * m1.y - m1.x * m0.y;
            if det == 0.0 || !det.is_finite() {
                return Solution {
                    uv: best,
                    steps: step,
                    degenerate: true,
                    left_surface: false,
                };
            }
            let alpha = (-ga.x * m1.y + m1.x * ga.y) / det;
            let beta = (-m0.x * ga.y + ga.x * m0.y) / det;
            let [a, b, c] = corners;
            let p = (1.0 - alpha - beta) * a + alpha * b + beta * c;
            let replaced = replaced_corner(&corners, p);
            corners[replaced] = p;
            gradients[replaced] = gradient(reflector, eye, vertex, p);
            moved = (p - best).length();
            best = p;
            if reflector.beyond_reach(p) {
                return Solution {
                    uv: best,
                    steps: step + 1,
                    degenerate: false,
                    left_surface: true,
                };
            }
        }
        Solution {
            uv: best,
            steps: self.max_steps,
            degenerate: false,
            left_surface: false,
        }
    }
}

/// How far `p` (with unit normal `n`) is from reflecting E into V: the angle between the
/// normal and the bisector of the directions to E and V (0 where the law of reflection holds).
pub fn reflection_error(p: DVec3, n: DVec3, eye: DVec3, vertex: DVec3) -> f64 {
    let bisector = ((eye - p).normalize() + (vertex - p).normalize()).normalize();
    let n = if n.dot(bisector) < 0.0 { -n } else { n };
    // atan2 rather than acos: acos loses half the digits near 0.
    n.cross(bisector).length().atan2(n.dot(bisector))
}

/// Whether the reflection at `p` (outward unit normal `n`) is seen from outside: E and V both
/// on the normal's side. The far side of a sphere satisfies the law of reflection too (the
/// path's maximum), but light cannot reach it.
pub fn seen_from_outside(p: DVec3, n: DVec3, eye: DVec3, vertex: DVec3) -> bool {
    (eye - p).dot(n) > 0.0 && (vertex - p).dot(n) > 0.0
}

/// Whether the raster preview draws a reflection found at `p` (outward unit normal `n`):
/// seen from outside, with the law of reflection holding to `layout::REFLECTION_TOLERANCE`
/// (the CPU twin of `reflection_shows` in wgsl/preview/fermat.wgsl).
pub fn drawn_in_preview(p: DVec3, n: DVec3, eye: DVec3, vertex: DVec3) -> bool {
    seen_from_outside(p, n, eye, vertex)
        && reflection_error(p, n, eye, vertex) < f64::from(crate::layout::REFLECTION_TOLERANCE)
}

/// The point of a `SAMPLED_START_GRID`² grid of `patch`'s parameters (4: its corners and
/// thirds) where the law of reflection fails least for `vertex` seen from `eye`: the least 1 − n · b, n the outward
/// normal and b the bisector of the directions to E and V (a point facing away fails most).
/// The kernel's `sampled_start`.
pub fn sampled_start(patch: &BezierPatch, eye: DVec3, vertex: DVec3) -> DVec2 {
    let failure = |uv: DVec2| {
        let p = patch.point(uv);
        let bisector = ((eye - p).normalize() + (vertex - p).normalize()).normalize();
        1.0 - patch.outward_normal(uv).dot(bisector)
    };
    let side = crate::layout::SAMPLED_START_GRID;
    (0..side * side)
        .map(|k| DVec2::new(f64::from(k % side), f64::from(k / side)) / f64::from(side - 1))
        .min_by(|&a, &b| failure(a).total_cmp(&failure(b)))
        .expect("a grid of at least one point")
}

/// The search for `vertex`, a point of the mirror `patch` is part of (a teapot's own point),
/// on `patch`: Roger and Holzschuch's search, and where the preview would show nothing of it, another
/// from `sampled_start` (A there, B = A + (`SAMPLED_START_SIDE`, half that)). A point of the
/// mirror sees its other patches from close by, where the segment V → O seldom crosses them
/// near the reflection. The kernel's, with `OWN_POINTS_SEARCHED_AGAIN`.
pub fn solve_on_patch(solver: &Solver, patch: &BezierPatch, eye: DVec3, vertex: DVec3) -> Solution {
    let shows = |solution: &Solution| {
        let seam = f64::from(crate::layout::PATCH_SEAM);
        let uv = solution.uv;
        uv.min_element() >= -seam
            && uv.max_element() <= 1.0 + seam
            && drawn_in_preview(patch.point(uv), patch.outward_normal(uv), eye, vertex)
    };
    let first = solver.solve(patch, eye, vertex);
    if shows(&first) {
        return first;
    }
    let a = sampled_start(patch, eye, vertex);
    let side = f64::from(crate::layout::SAMPLED_START_SIDE);
    let again = solver.solve(
        &StartedFrom(*patch, a, a + DVec2::new(side, side / 2.0)),
        eye,
        vertex,
    );
    if shows(&again) { again } else { first }
}

/// A surface whose search starts from given initial corners A and B
/// (`Reflector::initial_corners`): a teapot's own point searched again, and the tests'
/// brute-force searches from many starts.
pub struct StartedFrom<R: Reflector>(pub R, pub DVec2, pub DVec2);

impl<R: Reflector> ParametricSurface for StartedFrom<R> {
    fn point(&self, uv: DVec2) -> DVec3 {
        self.0.point(uv)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        self.0.tangents(uv)
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        self.0.outward_normal(uv)
    }

    fn u_period(&self) -> Option<f64> {
        self.0.u_period()
    }
}

impl<R: Reflector> Reflector for StartedFrom<R> {
    fn inside(&self, outside: DVec3) -> DVec3 {
        self.0.inside(outside)
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        self.0.crossing(outside)
    }

    fn initial_corners(&self, _eye: DVec3, _vertex: DVec3) -> (DVec2, DVec2) {
        (self.1, self.2)
    }

    fn beyond_reach(&self, uv: DVec2) -> bool {
        self.0.beyond_reach(uv)
    }
}

/// Whether a point of the searched mirror itself, reflected at `p`, stands clear enough of `p`
/// to be drawn there (`layout::SELF_REFLECTION_CLEARANCE`; the CPU twin of `fermat_cull`'s
/// test in wgsl/preview/fermat.wgsl): a vertex on the surface is its own "reflection" at P = V.
pub fn self_reflection_clear(p: DVec3, eye: DVec3, vertex: DVec3) -> bool {
    p.distance(vertex) > f64::from(crate::layout::SELF_REFLECTION_CLEARANCE) * p.distance(eye)
}

/// Alhazen's problem on a sphere in f64, independently of the solver: the reflection point lies
/// on the great circle of the plane through E, V and the centre, where d(φ) is extremal; found
/// by a dense scan of the arc facing E and V and bisection on d'(φ).
pub fn alhazen_sphere(sphere: &Sphere, eye: DVec3, vertex: DVec3) -> DVec3 {
    let (e, v) = (eye - sphere.center, vertex - sphere.center);
    // An orthonormal basis of the plane: x towards the bisector of E and V.
    let x = (e.normalize() + v.normalize()).normalize();
    let normal = e.cross(v);
    let y = if normal.length() > 1e-12 * e.length() * v.length() {
        normal.cross(x).normalize()
    } else {
        x.any_orthonormal_vector()
    };
    let at = |phi: f64| sphere.radius * (phi.cos() * x + phi.sin() * y);
    let slope = |phi: f64| {
        let p = at(phi);
        let dp = sphere.radius * (-phi.sin() * x + phi.cos() * y);
        -dp.dot((e - p).normalize() + (v - p).normalize())
    };
    // The reflection seen from outside lies on the arc facing both: within 90° of x.
    let n = 4096;
    let half = std::f64::consts::FRAC_PI_2;
    let (mut lo, mut hi) = (-half, half);
    for i in 0..n {
        let (a, b) = (
            -half + 2.0 * half * i as f64 / n as f64,
            -half + 2.0 * half * (i + 1) as f64 / n as f64,
        );
        if slope(a) <= 0.0 && slope(b) >= 0.0 {
            (lo, hi) = (a, b);
            break;
        }
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) <= 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    sphere.center + at(0.5 * (lo + hi))
}
