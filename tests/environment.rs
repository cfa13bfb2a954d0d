//! Lights at infinity (`[[lights]] type = "environment"` and `"sun"`) against what is known
//! exactly, on both integrators and both paths: furnaces (a convex Lambert object under a
//! constant environment of radiance L shows albedo x L), an infinite plane under a constant sky
//! (irradiance pi L), a plane facing a sun of any size (irradiance E cos theta), a map of one
//! value against the constant light, a plane under a spotted map against a quadrature of its
//! lookup, the map's importance sampling (its density integrates to
//! 1, its samples follow it, a sample's density is the lookup's), and refusals by name.
//!
//! The renders are noisy: a test compares the mean of a block of pixels with the exact value
//! within 4.5 standard errors of that mean (the pixels' own spread), and a small absolute slack.

mod common;

use std::f64::consts::PI;
use std::path::PathBuf;

use chambre::integrator::environment::{
    environment_radiance, environment_sample, map_coordinates, sky_radiance, sky_sample,
};
use chambre::layout::{GpuLight, LIGHT_ENVIRONMENT, LIGHT_SUN};
use chambre::math::rng::Rng;
use chambre::pack::{flatten, sun_cone, sun_radiance_over_density};
use chambre::render::Image;
use chambre::scene::environment::EnvironmentMap;
use chambre::scene::{Scene, SceneBuilder};
use glam::Vec3;

/// A scratch folder of this test binary.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-env-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes an OpenEXR map of `width` x `height` texels (rows from the top) to `path`.
fn write_exr(path: &std::path::Path, width: u32, height: u32, texels: &[[f32; 3]]) {
    let flat: Vec<f32> = texels.iter().flatten().copied().collect();
    image::Rgb32FImage::from_raw(width, height, flat)
        .unwrap()
        .save(path)
        .unwrap();
}

