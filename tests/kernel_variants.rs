//! A kernel specialised to a scene's features renders the same image as the general kernel,
//! bit for bit, on the sample scenes that leave features out; the split kernels render the
//! megakernel's; and no kernel can be built that lacks a feature its scene uses.

mod common;

use std::sync::atomic::AtomicBool;

use chambre::cpu::CpuRenderer;
use chambre::gpu::GpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::layout::*;
use chambre::pack::flatten;
use chambre::render::{Image, RayBudgets, render};

fn render_with(flat: &chambre::pack::FlatScene, features: u32) -> Option<(Image, u64)> {
    let context = common::gpu_context()?;
    let mut renderer = GpuRenderer::with_features(context, flat, features).unwrap();
    assert_eq!(renderer.features(), features);
    let output = common::render_clean(flat, &mut renderer);
    Some((output.image, output.rays))
}

#[test]
fn specialised_kernels_render_the_general_kernels_image() {
    let cases: [(&str, &[&str], u32); 6] = [
        // mirrors, point light, plane; no lens, area lights or triangles
        (
            "scenes/spheres.toml",
            &["render.width=96", "render.height=64"],
            0x2a,
        ),
        // the same without the mirror: no bounce loop
        (
            "scenes/spheres.toml",
            &[
                "render.width=96",
                "render.height=64",
                "materials[2].mirror=[0, 0, 0]",
            ],
            0x28,
        ),
        // triangles and a point light only
        (
            "scenes/bunny.toml",
            &["render.width=72", "render.height=48"],
            0x18,
        ),
        // an area light and quads, spheres: no punctual lights, triangles or planes
        (
            "scenes/area_light.toml",
            &["render.width=48", "render.height=48"],
            0x04,
        ),
        // a thin lens
        (
            "scenes/thin_lens.toml",
            &["render.width=72", "render.height=48"],
            0x29,
        ),
        // a mirror torus (curved shapes) over quads, ambient light only
        (
            "scenes/fermat_torus.toml",
            &["render.width=64", "render.height=48"],
            0x42,
        ),
    ];
    for (path, overrides, expected) in cases {
        let overrides = [overrides, &["render.spp=2"]].concat();
        let flat = flatten(&common::load(path, &overrides));
        assert_eq!(flat.features(), expected, "{path} {overrides:?}");
        assert_ne!(flat.features(), FEATURES_ALL);
        let Some((general, general_rays)) = render_with(&flat, FEATURES_ALL) else {
            return;
        };
        let (specialised, rays) = render_with(&flat, flat.features()).unwrap();
        assert_eq!(rays, general_rays, "{path}: rays traced");
        let differing = common::differing_pixels(&general, &specialised);
        eprintln!(
            "{path} {overrides:?}: features {:#x}, {differing} of {} pixels differ",
            flat.features(),
            general.pixels.len()
        );
        assert_eq!(
            differing, 0,
            "{path}: the specialised kernel's image differs"
        );
    }
}

