//! Adaptive sampling (`render.noise_target`): it meets its target with fewer samples than
//! uniform sampling needs, puts the samples where the variance is, its estimate matches the
//! error against a converged reference, and the GPU makes the CPU's decisions.

use chambre::adaptive::pixel_error;
use chambre::cpu::CpuRenderer;
use chambre::gpu::GpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::pack::{FlatScene, flatten};
use chambre::render::{Image, RayBudgets, RenderOutput};

mod common;

/// The soft-shadow stress scene, small: a large area light, one light sample per hit, so the
/// penumbrae carry most of the variance.
const SCENE: &str = "scenes/converge/soft_shadows.toml";
const TARGET: f32 = 0.05;
const MAX_SPP: u32 = 512;

fn adaptive_scene(extra: &[&str]) -> FlatScene {
    let mut overrides = vec![
        "render.width=48",
        "render.height=48",
        "render.noise_target=0.05",
        "render.min_spp=16",
    ];
    let spp = format!("render.spp={MAX_SPP}");
    overrides.push(&spp);
    overrides.extend_from_slice(extra);
    flatten(&common::load(SCENE, &overrides))
}

fn cpu(flat: &FlatScene) -> RenderOutput {
    common::render_clean(flat, &mut CpuRenderer::new(flat))
}

/// The converged image: uniform sampling at 4096 spp.
fn reference() -> Image {
    let flat = flatten(&common::load(
        SCENE,
        &["render.width=48", "render.height=48", "render.spp=4096"],
    ));
    cpu(&flat).image
}

/// The error measure of `adaptive.rs` (summed channel error over the root of the intensity),
/// of `image` against `reference`, pixel by pixel.
fn normalised_errors(image: &Image, reference: &Image) -> Vec<f32> {
    image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, r)| {
            let difference = (*p - *r).abs();
            (difference.x + difference.y + difference.z)
                / (1e-4 + (r.x + r.y + r.z).max(0.0).sqrt())
        })
        .collect()
}

#[test]
fn adaptive_sampling_meets_its_target_with_half_the_samples_uniform_sampling_needs() {
    let flat = adaptive_scene(&[]);
    let output = cpu(&flat);
    let report = output.adaptive.as_ref().expect("an adaptive report");
    let pixels = output.sample_counts.len();
    assert_eq!(report.pixels, pixels);
    // Every pixel meets the target, or took every sample it was allowed.
    let converged = report.pixels_converged;
    let at_max = output
        .sample_counts
        .iter()
        .filter(|&&n| n == MAX_SPP)
        .count();
    assert!(
        converged + at_max >= pixels,
        "{converged} converged and {at_max} at the maximum of {pixels}"
    );
    // The few that do not are at the emitter's edge, where half the samples see it.
    assert!(converged as f64 >= 0.9 * pixels as f64, "{report:?}");
    // Uniform sampling meets the target everywhere only with the samples of the slowest
    // converged pixel in every pixel.
    let slowest = output.sample_counts.iter().copied().max().unwrap();
    assert!(
        report.mean_spp <= 0.5 * slowest as f64,
        "mean {} spp against {slowest} for uniform sampling",
        report.mean_spp
    );
    assert!(output.samples_per_pixel >= 16, "min_spp is every pixel's");
    // The estimate is honest: the error against the converged reference, in the same measure,
    // is on average below the target (a standard error below the target gives a mean absolute
    // error of about 0.8 of it, before the reference's own noise).
    let errors = normalised_errors(&output.image, &reference());
    let mean = errors.iter().sum::<f32>() / errors.len() as f32;
    assert!(mean < TARGET, "mean error against the reference {mean}");
    assert!(
        (report.mean_error as f64) < TARGET as f64,
        "mean estimate {}",
        report.mean_error
    );
}

#[test]
fn adaptive_sampling_spends_its_samples_where_the_variance_is() {
    // Each pixel's standard deviation over renders with eight seeds (in the measure adaptive
    // sampling steers by: summed over the channels, over the root of the intensity).
    let renders: Vec<Image> = (1..=8)
        .map(|seed| {
            let seed = format!("render.seed={seed}");
            let overrides = [
                "render.width=48",
                "render.height=48",
                "render.spp=32",
                &seed,
            ];
            cpu(&flatten(&common::load(SCENE, &overrides))).image
        })
        .collect();
    let noise: Vec<f32> = (0..renders[0].pixels.len())
        .map(|p| {
            let values: Vec<glam::Vec3> = renders.iter().map(|r| r.pixels[p]).collect();
            let mean = values.iter().sum::<glam::Vec3>() / values.len() as f32;
            let variance = values
                .iter()
                .map(|v| (*v - mean) * (*v - mean))
                .sum::<glam::Vec3>()
                / (values.len() - 1) as f32;
            let deviation = variance.x.sqrt() + variance.y.sqrt() + variance.z.sqrt();
            deviation / (1e-4 + mean.element_sum().max(0.0).sqrt())
        })
        .collect();
    let counts = cpu(&adaptive_scene(&[])).sample_counts;
    let mut order: Vec<usize> = (0..noise.len()).collect();
    order.sort_by(|&i, &j| noise[i].total_cmp(&noise[j]));
    let quarter = order.len() / 4;
    let mean_count = |pixels: &[usize]| {
        pixels.iter().map(|&p| counts[p] as f64).sum::<f64>() / pixels.len() as f64
    };
    let (quiet, noisy) = (
        mean_count(&order[..quarter]),
        mean_count(&order[order.len() - quarter..]),
    );
    assert!(
        noisy > 3.0 * quiet,
        "noisiest quarter {noisy} spp, quietest quarter {quiet} spp"
    );
}

