//! OBJ material libraries: per-face materials mapped from `Kd`, `Ks`, `Ns`, `illum`, and `Ke`
//! emitters becoming triangle area lights, on both paths.

mod common;

use std::path::PathBuf;

use chambre::layout::{FEATURE_AREA_LIGHTS, LIGHT_TRIANGLE};
use chambre::pack::flatten;
use chambre::scene::mesh::load_mesh;

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
