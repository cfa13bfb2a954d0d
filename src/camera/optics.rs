//! What a view camera's settings mean in object space: the plane of sharp focus, the hinge and
//! Scheimpflug lines, the depth-of-field wedge, the equivalent raster projection, and the inverse
//! problem (`focus_points`: the lens tilt, swing and film distance that focus on three points).
//! CPU only, f64; `chambre camera SCENE` prints these. Equations: `docs/camera.md`.
//!
//! Everything rests on one fact of the ideal thin lens: in the lens frame (lens plane z = 0,
//! optical axis +z, lengths in mm) the conjugate of a film point A is X = A f / (f + A_z), a
//! projective map, so the conjugate of the film plane n.A = c is the plane
//! (f n + c e_z).X = c f. The hinge rule and the Scheimpflug rule follow from it.

use glam::{DMat4, DVec2, DVec3, DVec4};

use super::{CameraSpec, standard_rotation};

/// A plane in world space: a point on it and its unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane (world, scene units).
    pub point: DVec3,
    /// Unit normal.
    pub normal: DVec3,
}

impl Plane {
    /// Distance of `p` from the plane, positive on the side the normal points to.
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        (p - self.point).dot(self.normal)
    }
}

/// A line in world space: a point on it and its unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// A point on the line (world, scene units).
    pub point: DVec3,
    /// Unit direction.
    pub direction: DVec3,
}

impl Line {
    /// Distance of `p` from the line (scene units).
    pub fn distance_to(&self, p: DVec3) -> f64 {
        (p - self.point)
            .reject_from_normalized(self.direction)
            .length()
    }
}

/// A plane n.x = d (n not necessarily unit) in some frame.
#[derive(Clone, Copy, Debug)]
struct RawPlane {
    normal: DVec3,
    offset: f64,
}

/// Relative size under which a normal counts as zero (the plane has gone to infinity) or two
/// planes count as parallel.
const DEGENERATE: f64 = 1e-12;

fn intersect_planes(a: RawPlane, b: RawPlane) -> Option<(DVec3, DVec3)> {
    let direction = a.normal.cross(b.normal);
    let scale = a.normal.length() * b.normal.length();
    if direction.length() <= DEGENERATE * scale {
        return None;
    }
    let point = (a.offset * b.normal.cross(direction) + b.offset * direction.cross(a.normal))
        / direction.length_squared();
    Some((point, direction.normalize()))
}

impl CameraSpec {
    /// The film plane in the lens frame, n.A = c with n the unit film normal.
    fn film_plane_lens_frame(&self) -> RawPlane {
        let s = self.standards();
        let normal = s.lens.transpose() * s.film.z_axis;
        RawPlane {
            normal,
            offset: normal.dot(s.to_lens_frame(s.film_pivot)),
        }
    }

    /// The conjugate (object-side) plane of the film plane scaled by `k` about the lens centre,
    /// in the lens frame but relative to the front principal point H; `None` when it lies at
    /// infinity.
    fn conjugate_plane_lens_frame(&self, k: f64) -> Option<RawPlane> {
        let film = self.film_plane_lens_frame();
        let f = self.focal_length_mm;
        let c = k * film.offset;
        let normal = f * film.normal + c * DVec3::Z;
        (normal.length() > DEGENERATE * f).then_some(RawPlane {
            normal,
            offset: c * f,
        })
    }

    /// An object-side plane of the lens frame, given relative to the front principal point H
    /// (the thin lens's conjugates hold from H; H lies `principal_gap` ahead of the lens
    /// centre H'), in world space.
    fn lens_plane_to_world(&self, plane: RawPlane) -> Plane {
        let s = self.standards();
        let length = plane.normal.length();
        let mut normal = plane.normal / length;
        let mut offset = (plane.offset + self.principal_gap() * plane.normal.z) / length;
        // Orient the normal away from the lens centre.
        if offset < 0.0 {
            normal = -normal;
            offset = -offset;
        }
        let point_lens = normal * offset;
        let point_camera = s.lens * point_lens + s.lens_center;
        Plane {
            point: self.camera_to_world(point_camera),
            normal: self.basis().to_world(s.lens * normal),
        }
    }