fn build(builder: SceneBuilder, integrator: &str) -> Scene {
    builder
        .render_field("integrator", integrator.into())
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Mean and standard error of the mean of channel `c` over pixels `xs` x `ys`.
fn block_mean(
    image: &Image,
    xs: std::ops::Range<u32>,
    ys: std::ops::Range<u32>,
    c: usize,
) -> (f64, f64) {
    let values: Vec<f64> = ys
        .flat_map(|y| xs.clone().map(move |x| (x, y)))
        .map(|(x, y)| image.pixels[(y * image.width + x) as usize][c] as f64)
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// Asserts that the block's mean of every channel is `expected` within 4.5 standard errors
/// plus `slack` (relative); returns the worst deviation in standard errors.
fn assert_block(
    what: &str,
    image: &Image,
    xs: std::ops::Range<u32>,
    ys: std::ops::Range<u32>,
    expected: f64,
    slack: f64,
) -> f64 {
    let mut worst = 0f64;
    for c in 0..3 {
        let (mean, error) = block_mean(image, xs.clone(), ys.clone(), c);
        let deviation = (mean - expected).abs();
        assert!(
            deviation <= 4.5 * error + slack * expected,
            "{what}: channel {c}: mean {mean} vs {expected} (standard error {error:.2e})"
        );
        worst = worst.max(deviation / error.max(1e-12));
    }
    worst
}

/// A Lambert sphere in front of the default camera, lit by the lights `lights` adds.
fn sphere_scene(albedo: f64, lights: impl Fn(SceneBuilder) -> SceneBuilder) -> SceneBuilder {
    lights(
        SceneBuilder::new(32, 32)
            .spp(16)
            .max_depth(4)
            .lambert("grey", [albedo; 3])
            .sphere([0.0, 0.0, -4.0], 1.0, "grey"),
    )
}

/// The furnace: a convex Lambert sphere of albedo rho under a constant environment of radiance
/// 1 shows rho (Whitted's direct light is the whole of it, the path tracer's bounces all
/// escape), and the environment itself shows 1 exactly; on both paths.
#[test]
fn a_convex_sphere_in_a_constant_environment_shows_its_albedo() {
    for integrator in ["whitted", "path"] {
        for albedo in [1.0, 0.5] {
            let scene = build(
                sphere_scene(albedo, |b| b.environment_light([1.0; 3], 4)),
                integrator,
            );
            for (path, image) in common::both(&scene) {
                let what = format!("{integrator} {path} albedo {albedo}");
                let worst = assert_block(&what, &image, 10..22, 10..22, albedo, 0.0);
                eprintln!("{what}: worst {worst:.2} standard errors");
                for (x, y) in [(0, 0), (31, 0), (0, 31), (31, 31)] {
                    let p = image.pixels[(y * 32 + x) as usize];
                    assert_eq!(p, Vec3::ONE, "{what}: corner ({x}, {y})");
                }
            }
        }
    }
}

/// An infinite Lambert plane (y = 0, facing up) of `albedo`, seen from 1 above it towards the
/// horizon (rows 16 to 23 of 24 show it), at 16 spp; the lights are the caller's.
fn plane_scene(albedo: f64) -> SceneBuilder {
    SceneBuilder::new(24, 24)
        .spp(16)
        .pinhole([0.0, 1.0, 0.0], [0.0, 0.0, -3.0], 40.0)
        .lambert("ground", [albedo; 3])
        .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "ground")
}

/// An infinite Lambert plane under a constant environment of radiance L receives pi L from
/// the hemisphere above it and shows albedo x L everywhere (the analytic check).
#[test]
fn an_infinite_plane_under_a_constant_sky_shows_albedo_times_the_sky() {
    let (sky, albedo) = (2.0, 0.3);
    for integrator in ["whitted", "path"] {
        let scene = build(
            plane_scene(albedo).environment_light([sky; 3], 2),
            integrator,
        );
        for (path, image) in common::both(&scene) {
            let what = format!("{integrator} {path}");
            assert_block(&what, &image, 0..24, 16..24, albedo * sky, 0.0);
            assert_eq!(image.pixels[0], Vec3::splat(sky as f32), "{what}: sky");
        }
    }
}

/// A Lambert plane facing a sun at 30 degrees from its normal receives E cos 30 whatever the
/// sun's size (its disc stays above the horizon: the projected solid angle of a cap of
/// half-angle alpha is pi sin^2 alpha cos theta), so it shows albedo E cos 30 / pi: from the
/// smallest sun (1e-4 degrees, whose radiance is 1e11 E) to the largest (45 degrees).
#[test]
fn a_plane_facing_a_sun_receives_its_irradiance_times_the_cosine() {
    let (irradiance, albedo) = (2.0, 0.5);
    let theta = 30f64.to_radians();
    let direction = [-theta.sin(), -theta.cos(), 0.0];
    let expected = albedo * irradiance * theta.cos() / PI;
    for integrator in ["whitted", "path"] {
        for alpha in [1e-4, 0.2675, 10.0, 45.0] {
            let scene = build(
                SceneBuilder::new(24, 24)
                    .spp(8)
                    .pinhole([0.0, 1.0, 0.0], [0.0, 0.0, -3.0], 40.0)
                    .lambert("ground", [albedo; 3])
                    .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "ground")
                    .sun(direction, [irradiance; 3], alpha, 4),
                integrator,
            );
            for (path, image) in common::both(&scene) {
                let what = format!("{integrator} {path} alpha {alpha}");
                let worst = assert_block(&what, &image, 0..24, 16..24, expected, 1e-4);
                eprintln!("{what}: worst {worst:.2} standard errors");
                // The sky beside the sun is black.
                assert_eq!(image.pixels[0], Vec3::ZERO, "{what}: sky");
            }
        }
    }
}

