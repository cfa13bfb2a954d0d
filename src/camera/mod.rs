//! Primary-ray generation: the view camera (pinhole or thin lens, with film and lens movements).
//! Twin: `wgsl/camera.wgsl`. Model, conventions and equations: `docs/camera.md`.
//!
//! Geometry is built in f64 in the *camera frame* (x right, y up, z forward, origin at the lens
//! centre before any lens shift, lengths in mm): the lens is rotated by L = R_y(lens_swing) *
//! R_x(lens_tilt) about its pivot (its centre unless `lens_pivot` moves it) and shifted by
//! `lens_shift`; the film is rotated by T = R_y(-film_swing) * R_x(film_tilt) about the point
//! where the rail axis meets it, at `film_distance` behind the lens, and shifted within its
//! rotated plane by `film_shift`.
//!
//! The kernels then work in the *lens frame* (lens plane z = 0, optical axis +z) with the paraxial
//! ray-transfer form of the ideal thin lens: a ray from film point A through lens point P has
//! incoming slope (P - A.xy) / (-A.z) and leaves with slope `incoming - P / f`. Every ray of a
//! film point then passes through that point's conjugate, the form needs no division by
//! (s_i - f), and focus at infinity (parallel rays) or a film point nearer than f (a virtual
//! conjugate) is not a special case. All movements fold into the uploaded [`GpuCamera`]; ray
//! generation costs the same with or without them.
//!
//! An orthographic camera ([`Projection::Orthographic`]) has no lens: its film is a window in the
//! camera frame's plane z = 0 (through `position`, square to the view), of the scene file's size
//! in scene units (held here in mm, divided by `units_per_mm`, so that both projections share one
//! frame) and moved within it by the film shift; every ray leaves its window point along one
//! direction, T^-1 z for the film rotation T: the film tilt and swing turn the rays away from the
//! window's normal as they turn a view camera's film away from its rays, which makes the
//! projection oblique (docs/camera.md, "Orthographic camera").

pub mod coverage;
pub mod glass;
pub mod lens;
pub mod lens_focus;
pub mod optics;
pub mod report;
pub mod spectral;

use glam::{DMat3, DVec2, DVec3, Vec2, Vec3};

use crate::layout::{
    FOCUS_CYLINDER, FOCUS_PLANE, FOCUS_SPHERE, GpuCamera, LENS_PUPIL_CELLS, PROJECTION_LENS,
    PROJECTION_ORTHOGRAPHIC, PROJECTION_PERSPECTIVE,
};
use crate::sampler::SamplerName;

/// Film and lens movements in the scene file's units: degrees and millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Movements {
    /// Film rotation about the horizontal axis (degrees): corrects a camera pitched up by it.
    pub film_tilt: f64,
    /// Film rotation about the vertical axis (degrees): corrects a camera yawed right by it.
    pub film_swing: f64,
    /// [right, up] movement of the film within its plane (mm): moves the framing. An
    /// orthographic camera's window moves by it in its plane (given in scene units, held in mm).
    pub film_shift: [f64; 2],
    /// Lens rotation about its horizontal axis (degrees); positive turns the plane of sharp focus
    /// down.
    pub lens_tilt: f64,
    /// Lens rotation about its vertical axis (degrees); positive turns the plane of sharp focus to
    /// the right.
    pub lens_swing: f64,
    /// [right, up] movement of the lens (mm).
    pub lens_shift: [f64; 2],
    /// The point the lens turns about when tilted or swung (mm, in the unturned lens frame,
    /// from the lens centre): zero turns it about its centre (a real lens's rear nodal point
    /// H'); a point below the lens is a base tilt's axis (`docs/camera.md`).
    pub lens_pivot: [f64; 3],
}

/// How the focus was set (kept for reports; the geometry only needs `film_distance_mm`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Focus {
    /// A pinhole: the film at f, nothing to focus.
    Pinhole,
    /// `focus_distance` in scene units along the rail; `None`: infinity.
    Distance(Option<f64>),
    /// `film_distance` (bellows extension) given directly.
    FilmDistance,
    /// `focus_points`: lens tilt, swing and film distance solved from three world points.
    Points([DVec3; 3]),
}

/// How the camera's rays leave it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Through the lens centre (a pinhole) or the aperture (a thin lens): the view camera.
    #[default]
    Perspective,
    /// Parallel rays along the viewing axis from a window in scene units: an architect's
    /// elevation, glTF's orthographic camera. No lens.
    Orthographic,
}

