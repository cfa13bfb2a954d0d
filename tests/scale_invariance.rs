//! Scale invariance and precision at the extremes the scene format allows (lengths up to 1e9):
//! the same scene scaled by 1e-6 ... 1e6 renders the same image; a ground sphere of radius up to
//! 1e9 renders like the plane it approximates; a scene translated far from the origin stays
//! close to the untranslated one, and the GPU stays close to the CPU there. Both paths, and the
//! raster preview's shadow maps and Fermat reflections.
//!
//! Figures: `relative_l1` = sum |a - b| / sum |a| over all pixels and channels; "within x" =
//! fraction of pixels whose every channel agrees within x relative (`common::agreement`). The
//! bounds asserted are the measured figures with a margin; the measurements are in the report
//! that goes with docs/robustness.md.

mod common;

use chambre::layout::STATUS_LOOP_LIMIT;
use std::path::Path;

use chambre::pack::{FlatScene, flatten};
use chambre::render::Image;
use chambre::scene::Scene;

fn vec3(v: [f64; 3], scale: f64, offset: f64) -> String {
    format!(
        "[{:e}, {:e}, {:e}]",
        v[0] * scale + offset,
        v[1] * scale + offset,
        v[2] * scale + offset
    )
}

/// A mirror sphere, a bunny and a floor under a point and a directional light; every length is
/// multiplied by `scale`, then moved by `offset` along each axis.
fn scaled_scene(scale: f64, offset: f64) -> String {
    let p = |v: [f64; 3]| vec3(v, scale, offset);
    let l = |v: [f64; 3]| vec3(v, scale, 0.0);
    format!(
        "[scene]\nmeters_per_unit = {mpu:e}\n[render]\nwidth = 48\nheight = 36\nspp = 2\nmax_depth = 3\n\
         ambient = [0.05, 0.05, 0.05]\n\n[camera]\nposition = {cam}\nlook_at = {target}\nfocal_length = 30.0\nfilm = [36.0, 27.0]\n\n\
         [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.8, 0.8]\n\n\
         [[materials]]\nname = \"clay\"\nmodel = \"phong\"\ndiffuse = [0.7, 0.6, 0.5]\nspecular = [0.2, 0.2, 0.2]\nshininess = 20.0\n\n\
         [[materials]]\nname = \"mirror\"\nmodel = \"mirror\"\n\n\
         [[shapes]]\ntype = \"quad\"\ncorner = {floor}\nedge_u = {eu}\nedge_v = {ev}\nmaterial = \"white\"\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = {ball}\nradius = {radius:e}\nmaterial = \"mirror\"\n\n\
         [[shapes]]\ntype = \"mesh\"\nfile = \"meshes/bunny-npm-lowres.obj\"\nscale = {bunny:e}\ntranslate = {bt}\nmaterial = \"clay\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = {light}\nintensity = [{i:e}, {i:e}, {i:e}]\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = [0.8, 0.8, 0.8]\n",
        mpu = 1.0 / scale,
        cam = p([0.0, 4.0, 9.0]),
        target = p([0.0, 1.0, 0.0]),
        floor = p([-10.0, 0.0, -10.0]),
        eu = l([20.0, 0.0, 0.0]),
        ev = l([0.0, 0.0, 20.0]),
        ball = p([-1.8, 1.2, 0.0]),
        radius = 1.2 * scale,
        bunny = 0.35 * scale,
        bt = p([1.5, 0.0, 0.0]),
        light = p([3.0, 6.0, 4.0]),
        i = 40.0 * scale * scale,
    )
}

