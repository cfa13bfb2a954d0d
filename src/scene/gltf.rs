//! glTF 2.0 files (`.gltf` with its buffers, or `.glb`), through the `gltf` crate: the triangles
//! of every mesh of the default scene placed by their node transforms, their materials mapped
//! to chambre's models, the first perspective camera, and KHR_lights_punctual lights. A mesh
//! shape can name a glTF file (`load_mesh`), and `chambre render model.glb` renders one as a
//! scene (`scene_text`). The mappings are in docs/scene-format.md ("glTF").

use std::path::Path;

use glam::{DMat4, DVec3, Vec3};

use super::mesh::{MeshMaterial, NO_MATERIAL, TriangleMesh};

/// Luminous efficacy (lm/W) at 555 nm: candela and lux to W/sr and W/m².
pub const LUMENS_PER_WATT: f64 = 683.0;

/// What a glTF file holds beside its triangles.
#[derive(Clone, Debug, Default)]
pub struct GltfScene {
    /// Every triangle of the default scene in world space, with its materials.
    pub mesh: TriangleMesh,
    /// The first perspective camera met in the node tree.
    pub camera: Option<GltfCamera>,
    /// KHR_lights_punctual lights, radiometric.
    pub lights: Vec<GltfLight>,
    /// What the mapping left out (textures), for the user to read.
    pub notes: Vec<String>,
}

/// A perspective camera, placed by its node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfCamera {
    /// Where it is, world space.
    pub position: DVec3,
    /// A point it looks at (one unit along its -Z axis).
    pub look_at: DVec3,
    /// Its +Y axis.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub vertical_fov: f64,
    /// Width over height, when the file gives it.
    pub aspect: Option<f64>,
}

/// A KHR_lights_punctual light in chambre's radiometric units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GltfLight {
    /// A point light.
    Point {
        /// World position.
        position: DVec3,
        /// Radiant intensity, W/sr: colour × candela / 683.
        intensity: Vec3,
    },
    /// A spot light.
    Spot {
        /// World position.
        position: DVec3,
        /// The unit direction it points along (the node's -Z axis).
        direction: DVec3,
        /// Radiant intensity on its axis, W/sr: colour × candela / 683.
        intensity: Vec3,
        /// `innerConeAngle`, degrees.
        inner_deg: f64,
        /// `outerConeAngle`, degrees.
        outer_deg: f64,
    },
    /// A directional light.
    Directional {
        /// The unit direction the light travels (the node's -Z axis).
        direction: DVec3,
        /// Irradiance at normal incidence, W/m²: colour × lux / 683.
        irradiance: Vec3,
    },
}

/// Reads a glTF or GLB file, with its first perspective camera: the error is a sentence
/// without the path (the caller adds it).
pub fn read_gltf(path: &Path) -> Result<GltfScene, String> {
    read_gltf_with_camera(path, None)
}

/// [`read_gltf`] with the perspective camera named `camera` (an error naming the cameras
/// found if there is none of that name), or the first when `None`.
pub fn read_gltf_with_camera(path: &Path, camera: Option<&str>) -> Result<GltfScene, String> {
    let gltf = gltf::Gltf::open(path).map_err(|e| format!("not a readable glTF file: {e}"))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| format!("reading its buffers: {e}"))?;
    let document = &gltf.document;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or("the file has no scene")?;
    let mut out = GltfScene {
        mesh: TriangleMesh {
            materials: document.materials().map(map_material).collect(),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut normals = Vec::new();
    let mut any_normals = false;
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                let added =
                    add_primitive(&mut out.mesh, &mut normals, &primitive, &buffers, world)?;
                any_normals |= added;
            }
        }
        if let (None, Some(found)) = (out.camera, node.camera())
            && camera.is_none_or(|name| found.name() == Some(name))
        {
            out.camera = Some(placed_camera(&found, world)?);
        }
        if let Some(light) = node.light() {
            out.lights.push(placed_light(&light, world));
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if let (Some(name), None) = (camera, out.camera) {
        let names: Vec<String> = document
            .cameras()
            .map(|c| format!("{:?}", c.name().unwrap_or("(unnamed)")))
            .collect();
        return Err(format!(
            "no camera named {name:?} in the default scene (cameras: {})",
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            }
        ));
    }
    if any_normals {
        out.mesh.normals = Some(normals);
    }
    // Primitives without a material take glTF's default one (white, metallic 1, roughness 1).
    if out.mesh.face_materials.contains(&NO_MATERIAL) {
        let default = out.mesh.materials.len() as u32;
        let white = map_factors("glTF default", Vec3::ONE, 1.0, 1.0, Vec3::ZERO);
        out.mesh.materials.push(white);
        for m in &mut out.mesh.face_materials {
            if *m == NO_MATERIAL {
                *m = default;
            }
        }
    }
    for material in document.materials() {
        let pbr = material.pbr_metallic_roughness();
        if pbr.base_color_texture().is_some() || pbr.metallic_roughness_texture().is_some() {
            out.notes.push(format!(
                "material {:?}: textures are not read; its factors are",
                material.name().unwrap_or("(unnamed)")
            ));
        }
    }
    Ok(out)
}

