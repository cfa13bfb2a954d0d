//! The Fermat solver on a sphere: where it converged to the side E and V see, the law of
//! reflection holds to 1e-4 rad and the point is Alhazen's (solved independently in f64). Within
//! the seed's 5 steps it does so for all 1,747 random configurations that have a reflection
//! (the issue asks 99%; with O at the centre it was 96.9%; the failures, if any, are printed
//! with where they are, and the rate per band of the angle of incidence); the test asserts 99%.

use chambre::bench::fermat::{FermatConfig, FermatReport};
use chambre::math::rng::Rng;
use chambre::preview::MirrorSurface;
use chambre::preview::reflections::fermat::{
    Reflector, Solver, StartedFrom, TorusHalf, TorusSearch, alhazen_sphere, drawn_in_preview,
    on_cylinder, on_patch, on_torus_half, reflection_error, seen_from_outside,
    self_reflection_clear, solve_on_patch,
};
use chambre::scene::parametric::{
    BezierPatch, Cylinder, Ellipsoid, ParametricSurface, Sphere, Torus,
};
use chambre::scene::surface::Surface;
use glam::{DQuat, DVec3};

mod common;

/// A random direction (uniform on the sphere).
fn direction(rng: &mut Rng) -> DVec3 {
    let [a, b] = rng.next_2d();
    let z = 2.0 * a as f64 - 1.0;
    let phi = std::f64::consts::TAU * b as f64;
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), z, s * phi.sin())
}

/// `count` random points 1 to 3 units from `center`, in uniform directions.
fn points_around(center: DVec3, count: usize, seed: u32) -> Vec<DVec3> {
    let mut rng = Rng::new(seed, 0, 0);
    (0..count)
        .map(|_| center + direction(&mut rng) * (1.0 + 2.0 * rng.next_f32() as f64))
        .collect()
}

/// The seed's search on random configurations around a sphere (E at 2–6 radii, V at 1.2–4.2,
/// at most 150° apart seen from the centre). Where V shows in the mirror at all (E and V see a
/// common point of the sphere: the angles their tangent cones reach from the centre add up to
/// more than the angle between them), it finds Alhazen's point within 5 steps in 99% or more
/// of them (the rest are printed, by angle of incidence and by how far the pair is from having
/// no common point: grazing); where V does not show, it never claims a reflection seen from
/// outside.
#[test]
fn the_solver_finds_alhazens_point_within_five_steps() {
    let base = Sphere::new(DVec3::new(0.3, -0.2, 0.1), 1.3);
    let solver = Solver::default();
    let (mut converged, mut failures, mut without_reflection) = (0, Vec::new(), 0);
    // Per band of the angle of incidence at Alhazen's point: configurations, converged.
    let bands = [0.0, 30.0, 60.0, 75.0, 90.01];
    let mut by_incidence = [(0u32, 0u32); 4];
    let trials = 2000;
    let mut rng = Rng::new(11, 0, 0);
    for _ in 0..trials {
        let eye =
            base.center + direction(&mut rng) * base.radius * (2.0 + 4.0 * rng.next_f32() as f64);
        let vertex =
            base.center + direction(&mut rng) * base.radius * (1.2 + 3.0 * rng.next_f32() as f64);
        let (e, v) = (eye - base.center, vertex - base.center);
        // Beyond 150° apart the reflection grazes the silhouette.
        if e.angle_between(v).to_degrees() > 150.0 {
            continue;
        }
        let sphere = base.facing(eye, vertex);
        let solution = solver.solve(&sphere, eye, vertex);
        let p = sphere.point(solution.uv);
        let error = reflection_error(p, sphere.normal(solution.uv), eye, vertex);
        let visible = seen_from_outside(p, sphere.normal(solution.uv), eye, vertex);
        let found = error < 1e-4 && visible;
        // How much wider than the angle between E and V the two tangent cones reach (degrees):
        // at most 0, V does not show in the mirror; near 0, the reflection grazes.
        let reach = |x: DVec3| (base.radius / x.length()).acos();
        let margin = (reach(e) + reach(v) - e.angle_between(v)).to_degrees();
        if margin <= 0.0 {
            without_reflection += 1;
            assert!(
                !found,
                "a reflection seen from outside where none exists: {p}"
            );
            continue;
        }
        let exact = alhazen_sphere(&sphere, eye, vertex);
        let normal = (exact - sphere.center).normalize();
        let incidence = normal.angle_between(eye - exact).to_degrees();
        let band = bands.windows(2).position(|b| incidence < b[1]).unwrap_or(3);
        by_incidence[band].0 += 1;
        if found {
            converged += 1;
            by_incidence[band].1 += 1;
            assert!(
                (p - exact).length() < 1e-4 * sphere.radius,
                "converged to {p}, Alhazen's point is {exact}"
            );
        } else {
            failures.push((error, incidence, margin));
        }
    }
    let total = converged + failures.len();
    for (b, (count, ok)) in by_incidence.iter().enumerate() {
        eprintln!(
            "incidence {:.0}-{:.0} deg: {ok} of {count} converged ({:.0}%)",
            bands[b],
            bands[b + 1].floor(),
            100.0 * *ok as f64 / (*count).max(1) as f64
        );
    }
    let grazing = failures.iter().filter(|f| f.2 < 10.0).count();
    eprintln!(
        "{converged} of the {total} configurations where V shows in the mirror converged within \
         5 steps ({without_reflection} more have no reflection); of the {} that did not, \
         {grazing} are within 10 degrees of having none; failures (error rad, incidence deg, \
         margin deg): {failures:?}",
        failures.len()
    );
    assert!(total > 1500, "{total} configurations with a reflection");
    assert!(
        converged as f64 >= 0.99 * total as f64,
        "{converged} of {total}"
    );
}

/// The GPU kernel (f32) and the CPU solver (f64) run the same search: where the CPU converged,
/// the GPU's point is the CPU's to 1e-3 of the radius (f32 rounding moves a step's
/// extrapolation a little; five steps do not amplify it beyond that), and its depth is |P − V|.
#[test]
fn the_gpu_kernel_finds_the_cpu_solvers_points() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let sphere = Sphere::new(DVec3::new(0.3, -0.2, 0.1), 1.3);
    let eye = sphere.center + DVec3::new(0.4, 0.9, 3.5);
    let mut rng = Rng::new(5, 0, 0);
    let vertices: Vec<DVec3> = (0..4000)
        .map(|_| {
            sphere.center
                + direction(&mut rng) * sphere.radius * (1.2 + 3.0 * rng.next_f32() as f64)
        })
        .filter(|v| {
            (v - sphere.center)
                .angle_between(eye - sphere.center)
                .to_degrees()
                < 150.0
        })
        .collect();
    let on_gpu = chambre::preview::reflections::kernel::reflections(
        &context,
        MirrorSurface::Sphere {
            center: sphere.center.as_vec3(),
            radius: sphere.radius as f32,
        },
        eye.as_vec3(),
        &vertices.iter().map(|v| v.as_vec3()).collect::<Vec<_>>(),
        chambre::preview::reflections::kernel::PAPER_STEPS,
    )
    .unwrap();
    let solver = Solver::default();
    let (mut compared, mut agree) = (0, 0);
    for (v, gpu) in vertices.iter().zip(&on_gpu) {
        let facing = sphere.facing(eye, *v);
        let cpu = solver.solve(&facing, eye, *v);
        let p = facing.point(cpu.uv);
        let n = facing.normal(cpu.uv);
        if reflection_error(p, n, eye, *v) > 1e-4 || !seen_from_outside(p, n, eye, *v) {
            continue;
        }
        compared += 1;
        let gp = DVec3::from(glam::Vec3::from(gpu.point));
        if (gp - p).length() < 1e-3 * sphere.radius {
            agree += 1;
            let depth = (v - gp).length();
            assert!((gpu.depth as f64 - depth).abs() < 1e-5 * depth.max(1.0));
        }
    }
    eprintln!("{agree} of {compared} converged CPU points found by the GPU");
    assert_share((agree, compared), 2000, 0.99);
}

/// Of `whole` cases (more than `least`: where the CPU's search converged, where a reflection
/// exists), `part` went right (the GPU found the CPU's point, the search found one): at least
/// the fraction `share` of them.
fn assert_share((part, whole): (u32, u32), least: u32, share: f64) {
    assert!(whole > least, "{whole}");
    assert!(part as f64 >= share * whole as f64, "{part} of {whole}");
}