/// A lambert ball and a mirror ball resting on the ground at y = 0 near the origin: either a
/// plane, or a sphere of radius `radius` whose top touches the origin.
fn ground_scene(radius: Option<f64>) -> String {
    let p = |v: [f64; 3]| vec3(v, 1.0, 0.0);
    let ground = match radius {
        None => format!(
            "type = \"plane\"\npoint = {}\nnormal = [0.0, 1.0, 0.0]",
            p([0.0, 0.0, 0.0])
        ),
        Some(r) => format!(
            "type = \"sphere\"\ncenter = {}\nradius = {r:e}",
            p([0.0, -r, 0.0])
        ),
    };
    format!(
        "[render]\nwidth = 48\nheight = 36\nspp = 2\nmax_depth = 3\nambient = [0.05, 0.05, 0.05]\n\n\
         [camera]\nposition = {cam}\nlook_at = {target}\nfocal_length = 30.0\nfilm = [36.0, 27.0]\n\n\
         [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.8, 0.8]\n\n\
         [[materials]]\nname = \"mirror\"\nmodel = \"mirror\"\n\n\
         [[shapes]]\n{ground}\nmaterial = \"white\"\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = {a}\nradius = 1.0\nmaterial = \"white\"\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = {b}\nradius = 0.8\nmaterial = \"mirror\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = {light}\nintensity = [40.0, 40.0, 40.0]\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = [0.8, 0.8, 0.8]\n",
        cam = p([0.0, 7.0, 6.0]),
        target = p([0.0, 0.5, 0.0]),
        a = p([1.3, 1.0, 0.0]),
        b = p([-1.3, 0.8, 0.5]),
        light = p([3.0, 6.0, 4.0]),
    )
}

fn flat(text: &str) -> FlatScene {
    // A name in scenes/ (no file has it: the text is in memory) so that the bunny's relative
    // path resolves.
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join("in_memory");
    flatten(&Scene::from_str(&path, text, &[]).unwrap_or_else(|e| panic!("{e}")))
}

/// sum |a - b| / sum |a| over all pixels and channels.
fn relative_l1(reference: &Image, image: &Image) -> f64 {
    let (mut diff, mut sum) = (0.0f64, 0.0f64);
    for (p, q) in reference.pixels.iter().zip(&image.pixels) {
        diff += (*p - *q).abs().element_sum() as f64;
        sum += p.abs().element_sum() as f64;
    }
    diff / sum
}

/// Asserts that `image` is finite and within `max_relative_l1` and `min_within` (fraction of
/// pixels within `tolerance`) of `reference`.
fn assert_close(
    label: &str,
    reference: &Image,
    image: &Image,
    max_relative_l1: f64,
    tolerance: f32,
    min_within: f64,
) {
    assert_eq!(image.non_finite_count(), 0, "{label}: non-finite pixels");
    let difference = relative_l1(reference, image);
    let (within, _) = common::agreement(reference, image, tolerance);
    eprintln!(
        "{label}: relative L1 {difference:.2e}, {:.2}% within {tolerance:e}",
        within * 100.0
    );
    assert!(
        difference <= max_relative_l1 && within >= min_within,
        "{label}: relative L1 {difference:.3e} (bound {max_relative_l1:e}), {:.3}% within \
         {tolerance:e} (bound {:.2}%)",
        within * 100.0,
        min_within * 100.0
    );
}

/// Scales from 1e-6 to 1e6: measured relative L1 <= 2.2e-7 and every pixel within 1e-3 on
/// both paths (before the error-bounded offsets: 6.4e-2 at 1e-6, 7.3e-3 at 1e-4).
const SCALES: [f64; 6] = [1e-6, 1e-4, 1e-2, 1e2, 1e4, 1e6];
const SCALE_MAX_RELATIVE_L1: f64 = 2e-6;
const SCALE_MIN_WITHIN_1E3: f64 = 0.999;

/// Every scale of `SCALES` renders like scale 1 on the path `render` stands for.
fn assert_scale_invariant(path: &str, render: impl Fn(&FlatScene) -> Option<Image>) {
    let Some(reference) = render(&flat(&scaled_scene(1.0, 0.0))) else {
        return;
    };
    for scale in SCALES {
        let image = render(&flat(&scaled_scene(scale, 0.0))).unwrap();
        assert_close(
            &format!("{path}, scale {scale:e}"),
            &reference,
            &image,
            SCALE_MAX_RELATIVE_L1,
            1e-3,
            SCALE_MIN_WITHIN_1E3,
        );
    }
}