    fn lens_line_to_world(&self, (point, direction): (DVec3, DVec3)) -> Line {
        let s = self.standards();
        Line {
            point: self.camera_to_world(s.lens * point + s.lens_center),
            direction: self.basis().to_world(s.lens * direction),
        }
    }

    /// The plane of sharp focus; `None` when it lies at infinity (film at f, lens parallel).
    pub fn focus_plane(&self) -> Option<Plane> {
        self.conjugate_plane_lens_frame(1.0)
            .map(|p| self.lens_plane_to_world(p))
    }

    /// Hinge line: where the plane through the front principal point H (the thin lens's
    /// centre) parallel to the film meets the front focal plane; the plane of sharp focus turns
    /// about it as the focus changes. `None` when lens and film are parallel (no tilt between
    /// them: the line is at infinity).
    pub fn hinge_line(&self) -> Option<Line> {
        let film = self.film_plane_lens_frame();
        let gap = self.principal_gap();
        let parallel_through_h = RawPlane {
            normal: film.normal,
            offset: gap * film.normal.z,
        };
        let front_focal = RawPlane {
            normal: DVec3::Z,
            offset: self.focal_length_mm + gap,
        };
        intersect_planes(parallel_through_h, front_focal).map(|l| self.lens_line_to_world(l))
    }

    /// Scheimpflug line: where the film plane meets the lens plane (and the plane of sharp focus).
    /// For a real lens the lens plane is the rear principal plane; the plane of sharp focus
    /// meets the front one in the same line moved `principal_gap` along the axis.
    pub fn scheimpflug_line(&self) -> Option<Line> {
        let lens_plane = RawPlane {
            normal: DVec3::Z,
            offset: 0.0,
        };
        intersect_planes(self.film_plane_lens_frame(), lens_plane)
            .map(|l| self.lens_line_to_world(l))
    }

    /// Angle between the lens plane and the film plane, in degrees.
    pub fn lens_to_film_angle_deg(&self) -> f64 {
        self.film_plane_lens_frame()
            .normal
            .angle_between(DVec3::Z)
            .to_degrees()
    }

    /// Near and far limits of the depth-of-field wedge for a circle of confusion `coc_mm`: the
    /// conjugates of the film plane scaled about the lens centre by D / (D -+ c), where a point's
    /// blur disc (measured parallel to the lens) reaches c. Both pass through the hinge line.
    /// `None` for a limit at or beyond infinity; a pinhole has no limits at all.
    pub fn depth_of_field(&self, coc_mm: f64) -> Option<(Option<Plane>, Option<Plane>)> {
        if self.is_pinhole() {
            return None;
        }
        let d = 2.0 * self.lens_radius_mm();
        let near = (coc_mm < d)
            .then(|| self.conjugate_plane_lens_frame(d / (d - coc_mm)))
            .flatten();
        let far_scale = d / (d + coc_mm);
        // The far limit lies beyond infinity once the scaled film's conjugate crosses behind the
        // lens: the image centre's chief ray no longer meets it in front.
        let far = self
            .conjugate_plane_lens_frame(far_scale)
            .map(|p| self.lens_plane_to_world(p))
            .filter(|p| self.distance_along_chief_ray(p).is_some());
        Some((near.map(|p| self.lens_plane_to_world(p)), far))
    }

    /// Distance from the lens centre along the image centre's chief ray to a world plane.
    pub fn distance_along_chief_ray(&self, plane: &Plane) -> Option<f64> {
        let s = self.standards();
        let origin = self.camera_to_world(s.lens_center);
        let direction = (origin - self.camera_to_world(s.film_center)).normalize();
        let t = (plane.point - origin).dot(plane.normal) / direction.dot(plane.normal);
        (t.is_finite() && t > 0.0).then_some(t)
    }