/// The `fermat` kernel marks each vertex's reflection shown or not as the CPU twin
/// `fermat::drawn_in_preview` judges the kernel's own point, and the preview's cull
/// (`fermat_cull`) lists exactly the reflected triangles whose three vertices' reflections are
/// shown and that do not lie on the searched mirror itself, unless the search draws its own
/// mirror's triangles (self-reflections) and they stand clear of their points: a floor of 1,800
/// triangles under a sphere, one of the teapot's patches and a torus's inner half, a seventh of
/// them tagged as lying on the mirror (left out by the sphere, which cannot see itself; kept by
/// the patch and the torus, with self-reflections on, where `fermat::self_reflection_clear`
/// says), a seventh on another mirror (kept). A patch's search and a torus half's list only
/// the triangles anchored on their part of the mirror (`MirrorSurface::anchors`), some across
/// its edge. Triangles with a vertex
/// within 2% of the tolerance, or within 1e-4 of being unseen, where the kernel's f32 and the
/// twin's f64 may judge differently, are not compared.
#[test]
fn the_cull_lists_the_triangles_whose_reflections_show() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let (_, patches) = teapot();
    let cases = [
        (
            "sphere",
            MirrorSurface::Sphere {
                center: glam::Vec3::new(0.0, 0.65, 0.0),
                radius: 0.6,
            },
            DVec3::new(0.0, 1.6, 3.2),
            false,
        ),
        (
            "teapot patch",
            MirrorSurface::Patch(patches[2]),
            DVec3::new(0.3, 1.8, 3.5),
            true,
        ),
        (
            "torus's inner half",
            MirrorSurface::Torus(TorusSearch {
                torus: Torus::new(DVec3::new(0.0, 0.25, 0.0), 0.55, 0.2),
                half: TorusHalf::Inner,
            }),
            DVec3::new(0.0, 2.5, 0.8),
            true,
        ),
    ];
    // A 31 x 31 grid of floor points from -2 to 2, two triangles per cell.
    let n = 31;
    let vertices: Vec<glam::Vec3> = (0..n * n)
        .map(|k| {
            let at = |i: u32| -2.0 + 4.0 * i as f32 / (n - 1) as f32;
            glam::Vec3::new(at(k % n), 0.0, at(k / n))
        })
        .collect();
    let mut triangles = Vec::new();
    for row in 0..n - 1 {
        for column in 0..n - 1 {
            let k = row * n + column;
            for corners in [[k, k + 1, k + n], [k + 1, k + n + 1, k + n]] {
                // Tags: 0 on no mirror, 1 on the mirror searched, 2 on another.
                let tag = match triangles.len() % 7 {
                    3 => 1,
                    5 => 2,
                    _ => 0,
                };
                triangles.push([corners[0], corners[1], corners[2], tag]);
            }
        }
    }
    let tolerance = f64::from(chambre::layout::REFLECTION_TOLERANCE);
    for (name, surface, eye, sees_itself) in cases {
        let (points, shown) = chambre::preview::reflections::kernel::shown_triangles(
            &context,
            surface,
            (eye.as_vec3(), 1, sees_itself),
            &vertices,
            &triangles,
            chambre::preview::PreviewOptions::default().steps,
        )
        .unwrap();
        // Per vertex: drawn by the twin's judgement, or too close to call.
        let judged: Vec<Option<bool>> = vertices
            .iter()
            .zip(&points)
            .map(|(v, r)| {
                let (v, p) = (v.as_dvec3(), glam::Vec3::from(r.point).as_dvec3());
                let normal = glam::Vec3::from(r.normal).as_dvec3();
                let unseen = |x: DVec3| (x - p).normalize().dot(normal).abs() < 1e-4;
                let error = reflection_error(p, normal, eye, v);
                let close = normal != DVec3::ZERO
                    && (unseen(eye) || unseen(v) || (error / tolerance - 1.0).abs() < 0.02);
                (!close).then(|| drawn_in_preview(p, normal, eye, v))
            })
            .collect();
        // The kernel's own mark on each vertex is the twin's judgement.
        for (k, (judgement, r)) in judged.iter().zip(&points).enumerate() {
            if let Some(drawn) = judgement {
                assert_eq!(r.shown, *drawn as u32, "{name}: vertex {k}");
            }
        }
        let (mut compared, mut own_shown) = (0, 0);
        let mut expected = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            let corners: Option<Vec<bool>> = tri[..3].iter().map(|&k| judged[k as usize]).collect();
            let Some(corners) = corners else {
                continue;
            };
            compared += 1;
            let drawn = corners.iter().all(|&d| d);
            let own = tri[3] == 1;
            // A patch draws a triangle with a corner on it (the others may be in its seam).
            let uvs = [0, 1, 2].map(|c| glam::Vec2::from(points[tri[c] as usize].uv).as_dvec2());
            let drawn = drawn && surface.anchors(uvs);
            own_shown += (drawn && own) as u32;
            let clear = tri[..3].iter().all(|&k| {
                let p = glam::Vec3::from(points[k as usize].point).as_dvec3();
                self_reflection_clear(p, eye, vertices[k as usize].as_dvec3())
            });
            if drawn && (!own || (sees_itself && clear)) {
                expected.push(t as u32);
            }
        }
        let listed: Vec<u32> = shown
            .iter()
            .copied()
            .filter(|&t| {
                triangles[t as usize][..3]
                    .iter()
                    .all(|&k| judged[k as usize].is_some())
            })
            .collect();
        eprintln!(
            "{name}: {} triangles listed, {} of them compared; {compared} compared, {own_shown} \
             on the mirror itself whose reflections show",
            shown.len(),
            listed.len()
        );
        assert!(compared > 1700, "{name}: {compared} compared");
        assert!(expected.len() > 50, "{name}: {} shown", expected.len());
        // Some triangles drawn, and some not: what the cull removes.
        assert!(
            compared - expected.len() > 100,
            "{name}: {} shown",
            expected.len()
        );
        assert!(own_shown > 5, "{name}: {own_shown}");
        // The patch draws triangles across its seam, a corner on its continuation; the torus's
        // half those across the circles where it meets the other half.
        let on_its_part = |uv: glam::Vec2| match surface {
            MirrorSurface::Patch(_) => on_patch(uv.as_dvec2()),
            MirrorSurface::Torus(search) => on_torus_half(uv.as_dvec2(), search.half),
            _ => true,
        };
        let across = expected
            .iter()
            .filter(|&&t| {
                triangles[t as usize][..3]
                    .iter()
                    .any(|&k| !on_its_part(glam::Vec2::from(points[k as usize].uv)))
            })
            .count();
        if !matches!(surface, MirrorSurface::Sphere { .. }) {
            eprintln!("{name}: {across} triangles drawn across the seam");
            assert!(across > 0, "{name}: {across}");
        }
        assert_eq!(listed, expected, "{name}");
    }
}

/// The preview solves and culls the teapot's 32 patches in one dispatch, or in batches (5 a
/// dispatch, the last batch 2; or one a dispatch): the same image to the pixel and the same
/// triangles drawn, and an image with reflections in it (hundreds of pixels differ from the
/// teapot without its mirror term) drawn from a fraction of the reflected triangles.
#[test]
fn batching_the_searches_changes_no_pixel() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fermat_teapot.toml");
    let draw = |extra: &[&str], searches_per_dispatch| {
        let overrides: Vec<String> = ["render.width=160", "render.height=120"]
            .iter()
            .chain(extra)
            .map(|o| o.to_string())
            .collect();
        let scene = chambre::scene::Scene::load(&path, &overrides).unwrap();
        let options = chambre::preview::PreviewOptions {
            subdivision: Some(2),
            searches_per_dispatch,
            ..Default::default()
        };
        let flat = chambre::pack::flatten(&scene);
        chambre::preview::draw_with(&context, &scene, &flat, 1, options).unwrap()
    };
    let all = draw(&[], None);
    let no_mirror = draw(&["materials[0].mirror=[0.0,0.0,0.0]"], None);
    let reflected = common::differing_pixels(&all.image, &no_mirror.image);
    eprintln!("{reflected} pixels show reflections");
    assert!(reflected > 300, "{reflected} pixels show reflections");
    // The cull drew some of the 32 searches' reflected triangles, not all.
    assert!(
        all.reflected_drawn > 0 && all.reflected_drawn < all.reflected_triangles / 4,
        "{} of {} drawn",
        all.reflected_drawn,
        all.reflected_triangles
    );
    for batch in [5, 1] {
        let batched = draw(&[], Some(batch));
        assert!(
            all.image.pixels == batched.image.pixels,
            "{batch} a dispatch"
        );
        assert_eq!(
            all.reflected_drawn, batched.reflected_drawn,
            "{batch} a dispatch"
        );
    }
}

#[test]
fn alhazens_point_obeys_the_law_of_reflection() {
    let sphere = Sphere::new(DVec3::ZERO, 1.0);
    let (eye, vertex) = (DVec3::new(0.0, 0.5, 4.0), DVec3::new(3.0, -1.0, 1.0));
    let p = alhazen_sphere(&sphere, eye, vertex);
    assert!((p.length() - 1.0).abs() < 1e-12);
    assert!(reflection_error(p, p, eye, vertex) < 1e-9);
    // Symmetric case: E and V mirror images through the x axis; P on it.
    let p = alhazen_sphere(
        &sphere,
        DVec3::new(3.0, 1.0, 0.0),
        DVec3::new(3.0, -1.0, 0.0),
    );
    assert!((p - DVec3::X).length() < 1e-12, "{p}");
}

/// The Fermat comparison (`chambre bench fermat`) on `scene`, made small, at subdivisions 1
/// and 4 (4 cuts the scenes' 4x4 floor 16x16, as the seed's).
fn compare_small(context: &chambre::gpu::GpuContext, scene: &str) -> FermatReport {
    compare_small_with(context, scene, &[])
}

