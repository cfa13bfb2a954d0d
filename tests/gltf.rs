//! glTF 2.0 scenes: node transforms, the camera, KHR_lights_punctual and the material mapping
//! give a pixel its analytic value; `.glb` reads as `.gltf` does; a chambre scene can place a
//! glTF mesh under its own view camera; a file without camera or lights still renders; both
//! paths agree.

use std::path::{Path, PathBuf};

use chambre::pack::flatten;
use chambre::scene::Scene;
use chambre::scene::mesh_file::load_mesh;
use glam::Vec3;

mod common;

/// A unit quad (two triangles, normals +Z) in a buffer: 4 positions, 4 normals, 6 u16 indices.
fn quad_buffer() -> Vec<u8> {
    let mut bytes = Vec::new();
    for p in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..4 {
        for c in [0.0f32, 0.0, 1.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes
}

/// The glTF JSON: the quad scaled 2x and moved to z = -1; with `camera_and_light`, a camera
/// at z = 5 looking down -Z (yfov 0.6 rad, square) and a point light of 6830 cd at z = 3.
fn gltf_json(buffer_uri: Option<&str>, camera_and_light: bool) -> String {
    let uri = buffer_uri.map_or(String::new(), |u| format!(r#""uri": "{u}", "#));
    let (extra_nodes, scene_nodes, extensions) = if camera_and_light {
        (
            r#", {"camera": 0, "translation": [0, 0, 5]},
               {"translation": [0, 0, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
            "[0, 1, 2]",
            r#""extensionsUsed": ["KHR_lights_punctual"],
               "extensions": {"KHR_lights_punctual": {"lights": [
                   {"type": "point", "color": [1, 1, 1], "intensity": 6830}]}},
               "cameras": [{"type": "perspective",
                            "perspective": {"yfov": 0.6, "aspectRatio": 1.0, "znear": 0.01}}],"#,
        )
    } else {
        ("", "[0]", "")
    };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  {extensions}
  "scene": 0,
  "scenes": [{{"nodes": {scene_nodes}}}],
  "nodes": [{{"mesh": 0, "translation": [0, 0, -1], "scale": [2, 2, 2]}}{extra_nodes}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2,
                                 "material": 0}}]}}],
  "materials": [{{"name": "paint", "pbrMetallicRoughness": {{
      "baseColorFactor": [0.8, 0.2, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}}}],
  "buffers": [{{{uri}"byteLength": 108}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
      "min": [-1, -1, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}]
}}"#
    )
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-gltf-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `quad.gltf` with its buffer in `quad.bin`.
fn write_gltf(dir: &Path, camera_and_light: bool) -> PathBuf {
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let path = dir.join("quad.gltf");
    std::fs::write(&path, gltf_json(Some("quad.bin"), camera_and_light)).unwrap();
    path
}

/// The same content as one `.glb`: header, JSON chunk, BIN chunk (each padded to 4 bytes).
fn write_glb(dir: &Path) -> PathBuf {
    let mut json = gltf_json(None, true).into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin = quad_buffer();
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let path = dir.join("quad.glb");
    std::fs::write(&path, glb).unwrap();
    path
}

/// The centre pixel sees the quad's centre (0, 0, -1), 4 units below the light of
/// 6830 / 683 = 10 W/sr: irradiance 10 / 16. The material is diffuse (0.8, 0.2, 0.1) plus a
/// Blinn-Phong lobe of reflectance 0.04 and exponent 2 / 1 - 2 = 0, whose BRDF is 0.04 / pi.
fn expected_centre() -> Vec3 {
    (Vec3::new(0.8, 0.2, 0.1) + Vec3::splat(0.04)) / std::f32::consts::PI * (10.0 / 16.0)
}

#[test]
fn a_gltf_scene_renders_its_camera_light_and_material_analytically() {
    let dir = scratch("scene");
    for path in [write_gltf(&dir, true), write_glb(&dir)] {
        let scene = Scene::load(
            &path,
            &["render.width=33".into(), "render.height=33".into()],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.camera.position.z, 5.0, "{}", path.display());
        assert!(scene.notes().is_empty(), "{:?}", scene.notes());
        let flat = flatten(&scene);
        let image = common::render_cpu(&flat);
        let centre = image.get(16, 16);
        let expected = expected_centre();
        assert!(
            (centre - expected).abs().max_element() < 2e-3 * expected.max_element(),
            "{}: {centre} against {expected}",
            path.display()
        );
        // The quad spans x, y in [-2, 2] at 6 units: tan(0.3) * 6 = 1.86 < 2 fills the view.
        assert!(image.pixels.iter().all(|p| p.x > 0.0));
        if let Some(gpu) = common::render_gpu(&flat) {
            let (within, _) = common::agreement(&image, &gpu, 1e-3);
            assert!(within > 0.99, "{within}");
        }
    }
}

#[test]
fn a_gltf_mesh_takes_its_node_transform_and_materials() {
    let dir = scratch("mesh");
    let mesh = load_mesh(&write_gltf(&dir, false)).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    assert_eq!(
        (lo, hi),
        (Vec3::new(-2.0, -2.0, -1.0), Vec3::new(2.0, 2.0, -1.0))
    );
    assert_eq!(mesh.materials.len(), 1);
    let paint = &mesh.materials[0];
    assert_eq!(paint.name, "paint");
    assert_eq!(paint.diffuse, Vec3::new(0.8, 0.2, 0.1));
    assert_eq!(paint.specular, Vec3::splat(0.04));
    assert_eq!((paint.shininess, paint.mirror), (0.0, Vec3::ZERO));
    assert_eq!(mesh.face_materials, vec![0, 0]);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], Vec3::Z);
}