/// The sun seen directly: its disc shows radiance E / (pi sin^2 alpha), and a ray beside it
/// shows nothing; the cone's test holds for the smallest and the largest discs.
#[test]
fn a_sun_is_seen_within_its_cone_only() {
    for alpha_deg in [1e-4f64, 0.2675, 45.0] {
        let alpha = alpha_deg.to_radians();
        let axis = Vec3::new(0.3, 0.9, -0.1).normalize();
        let light = GpuLight {
            kind: LIGHT_SUN,
            p0: axis.to_array(),
            p1: sun_cone(alpha_deg),
            p2: [sun_radiance_over_density(alpha_deg), 0.0, 0.0],
            samples: 1,
            ..Default::default()
        };
        let (radiance, pdf) = sky_radiance(&light, &[], axis);
        let expected = 1.0 / (PI * alpha.sin().powi(2));
        assert!(
            (radiance.x as f64 / expected - 1.0).abs() < 1e-6,
            "{alpha_deg}"
        );
        let cone = 2.0 * PI * 2.0 * (0.5 * alpha).sin().powi(2);
        assert!((pdf as f64 * cone - 1.0).abs() < 1e-5, "{alpha_deg}: {pdf}");
        // L / pdf is 1 / cos^2(alpha / 2), E's scale, to f32's precision at every size.
        let ratio = (light.p1[1] / light.p1[2]) as f64 * (0.5 * alpha).cos().powi(2);
        assert!((ratio - 1.0).abs() < 1e-6, "{alpha_deg}: {ratio}");
        let (tangent, _) = chambre::integrator::bsdf::tangents(axis);
        let outside =
            (axis * (1.5 * alpha).cos() as f32 + tangent * (1.5 * alpha).sin() as f32).normalize();
        assert_eq!(sky_radiance(&light, &[], outside).1, 0.0, "{alpha_deg}");
        let mut rng = Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let s = sky_sample(&light, &[], rng.next_2d());
            let angle = (s.wi - axis).length() as f64;
            assert!(angle <= 2.0 * (0.5 * alpha).sin() * (1.0 + 1e-3) + 2e-7);
            assert!((s.wi.length() - 1.0).abs() < 1e-6);
        }
    }
}

/// An environment map of one value is the constant light of that value: the furnace again.
#[test]
fn a_map_of_one_value_lights_as_the_constant_environment() {
    let dir = scratch("flat-map");
    let file = dir.join("flat.exr");
    write_exr(&file, 8, 4, &[[2.0, 2.0, 2.0]; 32]);
    for integrator in ["whitted", "path"] {
        let scene = build(
            sphere_scene(0.5, |b| {
                b.environment_map(file.to_str().unwrap(), 0.5, 30.0, 4)
            }),
            integrator,
        );
        for (path, image) in common::both(&scene) {
            let what = format!("{integrator} {path}");
            assert_block(&what, &image, 10..22, 10..22, 0.5, 0.0);
            assert_eq!(image.pixels[0], Vec3::ONE, "{what}: corner");
        }
    }
}

