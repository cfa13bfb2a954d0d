//! Driver and kernel limits never give a quiet wrong image: work that one GPU invocation cannot
//! do within lavapipe's loop budget is split over dispatches, and what still exceeds it is
//! reported by the status flag and an error.

mod common;

use std::sync::atomic::AtomicBool;

use chambre::accel::flatten;
use chambre::gpu::GpuRenderer;
use chambre::layout::STATUS_LOOP_LIMIT;
use chambre::render::{RAYS_PER_INVOCATION, RayBound, describe_status_flags, plan_passes, render};

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
    let plan = plan_passes(&flat, 128 * 128);
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
    let flat = flatten(&split);
    assert!(plan_passes(&flat, 128 * 128).light_windows.len() > 1);
    let windowed = common::render_cpu(&flat);
    // The same estimate, every light sample in one call per camera sample.
    let whole = chambre::render::Image {
        width: 16,
        height: 16,
        pixels: (0..16 * 16)
            .map(|i| {
                let mut stats = Default::default();
                let sum: glam::Vec3 = (0..2)
                    .map(|s| {
                        chambre::integrator::trace_sample(
                            &flat,
                            i % 16,
                            i / 16,
                            s,
                            chambre::integrator::LightWindow::ALL,
                            &mut stats,
                        )
                    })
                    .sum();
                sum / 2.0
            })
            .collect(),
    };
    let (within, mean_abs) = common::agreement(&windowed, &whole, 1e-5);
    assert!(
        within == 1.0,
        "{within} of pixels within 1e-5, mean |diff| {mean_abs:.2e}"
    );
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
    assert!(RayBound::of(&flat).per_sample() > 64 * RAYS_PER_INVOCATION);
    let Some(context) = common::gpu_context() else {
        return;
    };
    let lavapipe = format!("{:?}", context.adapter_description).contains("llvmpipe");
    let mut renderer = GpuRenderer::new(context, &flat).unwrap();
    let output = render(
        &flat,
        &mut renderer,
        &mut |_, _| {},
        &AtomicBool::new(false),
    )
    .unwrap();
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