/// The validated camera of a scene, in the units of the scene file (f64 until uploaded).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpec {
    /// Perspective (the view camera) or orthographic (parallel rays, no lens).
    pub projection: Projection,
    /// Lens centre before any lens shift (world, scene units).
    pub position: DVec3,
    /// The point the unmoved optical axis passes through (world, scene units).
    pub look_at: DVec3,
    /// World up direction for the view; not parallel to it.
    pub up: DVec3,
    /// Focal length (mm); infinite for an orthographic camera (the limit its parallel rays
    /// are).
    pub focal_length_mm: f64,
    /// Film width and height (mm); an orthographic camera's window (its scene units divided by
    /// `units_per_mm`).
    pub film_mm: [f64; 2],
    /// 0: pinhole.
    pub f_number: f64,
    /// How the focus was set.
    pub focus: Focus,
    /// Lens centre to the film's pivot (the rail axis), in mm: the bellows extension; 0 for an
    /// orthographic camera (its window lies in the plane through `position`).
    pub film_distance_mm: f64,
    /// Film and lens tilts, swings and shifts.
    pub movements: Movements,
    /// 0: circular aperture; n >= 3: regular polygon.
    pub aperture_blades: u32,
    /// Rotation of the polygonal aperture (degrees, counter-clockwise in the image).
    pub aperture_rotation_deg: f64,
    /// Pattern of the lens points.
    pub lens_sampler: SamplerName,
    /// Scene units per millimetre (0.001 / meters_per_unit).
    pub units_per_mm: f64,
    /// [open, close] (seconds): the interval each camera sample takes its time from.
    pub shutter: [f64; 2],
    /// The surface of sharp focus (a curved one takes `focus_distance` as its radius).
    pub focus_surface: FocusSurface,
    /// A real lens's prescription placed at its f-number (`camera.lens`), traced in place of the
    /// thin lens: its H' is the lens centre (docs/lens.md).
    pub lens: Option<lens::LensSystem>,
    /// The spectral mode (`camera.spectral`; a dispersive real lens only): each sample at its
    /// own wavelength ([`spectral`]).
    pub spectral: bool,
}

/// The surface a lens focuses on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FocusSurface {
    /// The thin lens's plane (tilted by lens tilt and swing: Scheimpflug).
    #[default]
    Plane,
    /// A sphere centred on the lens, of radius `focus_distance`: field curvature.
    Sphere,
    /// A cylinder about the lens's vertical axis, of radius `focus_distance`.
    Cylinder,
}

/// An orthonormal camera basis: right = forward x up, image row 0 at the top.
#[derive(Clone, Copy, Debug)]
pub struct CameraBasis {
    /// Image right (world, unit).
    pub right: DVec3,
    /// Image up (world, unit), orthogonal to `forward`.
    pub up: DVec3,
    /// Towards `look_at` (world, unit).
    pub forward: DVec3,
}

impl CameraBasis {
    /// World direction of a camera-frame vector.
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        v.x * self.right + v.y * self.up + v.z * self.forward
    }

    /// Camera-frame components of a world direction.
    pub fn to_camera(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }
}

/// The edge between `inside`, where `holds`, and `outside`, where it does not, by bisection
/// until the two are `tolerance` apart: the last point found to hold.
pub(crate) fn bisect_edge(
    mut inside: f64,
    mut outside: f64,
    tolerance: f64,
    holds: impl Fn(f64) -> bool,
) -> f64 {
    while (outside - inside).abs() > tolerance {
        let middle = 0.5 * (inside + outside);
        if holds(middle) {
            inside = middle;
        } else {
            outside = middle;
        }
    }
    inside
}

/// How far turning the lens by `lens` about `pivot` (mm from its centre, unturned lens frame)
/// moves its centre: p - L p.
fn turned_about_pivot(lens: DMat3, pivot: [f64; 3]) -> DVec3 {
    let pivot = DVec3::from_array(pivot);
    if pivot == DVec3::ZERO {
        return DVec3::ZERO;
    }
    pivot - lens * pivot
}

/// R_y(swing) * R_x(tilt) in camera-frame components (x right, y up, z forward): tilt first,
/// so the tilt axis follows the swing. R_x(t) * z = (0, -sin t, cos t).
pub fn standard_rotation(tilt_deg: f64, swing_deg: f64) -> DMat3 {
    DMat3::from_rotation_y(swing_deg.to_radians()) * DMat3::from_rotation_x(tilt_deg.to_radians())
}