/// An infinite Lambert plane under a map that is far from uniform (a bright spot above the
/// horizon, a blue band below it), turned or not, shows albedo E / pi, where E = the integral of
/// L(w) cos(theta) over the upper hemisphere, by a midpoint rule on the map's own lookup: the
/// map's importance sampling (and the path tracer's MIS with it) is unbiased against the lookup,
/// on both integrators and both paths.
#[test]
fn a_plane_under_a_map_shows_the_quadrature_of_its_irradiance() {
    let (w, h) = (16u32, 8u32);
    let dir = scratch("plane-map");
    let file = dir.join("spotted.exr");
    write_exr(&file, w, h, &spotted_map(w, h));
    let map = EnvironmentMap::read(&file).unwrap();
    let albedo = 0.5;
    for degrees in [0.0f64, 50.0] {
        let (light, data) = map_light(&map, (degrees / 360.0) as f32);
        let (nu, nv) = (1024, 256);
        let mut irradiance = [0f64; 3];
        for j in 0..nv {
            let theta = 0.5 * PI * (j as f64 + 0.5) / nv as f64;
            for i in 0..nu {
                let phi = 2.0 * PI * (i as f64 + 0.5) / nu as f64;
                let d = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    theta.cos() as f32,
                    (theta.sin() * phi.sin()) as f32,
                );
                let (radiance, _) = environment_radiance(&light, &data, d);
                let weight =
                    theta.cos() * theta.sin() * (0.5 * PI / nv as f64) * (2.0 * PI / nu as f64);
                for c in 0..3 {
                    irradiance[c] += radiance[c] as f64 * weight;
                }
            }
        }
        for integrator in ["whitted", "path"] {
            let scene = build(
                plane_scene(albedo).environment_map(file.to_str().unwrap(), 1.0, degrees, 4),
                integrator,
            );
            for (path, image) in common::both(&scene) {
                for (c, e) in irradiance.iter().enumerate() {
                    let expected = albedo * e / PI;
                    let (mean, error) = block_mean(&image, 0..24, 16..24, c);
                    eprintln!(
                        "{degrees} deg {integrator} {path} channel {c}: {mean:.5} against \
                         {expected:.5} ({:.1} standard errors)",
                        (mean - expected) / error
                    );
                    assert!(
                        (mean - expected).abs() <= 4.5 * error + 2e-3 * expected,
                        "{degrees} deg {integrator} {path} channel {c}: {mean} against {expected}"
                    );
                }
            }
        }
    }
}

/// The lights at infinity render the same on the GPU as on the CPU (tests/gpu_cpu_agreement.rs's
/// tolerances): a map with a bright spot and a sun over a sphere, a mirror and a plane, on both
/// integrators.
#[test]
fn lights_at_infinity_agree_on_gpu_and_cpu() {
    let dir = scratch("agree");
    let file = dir.join("spot.exr");
    write_exr(&file, 16, 8, &spotted_map(16, 8));
    for integrator in ["whitted", "path"] {
        let scene = build(
            SceneBuilder::new(48, 32)
                .spp(4)
                .max_depth(3)
                .pinhole([0.0, 1.0, 3.0], [0.0, 0.5, 0.0], 50.0)
                .lambert("ground", [0.5, 0.4, 0.3])
                .lambert("red", [0.7, 0.2, 0.1])
                .mirror("chrome", [0.9; 3])
                .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "ground")
                .sphere([-0.6, 0.5, 0.0], 0.5, "red")
                .sphere([0.6, 0.5, 0.0], 0.5, "chrome")
                .environment_map(file.to_str().unwrap(), 1.0, 40.0, 2)
                .sun([-0.3, -1.0, -0.4], [3.0, 2.8, 2.5], 2.0, 2),
            integrator,
        );
        let flat = flatten(&scene);
        let Some(gpu) = common::render_gpu(&flat) else {
            return;
        };
        let cpu = common::render_cpu(&flat);
        assert_eq!(cpu.non_finite_count(), 0);
        let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
        eprintln!(
            "{integrator}: {:.4}% of pixels within 1e-3, mean |diff| {mean_abs:.3e}",
            within * 100.0
        );
        assert!(
            within >= 0.995 && mean_abs < 1e-4,
            "{integrator}: {:.3}% within 1e-3, mean |diff| {mean_abs:.3e}",
            within * 100.0
        );
    }
}

/// A sky of 0.2 with a bright spot (the sun-like texels at row 1, columns 3-4) and a blue
/// band at the bottom.
fn spotted_map(width: u32, height: u32) -> Vec<[f32; 3]> {
    (0..width * height)
        .map(|k| {
            let (x, y) = (k % width, k / width);
            match (x, y) {
                (3..=4, 1) => [60.0, 50.0, 40.0],
                (_, y) if y == height - 1 => [0.05, 0.1, 0.4],
                _ => [0.2, 0.25, 0.3],
            }
        })
        .collect()
}

