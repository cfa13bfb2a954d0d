//! Motion blur: a sphere moving while the shutter is open covers each pixel for the fraction of
//! the shutter interval that the analytic sphere-swept volume says, and so does a round
//! ellipsoid; the GPU agrees, with shadows, mirrors and a moving torus too; a closed shutter
//! renders the sphere where it stands; what cannot move is refused.

use std::path::Path;

use chambre::camera::generate_ray_f64;
use chambre::pack::flatten;
use chambre::scene::Scene;
use glam::{DVec2, DVec3};

mod common;

/// A sphere of radius 0.5 at x = -1 moving at 2 units a second along +x, seen 10 units away
/// (20° field of view); ambient light only, so a hit is worth exactly 1 and a miss 0: each
/// pixel is the fraction of its samples that hit.
const SCENE: &str = r#"
[render]
width = 48
height = 48
spp = 256
pixel_sampler = "sobol"
ambient = [1.0, 1.0, 1.0]
[camera]
position = [0.0, 0.0, 10.0]
look_at = [0.0, 0.0, 0.0]
vertical_fov = 20.0
film = [24.0, 24.0]
shutter = [0.0, 1.0]
[[materials]]
name = "white"
model = "lambert"
diffuse = [1.0, 1.0, 1.0]
[[shapes]]
type = "sphere"
center = [-1.0, 0.0, 0.0]
radius = 0.5
material = "white"
velocity = [2.0, 0.0, 0.0]
"#;

fn scene(overrides: &[&str]) -> Scene {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_str(Path::new("motion.toml"), SCENE, &overrides).unwrap_or_else(|e| panic!("{e}"))
}

/// The fraction of the shutter interval [0, 1] during which the ray `o + s d` (unit `d`) meets
/// the sphere of radius `r` centred at `c0 + v t`: the perpendicular distance from the ray's
/// line is a quadratic in `t`.
fn covered_fraction(o: DVec3, d: DVec3, c0: DVec3, v: DVec3, r: f64) -> f64 {
    let perpendicular = |w: DVec3| w - d * w.dot(d);
    let (a, b) = (perpendicular(c0 - o), perpendicular(v));
    let (qa, qb, qc) = (b.dot(b), 2.0 * a.dot(b), a.dot(a) - r * r);
    let discriminant = qb * qb - 4.0 * qa * qc;
    if discriminant <= 0.0 {
        return 0.0;
    }
    let root = discriminant.sqrt();
    let (t0, t1) = ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa));
    (t1.min(1.0) - t0.max(0.0)).max(0.0)
}

/// The analytic value of pixel (x, y): the covered fraction averaged over an 8 x 8 grid of
/// points in the pixel (the renderer's samples spread over it).
fn analytic_pixel(scene: &Scene, x: u32, y: u32) -> f64 {
    let camera = &scene.camera;
    let (w, h) = (scene.render.width as f64, scene.render.height as f64);
    let mut sum = 0.0;
    for i in 0..8 {
        for j in 0..8 {
            let (u, v) = ((i as f64 + 0.5) / 8.0, (j as f64 + 0.5) / 8.0);
            let film = DVec2::new(
                ((x as f64 + u) / w - 0.5) * camera.film_mm[0],
                (0.5 - (y as f64 + v) / h) * camera.film_mm[1],
            );
            let (o, d) = generate_ray_f64(camera, film, DVec2::ZERO);
            let (c0, velocity) = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0));
            sum += covered_fraction(o, d, c0, velocity, 0.5);
        }
    }
    sum / 64.0
}

#[test]
fn a_moving_sphere_covers_each_pixel_for_its_analytic_share_of_the_shutter() {
    covers_its_analytic_share(&[]);
}

/// The same sphere declared as an ellipsoid of equal semi-axes: the exact ellipsoid test
/// (`accel::curved`) moves as the sphere does.
#[test]
fn a_moving_round_ellipsoid_covers_each_pixel_as_the_sphere_does() {
    covers_its_analytic_share(&[
        "shapes=[{type=\"ellipsoid\", center=[-1.0, 0.0, 0.0], radii=[0.5, 0.5, 0.5], \
         material=\"white\", velocity=[2.0, 0.0, 0.0]}]",
    ]);
}