#[test]
fn cpu_renders_do_not_depend_on_the_scene_scale() {
    assert_scale_invariant("CPU", |scene| Some(common::render_cpu(scene)));
}

#[test]
fn gpu_renders_do_not_depend_on_the_scene_scale() {
    assert_scale_invariant("GPU", common::render_gpu);
}

/// Ground spheres of radius 1e6 to 1e9 against the plane y = 0: the curvature is below 1e-5
/// units inside the view, so the images must agree. Measured relative L1 <= 1.3e-6 (the 1e6
/// sphere's curvature); before the better-conditioned sphere test, 1e7 was 13% too dark and 1e8
/// 94%.
#[test]
fn huge_ground_spheres_render_like_the_plane_on_both_paths() {
    let plane = flat(&ground_scene(None));
    let cpu_plane = common::render_cpu(&plane);
    let gpu_plane = common::render_gpu(&plane);
    for radius in [1e6, 1e7, 1e8, 1e9] {
        let sphere = flat(&ground_scene(Some(radius)));
        let cpu = common::render_cpu(&sphere);
        assert_close(
            &format!("CPU, radius {radius:e}"),
            &cpu_plane,
            &cpu,
            1e-5,
            1e-3,
            0.999,
        );
        if let Some(gpu_plane) = &gpu_plane {
            let gpu = common::render_gpu(&sphere).unwrap();
            assert_close(
                &format!("GPU, radius {radius:e}"),
                gpu_plane,
                &gpu,
                1e-5,
                1e-3,
                0.999,
            );
        }
    }
}

/// Bounds per translation, in units of the scene size (the scene spans ~20 units at scale 1):
/// (offset / scale, max relative L1 from the untranslated CPU render, min fraction within 1e-2
/// of it, max GPU/CPU relative L1, min fraction of GPU pixels within 1e-3 of the CPU's).
/// Positions round to ULPs of the offset (6e-2 units at 1e6), which moves silhouettes, contact
/// points and 1/d^2 falloffs: the deviation grows with the offset and cannot vanish in f32.
const OFFSET_BOUNDS: [(f64, f64, f64, f64, f64); 4] = [
    (1.0, 2e-6, 0.999, 1e-6, 0.999),
    (1e2, 1e-5, 0.999, 1e-6, 0.999),
    (1e4, 3e-3, 0.96, 5e-5, 0.995),
    (1e6, 8e-2, 0.80, 2e-2, 0.92),
];

#[test]
fn translated_scenes_stay_close_to_the_origin_and_the_gpu_to_the_cpu() {
    for scale in [1e-3, 1.0, 1e3] {
        let reference = common::render_cpu(&flat(&scaled_scene(scale, 0.0)));
        for (ratio, max_l1, min_within, max_gpu_l1, min_gpu_within) in OFFSET_BOUNDS {
            let offset = ratio * scale;
            if offset + 10.0 * scale > 1e9 {
                continue; // beyond the format's +-1e9 coordinates
            }
            let scene = flat(&scaled_scene(scale, offset));
            let cpu = common::render_cpu(&scene);
            let label = format!("scale {scale:e}, offset {offset:e}");
            assert_close(
                &format!("CPU, {label}"),
                &reference,
                &cpu,
                max_l1,
                1e-2,
                min_within,
            );
            let Some((gpu, flags, lavapipe)) = common::render_gpu_with_flags(&scene) else {
                continue;
            };
            if flags == STATUS_LOOP_LIMIT && lavapipe && ratio >= 1e6 {
                // A million scene sizes from the origin, f32 rounds the bunny's vertices to a
                // few dozen steps across and its BVH boxes (widened by 16 ULPs of their
                // coordinates) overlap: the expected traversal grows from 4 to 244 loop
                // iterations per ray (surface-area estimate over the whole scene; far more
                // for rays into the bunny), and lavapipe's limit of 65535 loop iterations per
                // invocation cuts the traversal. The render reports it (never a quiet image);
                // the CPU path and real GPUs have no such limit.
                eprintln!("GPU, {label}: lavapipe's loop limit reported, as documented");
                continue;
            }
            assert_eq!(flags, 0, "GPU, {label}: kernel status flags");
            {
                assert_close(
                    &format!("GPU vs CPU, {label}"),
                    &cpu,
                    &gpu,
                    max_gpu_l1,
                    1e-3,
                    min_gpu_within,
                );
            }
        }
    }
}