/// The environment light of `map` turned `turns`, and its packed array.
fn map_light(map: &EnvironmentMap, turns: f32) -> (GpuLight, Vec<f32>) {
    let light = GpuLight {
        kind: LIGHT_ENVIRONMENT,
        p0: [turns, map.width as f32, map.height as f32],
        color: [1.0; 3],
        samples: 1,
        ..Default::default()
    };
    (light, map.packed())
}

/// The map's density integrates to 1 over the sphere (a midpoint rule on a fine grid of
/// directions, each cell weighted by its solid angle), turned or not.
#[test]
fn the_map_density_integrates_to_one_over_the_sphere() {
    let map =
        EnvironmentMap::new(std::path::Path::new("spotted"), 16, 8, spotted_map(16, 8)).unwrap();
    for turns in [0.0f32, 0.37] {
        let (light, data) = map_light(&map, turns);
        let (nu, nv) = (1024, 512);
        let mut integral = 0f64;
        for j in 0..nv {
            let theta = PI * (j as f64 + 0.5) / nv as f64;
            for i in 0..nu {
                let phi = 2.0 * PI * (i as f64 + 0.5) / nu as f64;
                let d = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    theta.cos() as f32,
                    (-theta.sin() * phi.sin()) as f32,
                );
                let (_, pdf) = environment_radiance(&light, &data, d);
                integral += pdf as f64 * theta.sin() * (PI / nv as f64) * (2.0 * PI / nu as f64);
            }
        }
        assert!((integral - 1.0).abs() < 2e-3, "turns {turns}: {integral}");
    }
}

/// Each sample's density and radiance are what a lookup of its direction finds, and the
/// samples' histogram over the texels follows the density (Pearson's chi-squared over the
/// texels with an expected count of 5 or more, against the 0.999 quantile).
#[test]
fn map_samples_follow_the_density_the_lookup_reports() {
    let (w, h) = (16u32, 8u32);
    let map =
        EnvironmentMap::new(std::path::Path::new("spotted"), w, h, spotted_map(w, h)).unwrap();
    let turns = 0.2f32;
    let (light, data) = map_light(&map, turns);
    let n = 400_000u32;
    let mut counts = vec![0u32; (w * h) as usize];
    let mut rng = Rng::new(9, 4, 2);
    let mut mismatched = 0;
    for _ in 0..n {
        let s = environment_sample(&light, &data, rng.next_2d());
        let (radiance, pdf) = environment_radiance(&light, &data, s.wi);
        if (pdf - s.pdf).abs() > 1e-3 * s.pdf || radiance != s.radiance {
            // Only a direction on a texel's edge may look up its neighbour.
            mismatched += 1;
        }
        let (u, v) = map_coordinates(s.wi, turns);
        let column = ((u * w as f32) as u32).min(w - 1);
        let row = ((v * h as f32) as u32).min(h - 1);
        counts[(row * w + column) as usize] += 1;
    }
    assert!(
        mismatched <= n / 10_000,
        "{mismatched} samples disagree with their lookup"
    );
    // Each texel's probability: its density in (u, v) over the texel's share of (u, v).
    let pdf = &data[(3 * w * h) as usize..(4 * w * h) as usize];
    let (mut chi2, mut bins) = (0f64, 0u32);
    for (k, &count) in counts.iter().enumerate() {
        let expected = n as f64 * pdf[k] as f64 / (w * h) as f64;
        if expected >= 5.0 {
            chi2 += (count as f64 - expected).powi(2) / expected;
            bins += 1;
        } else {
            assert!(count as f64 <= 5.0 * expected + 10.0, "texel {k}: {count}");
        }
    }
    // The 0.999 quantile of chi-squared with k degrees of freedom, Wilson-Hilferty.
    let k = (bins - 1) as f64;
    let z = 3.09;
    let quantile = k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
    assert!(
        chi2 < quantile,
        "chi2 {chi2:.1} over {bins} texels (0.999 quantile {quantile:.1})"
    );
    // The spot's two texels take the larger share, as their luminance says.
    let spot = counts[(w + 3) as usize] + counts[(w + 4) as usize];
    assert!(spot as f64 > 0.5 * n as f64, "the spot drew {spot} of {n}");
}