/// With the eye inside the mirror sphere nothing reflects (E sees no point from outside): the
/// comparison says so, no feature drawn and no displacement figures, rather than NaN or a
/// corner error of 0; with the mirror out of the frame, no FLIP over its pixels either.
#[test]
fn a_comparison_with_nothing_drawn_reports_no_figures() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let inside = [
        "camera.position=[0.0, 0.5, 0.1]",
        "camera.look_at=[0.0, 0.5, -1.0]",
    ];
    let report = compare_small_with(&context, "scenes/fermat_sphere.toml", &inside);
    for row in &report.rows {
        assert_eq!((row.drawn, row.reflected_drawn), (0, 0), "{row:?}");
        assert_eq!(row.corner_max_px, None, "{row:?}");
        assert_eq!(row.displacement_median_px, None, "{row:?}");
        assert_eq!(row.displacement_max_px, None, "{row:?}");
    }
    let table = report.to_markdown();
    assert!(!table.contains("NaN") && table.contains("| - |"), "{table}");
    // Looking away, the mirror has no pixel to take FLIP over.
    let away = ["camera.look_at=[0.0, 1.6, 12.0]"];
    let report = compare_small_with(&context, "scenes/fermat_sphere.toml", &away);
    for row in &report.rows {
        assert_eq!((row.features, row.flip_reflector), (0, None), "{row:?}");
    }
    assert!(!report.to_markdown().contains("NaN"));
}

/// `compare_small` with the scene's fields overridden as `-D` does.
fn compare_small_with(
    context: &chambre::gpu::GpuContext,
    scene: &str,
    extra: &[&str],
) -> FermatReport {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let overrides: Vec<String> = ["render.width=160", "render.height=120"]
        .iter()
        .chain(extra)
        .map(|o| o.to_string())
        .collect();
    let config = FermatConfig {
        scene: &scene,
        overrides: &overrides,
        subdivisions: &[1, 4],
        steps: chambre::preview::PreviewOptions::default().steps,
        runs: 1,
        frames: 2,
        reference_spp: 32,
        searches_per_dispatch: None,
        tolerance_px: chambre::preview::DEFAULT_TOLERANCE_PX,
        self_reflections: None,
    };
    let report = chambre::bench::fermat::run(&config, context).unwrap();
    eprintln!("{}", report.to_markdown());
    report
}

/// The raster preview's Fermat reflections against the ray tracer on the sphere scene:
/// corners (vertices) land where Alhazen's f64 points put them; points between them move as
/// the seed says (straight reflected edges) and come within a pixel once the floor is cut
/// 16x16; FLIP over the sphere's pixels falls with the subdivision; and the report's JSON
/// carries its figures.
#[test]
fn preview_reflections_land_where_the_ray_tracer_puts_them() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let report = compare_small(&context, "scenes/fermat_sphere.toml");
    let [coarse, fine] = [&report.rows[0], &report.rows[1]];
    for row in [coarse, fine] {
        assert!(row.features > 300, "{row:?}");
        assert!(row.corner_max_px.is_some_and(|d| d < 0.05), "{row:?}");
        assert!(row.preview_ms.median > 0.0);
        // One round: one ray-traced frame over the median of the preview frames after it.
        assert!(
            row.speedup.median > 0.0 && row.speedup.min == row.speedup.max,
            "{row:?}"
        );
        // Each stage of the frame timed alone.
        let stages = row.stages;
        for ms in [
            stages.solve_ms,
            stages.cull_ms,
            stages.main_ms,
            stages.reflect_ms,
        ] {
            assert!(ms > 0.0 && ms.is_finite(), "{row:?}");
        }
    }
    assert!(fine.drawn as f64 >= 0.9 * fine.features as f64, "{fine:?}");
    assert!(
        fine.displacement_p99_px.is_some_and(|d| d < 1.0),
        "{fine:?}"
    );
    assert!(
        fine.displacement_median_px.unwrap() < coarse.displacement_median_px.unwrap(),
        "{report:?}"
    );
    assert!(
        coarse.displacement_max_px.is_some_and(|d| d > 1.0),
        "{coarse:?}"
    );
    assert!(
        fine.flip_reflector.unwrap() < coarse.flip_reflector.unwrap(),
        "{report:?}"
    );
    assert!(fine.flip_reflector.is_some_and(|f| f < 0.08), "{fine:?}");
    assert!(report.ray_traced_gpu_ms.median > 0.0 && report.ray_traced_cpu_ms.median > 0.0);
    // Reading the image back comes after the passes finish.
    assert!(report.ray_traced_gpu_read_ms.min >= report.ray_traced_gpu_ms.min);
    let json = serde_json::to_value(&report).unwrap();
    for field in ["ray_traced_gpu_ms", "reference_spp", "rows"] {
        assert!(json.get(field).is_some(), "{field}");
    }
    assert_eq!(json["rows"][1]["subdivision"], 4);
    assert!(json["rows"][1]["speedup"]["median"].as_f64().is_some());
    assert!(json["rows"][1]["stages"]["solve_ms"].as_f64().is_some());
}

/// The same on the torus, ellipsoid and cylinder scenes (each intersected exactly): the
/// features the preview draws land where the converged f64 search puts them, corners exactly,
/// points between within a pixel at 16x16, and FLIP over the mirror's pixels falls with the
/// subdivision.
#[test]
fn preview_reflections_on_a_torus_an_ellipsoid_and_a_cylinder_land_where_the_ray_tracer_puts_them()
{
    let Some(context) = common::gpu_context() else {
        return;
    };
    for mirror in ["torus", "ellipsoid", "cylinder"] {
        let report = compare_small(&context, &format!("scenes/fermat_{mirror}.toml"));
        assert_reflections_land(mirror, &report, 300, 0.85);
    }
}

/// The curved-mirror scenes' checks: both subdivisions have more than `features` features,
/// their corners exact; at 16x16 at least `drawn` of them are drawn, 99% within a pixel, and
/// FLIP over the mirror's pixels is lower than at 4x4.
fn assert_reflections_land(mirror: &str, report: &FermatReport, features: usize, drawn: f64) {
    let [coarse, fine] = [&report.rows[0], &report.rows[1]];
    for row in [coarse, fine] {
        assert!(row.features > features, "{mirror}: {row:?}");
        assert!(
            row.corner_max_px.is_some_and(|d| d < 0.05),
            "{mirror}: {row:?}"
        );
    }
    assert!(
        fine.drawn as f64 >= drawn * fine.features as f64,
        "{mirror}: {fine:?}"
    );
    assert!(
        fine.displacement_p99_px.is_some_and(|d| d < 1.0),
        "{mirror}: {fine:?}"
    );
    assert!(
        fine.flip_reflector.unwrap() < coarse.flip_reflector.unwrap(),
        "{mirror}: {report:?}"
    );
}

/// The same with the torus, ellipsoid and cylinder turned (`rotate`), each raised clear of the
/// floor: the preview's mesh, its Fermat kernel in the shape's own
/// frame and the ray tracer's exact intersection all turn alike.
#[test]
fn preview_reflections_on_turned_mirrors_land_where_the_ray_tracer_puts_them() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    for (mirror, turn) in [
        (
            "torus",
            [
                "shapes[0].center=[0.0, 0.6, 0.0]",
                "shapes[0].rotate=[30.0, 0.0, 20.0]",
            ],
        ),
        (
            "ellipsoid",
            [
                "shapes[0].center=[0.0, 0.85, 0.0]",
                "shapes[0].rotate=[0.0, 35.0, 25.0]",
            ],
        ),
        (
            "cylinder",
            [
                "shapes[0].center=[0.0, 0.3, 0.0]",
                "shapes[0].rotate=[20.0, 0.0, 25.0]",
            ],
        ),
    ] {
        let report = compare_small_with(&context, &format!("scenes/fermat_{mirror}.toml"), &turn);
        assert_reflections_land(mirror, &report, 200, 0.8);
    }
}

/// The same on the teapot scene, whose 32 patches are searched one by one: the features drawn
/// land where the converged f64 search puts them on their patch, corners exactly, points
/// between within a pixel at 16x16 at this size; FLIP falls with the subdivision. At 16x16
/// more than 80% of the features are drawn (87%; 72% before triangles across the patches'
/// seams were drawn, `layout::PATCH_SEAM`).
#[test]
fn preview_reflections_on_a_teapot_land_where_the_ray_tracer_puts_them() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let report = compare_small(&context, "scenes/fermat_teapot.toml");
    let [coarse, fine] = [&report.rows[0], &report.rows[1]];
    for row in [coarse, fine] {
        assert!(row.features > 300, "{row:?}");
        assert!(row.corner_max_px.is_some_and(|d| d < 0.05), "{row:?}");
    }
    assert!(fine.drawn as f64 >= 0.8 * fine.features as f64, "{fine:?}");
    assert!(fine.drawn > coarse.drawn, "{report:?}");
    assert!(
        fine.displacement_p99_px.is_some_and(|d| d < 1.0),
        "{fine:?}"
    );
    assert!(
        fine.flip_reflector.unwrap() < coarse.flip_reflector.unwrap(),
        "{report:?}"
    );
}

