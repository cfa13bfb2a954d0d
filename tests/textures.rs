//! Image textures: a scene material's `diffuse_texture`, an OBJ's `map_Kd` and a glTF's base
//! colour texture, read where the files say, oriented as their formats define, decoded from
//! sRGB, on the CPU and the GPU alike; and refused by name where a shape has no texture
//! coordinates or a file cannot be read.

mod common;

use std::path::{Path, PathBuf};

use chambre::pack::flatten;
use chambre::render::Image;
use chambre::scene::Scene;
use chambre::scene::texture::Wrap;

/// sRGB bytes of the test texture's four quadrants: top left, top right, bottom left, bottom
/// right (as the image is shown).
const QUADRANTS: [[u8; 3]; 4] = [[200, 30, 10], [20, 180, 40], [15, 25, 220], [250, 250, 250]];

/// A scratch folder of its own for test `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-textures-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An 8 x 8 PNG whose 4 x 4 quadrants have the colours of [`QUADRANTS`].
fn quadrant_png(path: &Path) {
    let image = image::RgbImage::from_fn(8, 8, |x, y| {
        image::Rgb(QUADRANTS[(y / 4 * 2 + x / 4) as usize])
    });
    image.save(path).unwrap();
}

/// The linear value of an sRGB byte, in double precision (IEC 61966-2-1).
fn linear(byte: u8) -> f64 {
    let c = byte as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A scene of a 1.6 x 1.6 square at z = -2 in front of a pinhole at the origin (45° vertical
/// field of view: the square just fills the 32 x 32 image), white Lambert with the texture,
/// lit by ambient radiance 1 only: each pixel shows the texture's linear colour there.
fn square_scene(shape: &str, material: &str) -> String {
    format!(
        r#"[render]
width = 32
height = 32
spp = 4
ambient = [1.0, 1.0, 1.0]
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
film = [24.0, 24.0]
focal_length = 28.97
{material}
{shape}
"#
    )
}

/// Pixels well inside each quadrant of the square show that quadrant's colour exactly (the
/// bilinear filter then blends texels of one colour), upright: the image's top left is the
/// texture's top left.
fn assert_quadrants_upright(what: &str, image: &Image) {
    let corners = [(4, 4), (27, 4), (4, 27), (27, 27)];
    for ((x, y), srgb) in corners.into_iter().zip(QUADRANTS) {
        let got = image.pixels[(y * image.width + x) as usize];
        for c in 0..3 {
            let want = linear(srgb[c]);
            assert!(
                (got[c] as f64 - want).abs() < 1e-5,
                "{what}: pixel ({x}, {y}) channel {c} is {}, the texture's {want}",
                got[c]
            );
        }
    }
}

fn load(dir: &Path, text: &str) -> Result<Scene, String> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path, &[]).map_err(|e| e.to_string())
}

#[test]
fn a_quad_shows_its_texture_upright_and_decoded_from_srgb() {
    let dir = scratch("quad");
    quadrant_png(&dir.join("quadrants.png"));
    let text = square_scene(
        r#"[[shapes]]
type = "quad"
corner = [-0.8, -0.8, -2.0]
edge_u = [1.6, 0.0, 0.0]
edge_v = [0.0, 1.6, 0.0]
material = "textured""#,
        r#"[[materials]]
name = "textured"
model = "lambert"
diffuse = [1.0, 1.0, 1.0]
diffuse_texture = "quadrants.png""#,
    );
    let scene = load(&dir, &text).unwrap();
    for (path, image) in common::both(&scene) {
        assert_quadrants_upright(&format!("quad, {path}"), &image);
    }
}

/// OBJ's v grows upwards, from the image's bottom row; the `.mtl` names the texture in another
/// case than its file has, as files made on systems that ignore case do.
#[test]
fn an_obj_map_kd_is_read_beside_its_library_whatever_its_case() {
    let dir = scratch("obj");
    quadrant_png(&dir.join("quadrants.png"));
    std::fs::write(
        dir.join("square.obj"),
        "mtllib square.mtl\nv -0.8 -0.8 -2\nv 0.8 -0.8 -2\nv 0.8 0.8 -2\nv -0.8 0.8 -2\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("square.mtl"),
        "newmtl painted\nKd 1 1 1\nmap_Kd QUADRANTS.PNG\n",
    )
    .unwrap();
    let text = square_scene(
        "[[shapes]]\ntype = \"mesh\"\nfile = \"square.obj\"\nsmooth = false",
        "",
    );
    let scene = load(&dir, &text).unwrap();
    for (path, image) in common::both(&scene) {
        assert_quadrants_upright(&format!("OBJ, {path}"), &image);
    }
}