#[test]
fn metallic_smooth_is_a_mirror_and_roughness_sets_the_lobe() {
    use chambre::scene::gltf::map_factors;
    let gold = Vec3::new(1.0, 0.8, 0.3);
    let mirror = map_factors("m", gold, 1.0, 0.0, Vec3::ZERO);
    assert_eq!(
        (mirror.mirror, mirror.diffuse, mirror.specular),
        (gold, Vec3::ZERO, Vec3::ZERO)
    );
    // Roughness 0.5: alpha 0.25, exponent 2 / 0.0625 - 2 = 30; half metallic.
    let half = map_factors("h", gold, 0.5, 0.5, Vec3::ONE);
    assert!((half.shininess - 30.0).abs() < 1e-4);
    assert_eq!(half.diffuse, gold * 0.5);
    assert_eq!(half.specular, Vec3::splat(0.02) + gold * 0.5);
    assert_eq!(half.emission, Vec3::ONE);
    // A rough metal: GGX of the base colour, its roughness kept (alpha = roughness²).
    let metal = map_factors("r", gold, 1.0, 0.5, Vec3::ZERO);
    assert_eq!(
        (
            metal.conductor_roughness,
            metal.specular,
            metal.diffuse,
            metal.mirror
        ),
        (Some(0.5), gold, Vec3::ZERO, Vec3::ZERO)
    );
}

#[test]
fn a_chambre_scene_places_a_gltf_mesh_under_its_own_view_camera() {
    let dir = scratch("include");
    write_gltf(&dir, true);
    let text = r#"
[render]
width = 32
height = 32
spp = 2
[camera]
position = [0.0, 0.0, 6.0]
look_at = [0.0, 0.0, -1.0]
focal_length = 50.0
film = [24.0, 24.0]
film_tilt = 5.0
[[shapes]]
type = "mesh"
file = "quad.gltf"
[[lights]]
type = "point"
position = [0.0, 0.0, 3.0]
intensity = [10.0, 10.0, 10.0]
"#;
    let scene = Scene::from_str(&dir.join("scene.toml"), text, &[]).unwrap();
    assert_eq!(scene.camera.movements.film_tilt, 5.0);
    let image = common::render_cpu(&flatten(&scene));
    // The file's material: red dominates everywhere the quad is lit.
    assert!(image.pixels.iter().all(|p| p.x > 2.0 * p.y && p.x > 0.0));
}

#[test]
fn a_gltf_without_camera_or_lights_is_framed_and_lit() {
    let dir = scratch("bare");
    let path = write_gltf(&dir, false);
    let scene = Scene::load(&path, &[]).unwrap();
    assert_eq!(
        (scene.render.width, scene.render.height),
        (960, 720),
        "4:3 by default"
    );
    let small = ["render.width=48".into(), "render.height=36".into()];
    let flat = flatten(&Scene::load(&path, &small).unwrap());
    let image = common::render_cpu(&flat);
    let (w, h) = (image.width, image.height);
    // The framing camera looks at the quad's centre; the default light lights it.
    assert!(
        image.get(w / 2, h / 2).x > 0.05,
        "{}",
        image.get(w / 2, h / 2)
    );
    // The path tracer, which refuses ambient light, renders it with the key light alone, as
    // `--integrator path` (a bare word) or a quoted `--set` asks.
    assert_eq!(scene.render.ambient, Vec3::splat(0.1));
    for integrator in ["render.integrator=path", "render.integrator=\"path\""] {
        let overrides = [small[0].clone(), small[1].clone(), integrator.to_string()];
        let scene = Scene::load(&path, &overrides).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.render.ambient, Vec3::ZERO);
        let image = common::render_cpu(&flatten(&scene));
        assert!(image.get(w / 2, h / 2).x > 0.05, "{integrator}");
    }
}

