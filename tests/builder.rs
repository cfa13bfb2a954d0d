//! A scene built in code is the scene the same fields in a file give, and its errors name the
//! field at fault.

mod common;

use chambre::scene::{Scene, SceneBuilder};

#[test]
fn a_built_scene_renders_as_its_file_does() {
    let built = SceneBuilder::new(48, 32)
        .spp(2)
        .pinhole([0.0, 1.0, 4.0], [0.0, 0.5, 0.0], 40.0)
        .lambert("white", [0.8, 0.8, 0.8])
        .mirror("chrome", [0.9, 0.9, 0.9])
        .sphere([0.0, 0.5, 0.0], 0.5, "chrome")
        .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "white")
        .point_light([2.0, 4.0, 3.0], [30.0, 30.0, 30.0])
        .build()
        .unwrap();
    let text = r#"[render]
width = 48
height = 32
spp = 2
[camera]
position = [0.0, 1.0, 4.0]
look_at = [0.0, 0.5, 0.0]
vertical_fov = 40.0
film = [36.0, 24.0]
[[materials]]
name = "white"
model = "lambert"
diffuse = [0.8, 0.8, 0.8]
[[materials]]
name = "chrome"
model = "mirror"
mirror = [0.9, 0.9, 0.9]
[[shapes]]
type = "sphere"
center = [0.0, 0.5, 0.0]
radius = 0.5
material = "chrome"
[[shapes]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
material = "white"
[[lights]]
type = "point"
position = [2.0, 4.0, 3.0]
intensity = [30.0, 30.0, 30.0]
"#;
    let file = Scene::from_str(std::path::Path::new("file.toml"), text, &[]).unwrap();
    let images = [built, file].map(|scene| common::render_cpu(&chambre::pack::flatten(&scene)));
    assert!(images[0].pixels.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(images[0], images[1]);
}

#[test]
fn a_built_scenes_error_names_its_field() {
    let error = SceneBuilder::new(48, 32)
        .lambert("white", [0.8, 0.8, 0.8])
        .sphere([0.0, 0.0, -3.0], 1.0, "white")
        .sphere([0.0, 0.0, -3.0], -1.0, "white")
        .build()
        .expect_err("a negative radius");
    let message = error.to_string();
    assert!(
        message.contains("shapes[1].radius") && message.contains("positive"),
        "{message}"
    );
}
