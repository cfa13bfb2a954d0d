//! Reflections on smooth curved reflectors by Fermat's principle (the seed `004`): for an eye E
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
//! farthest from it, until the triangle is small or the steps run out. The first two corners
//! are where the segments E → O and V → O cross the reflector (O inside it); the third makes a
//! triangle that is not flat (a quarter of AB off its middle). A sphere is parametrised with its
//! poles on the normal of the plane through E, V and its centre (`Sphere::facing`): the
//! reflection lies on that plane's great circle, the equator, where the parametrisation is
//! regular. This is the CPU version (f64); `wgsl/fermat.wgsl` is the GPU's (the `fermat`
//! kernel, `gpu::fermat`). The other reflectors and the rasterisation of the reflected
//! triangles are to come (docs/fermat.md).

use glam::{DVec2, DVec3};

/// A smooth parametric surface a reflection is searched on.
pub trait Reflector {
    /// The surface point of parameters (u, v).
    fn point(&self, uv: DVec2) -> DVec3;
    /// ∂f/∂u and ∂f/∂v at (u, v).
    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3);
    /// A point inside the reflector (O).
    fn inside(&self) -> DVec3;
    /// The parameters of the surface point where the segment from `outside` to `inside()`
    /// crosses the surface.
    fn crossing(&self, outside: DVec3) -> DVec2;
    /// The period of u, when u is an angle around the surface.
    fn u_period(&self) -> Option<f64> {
        None
    }
}

/// A sphere, f(u, v) = c + r (sin v (cos u x + sin u z) + cos v y) in the orthonormal frame
/// (x, y, z): u the azimuth around y, v the angle from y; its poles, where f_u vanishes, are on
/// the y axis. [`Sphere::facing`] turns the poles away from a reflection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre (scene units).
    pub center: DVec3,
    /// Radius (scene units), > 0.
    pub radius: f64,
    /// The parametrisation's frame: x, y (the poles' axis), z.
    pub frame: [DVec3; 3],
}

impl Sphere {
    /// A sphere parametrised about the world axes.
    pub fn new(center: DVec3, radius: f64) -> Sphere {
        Sphere {
            center,
            radius,
            frame: [DVec3::X, DVec3::Y, DVec3::Z],
        }
    }

    /// The same sphere with its poles on the normal of the plane through E, V and the centre:
    /// the reflection lies on that plane's great circle (Alhazen), the equator here, far from
    /// the poles where the parametrisation degenerates.
    pub fn facing(&self, eye: DVec3, vertex: DVec3) -> Sphere {
        let (e, v) = (eye - self.center, vertex - self.center);
        let x = (e.normalize() + v.normalize()).normalize_or(e.normalize());
        let normal = e.cross(v);
        let y = if normal.length() > 1e-12 * e.length() * v.length() {
            normal.normalize()
        } else {
            x.any_orthonormal_vector()
        };
        Sphere {
            frame: [x, y, x.cross(y)],
            ..*self
        }
    }

    /// The parameters of the surface point in direction `d` from the centre.
    pub fn parameters_of(&self, d: DVec3) -> DVec2 {
        let d = d.normalize();
        let [x, y, z] = self.frame;
        DVec2::new(d.dot(z).atan2(d.dot(x)), d.dot(y).clamp(-1.0, 1.0).acos())
    }

    /// The outward unit normal at (u, v).
    pub fn normal(&self, uv: DVec2) -> DVec3 {
        (self.point(uv) - self.center) / self.radius
    }
}

impl Reflector for Sphere {
    fn point(&self, uv: DVec2) -> DVec3 {
        let (su, cu) = uv.x.sin_cos();
        let (sv, cv) = uv.y.sin_cos();
        let [x, y, z] = self.frame;
        self.center + self.radius * (sv * (cu * x + su * z) + cv * y)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        let (su, cu) = uv.x.sin_cos();
        let (sv, cv) = uv.y.sin_cos();
        let [x, y, z] = self.frame;
        (
            self.radius * sv * (-su * x + cu * z),
            self.radius * (cv * (cu * x + su * z) - sv * y),
        )
    }