/// The scene with `overrides` renders the moving sphere's analytic coverage, on both paths.
fn covers_its_analytic_share(overrides: &[&str]) {
    let scene = scene(overrides);
    let flat = flatten(&scene);
    let image = common::render_cpu(&flat);
    let mut total_error = 0.0;
    let mut worst: f64 = 0.0;
    let mut streak = 0;
    for y in 0..48 {
        for x in 0..48 {
            let expected = analytic_pixel(&scene, x, y);
            let got = image.get(x, y).x as f64;
            total_error += (got - expected).abs();
            worst = worst.max((got - expected).abs());
            if (0.05..0.95).contains(&expected) {
                streak += 1;
            }
        }
    }
    // The streak is wide: many pixels are partly covered, not a sharp disc.
    assert!(streak > 300, "{streak} partly covered pixels");
    let mean = total_error / (48.0 * 48.0);
    assert!(mean < 0.01, "mean error {mean}");
    assert!(worst < 0.1, "worst pixel off by {worst}");
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, mean_abs) = common::agreement(&image, &gpu, 1e-3);
        assert!(within > 0.99 && mean_abs < 1e-4, "{within} {mean_abs}");
    }
}

#[test]
fn a_closed_shutter_shows_the_sphere_where_it_stands() {
    // Shutter [0, 0]: every sample at time 0, the sphere at x = -1, exactly as without motion.
    let closed = common::render_cpu(&flatten(&scene(&["camera.shutter=[0.0, 0.0]"])));
    let still = common::render_cpu(&flatten(&scene(&[
        "camera.shutter=[0.0, 0.0]",
        "shapes[0].velocity=[0.0, 0.0, 0.0]",
    ])));
    assert_eq!(closed, still);
    // Opened later, the same sphere has moved: at t = 1 it stands at x = +1.
    let late = common::render_cpu(&flatten(&scene(&["camera.shutter=[1.0, 1.0]"])));
    let moved = common::render_cpu(&flatten(&scene(&[
        "camera.shutter=[0.0, 0.0]",
        "shapes[0].velocity=[0.0, 0.0, 0.0]",
        "shapes[0].center=[1.0, 0.0, 0.0]",
    ])));
    let (within, _) = common::agreement(&late, &moved, 1e-5);
    assert!(within > 0.999, "{within}");
}

#[test]
fn moving_shadows_and_mirrors_agree_on_both_paths() {
    // A point light and a mirror floor: shadow rays and bounces are traced at the camera
    // sample's time too.
    let flat = flatten(&scene(&[
        "lights=[{type=\"point\", position=[0.0, 3.0, 3.0], intensity=[20.0, 20.0, 20.0]}]",
        "materials=[{name=\"white\", model=\"lambert\", diffuse=[0.8, 0.8, 0.8]}, \
         {name=\"floor\", model=\"mirror\", mirror=[0.5, 0.5, 0.5], diffuse=[0.3, 0.3, 0.3]}]",
        "shapes=[{type=\"sphere\", center=[-1.0, 0.0, 0.0], radius=0.5, material=\"white\", \
         velocity=[2.0, 0.0, 0.0]}, {type=\"quad\", corner=[-5.0, -0.6, -5.0], \
         edge_u=[0.0, 0.0, 10.0], edge_v=[10.0, 0.0, 0.0], material=\"floor\"}, \
         {type=\"torus\", center=[0.5, 0.8, -1.0], major_radius=0.5, minor_radius=0.15, \
         material=\"white\", velocity=[0.0, -0.5, 0.0]}]",
        "render.spp=16",
    ]));
    let cpu = common::render_cpu(&flat);
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, _) = common::agreement(&cpu, &gpu, 1e-3);
        assert!(within > 0.99, "{within}");
    }
}

#[test]
fn what_cannot_move_is_refused_with_its_field() {
    let error = |overrides: &[&str]| {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Scene::from_str(Path::new("motion.toml"), SCENE, &overrides)
            .unwrap_err()
            .to_string()
    };
    let plane = error(&[
        "shapes=[{type=\"plane\", point=[0.0, -1.0, 0.0], normal=[0.0, 1.0, 0.0], \
         material=\"white\", velocity=[0.0, 1.0, 0.0]}]",
    ]);
    assert!(
        plane.contains("shapes[0].velocity") && plane.contains("plane"),
        "{plane}"
    );
    let shutter = error(&["camera.shutter=[1.0, 0.5]"]);
    assert!(
        shutter.contains("camera.shutter") && shutter.contains("before it opens"),
        "{shutter}"
    );
    let infinite = error(&["shapes[0].velocity=[1e39, 0.0, 0.0]"]);
    assert!(infinite.contains("shapes[0].velocity"), "{infinite}");
}
