//! Driver and kernel limits never give a quiet wrong image: work that one GPU invocation cannot
//! do within lavapipe's loop budget is split over dispatches, and what still exceeds it is
//! reported by the status flag and an error.

mod common;

use chambre::gpu::GpuRenderer;
use chambre::layout::STATUS_LOOP_LIMIT;
use chambre::pack::flatten;
use chambre::render::{RayBound, RayBudgets, describe_status_flags, plan_passes};

/// An area light with 4096 samples (the most a scene may ask) rendered on lavapipe with a mean
/// of 0.047 against the CPU's 0.127, exit 0, before light samples were split into windows: every
/// loop of an invocation stopped after 65535 iterations in total.
#[test]
fn an_area_light_with_4096_samples_agrees_with_the_cpu() {
    let scene = common::load(
        "scenes/area_light.toml",
        &[
            "render.width=12",
            "render.height=12",
            "render.spp=1",
            "lights[0].samples=4096",
        ],
    );
    let flat = flatten(&scene);
    let plan = plan_passes(&flat, &RayBudgets::DEFAULT);
    assert!(
        plan.light_windows.len() > 1,
        "4096 shadow rays per sample must be split into windows"
    );
    let Some(gpu) = common::render_gpu(&flat) else {
        return;
    };
    let cpu = common::render_cpu(&flat);
    let mean = |image: &chambre::render::Image| {
        image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / image.pixels.len() as f64
    };
    let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
    eprintln!(
        "4096 light samples: CPU mean {:.4}, GPU mean {:.4}, {:.2}% within 1e-3, mean |diff| {mean_abs:.2e}",
        mean(&cpu),
        mean(&gpu),
        within * 100.0
    );
    assert!(within >= 0.995 && mean_abs < 1e-4);
}

/// Splitting a pass into light windows changes no pixel: the windows' sums add up to the
/// whole-light estimate (same random dimensions), on the CPU path, which follows the same plan.
#[test]
fn light_windows_sum_to_the_unsplit_estimate() {
    let small = ["render.width=16", "render.height=16", "render.spp=2"];
    let split = common::load(
        "scenes/area_light.toml",
        &[&small[..], &["lights[0].samples=400"]].concat(),
    );
    common::assert_windows_sum_to_unsplit(&flatten(&split));
}

/// Two facing mirrors and 64 point lights at max_depth 1024: one sample traces ~66,000 rays in
/// one invocation, beyond any split (a path's vertices are not split). On lavapipe the driver's
/// loop limit cuts it short: the render must report it. On a GPU without such a limit, the image
/// must match the CPU's.
#[test]
fn a_path_over_the_loop_budget_is_reported_never_quiet() {
    let mut text = String::from(
        r#"[render]
width = 8
height = 8
spp = 1
max_depth = 1024
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
vertical_fov = 1.0
film = [24.0, 24.0]
[[materials]]
name = "mirror"
model = "mirror"
diffuse = [0.1, 0.1, 0.1]
mirror = [0.9, 0.9, 0.9]
[[shapes]]
type = "quad"
corner = [-1.0, -1.0, -1.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 2.0, 0.0]
material = "mirror"
[[shapes]]
type = "quad"
corner = [-1.0, -1.0, 1.0]
edge_u = [0.0, 2.0, 0.0]
edge_v = [2.0, 0.0, 0.0]
material = "mirror"
"#,
    );
    for i in 0..64 {
        let x = (i % 8) as f32 * 0.1 - 0.35;
        let y = (i / 8) as f32 * 0.1 - 0.35;
        text += &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{x}, {y}, 0.5]\nintensity = [0.01, 0.01, 0.01]\n"
        );
    }
    let scene =
        chambre::scene::Scene::from_str(std::path::Path::new("corridor.toml"), &text, &[]).unwrap();
    let flat = flatten(&scene);
    assert!(RayBound::of(&flat).per_sample() > 64 * RayBudgets::DEFAULT.per_invocation);
    let Some(context) = common::gpu_context() else {
        return;
    };
    let lavapipe = format!("{:?}", context.adapter_description).contains("llvmpipe");
    let mut renderer = GpuRenderer::new(context, &flat).unwrap();
    let output = common::render_through(&flat, &mut renderer);
    let flagged = output.status_flags & STATUS_LOOP_LIMIT != 0;
    eprintln!(
        "corridor: flags {:#x}, {} rays, lavapipe {lavapipe}",
        output.status_flags, output.rays
    );
    if lavapipe {
        assert!(flagged, "lavapipe cut the loops short without a report");
        let reason = describe_status_flags(output.status_flags).unwrap();
        assert!(reason.contains("--backend cpu"), "{reason}");
    }
    if !flagged {
        let cpu = common::render_cpu(&flat);
        let (within, mean_abs) = common::agreement(&cpu, &output.image, 1e-3);
        assert!(within >= 0.995 && mean_abs < 1e-4, "{within} {mean_abs}");
    }
}

