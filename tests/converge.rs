//! `chambre converge` end to end on a small scene: a row per run, error falling with samples at
//! Monte Carlo's rate for random patterns and faster for Sobol, both paths alike, the plot.

mod common;

use std::process::Command;

#[test]
fn converge_measures_the_error_of_each_pattern_and_backend() {
    drop(common::gpu_context());
    let dir = std::env::temp_dir().join(format!("chambre-converge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, plot) = (dir.join("c.csv"), dir.join("c.svg"));
    let output = Command::new(env!("CARGO_BIN_EXE_chambre"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "converge",
            "scenes/area_light.toml",
            "-D",
            "render.width=32",
        ])
        .args([
            "-D",
            "render.height=32",
            "--reference-spp",
            "512",
            "--max-spp",
            "32",
            "--noise-targets",
            "0.05",
        ])
        .args([
            "--samplers",
            "random,sobol",
            "--backends",
            "cpu,gpu",
            "--csv",
        ])
        .arg(&csv)
        .arg("--plot")
        .arg(&plot)
        .arg("--plot")
        .arg(dir.join("c.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("# ") && text.contains("converge scenes/area_light.toml"));
    assert!(text.contains("adapter: ") && text.contains("reference rendered"));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(
        lines.next(),
        Some(
            "backend,sampler,mode,spp,mean_spp,noise_target,wall_ms,kernel_ms,rays,rmse,rel_mse,flip"
        )
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(
        rows.len(),
        2 * 2 * 7,
        "2 backends x 2 patterns x (1..32 spp and one adaptive run)"
    );
    let (spp_column, mean_spp, rays, rmse_column, flip_column) = (3, 4, 8, 9, 11);
    let value = |row: &Vec<String>, i: usize| row[i].parse::<f64>().unwrap();
    let curve = |backend: &str, sampler: &str, mode: &str| -> Vec<&Vec<String>> {
        rows.iter()
            .filter(|r| r[0] == backend && r[1] == sampler && r[2] == mode)
            .collect()
    };
    for backend in ["cpu", "gpu"] {
        for sampler in ["random", "sobol"] {
            let c = curve(backend, sampler, "uniform");
            let spp: Vec<f64> = c.iter().map(|r| value(r, spp_column)).collect();
            assert_eq!(spp, [1.0, 2.0, 4.0, 8.0, 16.0, 32.0]);
            let means: Vec<f64> = c.iter().map(|r| value(r, mean_spp)).collect();
            assert_eq!(means, spp, "uniform sampling gives every pixel its samples");
            let rmse: Vec<f64> = c.iter().map(|r| value(r, rmse_column)).collect();
            let flip: Vec<f64> = c.iter().map(|r| value(r, flip_column)).collect();
            assert!(c.iter().all(|r| value(r, rays) > 0.0), "rays counted");
            assert!(flip.iter().all(|f| (0.0..=1.0).contains(f)));
            // 16x the samples: a quarter of the error for random patterns, less for Sobol.
            assert!(rmse[4] < 0.4 * rmse[0], "{backend} {sampler}: {rmse:?}");
            assert!(flip[4] < flip[0], "{backend} {sampler}: {flip:?}");
            let points: Vec<(f64, f64)> = spp.iter().copied().zip(rmse.iter().copied()).collect();
            let slope = chambre::metrics::log_log_slope(&points);
            if sampler == "random" {
                assert!((-0.7..=-0.35).contains(&slope), "random slope {slope}");
            } else {
                assert!(slope < -0.6, "sobol slope {slope}");
            }
            // The adaptive run: from 16 (its first decision) to 32 samples a pixel, and less
            // error than uniform sampling's at 16 (the target, an image error of 5%, is beyond
            // what 16 samples reach, so pixels go on).
            let adaptive = curve(backend, sampler, "adaptive");
            assert_eq!(adaptive.len(), 1);
            let run = adaptive[0];
            assert_eq!((value(run, spp_column), value(run, 5)), (32.0, 0.05));
            assert!((16.0..=32.0).contains(&value(run, mean_spp)), "{run:?}");
            assert!(
                value(run, rmse_column) < rmse[4],
                "{run:?} against {rmse:?}"
            );
        }
    }
    // The same samples on both paths: the same errors.
    for mode in ["uniform", "adaptive"] {
        for (c, g) in curve("cpu", "sobol", mode)
            .iter()
            .zip(curve("gpu", "sobol", mode))
        {
            let (a, b) = (value(c, rmse_column), value(g, rmse_column));
            assert!((a - b).abs() <= 1e-3 * a, "{mode}: CPU {a} GPU {b}");
        }
    }
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("slope") && svg.contains("RMSE against time"));
    // The PNG: the figure's size, a white background, and the curves' colours drawn.
    let png = image::open(dir.join("c.png")).unwrap().into_rgb8();
    assert_eq!(png.dimensions(), (1100, 460));
    let count = |rgb: [u8; 3]| png.pixels().filter(|p| p.0 == rgb).count();
    assert!(count([255, 255, 255]) > png.len() / 3 / 2, "mostly white");
    for (name, colour) in [("blue", [0, 0, 255]), ("green", [0, 255, 0])] {
        assert!(count(colour) > 100, "no {name} curve in the PNG");
    }
}

/// The scenes shipped to stress the trade each stress what their names say.
#[test]
fn the_stress_scenes_load_with_what_they_stress() {
    use chambre::layout::{FEATURE_AREA_LIGHTS, FEATURE_LENS, FEATURE_MIRRORS};
    let features = |name: &str| {
        let scene = common::load(&format!("scenes/converge/{name}.toml"), &[]);
        let flat = chambre::pack::flatten(&scene);
        (scene, flat.features())
    };
    let (scene, f) = features("defocus_tilt");
    assert!(f & FEATURE_LENS != 0 && scene.camera.aperture_blades >= 5);
    assert!(scene.camera.f_number <= 1.4 && scene.camera.movements.lens_tilt != 0.0);
    let (scene, f) = features("soft_shadows");
    assert!(f & FEATURE_AREA_LIGHTS != 0 && f & FEATURE_LENS == 0);
    assert_eq!(scene.render.spp, 64);
    let (scene, f) = features("mirror_corridor");
    assert!(f & FEATURE_MIRRORS != 0 && scene.render.max_depth >= 16);
    let (scene, f) = features("checkerboard");
    assert_eq!(
        f & (FEATURE_LENS | FEATURE_AREA_LIGHTS | FEATURE_MIRRORS),
        0
    );
    assert!(scene.triangle_count() >= 512, "the 16x16 board");
}

/// A small CPU study into `dir` with `flags` after the CSV's: its stderr, and the files `dir`
/// then holds, sorted.
fn small_study(dir: &std::path::Path, flags: &[&str]) -> (std::process::Output, Vec<String>) {
    std::fs::create_dir_all(dir).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_chambre"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["converge", "scenes/area_light.toml", "-D", "render.width=8"])
        .args([
            "-D",
            "render.height=8",
            "--reference-spp",
            "8",
            "--max-spp",
            "2",
        ])
        .args(["--samplers", "random", "--csv"])
        .arg(dir.join("c.csv"))
        .args(flags)
        .output()
        .unwrap();
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    (output, files)
}

#[test]
fn the_plot_is_written_beside_the_csv_unless_no_plot_is_given() {
    let root = std::env::temp_dir().join(format!("chambre-converge-plot-{}", std::process::id()));
    let (output, files) = small_study(&root.join("default"), &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert_eq!(files, ["c.csv", "c.svg"]);
    let svg = std::fs::read_to_string(root.join("default/c.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("slope"), "{svg}");
    assert!(
        stderr.contains("c.csv, ") && stderr.contains("c.svg"),
        "{stderr}"
    );

    let (output, files) = small_study(&root.join("none"), &["--no-plot"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(files, ["c.csv"]);

    // Named plots replace the default one.
    let named = root.join("named");
    let (output, files) = small_study(&named, &["--plot", named.join("p.png").to_str().unwrap()]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(files, ["c.csv", "p.png"]);

    let (output, files) = small_study(&root.join("both"), &["--no-plot", "--plot", "x.svg"]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("cannot be used with"));
    assert!(files.is_empty(), "{files:?}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A reference given by `--reference` is read as radiance: chambre's own PFM as its EXR; a
/// PNG (display codes) is refused, and so is a reference with a NaN or negative pixel, named.
#[test]
fn a_given_reference_is_linear_finite_and_non_negative() {
    let dir = std::env::temp_dir().join(format!("chambre-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let chambre = || {
        let mut command = Command::new(env!("CARGO_BIN_EXE_chambre"));
        command.current_dir(env!("CARGO_MANIFEST_DIR"));
        command
    };
    let size = ["-D", "render.width=8", "-D", "render.height=8"];
    let converge = |reference: &std::path::Path| {
        chambre()
            .args(["converge", "scenes/area_light.toml"])
            .args(size)
            .args([
                "--max-spp",
                "1",
                "--samplers",
                "random",
                "--backends",
                "cpu",
            ])
            .arg("--no-plot")
            .arg("--csv")
            .arg(dir.join("c.csv"))
            .arg("--reference")
            .arg(reference)
            .output()
            .unwrap()
    };
    for name in ["ref.pfm", "ref.png"] {
        let output = chambre()
            .args([
                "render",
                "scenes/area_light.toml",
                "--backend",
                "cpu",
                "--spp",
                "4",
            ])
            .args(size)
            .arg("-o")
            .arg(dir.join(name))
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let output = converge(&dir.join("ref.pfm"));
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let output = converge(&dir.join("ref.png"));
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("a reference is a linear image"));
    // One pixel made NaN (the PFM's floats, bottom row first, follow a 12-byte header here).
    let mut bytes = std::fs::read(dir.join("ref.pfm")).unwrap();
    let header = b"PF\n8 8\n-1.0\n".len();
    bytes[header..header + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.join("nan.pfm"), bytes).unwrap();
    let output = converge(&dir.join("nan.pfm"));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("pixel (0, 7) is"), "{stderr}");
}