/// On a torus, an ellipsoid (solved in its facing frame) and a cylinder (its reflections
/// within its height) too, each turned (the kernel searches in the shape's own frame, the CPU
/// in the world's), the GPU kernel (f32) runs the CPU solver's search: where the CPU found a
/// reflection seen from outside within the seed's steps, the GPU's point is the CPU's to 1e-3
/// (the surfaces are about 1 unit across), its normal to 1e-2. Both halves of the torus are
/// searched, and its own points (found by its inner half's search, from across the hole) are
/// among the vertices.
#[test]
fn the_gpu_kernel_finds_the_cpu_solvers_points_on_a_torus_an_ellipsoid_and_a_cylinder() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let center = DVec3::new(0.2, 0.3, -0.1);
    let orientation = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
    let ellipsoid = Ellipsoid {
        orientation,
        ..Ellipsoid::new(center, DVec3::new(0.8, 0.45, 0.5))
    };
    let cylinder = Cylinder {
        orientation,
        ..Cylinder::new(center, 0.45)
    };
    let height = 1.0;
    let torus = Torus {
        orientation,
        ..Torus::new(center, 0.6, 0.2)
    };
    let eye = center + DVec3::new(0.3, 1.1, 2.8);
    let around = points_around(center, 3000, 29);
    let first_own = around.len();
    let vertices: Vec<DVec3> = around.into_iter().chain(own_points(&torus)).collect();
    let solver = Solver::default();
    let surfaces = [
        MirrorSurface::Torus(TorusSearch {
            torus,
            half: TorusHalf::Outer,
        }),
        MirrorSurface::Torus(TorusSearch {
            torus,
            half: TorusHalf::Inner,
        }),
        MirrorSurface::Ellipsoid(ellipsoid),
        MirrorSurface::Cylinder { cylinder, height },
    ];
    for surface in surfaces {
        let on_gpu = chambre::preview::reflections::kernel::reflections(
            &context,
            surface,
            eye.as_vec3(),
            &vertices.iter().map(|v| v.as_vec3()).collect::<Vec<_>>(),
            chambre::preview::reflections::kernel::PAPER_STEPS,
        )
        .unwrap();
        let (mut compared, mut agree, mut own_agree) = (0, 0, 0);
        for (k, (v, gpu)) in vertices.iter().zip(&on_gpu).enumerate() {
            let (p, n) = match surface {
                MirrorSurface::Torus(t) => {
                    let uv = solver.solve(&t, eye, *v).uv;
                    (t.point(uv), t.outward_normal(uv))
                }
                MirrorSurface::Ellipsoid(e) => {
                    let e = e.facing(eye, *v);
                    let uv = solver.solve(&e, eye, *v).uv;
                    (e.point(uv), e.outward_normal(uv))
                }
                _ => {
                    let uv = solver.solve(&cylinder, eye, *v).uv;
                    if !on_cylinder(uv.y, height) {
                        continue;
                    }
                    (cylinder.point(uv), cylinder.outward_normal(uv))
                }
            };
            if reflection_error(p, n, eye, *v) > 1e-4 || !seen_from_outside(p, n, eye, *v) {
                continue;
            }
            compared += 1;
            let gp = DVec3::from(glam::Vec3::from(gpu.point));
            let gn = DVec3::from(glam::Vec3::from(gpu.normal));
            let agrees = (gp - p).length() < 1e-3 && (gn - n).length() < 1e-2;
            agree += agrees as u32;
            let torus_own = matches!(surface, MirrorSurface::Torus(_)) && k >= first_own;
            own_agree += (agrees && torus_own) as u32;
        }
        eprintln!(
            "{surface:?}: {agree} of {compared} converged CPU points found by the GPU \
             ({own_agree} of them the torus's own points)"
        );
        if let MirrorSurface::Torus(TorusSearch {
            half: TorusHalf::Inner,
            ..
        }) = surface
        {
            assert!(own_agree > 100, "{own_agree}");
        }
        assert_share((agree, compared), 500, 0.99);
    }
}

/// Turning a reflector and the eye and vertices with it turns its reflections: the search on a
/// turned torus, ellipsoid or cylinder takes the same steps as on the unturned one (its
/// parameters are the own frame's), so where the unturned search converged (the law of
/// reflection to 1e-4 rad) the turned one ends on its point turned, to rounding. (A search
/// that did not converge may run off to parameters in the thousands, where rounding decides.)
#[test]
fn turning_a_reflector_with_the_scene_turns_its_reflections() {
    let center = DVec3::new(0.2, 0.3, -0.1);
    let orientation = DQuat::from_axis_angle(DVec3::new(-0.3, 0.4, 1.0).normalize(), 2.1);
    let turn = |x: DVec3| center + orientation * (x - center);
    let ellipsoid = Ellipsoid::new(center, DVec3::new(0.8, 0.45, 0.5));
    let cylinder = Cylinder::new(center, 0.45);
    let torus = Torus::new(center, 0.6, 0.2);
    let eye = center + DVec3::new(0.3, 1.1, 2.8);
    let vertices = points_around(center, 2000, 31);
    let solver = Solver::default();
    let mut worst: f64 = 0.0;
    let mut compared = [0; 3];
    for v in &vertices {
        let (e, turned_v) = (turn(eye), turn(*v));
        let (plain, turned) = ((eye, *v), (e, turned_v));
        let pairs = [
            both(
                &solver,
                &ellipsoid.facing(eye, *v),
                &Ellipsoid {
                    orientation,
                    ..ellipsoid
                }
                .facing(e, turned_v),
                plain,
                turned,
            ),
            both(
                &solver,
                &cylinder,
                &Cylinder {
                    orientation,
                    ..cylinder
                },
                plain,
                turned,
            ),
            both(
                &solver,
                &torus,
                &Torus {
                    orientation,
                    ..torus
                },
                plain,
                turned,
            ),
        ];
        for (k, (plain, normal, turned)) in pairs.into_iter().enumerate() {
            if reflection_error(plain, normal, eye, *v) < 1e-4 {
                compared[k] += 1;
                worst = worst.max((turn(plain) - turned).length());
            }
        }
    }
    eprintln!(
        "converged (ellipsoid, cylinder, torus): {compared:?}; largest distance between a turned \
         search's point and the unturned one's, turned: {worst:e}"
    );
    assert!(compared.iter().all(|&c| c > 1000), "{compared:?}");
    assert!(worst < 1e-9, "{worst:e}");
}

/// Where the search on `plain` ends for (eye, vertex), with the normal there, and where it ends
/// on `turned` for the turned eye and vertex.
fn both(
    solver: &Solver,
    plain: &impl Reflector,
    turned: &impl Reflector,
    (eye, vertex): (DVec3, DVec3),
    (turned_eye, turned_vertex): (DVec3, DVec3),
) -> (DVec3, DVec3, DVec3) {
    let uv = solver.solve(plain, eye, vertex).uv;
    let turned_uv = solver.solve(turned, turned_eye, turned_vertex).uv;
    (
        plain.point(uv),
        plain.outward_normal(uv),
        turned.point(turned_uv),
    )
}

/// The sample teapot, its patches as the scene places them (Y-up, scaled, oriented outward).
fn teapot() -> (chambre::scene::Scene, Vec<BezierPatch>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fermat_teapot.toml");
    let scene = chambre::scene::Scene::load(&path, &[]).unwrap();
    let patches = match &scene.surfaces[0].surface {
        Surface::Patches(p) => p.clone(),
        other => panic!("{other:?}"),
    };
    (scene, patches)
}

/// The teapot's patches all face out once oriented (the preview's test of a reflection seen
/// from outside needs it): rays from above and around meet its traced mesh where the
/// patches' normals, interpolated, face the ray's origin, except the 1% that pass between the
/// lid and the body and meet the bottom from inside (rays from below are left out: they would
/// hit the bottom only).
#[test]
fn the_teapots_patches_face_outward() {
    let (scene, patches) = teapot();
    assert_eq!(patches.len(), 32);
    let flat = chambre::pack::flatten(&scene);
    let on_teapot: std::collections::HashSet<u32> =
        flat.surfaces[0].prims.iter().copied().collect();
    let centre = DVec3::new(0.0, 0.55, 0.0);
    let bottom = 0.05;
    let mut rng = Rng::new(3, 0, 0);
    let (mut hits, mut outward) = (0, 0);
    for _ in 0..2000 {
        let mut d = direction(&mut rng);
        d.y = d.y.abs() + 0.3;
        let origin = centre + 4.0 * d.normalize();
        let target = centre + 0.3 * direction(&mut rng);
        let dir = (target - origin).normalize();
        let ray = chambre::accel::intersect::RayQuery::new(origin.as_vec3(), dir.as_vec3());
        let Some((prim, hit)) =
            chambre::accel::traverse::closest_hit::<{ chambre::layout::FEATURES_ALL }>(
                flat.primitives(),
                &ray,
                chambre::layout::NONE,
                chambre::layout::T_FAR,
            )
        else {
            continue;
        };
        if !on_teapot.contains(&prim) {
            continue;
        }
        hits += 1;
        let n = flat.normals[flat.prims[prim as usize].normals as usize].n;
        let corner =
            |k: usize| DVec3::new(n[3 * k] as f64, n[3 * k + 1] as f64, n[3 * k + 2] as f64);
        let (b1, b2) = (hit.b1 as f64, hit.b2 as f64);
        let normal = corner(0) * (1.0 - b1 - b2) + corner(1) * b1 + corner(2) * b2;
        outward += (normal.dot(-dir) > 0.0) as u32;
        let at = origin + dir * hit.t as f64;
        // The lid does not seal the body: a ray between them meets the bottom from inside.
        assert!(
            normal.dot(-dir) > 0.0 || at.y < bottom + 0.03,
            "a hit at {at} sees a patch from behind"
        );
    }
    eprintln!("{outward} of {hits} hits on the teapot face the ray");
    assert!(hits > 1000, "{hits}");
    assert!(outward as f64 >= 0.98 * hits as f64, "{outward} of {hits}");
}