/// The camera's optical parts in the camera frame (mm, origin at the unshifted lens centre).
#[derive(Clone, Copy, Debug)]
pub struct Standards {
    /// Lens centre (non-zero only with a lens shift).
    pub lens_center: DVec3,
    /// Lens rotation: columns are the lens frame's axes; column z is the optical axis.
    pub lens: DMat3,
    /// Where the film's rotation axis meets the rail: (0, 0, -film_distance).
    pub film_pivot: DVec3,
    /// Film rotation: its z column is the film normal (pointing at the lens).
    pub film: DMat3,
    /// Film point of image centre (the pivot moved by the film shift).
    pub film_center: DVec3,
    /// Film directions of image right and image up (mirror image: the film is inverted).
    pub film_u: DVec3,
    /// Film direction of image up (see `film_u`).
    pub film_v: DVec3,
}

impl Standards {
    /// Film point (camera frame, mm) of image-plane coordinates (mm, x right, y up, centred).
    pub fn film_point(&self, image_mm: DVec2) -> DVec3 {
        self.film_center + image_mm.x * self.film_u + image_mm.y * self.film_v
    }

    /// Camera-frame point -> lens frame.
    pub fn to_lens_frame(&self, p: DVec3) -> DVec3 {
        self.lens.transpose() * (p - self.lens_center)
    }
}

impl CameraSpec {
    /// The camera frame's axes in world space, from `position`, `look_at` and `up`.
    pub fn basis(&self) -> CameraBasis {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        CameraBasis {
            right,
            up: right.cross(forward),
            forward,
        }
    }

    /// Whether there is no lens (`f_number` 0): every ray passes through the lens centre (or,
    /// orthographic, they all run parallel).
    pub fn is_pinhole(&self) -> bool {
        self.f_number == 0.0
    }

    /// Whether the rays are parallel (an orthographic camera).
    pub fn is_orthographic(&self) -> bool {
        self.projection == Projection::Orthographic
    }

    /// An orthographic camera's window [width, height] in scene units (the film scaled by
    /// `units_per_mm`).
    pub fn window(&self) -> [f64; 2] {
        self.film_mm.map(|v| v * self.units_per_mm)
    }

    /// How far the front principal point H lies ahead of the lens centre H' along the optical
    /// axis (mm): object distances count from H. 0 for the thin lens, whose H and H' coincide.
    pub fn principal_gap(&self) -> f64 {
        self.lens.as_ref().map_or(0.0, |l| l.principal_gap())
    }

    /// Aperture radius, f / (2 N), in mm; 0 for a pinhole.
    pub fn lens_radius_mm(&self) -> f64 {
        if self.is_pinhole() {
            0.0
        } else {
            self.focal_length_mm / (2.0 * self.f_number)
        }
    }

    /// The lens and film placed by the movements, in the camera frame (mm).
    pub fn standards(&self) -> Standards {
        if self.is_orthographic() {
            return self.orthographic_window();
        }
        let m = &self.movements;
        let lens = standard_rotation(m.lens_tilt, m.lens_swing);
        let film = standard_rotation(m.film_tilt, -m.film_swing);
        let film_pivot = DVec3::new(0.0, 0.0, -self.film_distance_mm);
        // The film is the mirror image of the projection plane through the lens centre: image
        // right and up run along -x and -y of the film's own frame.
        let film_u = -film.x_axis;
        let film_v = -film.y_axis;
        Standards {
            lens_center: DVec3::new(m.lens_shift[0], m.lens_shift[1], 0.0)
                + turned_about_pivot(lens, m.lens_pivot),
            lens,
            film_pivot,
            film,
            film_center: film_pivot + m.film_shift[0] * film_u + m.film_shift[1] * film_v,
            film_u,
            film_v,
        }
    }

    /// An orthographic camera's window as its `Standards`: the window in the camera frame's
    /// plane z = 0, image right and up along x and y (nothing inverts it: there is no lens), its
    /// centre moved by the film shift; `film` is the film rotation T, and `lens` (the frame the
    /// kernels work in) its inverse, whose z axis T^-1 z is the rays' direction. So the rays
    /// stand to the window as a view camera's rays to its film turned by T.
    fn orthographic_window(&self) -> Standards {
        let m = &self.movements;
        let film = standard_rotation(m.film_tilt, -m.film_swing);
        Standards {
            lens_center: DVec3::ZERO,
            lens: film.transpose(),
            film_pivot: DVec3::ZERO,
            film,
            film_center: DVec3::new(m.film_shift[0], m.film_shift[1], 0.0),
            film_u: DVec3::X,
            film_v: DVec3::Y,
        }
    }

