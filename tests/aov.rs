//! AOV layers (`chambre render --aov`): the first hits' depth, normal and albedo hold their
//! analytic values, both paths agree, splitting passes changes nothing, and the EXR carries
//! them as named channels.

use std::path::Path;
use std::process::Command;

use chambre::cpu::CpuRenderer;
use chambre::gpu::GpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::pack::{FlatScene, flatten};
use chambre::render::{Aovs, RayBudgets};
use chambre::scene::Scene;
use glam::Vec3;

mod common;

/// A pinhole 5 units in front of a quad in the plane z = 0 that covers the left half of the
/// view (x < 0); the right half sees the background.
const SCENE: &str = r#"
[render]
width = 32
height = 32
spp = 4
background = [0.2, 0.2, 0.2]
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
vertical_fov = 30.0
film = [24.0, 24.0]
[[materials]]
name = "paint"
model = "lambert"
diffuse = [0.5, 0.4, 0.3]
[[shapes]]
type = "quad"
corner = [-10.0, -10.0, 0.0]
edge_u = [10.0, 0.0, 0.0]
edge_v = [0.0, 20.0, 0.0]
material = "paint"
[[lights]]
type = "point"
position = [0.0, 0.0, 4.0]
intensity = [10.0, 10.0, 10.0]
"#;

fn scene(overrides: &[&str]) -> FlatScene {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let mut flat = flatten(&Scene::from_str(Path::new("aov.toml"), SCENE, &overrides).unwrap());
    flat.aovs = true;
    flat
}

#[test]
fn the_layers_hold_the_first_hits_depth_normal_and_albedo() {
    let flat = scene(&[]);
    let output = common::render_clean(&flat, &mut CpuRenderer::new(&flat));
    let aovs = output.aovs.expect("AOVs were asked for");
    let tan_half = 15f32.to_radians().tan();
    for y in 0..32u32 {
        for x in 0..32u32 {
            let i = (y * 32 + x) as usize;
            // The ray through the pixel's centre; its samples spread over the pixel, so the
            // mean depth departs from the centre's to second order (about 1e-4 here).
            let sx = ((x as f32 + 0.5) / 32.0 * 2.0 - 1.0) * tan_half;
            let sy = (1.0 - (y as f32 + 0.5) / 32.0 * 2.0) * tan_half;
            let direction = Vec3::new(sx, sy, -1.0).normalize();
            if x < 15 {
                let depth = 5.0 / -direction.z;
                assert!(
                    (aovs.depth[i] - depth).abs() < 2e-3 * depth,
                    "({x}, {y}): depth {} against {depth}",
                    aovs.depth[i]
                );
                assert!((aovs.normal[i] - Vec3::Z).abs().max_element() < 1e-6);
                assert!(
                    (aovs.albedo[i] - Vec3::new(0.5, 0.4, 0.3))
                        .abs()
                        .max_element()
                        < 1e-6
                );
            } else if x > 16 {
                // The background: no hit, every layer zero (the image shows the background).
                assert_eq!(
                    (aovs.depth[i], aovs.normal[i], aovs.albedo[i]),
                    (0.0, Vec3::ZERO, Vec3::ZERO)
                );
                assert_eq!(output.image.pixels[i], Vec3::splat(0.2));
            }
        }
    }
}

fn assert_close(a: &Aovs, b: &Aovs, tolerance: f32, what: &str) {
    let close = |p: f32, q: f32| (p - q).abs() <= tolerance * p.abs().max(q.abs()) + 1e-6;
    for i in 0..a.depth.len() {
        assert!(close(a.depth[i], b.depth[i]), "{what}: depth at {i}");
        for c in 0..3 {
            assert!(
                close(a.normal[i][c], b.normal[i][c]),
                "{what}: normal at {i}"
            );
            assert!(
                close(a.albedo[i][c], b.albedo[i][c]),
                "{what}: albedo at {i}"
            );
        }
    }
}

