//! Parametric surfaces f(u, v) and their evaluation: the point, the partial derivatives f_u and
//! f_v, and the outward normal of a sphere, an ellipsoid, a cylinder, a torus and a bicubic
//! Bézier patch ([`ParametricSurface`]). The scene's curved shapes are made of them
//! (`scene::surface`); the ray tracers intersect them (`accel::curved`), the raster preview cuts
//! them into triangles (`preview::tessellate`) and searches reflections on them
//! (`preview::reflections::fermat`). The ellipsoid, cylinder and torus are given in their own
//! frame turned by an orientation: their parameters are the own frame's.

use glam::{DQuat, DVec2, DVec3};

/// A smooth surface f(u, v) over a plane of parameters.
pub trait ParametricSurface {
    /// The surface point of parameters (u, v).
    fn point(&self, uv: DVec2) -> DVec3;
    /// ∂f/∂u and ∂f/∂v at (u, v).
    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3);
    /// The outward unit normal at (u, v).
    fn outward_normal(&self, uv: DVec2) -> DVec3;
    /// The period of u, when u is an angle around the surface.
    fn u_period(&self) -> Option<f64> {
        None
    }
}

/// A sphere, f(u, v) = c + r (sin v (cos u x + sin u z) + cos v y) in the orthonormal frame
/// (x, y, z): u the azimuth around y, v the angle from y; its poles, where f_u vanishes, are on
/// the y axis. [`Sphere::facing`] turns the poles away from two given points.
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

impl ParametricSurface for Sphere {
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

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        self.normal(uv)
    }

    fn u_period(&self) -> Option<f64> {
        Some(std::f64::consts::TAU)
    }
}

/// An ellipsoid with semi-axes `radii` along its own axes, the image of the unit sphere s(u,
/// v) = sin v (cos u x + sin u z) + cos v y under the scaling by `radii`, turned by
/// `orientation`: f(u, v) = c + Q (radii ⊙ s(u, v)). Its parametrisation's poles are on ±y of
/// the frame (x, y, z); as for the sphere, [`Ellipsoid::facing`] turns them away from two
/// given points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Centre (scene units).
    pub center: DVec3,
    /// Semi-axes along its own x, y and z, > 0.
    pub radii: DVec3,
    /// The unit sphere's parametrisation frame: x, y (the poles' axis), z.
    pub frame: [DVec3; 3],
    /// The rotation about the centre that turns its own axes into the world's.
    pub orientation: DQuat,
}

impl Ellipsoid {
    /// An ellipsoid with its semi-axes along the world axes, parametrised about them.
    pub fn new(center: DVec3, radii: DVec3) -> Ellipsoid {
        Ellipsoid {
            center,
            radii,
            frame: [DVec3::X, DVec3::Y, DVec3::Z],
            orientation: DQuat::IDENTITY,
        }
    }

    /// `x` in the ellipsoid's own frame, its centre at the origin.
    pub fn to_own(&self, x: DVec3) -> DVec3 {
        self.orientation.conjugate() * (x - self.center)
    }

    /// The same ellipsoid with the poles of its unit sphere on the normal of the plane through
    /// E, V and the centre, mapped to the unit sphere: the reflection lies near that plane, far
    /// from the poles where f_u vanishes (and a search there stalls without the law holding).
    pub fn facing(&self, eye: DVec3, vertex: DVec3) -> Ellipsoid {
        let unit = Sphere::new(DVec3::ZERO, 1.0).facing(
            self.to_own(eye) / self.radii,
            self.to_own(vertex) / self.radii,
        );
        Ellipsoid {
            frame: unit.frame,
            ..*self
        }
    }

    /// The unit sphere about the origin, parametrised in the ellipsoid's frame: the ellipsoid in
    /// its own coordinates divided by its radii.
    pub fn unit_sphere(&self) -> Sphere {
        Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            frame: self.frame,
        }
    }
}

impl ParametricSurface for Ellipsoid {
    fn point(&self, uv: DVec2) -> DVec3 {
        self.center + self.orientation * (self.radii * self.unit_sphere().point(uv))
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        let (su, sv) = self.unit_sphere().tangents(uv);
        (
            self.orientation * (self.radii * su),
            self.orientation * (self.radii * sv),
        )
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        // The gradient of |(x − c) / r|² in the own frame: (x − c) / r².
        let p = self.radii * self.unit_sphere().point(uv);
        self.orientation * (p / (self.radii * self.radii)).normalize()
    }

    fn u_period(&self) -> Option<f64> {
        Some(std::f64::consts::TAU)
    }
}

/// A cylinder of radius `radius` around the line through `center` along its own y, turned by
/// `orientation`: f(u, v) = c + Q (r cos u, v, r sin u) (unbounded in v: a scene's cylinder is
/// `height` tall, `scene::surface::Surface::Cylinder`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// A point of the axis (scene units).
    pub center: DVec3,
    /// Radius, > 0.
    pub radius: f64,
    /// The rotation about `center` that turns its own axes (the axis along y) into the world's.
    pub orientation: DQuat,
}