/// Appends a triangle primitive's vertices (placed by `world`) and triangles; returns whether
/// it had normals (a primitive without them gets zero normals, which the mesh code replaces
/// by the face's).
fn add_primitive(
    mesh: &mut TriangleMesh,
    normals: &mut Vec<Vec3>,
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: DMat4,
) -> Result<bool, String> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        return Err(format!(
            "a primitive of mode {:?}: only triangle lists are read",
            primitive.mode()
        ));
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or("a primitive without POSITION")?
        .collect();
    let first = mesh.positions.len() as u32;
    mesh.positions.extend(positions.iter().map(|&p| {
        world
            .transform_point3(DVec3::from(p.map(f64::from)))
            .as_vec3()
    }));
    let normal_matrix = world.inverse().transpose();
    let read_normals = reader.read_normals();
    let had_normals = read_normals.is_some();
    normals.resize(first as usize, Vec3::ZERO);
    match read_normals {
        Some(n) => normals.extend(n.map(|n| {
            let placed = normal_matrix.transform_vector3(DVec3::from(n.map(f64::from)));
            placed.normalize_or_zero().as_vec3()
        })),
        None => normals.extend(std::iter::repeat_n(Vec3::ZERO, positions.len())),
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(format!(
            "a primitive of {} indices, not triangles",
            indices.len()
        ));
    }
    let material = primitive
        .material()
        .index()
        .map_or(NO_MATERIAL, |i| i as u32);
    for t in indices.chunks_exact(3) {
        mesh.triangles
            .push([first + t[0], first + t[1], first + t[2]]);
        mesh.face_materials.push(material);
    }
    Ok(had_normals)
}

/// glTF's metallic-roughness material in chambre's models: metallic 1 and roughness 0 is a
/// mirror of the base colour; otherwise diffuse `base (1 - metallic)` and a Blinn-Phong lobe of
/// reflectance `0.04 (1 - metallic) + base metallic` and exponent `2 / α² - 2` with
/// `α = roughness²` (Walter et al.'s correspondence; at most 1e4); the emissive factor
/// becomes an emitter.
pub fn map_material(material: gltf::Material) -> MeshMaterial {
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    map_factors(
        material.name().unwrap_or("(unnamed)"),
        Vec3::new(r, g, b),
        pbr.metallic_factor(),
        pbr.roughness_factor(),
        Vec3::from(material.emissive_factor()),
    )
}

/// The mapping of [`map_material`], from the factors.
pub fn map_factors(
    name: &str,
    base: Vec3,
    metallic: f32,
    roughness: f32,
    emission: Vec3,
) -> MeshMaterial {
    let base = base.clamp(Vec3::ZERO, Vec3::ONE);
    let (metallic, roughness) = (metallic.clamp(0.0, 1.0), roughness.clamp(0.0, 1.0));
    let name = name.to_string();
    let emission = emission.max(Vec3::ZERO);
    if metallic >= 1.0 && roughness <= 0.0 {
        return MeshMaterial {
            name,
            mirror: base,
            emission,
            ..Default::default()
        };
    }
    let alpha = roughness * roughness;
    let exponent = if alpha > 0.0 {
        (2.0 / (alpha * alpha) - 2.0).clamp(0.0, 1.0e4)
    } else {
        1.0e4
    };
    MeshMaterial {
        name,
        diffuse: base * (1.0 - metallic),
        specular: Vec3::splat(0.04 * (1.0 - metallic)) + base * metallic,
        shininess: exponent,
        mirror: Vec3::ZERO,
        emission,
    }
}

fn placed_camera(camera: &gltf::Camera, world: DMat4) -> Result<GltfCamera, String> {
    let gltf::camera::Projection::Perspective(p) = camera.projection() else {
        return Err(format!(
            "camera {:?} is orthographic: chambre's cameras have a perspective",
            camera.name().unwrap_or("(unnamed)")
        ));
    };
    let position = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize();
    Ok(GltfCamera {
        position,
        look_at: position + forward,
        up: world.transform_vector3(DVec3::Y).normalize(),
        vertical_fov: (p.yfov() as f64).to_degrees(),
        aspect: p.aspect_ratio().map(f64::from),
    })
}