/// On a Bézier patch too (each of the teapot's, from one eye), the GPU kernel runs the CPU
/// solver's search: where the CPU found a reflection on the patch, seen from outside, within
/// the seed's steps, the GPU's point is the CPU's to 1e-3 of the teapot's size, its normal to
/// 1e-2; where the CPU's search leaves the patch, the GPU's normal is zero (no reflection).
#[test]
fn the_gpu_kernel_finds_the_cpu_solvers_points_on_bezier_patches() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let (_, patches) = teapot();
    let eye = DVec3::new(0.3, 1.4, 3.0);
    let mut rng = Rng::new(23, 0, 0);
    let vertices: Vec<DVec3> = (0..600)
        .map(|_| {
            let [a, b] = rng.next_2d();
            DVec3::new(4.0 * a as f64 - 2.0, 0.0, 4.0 * b as f64 - 2.0)
        })
        .collect();
    let solver = Solver::default();
    let (mut compared, mut agree, mut off, mut off_agree) = (0, 0, 0, 0);
    for patch in &patches {
        let on_gpu = chambre::preview::reflections::kernel::reflections(
            &context,
            MirrorSurface::Patch(*patch),
            eye.as_vec3(),
            &vertices.iter().map(|v| v.as_vec3()).collect::<Vec<_>>(),
            chambre::preview::reflections::kernel::PAPER_STEPS,
        )
        .unwrap();
        for (v, gpu) in vertices.iter().zip(&on_gpu) {
            let s = solver.solve(patch, eye, *v);
            let gn = DVec3::from(glam::Vec3::from(gpu.normal));
            if s.left_surface || !on_patch(s.uv) {
                // Far off the square and its seam band; near their edges f32 and f64 may
                // disagree.
                let (uv, beyond) = (s.uv, f64::from(chambre::layout::PATCH_SEAM) + 0.1);
                if uv.min_element() < -beyond || uv.max_element() > 1.0 + beyond {
                    off += 1;
                    off_agree += (gn == DVec3::ZERO) as u32;
                }
                continue;
            }
            let (p, n) = (patch.point(s.uv), patch.outward_normal(s.uv));
            if reflection_error(p, n, eye, *v) > 1e-4 || !seen_from_outside(p, n, eye, *v) {
                continue;
            }
            compared += 1;
            let gp = DVec3::from(glam::Vec3::from(gpu.point));
            agree += ((gp - p).length() < 1e-3 && (gn - n).length() < 1e-2) as u32;
        }
    }
    eprintln!(
        "{agree} of {compared} converged CPU points on the patches found by the GPU; {off_agree} \
         of {off} searches that left their patch have no GPU reflection either"
    );
    assert_share((agree, compared), 300, 0.98);
    assert!(
        off > 1000 && off_agree as f64 >= 0.98 * off as f64,
        "{off_agree} of {off}"
    );
}

/// A teapot's own points (its vertices, reflected in its other patches with self-reflections
/// on) search again where the seed's corners find no reflection the preview shows, from the
/// patch's point that fails the law of reflection least on a 4 x 4 grid
/// (`fermat::solve_on_patch`): a point of the mirror sees its other patches from close by,
/// where the segment V -> O seldom crosses them near the reflection. Over a grid of own points
/// (3 x 3 on each patch) and each other patch, of the pairs with a reflection on the patch
/// (found by either search, or by 40-step searches from 16 starts), the preview's 12 steps
/// find one for 80% or more that way (1,050 of 1,102), against about two thirds from the
/// seed's corners alone (699).
#[test]
fn a_teapots_own_points_search_again_from_where_the_law_fails_least() {
    let (_, patches) = teapot();
    let eye = DVec3::new(0.0, 1.6, 3.2);
    let thorough = Solver {
        max_steps: 40,
        min_size: 1e-12,
    };
    let shows = |patch: &BezierPatch, uv: glam::DVec2, v: DVec3| {
        on_patch(uv) && drawn_in_preview(patch.point(uv), patch.outward_normal(uv), eye, v)
    };
    let (mut pairs, mut seed, mut again) = (0, 0, 0);
    for (j, own) in patches.iter().enumerate() {
        for k in 0..9 {
            let uv = glam::UVec2::new(k % 3, k / 3).as_dvec2() / 3.0 + 1.0 / 6.0;
            let v = own.point(uv);
            for patch in patches
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != j)
                .map(|(_, p)| p)
            {
                // The seed's corners or the search again find it, or else a start of 16.
                let seed_uv = preview_solver().solve(patch, eye, v).uv;
                let again_uv = solve_on_patch(&preview_solver(), patch, eye, v).uv;
                let (by_seed, by_again) = (shows(patch, seed_uv, v), shows(patch, again_uv, v));
                let has_one = by_seed
                    || by_again
                    || (0..16).any(|s| {
                        let a = glam::UVec2::new(s % 4, s / 4).as_dvec2() / 3.0;
                        let start = StartedFrom(*patch, a, a + glam::DVec2::new(0.1, 0.05));
                        let uv = thorough.solve(&start, eye, v).uv;
                        let (p, n) = (patch.point(uv), patch.outward_normal(uv));
                        on_patch(uv)
                            && reflection_error(p, n, eye, v) < 1e-6
                            && seen_from_outside(p, n, eye, v)
                    });
                if has_one {
                    pairs += 1;
                    seed += by_seed as u32;
                    again += by_again as u32;
                }
            }
        }
    }
    eprintln!(
        "a teapot's own points: {pairs} pairs with a reflection on another patch; the seed's \
         corners find {seed}, searching again {again}"
    );
    assert_share((again, pairs), 1000, 0.8);
    assert!(again as f64 > 1.15 * seed as f64, "{again} against {seed}");
}

/// The kernel searches a teapot's own points again as the CPU does (`fermat::solve_on_patch`):
/// over a grid of own points and every other patch, where the CPU's search (its first or its
/// second) ends on a reflection the preview shows, the GPU's point is the CPU's to 1e-3 of the
/// teapot's size for 98% or more.
#[test]
fn the_gpu_kernel_searches_a_teapots_own_points_again_as_the_cpu_does() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let (_, patches) = teapot();
    let eye = DVec3::new(0.0, 1.6, 3.2);
    let steps = chambre::preview::PreviewOptions::default().steps;
    let solver = preview_solver();
    let (mut compared, mut agree) = (0, 0);
    for (j, patch) in patches.iter().enumerate() {
        // A 4 x 4 grid of points of each other patch.
        let others = patches.iter().enumerate().filter(|(i, _)| *i != j);
        let vertices: Vec<glam::Vec3> = others
            .flat_map(|(_, own)| {
                (0..16).map(|k| {
                    let uv = glam::UVec2::new(k % 4, k / 4).as_dvec2() / 4.0 + 0.125;
                    own.point(uv).as_vec3()
                })
            })
            .collect();
        let on_gpu = chambre::preview::reflections::kernel::own_reflections(
            &context,
            MirrorSurface::Patch(*patch),
            eye.as_vec3(),
            &vertices,
            steps,
        )
        .unwrap();
        for (v, gpu) in vertices.iter().zip(&on_gpu) {
            let v = v.as_dvec3();
            let uv = solve_on_patch(&solver, patch, eye, v).uv;
            let (p, n) = (patch.point(uv), patch.outward_normal(uv));
            if !on_patch(uv)
                || reflection_error(p, n, eye, v) > 1e-4
                || !seen_from_outside(p, n, eye, v)
            {
                continue;
            }
            compared += 1;
            let gp = DVec3::from(glam::Vec3::from(gpu.point));
            agree += (gp.distance(p) < 1e-3) as u32;
        }
    }
    eprintln!("a teapot's own points: {agree} of {compared} reflections the same on both");
    assert_share((agree, compared), 1000, 0.98);
}

