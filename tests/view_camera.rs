//! The view camera's geometry: conventions, the Scheimpflug and hinge rules, convergence of the
//! thin-lens rays, the raster-projection equivalence, focus_points, and the extremes.

mod common;

use std::path::Path;

use chambre::camera::optics::solve_focus_points;
use chambre::camera::{CameraSpec, Focus, film_position_mm, generate_ray, generate_ray_f64};
use chambre::layout::GpuCamera;
use chambre::math::rng::Rng;
use chambre::pack::flatten;
use chambre::sampler::sample_aperture;
use chambre::scene::Scene;
use glam::{DVec2, DVec3, Vec2, Vec3};

/// A scene around `camera_fields` (TOML lines of the [camera] table), at `width` x `height`.
fn scene_text(camera_fields: &str, width: u32, height: u32) -> String {
    format!(
        "[render]\nwidth = {width}\nheight = {height}\nspp = 4\n\n\
         [camera]\nposition = [0.3, 1.2, 5.0]\nlook_at = [0.0, 0.8, 0.0]\n{camera_fields}\n\n\
         [[materials]]\nname = \"m\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [2.0, 4.0, 3.0]\nintensity = [10.0, 10.0, 10.0]\n"
    )
}

fn try_scene(camera_fields: &str) -> chambre::Result<Scene> {
    Scene::from_str(
        Path::new("test.toml"),
        &scene_text(camera_fields, 360, 240),
        &[],
    )
}

fn scene(camera_fields: &str) -> Scene {
    try_scene(camera_fields).unwrap_or_else(|e| panic!("{e}"))
}

fn camera(camera_fields: &str) -> CameraSpec {
    scene(camera_fields).camera
}

fn error(camera_fields: &str) -> String {
    match try_scene(camera_fields) {
        Ok(_) => panic!("expected an error for {camera_fields}"),
        Err(e) => e.to_string(),
    }
}

/// Random movements in a range where an image forms with a 36 x 24 film and f = 50 mm.
fn random_movements(rng: &mut Rng) -> String {
    let mut r = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
    format!(
        "focal_length = 50.0\nf_number = 4.0\nfocus_distance = {}\n\
         film_tilt = {}\nfilm_swing = {}\nfilm_shift = [{}, {}]\n\
         lens_tilt = {}\nlens_swing = {}\nlens_shift = [{}, {}]\n",
        r(0.5, 50.0),
        r(-30.0, 30.0),
        r(-30.0, 30.0),
        r(-8.0, 8.0),
        r(-8.0, 8.0),
        r(-25.0, 25.0),
        r(-25.0, 25.0),
        r(-5.0, 5.0),
        r(-5.0, 5.0)
    )
}

/// World conjugate of image point `image_mm` through the thin lens, f64: `None` at infinity.
fn conjugate(camera: &CameraSpec, image_mm: DVec2) -> Option<DVec3> {
    let s = camera.standards();
    let a = s.to_lens_frame(s.film_point(image_mm));
    let f = camera.focal_length_mm;
    let denominator = f + a.z;
    if denominator.abs() < 1e-9 * f {
        return None;
    }
    let x = a * (f / denominator);
    Some(camera.camera_to_world(s.lens * x + s.lens_center))
}

#[test]
fn zero_movements_give_exactly_the_plain_camera() {
    let plain = "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 4.0";
    let zeros = "film_tilt = 0.0\nfilm_swing = 0.0\nfilm_shift = [0.0, 0.0]\nlens_tilt = 0.0\n\
                 lens_swing = 0.0\nlens_shift = [0.0, 0.0]\naperture_blades = 0";
    let a = flatten(&scene(plain));
    let b = flatten(&scene(&format!("{plain}\n{zeros}")));
    assert_eq!(a.camera, b.camera);
    // The foundation camera: film at s_i = 1 / (1/f - 1/d) on the axis, inverted, lens frame =
    // camera basis.
    let s_i = 1.0 / (1.0 / 50.0 - 0.001 / 4.0);
    assert_eq!(a.camera.film_center, [0.0, 0.0, -(s_i as f32)]);
    assert_eq!(a.camera.film_u, [-1.0, 0.0, 0.0]);
    assert_eq!(a.camera.film_v, [0.0, -1.0, 0.0]);
    let basis = scene(plain).camera.basis();
    assert_eq!(a.camera.lens_to_world_x, basis.right.as_vec3().to_array());
    assert_eq!(a.camera.lens_to_world_z, basis.forward.as_vec3().to_array());
    assert_eq!(a.camera.lens_center, [0.3, 1.2, 5.0]);
}

#[test]
fn film_tilt_equal_to_the_pitch_makes_verticals_parallel() {
    // Camera pitched up by atan(0.6 / 5): film_tilt of that angle makes the projection plane
    // vertical, so every vertical world line keeps one image column.
    let pitch = (0.6f64 / 5.0).atan().to_degrees();
    let fields = format!(
        "position = [0.0, 1.0, 5.0]\nlook_at = [0.0, 1.6, 0.0]\nfilm_tilt = {pitch}\nfocal_length = 35.0"
    );
    let text = scene_text("", 360, 240).replace(
        "position = [0.3, 1.2, 5.0]\nlook_at = [0.0, 0.8, 0.0]\n",
        &format!("{fields}\n"),
    );
    let scene = Scene::from_str(Path::new("t.toml"), &text, &[]).unwrap();
    let projection = scene.camera.raster_projection(100.0);
    for x in [-2.0, 0.7, 2.5] {
        let bottom = projection
            .project(DVec3::new(x, 0.0, -1.0), 360, 240)
            .unwrap();
        let top = projection
            .project(DVec3::new(x, 3.0, -1.0), 360, 240)
            .unwrap();
        assert!((bottom.x - top.x).abs() < 1e-9, "{bottom} {top}");
    }
    // Without the tilt they converge.
    let untilted = Scene::from_str(
        Path::new("t.toml"),
        &text.replace(&format!("film_tilt = {pitch}\n"), ""),
        &[],
    )
    .unwrap();
    let p = untilted.camera.raster_projection(100.0);
    let bottom = p.project(DVec3::new(2.5, 0.0, -1.0), 360, 240).unwrap();
    let top = p.project(DVec3::new(2.5, 3.0, -1.0), 360, 240).unwrap();
    assert!((bottom.x - top.x).abs() > 1.0);
}

