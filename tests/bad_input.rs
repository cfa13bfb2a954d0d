//! Every malformed scene gets one clear error naming file, line and field, never a panic.

use std::path::Path;

use chambre::scene::Scene;

const BASE: &str = r#"[render]
width = 64
height = 48
[camera]
position = [0.0, 1.0, 5.0]
look_at = [0.0, 1.0, 0.0]
up = [0.0, 1.0, 0.0]
film = [36.0, 27.0]
[[materials]]
name = "white"
model = "lambert"
[[shapes]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 1.0
material = "white"
[[shapes]]
type = "quad"
corner = [0.0, 0.0, 0.0]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
material = "white"
[[lights]]
type = "point"
position = [0.0, 3.0, 0.0]
intensity = [5.0, 5.0, 5.0]
"#;

/// Replace `from` (which must occur) in the base scene and expect an error at `line` about
/// `field` whose message contains `says`.
fn expect_error(from: &str, to: &str, line: usize, field: &str, says: &str) {
    assert!(BASE.contains(from), "{from}");
    let text = BASE.replacen(from, to, 1);
    let dir = std::env::temp_dir().join("chambre-bad-input");
    std::fs::create_dir_all(&dir).unwrap();
    let err = Scene::from_str(&dir.join("bad.toml"), &text, &[])
        .expect_err(to)
        .to_string();
    assert!(
        err.contains(&format!("bad.toml:{line}:")),
        "wrong line in: {err}"
    );
    assert!(err.contains(field), "no field `{field}` in: {err}");
    assert!(err.contains(says), "no `{says}` in: {err}");
}

#[test]
fn the_base_scene_is_valid() {
    Scene::from_str(Path::new("ok.toml"), BASE, &[]).unwrap();
}

#[test]
fn unknown_field() {
    expect_error(
        "radius = 1.0",
        "radius = 1.0\nradus = 2.0",
        16,
        "shapes[0].radus",
        "unknown field",
    );
}

#[test]
fn wrong_type() {
    expect_error(
        "radius = 1.0",
        "radius = \"big\"",
        15,
        "radius",
        "invalid type",
    );
}

#[test]
fn nan_and_inf() {
    expect_error(
        "radius = 1.0",
        "radius = nan",
        15,
        "shapes[0].radius",
        "finite",
    );
    expect_error(
        "position = [0.0, 3.0, 0.0]",
        "position = [0.0, inf, 0.0]",
        25,
        "lights[0].position[1]",
        "finite",
    );
}

#[test]
fn negative_radius_and_intensity() {
    expect_error(
        "radius = 1.0",
        "radius = -1.0",
        15,
        "shapes[0].radius",
        "positive",
    );
    expect_error(
        "intensity = [5.0, 5.0, 5.0]",
        "intensity = [5.0, -5.0, 5.0]",
        26,
        "lights[0].intensity",
        "negative",
    );
}

#[test]
fn zero_length_up_and_edge() {
    expect_error(
        "up = [0.0, 1.0, 0.0]",
        "up = [0.0, 0.0, 0.0]",
        7,
        "camera.up",
        "zero-length",
    );
    expect_error(
        "edge_u = [1.0, 0.0, 0.0]",
        "edge_u = [0.0, 0.0, 0.0]",
        20,
        "shapes[1].edge_u",
        "zero-length",
    );
}

#[test]
fn look_at_equal_to_position() {
    expect_error(
        "look_at = [0.0, 1.0, 0.0]",
        "look_at = [0.0, 1.0, 5.0]",
        6,
        "camera.look_at",
        "equals camera.position",
    );
}

#[test]
fn unknown_material() {
    expect_error(
        "material = \"white\"\n[[shapes]]",
        "material = \"chalk\"\n[[shapes]]",
        16,
        "shapes[0].material",
        "unknown material `chalk`",
    );
}

#[test]
fn aspect_ratio_mismatch() {
    expect_error(
        "film = [36.0, 27.0]",
        "film = [36.0, 24.0]",
        8,
        "camera.film",
        "does not match the image aspect",
    );
}

fn mesh_error(mesh_name: &str, contents: Option<&str>, says: &str) {
    let dir = std::env::temp_dir().join(format!("chambre-mesh-{mesh_name}"));
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(c) = contents {
        std::fs::write(dir.join(mesh_name), c).unwrap();
    }
    let text = BASE.replacen(
        "type = \"quad\"\ncorner = [0.0, 0.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]",
        &format!("type = \"mesh\"\nfile = \"{mesh_name}\""),
        1,
    );
    let err = Scene::from_str(&dir.join("bad.toml"), &text, &[])
        .expect_err(mesh_name)
        .to_string();
    assert!(
        err.contains("bad.toml:19:") && err.contains("shapes[1].file"),
        "{err}"
    );
    assert!(err.contains(says), "no `{says}` in: {err}");
}

#[test]
fn missing_mesh_file() {
    mesh_error("nowhere.obj", None, "cannot open mesh file");
}

#[test]
fn unreadable_mesh_file() {
    mesh_error(
        "garbage.ply",
        Some("this is not a ply file\n"),
        "malformed PLY",
    );
    mesh_error("mesh.stl", Some("solid x\n"), "unknown mesh format");
}

#[test]
fn out_of_range_mesh_indices() {
    mesh_error(
        "oob.obj",
        Some("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
        "malformed OBJ",
    );
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
               element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n";
    mesh_error("oob.ply", Some(ply), "out of range");
}

#[test]
fn empty_mesh() {
    mesh_error("empty.obj", Some("# nothing\n"), "no faces");
    mesh_error(
        "flat.obj",
        Some("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
        "zero area",
    );
}

#[test]
fn override_errors_name_the_override() {
    let overrides = vec!["shapes[0].radius=-2".to_string()];
    let err = Scene::from_str(Path::new("s.toml"), BASE, &overrides)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("set on the command line") && err.contains("shapes[0].radius"),
        "{err}"
    );
    let err = Scene::from_str(Path::new("s.toml"), BASE, &["render.spp".to_string()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("key=value"), "{err}");
}