/// Two mirror spheres: the preview shows each in the other, once. The right one is a red
/// mirror; where the left one is a mirror too it shows the red sphere in it (red pixels beyond
/// those of the red sphere itself), about as many as the ray tracer shows with two bounces.
#[test]
fn mirrors_reflect_each_other_in_the_preview() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fermat_sphere.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let one_sphere = "center = [0.0, 0.65, 0.0]\nradius = 0.6\nmaterial = \"mirror\"";
    assert!(text.contains(one_sphere));
    let two = |left: &str| {
        let spheres = format!(
            "center = [-0.55, 0.5, 0.0]\nradius = 0.45\nmaterial = \"{left}\"\n\n\
             [[shapes]]\ntype = \"sphere\"\ncenter = [0.55, 0.5, 0.0]\nradius = 0.45\n\
             material = \"red_mirror\"\n\n[[materials]]\nname = \"red_mirror\"\n\
             model = \"lambert\"\ndiffuse = [0.6, 0.05, 0.05]\nmirror = [0.3, 0.3, 0.3]"
        );
        let text = text
            .replace(one_sphere, &spheres)
            .replace("width = 320", "width = 160")
            .replace("height = 240", "height = 120")
            .replace("max_depth = 1", "max_depth = 2");
        chambre::scene::Scene::from_str(&path, &text, &[]).unwrap()
    };
    let red = |image: &chambre::render::Image| {
        image
            .pixels
            .iter()
            .filter(|p| p.x > 0.15 && p.x > 1.8 * p.y.max(p.z))
            .count()
    };
    let preview = |scene: &chambre::scene::Scene| {
        let flat = chambre::pack::flatten(scene);
        let options = chambre::preview::PreviewOptions::default();
        chambre::preview::draw_with(&context, scene, &flat, 1, options)
            .unwrap()
            .image
    };
    let (mirror, diffuse) = (two("mirror"), two("dark"));
    let with = red(&preview(&mirror));
    let without = red(&preview(&diffuse));
    let ray_traced = red(&common::render_cpu(&chambre::pack::flatten(&mirror)))
        - red(&common::render_cpu(&chambre::pack::flatten(&diffuse)));
    eprintln!(
        "red pixels: preview {with} with the left sphere a mirror, {without} without; the ray \
         tracer shows {ray_traced} more with it"
    );
    let shown = with as f64 - without as f64;
    assert!(ray_traced > 20, "{ray_traced}");
    assert!(
        (shown - ray_traced as f64).abs() < 0.35 * ray_traced as f64,
        "the preview shows {shown} red pixels in the left mirror, the ray tracer {ray_traced}"
    );
}

/// A mirror seen in a curved mirror where the scene's paths bounce once (max_depth 1) ends the
/// path there, as the ray tracer's does: it shows its own shading, no background. Two mirror
/// spheres under ambient light, the right one red: where the ray tracer shows the red sphere
/// in the left one (0.9 x its diffuse 0.6, 0.05, 0.05, exactly), the preview shows the same
/// colour, where it added 0.3 x the background before.
#[test]
fn a_mirror_seen_in_a_mirror_ends_the_path_at_max_depth_1() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fermat_sphere.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let one_sphere = "center = [0.0, 0.65, 0.0]\nradius = 0.6\nmaterial = \"mirror\"";
    assert!(text.contains(one_sphere));
    let spheres = "center = [-0.55, 0.5, 0.0]\nradius = 0.45\nmaterial = \"mirror\"\n\n\
                   [[shapes]]\ntype = \"sphere\"\ncenter = [0.55, 0.5, 0.0]\nradius = 0.45\n\
                   material = \"red_mirror\"\n\n[[materials]]\nname = \"red_mirror\"\n\
                   model = \"lambert\"\ndiffuse = [0.6, 0.05, 0.05]\nmirror = [0.3, 0.3, 0.3]";
    let text = text
        .replace(one_sphere, spheres)
        .replace("width = 320", "width = 160")
        .replace("height = 240", "height = 120");
    let scene = chambre::scene::Scene::from_str(&path, &text, &[]).unwrap();
    assert_eq!(scene.render.max_depth, 1);
    let flat = chambre::pack::flatten(&scene);
    let options = chambre::preview::PreviewOptions::default();
    let preview = chambre::preview::draw_with(&context, &scene, &flat, 1, options)
        .unwrap()
        .image;
    let traced = common::render_cpu(&flat);
    let red_in_mirror = glam::Vec3::new(0.54, 0.045, 0.045);
    let (mut shown, mut alike) = (0, 0);
    for (t, p) in traced.pixels.iter().zip(&preview.pixels) {
        if (*t - red_in_mirror).abs().max_element() < 1e-3 {
            shown += 1;
            alike += ((*p - red_in_mirror).abs().max_element() < 1e-3) as u32;
        }
    }
    eprintln!(
        "{alike} of the {shown} pixels where the ray tracer shows the red mirror in the other"
    );
    assert!(shown > 30, "{shown}");
    assert!(alike as f64 >= 0.8 * shown as f64, "{alike} of {shown}");
}

/// A scene whose paths do not bounce (max_depth 0) shows no reflection in the ray tracer, and
/// none in the preview: it has no curved mirrors to reflect in, and its image is the image of
/// the same scene with the mirror's reflectance 0.
#[test]
fn a_scene_whose_paths_do_not_bounce_shows_no_reflection_in_the_preview() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let draw = |extra: &[&str]| {
        let overrides: Vec<&str> = [
            "render.width=160",
            "render.height=120",
            "render.max_depth=0",
        ]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
        let scene = common::load("scenes/fermat_sphere.toml", &overrides);
        let flat = chambre::pack::flatten(&scene);
        let options = chambre::preview::PreviewOptions::default();
        let image = chambre::preview::draw_with(&context, &scene, &flat, 1, options)
            .unwrap()
            .image;
        (chambre::preview::reflectors(&flat).len(), image)
    };
    let (mirrors, image) = draw(&[]);
    let (_, without) = draw(&["materials[0].mirror=[0.0,0.0,0.0]"]);
    assert_eq!(mirrors, 0);
    assert_eq!(common::differing_pixels(&image, &without), 0);
}

/// The teapot reflects itself in the preview with self-reflections on, where the ray tracer
/// (max_depth 1) shows it: its path ends on the mirror, which shows black (its diffuse is 0).
/// Without them the preview shows the background or the floor there instead. The ray tracer
/// shows 208 black pixels; the preview covers 198 of them (166 before its own points searched
/// again) and shows 271, 228 of them black in the ray tracer within a pixel.
#[test]
fn the_teapot_reflects_itself_where_the_ray_tracer_sees_it() {
    reflects_itself_where_the_ray_tracer_sees_it("scenes/fermat_teapot.toml", (0.85, 0.75));
}

/// The torus too: the far inner wall, seen through the hole, shows the near one (its own
/// points found by its inner half's search, from across the hole). The ray tracer shows 77
/// black pixels; the preview covers 61 of them (22 when the search started at the point
/// itself) and shows 113, 88 of them black in the ray tracer within a pixel. The other 25 lie
/// along the lower edge of the near wall's reflection, where the ray tracer's reflected rays
/// pass under the near tube or meet the floor inside the hole: the preview's own triangles
/// there have corners on the tube's underside, which P sees only through the tube (the law of
/// reflection holds along such paths too; docs/fermat.md).
#[test]
fn the_torus_reflects_itself_where_the_ray_tracer_sees_it() {
    reflects_itself_where_the_ray_tracer_sees_it("scenes/fermat_torus.toml", (0.7, 0.7));
}

/// At 160x120: the ray tracer's black pixels (more than 50), of which the preview with
/// self-reflections (1 px) shows more than the fraction `found` black, a pixel away at most, and
/// fewer than 10% without them; and more than the fraction `right` of the preview's black
/// pixels black in the ray tracer.
fn reflects_itself_where_the_ray_tracer_sees_it(scene: &str, (found, right): (f64, f64)) {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let scene = common::load(
        scene,
        &["render.width=160", "render.height=120", "render.spp=4"],
    );
    let flat = chambre::pack::flatten(&scene);
    let traced = common::render_cpu(&flat);
    let draw = |self_reflections| {
        let options = chambre::preview::PreviewOptions {
            self_reflections,
            ..Default::default()
        };
        chambre::preview::draw_with(&context, &scene, &flat, 1, options)
            .unwrap()
            .image
    };
    // Black: below the floor's dark squares (0.05) and their reflections (0.045).
    let black = |image: &chambre::render::Image| -> Vec<bool> {
        image
            .pixels
            .iter()
            .map(|p| p.max_element() < 0.02)
            .collect()
    };
    // Black pixels of `a` with a black pixel of `b` at most a pixel away (a reflected edge
    // a pixel off, or grey in the ray tracer's 4 samples, is not a miss).
    let near = |a: &[bool], b: &[bool]| {
        let (w, h) = (160i32, 120i32);
        (0..w * h)
            .filter(|&i| a[i as usize])
            .filter(|&i| {
                (-1..=1).any(|dy| {
                    (-1..=1).any(|dx| {
                        let (x, y) = (i % w + dx, i / w + dy);
                        (0..w).contains(&x) && (0..h).contains(&y) && b[(y * w + x) as usize]
                    })
                })
            })
            .count()
    };
    let traced = black(&traced);
    let (without, with) = (black(&draw(None)), black(&draw(Some(1.0))));
    let count = |b: &[bool]| b.iter().filter(|&&b| b).count();
    eprintln!(
        "black pixels: ray tracer {} ({} of them black in the preview with self-reflections, \
         {} without, a pixel away at most); preview without {}, with {} ({} black in the ray \
         tracer)",
        count(&traced),
        near(&traced, &with),
        near(&traced, &without),
        count(&without),
        count(&with),
        near(&with, &traced)
    );
    let traced_black = count(&traced) as f64;
    assert!(traced_black > 50.0, "{traced_black}");
    assert!((count(&without) as f64) < 0.1 * traced_black);
    let covered = near(&traced, &with) as f64;
    assert!(
        covered > found * traced_black,
        "{covered} of {traced_black}"
    );
    let black_in_both = near(&with, &traced) as f64;
    assert!(
        black_in_both > right * count(&with) as f64,
        "{black_in_both} of {}",
        count(&with)
    );
}

