//! Every malformed scene gets one clear error naming file, line and field, never a panic.

use std::path::Path;

use chambre::scene::Scene;

mod common;

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
    mesh_error_with(mesh_name, contents.map(str::as_bytes), "", says);
}

/// Like `mesh_error`, with `fields` added to the mesh shape (after its `file` line).
fn mesh_error_with(mesh_name: &str, contents: Option<&[u8]>, fields: &str, says: &str) {
    let dir = std::env::temp_dir().join(format!("chambre-mesh-{mesh_name}"));
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(c) = contents {
        std::fs::write(dir.join(mesh_name), c).unwrap();
    }
    let text = BASE.replacen(
        "type = \"quad\"\ncorner = [0.0, 0.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]",
        &format!("type = \"mesh\"\nfile = \"{mesh_name}\"{fields}"),
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

/// The error of loading the scene at `path`, as `main` prints it: with its chain of causes.
fn printed_error(path: &Path, overrides: &[String]) -> String {
    let err = Scene::load(path, overrides).expect_err("an error");
    format!("{:#}", anyhow::Error::from(err))
}

fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-bad-input-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn arrays_of_the_wrong_length_are_refused_with_their_field() {
    // Too long: serde's fixed-size arrays would silently drop the surplus.
    expect_error(
        "position = [0.0, 1.0, 5.0]",
        "position = [2, 3, 3, 9]",
        5,
        "camera.position",
        "invalid length 4, expected an array of exactly 3 elements",
    );
    expect_error(
        "film = [36.0, 27.0]",
        "film = [36.0, 24.0, 1.0]",
        8,
        "camera.film",
        "invalid length 3, expected an array of exactly 2 elements",
    );
    // Too short.
    expect_error(
        "center = [0.0, 1.0, 0.0]",
        "center = [0.0, 1.0]",
        14,
        "shapes[0].center",
        "invalid length 2",
    );
    expect_error(
        "intensity = [5.0, 5.0, 5.0]",
        "intensity = []",
        26,
        "lights[0].intensity",
        "invalid length 0",
    );
    for shift in ["film_shift", "lens_shift"] {
        expect_error(
            "film = [36.0, 27.0]",
            &format!("film = [36.0, 27.0]\n{shift} = [1.0, 2.0, 3.0]"),
            9,
            &format!("camera.{shift}"),
            "invalid length 3",
        );
    }
    let lens = "film = [36.0, 27.0]\nf_number = 4.0\nfocus_points = ";
    expect_error(
        "film = [36.0, 27.0]",
        &format!("{lens}[[0, 0, 0], [1, 0, 0]]"),
        10,
        "camera.focus_points",
        "invalid length 2",
    );
    expect_error(
        "film = [36.0, 27.0]",
        &format!("{lens}[[0, 0, 0], [1, 0, 0], [0, 0, 1, 7]]"),
        10,
        "camera.focus_points[2]",
        "invalid length 4",
    );
    expect_error(
        "type = \"quad\"\ncorner = [0.0, 0.0, 0.0]",
        "type = \"mesh\"\nfile = \"m.obj\"\nscale = [1.0, 2.0]\ncorner = [0.0, 0.0, 0.0]",
        20,
        "shapes[1].scale",
        "invalid length 2",
    );
}

#[test]
fn arrays_of_the_wrong_length_in_overrides_name_the_override() {
    let set = |item: &str| vec![item.to_string()];
    let path = Path::new("s.toml");
    let err = Scene::from_str(path, BASE, &set("camera.position=[1, 2, 3, 4]"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("set on the command line")
            && err.contains("field `camera.position`")
            && err.contains("invalid length 4"),
        "{err}"
    );
    let err = Scene::from_str(path, BASE, &set("shapes[1].edge_u=[1]"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("field `shapes[1].edge_u`") && err.contains("invalid length 1"),
        "{err}"
    );
    // A bad array in the file is the file's fault, whatever the overrides.
    let text = BASE.replacen("position = [0.0, 1.0, 5.0]", "position = [2, 3, 3, 9]", 1);
    let err = Scene::from_str(path, &text, &set("render.spp=4"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s.toml:5:") && err.contains("camera.position"),
        "{err}"
    );
}

#[test]
fn radiometric_values_beyond_the_bound_are_refused() {
    expect_error(
        "intensity = [5.0, 5.0, 5.0]",
        "intensity = [3.4e38, 5.0, 5.0]",
        26,
        "lights[0].intensity",
        "exceeds 1e20",
    );
    expect_error(
        "height = 48",
        "height = 48\nbackground = [3.4e38, 3.4e38, 3.4e38]",
        4,
        "render.background",
        "exceeds 1e20",
    );
    expect_error(
        "height = 48",
        "height = 48\nambient = [0.0, 1.0e21, 0.0]",
        4,
        "render.ambient",
        "exceeds 1e20",
    );
}

#[test]
fn radiometric_values_at_the_bound_render_finite() {
    // Every radiometric value at the bound, and the largest BRDF normalisation (Phong at
    // shininess 1e4), close to the light: the image must stay finite.
    let text = BASE
        .replacen(
            "height = 48",
            "height = 6\nspp = 4\nbackground = [1e20, 1e20, 1e20]\nambient = [1e20, 1e20, 1e20]",
            1,
        )
        .replacen("width = 64", "width = 8", 1)
        .replacen("film = [36.0, 27.0]", "film = [36.0, 27.0]\nvertical_fov = 60.0", 1)
        .replacen(
            "model = \"lambert\"",
            "model = \"phong\"\ndiffuse = [1.0, 1.0, 1.0]\nspecular = [1.0, 1.0, 1.0]\nshininess = 1e4",
            1,
        )
        .replacen("intensity = [5.0, 5.0, 5.0]", "intensity = [1e20, 1e20, 1e20]", 1);
    let scene =
        Scene::from_str(Path::new("bound.toml"), &text, &[]).unwrap_or_else(|e| panic!("{e}"));
    let image = common::render_cpu(&chambre::pack::flatten(&scene));
    assert!(
        image.pixels.iter().all(|p| p.is_finite()),
        "non-finite pixels at the radiometric bound"
    );
    let brightest = image
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    assert!(
        brightest >= 1e20,
        "the bound did not reach the image: {brightest}"
    );
}

#[test]
fn invalid_utf8_is_placed_at_its_byte_and_said_once() {
    let path = scratch_dir("utf8").join("latin1.toml");
    let mut bytes = BASE.as_bytes().to_vec();
    // "white" -> "wh\xefte", as a Latin-1 editor writes "whïte": line 10, column 11.
    let at = BASE.find("\"white\"").unwrap() + 3;
    bytes[at] = 0xef;
    std::fs::write(&path, bytes).unwrap();
    let err = printed_error(&path, &[]);
    assert!(err.contains("latin1.toml:10:11"), "{err}");
    assert_eq!(err.matches("valid UTF-8").count(), 1, "{err}");
}

#[test]
fn an_unknown_key_is_named_once() {
    expect_error(
        "height = 48",
        "height = 48\nsppp = 4",
        4,
        "field `render.sppp`",
        "unknown field `sppp`",
    );
    expect_error(
        "look_at = [0.0, 1.0, 0.0]",
        "look_at = [0.0, 1.0, 0.0]\nfnumber = 2.8",
        7,
        "field `camera.fnumber`",
        "unknown field",
    );
}

#[test]
fn a_missing_scene_file_gives_its_cause_once() {
    let path = scratch_dir("missing").join("nowhere.toml");
    let err = printed_error(&path, &[]);
    assert!(err.contains("nowhere.toml"), "{err}");
    let cause = std::fs::read(&path).unwrap_err().to_string();
    assert_eq!(err.matches(cause.as_str()).count(), 1, "{err}");
}

#[test]
fn huge_numbers_print_compactly() {
    expect_error(
        "radius = 1.0",
        "radius = 1e300",
        15,
        "shapes[0].radius",
        "1e300 does not fit in a 32-bit float",
    );
    expect_error(
        "center = [0.0, 1.0, 0.0]",
        "center = [0.0, 1.0, 3e30]",
        14,
        "shapes[0].center",
        "[0, 1, 3e30] lies beyond",
    );
}

#[test]
fn a_bad_vertex_names_the_mesh_file_and_the_vertex() {
    let obj = |second: &str| format!("v 0 0 0\n{second}\nv 0 1 0\nf 1 2 3\n");
    mesh_error(
        "nan.obj",
        Some(&obj("v nan 0 0")),
        "nan.obj: line 2: `v nan 0 0`: a number that is not finite",
    );
    // Finite in the file's decimal text, infinite as the f32 every coordinate becomes.
    mesh_error(
        "big.obj",
        Some(&obj("v 1e39 0 0")),
        "big.obj: line 2: `v 1e39 0 0`: a number that is not finite",
    );
    // ASCII PLY has no spelling for NaN; binary PLY carries its bits.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for c in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, f32::NAN, 0.0f32] {
        ply.extend(c.to_le_bytes());
    }
    ply.push(3);
    for i in [0i32, 1, 2] {
        ply.extend(i.to_le_bytes());
    }
    mesh_error_with(
        "nan.ply",
        Some(&ply),
        "",
        "nan.ply: vertex 2 has a non-finite",
    );
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, obj("v 0 inf 0").as_bytes()).unwrap();
    mesh_error_with(
        "inf.obj.gz",
        Some(&gz.finish().unwrap()),
        "",
        "inf.obj.gz: line 2: `v 0 inf 0`: a number that is not finite",
    );
    // Texture coordinates and normals: the file's line, not v as flipped for the image.
    let attributes = |line: &str, face: &str| {
        format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n{line}\nvt 0 1\nvn 0 0 1\nf {face}\n")
    };
    mesh_error(
        "vt.obj",
        Some(&attributes("vt nan 0.25", "1/1 2/2 3/3")),
        "vt.obj: line 5: `vt nan 0.25`: a number that is not finite",
    );
    mesh_error(
        "vn.obj",
        Some(&attributes("vn 0 -inf 1", "1//1 2//1 3//2")),
        "vn.obj: line 5: `vn 0 -inf 1`: a number that is not finite",
    );
    mesh_error_with(
        "far.obj",
        Some(obj("v 1 0 0").as_bytes()),
        "\nscale = 2e9",
        "far.obj: vertex 1 lies at [2e9, 0, 0] after transformation, beyond",
    );
}

#[test]
fn a_bad_face_names_the_mesh_file_and_the_face() {
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 5\n";
    mesh_error(
        "face.ply",
        Some(ply),
        "face.ply: PLY face 1 has vertex index 5",
    );
    mesh_error(
        "face.obj",
        Some("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 x 3\n"),
        "face.obj: malformed OBJ at line 5",
    );
}

#[test]
fn crease_angle_belongs_to_meshes_and_lies_in_0_to_180() {
    expect_error(
        "radius = 1.0",
        "radius = 1.0\ncrease_angle = 30.0",
        16,
        "shapes[0].crease_angle",
        "does not apply to a sphere",
    );
    let dir = std::env::temp_dir().join(format!("chambre-crease-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let mesh_scene = BASE.replacen(
        "type = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0",
        "type = \"mesh\"\nfile = \"tri.obj\"\ncrease_angle = 200.0",
        1,
    );
    let error = Scene::from_str(&dir.join("scene.toml"), &mesh_scene, &[])
        .expect_err("a crease of 200 degrees")
        .to_string();
    assert!(
        error.contains("shapes[0].crease_angle") && error.contains("[0, 180]"),
        "{error}"
    );
}

#[test]
fn a_crop_window_must_hold_a_pixel_within_the_image() {
    for (window, says) in [
        ("[0.5, 0.5, 0.0, 1.0]", "holds no pixel"),
        ("[0.0, 1.2, 0.0, 1.0]", "lies in [0, 1]"),
        ("[0.8, 0.2, 0.0, 1.0]", "holds no pixel"),
    ] {
        expect_error(
            "height = 48",
            &format!("height = 48\ncrop = {window}"),
            4,
            "render.crop",
            says,
        );
    }
}

#[test]
fn adaptive_sampling_settings_are_checked_with_their_field() {
    let at = |to: &str, line: usize, field: &str, says: &str| {
        expect_error(
            "height = 48",
            &format!("height = 48\n{to}"),
            line,
            field,
            says,
        )
    };
    at(
        "noise_target = -0.1",
        4,
        "render.noise_target",
        "must be positive",
    );
    at(
        "noise_target = 1e7",
        4,
        "render.noise_target",
        "lies in [1e-37, 1e6]",
    );
    at(
        "min_spp = 8",
        4,
        "render.min_spp",
        "give render.noise_target",
    );
    at(
        "noise_target = 0.01\nmin_spp = 1",
        5,
        "render.min_spp",
        "2..=16",
    );
    // The first decision cannot come after the last sample.
    at(
        "spp = 8\nnoise_target = 0.01\nmin_spp = 32",
        6,
        "render.min_spp",
        "2..=8",
    );
}

#[test]
fn a_spot_light_needs_its_direction_and_ordered_cones() {
    let spot = |extra: &str| {
        format!("type = \"spot\"\nposition = [0.0, 3.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n{extra}")
    };
    let from = "type = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = [5.0, 5.0, 5.0]";
    expect_error(from, &spot(""), 23, "lights[0].direction", "required");
    let cones = spot("direction = [0.0, -1.0, 0.0]\ninner_angle = 40.0\nouter_angle = 30.0");
    expect_error(from, &cones, 28, "lights[0].inner_angle", "[0, outer_angle");
    let wide = spot("direction = [0.0, -1.0, 0.0]\nouter_angle = 120.0");
    expect_error(from, &wide, 28, "lights[0].outer_angle", "(0, 90]");
    let area = spot("direction = [0.0, -1.0, 0.0]\nsamples = 4");
    expect_error(from, &area, 28, "samples", "spot light");
}

/// A torus must be a ring torus (its tube thinner than its ring), have both radii, and take
/// none of a sphere's other fields; it may be turned (`rotate`, finite), a sphere not.
#[test]
fn torus_fields() {
    let sphere = "type = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0";
    let torus = |radii: &str| format!("type = \"torus\"\ncenter = [0.0, 1.0, 0.0]\n{radii}");
    let valid = BASE.replacen(sphere, &torus("major_radius = 1.0\nminor_radius = 0.3"), 1);
    Scene::from_str(Path::new("ok.toml"), &valid, &[]).unwrap();
    let turned = torus("major_radius = 1.0\nminor_radius = 0.3\nrotate = [90.0, 0.0, 0.0]");
    let scene = Scene::from_str(
        Path::new("ok.toml"),
        &BASE.replacen(sphere, &turned, 1),
        &[],
    )
    .unwrap();
    match &scene.surfaces[0].surface {
        chambre::scene::surface::Surface::Torus(t) => {
            // 90 degrees about x lays the axis along z.
            let axis = t.orientation * glam::DVec3::Y;
            assert!((axis - glam::DVec3::Z).length() < 1e-12, "{axis}");
        }
        other => panic!("{other:?}"),
    }
    expect_error(
        sphere,
        &torus("major_radius = 1.0\nminor_radius = 0.3\nrotate = [nan, 0.0, 0.0]"),
        17,
        "shapes[0].rotate[0]",
        "finite",
    );
    expect_error(
        sphere,
        &format!("{sphere}\nrotate = [0.0, 30.0, 0.0]"),
        16,
        "shapes[0].rotate",
        "does not apply to a sphere",
    );
    expect_error(
        sphere,
        &torus("major_radius = 1.0\nminor_radius = 0.3\nscale = 2.0"),
        17,
        "shapes[0].scale",
        "does not apply to a torus",
    );
    expect_error(
        sphere,
        &torus("major_radius = 1.0\nminor_radius = 1.5"),
        16,
        "shapes[0].minor_radius",
        "below major_radius",
    );
    expect_error(
        sphere,
        &torus("major_radius = 1.0\nminor_radius = -0.5"),
        16,
        "shapes[0].minor_radius",
        "positive",
    );
    expect_error(
        sphere,
        &torus("major_radius = 1.0\nradius = 0.5"),
        16,
        "shapes[0].radius",
        "does not apply to a torus",
    );
    expect_error(
        sphere,
        &torus("major_radius = 1.0"),
        12,
        "shapes[0].minor_radius",
        "required",
    );
}

/// A Bézier shape's patch file that cannot be read, or that is malformed, is named with the
/// line at fault; a mesh's smoothing fields do not apply to it.
#[test]
fn bezier_fields() {
    let sphere = "type = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0";
    let dir = std::env::temp_dir().join("chambre-bad-input");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("broken.bpt"), "1\n1,2,3\n").unwrap();
    let bezier = |rest: &str| format!("type = \"bezier\"\n{rest}");
    expect_error(
        sphere,
        &bezier("file = \"missing.bpt\""),
        14,
        "shapes[0].file",
        "cannot read patch file",
    );
    expect_error(
        sphere,
        &bezier("file = \"broken.bpt\""),
        14,
        "shapes[0].file",
        "broken.bpt:2: expected 16 numbers",
    );
    expect_error(
        sphere,
        &bezier("file = \"broken.bpt\"\nsmooth = false"),
        15,
        "shapes[0].smooth",
        "does not apply to a bezier",
    );
}

/// An ellipsoid needs positive semi-axes; a cylinder a positive height; neither takes the
/// other's fields.
#[test]
fn ellipsoid_and_cylinder_fields() {
    let sphere = "type = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0";
    let shape = |rest: &str| format!("{rest}\ncenter = [0.0, 1.0, 0.0]");
    let valid = BASE.replacen(
        sphere,
        &shape("type = \"ellipsoid\"\nradii = [1.0, 0.5, 2.0]"),
        1,
    );
    Scene::from_str(Path::new("ok.toml"), &valid, &[]).unwrap();
    let valid = BASE.replacen(
        sphere,
        &shape("type = \"cylinder\"\nradius = 0.5\nheight = 2.0\nrotate = [0.0, 0.0, 90.0]"),
        1,
    );
    Scene::from_str(Path::new("ok.toml"), &valid, &[]).unwrap();
    expect_error(
        sphere,
        &shape("type = \"ellipsoid\"\nradii = [1.0, 1.0, 1.0]\ntranslate = [1.0, 0.0, 0.0]"),
        15,
        "shapes[0].translate",
        "does not apply to an ellipsoid",
    );
    expect_error(
        sphere,
        &shape("type = \"ellipsoid\"\nradii = [1.0, 0.0, 2.0]"),
        14,
        "shapes[0].radii",
        "positive",
    );
    expect_error(
        sphere,
        &shape("type = \"cylinder\"\nradius = 0.5\nheight = -1.0"),
        15,
        "shapes[0].height",
        "positive",
    );
    expect_error(
        sphere,
        &shape("type = \"ellipsoid\"\nradii = [1.0, 1.0, 1.0]\nheight = 2.0"),
        15,
        "shapes[0].height",
        "does not apply to an ellipsoid",
    );
    expect_error(
        sphere,
        &shape("type = \"torus\"\nmajor_radius = 1.0\nminor_radius = 0.2\nradii = [1.0, 1.0, 1.0]"),
        16,
        "shapes[0].radii",
        "does not apply to a torus",
    );
}