/// The wavefront render (a kernel per stage of a path vertex, paths and shadow rays in queues)
/// renders the megakernel's image bit for bit: the same camera samples, hits, shadow rays and
/// shading, summed in the same order; with light windows, adaptive passes (pixel lists), AOV
/// layers, a real lens, curved mirrors cut off at max_depth and motion blur too, and the same rays, cut-off
/// paths and per-pixel sample counts.
#[test]
fn the_wavefront_render_renders_the_megakernels_image() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let few_rays = RayBudgets {
        per_invocation: 4,
        ..RayBudgets::DEFAULT
    };
    let cases: [(&str, &[&str], RayBudgets); 8] = [
        // mirrors, a point light, a plane
        (
            "scenes/spheres.toml",
            &["render.width=96", "render.height=64"],
            RayBudgets::DEFAULT,
        ),
        // triangles
        (
            "scenes/bunny.toml",
            &["render.width=72", "render.height=48"],
            RayBudgets::DEFAULT,
        ),
        // an area light of 8 samples a hit in light windows, adaptive sampling
        (
            "scenes/area_light.toml",
            &[
                "render.width=48",
                "render.height=48",
                "render.spp=8",
                "lights[0].samples=8",
                "render.noise_target=0.05",
            ],
            few_rays,
        ),
        // a thin lens
        (
            "scenes/thin_lens.toml",
            &["render.width=72", "render.height=48"],
            RayBudgets::DEFAULT,
        ),
        // a real lens: camera samples weighted by its exit-pupil bounds, some lost in the glass
        (
            "scenes/double_gauss.toml",
            &["render.width=72", "render.height=48"],
            RayBudgets::DEFAULT,
        ),
        // the spectral mode: the wavefront render finds each sample's wavelength again when it
        // adds the sample
        (
            "scenes/spectral_singlet.toml",
            &["render.width=72", "render.height=48"],
            RayBudgets::DEFAULT,
        ),
        // a curved mirror, its paths cut off at max_depth
        (
            "scenes/fermat_torus.toml",
            &["render.width=64", "render.height=48"],
            RayBudgets::DEFAULT,
        ),
        // motion blur: a rolling sphere
        (
            "scenes/tabletop.toml",
            &[
                "render.width=72",
                "render.height=48",
                "shapes[2].velocity=[0.3,0.0,0.1]",
                "camera.shutter=[0.0,1.0]",
            ],
            RayBudgets::DEFAULT,
        ),
    ];
    for (path, overrides, budgets) in cases {
        let overrides = [&["render.spp=2"], overrides].concat();
        let mut flat = flatten(&common::load(path, &overrides));
        flat.aovs = true;
        if budgets == few_rays {
            let windows = chambre::render::plan_passes(&flat, &budgets).light_windows;
            assert!(windows.len() > 1, "{path}: {windows:?}");
        }
        let run = |kernels| {
            let mut renderer = GpuRenderer::with_budgets(
                context.clone(),
                &flat,
                flat.features(),
                kernels,
                budgets,
            )
            .unwrap();
            let output = common::render_through(&flat, &mut renderer);
            assert!(output.stopped.is_none(), "{path}: {:?}", output.stopped);
            assert_eq!(output.status_flags, 0, "{path}");
            output
        };
        let mega = run(PathKernels::Megakernel);
        let wave = run(PathKernels::Wavefront);
        let differing = common::differing_pixels(&mega.image, &wave.image);
        eprintln!(
            "{path}: {differing} of {} pixels differ, {} rays, {} cut off",
            mega.image.pixels.len(),
            mega.rays,
            mega.truncated_paths
        );
        assert_eq!(differing, 0, "{path}: the wavefront render's image differs");
        assert_eq!(wave.rays, mega.rays, "{path}: rays");
        assert_eq!(wave.truncated_paths, mega.truncated_paths, "{path}");
        assert_eq!(wave.sample_counts, mega.sample_counts, "{path}");
        let (a, b) = (mega.aovs.unwrap(), wave.aovs.unwrap());
        assert!(a.depth == b.depth && a.normal == b.normal && a.albedo == b.albedo);
    }
}

/// A dispatch of more paths than the wavefront render's buffers hold is refused before anything
/// runs, rather than overrunning them (the render plan never makes one).
#[test]
fn the_wavefront_render_refuses_a_dispatch_its_buffers_cannot_hold() {
    use chambre::render::Backend;
    let Some(context) = common::gpu_context() else {
        return;
    };
    let flat = flatten(&common::load(
        "scenes/spheres.toml",
        &["render.width=24", "render.height=16"],
    ));
    let mut renderer = GpuRenderer::with_budgets(
        context,
        &flat,
        flat.features(),
        PathKernels::Wavefront,
        RayBudgets::DEFAULT,
    )
    .unwrap();
    let plan = chambre::render::plan_passes(&flat, &RayBudgets::DEFAULT);
    let mut pass = plan.dispatches(0)[0];
    pass.sample_count = (plan.samples_per_dispatch() + 1) as u32;
    pass.tile_width = 1;
    pass.tile_height = 1;
    let error = renderer.submit(&[pass]).expect_err("an oversized dispatch");
    assert!(error.to_string().contains("wavefront render's"), "{error}");
    assert_eq!(renderer.in_flight(), 0);
}

