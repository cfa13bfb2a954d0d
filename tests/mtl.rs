//! OBJ material libraries: per-face materials mapped from `Kd`, `Ks`, `Ns`, `illum`, and `Ke`
//! emitters becoming triangle area lights, on both paths.

mod common;

use std::path::PathBuf;

use chambre::layout::{FEATURE_AREA_LIGHTS, LIGHT_TRIANGLE};
use chambre::pack::flatten;
use chambre::scene::mesh_file::load_mesh;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-mtl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn the_cornell_boxs_library_gives_each_face_its_material_and_the_light_its_radiance() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/meshes/CornellBox-Original.obj");
    let mesh = load_mesh(&path).unwrap();
    assert_eq!(mesh.face_materials.len(), mesh.triangles.len());
    let named = |name: &str| mesh.materials.iter().find(|m| m.name == name).unwrap();
    assert_eq!(named("leftWall").diffuse.to_array(), [0.63, 0.065, 0.05]);
    assert_eq!(named("light").emission.to_array(), [17.0, 12.0, 4.0]);
    let light = mesh
        .materials
        .iter()
        .position(|m| m.name == "light")
        .unwrap() as u32;
    let emitting = mesh.face_materials.iter().filter(|&&m| m == light).count();
    assert_eq!(emitting, 2, "the light is a quad: two triangles");
    // The scene: two triangle lights, the scene's materials named after the file.
    let scene = common::load(
        "scenes/cornell_box.toml",
        &["render.width=32", "render.height=32"],
    );
    assert!(
        scene
            .materials
            .iter()
            .any(|m| m.name == "CornellBox-Original.obj:leftWall")
    );
    let flat = flatten(&scene);
    let lights: Vec<_> = flat
        .lights
        .iter()
        .filter(|l| l.kind == LIGHT_TRIANGLE)
        .collect();
    assert_eq!(lights.len(), 2);
    assert!(flat.features() & FEATURE_AREA_LIGHTS != 0);
    // A scene material given on the mesh overrides the file's: no emitter then.
    let overridden = common::load(
        "scenes/cornell_box.toml",
        &[
            "render.width=32",
            "render.height=32",
            "materials=[{name = \"grey\", model = \"lambert\"}]",
            "shapes[0].material=grey",
        ],
    );
    assert!(flatten(&overridden).lights.is_empty());
}

#[test]
fn the_cornell_box_renders_alike_on_both_paths() {
    let Some((cpu, gpu)) = common::render_both(
        "scenes/cornell_box.toml",
        &["render.width=48", "render.height=48", "render.spp=4"],
    ) else {
        return;
    };
    let lit = cpu.pixels.iter().filter(|p| p.x > 0.01).count();
    assert!(lit > 48 * 48 / 2, "{lit} lit pixels");
    let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
    assert!(within >= 0.995 && mean_abs < 1e-4, "{within} {mean_abs}");
}

/// A small emitting triangle 10 units above a Lambert floor: the radiance the floor reflects
/// below it is rho / pi * L * A / d^2 (both cosines 1, the triangle small against d), on both
/// paths, within 0.5%.
#[test]
fn a_triangle_light_gives_its_analytic_irradiance() {
    let obj = scratch("lamp.obj");
    std::fs::write(
        scratch("lamp.mtl"),
        "newmtl lamp\nKd 0 0 0\nKe 1000 1000 1000\n",
    )
    .unwrap();
    // Wound so its normal points down, towards the floor.
    std::fs::write(
        &obj,
        "mtllib lamp.mtl\nusemtl lamp\nv -0.05 10 -0.05\nv 0.05 10 -0.05\nv -0.05 10 0.05\nf 1 2 3\n",
    )
    .unwrap();
    let text = format!(
        "[render]\nwidth = 1\nheight = 1\nspp = 64\nmax_depth = 0\n\
         [camera]\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         vertical_fov = 0.001\nfilm = [24.0, 24.0]\n\
         [[materials]]\nname = \"floor\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\
         [[shapes]]\ntype = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\nmaterial = \"floor\"\n\
         [[shapes]]\ntype = \"mesh\"\nfile = {:?}\n",
        obj.to_str().unwrap()
    );
    let scene = chambre::scene::Scene::from_str(&scratch("lamp.toml"), &text, &[]).unwrap();
    let flat = flatten(&scene);
    // Area 0.005, radiance 1000, distance 10 (the triangle's centroid is off the axis by
    // 0.017, a cosine of 0.999997).
    let expected = 0.5 / std::f32::consts::PI * 1000.0 * 0.005 / 100.0;
    let cpu = common::render_cpu(&flat).pixels[0].x;
    assert!(
        (cpu / expected - 1.0).abs() < 5e-3,
        "CPU {cpu} against {expected}"
    );
    if let Some(gpu) = common::render_gpu(&flat) {
        let gpu = gpu.pixels[0].x;
        assert!(
            (gpu / expected - 1.0).abs() < 5e-3,
            "GPU {gpu} against {expected}"
        );
    }
}