impl Cylinder {
    /// A cylinder around the vertical line through `center`.
    pub fn new(center: DVec3, radius: f64) -> Cylinder {
        Cylinder {
            center,
            radius,
            orientation: DQuat::IDENTITY,
        }
    }

    /// `x` in the cylinder's own frame, `center` at the origin.
    pub fn to_own(&self, x: DVec3) -> DVec3 {
        self.orientation.conjugate() * (x - self.center)
    }
}

impl ParametricSurface for Cylinder {
    fn point(&self, uv: DVec2) -> DVec3 {
        let (su, cu) = uv.x.sin_cos();
        self.center + self.orientation * DVec3::new(self.radius * cu, uv.y, self.radius * su)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        let (su, cu) = uv.x.sin_cos();
        (
            self.orientation * DVec3::new(-self.radius * su, 0.0, self.radius * cu),
            self.orientation * DVec3::Y,
        )
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        let (su, cu) = uv.x.sin_cos();
        self.orientation * DVec3::new(cu, 0.0, su)
    }

    fn u_period(&self) -> Option<f64> {
        Some(std::f64::consts::TAU)
    }
}

/// A torus around the line through `center` along its own y, turned by `orientation`:
/// f(u, v) = c + Q ((R + r cos v)(cos u, 0, sin u) + r sin v y), u around the axis, v around
/// the tube.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Torus {
    /// Centre (scene units).
    pub center: DVec3,
    /// R: the tube circle's radius.
    pub major: f64,
    /// r: the tube's radius, below R.
    pub minor: f64,
    /// The rotation about `center` that turns its own axes (the axis along y) into the world's.
    pub orientation: DQuat,
}

impl Torus {
    /// A torus around the vertical line through `center`.
    pub fn new(center: DVec3, major: f64, minor: f64) -> Torus {
        Torus {
            center,
            major,
            minor,
            orientation: DQuat::IDENTITY,
        }
    }

    /// `x` in the torus's own frame, `center` at the origin.
    pub fn to_own(&self, x: DVec3) -> DVec3 {
        self.orientation.conjugate() * (x - self.center)
    }
}

impl ParametricSurface for Torus {
    fn point(&self, uv: DVec2) -> DVec3 {
        let (su, cu) = uv.x.sin_cos();
        let (sv, cv) = uv.y.sin_cos();
        let ring = self.major + self.minor * cv;
        self.center + self.orientation * DVec3::new(ring * cu, self.minor * sv, ring * su)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        let (su, cu) = uv.x.sin_cos();
        let (sv, cv) = uv.y.sin_cos();
        let ring = self.major + self.minor * cv;
        (
            self.orientation * DVec3::new(-ring * su, 0.0, ring * cu),
            self.orientation * (self.minor * DVec3::new(-sv * cu, cv, -sv * su)),
        )
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        let (su, cu) = uv.x.sin_cos();
        let (sv, cv) = uv.y.sin_cos();
        self.orientation * DVec3::new(cv * cu, sv, cv * su)
    }

    fn u_period(&self) -> Option<f64> {
        Some(std::f64::consts::TAU)
    }
}

/// A bicubic Bézier patch (as the Newell teapot's): f(u, v) = Σ B_i(u) B_j(v) P_ij over
/// (u, v) in [0, 1]², with Bernstein polynomials B. Its outward side is the one f_u × f_v
/// points to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BezierPatch {
    /// Control points, `points[i][j]` weighted by B_i(u) B_j(v).
    pub points: [[DVec3; 4]; 4],
}

/// The cubic Bernstein polynomials at t and their derivatives.
fn bernstein(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    (
        [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t],
        [
            -3.0 * s * s,
            3.0 * s * s - 6.0 * t * s,
            6.0 * t * s - 3.0 * t * t,
            3.0 * t * t,
        ],
    )
}

impl BezierPatch {
    /// Σ a_i(u) b_j(v) P_ij.
    fn mix(&self, a: [f64; 4], b: [f64; 4]) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for (i, row) in self.points.iter().enumerate() {
            for (j, p) in row.iter().enumerate() {
                sum += a[i] * b[j] * *p;
            }
        }
        sum
    }
}

impl ParametricSurface for BezierPatch {
    fn point(&self, uv: DVec2) -> DVec3 {
        self.mix(bernstein(uv.x).0, bernstein(uv.y).0)
    }

    fn tangents(&self, uv: DVec2) -> (DVec3, DVec3) {
        let ((bu, du), (bv, dv)) = (bernstein(uv.x), bernstein(uv.y));
        (self.mix(du, bv), self.mix(bu, dv))
    }

    fn outward_normal(&self, uv: DVec2) -> DVec3 {
        let (fu, fv) = self.tangents(uv);
        fu.cross(fv).normalize_or_zero()
    }
}