/// A 24 x 12 grid of the points of `torus` (its vertices, as the preview would reflect them).
fn own_points(torus: &Torus) -> Vec<DVec3> {
    let tau = std::f64::consts::TAU;
    (0..24 * 12)
        .map(|k| {
            torus.point(glam::DVec2::new(
                tau * (k % 24) as f64 / 24.0,
                tau * (k / 24) as f64 / 12.0 + 0.1,
            ))
        })
        .collect()
}

/// The search as the preview runs it: its steps, and the kernel's smallest triangle.
fn preview_solver() -> Solver {
    Solver {
        max_steps: chambre::preview::PreviewOptions::default().steps,
        min_size: 1e-7,
    }
}

/// A torus's own points (its vertices, reflected with self-reflections on) are found by its
/// inner half's search, from across the hole: their own crossing is the point itself (P = V),
/// and what a point of the torus sees of it lies on the far inner wall. Over a grid of own
/// points seen from above, the preview's 12 steps find a reflection clear of the point for 80%
/// or more of those that have one (found by 40-step searches from 128 starts each); from the
/// seed's corners (the outer half's search, the point itself) 10 of 288, where from across the
/// hole 260. (Hidden reflections count here; with
/// the torus's own occlusion tested, scratch code found 382 of 442 against 33.) The few left
/// have two or three reflections, or one near the silhouette.
#[test]
fn a_torus_finds_its_own_points_reflections_from_across_the_hole() {
    let torus = Torus::new(DVec3::new(0.0, 0.25, 0.0), 0.55, 0.2);
    let eye = DVec3::new(0.0, 1.2, 3.2);
    let tolerance = f64::from(chambre::layout::REFLECTION_TOLERANCE);
    let shows = |uv: glam::DVec2, v: DVec3, law: f64| {
        let (p, n) = (torus.point(uv), torus.outward_normal(uv));
        reflection_error(p, n, eye, v) < law
            && seen_from_outside(p, n, eye, v)
            && self_reflection_clear(p, eye, v)
    };
    let thorough = Solver {
        max_steps: 40,
        min_size: 1e-12,
    };
    let tau = std::f64::consts::TAU;
    let (mut with_reflection, mut found) = (0, 0);
    let inner = TorusSearch {
        torus,
        half: TorusHalf::Inner,
    };
    for v in own_points(&torus) {
        let has_one = (0..128).any(|k| {
            let a = glam::DVec2::new(tau * (k % 16) as f64 / 16.0, tau * (k / 16) as f64 / 8.0);
            let start = StartedFrom(torus, a, a + glam::DVec2::new(0.2, 0.1));
            shows(thorough.solve(&start, eye, v).uv, v, 1e-6)
        });
        if has_one {
            with_reflection += 1;
            found += shows(preview_solver().solve(&inner, eye, v).uv, v, tolerance) as u32;
        }
    }
    eprintln!("a torus's own points: {found} of {with_reflection} reflections found in 12 steps");
    assert_share((found, with_reflection), 50, 0.8);
}

/// The floor inside a torus's hole shows in the far inner wall, seen through the hole, and
/// only there: the seed's crossings (the outer half's search) never lead there, the search of
/// the inner half from across the hole does. Over a grid of floor points inside the hole of
/// the torus scene (a 15 x 15 grid, 149 of them with an image, found by 40-step searches from
/// 128 starts each), the preview's 12 steps find it for 80% or more from across the hole
/// (130), for none from the seed's crossings.
#[test]
fn the_floor_inside_a_torus_shows_in_its_far_inner_wall() {
    let torus = Torus::new(DVec3::new(0.0, 0.25, 0.0), 0.55, 0.2);
    let eye = DVec3::new(0.0, 1.2, 3.2);
    let tolerance = f64::from(chambre::layout::REFLECTION_TOLERANCE);
    let shows = |uv: glam::DVec2, v: DVec3, law: f64| {
        let (p, n) = (torus.point(uv), torus.outward_normal(uv));
        reflection_error(p, n, eye, v) < law && seen_from_outside(p, n, eye, v)
    };
    let thorough = Solver {
        max_steps: 40,
        min_size: 1e-12,
    };
    let search = |half| TorusSearch { torus, half };
    let tau = std::f64::consts::TAU;
    let (mut with_reflection, mut inner, mut outer) = (0, 0, 0);
    for k in 0..15 * 15 {
        let at = |i: u32| -0.35 + 0.7 * f64::from(i) / 14.0;
        let v = DVec3::new(at(k % 15), 0.0, at(k / 15));
        if v.x.hypot(v.z) > torus.major - torus.minor {
            continue;
        }
        let has_one = (0..128).any(|k| {
            let a = glam::DVec2::new(tau * (k % 16) as f64 / 16.0, tau * (k / 16) as f64 / 8.0);
            let start = StartedFrom(torus, a, a + glam::DVec2::new(0.3, 0.2));
            let uv = thorough.solve(&start, eye, v).uv;
            // On the far inner wall: the half of the torus away from the eye, inside.
            shows(uv, v, 1e-6) && on_torus_half(uv, TorusHalf::Inner) && torus.point(uv).z < 0.0
        });
        if has_one {
            with_reflection += 1;
            for (half, found) in [
                (TorusHalf::Inner, &mut inner),
                (TorusHalf::Outer, &mut outer),
            ] {
                let uv = preview_solver().solve(&search(half), eye, v).uv;
                *found += (shows(uv, v, tolerance) && on_torus_half(uv, half)) as u32;
            }
        }
    }
    eprintln!(
        "the floor inside the hole: {with_reflection} points with an image; the inner half's \
         search finds {inner}, the outer half's {outer}"
    );
    assert_share((inner, with_reflection), 100, 0.8);
    assert_eq!(outer, 0);
}

/// A thin torus far from the origin (tube 0.1 at 600 units, turned, where f32 rounds its
/// points' coordinates to 3e-5 of their own 1e-1): the kernel's (f32) search of its inner half
/// finds its own points' reflections as the CPU's (f64) does, the same points to 1e-4 of the
/// distance from the eye (f32's rounding there is 1e-5 of it) where the CPU's search converged,
/// but for a few that found another of a point's images. (When the torus's own points were
/// told from others, by their distance to its surface, to start across the hole, f32's
/// rounding there took 45-55% of them for others' on the GPU.)
#[test]
fn a_thin_torus_far_from_the_origin_finds_its_own_points_as_the_cpu_does() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let torus = Torus {
        orientation: DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
        ..Torus::new(DVec3::new(310.0, -270.0, 530.0), 1.0, 0.1)
    };
    let eye = torus.center + torus.orientation * DVec3::new(0.0, 2.2, 3.5);
    let own: Vec<glam::Vec3> = own_points(&torus).iter().map(|v| v.as_vec3()).collect();
    let inner = TorusSearch {
        torus,
        half: TorusHalf::Inner,
    };
    let on_gpu = chambre::preview::reflections::kernel::reflections(
        &context,
        MirrorSurface::Torus(inner),
        eye.as_vec3(),
        &own,
        12,
    )
    .unwrap();
    let solver = preview_solver();
    let (mut compared, mut agree) = (0, 0);
    for (v, gpu) in own.iter().zip(&on_gpu) {
        let v = v.as_dvec3();
        let uv = solver.solve(&inner, eye, v).uv;
        let (p, n) = (torus.point(uv), torus.outward_normal(uv));
        if reflection_error(p, n, eye, v) > 1e-4
            || !seen_from_outside(p, n, eye, v)
            || !self_reflection_clear(p, eye, v)
        {
            continue;
        }
        compared += 1;
        let gp = DVec3::from(glam::Vec3::from(gpu.point));
        agree += (gp.distance(p) < 1e-4 * p.distance(eye)) as u32;
    }
    eprintln!("a far thin torus's own points: {agree} of {compared} reflections the same on both");
    assert_share((agree, compared), 100, 0.98);
}