/// Refusals by field name: a background beside an environment, two environments, a missing
/// or unreadable file, a black map or a negative texel, a negative scale, a sun out of range.
#[test]
fn bad_environments_are_refused_by_name() {
    let dir = scratch("refusals");
    let black = dir.join("black.exr");
    write_exr(&black, 2, 2, &[[0.0; 3]; 4]);
    let negative = dir.join("negative.exr");
    write_exr(&negative, 2, 1, &[[1.0; 3], [-1.0, 0.0, 0.0]]);
    let text = dir.join("text.exr");
    std::fs::write(&text, "not an image").unwrap();
    let base = || SceneBuilder::new(8, 8).lambert("grey", [0.5; 3]);
    let cases: Vec<(SceneBuilder, &str)> = vec![
        (
            base().background([0.1; 3]).environment_light([1.0; 3], 1),
            "render.background",
        ),
        (
            base()
                .environment_light([1.0; 3], 1)
                .environment_light([1.0; 3], 1),
            "lights[1].type",
        ),
        (
            base().environment_map(dir.join("missing.exr").to_str().unwrap(), 1.0, 0.0, 1),
            "lights[0].file",
        ),
        (
            base().environment_map(text.to_str().unwrap(), 1.0, 0.0, 1),
            "lights[0].file",
        ),
        (
            base().environment_map(black.to_str().unwrap(), 1.0, 0.0, 1),
            "lights[0].file",
        ),
        (
            base().environment_map(negative.to_str().unwrap(), 1.0, 0.0, 1),
            "lights[0].file",
        ),
        (
            base().environment_map(black.to_str().unwrap(), -1.0, 0.0, 1),
            "lights[0].scale",
        ),
        (
            base().sun([0.0, -1.0, 0.0], [1.0; 3], 50.0, 1),
            "lights[0].angular_radius_deg",
        ),
        (
            base().sun([0.0, -1.0, 0.0], [1.0; 3], 1e-5, 1),
            "lights[0].angular_radius_deg",
        ),
    ];
    for (builder, field) in cases {
        let error = builder.build().expect_err(field).to_string();
        assert!(error.contains(field), "{field}: {error}");
        assert!(
            !error.contains("  "),
            "{field}: a run of spaces in {error:?}"
        );
    }
    let negative_message = base()
        .environment_map(negative.to_str().unwrap(), 1.0, 0.0, 1)
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        negative_message.contains("negative.exr") && negative_message.contains("column 1, row 0"),
        "{negative_message}"
    );
    // Too bright: the file's texel where it is the file's own, the scale where it raised it.
    let bright = dir.join("bright.exr");
    write_exr(&bright, 2, 1, &[[1.0; 3], [3e38, 0.0, 0.0]]);
    let message = base()
        .environment_map(bright.to_str().unwrap(), 1.0, 0.0, 1)
        .build()
        .unwrap_err()
        .to_string();
    for part in ["lights[0].file", "bright.exr", "column 1, row 0"] {
        assert!(message.contains(part), "`{part}` not in {message}");
    }
    let dim = dir.join("dim.exr");
    write_exr(&dim, 2, 1, &[[100.0; 3], [1.0; 3]]);
    let message = base()
        .environment_map(dim.to_str().unwrap(), 1e19, 0.0, 1)
        .build()
        .unwrap_err()
        .to_string();
    for part in ["lights[0].scale", "dim.exr", "column 0, row 0"] {
        assert!(message.contains(part), "`{part}` not in {message}");
    }
}