/// A library's `Ke` that no radiance can be (beyond the scene's bound, not a number,
/// negative) is refused naming the mesh and its material, not clamped to a silent zero.
#[test]
fn an_emission_no_radiance_can_be_is_refused_naming_the_material() {
    for (name, ke) in [
        ("huge", "1e30 1 1"),
        ("nan", "nan 1 1"),
        ("negative", "-1 -1 -1"),
    ] {
        let dir = scratch(&format!("ke_{name}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("lamp.mtl"), format!("newmtl lamp\nKe {ke}\n")).unwrap();
        std::fs::write(
            dir.join("lamp.obj"),
            "mtllib lamp.mtl\nusemtl lamp\nv 0 1 0\nv 1 1 0\nv 0 1 1\nf 1 2 3\n",
        )
        .unwrap();
        let text = "[render]\nwidth = 4\nheight = 4\nspp = 1\n\
             [camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             film = [24.0, 24.0]\n[[shapes]]\ntype = \"mesh\"\nfile = \"lamp.obj\"\n";
        let error = chambre::scene::Scene::from_str(&dir.join("scene.toml"), text, &[])
            .err()
            .unwrap_or_else(|| panic!("Ke {ke} was accepted"))
            .to_string();
        for part in ["shapes[0]", "lamp.obj", "\"lamp\"", "Ke"] {
            assert!(error.contains(part), "Ke {ke}: `{part}` not in {error}");
        }
    }
}

/// A scene of one OBJ triangle in its own folder: `mtllib` lines for `libraries` (of which only
/// `present` exist beside it, each defining `red`), faces that `usemtl red`, and a scene
/// material `grey` given to the mesh when `scene_material`. Returns the scene file.
fn scene_with_libraries(
    folder: &str,
    libraries: &[&str],
    present: &[&str],
    scene_material: bool,
) -> PathBuf {
    let dir = scratch(folder);
    std::fs::create_dir_all(&dir).unwrap();
    for name in present {
        std::fs::write(dir.join(name), "newmtl red\nKd 0.8 0.1 0.1\n").unwrap();
    }
    let mut obj = String::from("# a triangle\n");
    for name in libraries {
        obj.push_str(&format!("mtllib {name}\n"));
    }
    obj.push_str("usemtl red\nv -1 0 -3\nv 1 0 -3\nv 0 1 -3\nf 1 2 3\n");
    std::fs::write(dir.join("tri.obj"), obj).unwrap();
    let material = match scene_material {
        true => "material = \"grey\"\n",
        false => "",
    };
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            "[render]\nwidth = 8\nheight = 8\nspp = 1\n\
             [camera]\nposition = [0.0, 0.3, 0.0]\nlook_at = [0.0, 0.3, -3.0]\n\
             vertical_fov = 40.0\nfilm = [24.0, 24.0]\n\
             [[materials]]\nname = \"grey\"\nmodel = \"lambert\"\n\
             [[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n\
             [[shapes]]\ntype = \"mesh\"\nfile = \"tri.obj\"\n{material}"
        ),
    )
    .unwrap();
    scene
}

fn check(scene: &std::path::Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_chambre"))
        .arg("check")
        .arg(scene)
        .output()
        .unwrap()
}

/// A missing `mtllib` is a warning with the OBJ's file and line where the scene gives the mesh
/// its own material (Blender and pbrt go on too), and the mesh renders with that material.
#[test]
fn a_missing_library_is_a_warning_when_the_scene_gives_the_mesh_a_material() {
    let scene = scene_with_libraries("warn", &["gone.mtl"], &[], true);
    let output = check(&scene);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let obj = scene.with_file_name("tri.obj");
    let expected = format!(
        "warning: {}:2: mtllib {}: ",
        obj.display(),
        scene.with_file_name("gone.mtl").display()
    );
    assert!(stderr.contains(&expected), "{expected} not in {stderr}");
    assert!(stderr.contains("No such file"), "{stderr}");
    assert!(
        stderr.contains("the scene's material `grey` is used"),
        "{stderr}"
    );
    let loaded = chambre::scene::Scene::load(&scene, &[]).unwrap();
    assert_eq!(loaded.warnings().len(), 1);
    let flat = flatten(&loaded);
    assert_eq!(flat.materials.len(), 1, "grey alone");
    let image = common::render_cpu(&flat);
    assert!(
        image.pixels.iter().any(|p| p.x > 0.0),
        "the triangle is lit"
    );
}

/// Where the faces' materials must come from the file, a missing library is an error naming the
/// scene's field, the OBJ's file and line, and the library.
#[test]
fn a_missing_library_is_an_error_when_the_files_materials_are_needed() {
    let scene = scene_with_libraries("refuse", &["gone.mtl"], &[], false);
    let output = check(&scene);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    let obj = scene.with_file_name("tri.obj");
    for part in [
        format!("{}:", scene.display()),
        "`shapes[0].material`".to_string(),
        format!(
            "{}:2: mtllib {}: No such file",
            obj.display(),
            scene.with_file_name("gone.mtl").display()
        ),
    ] {
        assert!(stderr.contains(&part), "{part} not in {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Two libraries, the missing one second: each face finds its material in the first, so the
    // file's materials are used and the missing one is only a warning, with its own line.
    let scene = scene_with_libraries("second", &["red.mtl", "gone.mtl"], &["red.mtl"], false);
    let output = check(&scene);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("tri.obj:3: mtllib "), "{stderr}");
    assert!(stderr.contains("no face of the mesh needs"), "{stderr}");
    let loaded = chambre::scene::Scene::load(&scene, &[]).unwrap();
    assert!(loaded.materials.iter().any(|m| m.name == "tri.obj:red"));
}

/// A library tobj refuses (a `map_Kd` with no file) is named with the line it refuses, found
/// again since tobj names none.
#[test]
fn a_malformed_library_names_its_line() {
    let scene = scene_with_libraries("malformed", &["bad.mtl"], &[], false);
    std::fs::write(
        scene.with_file_name("bad.mtl"),
        "newmtl red\nKd 0.8 0.1 0.1\n\nnewmtl blue\nKd 0.1 0.1 0.8\nmap_Kd\nKs 0 0 0\n",
    )
    .unwrap();
    let output = check(&scene);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    let expected = "malformed material library: line 6: `map_Kd`: material parse error";
    assert!(stderr.contains(expected), "{expected} not in {stderr}");
}
