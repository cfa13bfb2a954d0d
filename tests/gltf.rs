//! glTF 2.0 scenes: node transforms, the camera, KHR_lights_punctual and the material mapping
//! give a pixel its analytic value; `.glb` reads as `.gltf` does; a chambre scene can place a
//! glTF mesh under its own view camera; a file without camera or lights still renders; both
//! paths agree.

use std::path::{Path, PathBuf};

use chambre::pack::flatten;
use chambre::scene::Scene;
use chambre::scene::mesh::load_mesh;
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