#[test]
fn film_swing_equal_to_the_yaw_makes_horizontals_parallel() {
    // Yawed right by 20 degrees from a facade in the plane z = 0 that it would face squarely.
    let yaw = 20f64;
    let look = DVec3::new(yaw.to_radians().sin(), 0.0, -yaw.to_radians().cos());
    let fields = format!(
        "position = [0.0, 1.0, 5.0]\nlook_at = [{}, 1.0, {}]\nfilm_swing = {yaw}\nfocal_length = 35.0",
        look.x,
        5.0 + look.z
    );
    let text = scene_text("", 360, 240).replace(
        "position = [0.3, 1.2, 5.0]\nlook_at = [0.0, 0.8, 0.0]\n",
        &format!("{fields}\n"),
    );
    let scene = Scene::from_str(Path::new("t.toml"), &text, &[]).unwrap();
    let projection = scene.camera.raster_projection(100.0);
    for y in [0.2, 1.0, 1.9] {
        let left = projection
            .project(DVec3::new(0.5, y, 0.0), 360, 240)
            .unwrap();
        let right = projection
            .project(DVec3::new(3.0, y, 0.0), 360, 240)
            .unwrap();
        assert!((left.y - right.y).abs() < 1e-9, "{left} {right}");
    }
}

#[test]
fn film_shift_moves_the_framing_without_changing_perspective() {
    let base = camera("focal_length = 50.0");
    let risen = camera("focal_length = 50.0\nfilm_shift = [3.0, 5.0]");
    let (p, q) = (
        base.raster_projection(100.0),
        risen.raster_projection(100.0),
    );
    // Framing moves right and up: every point moves left and down in the image, all by the
    // same number of pixels (3 mm and 5 mm of a 36 x 24 mm film at 360 x 240 pixels).
    for point in [
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(-1.0, 2.0, -3.0),
        DVec3::new(2.0, 0.0, 1.0),
    ] {
        let d = q.project(point, 360, 240).unwrap() - p.project(point, 360, 240).unwrap();
        assert!((d - DVec2::new(-30.0, 50.0)).length() < 1e-6, "{d}");
    }
}

#[test]
fn positive_lens_tilt_turns_the_focus_plane_down_and_swing_to_the_right() {
    let tilted =
        camera("focal_length = 50.0\nf_number = 4.0\nfocus_distance = 5.0\nlens_tilt = 8.0");
    let basis = tilted.basis();
    let lens = tilted.position;
    let hinge = tilted.hinge_line().unwrap();
    let below = basis.to_camera(hinge.point - lens);
    assert!(below.y < 0.0, "hinge below the lens: {below}");
    let normal = basis.to_camera(tilted.focus_plane().unwrap().normal);
    assert!(
        normal.y.abs() > 0.1,
        "the plane turned towards the ground: {normal}"
    );
    let swung =
        camera("focal_length = 50.0\nf_number = 4.0\nfocus_distance = 5.0\nlens_swing = 8.0");
    let hinge = swung.hinge_line().unwrap();
    assert!(swung.basis().to_camera(hinge.point - lens).x > 0.0);
}

#[test]
fn scheimpflug_and_hinge_rules_hold_for_random_movements() {
    let mut rng = Rng::new(99, 0, 0);
    let mut checked = 0;
    for trial in 0..200 {
        let fields = random_movements(&mut rng);
        let Ok(scene) = try_scene(&fields) else {
            continue;
        };
        let c = scene.camera;
        let plane = c.focus_plane().expect("finite focus");
        let scale = c.units_per_mm * c.film_distance_mm;
        let angle = c.lens_to_film_angle_deg().to_radians();
        let Some(scheimpflug) = c.scheimpflug_line() else {
            continue;
        };
        let hinge = c.hinge_line().unwrap();
        for line in [scheimpflug, hinge] {
            for t in [-3.0, 0.0, 5.0] {
                let p = line.point + t * line.direction;
                let d = plane.signed_distance(p).abs();
                assert!(
                    d < 1e-9 * (scale + (p - c.position).length()),
                    "trial {trial}: {d}\n{fields}"
                );
            }
        }
        // The Scheimpflug line lies in the film plane and the lens plane too.
        let s = c.standards();
        let on_film = |p: DVec3| {
            let q = c.world_to_camera(p);
            (q - s.film_pivot).dot(s.film.z_axis)
        };
        let on_lens = |p: DVec3| (c.world_to_camera(p) - s.lens_center).dot(s.lens.z_axis);
        for t in [-2.0, 4.0] {
            let p = scheimpflug.point + t * scheimpflug.direction;
            assert!(
                on_film(p).abs() < 1e-9 * c.film_distance_mm,
                "trial {trial}"
            );
            assert!(
                on_lens(p).abs() < 1e-9 * c.film_distance_mm,
                "trial {trial}"
            );
        }
        // Hinge rule: the hinge lies f / sin(angle between lens and film) from the lens centre.
        let lens_center = c.camera_to_world(s.lens_center);
        let expected = c.focal_length_mm * c.units_per_mm / angle.sin();
        let j = hinge.distance_to(lens_center);
        assert!(
            (j / expected - 1.0).abs() < 1e-9,
            "trial {trial}: {j} vs {expected}"
        );
        checked += 1;
    }
    assert!(checked > 150, "{checked}");
}

#[test]
fn refocusing_turns_the_focus_plane_about_the_fixed_hinge() {
    let hinge_of = |d: f64| {
        let c = camera(&format!(
            "focal_length = 50.0\nf_number = 4.0\nfocus_distance = {d}\nlens_tilt = 6.0"
        ));
        let h = c.hinge_line().unwrap();
        (h, c.focus_plane().unwrap())
    };
    let (h1, p1) = hinge_of(3.0);
    let (h2, p2) = hinge_of(12.0);
    assert!(h1.distance_to(h2.point) < 1e-12 && h1.direction.dot(h2.direction).abs() > 1.0 - 1e-12);
    assert!(p1.normal.dot(p2.normal) < 1.0 - 1e-6, "the plane turned");
}