    /// Camera-frame point in mm -> world point.
    pub fn camera_to_world(&self, p_mm: DVec3) -> DVec3 {
        self.position + self.basis().to_world(p_mm * self.units_per_mm)
    }

    /// World point -> camera-frame point in mm.
    pub fn world_to_camera(&self, p: DVec3) -> DVec3 {
        self.basis().to_camera(p - self.position) / self.units_per_mm
    }

    /// The film's four corners in the lens frame (mm).
    pub fn film_corners_in_lens_frame(&self) -> [DVec3; 4] {
        let s = self.standards();
        let [w, h] = self.film_mm.map(|v| 0.5 * v);
        [(-w, -h), (w, -h), (w, h), (-w, h)]
            .map(|(x, y)| s.to_lens_frame(s.film_point(DVec2::new(x, y))))
    }

    /// Horizontal and vertical field of view in degrees: the angles the film's edge midpoints
    /// subtend at the lens centre (for an unmoved camera, 2 atan(size / 2 s_i)); 0 for an
    /// orthographic camera, whose rays are parallel.
    pub fn field_of_view_deg(&self) -> [f64; 2] {
        if self.is_orthographic() {
            return [0.0; 2];
        }
        let s = self.standards();
        let angle = |a: DVec2, b: DVec2| {
            let (pa, pb) = (
                s.film_point(a) - s.lens_center,
                s.film_point(b) - s.lens_center,
            );
            pa.angle_between(pb).to_degrees()
        };
        let [w, h] = self.film_mm.map(|v| 0.5 * v);
        [
            angle(DVec2::new(-w, 0.0), DVec2::new(w, 0.0)),
            angle(DVec2::new(0.0, -h), DVec2::new(0.0, h)),
        ]
    }

    /// The angle between an orthographic camera's rays and its window's normal (the view
    /// direction), in degrees: 0 for rays square to the window, otherwise the obliquity the film
    /// tilt and swing give the projection.
    pub fn oblique_angle_deg(&self) -> f64 {
        self.standards()
            .lens
            .z_axis
            .angle_between(DVec3::Z)
            .to_degrees()
    }

    /// An orthographic camera's rays' direction in the world: T^-1 z in the camera frame.
    pub fn ray_direction(&self) -> DVec3 {
        self.basis().to_world(self.standards().lens.z_axis)
    }

    /// The camera as the kernels see it. `aperture_table_offset` locates the polygon's vertices
    /// in the sample table.
    pub fn to_gpu(&self, aperture_table_offset: u32) -> GpuCamera {
        let basis = self.basis();
        let s = self.standards();
        let f32x3 = |v: DVec3| v.as_vec3().to_array();
        let lens_axis_world = |column: DVec3| f32x3(basis.to_world(column));
        let film_dir = |v: DVec3| f32x3(s.lens.transpose() * v);
        let (focal_length_mm, inv_focal_length_mm, projection) = match self.projection {
            Projection::Perspective if self.lens.is_some() => (
                self.focal_length_mm as f32,
                (1.0 / self.focal_length_mm) as f32,
                PROJECTION_LENS,
            ),
            Projection::Perspective => (
                self.focal_length_mm as f32,
                (1.0 / self.focal_length_mm) as f32,
                PROJECTION_PERSPECTIVE,
            ),
            Projection::Orthographic => (0.0, 0.0, PROJECTION_ORTHOGRAPHIC),
        };
        GpuCamera {
            lens_to_world_x: lens_axis_world(s.lens.x_axis),
            focal_length_mm,
            lens_to_world_y: lens_axis_world(s.lens.y_axis),
            lens_radius_mm: self.lens_radius_mm() as f32,
            lens_to_world_z: lens_axis_world(s.lens.z_axis),
            units_per_mm: self.units_per_mm as f32,
            lens_center: f32x3(self.camera_to_world(s.lens_center)),
            inv_focal_length_mm,
            film_center: f32x3(s.to_lens_frame(s.film_center)),
            film_width_mm: self.film_mm[0] as f32,
            film_u: film_dir(s.film_u),
            film_height_mm: self.film_mm[1] as f32,
            film_v: film_dir(s.film_v),
            aperture_blades: self.aperture_blades,
            aperture_table_offset,
            shutter_open: self.shutter[0] as f32,
            shutter_span: (self.shutter[1] - self.shutter[0]) as f32,
            focus_surface: match self.focus_surface {
                FocusSurface::Plane => FOCUS_PLANE,
                FocusSurface::Sphere => FOCUS_SPHERE,
                FocusSurface::Cylinder => FOCUS_CYLINDER,
            },
            focus_radius_mm: match self.focus {
                Focus::Distance(Some(d)) => (d / self.units_per_mm) as f32,
                _ => 0.0,
            },
            projection,
            lens_surface_count: self.lens.as_ref().map_or(0, |l| l.surfaces.len() as u32),
            spectral: self.spectral as u32,
            ..Default::default()
        }
    }