/// A point light exactly on a wall (or, `wall: false`, the same light with no wall), lighting
/// a floor in front of it; everything moved by `offset`.
fn light_on_wall(wall: bool, offset: f64) -> String {
    let p = |v: [f64; 3]| vec3(v, 1.0, offset);
    let wall = if wall {
        format!(
            "[[shapes]]\ntype = \"quad\"\ncorner = {}\nedge_u = [20.0, 0.0, 0.0]\nedge_v = [0.0, 10.0, 0.0]\nmaterial = \"white\"\n",
            p([-10.0, 0.0, -5.0])
        )
    } else {
        String::new()
    };
    format!(
        "[render]\nwidth = 48\nheight = 36\nspp = 1\nmax_depth = 0\n\n\
         [camera]\nposition = {cam}\nlook_at = {target}\nfocal_length = 20.0\nfilm = [36.0, 27.0]\n\n\
         [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.8, 0.8]\n\n\
         [[shapes]]\ntype = \"quad\"\ncorner = {floor}\nedge_u = [20.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 20.0]\nmaterial = \"white\"\n\n\
         {wall}\n[[lights]]\ntype = \"point\"\nposition = {light}\nintensity = [40.0, 40.0, 40.0]\n",
        cam = p([0.0, 4.0, 9.0]),
        target = p([0.0, 1.0, -5.0]),
        floor = p([-10.0, 0.0, -5.0]),
        light = p([0.3, 3.0, -5.0]),
    )
}

/// A point light exactly on a wall lights the floor in front as if the wall were not there:
/// shadow rays end on the wall's plane, where its hit rounds to either side of the light's
/// distance, and stop `SHADOW_EPSILON` short of it. Without that, 113 of 762 floor pixels were
/// in shadow at offset 0. At 1e6, positions round by 0.06 units and one pixel where the floor
/// meets the wall may show the wall: at most 2 pixels may change.
#[test]
fn a_point_light_on_a_wall_is_not_shadowed_by_it() {
    for offset in [0.0, 1e2, 1e4, 1e6] {
        let scenes = [false, true].map(|wall| flat(&light_on_wall(wall, offset)));
        let mut images = vec![[0, 1].map(|i| common::render_cpu(&scenes[i]))];
        if let (Some(a), Some(b)) = (
            common::render_gpu(&scenes[0]),
            common::render_gpu(&scenes[1]),
        ) {
            images.push([a, b]);
        }
        for (path, [open, walled]) in ["CPU", "GPU"].iter().zip(&images) {
            let floor = open.pixels.iter().filter(|p| p.x > 0.0).count();
            let shadowed = open
                .pixels
                .iter()
                .zip(&walled.pixels)
                .filter(|(o, w)| o.x > 0.0 && (w.x - o.x).abs() > 1e-3 * o.x)
                .count();
            eprintln!("{path}, offset {offset:e}: {shadowed} of {floor} floor pixels changed");
            assert!(floor > 500, "the floor fills the lower image");
            assert!(
                shadowed <= 2,
                "{path}, offset {offset:e}: {shadowed} pixels changed"
            );
        }
    }
}