    fn inside(&self) -> DVec3 {
        self.center
    }

    fn crossing(&self, outside: DVec3) -> DVec2 {
        self.parameters_of(outside - self.center)
    }

    fn u_period(&self) -> Option<f64> {
        Some(std::f64::consts::TAU)
    }
}

/// How far C stands off the middle of AB, in lengths of AB.
const C_OFFSET: f64 = 0.25;

/// The solver's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solver {
    /// Steps at most (the seed's 4–5).
    pub max_steps: u32,
    /// The search stops when the triangle's longest side in (u, v) is below this.
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
}

/// The gradient of d(u, v) = |E − f| + |V − f|.
pub fn gradient(reflector: &impl Reflector, eye: DVec3, vertex: DVec3, uv: DVec2) -> DVec2 {
    let f = reflector.point(uv);
    let (fu, fv) = reflector.tangents(uv);
    let pull = (eye - f).normalize() + (vertex - f).normalize();
    DVec2::new(-fu.dot(pull), -fv.dot(pull))
}

/// The seed's initial triangle: A and B where E → O and V → O cross the reflector, C off the
/// side AB by its length (or by `spread` when A and B coincide), so the triangle is not flat.
pub fn initial_triangle(
    reflector: &impl Reflector,
    eye: DVec3,
    vertex: DVec3,
    spread: f64,
) -> [DVec2; 3] {
    let (a, mut b) = (reflector.crossing(eye), reflector.crossing(vertex));
    // A periodic u (an azimuth) is unwrapped so that the side AB takes the short way round.
    if let Some(period) = reflector.u_period() {
        b.x += period * ((a.x - b.x) / period).round();
    }
    let side = b - a;
    let length = side.length();
    let c = if length > spread {
        (a + b) / 2.0 + side.perp() * C_OFFSET
    } else {
        a + DVec2::new(spread, spread)
    };
    let b = if length > spread {
        b
    } else {
        a + DVec2::new(spread, 0.0)
    };
    [a, b, c]
}

impl Solver {
    /// Searches the reflection of `vertex` seen from `eye` on `reflector`.
    pub fn solve(&self, reflector: &impl Reflector, eye: DVec3, vertex: DVec3) -> Solution {
        let mut corners = initial_triangle(reflector, eye, vertex, 1e-3);
        let mut best = corners[0];
        for step in 0..self.max_steps {
            let size = (0..3)
                .map(|i| (corners[i] - corners[(i + 1) % 3]).length())
                .fold(0.0, f64::max);
            if size < self.min_size {
                return Solution {
                    uv: best,
                    steps: step,
                    degenerate: false,
                };
            }
            let [ga, gb, gc] = corners.map(|c| gradient(reflector, eye, vertex, c));
            // α (G_B − G_A) + β (G_C − G_A) = −G_A.
            let (m0, m1) = (gb - ga, gc - ga);
            let det = m0.x * m1.y - m1.x * m0.y;
            if det == 0.0 || !det.is_finite() {
                return Solution {
                    uv: best,
                    steps: step,
                    degenerate: true,
                };
            }
            let alpha = (-ga.x * m1.y + m1.x * ga.y) / det;
            let beta = (-m0.x * ga.y + ga.x * m0.y) / det;
            let [a, b, c] = corners;
            let p = (1.0 - alpha - beta) * a + alpha * b + beta * c;
            let farthest = (0..3)
                .max_by(|&i, &j| {
                    let (di, dj) = ((corners[i] - p).length(), (corners[j] - p).length());
                    di.total_cmp(&dj)
                })
                .expect("three corners");
            corners[farthest] = p;
            best = p;
        }
        Solution {
            uv: best,
            steps: self.max_steps,
            degenerate: false,
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
/// (the CPU twin of `reflection_holds` in wgsl/preview_reflect.wgsl).
pub fn drawn_in_preview(p: DVec3, n: DVec3, eye: DVec3, vertex: DVec3) -> bool {
    seen_from_outside(p, n, eye, vertex)
        && reflection_error(p, n, eye, vertex) < f64::from(crate::layout::REFLECTION_TOLERANCE)
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
