//! Real lenses: the shipped prescriptions read, their paraxial properties (ray-transfer matrices)
//! against exact rays traced through their surfaces in the paraxial limit, and rays lost to the
//! stop and the barrel.

use std::path::Path;

use chambre::camera::lens::{LensSystem, Lost, Prescription};
use glam::DVec3;

/// The shipped lenses and their nominal focal lengths (mm), as their sources state them.
const LENSES: [(&str, f64); 3] = [
    ("scenes/lenses/dgauss_50mm.dat", 50.0),
    ("scenes/lenses/wide_22mm.dat", 22.0),
    ("scenes/lenses/telephoto_250mm.dat", 254.0),
];

fn lens(path: &str) -> LensSystem {
    let prescription = Prescription::read(Path::new(path)).unwrap();
    LensSystem::new(&prescription, None).unwrap()
}

/// A ray from the rear focal point at a small angle leaves the lens parallel to the axis, at
/// the height f tan(angle): the traced back focal distance and focal length agree with the
/// paraxial ones to 1e-6 (the angle, 1e-6 rad, leaves aberrations of order 1e-12).
#[test]
fn traced_rays_in_the_paraxial_limit_agree_with_the_transfer_matrices() {
    for (path, nominal) in LENSES {
        let lens = lens(path);
        let f = lens.paraxial.focal_length;
        assert!(
            (f / nominal - 1.0).abs() < 0.02,
            "{path}: f = {f} mm, nominal {nominal}"
        );
        let angle = 1e-6_f64;
        let direction = DVec3::new(0.0, angle.sin(), angle.cos());
        let (origin, out) = lens
            .trace_from_film(DVec3::new(0.0, 0.0, -f), direction)
            .unwrap_or_else(|lost| panic!("{path}: {lost:?}"));
        let focal_error = (out.y / out.z).abs() * f / (f * angle.tan());
        assert!(focal_error < 1e-6, "{path}: not parallel: {focal_error:e}");
        let traced_f = origin.y / angle.tan();
        assert!(
            (traced_f / f - 1.0).abs() < 1e-6,
            "{path}: {traced_f} against {f}"
        );
    }
}

/// Stopped down, the marginal rays of the widest aperture are lost at the stop and the axial
/// rays within it pass; a ray far off axis is lost to a barrel, never returned.
#[test]
fn the_stop_and_the_barrel_stop_rays() {
    let prescription = Prescription::read(Path::new(LENSES[0].0)).unwrap();
    let wide = LensSystem::new(&prescription, None).unwrap();
    let stopped = LensSystem::new(&prescription, Some(8.0)).unwrap();
    let f = wide.paraxial.focal_length;
    let from = DVec3::new(0.0, 0.0, -f);
    // Aimed at the rear element's edge: through at f/2, stopped at f/8.
    let rear = wide.surfaces[0];
    let edge = DVec3::new(0.0, 0.9 * rear.aperture_radius, rear.z) - from;
    assert!(wide.trace_from_film(from, edge.normalize()).is_ok());
    let stop = stopped
        .surfaces
        .iter()
        .position(|s| s.radius == 0.0)
        .unwrap();
    assert_eq!(
        stopped.trace_from_film(from, edge.normalize()),
        Err(Lost::Blocked(stop))
    );
    let far = DVec3::new(0.0, 0.8, 1.0).normalize();
    assert!(matches!(
        wide.trace_from_film(from, far),
        Err(Lost::Blocked(_))
    ));
}

/// Through a small stop that nothing else vignettes, the relative illumination follows the
/// cos^4 law of the angle the film point sees the exit pupil's centre at (a biconvex lens of
/// 100 mm at f/16, its stop in front; within 1% out to 17 degrees), and a lens stopped down
/// loses less to vignetting than wide open, never more.
#[test]
fn relative_illumination_follows_the_cosine_fourth_law_through_a_small_stop() {
    let f = 100.0_f64;
    let sag = f - (f * f - 100.0).sqrt();
    let text = format!("0 0 1 10\n{f} {} 1.5 20\n{} 0 1 20\n", 2.0 * sag + 0.1, -f);
    let prescription = Prescription::parse(Path::new("biconvex.dat"), &text).unwrap();
    let lens = LensSystem::new(&prescription, Some(16.0)).unwrap();
    let p = lens.paraxial;
    let exit_pupil_z = p.rear_principal - p.exit_pupil;
    let film = p.focal_length;
    for r in [5.0, 15.0, 30.0] {
        let relative = lens.relative_illumination(r, film, 400);
        let cos = (film + exit_pupil_z) / (r * r + (film + exit_pupil_z).powi(2)).sqrt();
        let law = cos.powi(4);
        assert!((relative / law - 1.0).abs() < 0.01, "r {r}: {relative} against {law}");
    }
    let prescription = Prescription::read(Path::new(LENSES[0].0)).unwrap();
    let open = LensSystem::new(&prescription, None).unwrap();
    let stopped = LensSystem::new(&prescription, Some(8.0)).unwrap();
    let film = open.paraxial.focal_length;
    let mut previous = 1.0;
    for r in [5.0, 10.0, 15.0, 20.0] {
        let (wide, narrow) = (
            open.relative_illumination(r, film, 128),
            stopped.relative_illumination(r, film, 128),
        );
        assert!(wide <= previous + 1e-9, "falls off the axis: {wide} after {previous}");
        assert!(narrow >= wide - 0.01, "r {r}: f/8 {narrow} against f/2 {wide}");
        previous = wide;
    }
}