    /// A real lens's table for the kernels (`LensSystem::kernel_table`): each film cell's
    /// bounds searched from [`pupil_cell_points`](Self::pupil_cell_points); empty without a lens.
    pub fn lens_table(&self) -> Vec<[f32; 2]> {
        let Some(lens) = &self.lens else {
            return Vec::new();
        };
        lens.kernel_table(
            self.film_distance_mm,
            |i, j| self.pupil_cell_points(i, j),
            self.spectral,
        )
    }

    /// The film points (lens frame, mm) whose rays bound the exit pupil of film cell (column i,
    /// row j from the bottom) of the `LENS_PUPIL_CELLS`^2: its four corners and its centre.
    pub fn pupil_cell_points(&self, i: u32, j: u32) -> Vec<DVec3> {
        let s = self.standards();
        let cells = LENS_PUPIL_CELLS as f64;
        let [w, h] = self.film_mm;
        let film = |x: f64, y: f64| {
            s.to_lens_frame(s.film_point(DVec2::new((x / cells - 0.5) * w, (y / cells - 0.5) * h)))
        };
        let (x, y) = (i as f64, j as f64);
        vec![
            film(x, y),
            film(x + 1.0, y),
            film(x, y + 1.0),
            film(x + 1.0, y + 1.0),
            film(x + 0.5, y + 0.5),
        ]
    }
}

/// A ray in world space; `direction` is unit length.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ray {
    /// Origin (world, scene units).
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

/// Image-plane position in mm (x right, y up, centred) of a point `raster` in raster space
/// (x right, y down, in pixels).
pub fn film_position_mm(camera: &GpuCamera, width: u32, height: u32, raster: Vec2) -> Vec2 {
    Vec2::new(
        (raster.x / width as f32 - 0.5) * camera.film_width_mm,
        (0.5 - raster.y / height as f32) * camera.film_height_mm,
    )
}

/// The ray from image-plane point `film_mm` through the lens point `lens_mm` (lens frame, mm;
/// from `sampler::sample_aperture`, or the centre for a pinhole).
pub fn generate_ray(camera: &GpuCamera, film_mm: Vec2, lens_mm: Vec2) -> Ray {
    let film_point = Vec3::from(camera.film_center)
        + film_mm.x * Vec3::from(camera.film_u)
        + film_mm.y * Vec3::from(camera.film_v);
    if camera.projection == PROJECTION_ORTHOGRAPHIC {
        // Parallel rays along the lens frame's z, each from its window point.
        let origin_lens = film_point * camera.units_per_mm;
        return Ray {
            origin: Vec3::from(camera.lens_center) + lens_to_world(camera, origin_lens),
            direction: Vec3::from(camera.lens_to_world_z),
        };
    }
    let direction_lens = if camera.focus_surface == FOCUS_PLANE {
        // Thin-lens ray transfer: outgoing slope = incoming slope - h / f.
        let slope_in = (lens_mm - film_point.truncate()) / -film_point.z;
        let slope_out = slope_in - lens_mm * camera.inv_focal_length_mm;
        slope_out.extend(1.0).normalize()
    } else {
        // The chief ray's point on the curved surface, then the ray from the lens point to it.
        let sharp = curved_focus_point(camera.focus_surface, camera.focus_radius_mm, film_point);
        (sharp - lens_mm.extend(0.0)).normalize()
    };
    let origin_lens = lens_mm.extend(0.0) * camera.units_per_mm;
    Ray {
        origin: Vec3::from(camera.lens_center) + lens_to_world(camera, origin_lens),
        direction: lens_to_world(camera, direction_lens),
    }
}

