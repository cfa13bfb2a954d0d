//! Primary-ray generation: the physical camera (pinhole or thin lens).
//! Twin: `wgsl/camera.wgsl`. Model and equations: `docs/camera.md`.
//!
//! Rays are generated in the *lens frame* (lens plane z = 0, optical axis +z) with the paraxial
//! ray-transfer form of the ideal thin lens: a ray from film point A through lens point L has
//! incoming slope (L - A.xy) / (-A.z) and leaves with slope `incoming - L / f`. Every ray of a
//! film point then passes through that point's conjugate, the form needs no division by
//! (s_i - f), and focus at infinity (film at f: parallel rays) is not a special case.

use glam::{DVec3, Vec2, Vec3};

use crate::layout::GpuCamera;
use crate::math::sampling::concentric_disk;

/// The validated camera of a scene, in the units of the scene file (f64 until uploaded).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpec {
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    pub focal_length_mm: f64,
    pub film_mm: [f64; 2],
    /// 0: pinhole.
    pub f_number: f64,
    /// Focus distance along the optical axis in scene units; `None`: infinity.
    pub focus_distance: Option<f64>,
    /// Scene units per millimetre (0.001 / meters_per_unit).
    pub units_per_mm: f64,
}

/// An orthonormal camera basis: right = forward x up, image row 0 at the top.
#[derive(Clone, Copy, Debug)]
pub struct CameraBasis {
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
}

impl CameraSpec {
    pub fn basis(&self) -> CameraBasis {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        CameraBasis {
            right,
            up: right.cross(forward),
            forward,
        }
    }

    pub fn is_pinhole(&self) -> bool {
        self.f_number == 0.0
    }

    /// 1 / focus distance in 1/mm; 0 for focus at infinity (the finite sentinel the GPU gets).
    pub fn inv_focus_distance_mm(&self) -> f64 {
        self.focus_distance.map_or(0.0, |d| self.units_per_mm / d)
    }

    /// Lens-to-film distance s_i in mm: 1/(1/f - 1/s_o) for a lens, f for a pinhole.
    pub fn image_distance_mm(&self) -> f64 {
        if self.is_pinhole() {
            return self.focal_length_mm;
        }
        1.0 / (1.0 / self.focal_length_mm - self.inv_focus_distance_mm())
    }

    pub fn lens_radius_mm(&self) -> f64 {
        if self.is_pinhole() {
            0.0
        } else {
            self.focal_length_mm / (2.0 * self.f_number)
        }
    }

    /// Horizontal and vertical field of view in degrees, from the film size and s_i.
    pub fn field_of_view_deg(&self) -> [f64; 2] {
        let s_i = self.image_distance_mm();
        self.film_mm
            .map(|size| 2.0 * (0.5 * size / s_i).atan().to_degrees())
    }

    /// The camera as the kernels see it.
    pub fn to_gpu(&self) -> GpuCamera {
        let basis = self.basis();
        let f32x3 = |v: DVec3| v.as_vec3().to_array();
        GpuCamera {
            lens_to_world_x: f32x3(basis.right),
            focal_length_mm: self.focal_length_mm as f32,
            lens_to_world_y: f32x3(basis.up),
            lens_radius_mm: self.lens_radius_mm() as f32,
            lens_to_world_z: f32x3(basis.forward),
            units_per_mm: self.units_per_mm as f32,
            lens_center: f32x3(self.position),
            inv_focal_length_mm: (1.0 / self.focal_length_mm) as f32,
            // The film is the mirror image of the projection plane through the lens centre:
            // image right/up run along -x/-y of the lens frame, so images come out upright.
            film_center: [0.0, 0.0, -self.image_distance_mm() as f32],
            film_width_mm: self.film_mm[0] as f32,
            film_u: [-1.0, 0.0, 0.0],
            film_height_mm: self.film_mm[1] as f32,
            film_v: [0.0, -1.0, 0.0],
            _pad0: 0,
        }
    }
}

/// A ray in world space; `direction` is unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
}

/// Image-plane position in mm (x right, y up, centred) of a point `pixel` in raster space
/// (x right, y down, in pixels).
pub fn film_position_mm(camera: &GpuCamera, width: u32, height: u32, raster: Vec2) -> Vec2 {
    Vec2::new(
        (raster.x / width as f32 - 0.5) * camera.film_width_mm,
        (0.5 - raster.y / height as f32) * camera.film_height_mm,
    )
}

/// The ray from image-plane point `film_mm` through the lens point drawn from `lens_u`.
pub fn generate_ray(camera: &GpuCamera, film_mm: Vec2, lens_u: [f32; 2]) -> Ray {
    let film_point = Vec3::from(camera.film_center)
        + film_mm.x * Vec3::from(camera.film_u)
        + film_mm.y * Vec3::from(camera.film_v);
    let lens = if camera.lens_radius_mm > 0.0 {
        camera.lens_radius_mm * Vec2::from(concentric_disk(lens_u))
    } else {
        Vec2::ZERO
    };
    // Thin-lens ray transfer: outgoing slope = incoming slope - h / f.
    let slope_in = (lens - film_point.truncate()) / -film_point.z;
    let slope_out = slope_in - lens * camera.inv_focal_length_mm;
    let direction_lens = slope_out.extend(1.0).normalize();
    let origin_lens = lens.extend(0.0) * camera.units_per_mm;
    Ray {
        origin: Vec3::from(camera.lens_center) + lens_to_world(camera, origin_lens),
        direction: lens_to_world(camera, direction_lens),
    }
}

fn lens_to_world(camera: &GpuCamera, v: Vec3) -> Vec3 {
    v.x * Vec3::from(camera.lens_to_world_x)
        + v.y * Vec3::from(camera.lens_to_world_y)
        + v.z * Vec3::from(camera.lens_to_world_z)
}
