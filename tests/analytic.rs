//! Renders checked against values known in closed form.

mod common;

use std::f32::consts::PI;

use chambre::camera::Ray;
use chambre::camera::{film_position_mm, generate_ray};
use chambre::integrator::{CameraHit, FirstHit, LightWindow, SampleStats, trace_path};
use chambre::layout::FEATURES_ALL;
use chambre::math::rng::Rng;
use chambre::pack::flatten;
use chambre::scene::Scene;
use glam::{Vec2, Vec3};

fn scene(text: &str) -> Scene {
    Scene::from_str(std::path::Path::new("inline.toml"), text, &[])
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The sphere's diffuse reflectance in `LAMBERT_SPHERE`.
const ALBEDO: Vec3 = Vec3::new(0.5, 0.25, 0.125);

const LAMBERT_SPHERE: &str = r#"
[render]
width = 64
height = 64
spp = 16
[camera]
position = [0.0, 0.0, 10.0]
look_at = [0.0, 0.0, 0.0]
focal_length = 100.0
film = [24.0, 24.0]
[[materials]]
name = "m"
model = "lambert"
diffuse = [0.5, 0.25, 0.125]
[[shapes]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "m"
[[lights]]
type = "point"
position = [3.0, 4.0, 5.0]
intensity = [10.0, 10.0, 10.0]
"#;

fn lambert_expected(p: Vec3) -> Vec3 {
    let light = Vec3::new(3.0, 4.0, 5.0);
    let to_light = light - p;
    let cos = p.normalize().dot(to_light.normalize()).max(0.0);
    Vec3::new(0.5, 0.25, 0.125) / PI * 10.0 * cos / to_light.length_squared()
}

#[test]
fn lambert_sphere_under_point_light_matches_closed_form_on_cpu() {
    let flat = flatten(&scene(LAMBERT_SPHERE));
    let origin = Vec3::new(0.0, 0.0, 10.0);
    for target in [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.3, 0.4, 0.866_025_4),
        Vec3::new(-0.5, 0.2, 0.842_615),
    ] {
        let p = target.normalize();
        let mut first_hit = FirstHit::default();
        let radiance = trace_path::<FEATURES_ALL>(
            &flat,
            Ray {
                origin,
                direction: (p - origin).normalize(),
            },
            CameraHit::Trace,
            0.0,
            LightWindow::ALL,
            &mut Rng::new(0, 0, 0),
            &mut SampleStats::default(),
            &mut first_hit,
        );
        // The AOVs of the hit: its distance, the sphere's outward normal there, the albedo.
        let depth = (p - origin).length();
        assert!(
            (first_hit.depth - depth).abs() < 1e-5 * depth,
            "{first_hit:?}"
        );
        assert!(
            (first_hit.normal - p).abs().max_element() < 1e-5,
            "{first_hit:?}"
        );
        assert_eq!(first_hit.albedo, ALBEDO);
        let expected = lambert_expected(p);
        assert!(
            (radiance - expected).abs().max_element() <= 1e-5 * expected.max_element(),
            "{radiance} vs {expected}"
        );
    }
}

#[test]
fn lambert_sphere_pixels_match_closed_form_on_both_paths() {
    let flat = flatten(&scene(LAMBERT_SPHERE));
    let cpu = common::render_cpu(&flat);
    let gpu = common::render_gpu(&flat);
    // The centre ray of chosen pixels, intersected analytically with the unit sphere.
    for (x, y) in [(32, 32), (36, 28), (28, 38), (40, 33)] {
        let film = film_position_mm(
            &flat.camera,
            64,
            64,
            Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
        );
        let ray = generate_ray(&flat.camera, film, glam::Vec2::ZERO);
        let b = ray.origin.dot(ray.direction);
        let t = -b - (b * b - ray.origin.length_squared() + 1.0).sqrt();
        let expected = lambert_expected(ray.origin + t * ray.direction);
        // A pixel is the mean over its footprint; the field is smooth, so 1% covers curvature.
        for (name, image) in [("cpu", Some(&cpu)), ("gpu", gpu.as_ref())] {
            let Some(image) = image else { continue };
            let got = image.get(x, y);
            assert!(
                (got - expected).abs().max_element() <= 0.01 * expected.max_element(),
                "{name} ({x},{y}): {got} vs {expected}"
            );
        }
    }
}

#[test]
fn pinhole_projects_known_points_to_known_pixels() {
    // f = 18 mm on a 36 x 24 mm film: 90 degrees horizontally. Camera at the origin looking -z.
    let text = r#"
[render]
width = 360
height = 240
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
focal_length = 18.0
film = [36.0, 24.0]
"#;
    let flat = flatten(&scene(text));
    let cases = [
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(180.0, 120.0)),
        (Vec3::new(0.5, 0.0, -1.0), Vec2::new(270.0, 120.0)),
        (Vec3::new(-1.0, 0.0, -1.0), Vec2::new(0.0, 120.0)),
        (Vec3::new(0.0, 0.5, -1.0), Vec2::new(180.0, 30.0)),
        (Vec3::new(2.0, -1.0, -4.0), Vec2::new(270.0, 165.0)),
    ];
    for (world, raster) in cases {
        let film = film_position_mm(&flat.camera, 360, 240, raster);
        let ray = generate_ray(&flat.camera, film, glam::Vec2::ZERO);
        let to_point = world - ray.origin;
        let miss = (to_point - to_point.dot(ray.direction) * ray.direction).length();
        assert!(
            miss <= 1e-5 * to_point.length(),
            "{world} should be seen at pixel {raster}, ray misses by {miss}"
        );
    }
}