    /// The film-tilted pinhole camera as a raster pipeline would set it up: a view matrix whose
    /// axis is the film normal, and an off-axis frustum whose window is the film mirrored
    /// through the lens centre. Lens tilt and swing do not move a pinhole's rays and are
    /// ignored; the aperture is taken as a point. An orthographic camera gets
    /// [`Self::orthographic_projection`].
    pub fn raster_projection(&self, far: f64) -> RasterProjection {
        if self.is_orthographic() {
            return self.orthographic_projection(far);
        }
        let s = self.standards();
        let basis = self.basis();
        let eye = self.camera_to_world(s.lens_center);
        let (right, up, forward) = (
            basis.to_world(s.film.x_axis),
            basis.to_world(s.film.y_axis),
            basis.to_world(s.film.z_axis),
        );
        let to_window = s.lens_center - s.film_center;
        let centre = DVec2::new(to_window.dot(s.film.x_axis), to_window.dot(s.film.y_axis));
        let near_mm = to_window.dot(s.film.z_axis);
        let [w, h] = self.film_mm.map(|v| 0.5 * v);
        let scale = self.units_per_mm;
        let frustum = Frustum {
            left: (centre.x - w) * scale,
            right: (centre.x + w) * scale,
            bottom: (centre.y - h) * scale,
            top: (centre.y + h) * scale,
            near: near_mm * scale,
            far,
        };
        let view = view_matrix(right, up, forward, eye);
        RasterProjection {
            view,
            frustum,
            projection: frustum.matrix(),
        }
    }

    /// An orthographic camera as a raster pipeline would set it up: the view square to its
    /// window (the camera frame, eye at `position`), and the oblique parallel projection that
    /// gives a point at camera-frame (x, y, z) its window coordinates. The ray from window point
    /// (c_x + a, c_y + b, 0) (c the shift) along r = T^-1 z meets the point after z / r_z, so
    /// a = x - (r_x / r_z) z - c_x and b = y - (r_y / r_z) z - c_y: glOrtho's matrix with the
    /// shear of a cavalier projection. Depth is z, from the window's plane (near 0) to `far`.
    /// `frustum` holds the window's edges (glOrtho's left, right, bottom, top).
    pub fn orthographic_projection(&self, far: f64) -> RasterProjection {
        let s = self.standards();
        let basis = self.basis();
        let scale = self.units_per_mm;
        let r = s.lens.z_axis;
        let centre = s.film_center.truncate() * scale;
        let [w, h] = self.film_mm.map(|v| 0.5 * v * scale);
        // ndc = (a / w, b / h), z_ndc = 2 z / far - 1, with the view frame's z = -z.
        let projection = DMat4::from_cols(
            DVec4::new(1.0 / w, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / h, 0.0, 0.0),
            DVec4::new(r.x / r.z / w, r.y / r.z / h, -2.0 / far, 0.0),
            DVec4::new(-centre.x / w, -centre.y / h, -1.0, 1.0),
        );
        RasterProjection {
            view: view_matrix(basis.right, basis.up, basis.forward, self.position),
            frustum: Frustum {
                left: centre.x - w,
                right: centre.x + w,
                bottom: centre.y - h,
                top: centre.y + h,
                near: 0.0,
                far,
            },
            projection,
        }
    }
}

/// World to view space, OpenGL's convention: the eye at `eye` looking down -z along `forward`.
fn view_matrix(right: DVec3, up: DVec3, forward: DVec3, eye: DVec3) -> DMat4 {
    let back = -forward;
    DMat4::from_cols(
        DVec4::new(right.x, up.x, back.x, 0.0),
        DVec4::new(right.y, up.y, back.y, 0.0),
        DVec4::new(right.z, up.z, back.z, 0.0),
        DVec4::new(-right.dot(eye), -up.dot(eye), -back.dot(eye), 1.0),
    )
}

/// glFrustum's parameters, in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Left edge of the window on the near plane.
    pub left: f64,
    /// Right edge of the window on the near plane.
    pub right: f64,
    /// Bottom edge of the window on the near plane.
    pub bottom: f64,
    /// Top edge of the window on the near plane.
    pub top: f64,
    /// Distance from the eye to the near plane, along the view axis.
    pub near: f64,
    /// Distance from the eye to the far plane, along the view axis.
    pub far: f64,
}