/// The ray from image-plane point `film_mm` through a real lens (`PROJECTION_LENS`), aimed at
/// the point `u` (in [0, 1)^2) of its film cell's exit-pupil bounds, with its weight (0: lost in
/// the lens, the ray then the chief ray through the lens centre), at `wavelength_nm` in the
/// spectral mode (0: the reference line). Twin: `generate_lens_ray` in wgsl/camera.wgsl.
pub fn generate_lens_ray(
    camera: &GpuCamera,
    table: &[[f32; 2]],
    film_mm: Vec2,
    u: [f32; 2],
    wavelength_nm: f32,
) -> (Ray, f32) {
    let film_u = Vec3::from(camera.film_u);
    let film_v = Vec3::from(camera.film_v);
    let film_point = Vec3::from(camera.film_center) + film_mm.x * film_u + film_mm.y * film_v;
    let cells = LENS_PUPIL_CELLS as f32;
    let cell = |x: f32, size: f32| ((x / size + 0.5) * cells).clamp(0.0, cells - 1.0) as u32;
    let traced = lens::lens_ray(
        table,
        camera.lens_table_offset,
        camera.lens_surface_count,
        film_point,
        film_u.cross(film_v),
        [
            cell(film_mm.x, camera.film_width_mm),
            cell(film_mm.y, camera.film_height_mm),
        ],
        u,
        wavelength_nm,
    );
    let ray = Ray {
        origin: Vec3::from(camera.lens_center)
            + lens_to_world(camera, traced.origin * camera.units_per_mm),
        direction: lens_to_world(camera, traced.direction),
    };
    (ray, traced.weight)
}

/// Where the chief ray of film point `film_point` (lens frame, mm; the lens centre at the
/// origin) meets a curved focal surface of radius `radius_mm`: on the ray from the film point
/// through the lens centre, at distance `radius_mm` from the centre (a sphere) or from the
/// lens's vertical axis (a cylinder). Twin: `curved_focus_point` in camera.wgsl.
pub fn curved_focus_point(surface: u32, radius_mm: f32, film_point: Vec3) -> Vec3 {
    let chief = -film_point.normalize();
    let reach = if surface == FOCUS_CYLINDER {
        chief.x.hypot(chief.z)
    } else {
        1.0
    };
    chief * (radius_mm / reach)
}

/// [`generate_ray`] in f64 from the camera's own f64 description: the same thin-lens transfer
/// without rounding to f32 anywhere (`chambre bench precision` measures the f32 version against
/// it). Returns (origin, unit direction) in world space.
pub fn generate_ray_f64(camera: &CameraSpec, film_mm: DVec2, lens_mm: DVec2) -> (DVec3, DVec3) {
    let s = camera.standards();
    let basis = camera.basis();
    let film_point = s.to_lens_frame(s.film_point(film_mm));
    if camera.is_orthographic() {
        return (
            camera.camera_to_world(s.film_point(film_mm)),
            basis.to_world(s.lens.z_axis),
        );
    }
    let direction_lens = match (camera.focus_surface, camera.focus) {
        (FocusSurface::Sphere | FocusSurface::Cylinder, Focus::Distance(Some(d))) => {
            let radius = d / camera.units_per_mm;
            let chief = -film_point.normalize();
            let reach = match camera.focus_surface {
                FocusSurface::Cylinder => chief.x.hypot(chief.z),
                _ => 1.0,
            };
            (chief * (radius / reach) - lens_mm.extend(0.0)).normalize()
        }
        _ => {
            let slope_in = (lens_mm - film_point.truncate()) / -film_point.z;
            let slope_out = slope_in - lens_mm / camera.focal_length_mm;
            slope_out.extend(1.0).normalize()
        }
    };
    let origin_lens = lens_mm.extend(0.0) * camera.units_per_mm;
    (
        camera.camera_to_world(s.lens_center) + basis.to_world(s.lens * origin_lens),
        basis.to_world(s.lens * direction_lens),
    )
}

fn lens_to_world(camera: &GpuCamera, v: Vec3) -> Vec3 {
    v.x * Vec3::from(camera.lens_to_world_x)
        + v.y * Vec3::from(camera.lens_to_world_y)
        + v.z * Vec3::from(camera.lens_to_world_z)
}