#[test]
fn both_paths_and_split_passes_give_the_same_layers() {
    // An area light with 8 samples a hit, split into light windows by small budgets, and
    // adaptive sampling (pixel lists): the AOV layers sit between the image's sums and the
    // scratch sums.
    let overrides = [
        "lights[0]={type=\"area\", corner=[-1.0,-1.0,4.0], edge_u=[2.0,0.0,0.0], \
         edge_v=[0.0,2.0,0.0], radiance=[5.0,5.0,5.0], samples=8}",
        "render.spp=32",
        "render.noise_target=0.05",
    ];
    let flat = scene(&overrides);
    let whole = common::render_clean(&flat, &mut CpuRenderer::new(&flat));
    let budgets = RayBudgets {
        per_invocation: 4,
        ..RayBudgets::DEFAULT
    };
    assert!(
        chambre::render::plan_passes(&flat, &budgets)
            .light_windows
            .len()
            > 1
    );
    let split = common::render_clean(&flat, &mut CpuRenderer::new(&flat).with_budgets(budgets));
    assert_eq!(whole.sample_counts, split.sample_counts);
    let reference = whole.aovs.as_ref().unwrap();
    assert_close(reference, split.aovs.as_ref().unwrap(), 1e-6, "split");
    if let Some(context) = common::gpu_context() {
        let ways = [PathKernels::Megakernel, PathKernels::Wavefront]
            .into_iter()
            .flat_map(|kernels| [(kernels, RayBudgets::DEFAULT), (kernels, budgets)]);
        for (kernels, budgets) in ways {
            let mut gpu = GpuRenderer::with_budgets(
                context.clone(),
                &flat,
                flat.features(),
                kernels,
                budgets,
            )
            .unwrap();
            let output = common::render_clean(&flat, &mut gpu);
            let same = output
                .sample_counts
                .iter()
                .zip(&whole.sample_counts)
                .filter(|(a, b)| a == b)
                .count();
            // Adaptive decisions may differ where float sums cross the target; the AOVs are
            // means over the samples taken, the same where the counts are.
            assert!(same * 100 >= 99 * whole.sample_counts.len());
            let (g, c) = (output.aovs.as_ref().unwrap(), reference);
            for i in
                (0..g.depth.len()).filter(|&i| output.sample_counts[i] == whole.sample_counts[i])
            {
                let close = |p: f32, q: f32| (p - q).abs() <= 1e-4 * p.abs().max(q.abs()) + 1e-6;
                assert!(close(g.depth[i], c.depth[i]), "GPU depth at {i}");
                assert!((g.normal[i] - c.normal[i]).abs().max_element() < 1e-5);
                assert!((g.albedo[i] - c.albedo[i]).abs().max_element() < 1e-6);
            }
        }
    }
}

#[test]
fn the_exr_carries_the_layers_as_named_channels() {
    let dir = std::env::temp_dir().join(format!("chambre-aov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("aov.toml"), SCENE).unwrap();
    let image = dir.join("aov.exr");
    let status = Command::new(env!("CARGO_BIN_EXE_chambre"))
        .args([
            "render",
            "--backend",
            "cpu",
            "--aov",
            "depth,normal,albedo,samples",
            "-o",
        ])
        .arg(&image)
        .arg(dir.join("aov.toml"))
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    use exr::prelude::*;
    let read = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(&image)
        .unwrap();
    let channels = &read.layer_data.channel_data.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    for name in [
        "R",
        "G",
        "B",
        "depth.Z",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "samples.Y",
    ] {
        assert!(
            names.iter().any(|n| n == name),
            "{name} missing from {names:?}"
        );
    }
    let channel = |name: &str| -> Vec<f32> {
        let c = channels
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap();
        c.sample_data.values_as_f32().collect()
    };
    // The library's layers, written as they are.
    let flat = scene(&[]);
    let output = common::render_clean(&flat, &mut CpuRenderer::new(&flat));
    let aovs = output.aovs.unwrap();
    assert_eq!(channel("depth.Z"), aovs.depth);
    let normal_z: Vec<f32> = aovs.normal.iter().map(|n| n.z).collect();
    assert_eq!(channel("normal.Z"), normal_z);
    assert!(channel("samples.Y").iter().all(|&n| n == 4.0));
    // An 8-bit image cannot hold them.
    let refused = Command::new(env!("CARGO_BIN_EXE_chambre"))
        .args(["render", "--aov", "depth", "-o"])
        .arg(dir.join("aov.png"))
        .arg(dir.join("aov.toml"))
        .output()
        .unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("give -o an .exr path"));
    assert!(!dir.join("aov.png").exists());
}