impl Frustum {
    /// The OpenGL off-axis perspective matrix (glFrustum), clip z in [-w, w].
    pub fn matrix(&self) -> DMat4 {
        let Frustum {
            left: l,
            right: r,
            bottom: b,
            top: t,
            near: n,
            far: f,
        } = *self;
        DMat4::from_cols(
            DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
            DVec4::new(
                (r + l) / (r - l),
                (t + b) / (t - b),
                -(f + n) / (f - n),
                -1.0,
            ),
            DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
        )
    }
}

/// View rotation + off-axis frustum (an orthographic camera: its window and oblique parallel
/// projection); `projection * view` maps world points to clip space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterProjection {
    /// World to view space (OpenGL convention: the eye at the origin, looking down -z, along the
    /// film normal).
    pub view: DMat4,
    /// The off-axis frustum in view space.
    pub frustum: Frustum,
    /// `frustum.matrix()`: view space to clip space.
    pub projection: DMat4,
}

impl RasterProjection {
    /// World to clip space: `projection * view`.
    pub fn matrix(&self) -> DMat4 {
        self.projection * self.view
    }

    /// Raster position (pixels, x right, y down) of a world point, `None` behind the eye.
    pub fn project(&self, p: DVec3, width: u32, height: u32) -> Option<DVec2> {
        let clip = self.matrix() * p.extend(1.0);
        (clip.w > 0.0).then(|| {
            let ndc = DVec2::new(clip.x, clip.y) / clip.w;
            DVec2::new(
                0.5 * (ndc.x + 1.0) * width as f64,
                0.5 * (1.0 - ndc.y) * height as f64,
            )
        })
    }
}

/// The lens movements and focus that put the plane of sharp focus through three points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FocusSolution {
    /// Lens tilt (degrees).
    pub lens_tilt: f64,
    /// Lens swing (degrees).
    pub lens_swing: f64,
    /// Lens centre to the film pivot (mm): the bellows extension.
    pub film_distance_mm: f64,
}

/// How many times [`solve_focus_points`] re-solves before it gives up: the lens centre moves
/// with the tilt when the lens turns about a pivot away from it, and a thick lens's H moves
/// along its axis; each pass shrinks the error by about pivot distance (or gap) over object
/// distance.
const FOCUS_ITERATIONS: usize = 100;

/// Solve `focus_points` for a camera whose film movements, lens shift and pivot, and lens are
/// set: the thin-lens solution from the front principal point H, re-solved until the lens
/// centre and H stop moving with the tilt it finds (once for a thin lens turned about its
/// centre). A real lens's paraxial solution is then refined by tracing
/// (`lens_focus::refine_focus_points`).
pub fn solve_focus_points(
    camera: &CameraSpec,
    points: [DVec3; 3],
) -> Result<FocusSolution, String> {
    let mut trial = camera.clone();
    let mut last: Option<FocusSolution> = None;
    for _ in 0..FOCUS_ITERATIONS {
        let solution = solve_with_lens_centre_fixed(&trial, points)?;
        if last == Some(solution) || last.is_some_and(|l| l.settled_with(&solution)) {
            return Ok(solution);
        }
        trial.movements.lens_tilt = solution.lens_tilt;
        trial.movements.lens_swing = solution.lens_swing;
        trial.film_distance_mm = solution.film_distance_mm;
        last = Some(solution);
    }
    Err(format!(
        "the focus does not settle in {FOCUS_ITERATIONS} passes: the lens's pivot lies too far \
         from it for points this near"
    ))
}

impl FocusSolution {
    /// Whether two passes agree to rounding (1e-12 degrees, 1e-12 of the film distance).
    fn settled_with(&self, next: &FocusSolution) -> bool {
        (self.lens_tilt - next.lens_tilt).abs() <= 1e-12
            && (self.lens_swing - next.lens_swing).abs() <= 1e-12
            && (self.film_distance_mm - next.film_distance_mm).abs()
                <= 1e-12 * next.film_distance_mm
    }
}