#[test]
fn a_broken_gltf_names_the_file() {
    let dir = scratch("broken");
    let path = dir.join("broken.gltf");
    std::fs::write(&path, "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [").unwrap();
    let error = Scene::load(&path, &[]).unwrap_err().to_string();
    assert!(error.contains("broken.gltf"), "{error}");
    // A buffer that is not there.
    let dir = scratch("missing");
    std::fs::write(dir.join("quad.gltf"), gltf_json(Some("nowhere.bin"), true)).unwrap();
    let error = Scene::load(&dir.join("quad.gltf"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("quad.gltf") && error.contains("buffer"),
        "{error}"
    );
}

#[test]
fn a_gltf_spot_light_keeps_its_cone() {
    let dir = scratch("spot");
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let json = gltf_json(Some("quad.bin"), true).replace(
        r#"{"type": "point", "color": [1, 1, 1], "intensity": 6830}"#,
        r#"{"type": "spot", "color": [1, 1, 1], "intensity": 6830,
            "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.3}}"#,
    );
    assert!(json.contains("\"spot\""));
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = Scene::load(
        &path,
        &["render.width=33".into(), "render.height=33".into()],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    match scene.lights[0] {
        chambre::scene::Light::Spot {
            direction,
            inner_deg,
            outer_deg,
            ..
        } => {
            assert_eq!(direction, -Vec3::Z);
            assert!((inner_deg - 0.1f32.to_degrees()).abs() < 1e-4);
            assert!((outer_deg - 0.3f32.to_degrees()).abs() < 1e-4);
        }
        ref other => panic!("{other:?}"),
    }
    let image = common::render_cpu(&flatten(&scene));
    // On the axis, as the point light gave; the image's corner is 33° off the axis, beyond the
    // outer cone's 17.2°.
    let expected = expected_centre();
    assert!((image.get(16, 16) - expected).abs().max_element() < 2e-3 * expected.max_element());
    assert_eq!(image.get(0, 0), Vec3::ZERO);
}

#[test]
fn gltf_camera_names_the_camera_to_render_with() {
    let dir = scratch("named");
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    // A second camera node, named "side", 5 units along +x looking back at the origin.
    let json = gltf_json(Some("quad.bin"), true)
        .replace(
            r#""cameras": [{"type": "perspective","#,
            r#""cameras": [{"name": "side", "type": "perspective",
                            "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.01}},
                           {"name": "front", "type": "perspective","#,
        )
        .replace(
            r#"{"camera": 0, "translation": [0, 0, 5]}"#,
            r#"{"camera": 1, "translation": [0, 0, 5]},
            {"camera": 0, "translation": [5, 0, 0], "rotation": [0, 0.7071068, 0, 0.7071068]}"#,
        )
        .replace(r#""nodes": [0, 1, 2]"#, r#""nodes": [0, 1, 2, 3]"#);
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    let side = Scene::load(&path, &["gltf.camera=side".into()]).unwrap_or_else(|e| panic!("{e}"));
    assert!((side.camera.position - glam::DVec3::new(5.0, 0.0, 0.0)).length() < 1e-9);
    assert_eq!(
        (side.render.width, side.render.height),
        (960, 480),
        "its 2:1 aspect"
    );
    let front = Scene::load(&path, &["gltf.camera=\"front\"".into()]).unwrap();
    assert_eq!(front.camera.position, glam::DVec3::new(0.0, 0.0, 5.0));
    let error = Scene::load(&path, &["gltf.camera=top".into()])
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("\"top\"") && error.contains("\"side\", \"front\""),
        "{error}"
    );
}

/// Khronos' `Cameras` sample (scenes/meshes/Cameras.gltf, CC0): a unit square turned -45° about
/// x, a perspective camera (yfov 0.7, square) and an orthographic one (xmag = ymag = 1), both
/// at (0.5, 0.5, 3) looking down -Z; no names, no lights.
fn cameras_sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/Cameras.gltf")
}

/// The square under the orthographic camera: its x in [0, 1] and its y in [0, cos 45°] fill,
/// of the 2 x 2 window centred on (0.5, 0.5), the fraction 0.5 x 0.3536 of the image; the
/// surface is flat and lit by one directional light, so every pixel it covers has one value and
/// the mean over the image is that fraction of it.
const SQUARE_FRACTION: f64 = 0.5 * std::f64::consts::FRAC_1_SQRT_2 / 2.0;

fn covered_fraction(image: &chambre::render::Image) -> f64 {
    let full = image.get(image.width / 2, image.height * 2 / 3).x as f64;
    assert!(full > 0.0);
    let sum: f64 = image.pixels.iter().map(|p| p.x as f64).sum();
    sum / image.pixels.len() as f64 / full
}

#[test]
fn khronos_cameras_sample_renders_with_its_first_camera_and_each_by_index() {
    let path = cameras_sample();
    let first = Scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !first.camera.is_orthographic(),
        "the first camera is the perspective one"
    );
    assert_eq!(first.camera.position, glam::DVec3::new(0.5, 0.5, 3.0));
    assert_eq!((first.render.width, first.render.height), (960, 960));
    assert!((first.camera.field_of_view_deg()[1] - (0.7f32 as f64).to_degrees()).abs() < 1e-4);
    let by_index = Scene::load(&path, &["gltf.camera=0".into()]).unwrap();
    assert_eq!(by_index.camera, first.camera);
    let ortho = Scene::load(&path, &["gltf.camera=1".into()]).unwrap();
    assert!(ortho.camera.is_orthographic());
    let [w, h] = ortho.camera.window();
    assert!(
        (w - 2.0).abs() < 1e-12 && (h - 2.0).abs() < 1e-12,
        "{w} x {h}"
    );
    let size = ["render.width=64".into(), "render.height=64".into()];
    let render = |camera: &str, extra: &[&str]| {
        let mut overrides: Vec<String> = size.to_vec();
        overrides.push(format!("gltf.camera={camera}"));
        overrides.extend(extra.iter().map(|s| s.to_string()));
        let flat = flatten(&Scene::load(&path, &overrides).unwrap_or_else(|e| panic!("{e}")));
        (common::render_cpu(&flat), flat)
    };
    let (image, flat) = render("1", &[]);
    let fraction = covered_fraction(&image);
    assert!(
        (fraction / SQUARE_FRACTION - 1.0).abs() < 0.01,
        "{fraction} of the image against {SQUARE_FRACTION}"
    );
    // Its edges: x from 16 to 48 pixels, y (down) from 64 (1.5 - 0.7071) / 2 = 25.4 to 48.
    assert!(image.get(16, 30).x > 0.0 && image.get(47, 47).x > 0.0);
    assert_eq!(image.get(14, 30).x, 0.0);
    assert_eq!(image.get(49, 30).x, 0.0);
    assert_eq!(image.get(30, 24).x, 0.0);
    assert_eq!(image.get(30, 49).x, 0.0);
    // Ten times farther away the orthographic square is as large; the perspective one is not.
    let far = [
        "camera.position=[0.5, 0.5, 30.0]",
        "camera.look_at=[0.5, 0.5, 0.0]",
    ];
    let (far_image, _) = render("1", &far);
    let far_fraction = covered_fraction(&far_image);
    assert!(
        (far_fraction / fraction - 1.0).abs() < 1e-3,
        "{far_fraction} against {fraction}"
    );
    let (near_view, _) = render("0", &[]);
    let (far_view, _) = render("0", &far);
    let lit = |i: &chambre::render::Image| i.pixels.iter().filter(|p| p.x > 0.0).count();
    assert!(
        lit(&far_view) * 20 < lit(&near_view),
        "{} {}",
        lit(&far_view),
        lit(&near_view)
    );
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, mean_abs) = common::agreement(&image, &gpu, 1e-3);
        assert!(within > 0.995 && mean_abs < 1e-4, "{within} {mean_abs}");
    }
}