/// PLOC builds these 82 and 393 levels deep, beyond the GPU's 64-entry traversal stack, which
/// once made the GPU refuse them; the depth-bounded build makes both paths render them.
#[test]
fn meshes_with_deep_bvhs_render_on_the_gpu_and_agree() {
    for (name, obj) in [
        ("fan", common::fan_disc()),
        ("slivers", common::nested_slivers()),
    ] {
        let scene = chambre::scene::Scene::load(&common::deep_mesh_scene(name, &obj), &[]).unwrap();
        let chambre::scene::Shape::Mesh { mesh, .. } = &scene.shapes[0] else {
            unreachable!()
        };
        let boxes: Vec<obvhs::aabb::Aabb> = mesh
            .triangles
            .iter()
            .map(|t| obvhs::aabb::Aabb::from_points(&t.map(|i| mesh.positions[i as usize].into())))
            .collect();
        let (unbounded, _) = chambre::accel::build::build_bvh(&boxes, usize::MAX);
        let free_depth = chambre::accel::build::tree_depth(&unbounded.nodes);
        assert!(
            free_depth > 64,
            "{name}: PLOC's tree is only {free_depth} deep"
        );
        let flat = flatten(&scene);
        assert!(
            flat.bvh_depth <= chambre::layout::BVH_STACK_SIZE as usize,
            "{name}: depth {}",
            flat.bvh_depth
        );
        let cpu = common::render_cpu(&flat);
        let lit = cpu.pixels.iter().filter(|p| p.max_element() > 0.0).count();
        assert!(lit > 20, "{name}: the mesh is in view ({lit} lit pixels)");
        let Some(gpu) = common::render_gpu(&flat) else {
            return;
        };
        let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
        eprintln!(
            "{name}: depth {free_depth} bounded to {}, {lit} lit pixels, {:.2}% within 1e-3",
            flat.bvh_depth,
            within * 100.0
        );
        assert!(
            within >= 0.995 && mean_abs < 1e-4,
            "{name}: {within} {mean_abs}"
        );
    }
}

/// An image whose accumulation buffer is larger than the adapter's largest storage binding
/// (lavapipe: 128 MiB) is refused before any work, with the size, the limit and the flag to use;
/// an adapter that can bind it accepts it.
#[test]
fn a_scene_over_the_binding_limit_is_refused_with_its_size_the_limit_and_the_flag() {
    let scene = common::load(
        "scenes/spheres.toml",
        &["render.width=6144", "render.height=4096", "render.spp=1"],
    );
    let flat = flatten(&scene);
    let Some(context) = common::gpu_context() else {
        return;
    };
    let limit = context.device.limits().max_storage_buffer_binding_size;
    let needed = 6144u64 * 4096 * 16;
    match GpuRenderer::new(context, &flat) {
        Err(e) => {
            let message = e.to_string();
            eprintln!("{message}");
            assert!(needed > limit, "refused although it fits: {message}");
            assert!(message.contains("384.0 MiB"), "{message}");
            assert!(
                message.contains(&format!("{:.1} MiB", limit as f64 / 1048576.0)),
                "{message}"
            );
            assert!(message.contains("--backend cpu"), "{message}");
        }
        Ok(_) => assert!(needed <= limit, "accepted an image over the limit"),
    }
}

/// A real GPU's budgets give a megapixel image a million invocations per dispatch (fewer
/// samples each), a small image the same plan as a CPU adapter's, and both plans the same
/// image up to rounding: a pass sums its samples before adding them to the accumulation.
#[test]
fn real_gpu_budgets_fill_a_dispatch_and_change_no_pixel() {
    let megapixel = flatten(&common::load(
        "scenes/area_light.toml",
        &["render.width=1024", "render.height=1024", "render.spp=8"],
    ));
    let plan = plan_passes(&megapixel, &RayBudgets::REAL_GPU);
    let invocations =
        |plan: &chambre::render::RenderPlan| plan.bands[0].1 as u64 * plan.width as u64;
    assert!(invocations(&plan) >= 1 << 20, "{plan:?}");
    let lavapipe = plan_passes(&megapixel, &RayBudgets::DEFAULT);
    assert!(invocations(&lavapipe) < 1 << 20);
    let samples = |plan: &chambre::render::RenderPlan| plan.passes.iter().map(|p| p.1).sum::<u32>();
    assert_eq!((samples(&plan), samples(&lavapipe)), (8, 8));

    let small = flatten(&common::load("scenes/area_light.toml", &[]));
    assert_eq!(
        plan_passes(&small, &RayBudgets::REAL_GPU),
        plan_passes(&small, &RayBudgets::DEFAULT)
    );

    let scene = flatten(&common::load(
        "scenes/spheres.toml",
        &["render.width=480", "render.height=320", "render.spp=4"],
    ));
    let real = plan_passes(&scene, &RayBudgets::REAL_GPU);
    assert!(real.passes.len() > plan_passes(&scene, &RayBudgets::DEFAULT).passes.len());
    let mut cpu = chambre::cpu::CpuRenderer::new(&scene).with_budgets(RayBudgets::REAL_GPU);
    let split = common::render_through(&scene, &mut cpu).image;
    let (within, mean_abs) = common::agreement(&common::render_cpu(&scene), &split, 1e-5);
    assert!(within >= 0.999 && mean_abs < 1e-6, "{within} {mean_abs:e}");
}