/// The CPU path traces a pixel's camera rays in packets and draws its camera samples eight at a
/// time (`integrator::trace_pixel`): at every scale, and far from the origin, each sample is
/// the one `trace_sample` traces alone, bit for bit but at a tie (the same depth, another
/// primitive's shading).
#[test]
fn packets_trace_what_each_sample_traces_alone_at_every_scale_and_offset() {
    use chambre::integrator::{FirstHit, LightWindow, SampleStats, trace_pixel, trace_sample};
    use chambre::layout::FEATURES_ALL;
    let cases =
        SCALES
            .iter()
            .map(|&scale| (scale, 0.0))
            .chain([(1.0, 1e4), (1.0, 1e6), (1e3, 1e8)]);
    for (scale, offset) in cases {
        let text = scaled_scene(scale, offset).replace("spp = 2\n", "spp = 16\n");
        let scene = flat(&text);
        let (mut hits, mut differing) = (0, 0);
        for y in 0..scene.frame.height {
            for x in 0..scene.frame.width {
                let mut packed = Vec::new();
                let mut stats = SampleStats::default();
                trace_pixel::<FEATURES_ALL>(
                    &scene,
                    x,
                    y,
                    0..16,
                    LightWindow::ALL,
                    &mut stats,
                    &mut |radiance, hit| packed.push((radiance, *hit)),
                );
                for (sample, &(radiance, hit)) in packed.iter().enumerate() {
                    let mut alone = FirstHit::default();
                    let mut alone_stats = SampleStats::default();
                    let expected = trace_sample::<FEATURES_ALL>(
                        &scene,
                        x,
                        y,
                        sample as u32,
                        LightWindow::ALL,
                        &mut alone_stats,
                        &mut alone,
                    );
                    hits += (alone.depth > 0.0) as usize;
                    if (radiance, hit) != (expected, alone) {
                        assert_eq!(hit.depth, alone.depth, "scale {scale:e}, offset {offset:e}");
                        differing += 1;
                    }
                }
            }
        }
        let samples = (scene.frame.width * scene.frame.height * 16) as usize;
        assert!(
            hits > samples / 2,
            "scale {scale:e}, offset {offset:e}: {hits} hits"
        );
        assert!(
            differing <= 4,
            "scale {scale:e}: {differing} samples differ"
        );
    }
}

/// The raster preview with shadows (shadow maps whose views, near planes and offsets are all
/// relative to the scene's size) draws every scale of `SCALES` as it draws scale 1, within the
/// ray tracer's bounds (measured: relative L1 at most 3.5e-7).
#[test]
fn preview_shadows_do_not_depend_on_the_scene_scale() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let options = chambre::preview::PreviewOptions {
        shadows: true,
        ..Default::default()
    };
    let preview = |text: &str| {
        // In scenes/, as `flat` places it, so that the bunny's relative path resolves.
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join("in_memory");
        let scene = Scene::from_str(&path, text, &[]).unwrap_or_else(|e| panic!("{e}"));
        chambre::preview::draw_with(&context, &scene, &flatten(&scene), 1, options)
            .unwrap()
            .image
    };
    let reference = preview(&scaled_scene(1.0, 0.0));
    for scale in SCALES {
        let image = preview(&scaled_scene(scale, 0.0));
        let l1 = relative_l1(&reference, &image);
        let within = common::agreement(&reference, &image, 1e-3).0;
        println!(
            "preview with shadows, scale {scale:e}: relative L1 {l1:.2e}, within 1e-3 {within:.4}"
        );
        assert!(
            l1 < SCALE_MAX_RELATIVE_L1 && within > SCALE_MIN_WITHIN_1E3,
            "scale {scale:e}: {l1:e}, {within}"
        );
    }
}