#[test]
fn the_gpu_makes_the_cpu_paths_decisions() {
    let Some(context) = common::gpu_context() else {
        return;
    };
    let flat = adaptive_scene(&[]);
    let cpu = cpu(&flat);
    let gpu = common::render_clean(&flat, &mut GpuRenderer::new(context, &flat).unwrap());
    assert_same_render(&cpu, &gpu, "GPU");
}

#[test]
fn light_windows_and_a_crop_window_keep_the_decisions() {
    // Small budgets split each sample's 8 light samples into windows (the scratch sums sit
    // after both halves), and the crop window narrows the pixels decided.
    let flat = adaptive_scene(&["lights[0].samples=8", "render.crop=[0.25, 0.75, 0.5, 1.0]"]);
    let budgets = RayBudgets {
        per_invocation: 4,
        ..RayBudgets::DEFAULT
    };
    let plan = chambre::render::plan_passes(&flat, &budgets);
    assert!(plan.light_windows.len() > 1, "{plan:?}");
    let whole = cpu(&flat);
    assert_eq!(whole.sample_counts.len(), 24 * 24);
    let split = common::render_clean(&flat, &mut CpuRenderer::new(&flat).with_budgets(budgets));
    assert_same_render(&whole, &split, "split into light windows");
    if let Some(context) = common::gpu_context() {
        let features = flat.features();
        for kernels in [PathKernels::Megakernel, PathKernels::Wavefront] {
            let mut gpu =
                GpuRenderer::with_budgets(context.clone(), &flat, features, kernels, budgets)
                    .unwrap();
            let what = format!("GPU ({kernels:?}), split");
            assert_same_render(&whole, &common::render_clean(&flat, &mut gpu), &what);
        }
    }
}

/// Two renders of one adaptive scene: the same samples in (nearly) every pixel, images within
/// the GPU/CPU agreement tolerance, and the error reports alike.
fn assert_same_render(a: &RenderOutput, b: &RenderOutput, what: &str) {
    let same = a
        .sample_counts
        .iter()
        .zip(&b.sample_counts)
        .filter(|(m, n)| m == n)
        .count();
    let pixels = a.sample_counts.len();
    // Sums in another order can move an estimate across the target; a decision differs then
    // for that pixel and its neighbours.
    assert!(
        same as f64 >= 0.99 * pixels as f64,
        "{what}: {same} of {pixels} pixels got the same samples"
    );
    let (within, _) = common::agreement(&a.image, &b.image, 1e-3);
    assert!(within >= 0.99, "{what}: {within} of the pixels agree");
    let (ra, rb) = (a.adaptive.as_ref().unwrap(), b.adaptive.as_ref().unwrap());
    assert!(
        (ra.mean_spp - rb.mean_spp).abs() <= 0.01 * ra.mean_spp,
        "{what}: {ra:?} against {rb:?}"
    );
}

#[test]
fn the_estimate_of_a_constant_pixel_is_zero_and_of_a_noisy_one_its_standard_error() {
    // A pixel of mean 1 (each channel) with Bernoulli samples 0 or 2: sigma 1 per channel. Over
    // 2 x 5000 samples the estimate is |a - b| / 2 summed over channels, over sqrt(3): its mean
    // is 3 * sqrt(2/pi) / sqrt(10000) / sqrt(3).
    let mut rng = chambre::math::rng::Rng::new(3, 7, 11);
    let mut half = || {
        let mut sum = [0f32; 4];
        for _ in 0..5000 {
            let value = if rng.next_f32() < 0.5 { 0.0 } else { 2.0 };
            for s in &mut sum[..3] {
                *s += value;
            }
            sum[3] += 1.0;
        }
        sum
    };
    let trials = 2000;
    let mean: f32 = (0..trials)
        .map(|_| pixel_error(half(), half()))
        .sum::<f32>()
        / trials as f32;
    let expected = 3.0 * (2.0 / std::f32::consts::PI).sqrt() / 100.0 / 3f32.sqrt();
    // 2000 trials of a half-normal: the mean's relative deviation is 1.7%, so 10% is 6 sigma.
    assert!(
        (mean - expected).abs() < 0.1 * expected,
        "{mean} against {expected}"
    );
    assert_eq!(pixel_error([4.0, 4.0, 4.0, 4.0], [4.0, 4.0, 4.0, 4.0]), 0.0);
}