/// KHR_texture_transform's example, "the lower left quadrant of the source image, rotated
/// clockwise 90°" (offset [0, 1], rotation π/2, scale 0.5), baked into the coordinates; the
/// sampler's wrap modes kept per axis.
#[test]
fn a_gltf_base_colour_texture_keeps_its_transform_and_wrap_modes() {
    use base64::Engine;
    let dir = scratch("gltf");
    let png = dir.join("quadrants.png");
    quadrant_png(&png);
    let png = base64::engine::general_purpose::STANDARD.encode(std::fs::read(&png).unwrap());
    let mut buffer = Vec::new();
    let positions = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let texcoords = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for p in positions.iter().flatten().chain(texcoords.iter().flatten()) {
        buffer.extend_from_slice(&p.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        buffer.extend_from_slice(&i.to_le_bytes());
    }
    let buffer = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"metallicFactor": 0.0, "baseColorTexture": {{"index": 0,
    "extensions": {{"KHR_texture_transform": {{"offset": [0, 1], "rotation": 1.5707963267948966, "scale": [0.5, 0.5]}}}}}}}}}}],
  "textures": [{{"source": 0, "sampler": 0}}],
  "samplers": [{{"wrapS": 33071, "wrapT": 33648}}],
  "images": [{{"uri": "data:image/png;base64,{png}"}}],
  "extensionsUsed": ["KHR_texture_transform"],
  "buffers": [{{"byteLength": 92, "uri": "data:application/octet-stream;base64,{buffer}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}]}}"#
    );
    let path = dir.join("square.gltf");
    std::fs::write(&path, gltf).unwrap();
    let read = chambre::scene::gltf::read_gltf(&path).unwrap();
    let texcoords = read.mesh.texcoords.expect("texture coordinates");
    let want = [[0.0, 1.0], [0.0, 0.5], [0.5, 0.5], [0.5, 1.0]];
    for (k, (got, want)) in texcoords.iter().zip(want).enumerate() {
        assert!(
            (got.x - want[0]).abs() < 1e-6 && (got.y - want[1]).abs() < 1e-6,
            "vertex {k}: ({}, {}), the extension's example gives {want:?}",
            got.x,
            got.y
        );
    }
    let texture = read.mesh.materials[0]
        .diffuse_texture
        .as_ref()
        .expect("the base colour texture");
    assert_eq!((texture.width, texture.height), (8, 8));
    assert_eq!(texture.wrap, [Wrap::Clamp, Wrap::Mirror]);
    assert!(read.notes.is_empty(), "{:?}", read.notes);
}

#[test]
fn a_texture_where_a_shape_has_no_coordinates_or_the_file_is_unreadable_is_refused_by_name() {
    let dir = scratch("refusals");
    quadrant_png(&dir.join("quadrants.png"));
    std::fs::write(
        dir.join("bare.obj"),
        "v 0 0 -2\nv 1 0 -2\nv 0 1 -2\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.join("broken.png"), b"not a png").unwrap();
    let material = |texture: &str| {
        format!("[[materials]]\nname = \"m\"\nmodel = \"lambert\"\ndiffuse_texture = \"{texture}\"")
    };
    let cases = [
        (
            material("quadrants.png"),
            "[[shapes]]\ntype = \"plane\"\npoint = [0.0, -1.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\nmaterial = \"m\"",
            &["shapes[0].material", "a plane has no texture coordinates"][..],
        ),
        (
            material("quadrants.png"),
            "[[shapes]]\ntype = \"mesh\"\nfile = \"bare.obj\"\nmaterial = \"m\"",
            &["shapes[0].material", "no texture coordinates"][..],
        ),
        (
            material("absent.png"),
            "",
            &["materials[0].diffuse_texture", "absent.png"][..],
        ),
        (
            material("broken.png"),
            "",
            &["materials[0].diffuse_texture", "broken.png", "image"][..],
        ),
        (
            "[[materials]]\nname = \"m\"\nmodel = \"lambert\"\ntexture_wrap = \"clamp\""
                .to_string(),
            "",
            &["materials[0].texture_wrap"][..],
        ),
        (
            "[[materials]]\nname = \"m\"\nmodel = \"mirror\"\ndiffuse_texture = \"quadrants.png\""
                .to_string(),
            "",
            &["materials[0].diffuse_texture", "no diffuse"][..],
        ),
    ];
    for (material, shape, expected) in cases {
        let e = load(&dir, &square_scene(shape, &material)).unwrap_err();
        for part in expected {
            assert!(e.contains(part), "`{e}` should name {part}");
        }
    }
}

/// A real file as it was made: the Sponza's `.mtl` names its textures in capitals that its
/// files do not have, and two of its materials share each of several. Every material with a
/// `map_Kd` gets its texture, each image read once.
#[test]
fn the_sponza_reads_every_map_kd_of_its_library_once() {
    let scene = common::load(
        "scenes/sponza.toml",
        &["render.width=16", "render.height=12"],
    );
    let mtl = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/sponza/sponza.mtl"),
    )
    .unwrap();
    let mut with_map = Vec::new();
    let mut current = String::new();
    for line in mtl.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix("newmtl ") {
            current = name.trim().to_string();
        } else if let Some(map) = line.strip_prefix("map_Kd ") {
            with_map.push((current.clone(), map.trim().to_lowercase()));
        }
    }
    assert_eq!(with_map.len(), 19, "materials with map_Kd");
    for (name, map) in &with_map {
        let material = scene
            .materials
            .iter()
            .find(|m| m.name.ends_with(&format!(":{name}")))
            .unwrap_or_else(|| panic!("material {name}"));
        let texture = material
            .diffuse_texture
            .as_ref()
            .unwrap_or_else(|| panic!("{name} has no texture"));
        let file = texture
            .source
            .file_name()
            .unwrap()
            .to_string_lossy()
            .to_lowercase();
        assert_eq!(&file, map, "{name}");
    }
    let distinct: std::collections::BTreeSet<_> = with_map.iter().map(|(_, m)| m).collect();
    assert_eq!(flatten(&scene).textures.len(), distinct.len());
}