/// A turned mirror torus over a floor beside a ball, ambient light only; every length is
/// multiplied by `scale`.
fn torus_scene(scale: f64) -> String {
    let p = |v: [f64; 3]| vec3(v, scale, 0.0);
    format!(
        "[scene]\nmeters_per_unit = {mpu:e}\n[render]\nwidth = 64\nheight = 48\nspp = 1\nmax_depth = 1\n\
         ambient = [1.0, 1.0, 1.0]\nbackground = [0.55, 0.7, 0.9]\n\n[camera]\nposition = {cam}\nlook_at = {target}\n\
         focal_length = 40.0\nfilm = [36.0, 27.0]\n\n\
         [[materials]]\nname = \"mirror\"\nmodel = \"mirror\"\nmirror = [0.9, 0.9, 0.9]\n\n\
         [[materials]]\nname = \"red\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.15, 0.1]\n\n\
         [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [0.8, 0.8, 0.8]\n\n\
         [[shapes]]\ntype = \"quad\"\ncorner = {floor}\nedge_u = {eu}\nedge_v = {ev}\nmaterial = \"white\"\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = {ball}\nradius = {radius:e}\nmaterial = \"red\"\n\n\
         [[shapes]]\ntype = \"torus\"\ncenter = {torus}\nmajor_radius = {major:e}\nminor_radius = {minor:e}\n\
         rotate = [30.0, 0.0, 20.0]\nmaterial = \"mirror\"\n",
        mpu = 1.0 / scale,
        cam = p([0.0, 1.6, 3.2]),
        target = p([0.0, 0.5, 0.0]),
        floor = p([-2.0, 0.0, -2.0]),
        eu = p([0.0, 0.0, 4.0]),
        ev = p([4.0, 0.0, 0.0]),
        ball = p([0.9, 0.3, 0.4]),
        radius = 0.3 * scale,
        torus = p([0.0, 0.6, 0.0]),
        major = 0.55 * scale,
        minor = 0.2 * scale,
    )
}

/// The preview's Fermat reflections, a torus reflecting itself among them (whose clearance
/// from its own points is relative to the eye's distance), draw every scale of `SCALES` as
/// they draw scale 1 but for a triangle whose corner sits at a threshold of the search (the law
/// of reflection's tolerance, the seam, the clearance), which f32 rounding of the scaled
/// coordinates could tip either way: measured, 6,002 triangles drawn at every scale and the
/// same pixels (both halves of the torus searched, 2026-11-25: 3,058 with one search, since
/// the torus's own points started across the hole; before that, 2,891 drawn but at 1e-2 and
/// 1, where 2,890 were, and 2 of 3,072 pixels differed).
#[test]
fn fermat_reflections_do_not_depend_on_the_scene_scale() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let options = chambre::preview::PreviewOptions {
        subdivision: Some(4),
        self_reflections: Some(1.0),
        ..Default::default()
    };
    let preview = |scale: f64| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join("in_memory");
        let scene =
            Scene::from_str(&path, &torus_scene(scale), &[]).unwrap_or_else(|e| panic!("{e}"));
        chambre::preview::draw_with(&context, &scene, &flatten(&scene), 1, options).unwrap()
    };
    let reference = preview(1.0);
    assert!(reference.reflected_drawn > 0);
    for scale in SCALES {
        let frame = preview(scale);
        let l1 = relative_l1(&reference.image, &frame.image);
        let within = common::agreement(&reference.image, &frame.image, 1e-3).0;
        println!(
            "Fermat preview, scale {scale:e}: {} reflected triangles drawn (scale 1: {}), \
             relative L1 {l1:.2e}, within 1e-3 {within:.4}",
            frame.reflected_drawn, reference.reflected_drawn
        );
        assert!(
            frame.reflected_drawn.abs_diff(reference.reflected_drawn) <= 2,
            "scale {scale:e}: {} triangles drawn against {}",
            frame.reflected_drawn,
            reference.reflected_drawn
        );
        assert!(
            l1 < 2e-3 && within > 0.998,
            "scale {scale:e}: {l1:e}, {within}"
        );
    }
}