/// One pass of [`solve_focus_points`], with the lens centre where `camera`'s current tilt puts
/// it and H `principal_gap` ahead of it along its current axis.
///
/// With the points' plane m.X = e (camera frame, origin at the lens centre, |m| = 1, e > 0),
/// e_H = e - gap (m . a_current) its offset from H, and the film normal n_f, the Scheimpflug and
/// hinge rules leave one family of lens axes: a = (f / e_H)(m - mu n_f) with |a| = 1, a
/// quadratic in mu; the root whose axis lies nearer the rail is taken. The film distance then
/// follows from the conjugate of the plane.
fn solve_with_lens_centre_fixed(
    camera: &CameraSpec,
    points: [DVec3; 3],
) -> Result<FocusSolution, String> {
    let f = camera.focal_length_mm;
    let gap = camera.principal_gap();
    let s = camera.standards();
    let local: Vec<DVec3> = points
        .iter()
        .map(|p| camera.world_to_camera(*p) - s.lens_center)
        .collect();
    for (i, p) in local.iter().enumerate() {
        if p.z <= 0.0 {
            return Err(format!("point {i} lies behind the lens"));
        }
    }
    let span = local[1] - local[0];
    let cross = span.cross(local[2] - local[0]);
    let size = span.length().max((local[2] - local[0]).length());
    if cross.length() <= 1e-9 * size * size {
        return Err("the three points are collinear (or coincide): they fix no plane".into());
    }
    let mut m = cross.normalize();
    let mut e = m.dot(local[0]);
    if e < 0.0 {
        m = -m;
        e = -e;
    }
    if e <= 1e-9 * local[0].length() {
        return Err("the plane through the points passes through the lens centre".into());
    }
    let e = e - gap * m.dot(s.lens.z_axis);
    if e <= 1e-9 * local[0].length() {
        return Err(
            "the plane through the points passes through the lens's front principal \
                    point"
                .into(),
        );
    }
    let film_normal = s.film.z_axis;
    let cos_mf = m.dot(film_normal);
    let discriminant = cos_mf * cos_mf - 1.0 + (e / f) * (e / f);
    if discriminant < 0.0 {
        return Err(format!(
            "the plane through the points passes {e:.4} mm from the lens centre, too close for \
             a lens of {f} mm to focus on it (it would need more than a 90 degree tilt)"
        ));
    }
    let axis = |mu: f64| (f / e) * (m - mu * film_normal);
    let root = discriminant.sqrt();
    let a = [axis(cos_mf + root), axis(cos_mf - root)]
        .into_iter()
        .max_by(|x, y| x.z.total_cmp(&y.z))
        .unwrap();
    if a.z <= 1e-9 {
        return Err("the lens would have to turn 90 degrees or more to focus on the points".into());
    }
    for (i, p) in local.iter().enumerate() {
        if a.dot(*p) - gap <= f {
            return Err(format!(
                "point {i} lies {:.4} mm in front of the lens, within its focal length {f} mm: \
                 no real image of it forms",
                a.dot(*p) - gap
            ));
        }
    }
    let lens_tilt = (-a.y).clamp(-1.0, 1.0).asin().to_degrees();
    let lens_swing = a.x.atan2(a.z).to_degrees();
    // The film plane n.A = c (lens frame) whose conjugate is the points' plane:
    // f n + c e_z = (c f / e) m_l  =>  c = f / (((f / e) m_l - e_z) . n).
    let lens = standard_rotation(lens_tilt, lens_swing);
    let m_lens = lens.transpose() * m;
    let n_lens = lens.transpose() * film_normal;
    let c = f / (((f / e) * m_lens - DVec3::Z).dot(n_lens));
    // The film's offset from the lens centre this pass assumed (where the found tilt puts it
    // is the next pass's).
    let film_distance_mm = -(c + film_normal.dot(s.lens_center)) / film_normal.z;
    if !(film_distance_mm.is_finite() && film_distance_mm > 0.0) {
        return Err(format!(
            "no film position focuses on the points (film distance {film_distance_mm:.4} mm)"
        ));
    }
    Ok(FocusSolution {
        lens_tilt,
        lens_swing,
        film_distance_mm,
    })
}