/// A mirror's own point drawn reflected in it must stand clear of its reflection point: a
/// point of the searched surface itself is its own "reflection" (P = V, the minimum of
/// |E − P| + |P − V|), and its triangle would cover the true reflection there at depth 0. Points
/// a little off one of the teapot's body patches, along the direction the eye's rays reflect
/// to (so the law of reflection holds at the patch point below them): tagged as the mirror's
/// own, the cull draws their triangles in that patch where they stand twice
/// `SELF_REFLECTION_CLEARANCE` of the eye's distance off, and none at half of it; tagged as
/// another shape's, both.
#[test]
fn a_mirrors_own_points_are_drawn_only_clear_of_their_reflection() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let (_, patches) = teapot();
    let patch = patches[5];
    let eye = DVec3::new(0.3, 1.8, 3.5);
    let clearance = f64::from(chambre::layout::SELF_REFLECTION_CLEARANCE);
    let n = 12;
    let grid = |off: f64| -> Vec<glam::Vec3> {
        (0..=n)
            .flat_map(|i| (0..=n).map(move |j| glam::DVec2::new(i as f64, j as f64) / n as f64))
            .map(|uv| {
                let (p, normal) = (patch.point(uv), patch.outward_normal(uv));
                let to_eye = (eye - p).normalize();
                let reflected = 2.0 * to_eye.dot(normal) * normal - to_eye;
                (p + off * clearance * eye.distance(p) * reflected).as_vec3()
            })
            .collect()
    };
    let triangles = |tag: u32| -> Vec<[u32; 4]> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let k = i * (n + 1) + j;
                out.push([k, k + 1, k + n + 1, tag]);
                out.push([k + 1, k + n + 2, k + n + 1, tag]);
            }
        }
        out
    };
    let listed = |off: f64, tag: u32| {
        let (_, shown) = chambre::preview::reflections::kernel::shown_triangles(
            &context,
            MirrorSurface::Patch(patch),
            (eye.as_vec3(), 1, true),
            &grid(off),
            &triangles(tag),
            chambre::preview::PreviewOptions::default().steps,
        )
        .unwrap();
        shown.len()
    };
    let (near_own, far_own) = (listed(0.5, 1), listed(2.0, 1));
    let (near_other, far_other) = (listed(0.5, 0), listed(2.0, 0));
    eprintln!(
        "triangles drawn: own at half the clearance {near_own}, at twice it {far_own}; another \
         shape's {near_other} and {far_other}"
    );
    assert_eq!(near_own, 0);
    assert!(far_own > 50, "{far_own}");
    assert!(
        near_other > 20 && far_other > 50,
        "{near_other}, {far_other}"
    );
}

/// How the search went on one reflector over random configurations.
#[derive(Debug, Default)]
struct Tally {
    /// Configurations tried.
    tried: u32,
    /// The search says it converged (its triangle shrank below the stopping size).
    claimed: u32,
    /// Of those, where the law of reflection holds to 1e-4 rad.
    lawful: u32,
    /// Of those, where the point lies on the segment E → V instead (to 1e-6 of |EV|): d's
    /// global minimum |EV|, a stationary point that is no reflection.
    through: u32,
    /// Of those, neither a reflection nor on the segment: a false convergence.
    neither: u32,
    /// Of those, on the side E and V both see.
    seen: u32,
    /// The law holds (and seen) within the seed's 5 steps.
    within_five: u32,
}

/// `reflector` for an eye and a vertex: the reflector itself, or a reparametrisation facing them.
fn tally<R: Reflector>(
    reflector: impl Fn(DVec3, DVec3) -> R,
    mut configuration: impl FnMut() -> (DVec3, DVec3),
) -> Tally {
    let (five, long) = (
        Solver::default(),
        Solver {
            max_steps: 30,
            ..Solver::default()
        },
    );
    let mut t = Tally::default();
    let holds = |reflector: &R, uv, eye, vertex| {
        let p = reflector.point(uv);
        let n = reflector.outward_normal(uv);
        (
            reflection_error(p, n, eye, vertex) < 1e-4,
            seen_from_outside(p, n, eye, vertex),
        )
    };
    for _ in 0..400 {
        let (eye, vertex) = configuration();
        let reflector = reflector(eye, vertex);
        t.tried += 1;
        let s = long.solve(&reflector, eye, vertex);
        if !s.degenerate && !s.left_surface && s.steps < long.max_steps {
            t.claimed += 1;
            let (lawful, seen) = holds(&reflector, s.uv, eye, vertex);
            t.lawful += lawful as u32;
            let p = reflector.point(s.uv);
            let straight = (eye - p).length() + (vertex - p).length() - (eye - vertex).length();
            let through = straight < 1e-6 * (eye - vertex).length();
            t.through += through as u32;
            t.neither += (!lawful && !through) as u32;
            t.seen += (lawful && seen) as u32;
        }
        let s = five.solve(&reflector, eye, vertex);
        let (lawful, seen) = holds(&reflector, s.uv, eye, vertex);
        t.within_five += (lawful && seen) as u32;
    }
    t
}

/// The other reflectors (ellipsoid, cylinder, torus, a bicubic Bézier dome), 400 random
/// configurations each: where the search says it converged (its triangle or its last step
/// shrank below 1e-9 within 30 steps), its point is a reflection (the law of reflection holds
/// to 1e-4 rad) or the point where the segment E → V crosses the surface, d's other stationary
/// point (its global minimum |EV|: V hidden behind the reflector, no reflection). Measured
/// (seeded): ellipsoid 395 reflections + 5 crossings of 400; cylinder 378 + 20 of 398; torus
/// 362 + 15 of 377; dome 399 of 399. How often it converges within the seed's 5 steps is
/// printed and kept above floors, not promised.
#[test]
fn the_other_reflectors_obey_the_law_of_reflection_where_the_search_converged() {
    let mut rng = Rng::new(23, 0, 0);
    let mut uniform = move || rng.next_f32() as f64;
    let ellipsoid = Ellipsoid::new(DVec3::new(0.2, 0.1, -0.3), DVec3::new(1.0, 0.6, 1.4));
    let cylinder = Cylinder::new(DVec3::new(-0.1, 0.0, 0.2), 0.8);
    let torus = Torus::new(DVec3::ZERO, 1.5, 0.5);
    // A dome over [-1, 1]²: the inner control points raised.
    let mut points = [[DVec3::ZERO; 4]; 4];
    for (i, row) in points.iter_mut().enumerate() {
        for (j, p) in row.iter_mut().enumerate() {
            let inner = (1..3).contains(&i) && (1..3).contains(&j);
            *p = DVec3::new(
                -1.0 + 2.0 * j as f64 / 3.0,
                if inner { 0.6 } else { 0.0 },
                -1.0 + 2.0 * i as f64 / 3.0,
            );
        }
    }
    let dome = BezierPatch { points };
    let mut around = |centre: DVec3, near: f64, far: f64| {
        let d = DVec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalize();
        centre + d * (near + (far - near) * uniform())
    };
    let mut results = Vec::new();
    // E and V outside each reflector, at most 150 degrees apart seen from its centre.
    let mut pair = |centre: DVec3, near: f64, far: f64| loop {
        let (e, v) = (around(centre, near, far), around(centre, near, far));
        if (e - centre).angle_between(v - centre).to_degrees() < 150.0 {
            return (e, v);
        }
    };
    results.push((
        "ellipsoid",
        tally(
            |e, v| ellipsoid.facing(e, v),
            || pair(ellipsoid.center, 2.0, 5.0),
        ),
    ));
    results.push((
        "cylinder",
        tally(
            |_, _| cylinder,
            || {
                let (mut e, mut v) = pair(cylinder.center, 1.6, 4.0);
                // Outside the cylinder, not only its bounding sphere.
                for p in [&mut e, &mut v] {
                    let radial = DVec3::new(p.x - cylinder.center.x, 0.0, p.z - cylinder.center.z);
                    if radial.length() < 1.2 * cylinder.radius {
                        *p += radial.normalize_or(DVec3::X) * 1.2 * cylinder.radius;
                    }
                }
                (e, v)
            },
        ),
    ));
    results.push((
        "torus",
        tally(|_, _| torus, || pair(torus.center, 2.5, 6.0)),
    ));
    let mut above = {
        let mut rng = Rng::new(29, 0, 0);
        move || {
            let [a, b] = rng.next_2d();
            let [c, _] = rng.next_2d();
            DVec3::new(
                3.0 * a as f64 - 1.5,
                1.0 + 2.0 * c as f64,
                3.0 * b as f64 - 1.5,
            )
        }
    };
    results.push(("Bézier dome", tally(|_, _| dome, || (above(), above()))));
    for (name, t) in &results {
        eprintln!(
            "{name}: {} configurations, the search claims convergence for {} (30 steps), the \
             law of reflection holds at {} of them ({} on the side E and V see), {} lie on \
             the segment E-V, {} neither; within 5 steps: {}",
            t.tried, t.claimed, t.lawful, t.seen, t.through, t.neither, t.within_five
        );
        assert!(t.claimed as f64 >= 0.9 * t.tried as f64, "{name}: {t:?}");
        assert!(t.lawful as f64 >= 0.94 * t.claimed as f64, "{name}: {t:?}");
        assert!(
            t.neither as f64 <= 0.005 * t.claimed as f64,
            "{name}: {t:?}"
        );
    }
    let (_, dome) = &results[3];
    assert_eq!(dome.lawful, dome.claimed, "{dome:?}");
    assert!(
        dome.within_five as f64 >= 0.95 * dome.tried as f64,
        "{dome:?}"
    );
    for (name, t) in &results {
        assert!(t.seen > 0 && t.within_five > 0, "{name}: {t:?}");
    }
}
