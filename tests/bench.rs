//! `chambre bench` runs end to end on a small mesh, and its JSON holds every field with sane
//! values: the same rays give the same checksum on every backend. No timing is asserted.

mod common;

use std::process::Command;

/// Runs `chambre bench ARGS --json JSON`; checks the exit and that the table has `header`.
fn run_bench(args: &[&str], json: &std::path::Path, header: &str) -> serde_json::Value {
    let output = Command::new(env!("CARGO_BIN_EXE_chambre"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench"])
        .args(args)
        .arg("--json")
        .arg(json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let table = String::from_utf8_lossy(&output.stdout);
    assert!(table.contains(header), "{table}");
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

#[test]
fn bench_rays_reports_the_same_checksum_on_every_backend() {
    // The GPU must be there: the helper fails without an adapter (see common::gpu_context).
    drop(common::gpu_context());
    let json = std::env::temp_dir().join(format!("chambre-bench-{}.json", std::process::id()));
    let report = run_bench(
        &[
            "rays",
            "--mesh",
            "scenes/meshes/bunny-npm-lowres.obj",
            "--position",
            "0",
            "0",
            "30",
            "--look-at",
            "0",
            "0",
            "0",
            "--width",
            "48",
            "--height",
            "32",
            "--frames",
            "2",
            "--runs",
            "2",
            "--backends",
            "cpu,gpu",
        ],
        &json,
        "| rays | query | backend |",
    );
    let machine = &report["machine"];
    assert!(machine["cpu_threads"].as_u64().unwrap() >= 1);
    assert_eq!(machine["date_utc"].as_str().unwrap().len(), 10);
    assert!(report["command"].as_str().unwrap().contains("bench rays"));
    let body = &report["report"];
    assert_eq!(body["triangles"].as_u64(), Some(3674));
    assert!(body["bvh_build_ms"].as_f64().unwrap() > 0.0);
    assert!(body["cwbvh_build_ms"].as_f64().unwrap() > 0.0);
    let (bvh2_nodes, cwbvh_nodes) = (
        body["bvh2_nodes"].as_u64().unwrap(),
        body["cwbvh_nodes"].as_u64().unwrap(),
    );
    assert!(0 < cwbvh_nodes && cwbvh_nodes < bvh2_nodes);
    let cwbvh_reads = body["cwbvh_reads"].as_array().unwrap();
    assert_eq!(cwbvh_reads.len(), 2, "one per ray set");
    for reads in cwbvh_reads {
        let nodes = reads["nodes_per_ray"].as_f64().unwrap();
        let prims = reads["prims_per_ray"].as_f64().unwrap();
        // Every ray reads the root; a hit needs a primitive test.
        assert!(nodes >= 1.0 && prims > 0.0, "{reads}");
        let bytes = reads["bytes_per_ray"].as_f64().unwrap();
        assert!((bytes - (80.0 * nodes + 48.0 * prims + 36.0)).abs() < 1e-6 * bytes);
    }
    let set_up = body["set_up"].as_array().unwrap();
    assert_eq!(set_up.len(), 2, "one per ray set");
    for s in set_up {
        let m = &s["mrays_per_s"];
        assert!(m["min"].as_f64().unwrap() > 0.0, "{s}");
        assert!(m["min"].as_f64() <= m["median"].as_f64(), "{s}");
    }
    let results = body["results"].as_array().unwrap();
    assert_eq!(
        results.len(),
        28,
        "2 sets x 2 queries x (2 backends x 2 BVH layouts + the CPU's wide BVH, one ray, \
         packets and streams at a time)"
    );
    for r in results {
        assert_eq!(r["rays"].as_u64(), Some(48 * 32 * 2));
        let m = &r["mrays_per_s"];
        let (min, median, max) = (
            m["min"].as_f64().unwrap(),
            m["median"].as_f64().unwrap(),
            m["max"].as_f64().unwrap(),
        );
        assert!(0.0 < min && min <= median && median <= max, "{m}");
        let hits = r["checksum"]["hits"].as_u64().unwrap();
        assert!(hits > 0 && hits < 48 * 32 * 2, "{r}");
        // The same set and query traced by the other backends and BVH layouts found the same
        // hits.
        let twins = results.iter().filter(|o| {
            o["set"] == r["set"]
                && o["query"] == r["query"]
                && (o["backend"] != r["backend"] || o["bvh"] != r["bvh"])
        });
        assert_eq!(twins.clone().count(), 6);
        let a = r["checksum"]["sum_t"].as_f64().unwrap();
        for twin in twins {
            assert_eq!(
                twin["checksum"]["hits"], r["checksum"]["hits"],
                "{r} vs {twin}"
            );
            let b = twin["checksum"]["sum_t"].as_f64().unwrap();
            assert!((a - b).abs() <= 1e-5 * a.abs(), "{a} vs {b}");
        }
        if r["query"] == "any_hit" {
            assert_eq!(a, 0.0);
        } else {
            assert!(a > 0.0);
        }
    }
}

/// `--rays` and `--queries` trace only the sets and queries asked for, in the order asked.
#[test]
fn bench_rays_traces_only_the_sets_and_queries_asked_for() {
    let json = std::env::temp_dir().join(format!("chambre-bench-some-{}.json", std::process::id()));
    let report = run_bench(
        &[
            "rays",
            "--mesh",
            "scenes/meshes/bunny-npm-lowres.obj",
            "--width",
            "16",
            "--height",
            "8",
            "--frames",
            "1",
            "--runs",
            "1",
            "--backends",
            "cpu",
            "--bvh",
            "wide,stream",
            "--rays",
            "incoherent",
            "--queries",
            "any,closest",
        ],
        &json,
        "| rays | query | backend |",
    );
    let body = &report["report"];
    let rows: Vec<(&str, &str)> = body["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| (r["set"].as_str().unwrap(), r["query"].as_str().unwrap()))
        .collect();
    let asked = [("incoherent", "any_hit"), ("incoherent", "closest_hit")];
    assert_eq!(
        rows,
        [asked, asked].concat(),
        "one row per BVH, set and query"
    );
    let set_up = body["set_up"].as_array().unwrap();
    assert_eq!(set_up.len(), 1);
    assert_eq!(set_up[0]["set"], "incoherent");
}

#[test]
fn bench_scale_measures_each_size_and_plots_them() {
    drop(common::gpu_context());
    let dir = std::env::temp_dir().join(format!("chambre-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let plot = dir.join("scale.svg");
    let report = run_bench(
        &[
            "scale",
            "--mesh",
            "scenes/meshes/bunny-npm-lowres.obj",
            "--prefixes",
            "100,1000",
            "--copies",
            "2",
            "--pad-mib",
            "1",
            "--size",
            "32",
            "--runs",
            "1",
            "--plot",
            plot.to_str().unwrap(),
        ],
        &dir.join("scale.json"),
        "| triangles | padding MiB | build ms |",
    );
    let results = report["report"]["results"].as_array().unwrap();
    let triangles: Vec<u64> = results
        .iter()
        .map(|r| r["triangles"].as_u64().unwrap())
        .collect();
    assert_eq!(triangles, [100, 1000, 2 * 3674, 3674]);
    // The padded mesh: the whole mesh's tree over a buffer a MiB larger.
    let padded = &results[3];
    assert_eq!(padded["padding_bytes"], 1 << 20, "{padded}");
    assert!(padded["scene_bytes"].as_u64().unwrap() >= (1 << 20) + 48 * 3674);
    for r in results {
        assert!(r["cpu_mrays_per_s"]["median"].as_f64().unwrap() > 0.0);
        assert!(
            r["gpu_mrays_per_s"]["median"].as_f64().unwrap() > 0.0,
            "{r}"
        );
        assert!(r["bvh_nodes"].as_u64().unwrap() >= 1);
        assert!(r["scene_bytes"].as_u64().unwrap() >= 48 * r["triangles"].as_u64().unwrap());
        // The renderer's layouts: the CPU's packets through the wide BVH, the GPU's CWBVH.
        assert_eq!(r["cpu_bvh"], "packets", "{r}");
        assert_eq!(r["gpu_bvh"], "cwbvh", "{r}");
        assert!(r["wide_build_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("closest-hit throughput"));
}

/// `bench precision`: at unit scale near the origin both paths are within a few ULPs of the f64
/// oracle; far from the origin the error grows with the offset; tiny and huge scales alone
/// change nothing (chambre's offsets are relative).
#[test]
fn bench_precision_measures_f32_error_against_an_f64_oracle() {
    drop(common::gpu_context());
    let json = std::env::temp_dir().join(format!("chambre-precision-{}.json", std::process::id()));
    let report = run_bench(
        &["precision", "--size", "32", "--backends", "cpu,gpu"],
        &json,
        "| offset | scale | rays |",
    );
    let results = report["report"]["results"].as_array().unwrap();
    assert_eq!(results.len(), 7);
    let field = |r: &serde_json::Value, path: &str, name: &str| r[path][name].as_f64().unwrap();
    for r in results {
        assert!(r["oracle_hits"].as_u64().unwrap() > 50, "{r}");
        // Both paths trace the same f32 scene and rays to the same distances.
        for name in ["median_relative_t", "max_relative_t", "median_point_error"] {
            let (c, g) = (field(r, "cpu", name), field(r, "gpu", name));
            assert!(
                (c - g).abs() <= 1e-3 * c.max(1e-12) + 1e-9,
                "{name}: {c} {g}"
            );
        }
    }
    let median_point = |i: usize| field(&results[i], "cpu", "median_point_error");
    // Offsets 0, 1e2, 1e4, 1e6 at unit scale.
    assert!(field(&results[0], "cpu", "max_relative_t") < 1e-5);
    assert_eq!(results[0]["cpu"]["hit_disagreements"].as_u64(), Some(0));
    assert!(median_point(0) < median_point(2) && median_point(2) < median_point(3));
    assert!(
        median_point(3) > 1e-4,
        "f32 at 1e6 cannot hold the mesh to 1e-4 of its size"
    );
    // Scales 1e-4 and 1e4 at the origin: the unit scale's error, within 2x.
    for i in [4, 5] {
        assert!(
            median_point(i) < 2.0 * median_point(0) + 1e-9,
            "{}",
            median_point(i)
        );
    }
    // Pixel values: the renderer's shading (both paths) against the oracle's independent f64
    // Lambert. Near the origin a few ULPs everywhere; far away the error grows.
    let pixels = |i: usize, path: &str| &results[i][format!("{path}_pixels")];
    let pixel = |i: usize, path: &str, name: &str| pixels(i, path)[name].as_f64().unwrap();
    for path in ["cpu", "gpu"] {
        let lit = pixels(0, path)["lit"].as_u64().unwrap();
        assert!(lit > 50, "{path}: {lit} lit pixels");
        let disagreements = pixels(0, path)["disagreements"].as_u64().unwrap();
        assert!(
            disagreements * 100 <= lit,
            "{path}: {disagreements} of {lit}"
        );
        assert!(pixel(0, path, "median_relative") < 1e-5, "{path}");
        assert!(pixel(0, path, "max_relative") < 1e-3, "{path}");
        assert!(pixel(0, path, "median_relative") < pixel(2, path, "median_relative"));
        assert!(pixel(2, path, "median_relative") < pixel(3, path, "median_relative"));
        for i in [4, 5] {
            assert!(
                pixel(i, path, "median_relative") < 1e-5,
                "{path}, scale {i}"
            );
        }
    }
}

/// `bench motion`: every slicing of the shutter finds the same hits at the same distances (a
/// ray's geometry depends on its time, not on which BVH bounds it).
#[test]
fn bench_motion_finds_the_same_hits_with_every_slicing() {
    let json = std::env::temp_dir().join(format!("chambre-motion-{}.json", std::process::id()));
    let report = run_bench(
        &["motion", "--size", "48", "--slices", "1,3,8", "--runs", "1"],
        &json,
        "| slices | build ms |",
    );
    let results = report["report"]["results"].as_array().unwrap();
    assert_eq!(results.len(), 3);
    let hits: Vec<u64> = results
        .iter()
        .map(|r| r["hits"].as_u64().unwrap())
        .collect();
    assert!(hits[0] > 100, "{hits:?}");
    assert!(hits.iter().all(|&h| h == hits[0]), "{hits:?}");
    let t: Vec<f64> = results
        .iter()
        .map(|r| r["t_sum"].as_f64().unwrap())
        .collect();
    assert!(t.iter().all(|&x| (x - t[0]).abs() <= 1e-9 * t[0]), "{t:?}");
}

/// `bench fermat --self-reflections` reports the tolerance in its table's title and its JSON,
/// and the teapot reflects more triangles (its own) than without, with the same features
/// measured (the floor's).
#[test]
fn bench_fermat_measures_a_mirror_reflecting_itself() {
    drop(common::gpu_context());
    let run = |extra: &[&str], header: &str| {
        let json = std::env::temp_dir().join(format!(
            "chambre-fermat-{}-{}.json",
            std::process::id(),
            extra.len()
        ));
        let args: Vec<&str> = [
            "fermat",
            "--scene",
            "scenes/fermat_teapot.toml",
            "--subdivisions",
            "1",
            "--runs",
            "1",
            "--frames",
            "1",
            "--reference-spp",
            "1",
            "-D",
            "render.width=64",
            "-D",
            "render.height=48",
        ]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
        run_bench(&args, &json, header)["report"].clone()
    };
    let without = run(&[], "curved shapes within 0.5 px\n");
    let with = run(&["--self-reflections", "2"], "self-reflections within 2 px");
    assert!(without["self_reflections"].is_null(), "{without}");
    assert_eq!(with["self_reflections"].as_f64(), Some(2.0));
    let row = |r: &serde_json::Value, name: &str| r["rows"][0][name].as_u64().unwrap();
    assert!(row(&with, "reflected_triangles") > row(&without, "reflected_triangles"));
    assert_eq!(row(&with, "features"), row(&without, "features"));
}