#[test]
fn an_explicit_size_of_another_aspect_keeps_the_cameras_vertical_extent() {
    // The quad file's camera: yfov 0.6, aspect 1. A 2:1 image widens the film, the vertical
    // field of view stays.
    let dir = scratch("aspect");
    let path = write_gltf(&dir, true);
    let wide = Scene::load(
        &path,
        &["render.width=200".into(), "render.height=100".into()],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(wide.camera.film_mm, [48.0, 24.0]);
    assert!((wide.camera.field_of_view_deg()[1] - (0.6f32 as f64).to_degrees()).abs() < 1e-9);
    // A side given alone takes its partner from the camera's aspect.
    let alone = Scene::load(&path, &["render.height=50".into()]).unwrap();
    assert_eq!((alone.render.width, alone.render.height), (50, 50));
    // The orthographic camera keeps its window's height, 2 ymag.
    let ortho = Scene::load(
        &cameras_sample(),
        &[
            "gltf.camera=1".into(),
            "render.width=128".into(),
            "render.height=64".into(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let [w, h] = ortho.camera.window();
    assert!(
        (w - 4.0).abs() < 1e-12 && (h - 2.0).abs() < 1e-12,
        "{w} x {h}"
    );
}

#[test]
fn a_gltf_without_a_camera_renders_at_any_explicit_size_with_its_bounds_in_view() {
    let dir = scratch("sized");
    let path = write_gltf(&dir, false);
    for (w, h) in [(96u32, 96u32), (40, 120), (120, 40)] {
        let size = [format!("render.width={w}"), format!("render.height={h}")];
        let scene = Scene::load(&path, &size).unwrap_or_else(|e| panic!("{w}x{h}: {e}"));
        let film = scene.camera.film_mm;
        assert!((film[0] / film[1] - w as f64 / h as f64).abs() < 1e-12);
        let image = common::render_cpu(&flatten(&scene));
        assert!(image.get(w / 2, h / 2).x > 0.05, "{w}x{h}");
        // The framing camera fits the bounding sphere in the narrower field of view: the
        // quad touches no edge of the image.
        let border = (0..w)
            .flat_map(|x| [(x, 0), (x, h - 1)])
            .chain((0..h).flat_map(|y| [(0, y), (w - 1, y)]));
        for (x, y) in border {
            assert_eq!(image.get(x, y).x, 0.0, "{w}x{h}: pixel ({x}, {y})");
        }
    }
}

#[test]
fn the_first_camera_is_the_first_reached_depth_first_in_node_order() {
    let dir = scratch("order");
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    // Node 0 (the mesh) has a child camera "child"; the second root node holds "later".
    let json = gltf_json(Some("quad.bin"), true)
        .replace(
            r#""cameras": [{"type": "perspective","#,
            r#""cameras": [{"name": "later", "type": "perspective",
                            "perspective": {"yfov": 0.5, "znear": 0.01}},
                           {"name": "child", "type": "perspective","#,
        )
        .replace(
            r#""nodes": [{"mesh": 0, "translation": [0, 0, -1], "scale": [2, 2, 2]}"#,
            r#""nodes": [{"mesh": 0, "translation": [0, 0, -1], "scale": [2, 2, 2],
                          "children": [3]}"#,
        )
        .replace(
            r#"{"KHR_lights_punctual": {"light": 0}}}"#,
            r#"{"KHR_lights_punctual": {"light": 0}}},
               {"camera": 1, "translation": [0, 0, 3]}"#,
        );
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = Scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    // The child sits 3 units up its parent's z, scaled 2 and moved to z = -1: at z = 5.
    assert!((scene.camera.position - glam::DVec3::new(0.0, 0.0, 5.0)).length() < 1e-9);
    assert!((scene.camera.field_of_view_deg()[1] - (0.6f32 as f64).to_degrees()).abs() < 1e-9);
    let later = Scene::load(&path, &["gltf.camera=later".into()]).unwrap();
    assert!((later.camera.field_of_view_deg()[1] - (0.5f32 as f64).to_degrees()).abs() < 1e-9);
}

#[test]
fn bad_camera_names_and_degenerate_cameras_are_refused_with_the_file_and_field() {
    let error = Scene::load(&cameras_sample(), &["gltf.camera=top".into()])
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("Cameras.gltf")
            && error.contains("\"top\"")
            && error.contains("0 (unnamed), 1 (unnamed)"),
        "{error}"
    );
    let sample = std::fs::read_to_string(cameras_sample()).unwrap();
    let dir = scratch("degenerate");
    for (from, to, camera, field) in [
        ("\"xmag\": 1.0", "\"xmag\": 0.0", "1", "orthographic.xmag"),
        ("\"ymag\": 1.0", "\"ymag\": -1.0", "1", "orthographic.ymag"),
        ("\"xmag\": 1.0", "\"xmag\": 1e39", "1", "orthographic.xmag"),
        ("\"yfov\": 0.7", "\"yfov\": 0.0", "0", "perspective.yfov"),
        ("\"yfov\": 0.7", "\"yfov\": 3.5", "0", "perspective.yfov"),
        (
            "\"aspectRatio\": 1.0",
            "\"aspectRatio\": -2.0",
            "0",
            "perspective.aspectRatio",
        ),
    ] {
        let json = sample.replace(from, to);
        assert_ne!(json, sample, "{from}");
        let path = dir.join("bad.gltf");
        std::fs::write(&path, json).unwrap();
        let error = Scene::load(&path, &[format!("gltf.camera={camera}")])
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("bad.gltf") && error.contains(field) && error.contains("camera"),
            "{to}: {error}"
        );
    }
    // A degenerate camera that is not chosen does not stop the file.
    let json = sample.replace("\"xmag\": 1.0", "\"xmag\": 0.0");
    std::fs::write(dir.join("unused.gltf"), json).unwrap();
    let scene = Scene::load(&dir.join("unused.gltf"), &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(!scene.camera.is_orthographic());
    // Read as a mesh, a file's cameras do not matter at all.
    assert_eq!(
        load_mesh(&dir.join("unused.gltf")).unwrap().triangles.len(),
        2
    );
}

/// The quad scene (`gltf_json` with its camera and light) with each `(from, to)` of `edits`
/// made, in folder `case`: the error both `Scene::load` and `load_mesh` give for it, which must
/// name the file and each of `expected`, and must not place the fault in the scene text
/// chambre builds from the file (`file:line:column: field `...``), which the user never sees.
fn assert_refused(case: &str, edits: &[(&str, &str)], expected: &[&str]) {
    let dir = scratch(case);
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let mut json = gltf_json(Some("quad.bin"), true);
    for (from, to) in edits {
        assert!(json.contains(from), "{case}: {from}");
        json = json.replace(from, to);
    }
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    let errors = [
        Scene::load(&path, &[]).unwrap_err().to_string(),
        load_mesh(&path).unwrap_err(),
    ];
    for error in errors {
        assert!(error.contains("quad.gltf"), "{case}: {error}");
        assert!(!error.contains("field `"), "{case}: {error}");
        for part in expected {
            assert!(error.contains(part), "{case}: {part} not in {error}");
        }
    }
}

/// The POSITION, NORMAL and index accessors of `gltf_json`, and the index buffer view.
const POSITION: &str = r#""bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3""#;
const NORMAL: &str = r#""bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3""#;
const INDICES: &str = r#""bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR""#;
const INDEX_VIEW: &str = r#"{"buffer": 0, "byteOffset": 96, "byteLength": 12}"#;
const MESH_NODE: &str = r#"{"mesh": 0, "translation""#;
const CAMERA_NODE: &str = r#"{"camera": 0, "translation": [0, 0, 5]"#;
const LIGHT_NODE: &str = r#"{"translation": [0, 0, 3], "extensions""#;

#[test]
fn node_cycles_and_shared_nodes_are_refused_naming_the_node() {
    // The mesh node its own child: its traversal never ended, each round adding the mesh.
    assert_refused(
        "self-cycle",
        &[(MESH_NODE, r#"{"mesh": 0, "children": [0], "translation""#)],
        &["nodes[0].children", "nodes[0] is the node itself (a cycle)"],
    );
    assert_refused(
        "cycle",
        &[
            (
                CAMERA_NODE,
                r#"{"camera": 0, "children": [2], "translation": [0, 0, 5]"#,
            ),
            (
                LIGHT_NODE,
                r#"{"translation": [0, 0, 3], "children": [1], "extensions""#,
            ),
        ],
        &["nodes[1].children", "nodes[2] is its ancestor (a cycle)"],
    );
    assert_refused(
        "two-parents",
        &[
            (MESH_NODE, r#"{"mesh": 0, "children": [1], "translation""#),
            (
                LIGHT_NODE,
                r#"{"translation": [0, 0, 3], "children": [1], "extensions""#,
            ),
        ],
        &[
            "nodes[2].children",
            "nodes[1] is already a child of nodes[0]",
        ],
    );
    assert_refused(
        "root-child",
        &[(MESH_NODE, r#"{"mesh": 0, "children": [2], "translation""#)],
        &["scenes[0].nodes", "nodes[2] is a child of nodes[0]"],
    );
    assert_refused(
        "root-twice",
        &[(r#""nodes": [0, 1, 2]"#, r#""nodes": [0, 1, 2, 0]"#)],
        &["scenes[0].nodes", "lists nodes[0] twice"],
    );
}

#[test]
fn accessors_of_types_gltf_does_not_allow_there_are_refused_naming_them() {
    let indices = "meshes[0].primitives[0].indices -> accessors[2]";
    for (component, name) in [("5126", "float SCALAR"), ("5120", "byte SCALAR")] {
        let to = INDICES.replace("5123", component);
        assert_refused(
            &format!("indices-{component}"),
            &[(INDICES, &to)],
            &[indices, name],
        );
    }
    let position = "meshes[0].primitives[0].attributes.POSITION -> accessors[0]";
    for (from, to, name) in [
        ("5126", "5123", "unsigned short VEC3"),
        ("5126", "5120", "byte VEC3"),
        ("VEC3", "VEC2", "float VEC2"),
    ] {
        let edited = POSITION.replace(from, to);
        assert_refused(
            &format!("position-{to}"),
            &[(POSITION, &edited)],
            &[position, name],
        );
    }
    let edited = NORMAL.replace("5126", "5122");
    assert_refused(
        "normal-short",
        &[(NORMAL, &edited)],
        &["attributes.NORMAL -> accessors[1]", "short VEC3"],
    );
}

/// `gltf_json` with a 1 x 1 base colour texture on its material, read through TEXCOORD_0 from
/// a fourth accessor, of `component` and `kind`, over the normals' buffer view.
fn textured(component: &str, kind: &str) -> Vec<(&'static str, String)> {
    const PNG: &str = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==";
    vec![
        (
            r#""NORMAL": 1}"#,
            r#""NORMAL": 1, "TEXCOORD_0": 3}"#.to_string(),
        ),
        (
            r#""metallicFactor": 0.0"#,
            r#""baseColorTexture": {"index": 0}, "metallicFactor": 0.0"#.to_string(),
        ),
        (
            r#""buffers": ["#,
            format!(
                r#""textures": [{{"source": 0}}],
                   "images": [{{"uri": "data:image/png;base64,{PNG}"}}],
                   "buffers": ["#
            ),
        ),
        (
            INDICES,
            format!(
                r#"{INDICES}}},
                {{"bufferView": 1, "componentType": {component}, "count": 4, "type": "{kind}""#
            ),
        ),
    ]
}

#[test]
fn texture_coordinates_of_types_gltf_does_not_allow_are_refused_naming_them() {
    let at = "meshes[0].primitives[0].attributes.TEXCOORD_0 -> accessors[3]";
    for (component, kind, name) in [
        ("5125", "VEC2", "unsigned int VEC2"),
        ("5122", "VEC2", "short VEC2"),
        ("5126", "VEC3", "float VEC3"),
    ] {
        let case = format!("uv-{component}-{kind}");
        let edits = textured(component, kind);
        let edits: Vec<(&str, &str)> = edits.iter().map(|(f, t)| (*f, t.as_str())).collect();
        assert_refused(&case, &edits, &[at, name]);
    }
    // Floats are read.
    let dir = scratch("uv-float");
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let mut json = gltf_json(Some("quad.bin"), true);
    for (from, to) in textured("5126", "VEC2") {
        json = json.replace(from, &to);
    }
    std::fs::write(dir.join("quad.gltf"), json).unwrap();
    let mesh = load_mesh(&dir.join("quad.gltf")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.texcoords.map(|t| t.len()), Some(4));
}

#[test]
fn accessors_past_their_data_are_refused_naming_the_accessor_and_view() {
    let position = "meshes[0].primitives[0].attributes.POSITION -> accessors[0]";
    let longer = POSITION.replace("\"count\": 4", "\"count\": 5");
    assert_refused(
        "position-count",
        &[(POSITION, &longer)],
        &[
            position,
            "end at byte 60, past the 48 bytes of bufferViews[0]",
        ],
    );
    let longer = NORMAL.replace("\"count\": 4", "\"count\": 5");
    assert_refused(
        "normal-count",
        &[(NORMAL, &longer)],
        &["attributes.NORMAL -> accessors[1]", "bufferViews[1]"],
    );
    let shorter = NORMAL.replace("\"count\": 4", "\"count\": 3");
    assert_refused(
        "normal-fewer",
        &[(NORMAL, &shorter)],
        &[
            "attributes.NORMAL -> accessors[1]",
            "has 3 elements where POSITION has 4",
        ],
    );
    let indices = "meshes[0].primitives[0].indices -> accessors[2]";
    let longer = INDICES.replace("\"count\": 6", "\"count\": 9");
    assert_refused(
        "indices-count",
        &[(INDICES, &longer)],
        &[indices, "past the 12 bytes of bufferViews[2]"],
    );
    let moved = INDEX_VIEW.replace("96", "1000");
    assert_refused(
        "view-offset",
        &[(INDEX_VIEW, &moved)],
        &[
            indices,
            "bufferViews[2] (bytes 1000 to 1012)",
            "108 bytes of buffers[0]",
        ],
    );
    // Three vertices, which the index 3 lies past.
    let (three, three_normals) = (
        POSITION.replace("\"count\": 4", "\"count\": 3"),
        NORMAL.replace("\"count\": 4", "\"count\": 3"),
    );
    assert_refused(
        "index-value",
        &[(POSITION, &three), (NORMAL, &three_normals)],
        &[indices, "element 5 is 3, past the 3 vertices of POSITION"],
    );
    // Sparse indices 0, 1, 2, 0 (the index view's), which must rise.
    let sparse = format!(
        r#"{POSITION}, "sparse": {{"count": 4, "indices": {{"bufferView": 2,
            "componentType": 5123}}, "values": {{"bufferView": 1}}}}"#
    );
    assert_refused(
        "sparse",
        &[(POSITION, &sparse)],
        &[&format!("{position}.sparse.indices"), "element 3 is 0"],
    );
}

#[test]
fn material_and_light_factors_outside_gltfs_bounds_are_refused_naming_them() {
    let pbr = "materials[0].pbrMetallicRoughness";
    let light = "extensions.KHR_lights_punctual.lights[0]";
    let point = r#"{"type": "point", "color": [1, 1, 1], "intensity": 6830}"#;
    let spot = |inner: &str, outer: &str| {
        format!(
            r#"{{"type": "spot", "color": [1, 1, 1], "intensity": 6830,
                 "spot": {{"innerConeAngle": {inner}, "outerConeAngle": {outer}}}}}"#
        )
    };
    let cases: [(&str, &str, String, String); 9] = [
        (
            "base",
            "[0.8, 0.2, 0.1, 1.0]",
            "[5, -1, 0.5, 1]".into(),
            format!("{pbr}.baseColorFactor: must lie in [0, 1]"),
        ),
        (
            "metallic",
            r#""metallicFactor": 0.0"#,
            r#""metallicFactor": 2"#.into(),
            format!("{pbr}.metallicFactor: must lie in [0, 1], got 2.0"),
        ),
        (
            "roughness",
            r#""roughnessFactor": 1.0"#,
            r#""roughnessFactor": -1"#.into(),
            format!("{pbr}.roughnessFactor: must lie in [0, 1], got -1.0"),
        ),
        (
            "emissive",
            r#""name": "paint","#,
            r#""name": "paint", "emissiveFactor": [1e30, 1, 1],"#.into(),
            "materials[0].emissiveFactor: must lie in [0, 1e20]".into(),
        ),
        (
            "emissive-max",
            r#""name": "paint","#,
            r#""name": "paint", "emissiveFactor": [3e38, 0, 0],"#.into(),
            "materials[0].emissiveFactor".into(),
        ),
        (
            "intensity",
            point,
            point.replace("6830", "1e30"),
            format!("{light}.intensity"),
        ),
        (
            "color",
            point,
            point.replace("[1, 1, 1]", "[1, -1, 0.5]"),
            format!("{light}.color"),
        ),
        (
            "spot-inner",
            point,
            spot("1.0", "0.5"),
            format!("{light}.spot.innerConeAngle: must lie in [0, outerConeAngle = 0.5)"),
        ),
        (
            "spot-outer",
            point,
            spot("0.1", "3.0"),
            format!("{light}.spot.outerConeAngle: must lie in (0, pi/2]"),
        ),
    ];
    for (case, from, to, expected) in &cases {
        assert_refused(case, &[(from, to)], &[expected]);
    }
}

#[test]
fn a_mesh_fault_found_after_reading_is_not_placed_in_the_scene_text() {
    // A zero scale leaves every triangle without area, which the mesh checks find.
    assert_refused(
        "flat",
        &[(r#""scale": [2, 2, 2]"#, r#""scale": [0, 0, 0]"#)],
        &["all 2 triangles of the mesh have zero area"],
    );
}

#[test]
fn an_empty_file_or_json_without_asset_is_said_to_be_one() {
    let dir = scratch("empty");
    for (name, text, expected) in [
        ("empty.gltf", "", "the file is empty"),
        ("blank.gltf", " \n", "the file is empty"),
        ("object.gltf", "{}", "missing field `asset`"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        for error in [
            Scene::load(&path, &[]).unwrap_err().to_string(),
            load_mesh(&path).unwrap_err(),
        ] {
            assert!(
                error.contains(name) && error.contains(expected),
                "{name}: {error}"
            );
        }
    }
}

/// A fault only the scene's validation finds (a camera beyond the coordinates chambre
/// accepts) names the glTF file and the scene field, with no line of the scene text chambre
/// made from the file, which its user cannot open.
#[test]
fn a_fault_found_by_the_scenes_validation_names_no_line_of_the_made_scene() {
    let dir = scratch("far_camera");
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let json = gltf_json(Some("quad.bin"), true)
        .replace(CAMERA_NODE, r#"{"camera": 0, "translation": [0, 0, 5e12]"#);
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    let error = Scene::load(&path, &[]).unwrap_err().to_string();
    assert!(
        error.contains("quad.gltf: field `camera.position"),
        "{error}"
    );
    assert!(
        error.contains("(of the scene chambre reads it as)"),
        "{error}"
    );
    let placed = error.split("quad.gltf:").nth(1).unwrap();
    assert!(placed.starts_with(' '), "a line of the made scene: {error}");
}

/// A GLB cut short says so, with the length its header declares.
#[test]
fn a_glb_cut_short_says_so() {
    let dir = scratch("short_glb");
    let whole = std::fs::read(write_glb(&dir)).unwrap();
    let path = dir.join("short.glb");
    std::fs::write(&path, &whole[..whole.len() - 9]).unwrap();
    let error = Scene::load(&path, &[]).unwrap_err().to_string();
    let expected = format!("its header declares {} bytes", whole.len());
    assert!(
        error.contains("short.glb") && error.contains(&expected),
        "{error}"
    );
}

/// The quad of `quad_buffer` quantized as gltfpack writes it, in one buffer: POSITION in
/// unsigned shorts, not normalized (0 and 2, the node's transform taking them to -2 and 2),
/// NORMAL in normalized bytes (0, 0, 127), each vertex attribute 4-byte aligned as
/// KHR_mesh_quantization requires; `declared` lists the extension in `extensionsUsed` and
/// `required` (with `more_required`).
fn quantized_quad(dir: &Path, declared: bool, more_required: &str) -> PathBuf {
    let mut bytes = Vec::new();
    for p in [[0u16, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    for _ in 0..4 {
        bytes.extend_from_slice(&[0, 0, 127, 0]);
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("quantized.bin"), &bytes).unwrap();
    let extensions = match declared {
        true => format!(
            r#""extensionsUsed": ["KHR_mesh_quantization"],
               "extensionsRequired": ["KHR_mesh_quantization"{more_required}],"#
        ),
        false => String::new(),
    };
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  {extensions}
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "translation": [-2, -2, -1], "scale": [2, 2, 2]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2}}]}}],
  "buffers": [{{"uri": "quantized.bin", "byteLength": {}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 32, "byteStride": 8}},
    {{"buffer": 0, "byteOffset": 32, "byteLength": 16, "byteStride": 4}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5123, "count": 4, "type": "VEC3",
      "min": [0, 0, 0], "max": [2, 2, 0]}},
    {{"bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}]
}}"#,
        bytes.len()
    );
    let path = dir.join("quantized.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// A KHR_mesh_quantization file reads as the float original it was made from, exactly here
/// (its integers and their scales are exact in f32); a file that does not declare the
/// extension has its integer attributes refused, told of it; a required extension chambre
/// does not read is still refused.
#[test]
fn quantized_attributes_read_as_their_float_originals() {
    let dir = scratch("quantized");
    let float = load_mesh(&write_gltf(&dir, false)).unwrap();
    let quantized = load_mesh(&quantized_quad(&dir, true, "")).unwrap();
    assert_eq!(quantized.positions, float.positions);
    assert_eq!(quantized.normals, float.normals);
    assert_eq!(quantized.triangles, float.triangles);
    let scene = Scene::load(&quantized_quad(&dir, true, ""), &[]).unwrap();
    assert_eq!(flatten(&scene).prims.len(), 2);

    let undeclared = quantized_quad(&dir, false, "");
    for error in [
        Scene::load(&undeclared, &[]).unwrap_err().to_string(),
        load_mesh(&undeclared).unwrap_err(),
    ] {
        for part in [
            "quantized.gltf",
            "attributes.POSITION -> accessors[0]: unsigned short VEC3, where glTF allows float VEC3",
            "in a file whose extensionsUsed lists KHR_mesh_quantization",
        ] {
            assert!(error.contains(part), "{part} not in {error}");
        }
    }
    // Texture coordinates in shorts, over the normals' floats: element 2 holds the bytes of
    // 1.0f32, 0x3f800000, as the shorts 0 and 0x3f80.
    let mut json = gltf_json(Some("quad.bin"), true).replace(
        r#""extensionsUsed": ["KHR_lights_punctual"]"#,
        r#""extensionsUsed": ["KHR_lights_punctual", "KHR_mesh_quantization"]"#,
    );
    for (from, to) in textured("5122", "VEC2") {
        json = json.replace(from, &to);
    }
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    for (normalized, v) in [(false, 16256.0), (true, 16256.0 / 32767.0)] {
        let json = json.replace(
            r#""componentType": 5122,"#,
            &format!(r#""componentType": 5122, "normalized": {normalized},"#),
        );
        std::fs::write(dir.join("uv.gltf"), json).unwrap();
        let mesh = load_mesh(&dir.join("uv.gltf")).unwrap_or_else(|e| panic!("{e}"));
        let uv = mesh.texcoords.unwrap();
        assert_eq!(uv[2], glam::Vec2::new(0.0, v), "normalized {normalized}");
        assert_eq!(
            (uv[0], uv[1], uv[3]),
            (glam::Vec2::ZERO, glam::Vec2::ZERO, glam::Vec2::ZERO)
        );
    }
    let draco = quantized_quad(&dir, true, r#", "KHR_draco_mesh_compression""#);
    let error = load_mesh(&draco).unwrap_err();
    assert!(
        error.contains("extensionsRequired[1]") && error.contains("Unsupported extension"),
        "{error}"
    );
}

/// `gltf_json`'s material given `extra` fields (and, with `metal`, metallic 1).
fn material_with(dir: &Path, extra: &str, metal: bool) -> PathBuf {
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let mut json = gltf_json(Some("quad.bin"), false).replace(
        r#"{"name": "paint","#,
        &format!(r#"{{"name": "paint", {extra},"#),
    );
    if metal {
        json = json.replace(r#""metallicFactor": 0.0"#, r#""metallicFactor": 1.0"#);
    }
    let path = dir.join("material.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// KHR_materials_emissive_strength scales the emission (Blender writes it for strengths above
/// 1); KHR_materials_transmission makes a dielectric glass of KHR_materials_ior's index (1.5
/// without one), a metal not, and what the glass approximates is noted; values outside glTF's
/// bounds, or beyond chambre's glass, are refused naming the field.
#[test]
fn emissive_strength_scales_emission_and_transmission_makes_glass() {
    let dir = scratch("material-extensions");
    let strength = r#""emissiveFactor": [1, 0.5, 0.25],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}"#;
    let mesh = load_mesh(&material_with(&dir, strength, false)).unwrap();
    assert_eq!(mesh.materials[0].emission, Vec3::new(8.0, 4.0, 2.0));
    assert_eq!(mesh.materials[0].ior, None);

    let glass = r#""extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                                   "KHR_materials_ior": {"ior": 1.33}}"#;
    for (extra, metal, ior) in [
        (glass, false, Some(1.33)),
        (
            r#""extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5}}"#,
            false,
            Some(1.5),
        ),
        (glass, true, None),
    ] {
        let path = material_with(&dir, extra, metal);
        let read = chambre::scene::gltf::read_gltf(&path).unwrap();
        assert_eq!(read.mesh.materials[0].ior, ior, "{extra}, metal {metal}");
        let notes = read.notes.join("\n");
        // The quad's roughness is 1: rendered smooth, and said so.
        assert_eq!(
            notes.contains("a roughness of 1 as smooth"),
            ior.is_some(),
            "{notes}"
        );
        assert_eq!(
            notes.contains("a transmission of 0.5"),
            extra.contains("0.5"),
            "{notes}"
        );
    }

    for (extra, field) in [
        (
            r#""extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": -1}}"#,
            "materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength",
        ),
        (
            r#""emissiveFactor": [1, 1, 1],
               "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e30}}"#,
            "materials[0].emissiveFactor: must lie in [0, 1e20] once multiplied by its \
             emissiveStrength 1e30",
        ),
        (
            r#""extensions": {"KHR_materials_transmission": {"transmissionFactor": 2}}"#,
            "materials[0].extensions.KHR_materials_transmission.transmissionFactor",
        ),
        (
            r#""extensions": {"KHR_materials_ior": {"ior": 0.5}}"#,
            "materials[0].extensions.KHR_materials_ior.ior",
        ),
    ] {
        let path = material_with(&dir, extra, false);
        for error in [
            Scene::load(&path, &[]).unwrap_err().to_string(),
            load_mesh(&path).unwrap_err(),
        ] {
            assert!(
                error.contains("material.gltf") && error.contains(field),
                "{field} not in {error}"
            );
        }
    }
}