const SHADOW: &str = r#"
[render]
width = 64
height = 64
spp = 4
ambient = [0.2, 0.2, 0.2]
[camera]
position = [0.0, 2.0, 4.0]
look_at = [0.0, 0.0, 0.0]
focal_length = 50.0
film = [24.0, 24.0]
[[materials]]
name = "m"
model = "lambert"
diffuse = [0.8, 0.6, 0.4]
[[shapes]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
material = "m"
[[shapes]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.5
material = "m"
[[lights]]
type = "point"
position = [0.0, 3.0, 0.0]
intensity = [20.0, 20.0, 20.0]
"#;

#[test]
fn point_in_shadow_gets_only_the_ambient_term() {
    let flat = flatten(&scene(SHADOW));
    let ambient_only = Vec3::new(0.8, 0.6, 0.4) * 0.2;
    let radiance = trace_path::<FEATURES_ALL>(
        &flat,
        Ray {
            origin: Vec3::new(3.0, 1.0, 0.0),
            direction: Vec3::new(-3.0, -1.0, 0.0).normalize(),
        },
        CameraHit::Trace,
        0.0,
        LightWindow::ALL,
        &mut Rng::new(0, 0, 0),
        &mut SampleStats::default(),
        &mut FirstHit::default(),
    );
    assert!(
        (radiance - ambient_only).abs().max_element() < 1e-6,
        "{radiance}"
    );
    // A point outside the shadow gets more.
    let lit = trace_path::<FEATURES_ALL>(
        &flat,
        Ray {
            origin: Vec3::new(3.0, 1.0, 0.0),
            direction: Vec3::new(-1.0, -1.0, 0.0).normalize(),
        },
        CameraHit::Trace,
        0.0,
        LightWindow::ALL,
        &mut Rng::new(0, 0, 0),
        &mut SampleStats::default(),
        &mut FirstHit::default(),
    );
    assert!(lit.x > ambient_only.x * 2.0, "{lit}");
    // The image's centre pixel sees the ground under the sphere (umbra radius 0.75).
    let cpu = common::render_cpu(&flat);
    assert!((cpu.get(32, 32) - ambient_only).abs().max_element() < 1e-6);
    if let Some(gpu) = common::render_gpu(&flat) {
        assert!(
            (gpu.get(32, 32) - ambient_only).abs().max_element() < 1e-6,
            "{}",
            gpu.get(32, 32)
        );
    }
}

#[test]
fn mirror_shows_the_object_behind_the_camera() {
    // A mirror 5 units ahead; a red sphere 3 units behind the camera, seen at about 4.4 degrees
    // around the image centre; the image corners see the mirror's reflection of the background.
    let text = r#"
[render]
width = 64
height = 64
spp = 4
max_depth = 3
background = [0.0, 0.0, 1.0]
ambient = [1.0, 1.0, 1.0]
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
focal_length = 12.0
film = [24.0, 24.0]
[[materials]]
name = "mirror"
model = "mirror"
mirror = [0.5, 0.5, 0.5]
[[materials]]
name = "red"
model = "lambert"
diffuse = [1.0, 0.0, 0.0]
[[shapes]]
type = "quad"
corner = [-50.0, -50.0, -5.0]
edge_u = [100.0, 0.0, 0.0]
edge_v = [0.0, 100.0, 0.0]
material = "mirror"
[[shapes]]
type = "sphere"
center = [0.0, 0.0, 3.0]
radius = 1.0
material = "red"
"#;
    let flat = flatten(&scene(text));
    let cpu = common::render_cpu(&flat);
    let gpu = common::render_gpu(&flat);
    for image in [Some(&cpu), gpu.as_ref()].into_iter().flatten() {
        assert!(
            (image.get(32, 32) - Vec3::new(0.5, 0.0, 0.0))
                .abs()
                .max_element()
                < 1e-6,
            "centre {}",
            image.get(32, 32)
        );
        assert!(
            (image.get(0, 0) - Vec3::new(0.0, 0.0, 0.5))
                .abs()
                .max_element()
                < 1e-6,
            "corner {}",
            image.get(0, 0)
        );
    }
}

/// A spot light 2 units above a grey Lambert floor, pointing down, full within 10° of its axis
/// and dark beyond 30°.
const SPOT: &str = r#"
[render]
width = 48
height = 48
spp = 4
[camera]
position = [0.0, 6.0, 0.01]
look_at = [0.0, 0.0, 0.0]
vertical_fov = 60.0
film = [24.0, 24.0]
[[materials]]
name = "grey"
model = "lambert"
diffuse = [0.5, 0.5, 0.5]
[[shapes]]
type = "quad"
corner = [-5.0, 0.0, 5.0]
edge_u = [10.0, 0.0, 0.0]
edge_v = [0.0, 0.0, -10.0]
material = "grey"
[[lights]]
type = "spot"
position = [0.0, 2.0, 0.0]
direction = [0.0, -1.0, 0.0]
intensity = [8.0, 8.0, 8.0]
inner_angle = 10.0
outer_angle = 30.0
"#;

#[test]
fn a_spot_light_falls_off_between_its_cones_as_khr_lights_punctual_says() {
    let flat = flatten(&scene(SPOT));
    let (cos_inner, cos_outer) = (10f32.to_radians().cos(), 30f32.to_radians().cos());
    // Floor points at distance rho from the spot's foot: inside the inner cone, between the
    // cones, outside the outer one.
    for rho in [0.2f32, 0.5, 0.8, 1.0, 2.0] {
        let p = Vec3::new(rho, 0.0, 0.0);
        let radiance = trace_path::<FEATURES_ALL>(
            &flat,
            Ray {
                origin: p + Vec3::new(0.0, 5.0, 0.0),
                direction: Vec3::NEG_Y,
            },
            CameraHit::Trace,
            0.0,
            LightWindow::ALL,
            &mut Rng::new(0, 0, 0),
            &mut SampleStats::default(),
            &mut FirstHit::default(),
        );
        let r2 = 4.0 + rho * rho;
        let cos = 2.0 / r2.sqrt();
        let cone = ((cos - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
        let expected = 0.5 / PI * 8.0 * cos * cone * cone / r2;
        assert!(
            (radiance.x - expected).abs() <= 1e-5 * expected.max(1e-3),
            "rho {rho}: {} against {expected}",
            radiance.x
        );
    }
    // Both paths render the pool of light alike.
    let cpu = common::render_cpu(&flat);
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, _) = common::agreement(&cpu, &gpu, 1e-3);
        assert!(within > 0.99, "{within}");
    }
}