fn placed_light(light: &gltf::khr_lights_punctual::Light, world: DMat4) -> GltfLight {
    use gltf::khr_lights_punctual::Kind;
    let power = Vec3::from(light.color()) * (light.intensity() as f64 / LUMENS_PER_WATT) as f32;
    let position = world.transform_point3(DVec3::ZERO);
    let axis = world.transform_vector3(DVec3::NEG_Z).normalize();
    match light.kind() {
        Kind::Directional => GltfLight::Directional {
            direction: axis,
            irradiance: power,
        },
        Kind::Point => GltfLight::Point {
            position,
            intensity: power,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => GltfLight::Spot {
            position,
            direction: axis,
            intensity: power,
            inner_deg: (inner_cone_angle as f64).to_degrees(),
            outer_deg: (outer_cone_angle as f64).to_degrees(),
        },
    }
}

/// Image width of a glTF file rendered as a scene; the height follows the camera's aspect.
pub const DEFAULT_WIDTH: u32 = 960;

/// A glTF file as chambre scene text, so that `chambre render model.glb` renders it (with
/// `--set` overrides as for any scene): the file as one mesh shape with its own materials, its
/// perspective camera named `camera` or its first (or one framing its bounds: 40° vertical field of view, from above
/// the front right, the bounds filling the view), its lights (or, when it has none, a default
/// key light: a directional light of irradiance 3 from above the camera, and ambient 0.1).
pub fn scene_text(path: &Path, camera: Option<&str>) -> Result<String, String> {
    let scene = read_gltf_with_camera(path, camera)?;
    if scene.mesh.triangles.is_empty() {
        return Err("the file's default scene has no triangles".into());
    }
    let (lo, hi) = scene.mesh.positions.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(p.as_dvec3()), hi.max(p.as_dvec3())),
    );
    let camera = scene.camera.unwrap_or_else(|| framing_camera(lo, hi));
    let aspect = camera.aspect.unwrap_or(4.0 / 3.0).clamp(0.05, 20.0);
    let height = ((DEFAULT_WIDTH as f64 / aspect).round() as u32).max(1);
    let v = |d: DVec3| format!("[{:?}, {:?}, {:?}]", d.x, d.y, d.z);
    let absolute = std::path::absolute(path).map_err(|e| e.to_string())?;
    let mut text = format!(
        "[render]\nwidth = {DEFAULT_WIDTH}\nheight = {height}\n{}\n\
         [camera]\nposition = {}\nlook_at = {}\nup = {}\nvertical_fov = {:?}\n\
         film = [{:?}, 24.0]\n\n\
         [[shapes]]\ntype = \"mesh\"\nfile = {}\n",
        if scene.lights.is_empty() {
            "ambient = [0.1, 0.1, 0.1]\n"
        } else {
            ""
        },
        v(camera.position),
        v(camera.look_at),
        v(camera.up),
        camera.vertical_fov,
        24.0 * DEFAULT_WIDTH as f64 / height as f64,
        toml::Value::String(absolute.to_string_lossy().into_owned()),
    );
    let rgb = |c: Vec3| format!("[{:?}, {:?}, {:?}]", c.x, c.y, c.z);
    for light in &scene.lights {
        text += &match light {
            GltfLight::Point {
                position,
                intensity,
            } => format!(
                "\n[[lights]]\ntype = \"point\"\nposition = {}\nintensity = {}\n",
                v(*position),
                rgb(*intensity)
            ),
            GltfLight::Spot {
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
            } => format!(
                "\n[[lights]]\ntype = \"spot\"\nposition = {}\ndirection = {}\nintensity = {}\n\
                 outer_angle = {:?}\ninner_angle = {:?}\n",
                v(*position),
                v(*direction),
                rgb(*intensity),
                outer_deg.clamp(1e-3, 90.0),
                inner_deg.clamp(0.0, outer_deg.clamp(1e-3, 90.0) * 0.999),
            ),
            GltfLight::Directional {
                direction,
                irradiance,
            } => format!(
                "\n[[lights]]\ntype = \"directional\"\ndirection = {}\nirradiance = {}\n",
                v(*direction),
                rgb(*irradiance)
            ),
        };
    }
    if scene.lights.is_empty() {
        let forward = (camera.look_at - camera.position).normalize();
        let direction = (forward - camera.up.normalize() * 0.7).normalize();
        text += &format!(
            "\n[[lights]]\ntype = \"directional\"\ndirection = {}\nirradiance = [3.0, 3.0, 3.0]\n",
            v(direction)
        );
    }
    Ok(text)
}

/// A camera that frames the box `lo..hi`: 40° vertical field of view, looking at its centre
/// from the front right and above, far enough for the bounding sphere to fit the view.
fn framing_camera(lo: DVec3, hi: DVec3) -> GltfCamera {
    let centre = (lo + hi) / 2.0;
    let radius = ((hi - lo).length() / 2.0).max(1e-6);
    let distance = radius / 20f64.to_radians().sin();
    let position = centre + DVec3::new(0.4, 0.3, 1.0).normalize() * distance;
    GltfCamera {
        position,
        look_at: centre,
        up: DVec3::Y,
        vertical_fov: 40.0,
        aspect: None,
    }
}