#[test]
fn a_kernel_without_a_feature_the_scene_uses_is_refused() {
    let flat = flatten(&common::load(
        "scenes/spheres.toml",
        &["render.width=24", "render.height=16"],
    ));
    let Some(context) = common::gpu_context() else {
        return;
    };
    let error = GpuRenderer::with_features(context, &flat, flat.features() & !FEATURE_MIRRORS)
        .err()
        .expect("a kernel without mirrors for a scene with a mirror");
    assert!(error.to_string().contains("0x2"), "{error}");
}

/// The CPU integrator compiled for a scene's features renders the general integrator's image,
/// bit for bit.
#[test]
fn specialised_cpu_integrators_render_the_general_integrators_image() {
    for (path, overrides) in [
        (
            "scenes/spheres.toml",
            &["render.width=48", "render.height=32"][..],
        ),
        (
            "scenes/bunny.toml",
            &["render.width=48", "render.height=32"][..],
        ),
        (
            "scenes/area_light.toml",
            &["render.width=32", "render.height=32"][..],
        ),
        (
            "scenes/thin_lens.toml",
            &["render.width=48", "render.height=32"][..],
        ),
        (
            "scenes/fermat_cylinder.toml",
            &["render.width=48", "render.height=36"][..],
        ),
    ] {
        let flat = flatten(&common::load(
            path,
            &[overrides, &["render.spp=2"]].concat(),
        ));
        let cancel = AtomicBool::new(false);
        let mut images = Vec::new();
        for features in [flat.features(), FEATURES_ALL] {
            let mut cpu = CpuRenderer::new(&flat).with_features(features).unwrap();
            assert_eq!(cpu.features(), features);
            images.push(
                render(&flat, &mut cpu, &mut |_, _| {}, &cancel)
                    .unwrap()
                    .image,
            );
        }
        assert_ne!(flat.features(), FEATURES_ALL, "{path}");
        assert_eq!(images[0], images[1], "{path}");
    }
    let flat = flatten(&common::load(
        "scenes/spheres.toml",
        &["render.width=24", "render.height=16"],
    ));
    assert!(CpuRenderer::new(&flat).with_features(0).is_err());
}

/// A renderer renders its scene again from zero: the same image and sample counts the second
/// time (not the sums of both), on both GPU ways and on the CPU path, adaptive sampling and a
/// pass split into light windows included.
#[test]
fn a_renderer_renders_its_scene_again_from_zero() {
    let flat = flatten(&common::load(
        "scenes/area_light.toml",
        &[
            "render.width=24",
            "render.height=24",
            "render.spp=4",
            "lights[0].samples=8",
            "render.noise_target=0.05",
        ],
    ));
    let few_rays = RayBudgets {
        per_invocation: 4,
        ..RayBudgets::DEFAULT
    };
    let twice = |backend: &mut dyn chambre::render::Backend, what: &str| {
        let first = common::render_through(&flat, backend);
        let second = common::render_through(&flat, backend);
        assert_eq!(first.sample_counts, second.sample_counts, "{what}");
        assert_eq!(
            common::differing_pixels(&first.image, &second.image),
            0,
            "{what}"
        );
        assert_eq!(first.rays, second.rays, "{what}");
    };
    twice(
        &mut chambre::cpu::CpuRenderer::new(&flat).with_budgets(few_rays),
        "CPU",
    );
    let Some(context) = common::gpu_context() else {
        return;
    };
    for kernels in [PathKernels::Megakernel, PathKernels::Wavefront] {
        let mut renderer =
            GpuRenderer::with_budgets(context.clone(), &flat, flat.features(), kernels, few_rays)
                .unwrap();
        twice(&mut renderer, &format!("{kernels:?}"));
    }
}
