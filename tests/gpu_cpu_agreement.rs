//! The GPU kernel and the CPU reference render the same scenes to the same image:
//! at least 99.5% of pixels within 1e-3 (relative, linear) and mean absolute difference < 1e-4.

mod common;

fn check(path: &str, overrides: &[&str]) {
    let Some((cpu, gpu)) = common::render_both(path, overrides) else {
        return;
    };
    assert_eq!(
        cpu.non_finite_count(),
        0,
        "{path}: CPU image has non-finite pixels"
    );
    assert_eq!(
        gpu.non_finite_count(),
        0,
        "{path}: GPU image has non-finite pixels"
    );
    let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
    eprintln!(
        "{path}: {:.4}% of pixels within 1e-3, mean |diff| {mean_abs:.3e}",
        within * 100.0
    );
    assert!(
        within >= 0.995 && mean_abs < 1e-4,
        "{path}: only {:.3}% of pixels agree within 1e-3 (need 99.5%), mean |diff| {mean_abs:.3e} (need < 1e-4)",
        within * 100.0
    );
}

#[test]
fn spheres_agree() {
    check(
        "scenes/spheres.toml",
        &["render.width=192", "render.height=128", "render.spp=4"],
    );
}

#[test]
fn bunny_mesh_agrees() {
    check(
        "scenes/bunny.toml",
        &["render.width=192", "render.height=128", "render.spp=4"],
    );
}

#[test]
fn mirrors_with_many_bounces_agree() {
    check(
        "scenes/mirrors.toml",
        &["render.width=192", "render.height=128", "render.spp=2"],
    );
}

#[test]
fn area_light_soft_shadows_agree() {
    check(
        "scenes/area_light.toml",
        &["render.width=128", "render.height=128", "render.spp=2"],
    );
}

#[test]
fn thin_lens_agrees() {
    check(
        "scenes/thin_lens.toml",
        &["render.width=192", "render.height=128", "render.spp=8"],
    );
}

#[test]
fn phong_mix_agrees() {
    check(
        "scenes/phong.toml",
        &["render.width=192", "render.height=128", "render.spp=4"],
    );
}

#[test]
fn random_pixel_sampler_agrees() {
    check(
        "scenes/spheres.toml",
        &[
            "render.width=96",
            "render.height=64",
            "render.spp=3",
            "render.pixel_sampler=random",
        ],
    );
}