#[test]
fn rays_of_a_film_point_meet_at_its_conjugate_on_the_focus_plane() {
    let mut rng = Rng::new(5, 0, 0);
    let mut checked = 0;
    for _ in 0..60 {
        let fields = random_movements(&mut rng);
        let Ok(scene) = try_scene(&fields) else {
            continue;
        };
        let flat = flatten(&scene);
        let c = &scene.camera;
        let plane = c.focus_plane().unwrap();
        for raster in [
            [0.5, 0.5],
            [359.5, 0.5],
            [180.0, 120.0],
            [0.5, 239.5],
            [300.0, 200.0],
        ] {
            let film = film_position_mm(&flat.camera, 360, 240, Vec2::from(raster));
            let Some(target) = conjugate(c, film.as_dvec2()) else {
                continue;
            };
            let lens_center = c.camera_to_world(c.standards().lens_center);
            let reach = (target - lens_center).length();
            // The conjugate lies on the reported plane of sharp focus.
            assert!(plane.signed_distance(target).abs() < 1e-9 * reach.max(1.0));
            for k in 0..32 {
                let u = Rng::new(1, k, 0).next_2d();
                let lens = Vec2::from(sample_aperture(&flat.camera, &flat.sample_table, u));
                let ray = generate_ray(&flat.camera, film, lens);
                let to_target = target - ray.origin.as_dvec3();
                let miss = to_target
                    .reject_from_normalized(ray.direction.as_dvec3().normalize())
                    .length();
                // Virtual conjugates (film nearer than f) lie behind the lens: the rays' lines
                // still pass through them.
                assert!(miss < 1e-5 * reach, "miss {miss} at {reach}\n{fields}");
            }
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked}");
}

#[test]
fn focus_at_infinity_gives_parallel_rays_per_film_point() {
    let scene = scene("focal_length = 50.0\nf_number = 1.4\nfocus_distance = inf\nlens_tilt = 0.0");
    let flat = flatten(&scene);
    assert!(scene.camera.focus_plane().is_none());
    for raster in [[0.5, 0.5], [180.0, 120.0], [359.5, 239.5]] {
        let film = film_position_mm(&flat.camera, 360, 240, Vec2::from(raster));
        let chief = generate_ray(&flat.camera, film, Vec2::ZERO).direction;
        for k in 0..16 {
            let lens = Vec2::from(sample_aperture(
                &flat.camera,
                &flat.sample_table,
                Rng::new(3, k, 0).next_2d(),
            ));
            let d = generate_ray(&flat.camera, film, lens).direction;
            assert!(d.angle_between(chief) < 1e-5, "{d} vs {chief}");
        }
    }
}

#[test]
fn tiny_aperture_is_the_pinhole_limit() {
    // f/1e6 with the film where a pinhole's film sits gives the pinhole's rays.
    let lens = flatten(&scene(
        "focal_length = 50.0\nf_number = 1e6\nfilm_distance = 52.0\nlens_tilt = 10.0",
    ));
    let pinhole = flatten(&scene("focal_length = 50.0\nfilm_distance = 52.0"));
    for raster in [[0.5, 0.5], [200.0, 40.0], [359.5, 239.5]] {
        let film = film_position_mm(&lens.camera, 360, 240, Vec2::from(raster));
        let reference = generate_ray(&pinhole.camera, film, Vec2::ZERO);
        for k in 0..16 {
            let p = Vec2::from(sample_aperture(
                &lens.camera,
                &lens.sample_table,
                Rng::new(4, k, 0).next_2d(),
            ));
            let ray = generate_ray(&lens.camera, film, p);
            assert!(ray.direction.angle_between(reference.direction) < 1e-6);
            assert!((ray.origin - reference.origin).length() < 1e-6);
        }
    }
}

#[test]
fn raster_projection_reproduces_the_film_tilted_pinhole() {
    let mut rng = Rng::new(17, 0, 0);
    let mut checked = 0;
    for trial in 0..40 {
        let mut r = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
        let fields = format!(
            "focal_length = {}\nfilm_tilt = {}\nfilm_swing = {}\nfilm_shift = [{}, {}]\nlens_shift = [{}, {}]",
            r(20.0, 120.0),
            r(-60.0, 60.0),
            r(-60.0, 60.0),
            r(-10.0, 10.0),
            r(-10.0, 10.0),
            r(-5.0, 5.0),
            r(-5.0, 5.0)
        );
        let Ok(scene) = try_scene(&fields) else {
            continue;
        };
        let flat = flatten(&scene);
        let projection = scene.camera.raster_projection(1000.0);
        for raster in [[0.5, 0.5], [359.5, 0.5], [17.25, 200.5], [180.0, 120.0]] {
            let film = film_position_mm(&flat.camera, 360, 240, Vec2::from(raster));
            let ray = generate_ray(&flat.camera, film, Vec2::ZERO);
            for t in [0.5, 7.0, 40.0] {
                let p = (ray.origin + t * ray.direction).as_dvec3();
                let projected = projection.project(p, 360, 240).unwrap();
                let error = (projected - DVec2::new(raster[0] as f64, raster[1] as f64)).length();
                assert!(error < 1e-3, "trial {trial}: {error} px\n{fields}");
            }
        }
        checked += 1;
    }
    assert!(checked > 30, "{checked}");
    // The closed form: near plane d cos(phi) cos(theta), window centre
    // (-d sin(phi), d cos(phi) sin(theta)) with phi = -film_swing in these conventions.
    let c = camera("focal_length = 50.0\nfilm_tilt = 20.0\nfilm_swing = 30.0");
    let f = c.raster_projection(10.0).frustum;
    let (d, theta, phi) = (50.0 * 0.001, 20f64.to_radians(), -30f64.to_radians());
    assert!((f.near - d * phi.cos() * theta.cos()).abs() < 1e-12);
    assert!((0.5 * (f.left + f.right) + d * phi.sin()).abs() < 1e-12);
    assert!((0.5 * (f.bottom + f.top) - d * phi.cos() * theta.sin()).abs() < 1e-12);
}

#[test]
fn focus_points_put_all_three_points_on_the_focus_plane() {
    let mut rng = Rng::new(23, 0, 0);
    let mut solved = 0;
    for trial in 0..100 {
        let mut r = |lo: f32, hi: f32| (lo + (hi - lo) * rng.next_f32()) as f64;
        let points: Vec<[f64; 3]> = (0..3)
            .map(|_| [r(-3.0, 3.0), r(-1.0, 3.0), r(-8.0, 2.5)])
            .collect();
        let fields = format!(
            "focal_length = {}\nf_number = 5.6\nfilm_tilt = {}\nfilm_swing = {}\n\
             focus_points = [{:?}, {:?}, {:?}]",
            r(35.0, 150.0),
            r(-15.0, 15.0),
            r(-15.0, 15.0),
            points[0],
            points[1],
            points[2]
        );
        match try_scene(&fields) {
            Ok(scene) => {
                let c = scene.camera;
                let plane = c.focus_plane().unwrap();
                for p in &points {
                    let p = DVec3::from_array(*p);
                    let d = plane.signed_distance(p).abs();
                    assert!(
                        d < 1e-6 * (p - c.position).length(),
                        "trial {trial}: {d}\n{fields}"
                    );
                }
                assert!(matches!(c.focus, Focus::Points(_)));
                solved += 1;
            }
            Err(e) => {
                let message = e.to_string();
                assert!(message.contains("camera.focus_points"), "{message}");
            }
        }
    }
    assert!(solved > 50, "{solved}");
}

#[test]
fn focus_points_without_a_solution_give_clear_errors() {
    let lens = "focal_length = 50.0\nf_number = 4.0\n";
    let collinear = error(&format!(
        "{lens}focus_points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]"
    ));
    assert!(collinear.contains("collinear"), "{collinear}");
    let behind = error(&format!(
        "{lens}focus_points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 9.0]]"
    ));
    assert!(behind.contains("behind the lens"), "{behind}");
    let through_lens = error(&format!(
        "{lens}focus_points = [[0.3, 1.2, 5.0], [0.3, 1.2, 1.0], [1.0, 0.0, 1.0]]"
    ));
    assert!(
        through_lens.contains("behind the lens") || through_lens.contains("lens centre"),
        "{through_lens}"
    );
    let pinhole = error("focus_points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]");
    assert!(pinhole.contains("needs a lens"), "{pinhole}");
    let both = error(&format!(
        "{lens}lens_tilt = 3.0\nfocus_points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]"
    ));
    assert!(both.contains("camera.lens_tilt"), "{both}");
    // Solving directly reports the same reasons.
    let c = camera(lens);
    let p = DVec3::new(0.0, 0.0, 0.0);
    assert!(solve_focus_points(&c, [p, p, p]).is_err());
}

#[test]
fn extreme_movements_render_without_nan_or_are_refused_with_reasons() {
    for fields in [
        "focal_length = 50.0\nfilm_tilt = 80.0",
        "focal_length = 50.0\nfilm_swing = -80.0",
        "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 3.0\nlens_tilt = 80.0\nfilm = [12.0, 8.0]",
        "focal_length = 50.0\nf_number = 2.0\nlens_swing = -80.0\nfilm = [12.0, 8.0]",
        "focal_length = 50.0\nf_number = 0.7\nfocus_distance = 0.2",
        "focal_length = 50.0\nf_number = 1e6\nfocus_distance = 3.0",
        "focal_length = 10.0\nf_number = 2.8\nfilm = [180.0, 120.0]\nfocus_distance = 2.0",
        "focal_length = 50.0\nf_number = 2.0\nfocus_distance = inf\nlens_tilt = 30.0",
    ] {
        let scene = Scene::from_str(Path::new("t.toml"), &scene_text(fields, 36, 24), &[])
            .unwrap_or_else(|e| panic!("{fields}: {e}"));
        let flat = flatten(&scene);
        let image = common::render_cpu(&flat);
        assert_eq!(image.non_finite_count(), 0, "{fields}");
    }
    let edge_on = error("focal_length = 50.0\nfilm_tilt = 90.0");
    assert!(
        edge_on.contains("camera.film_tilt") && edge_on.contains("edge-on"),
        "{edge_on}"
    );
    let crossing = error("focal_length = 50.0\nf_number = 2.0\nlens_tilt = 80.0");
    assert!(crossing.contains("no image can form"), "{crossing}");
    let too_close = error("focal_length = 50.0\nf_number = 2.0\nfilm_distance = 40.0");
    assert!(
        too_close.contains("camera.film_distance") && too_close.contains("focal length"),
        "{too_close}"
    );
    let blades = error("focal_length = 50.0\nf_number = 2.0\naperture_blades = 2");
    assert!(blades.contains("camera.aperture_blades"), "{blades}");
    let sampler = error("focal_length = 50.0\nlens_sampler = \"halton\"");
    assert!(
        sampler.contains("camera.lens_sampler") && sampler.contains("sobol"),
        "{sampler}"
    );
    let both =
        error("focal_length = 50.0\nf_number = 2.0\nfocus_distance = 3.0\nfilm_distance = 60.0");
    assert!(both.contains("film_distance"), "{both}");
}

/// Image position (mm, x right, y up) where the ray from world point `q` through lens point
/// `lens_mm` meets the (unmoved) film: the thin-lens transfer run backwards.
fn image_of_ray(c: &CameraSpec, q: DVec3, lens_mm: DVec2) -> DVec2 {
    let s = c.standards();
    let q = s.to_lens_frame(c.world_to_camera(q));
    let object_slope = (q.truncate() - lens_mm) / q.z;
    let film_slope = object_slope + lens_mm / c.focal_length_mm;
    let film = lens_mm - c.film_distance_mm * film_slope;
    -film
}

#[test]
fn bokeh_behind_the_focus_shows_the_aperture_upright_and_rotation_turns_it_counter_clockwise() {
    use chambre::sampler::aperture_vertices;
    for rotation in [0.0f64, 30.0, -50.0] {
        let c = camera(&format!(
            "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 3.0\naperture_blades = 5\n\
             aperture_rotation = {rotation}"
        ));
        let c = CameraSpec {
            position: DVec3::ZERO,
            look_at: DVec3::new(0.0, 0.0, -1.0),
            ..c
        };
        let radius = c.lens_radius_mm();
        let behind = DVec3::new(0.0, 0.0, -20.0);
        let in_front = DVec3::new(0.0, 0.0, -1.0);
        let centre_behind = image_of_ray(&c, behind, DVec2::ZERO);
        let centre_front = image_of_ray(&c, in_front, DVec2::ZERO);
        for v in aperture_vertices(5, rotation).iter().take(5) {
            let v = DVec2::new(v[0] as f64, v[1] as f64);
            let offset = image_of_ray(&c, behind, radius * v) - centre_behind;
            // Same direction as the vertex, in image axes (x right, y up).
            assert!(offset.normalize().dot(v) > 1.0 - 1e-6, "{offset} vs {v}");
            // In front of the focus the spot is inverted.
            let offset = image_of_ray(&c, in_front, radius * v) - centre_front;
            assert!(offset.normalize().dot(v) < -1.0 + 1e-6);
        }
    }
    // Rotation 0: the edge between vertices 0 and 1 stands vertical on the right.
    let v = aperture_vertices(6, 0.0);
    assert!((v[0][0] - v[1][0]).abs() < 1e-6 && v[0][0] > 0.0 && v[0][1] < 0.0 && v[1][1] > 0.0);
    // A positive rotation turns the polygon counter-clockwise.
    let turned = aperture_vertices(6, 10.0);
    let angle = |p: [f32; 2]| (p[1] as f64).atan2(p[0] as f64).to_degrees();
    assert!((angle(turned[1]) - angle(v[1]) - 10.0).abs() < 1e-4);
}

/// Every column of the image, for [`common::sharpness`].
const WHOLE_WIDTH: (f64, f64) = (0.0, 1.0);

#[test]
fn tilted_lens_keeps_a_receding_checkerboard_sharp_from_front_to_back() {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tabletop.toml"));
    // The board alone (the spheres stand above the plane of sharp focus), lit by the ambient
    // term only, so that light-sampling noise does not pass for detail.
    let text = std::fs::read_to_string(path)
        .unwrap()
        .split("\n[[")
        .filter(|section| {
            !section.starts_with("shapes]]\ntype = \"sphere\"") && !section.starts_with("lights]]")
        })
        .collect::<Vec<_>>()
        .join("\n[[")
        .replace("ambient = [0.05, 0.05, 0.05]", "ambient = [1.0, 1.0, 1.0]");
    let small = ["render.width=240", "render.height=160", "render.spp=16"].map(String::from);
    let render_variant = |focus: &str| {
        // Wide open at f/1.2, so that the board's ends fall far outside the depth of field.
        let text = text
            .replace(
                "focus_points = [[-0.4, 0.0, -0.5], [0.4, 0.0, -0.5], [0.0, 0.0, -3.0]]",
                focus,
            )
            .replace("f_number = 2.8", "f_number = 1.2");
        let scene = Scene::from_str(path, &text, &small).unwrap_or_else(|e| panic!("{e}"));
        // The same framing through a pinhole at the same bellows extension: sharp everywhere.
        let pinhole_text = text
            .replace(
                focus,
                &format!("film_distance = {}", scene.camera.film_distance_mm),
            )
            .replace("f_number = 1.2", "f_number = 0.0");
        let pinhole = Scene::from_str(path, &pinhole_text, &small).unwrap();
        (
            common::render_cpu(&flatten(&scene)),
            common::render_cpu(&flatten(&pinhole)),
        )
    };
    let bands = [
        ("far", (0.0, 0.3)),
        ("middle", (0.45, 0.6)),
        ("near", (0.8, 1.0)),
    ];
    let (tilted, tilted_pinhole) =
        render_variant("focus_points = [[-0.4, 0.0, -0.5], [0.4, 0.0, -0.5], [0.0, 0.0, -3.0]]");
    let (plain, plain_pinhole) = render_variant("focus_distance = 1.5");
    for (name, rows) in bands {
        let t = common::sharpness(&tilted, rows, WHOLE_WIDTH)
            / common::sharpness(&tilted_pinhole, rows, WHOLE_WIDTH);
        let p = common::sharpness(&plain, rows, WHOLE_WIDTH)
            / common::sharpness(&plain_pinhole, rows, WHOLE_WIDTH);
        eprintln!("{name}: tilted lens {t:.3}, untilted {p:.3} of the pinhole's sharpness");
        assert!(t > 0.9, "{name}: the tilted lens blurs the board ({t:.3})");
        if name == "middle" {
            assert!(
                p > 0.8,
                "{name}: the untilted lens is focused here ({p:.3})"
            );
        } else {
            assert!(
                p < 0.5,
                "{name}: the untilted lens should blur here ({p:.3})"
            );
        }
    }
}

#[test]
fn untilted_depth_of_field_matches_the_hyperfocal_formulas() {
    // Classic limits: H = f^2 / (N c) + f, near = s (H - f) / (H + s - 2f), far = s (H - f) / (H - s).
    for (f, n, s_mm, c) in [
        (50.0, 1.4, 4000.0, 0.03),
        (90.0, 8.0, 2500.0, 0.1),
        (35.0, 2.0, 900.0, 0.02),
    ] {
        let camera = camera(&format!(
            "focal_length = {f}\nf_number = {n}\nfocus_distance = {}",
            s_mm / 1000.0
        ));
        let h = f * f / (n * c) + f;
        let near = s_mm * (h - f) / (h + s_mm - 2.0 * f);
        let far = s_mm * (h - f) / (h - s_mm);
        let (near_plane, far_plane) = camera.depth_of_field(c).unwrap();
        let along = |p: Option<chambre::camera::optics::Plane>| {
            camera.distance_along_chief_ray(&p.unwrap()).unwrap() * 1000.0
        };
        // With no movements the image centre's chief ray is the optical axis.
        assert!(
            (along(near_plane) / near - 1.0).abs() < 1e-9,
            "{} vs {near}",
            along(near_plane)
        );
        assert!(
            (along(far_plane) / far - 1.0).abs() < 1e-9,
            "{} vs {far}",
            along(far_plane)
        );
    }
    // Beyond the hyperfocal distance the far limit is at infinity.
    let camera = camera("focal_length = 50.0\nf_number = 16.0\nfocus_distance = 10.0");
    assert!(camera.depth_of_field(0.03).unwrap().1.is_none());
}

/// The point of a curved focal surface on the chief ray of `film_mm`, in world space: at
/// distance `radius` from the lens centre (a sphere) or from the lens's vertical axis through
/// it (a cylinder).
fn on_curved_surface(gpu: &GpuCamera, film_mm: Vec2, radius: f32, cylinder: bool) -> Vec3 {
    let chief = generate_ray(gpu, film_mm, Vec2::ZERO);
    let axis = Vec3::from(gpu.lens_to_world_y);
    let reach = if cylinder {
        (chief.direction - axis * chief.direction.dot(axis)).length()
    } else {
        1.0
    };
    chief.origin + chief.direction * (radius / reach)
}

#[test]
fn a_curved_focal_surface_brings_every_lens_point_to_its_points() {
    for (surface, cylinder) in [("sphere", false), ("cylinder", true)] {
        let spec = camera(&format!(
            "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 4.0\nfilm_tilt = 8.0\n\
             focus_surface = \"{surface}\""
        ));
        let plane =
            camera("focal_length = 50.0\nf_number = 2.0\nfocus_distance = 4.0\nfilm_tilt = 8.0");
        let (gpu, plane_gpu) = (spec.to_gpu(0), plane.to_gpu(0));
        let radius = 4.0;
        let mut plane_miss: f32 = 0.0;
        for film in [
            Vec2::new(0.0, 0.0),
            Vec2::new(15.0, 9.0),
            Vec2::new(-17.0, -11.0),
            Vec2::new(8.0, -10.0),
        ] {
            let sharp = on_curved_surface(&gpu, film, radius, cylinder);
            for lens in [
                Vec2::new(12.0, 0.0),
                Vec2::new(-12.0, 0.0),
                Vec2::new(0.0, 12.0),
                Vec2::new(-8.0, -8.0),
            ] {
                let ray = generate_ray(&gpu, film, lens);
                let to = sharp - ray.origin;
                let miss = (to - ray.direction * to.dot(ray.direction)).length();
                assert!(
                    miss < 2e-6 * radius,
                    "{surface}, film {film}, lens {lens}: {miss}"
                );
                // A plane of focus brings the off-axis points of the curved surface to a blur.
                let ray = generate_ray(&plane_gpu, film, lens);
                let to = sharp - ray.origin;
                plane_miss = plane_miss.max((to - ray.direction * to.dot(ray.direction)).length());
            }
        }
        assert!(
            plane_miss > 1e-3,
            "{surface}: the plane focuses there too ({plane_miss})"
        );
        // The f64 twin agrees.
        let (o, d) = generate_ray_f64(&spec, DVec2::new(15.0, 9.0), DVec2::new(12.0, 0.0));
        let ray = generate_ray(&gpu, Vec2::new(15.0, 9.0), Vec2::new(12.0, 0.0));
        assert!(
            (d.as_vec3() - ray.direction).length() < 1e-6,
            "{d} {}",
            ray.direction
        );
        assert!((o.as_vec3() - ray.origin).length() < 1e-5);
    }
}

#[test]
fn a_curved_focal_surface_needs_a_focused_lens_and_no_lens_tilt() {
    let pinhole = error("focal_length = 50.0\nfocus_surface = \"sphere\"");
    assert!(
        pinhole.contains("camera.focus_surface") && pinhole.contains("focus_distance"),
        "{pinhole}"
    );
    let tilted = error(
        "focal_length = 50.0\nf_number = 2.0\nfocus_distance = 4.0\nlens_tilt = 5.0\n\
         focus_surface = \"cylinder\"",
    );
    assert!(tilted.contains("cannot be tilted"), "{tilted}");
}

#[test]
fn curved_focal_surfaces_render_alike_on_both_paths() {
    for surface in ["sphere", "cylinder"] {
        let text = scene_text(
            &format!(
                "focal_length = 35.0\nf_number = 1.4\nfocus_distance = 5.5\nfilm_shift = [2.0, 1.0]\n\
                 focus_surface = \"{surface}\""
            ),
            48,
            32,
        );
        let scene = Scene::from_str(Path::new("t.toml"), &text, &[]).unwrap();
        let flat = flatten(&scene);
        let cpu = common::render_cpu(&flat);
        if let Some(gpu) = common::render_gpu(&flat) {
            let (within, _) = common::agreement(&cpu, &gpu, 1e-3);
            assert!(within > 0.99, "{surface}: {within}");
        }
    }
}

/// An orthographic camera over the sphere scene: at (0.3, 1.2, 5) looking at (0, 0.8, 0), a
/// 3 x 2 window for the 360 x 240 image, and `fields`.
fn orthographic(fields: &str) -> CameraSpec {
    camera(&format!(
        "projection = \"orthographic\"\nwindow = [3.0, 2.0]\n{fields}"
    ))
}

/// The rays' direction of docs/camera.md's orthographic camera, in the camera frame:
/// r = T^-1 z = (sin swing, cos swing sin tilt, cos swing cos tilt).
fn orthographic_rays(c: &CameraSpec) -> DVec3 {
    let (t, s) = (
        c.movements.film_tilt.to_radians(),
        c.movements.film_swing.to_radians(),
    );
    DVec3::new(s.sin(), s.cos() * t.sin(), s.cos() * t.cos())
}

/// Where docs/camera.md's orthographic camera puts world point `p`, from its equations alone:
/// the ray from window point (s_x + a, s_y + b, 0) along r meets the camera-frame point
/// (x, y, z) when a = x - (r_x / r_z) z - s_x, b = y - (r_y / r_z) z - s_y; returned in raster
/// coordinates (pixels, y down) of a `size` image of a `window` (scene units).
fn orthographic_raster(
    c: &CameraSpec,
    window: [f64; 2],
    shift: [f64; 2],
    p: DVec3,
    size: [f64; 2],
) -> DVec2 {
    let forward = (c.look_at - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let r = orthographic_rays(c);
    let q = p - c.position;
    let (x, y, z) = (q.dot(right), q.dot(up), q.dot(forward));
    let a = x - r.x / r.z * z - shift[0];
    let b = y - r.y / r.z * z - shift[1];
    DVec2::new(
        (a / window[0] + 0.5) * size[0],
        (0.5 - b / window[1]) * size[1],
    )
}

#[test]
fn an_orthographic_camera_sends_each_pixel_parallel_rays_through_its_points() {
    let mut rng = Rng::new(41, 0, 0);
    let (w, h) = (360u32, 240u32);
    for (fields, shift) in [
        ("", [0.0, 0.0]),
        ("film_shift = [0.4, -0.3]", [0.4, -0.3]),
        ("film_tilt = 25.0", [0.0, 0.0]),
        ("film_swing = -35.0", [0.0, 0.0]),
        (
            "film_tilt = -40.0\nfilm_swing = 20.0\nfilm_shift = [-0.7, 0.2]",
            [-0.7, 0.2],
        ),
    ] {
        let c = orthographic(fields);
        assert!(c.is_orthographic() && c.is_pinhole(), "{fields}");
        let gpu = c.to_gpu(0);
        let raster = c.raster_projection(100.0);
        let basis = c.basis();
        let rays = basis.to_world(orthographic_rays(&c));
        assert!((c.ray_direction() - rays).length() < 1e-12, "{fields}");
        for _ in 0..50 {
            let mut r = |lo: f32, hi: f32| (lo + (hi - lo) * rng.next_f32()) as f64;
            let p = DVec3::new(r(-2.0, 2.0), r(-1.0, 3.0), r(-3.0, 3.0));
            let expected = orthographic_raster(&c, [3.0, 2.0], shift, p, [w as f64, h as f64]);
            let projected = raster.project(p, w, h).unwrap();
            assert!(
                (projected - expected).length() < 1e-9 * w as f64,
                "{fields}: raster projection {projected} against {expected}"
            );
            // The f32 ray of that pixel position, and its f64 twin, pass through the point.
            let film = film_position_mm(&gpu, w, h, expected.as_vec2());
            let ray = generate_ray(&gpu, film, Vec2::ZERO);
            let direction = ray.direction.as_dvec3();
            assert!((direction - rays).length() < 1e-6, "{fields}: {direction}");
            let miss = (p - ray.origin.as_dvec3())
                .reject_from_normalized(rays)
                .length();
            assert!(miss < 2e-5, "{fields}: the ray misses {p} by {miss}");
            let film64 = DVec2::new(
                (expected.x / w as f64 - 0.5) * c.film_mm[0],
                (0.5 - expected.y / h as f64) * c.film_mm[1],
            );
            let (origin, direction) = generate_ray_f64(&c, film64, DVec2::ZERO);
            assert!((direction - rays).length() < 1e-12);
            assert!((p - origin).reject_from_normalized(direction).length() < 1e-9);
            // Every ray leaves the window's plane, through the position and square to the view.
            assert!((origin - c.position).dot(basis.forward).abs() < 1e-9);
        }
    }
}

#[test]
fn orthographic_sizes_do_not_change_with_distance_and_parallel_lines_stay_parallel() {
    let near = orthographic("film_tilt = 15.0\nfilm_swing = 10.0\nfilm_shift = [0.2, 0.1]");
    // Backed away 40 units along its rays, it sees every point where it saw it.
    let back = near.ray_direction() * 40.0;
    let far = CameraSpec {
        position: near.position - back,
        look_at: near.look_at - back,
        ..near.clone()
    };
    let image =
        |c: &CameraSpec, p: DVec3| c.raster_projection(1000.0).project(p, 360, 240).unwrap();
    let points = [
        DVec3::new(-1.0, 0.0, 0.5),
        DVec3::new(0.8, 2.0, -2.0),
        DVec3::new(0.1, 1.0, 2.5),
    ];
    for p in points {
        assert!((image(&near, p) - image(&far, p)).length() < 1e-9, "{p}");
    }
    // Two parallel segments, at different depths: their images are parallel and as long.
    let d = DVec3::new(0.3, 0.7, -1.1);
    let a = image(&near, points[0] + d) - image(&near, points[0]);
    let b = image(&near, points[1] + d) - image(&near, points[1]);
    assert!((a - b).length() < 1e-9, "{a} against {b}");
    // A perspective camera at the same place draws the nearer one larger.
    let perspective = camera("vertical_fov = 25.0");
    let seen = |p: DVec3| {
        perspective
            .raster_projection(1000.0)
            .project(p, 360, 240)
            .unwrap()
    };
    let near_seg = seen(points[2] + d) - seen(points[2]);
    let far_seg = seen(points[1] + d) - seen(points[1]);
    assert!(near_seg.length() > 1.5 * far_seg.length());
}

#[test]
fn slanted_rays_keep_a_facade_square_to_the_window_true_and_show_its_depth() {
    // scenes/elevation.toml's camera: square to the facade (z = -18), rays 20 degrees down and
    // 25 degrees left.
    let text = |movements: &str| {
        format!(
            "[render]\nwidth = 240\nheight = 360\n\
             [camera]\nprojection = \"orthographic\"\nposition = [31.26, 39.93, 40.0]\n\
             look_at = [31.26, 39.93, 0.0]\nwindow = [32.0, 48.0]\n{movements}\n\
             [[materials]]\nname = \"m\"\nmodel = \"lambert\"\n\
             [[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 17.0, -23.0]\nradius = 1.0\n\
             material = \"m\"\n"
        )
    };
    let load = |movements: &str| {
        Scene::from_str(Path::new("t.toml"), &text(movements), &[])
            .unwrap_or_else(|e| panic!("{e}"))
            .camera
    };
    let units_per_pixel = 32.0 / 240.0;
    let image = |c: &CameraSpec, p: [f64; 3]| {
        c.raster_projection(1000.0)
            .project(DVec3::from(p), 240, 360)
            .unwrap()
            * units_per_pixel
    };
    let oblique = load("film_tilt = -20.0\nfilm_swing = -25.0");
    let corner = image(&oblique, [-5.0, 0.0, -18.0]);
    let across = image(&oblique, [5.0, 0.0, -18.0]) - corner;
    let upward = image(&oblique, [-5.0, 34.0, -18.0]) - corner;
    // Pixels run down: a vertical of 34 units is 34 units straight up the image.
    assert!((across - DVec2::new(10.0, 0.0)).length() < 1e-9, "{across}");
    assert!(
        (upward - DVec2::new(0.0, -34.0)).length() < 1e-9,
        "{upward}"
    );
    // Depth recedes along the rays' slant, up and right (they run down and left), 10 units of
    // it as 10 tan(angle), the angle between the rays and the window's normal.
    let depth = image(&oblique, [5.0, 0.0, -28.0]) - image(&oblique, [5.0, 0.0, -18.0]);
    let angle = oblique.oblique_angle_deg().to_radians();
    let expected_cos = 25f64.to_radians().cos() * 20f64.to_radians().cos();
    assert!((angle.cos() - expected_cos).abs() < 1e-12, "{angle}");
    assert!(
        (depth.length() - 10.0 * angle.tan()).abs() < 1e-9,
        "{depth}"
    );
    assert!(depth.x > 0.0 && depth.y < 0.0, "{depth}");
    // The rays through the tower's centre pass near the window's centre: the scene's framing.
    let centre = image(&oblique, [0.0, 17.0, -23.0]) - DVec2::new(16.0, 24.0);
    assert!(centre.length() < 0.01, "{centre}");
    // Square rays: a plain elevation, the depth hidden.
    let plain = load("");
    assert_eq!(plain.oblique_angle_deg(), 0.0);
    let depth = image(&plain, [5.0, 0.0, -28.0]) - image(&plain, [5.0, 0.0, -18.0]);
    assert!(depth.length() < 1e-9, "{depth}");
}

#[test]
fn an_orthographic_film_shift_moves_the_image_by_minus_the_shift() {
    let plain = orthographic("");
    let shifted = orthographic("film_shift = [0.5, -0.25]");
    let p = DVec3::new(0.4, 1.3, -0.6);
    let moved = shifted
        .raster_projection(100.0)
        .project(p, 360, 240)
        .unwrap()
        - plain.raster_projection(100.0).project(p, 360, 240).unwrap();
    // 0.5 units right of a 3-unit window is 60 pixels; 0.25 down of a 2-unit one, 30 (y down).
    assert!(
        (moved - DVec2::new(-60.0, -30.0)).length() < 1e-9,
        "{moved}"
    );
}

#[test]
fn an_orthographic_camera_refuses_lens_fields_by_name() {
    let ortho = "projection = \"orthographic\"\nwindow = [3.0, 2.0]\n";
    for (field, line) in [
        ("f_number", "f_number = 2.8"),
        ("focal_length", "focal_length = 50.0"),
        ("vertical_fov", "vertical_fov = 30.0"),
        ("film", "film = [36.0, 24.0]"),
        ("focus_distance", "focus_distance = 4.0"),
        ("film_distance", "film_distance = 52.0"),
        ("lens_tilt", "lens_tilt = 3.0"),
        ("lens_shift", "lens_shift = [1.0, 0.0]"),
        ("aperture_blades", "aperture_blades = 6"),
        ("focus_surface", "focus_surface = \"sphere\""),
    ] {
        let message = error(&format!("{ortho}{line}"));
        assert!(
            message.contains(&format!("camera.{field}")) && message.contains("orthographic"),
            "{field}: {message}"
        );
    }
    let message = error("projection = \"orthographic\"");
    assert!(message.contains("window"), "{message}");
    for (window, field) in [
        ("[0.0, 2.0]", "camera.window[0]"),
        ("[3.0, -2.0]", "camera.window[1]"),
        ("[nan, 2.0]", "camera.window[0]"),
        ("[3.0, inf]", "camera.window[1]"),
        ("[4.0, 2.0]", "window aspect 2.0000"),
    ] {
        let message = error(&format!("projection = \"orthographic\"\nwindow = {window}"));
        assert!(message.contains(field), "{window}: {message}");
    }
    let message = error(&format!("{ortho}film_tilt = 90.0"));
    assert!(message.contains("camera.film_tilt"), "{message}");
    let message = error("window = [3.0, 2.0]");
    assert!(
        message.contains("camera.window") && message.contains("orthographic"),
        "{message}"
    );
}

#[test]
fn the_camera_report_of_an_orthographic_camera_has_no_lens_figures() {
    use chambre::camera::report::{camera_report, camera_summary};
    let c = orthographic("film_tilt = 10.0\nfilm_shift = [0.5, 0.0]");
    let report = camera_report(&c, 0.03, 100.0);
    for wanted in [
        "projection: orthographic",
        "window: 3.000000 x 2.000000 scene units",
        "shift [0.500000, 0.000000] scene units",
        "10.000000 deg from the window's normal",
    ] {
        assert!(report.contains(wanted), "{wanted:?} in\n{report}");
    }
    for unwanted in [
        "inf",
        "NaN",
        "focal",
        "f = ",
        "hinge",
        "field of view",
        "mm",
    ] {
        assert!(!report.contains(unwanted), "{unwanted:?} in\n{report}");
    }
    let summary = camera_summary(&c);
    assert!(
        summary.contains("orthographic, window 3.000000 x 2.000000"),
        "{summary}"
    );
    assert!(
        !summary.contains("inf") && !summary.contains("NaN"),
        "{summary}"
    );
}

#[test]
fn an_orthographic_render_agrees_on_both_paths_and_is_not_black() {
    let text = scene_text(
        "projection = \"orthographic\"\nwindow = [3.0, 2.0]\nfilm_tilt = 12.0\n\
         film_swing = -8.0\nfilm_shift = [0.1, 0.2]",
        48,
        32,
    );
    let scene = Scene::from_str(Path::new("t.toml"), &text, &[]).unwrap();
    let flat = flatten(&scene);
    let cpu = common::render_cpu(&flat);
    let lit = cpu.pixels.iter().filter(|p| p.x > 0.0).count();
    assert!(lit > 100 && lit < 48 * 32, "{lit} pixels see the sphere");
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
        assert!(within > 0.995 && mean_abs < 1e-4, "{within} {mean_abs}");
    }
}
