//! glTF 2.0 files (`.gltf` with its buffers, or `.glb`), through the `gltf` crate: the triangles
//! of every mesh of the default scene placed by their node transforms, their materials mapped
//! to chambre's models, its cameras (perspective or orthographic), and KHR_lights_punctual
//! lights; vertex attributes in floats or, with KHR_mesh_quantization, in small integers. A
//! mesh shape can name a glTF file (`load_mesh`), and `chambre render model.glb` renders one as
//! a scene (`scene_text`), with the first camera reached from the scene's nodes or the one
//! `gltf.camera` names. The mappings are in docs/scene-format.md ("glTF").

use std::path::Path;
use std::sync::Arc;

use glam::{DMat4, DVec3, Vec2, Vec3};

use gltf::accessor::{DataType, Dimensions, Item, Iter};

use super::mesh::{
    DEFAULT_IOR, IOR_RANGE, MAX_MESH_BYTES, MeshMaterial, NO_MATERIAL, TriangleMesh, check_mesh,
};
use super::texture::{Texture, Wrap};

/// Luminous efficacy (lm/W) at 555 nm: candela and lux to W/sr and W/m².
pub const LUMENS_PER_WATT: f64 = 683.0;

/// What a glTF file holds beside its triangles.
#[derive(Clone, Debug, Default)]
pub struct GltfScene {
    /// Every triangle of the default scene in world space, with its materials.
    pub mesh: TriangleMesh,
    /// Every camera node of the default scene, in the order a viewer reaches them: depth
    /// first, children in node order.
    pub cameras: Vec<CameraNode>,
    /// KHR_lights_punctual lights, radiometric.
    pub lights: Vec<GltfLight>,
    /// What the mapping left out (textures), for the user to read.
    pub notes: Vec<String>,
}

/// A camera as the file gives it, with the world transform of the node that places it.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraNode {
    /// Its index in the file's `cameras`.
    pub index: usize,
    /// Its `name`, if it has one.
    pub name: Option<String>,
    /// Its projection, unchecked.
    pub projection: RawProjection,
    /// The node's world transform.
    pub world: DMat4,
}

/// A glTF camera's projection as the file gives it (radians, scene units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RawProjection {
    /// `perspective`: `yfov` and `aspectRatio`.
    Perspective {
        /// Vertical field of view, radians.
        yfov: f32,
        /// Width over height, when given.
        aspect_ratio: Option<f32>,
    },
    /// `orthographic`: half the window's width and height.
    Orthographic {
        /// Half the width (scene units).
        xmag: f32,
        /// Half the height (scene units).
        ymag: f32,
    },
}

/// A checked camera, placed by its node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfCamera {
    /// Where it is, world space.
    pub position: DVec3,
    /// A point it looks at (one unit along its -Z axis).
    pub look_at: DVec3,
    /// Its +Y axis.
    pub up: DVec3,
    /// How it projects.
    pub projection: GltfProjection,
}

/// A checked glTF projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GltfProjection {
    /// Through a point.
    Perspective {
        /// Vertical field of view, degrees, in (0, 180).
        vertical_fov: f64,
        /// Width over height, when the file gives it.
        aspect: Option<f64>,
    },
    /// Parallel.
    Orthographic {
        /// Half the window's width (scene units), > 0.
        xmag: f64,
        /// Half the window's height (scene units), > 0.
        ymag: f64,
    },
}

impl GltfProjection {
    /// Width over height, when the camera fixes it: `aspectRatio`, or xmag / ymag.
    pub fn aspect(&self) -> Option<f64> {
        match *self {
            GltfProjection::Perspective { aspect, .. } => aspect,
            GltfProjection::Orthographic { xmag, ymag } => Some(xmag / ymag),
        }
    }
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

/// Reads a glTF or GLB file: the error is a sentence without the path (the caller adds it).
/// Its cameras are listed, not checked: a file read as a mesh does not need them.
pub fn read_gltf(path: &Path) -> Result<GltfScene, String> {
    let gltf = open_gltf(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| format!("reading its buffers: {e}"))?;
    let document = &gltf.document;
    let quantized = document.extensions_used().any(|name| name == QUANTIZATION);
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or("the file has no scene")?;
    check_node_trees(document, &scene)?;
    check_materials(document)?;
    check_lights(document)?;
    let textures = read_textures(document, base, &buffers)?;
    let (materials, texture_uses): (Vec<_>, Vec<_>) = document
        .materials()
        .map(|m| textured_material(m, &textures))
        .unzip();
    let mut out = GltfScene {
        mesh: TriangleMesh {
            materials,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut normals = Vec::new();
    let mut texcoords = Vec::new();
    let mut any_normals = false;
    // Depth first in node order: the stack holds the nodes still to visit in reverse.
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                let at = format!("meshes[{}].primitives[{}]", mesh.index(), primitive.index());
                let attributes = Attributes {
                    primitive: &primitive,
                    at: &at,
                    buffers: &buffers,
                    quantized,
                };
                let added = add_primitive(&mut out.mesh, &mut normals, &attributes, world)?;
                any_normals |= added;
                let vertices = out.mesh.positions.len();
                add_texcoords(&mut texcoords, &attributes, vertices, &texture_uses)?;
            }
        }
        if let Some(camera) = node.camera() {
            out.cameras.push(camera_node(&camera, world));
        }
        if let Some(light) = node.light() {
            out.lights.push(placed_light(&light, world));
        }
        let children: Vec<_> = node.children().map(|c| (c, world)).collect();
        stack.extend(children.into_iter().rev());
    }
    if any_normals {
        out.mesh.normals = Some(normals);
    }
    if texture_uses.iter().any(Option::is_some) {
        texcoords.resize(out.mesh.positions.len(), Vec2::ZERO);
        out.mesh.texcoords = Some(texcoords);
    }
    // Primitives without a material take a white Lambert: glTF's default (white, metallic 1,
    // roughness 1) as a rough conductor would keep a third of the light (Smith's GGX loses
    // what bounces between microfacets), where viewers show a light grey.
    if out.mesh.face_materials.contains(&NO_MATERIAL) {
        let default = out.mesh.materials.len() as u32;
        let white = MeshMaterial {
            name: "glTF default".to_string(),
            diffuse: Vec3::ONE,
            ..Default::default()
        };
        out.mesh.materials.push(white);
        for m in &mut out.mesh.face_materials {
            if *m == NO_MATERIAL {
                *m = default;
            }
        }
    }
    for material in document.materials() {
        out.notes.extend(material_notes(&material));
    }
    Ok(out)
}

/// The file parsed and checked by the gltf crate. An empty file is said to be one: the crate
/// would report that it could not read the four bytes of a GLB's magic.
fn open_gltf(path: &Path) -> Result<gltf::Gltf, String> {
    // The file is read whole, as a mesh or as a scene: bound it first.
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if size > MAX_MESH_BYTES {
        return Err(format!(
            "{size} bytes, more than the {MAX_MESH_BYTES} a mesh may have"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(
            "the file is empty: a glTF file is JSON with an `asset` object, or a GLB".into(),
        );
    }
    // A GLB's header (magic, version, length) says how long the file is.
    if let Some(declared) = bytes
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|length| u32::from_le_bytes(length.try_into().expect("four bytes")) as usize)
        .filter(|&declared| declared > bytes.len())
    {
        return Err(format!(
            "a GLB cut short: its header declares {declared} bytes, the file has {}",
            bytes.len()
        ));
    }
    let not_readable = |e: gltf::Error| format!("not a readable glTF file: {e}");
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes).map_err(not_readable)?;
    let errors = validation_errors(gltf.document.as_json());
    if !errors.is_empty() {
        return Err(not_readable(gltf::Error::Validation(errors)));
    }
    Ok(gltf)
}

/// The gltf crate's checks of a file, but for its refusal of the required extensions chambre
/// reads itself (the crate refuses every one it does not know).
fn validation_errors(
    json: &gltf::json::Root,
) -> Vec<(gltf::json::Path, gltf::json::validation::Error)> {
    use gltf::json::validation::{Error, Validate};
    let mut errors = Vec::new();
    json.validate(json, gltf::json::Path::new, &mut |path, error| {
        errors.push((path(), error))
    });
    // Such a refusal's path ends in the extension's name: `extensionsRequired[1] = "NAME"`.
    let read_here = |path: &gltf::json::Path| {
        READ_HERE
            .iter()
            .any(|name| path.as_str().ends_with(&format!("= \"{name}\"")))
    };
    errors.retain(|(path, error)| !(*error == Error::Unsupported && read_here(path)));
    errors
}

/// Extensions a file may require that chambre reads itself, the gltf crate not knowing them.
const READ_HERE: &[&str] = &[QUANTIZATION];

/// KHR_mesh_quantization: vertex attributes in 8- and 16-bit integers (normalized or not),
/// placed by their nodes' transforms; gltfpack and glTF-Transform write it.
const QUANTIZATION: &str = "KHR_mesh_quantization";

/// glTF's nodes form disjoint strict trees (a node has one parent at most, and no node is its
/// own ancestor), of which a scene lists the roots, each once. A file that breaks this is
/// refused: its traversal would never end on a cycle, and would place a subtree again (as
/// often as the paths to it, exponentially many) under a node of several parents.
fn check_node_trees(document: &gltf::Document, scene: &gltf::Scene) -> Result<(), String> {
    let children: Vec<Vec<usize>> = document
        .nodes()
        .map(|n| n.children().map(|c| c.index()).collect())
        .collect();
    let mut parent: Vec<Option<usize>> = vec![None; children.len()];
    for (n, list) in children.iter().enumerate() {
        for &c in list {
            match parent[c] {
                Some(p) if p == n => {
                    return Err(format!("nodes[{n}].children: lists nodes[{c}] twice"));
                }
                Some(p) => {
                    return Err(format!(
                        "nodes[{n}].children: nodes[{c}] is already a child of nodes[{p}]; \
                         glTF's nodes form disjoint trees, a node having one parent at most"
                    ));
                }
                None => parent[c] = Some(n),
            }
        }
    }
    if let Some(n) = node_on_cycle(&children, &parent) {
        let p = parent[n].unwrap_or(n);
        return Err(format!(
            "nodes[{p}].children: nodes[{n}] is {} (a cycle); glTF's nodes form strict trees",
            if p == n {
                "the node itself"
            } else {
                "its ancestor"
            }
        ));
    }
    let mut listed = vec![false; children.len()];
    for root in scene.nodes().map(|n| n.index()) {
        if let Some(p) = parent[root] {
            return Err(format!(
                "scenes[{}].nodes: nodes[{root}] is a child of nodes[{p}], not a root node",
                scene.index()
            ));
        }
        if std::mem::replace(&mut listed[root], true) {
            return Err(format!(
                "scenes[{}].nodes: lists nodes[{root}] twice",
                scene.index()
            ));
        }
    }
    Ok(())
}

/// A node on a cycle of children, given each node's only parent: nodes that no walk down from a
/// parentless node reaches lie on a cycle or below one, and going up from one of them as many
/// times as there are nodes ends on the cycle.
fn node_on_cycle(children: &[Vec<usize>], parent: &[Option<usize>]) -> Option<usize> {
    let mut reached = vec![false; children.len()];
    let mut stack: Vec<usize> = (0..children.len())
        .filter(|&n| parent[n].is_none())
        .collect();
    while let Some(n) = stack.pop() {
        reached[n] = true;
        stack.extend(&children[n]);
    }
    let unreached = reached.iter().position(|r| !r)?;
    // An unreached node's parent is unreached too, so there always is one to go up to.
    Some((0..children.len()).fold(unreached, |n, _| parent[n].unwrap_or(n)))
}

/// The factors glTF bounds: base colour, metallic and roughness in [0, 1]; the emissive factor,
/// which becomes an emitter's radiance, non-negative and at most `MAX_RADIOMETRIC` as a
/// scene's radiometric values are (glTF bounds it by 1, but files brighten emitters past that).
fn check_materials(document: &gltf::Document) -> Result<(), String> {
    use super::validate::MAX_RADIOMETRIC;
    for material in document.materials() {
        let at = format!("materials[{}]", material.index().unwrap_or_default());
        let pbr = material.pbr_metallic_roughness();
        let base = pbr.base_color_factor();
        for (field, values) in [
            ("pbrMetallicRoughness.baseColorFactor", &base[..]),
            (
                "pbrMetallicRoughness.metallicFactor",
                &[pbr.metallic_factor()],
            ),
            (
                "pbrMetallicRoughness.roughnessFactor",
                &[pbr.roughness_factor()],
            ),
        ] {
            if !values.iter().all(|v| (0.0..=1.0).contains(v)) {
                let got = match values {
                    [v] => format!("{v:?}"),
                    _ => format!("{values:?}"),
                };
                return Err(format!("{at}.{field}: must lie in [0, 1], got {got}"));
            }
        }
        let strength = material.emissive_strength().unwrap_or(1.0);
        if !(strength >= 0.0 && strength.is_finite()) {
            return Err(format!(
                "{at}.extensions.KHR_materials_emissive_strength.emissiveStrength: must be a \
                 non-negative number, got {strength:?}"
            ));
        }
        let emissive = material.emissive_factor();
        if !emissive
            .iter()
            .all(|&v| (0.0..=MAX_RADIOMETRIC).contains(&(v as f64 * strength as f64)))
        {
            let times = match material.emissive_strength() {
                Some(strength) => format!(" once multiplied by its emissiveStrength {strength:?}"),
                None => String::new(),
            };
            return Err(format!(
                "{at}.emissiveFactor: must lie in [0, {MAX_RADIOMETRIC:e}]{times} (sums of \
                 samples would overflow the 32-bit floats of the render), got {emissive:?}"
            ));
        }
        check_transmission(&material, &at)?;
    }
    Ok(())
}

/// KHR_materials_transmission's factor in [0, 1], and KHR_materials_ior's index from 1 (as
/// glTF requires) to the largest chambre's glass takes (`IOR_RANGE`).
fn check_transmission(material: &gltf::Material, at: &str) -> Result<(), String> {
    if let Some(transmission) = material.transmission() {
        let factor = transmission.transmission_factor();
        if !(0.0..=1.0).contains(&factor) {
            return Err(format!(
                "{at}.extensions.KHR_materials_transmission.transmissionFactor: must lie in \
                 [0, 1], got {factor:?}"
            ));
        }
    }
    let ior = material.ior().unwrap_or(DEFAULT_IOR);
    let high = *IOR_RANGE.end();
    if !(1.0..=high).contains(&f64::from(ior)) {
        return Err(format!(
            "{at}.extensions.KHR_materials_ior.ior: must lie in [1, {high}], got {ior:?}"
        ));
    }
    Ok(())
}

/// What the mapping of `material` leaves out or approximates, for the user to read.
fn material_notes(material: &gltf::Material) -> Vec<String> {
    let name = material.name().unwrap_or("(unnamed)");
    let pbr = material.pbr_metallic_roughness();
    let mut notes = Vec::new();
    if pbr.metallic_roughness_texture().is_some() {
        notes.push(format!(
            "material {name:?}: its metallic-roughness texture is not read; its factors are"
        ));
    }
    let transmission = material.transmission();
    let factor = transmission
        .as_ref()
        .map_or(0.0, |t| t.transmission_factor());
    if factor > 0.0 && pbr.metallic_factor() < 1.0 {
        let approximated = [
            (
                factor < 1.0,
                format!("a transmission of {factor} as a whole one"),
            ),
            (
                pbr.roughness_factor() > 0.0,
                format!("a roughness of {} as smooth", pbr.roughness_factor()),
            ),
            (
                transmission.is_some_and(|t| t.transmission_texture().is_some()),
                "its transmission texture as its factor".to_string(),
            ),
        ];
        for (_, what) in approximated.into_iter().filter(|(applies, _)| *applies) {
            notes.push(format!(
                "material {name:?}: glass under the path tracer, which renders {what}"
            ));
        }
    }
    notes
}

/// KHR_lights_punctual's bounds: a colour in [0, 1], a non-negative intensity that makes a
/// radiometric value of at most `MAX_RADIOMETRIC`, as a scene's lights have, and a spot's
/// `0 <= innerConeAngle < outerConeAngle <= pi/2`.
fn check_lights(document: &gltf::Document) -> Result<(), String> {
    use super::validate::MAX_RADIOMETRIC;
    for light in document.lights().into_iter().flatten() {
        let at = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let color = light.color();
        if !color.iter().all(|c| (0.0..=1.0).contains(c)) {
            return Err(format!("{at}.color: must lie in [0, 1], got {color:?}"));
        }
        let intensity = light.intensity();
        let radiometric = intensity as f64 / LUMENS_PER_WATT;
        if !(intensity >= 0.0 && radiometric <= MAX_RADIOMETRIC) {
            return Err(format!(
                "{at}.intensity: must lie in [0, {:e}] (chambre's bound of {MAX_RADIOMETRIC:e} \
                 W/sr or W/m², times {LUMENS_PER_WATT} lm/W), got {intensity:?}",
                MAX_RADIOMETRIC * LUMENS_PER_WATT
            ));
        }
        if let gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle: inner,
            outer_cone_angle: outer,
        } = light.kind()
        {
            if !(outer > 0.0 && outer <= std::f32::consts::FRAC_PI_2) {
                return Err(format!(
                    "{at}.spot.outerConeAngle: must lie in (0, pi/2] radians, got {outer:?}"
                ));
            }
            if !(0.0..outer).contains(&inner) {
                return Err(format!(
                    "{at}.spot.innerConeAngle: must lie in [0, outerConeAngle = {outer:?}) \
                     radians, got {inner:?}"
                ));
            }
        }
    }
    Ok(())
}

/// Which component types (each with whether it is normalized) and which element type glTF
/// allows an accessor chambre reads, and how messages name them; with KHR_mesh_quantization,
/// which more.
struct Layout {
    components: &'static [(DataType, bool)],
    dimensions: Dimensions,
    allowed: &'static str,
    quantized: &'static [(DataType, bool)],
    quantized_allowed: &'static str,
}

const INDICES: Layout = Layout {
    components: &[
        (DataType::U8, false),
        (DataType::U16, false),
        (DataType::U32, false),
    ],
    dimensions: Dimensions::Scalar,
    allowed: "unsigned byte, unsigned short or unsigned int SCALAR",
    quantized: &[],
    quantized_allowed: "",
};

/// The 8- and 16-bit integers, normalized or not.
const SMALL_INTEGERS: &[(DataType, bool)] = &[
    (DataType::I8, false),
    (DataType::I8, true),
    (DataType::U8, false),
    (DataType::U8, true),
    (DataType::I16, false),
    (DataType::I16, true),
    (DataType::U16, false),
    (DataType::U16, true),
];

const POSITION: Layout = Layout {
    components: &[(DataType::F32, false)],
    dimensions: Dimensions::Vec3,
    allowed: "float VEC3",
    quantized: SMALL_INTEGERS,
    quantized_allowed: "byte, unsigned byte, short or unsigned short VEC3, normalized or not",
};

const NORMAL: Layout = Layout {
    components: &[(DataType::F32, false)],
    dimensions: Dimensions::Vec3,
    allowed: "float VEC3",
    quantized: &[(DataType::I8, true), (DataType::I16, true)],
    quantized_allowed: "normalized byte or normalized short VEC3",
};

const TEXCOORD: Layout = Layout {
    components: &[
        (DataType::F32, false),
        (DataType::U8, true),
        (DataType::U16, true),
    ],
    dimensions: Dimensions::Vec2,
    allowed: "float, normalized unsigned byte or normalized unsigned short VEC2",
    quantized: SMALL_INTEGERS,
    quantized_allowed: "byte, unsigned byte, short or unsigned short VEC2, normalized or not",
};

/// How glTF names a component type.
fn component_name(data_type: DataType) -> &'static str {
    match data_type {
        DataType::I8 => "byte",
        DataType::U8 => "unsigned byte",
        DataType::I16 => "short",
        DataType::U16 => "unsigned short",
        DataType::U32 => "unsigned int",
        DataType::F32 => "float",
    }
}

/// How glTF names an element type.
fn dimensions_name(dimensions: Dimensions) -> &'static str {
    match dimensions {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// Checks that `accessor` (which `label` names, `meshes[0].primitives[0].indices ->
/// accessors[2]`) has a type of `layout` (with its `quantized` types where the file uses
/// KHR_mesh_quantization), and that each of its elements lies inside its buffer view and each
/// view inside its buffer. The gltf crate's readers would panic on another type, and give
/// nothing for data past the end, which reads as an absent attribute.
fn check_accessor(
    accessor: &gltf::Accessor,
    label: &str,
    layout: &Layout,
    quantized: bool,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let component = (accessor.data_type(), accessor.normalized());
    let with_quantization = layout.quantized.contains(&component);
    if accessor.dimensions() != layout.dimensions
        || !(layout.components.contains(&component) || quantized && with_quantization)
    {
        let hint =
            match with_quantization && !quantized && accessor.dimensions() == layout.dimensions {
                true => format!(
                    " (and {}, in a file whose extensionsUsed lists {QUANTIZATION})",
                    layout.quantized_allowed
                ),
                false => String::new(),
            };
        return Err(format!(
            "{label}: {}{} {}, where glTF allows {}{hint}",
            if component.1 { "normalized " } else { "" },
            component_name(component.0),
            dimensions_name(accessor.dimensions()),
            match quantized && !layout.quantized.is_empty() {
                true => format!("{} or {}", layout.allowed, layout.quantized_allowed),
                false => layout.allowed.to_string(),
            }
        ));
    }
    if let Some(view) = accessor.view() {
        check_span(
            label,
            &view,
            accessor.offset(),
            accessor.count(),
            accessor.size(),
        )?;
    }
    if let Some(sparse) = accessor.sparse() {
        let (indices, values) = (sparse.indices(), sparse.values());
        let size = indices.index_type().size();
        let at = format!("{label}.sparse.indices");
        check_span(&at, &indices.view(), indices.offset(), sparse.count(), size)?;
        let at = format!("{label}.sparse.values");
        check_span(
            &at,
            &values.view(),
            values.offset(),
            sparse.count(),
            accessor.size(),
        )?;
        check_sparse_indices(&sparse, label, accessor.count(), buffers)?;
    }
    Ok(())
}

/// Checks that a sparse accessor's indices rise and stay below its `count`, as glTF requires:
/// the gltf crate's reader puts a value in only where the next index is the element it is at,
/// so one out of order or past the end would leave its value out without a word. Its span
/// has been checked (`check_span`).
fn check_sparse_indices(
    sparse: &gltf::accessor::sparse::Sparse,
    label: &str,
    count: usize,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let indices = sparse.indices();
    let view = indices.view();
    let size = indices.index_type().size();
    let stride = view.stride().unwrap_or(size);
    let data = buffers
        .get(view.buffer().index())
        .map_or(&[][..], |d| &d.0[..]);
    let mut previous = None;
    for i in 0..sparse.count() {
        let at = view.offset() + indices.offset() + i * stride;
        let bytes = data.get(at..at + size).unwrap_or_default();
        let index = bytes
            .iter()
            .rev()
            .fold(0u64, |v, &b| (v << 8) | u64::from(b));
        if bytes.len() < size || index >= count as u64 || previous.is_some_and(|p| index <= p) {
            return Err(format!(
                "{label}.sparse.indices: element {i} is {index}, where glTF requires indices \
                 that rise, each below the accessor's count {count}"
            ));
        }
        previous = Some(index);
    }
    Ok(())
}

/// Checks that `count` elements of `size` bytes, from byte `offset` of `view` and its stride
/// apart, lie inside it, and it inside its buffer (whose data the gltf crate has checked to be
/// as long as it says).
fn check_span(
    label: &str,
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    size: usize,
) -> Result<(), String> {
    let v = view.index();
    let stride = view.stride().unwrap_or(size);
    if count == 0 {
        return Err(format!(
            "{label}: has no elements (glTF requires a count of 1 or more)"
        ));
    }
    if stride < size {
        return Err(format!(
            "{label}: bufferViews[{v}].byteStride {stride} is less than its {size}-byte elements"
        ));
    }
    let end = (count as u128 - 1) * stride as u128 + size as u128 + offset as u128;
    if end > view.length() as u128 {
        return Err(format!(
            "{label}: its {count} elements of {size} bytes from byte {offset}, {stride} apart, \
             end at byte {end}, past the {} bytes of bufferViews[{v}]",
            view.length()
        ));
    }
    let buffer = view.buffer();
    let view_end = view.offset() as u128 + view.length() as u128;
    if view_end > buffer.length() as u128 {
        return Err(format!(
            "{label}: bufferViews[{v}] (bytes {} to {view_end}) lies past the end of the {} \
             bytes of buffers[{}]",
            view.offset(),
            buffer.length(),
            buffer.index()
        ));
    }
    Ok(())
}

/// A primitive whose attributes are read: how messages name it (`meshes[0].primitives[1]`),
/// the file's buffers, and whether the file uses KHR_mesh_quantization.
struct Attributes<'a> {
    primitive: &'a gltf::Primitive<'a>,
    at: &'a str,
    buffers: &'a [gltf::buffer::Data],
    quantized: bool,
}

impl Attributes<'_> {
    /// The elements of the attribute `semantic` as floats, once checked for `layout`, for as
    /// many elements as the primitive has `vertices` (when known) and for finite values; `None`
    /// when the primitive has no such attribute. A normalized integer `c` reads as glTF maps
    /// it, `c / 255` or `c / 65535` unsigned and `max(c / 127, -1)` or `max(c / 32767, -1)`
    /// signed; an integer not normalized as its value.
    fn read<const N: usize>(
        &self,
        semantic: gltf::Semantic,
        layout: &Layout,
        vertices: Option<usize>,
    ) -> Result<Option<Vec<[f32; N]>>, String>
    where
        [f32; N]: Item,
        [i8; N]: Item,
        [u8; N]: Item,
        [i16; N]: Item,
        [u16; N]: Item,
    {
        fn floats<T: Copy, const N: usize>(
            items: Option<Iter<[T; N]>>,
            to_float: impl Fn(T) -> f32,
        ) -> Option<Vec<[f32; N]>>
        where
            [T; N]: Item,
        {
            Some(items?.map(|item| item.map(&to_float)).collect())
        }
        let Some((accessor, label)) = self.checked(semantic, layout, vertices)? else {
            return Ok(None);
        };
        let data = |buffer: gltf::Buffer| self.buffers.get(buffer.index()).map(|d| &d.0[..]);
        let normalized = accessor.normalized();
        let scaled = move |c: f32, max: f32| match normalized {
            true => (c / max).max(-1.0),
            false => c,
        };
        let values = match accessor.data_type() {
            DataType::F32 => floats(Iter::<[f32; N]>::new(accessor, data), |c| c),
            DataType::I8 => floats(Iter::<[i8; N]>::new(accessor, data), |c| {
                scaled(f32::from(c), 127.0)
            }),
            DataType::U8 => floats(Iter::<[u8; N]>::new(accessor, data), |c| {
                scaled(f32::from(c), 255.0)
            }),
            DataType::I16 => floats(Iter::<[i16; N]>::new(accessor, data), |c| {
                scaled(f32::from(c), 32767.0)
            }),
            DataType::U16 => floats(Iter::<[u16; N]>::new(accessor, data), |c| {
                scaled(f32::from(c), 65535.0)
            }),
            DataType::U32 => None,
        };
        // The gltf crate gives `None` for data it cannot reach, which the checks rule out.
        let values = values.ok_or_else(|| format!("{label}: its data cannot be read"))?;
        if let Some(i) = first_non_finite(&values) {
            return Err(format!(
                "{label}: element {i} is not finite: {:?}",
                values[i]
            ));
        }
        Ok(Some(values))
    }

    /// The accessor of the attribute `semantic`, checked for `layout` and for as many elements
    /// as the primitive has `vertices` (when known), with how messages name it; `None` when the
    /// primitive has no such attribute.
    fn checked(
        &self,
        semantic: gltf::Semantic,
        layout: &Layout,
        vertices: Option<usize>,
    ) -> Result<Option<(gltf::Accessor<'_>, String)>, String> {
        let Some(accessor) = self.primitive.get(&semantic) else {
            return Ok(None);
        };
        let label = format!(
            "{}.attributes.{} -> accessors[{}]",
            self.at,
            semantic.to_string(),
            accessor.index()
        );
        check_accessor(&accessor, &label, layout, self.quantized, self.buffers)?;
        if let Some(n) = vertices.filter(|&n| n != accessor.count()) {
            return Err(format!(
                "{label}: has {} elements where POSITION has {n}",
                accessor.count()
            ));
        }
        Ok(Some((accessor, label)))
    }
}

/// What a reader of a checked accessor gave, or an error naming it: the gltf crate gives
/// `None` for data it cannot reach, which the checks before rule out.
fn read<T>(data: Option<T>, label: &str) -> Result<T, String> {
    data.ok_or_else(|| format!("{label}: its data cannot be read"))
}

/// The index of the first element of `values` with a component that is not finite.
fn first_non_finite<const N: usize>(values: &[[f32; N]]) -> Option<usize> {
    values.iter().position(|v| !v.iter().all(|c| c.is_finite()))
}

/// Appends a triangle primitive's vertices (placed by `world`) and triangles; returns whether
/// it had normals (a primitive without them gets zero normals, which the mesh code replaces
/// by the face's).
fn add_primitive(
    mesh: &mut TriangleMesh,
    normals: &mut Vec<Vec3>,
    attributes: &Attributes,
    world: DMat4,
) -> Result<bool, String> {
    let (primitive, at, buffers) = (attributes.primitive, attributes.at, attributes.buffers);
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        return Err(format!(
            "{at}.mode: {:?}: only triangle lists are read",
            primitive.mode()
        ));
    }
    let positions = attributes
        .read::<3>(gltf::Semantic::Positions, &POSITION, None)?
        .ok_or_else(|| format!("{at}.attributes: has no POSITION"))?;
    let first = mesh.positions.len() as u32;
    mesh.positions.extend(positions.iter().map(|&p| {
        world
            .transform_point3(DVec3::from(p.map(f64::from)))
            .as_vec3()
    }));
    let had_normals = add_normals(normals, attributes, positions.len(), world)?;
    let indices = read_indices(primitive, at, buffers, positions.len())?;
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

/// Appends the `vertices` normals of a primitive (turned by `world`), zero when it has none;
/// returns whether it had them.
fn add_normals(
    normals: &mut Vec<Vec3>,
    attributes: &Attributes,
    vertices: usize,
    world: DMat4,
) -> Result<bool, String> {
    let first = normals.len();
    let semantic = gltf::Semantic::Normals;
    let Some(read) = attributes.read::<3>(semantic, &NORMAL, Some(vertices))? else {
        normals.resize(first + vertices, Vec3::ZERO);
        return Ok(false);
    };
    let normal_matrix = world.inverse().transpose();
    normals.extend(read.iter().map(|&n| {
        let placed = normal_matrix.transform_vector3(DVec3::from(n.map(f64::from)));
        placed.normalize_or_zero().as_vec3()
    }));
    Ok(true)
}

/// A primitive's vertex indices, each below `vertices`, in threes; `0..vertices` when it has
/// none.
fn read_indices(
    primitive: &gltf::Primitive,
    at: &str,
    buffers: &[gltf::buffer::Data],
    vertices: usize,
) -> Result<Vec<u32>, String> {
    let Some(accessor) = primitive.indices() else {
        if !vertices.is_multiple_of(3) {
            return Err(format!(
                "{at}: {vertices} vertices without indices, not a list of triangles"
            ));
        }
        return Ok((0..vertices as u32).collect());
    };
    let label = format!("{at}.indices -> accessors[{}]", accessor.index());
    check_accessor(&accessor, &label, &INDICES, false, buffers)?;
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let indices: Vec<u32> = read(reader.read_indices(), &label)?.into_u32().collect();
    if !indices.len().is_multiple_of(3) {
        return Err(format!(
            "{label}: {} indices, not a list of triangles",
            indices.len()
        ));
    }
    if let Some(i) = indices.iter().position(|&v| v as usize >= vertices) {
        return Err(format!(
            "{label}: element {i} is {}, past the {vertices} vertices of POSITION",
            indices[i]
        ));
    }
    Ok(indices)
}

/// How a material reads its base colour texture: from which TEXCOORD set, through which
/// KHR_texture_transform (baked into the coordinates of the primitives that use it).
#[derive(Clone, Copy, Debug, PartialEq)]
struct TextureUse {
    set: u32,
    /// offset, rotation (radians), scale, as the extension gives them.
    transform: Option<([f32; 2], f32, [f32; 2])>,
}

/// Every texture of the file, decoded, with its sampler's wrap modes; `None` for a texture no
/// base colour uses (it is never decoded).
fn read_textures(
    document: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Result<Vec<Option<Arc<Texture>>>, String> {
    let used: Vec<usize> = document
        .materials()
        .filter_map(|m| m.pbr_metallic_roughness().base_color_texture())
        .map(|info| info.texture().index())
        .collect();
    document
        .textures()
        .map(|texture| {
            if !used.contains(&texture.index()) {
                return Ok(None);
            }
            let image = texture.source();
            let (bytes, source) = image_bytes(&image, base, buffers)
                .map_err(|e| format!("image {}: {e}", image.index()))?;
            let decoded = Texture::decode(&bytes, &source)
                .map_err(|e| format!("image {} ({}): {e}", image.index(), source.display()))?;
            let sampler = texture.sampler();
            let wrap = [sampler.wrap_s(), sampler.wrap_t()].map(|mode| match mode {
                gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
                gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
                gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            });
            Ok(Some(Arc::new(Texture { wrap, ..decoded })))
        })
        .collect()
}

/// The encoded bytes of `image` and where they came from: a buffer view, a `data:` URI, or a
/// file beside the glTF file.
fn image_bytes(
    image: &gltf::Image,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Result<(Vec<u8>, std::path::PathBuf), String> {
    use base64::Engine;
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = buffers.get(view.buffer().index()).ok_or("no such buffer")?;
            let bytes = buffer
                .0
                .get(view.offset()..view.offset() + view.length())
                .ok_or("its buffer view lies beyond its buffer")?;
            Ok((
                bytes.to_vec(),
                base.join(format!("image {}", image.index())),
            ))
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(data) => {
                let (_, encoded) = data
                    .split_once(";base64,")
                    .ok_or("a data URI not in base64")?;
                let bytes = base64::engine::general_purpose::STANDARD
                    .decode(encoded)
                    .map_err(|e| format!("its data URI: {e}"))?;
                Ok((bytes, base.join(format!("image {}", image.index()))))
            }
            None => {
                let path = base.join(percent_decoded(uri));
                let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
                Ok((bytes, path))
            }
        },
    }
}

/// A URI's path with its %XX escapes decoded.
fn percent_decoded(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (byte, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A material mapped by [`map_material`] with its base colour texture, and how it reads it.
fn textured_material(
    material: gltf::Material,
    textures: &[Option<Arc<Texture>>],
) -> (MeshMaterial, Option<TextureUse>) {
    let info = material.pbr_metallic_roughness().base_color_texture();
    let texture_use = info.as_ref().map(|info| {
        let transform = info.texture_transform();
        TextureUse {
            set: transform
                .as_ref()
                .and_then(|t| t.tex_coord())
                .unwrap_or(info.tex_coord()),
            transform: transform.map(|t| (t.offset(), t.rotation(), t.scale())),
        }
    });
    let texture = info.and_then(|info| textures.get(info.texture().index()).cloned().flatten());
    let mapped = MeshMaterial {
        diffuse_texture: texture,
        ..map_material(material)
    };
    (mapped, texture_use)
}

/// Appends a primitive's texture coordinates, up to `vertices` (those of the vertices before
/// it and its own), from the set its material's base colour texture reads, through its
/// KHR_texture_transform; zero for a primitive whose material has no texture.
fn add_texcoords(
    texcoords: &mut Vec<Vec2>,
    attributes: &Attributes,
    vertices: usize,
    texture_uses: &[Option<TextureUse>],
) -> Result<(), String> {
    let own = vertices - texcoords.len();
    let (primitive, at) = (attributes.primitive, attributes.at);
    let material = primitive.material().index();
    let used = material.and_then(|m| texture_uses.get(m).copied().flatten());
    if let Some(texture_use) = used {
        let set = texture_use.set;
        let semantic = gltf::Semantic::TexCoords(set);
        let missing = || {
            format!(
                "{at}.attributes: has no TEXCOORD_{set}, which the baseColorTexture of \
                 materials[{}] reads",
                material.unwrap_or_default()
            )
        };
        let read = attributes
            .read::<2>(semantic, &TEXCOORD, Some(own))?
            .ok_or_else(missing)?;
        texcoords.extend(
            read.iter()
                .map(|&uv| transformed(Vec2::from(uv), texture_use)),
        );
    }
    texcoords.resize(vertices, Vec2::ZERO);
    Ok(())
}

/// `uv` through KHR_texture_transform: scaled, rotated by `rotation` radians (anticlockwise
/// in the image as it is shown, v growing downwards), then offset.
fn transformed(uv: Vec2, texture_use: TextureUse) -> Vec2 {
    let Some((offset, rotation, scale)) = texture_use.transform else {
        return uv;
    };
    let s = uv * Vec2::from(scale);
    let (sin, cos) = rotation.sin_cos();
    Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y) + Vec2::from(offset)
}

/// glTF's metallic-roughness material in chambre's models: metallic 1 and roughness 0 is a
/// mirror of the base colour, metallic 1 and roughness r > 0 a rough conductor of reflectance
/// the base colour and GGX alpha r²; otherwise diffuse `base (1 - metallic)` and a Blinn-Phong lobe of
/// reflectance `0.04 (1 - metallic) + base metallic` and exponent `2 / α² - 2` with
/// `α = roughness²` (Walter et al.'s correspondence; at most 1e4); the emissive factor, times
/// KHR_materials_emissive_strength's strength, becomes an emitter; a dielectric with a
/// KHR_materials_transmission factor above 0 becomes glass of KHR_materials_ior's index.
pub fn map_material(material: gltf::Material) -> MeshMaterial {
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let strength = material.emissive_strength().unwrap_or(1.0);
    let mapped = map_factors(
        material.name().unwrap_or("(unnamed)"),
        Vec3::new(r, g, b),
        pbr.metallic_factor(),
        pbr.roughness_factor(),
        Vec3::from(material.emissive_factor()) * strength,
    );
    // A dielectric that lets light through is glass under the path tracer (a metal's
    // transmission is none, as glTF defines it); Whitted's integrator keeps the factors' lobes.
    let transmits = material
        .transmission()
        .is_some_and(|t| t.transmission_factor() > 0.0);
    let ior =
        (transmits && pbr.metallic_factor() < 1.0).then(|| material.ior().unwrap_or(DEFAULT_IOR));
    MeshMaterial { ior, ..mapped }
}

/// The mapping of [`map_material`], from factors within glTF's bounds (base colour, metallic
/// and roughness in [0, 1], emission non-negative), which `read_gltf` checks.
pub fn map_factors(
    name: &str,
    base: Vec3,
    metallic: f32,
    roughness: f32,
    emission: Vec3,
) -> MeshMaterial {
    let name = name.to_string();
    if metallic >= 1.0 && roughness <= 0.0 {
        return MeshMaterial {
            name,
            mirror: base,
            emission,
            ..Default::default()
        };
    }
    if metallic >= 1.0 {
        return MeshMaterial {
            name,
            specular: base,
            emission,
            conductor_roughness: Some(roughness),
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
        ior: None,
        diffuse_texture: None,
        conductor_roughness: None,
    }
}

fn camera_node(camera: &gltf::Camera, world: DMat4) -> CameraNode {
    use gltf::camera::Projection;
    CameraNode {
        index: camera.index(),
        name: camera.name().map(str::to_string),
        projection: match camera.projection() {
            Projection::Perspective(p) => RawProjection::Perspective {
                yfov: p.yfov(),
                aspect_ratio: p.aspect_ratio(),
            },
            Projection::Orthographic(o) => RawProjection::Orthographic {
                xmag: o.xmag(),
                ymag: o.ymag(),
            },
        },
        world,
    }
}

impl CameraNode {
    /// How messages name it: `camera 1 "side"`, or `camera 0` when it has no name.
    pub fn label(&self) -> String {
        match &self.name {
            Some(name) => format!("camera {} {name:?}", self.index),
            None => format!("camera {}", self.index),
        }
    }

    /// The camera checked and placed: a perspective one's `yfov` in (0, pi) and `aspectRatio`
    /// positive, an orthographic one's `xmag` and `ymag` positive (glTF forbids 0; a negative
    /// one, which glTF discourages, would mirror the image), all finite, and its node's
    /// transform invertible (its -Z and +Y axes give the view).
    pub fn placed(&self) -> Result<GltfCamera, String> {
        let at = |field: &str, why: &str, value: f32| {
            format!("{}: {field} {why}, got {value}", self.label())
        };
        let projection = match self.projection {
            RawProjection::Perspective { yfov, aspect_ratio } => {
                if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
                    return Err(at("perspective.yfov", "must lie in (0, pi) radians", yfov));
                }
                if let Some(a) = aspect_ratio.filter(|a| !(a.is_finite() && *a > 0.0)) {
                    return Err(at("perspective.aspectRatio", "must be positive", a));
                }
                GltfProjection::Perspective {
                    vertical_fov: (yfov as f64).to_degrees(),
                    aspect: aspect_ratio.map(f64::from),
                }
            }
            RawProjection::Orthographic { xmag, ymag } => {
                for (field, v) in [("orthographic.xmag", xmag), ("orthographic.ymag", ymag)] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(at(field, "must be positive and finite", v));
                    }
                }
                GltfProjection::Orthographic {
                    xmag: xmag as f64,
                    ymag: ymag as f64,
                }
            }
        };
        let position = self.world.transform_point3(DVec3::ZERO);
        let forward = self.world.transform_vector3(DVec3::NEG_Z);
        let up = self.world.transform_vector3(DVec3::Y);
        let square = forward.length() * up.length();
        if !(position.is_finite() && square.is_finite())
            || forward.cross(up).length() <= 1e-9 * square
        {
            return Err(format!(
                "{}: its node's transform leaves no viewing direction and up (a zero scale?)",
                self.label()
            ));
        }
        Ok(GltfCamera {
            position,
            look_at: position + forward.normalize(),
            up: up.normalize(),
            projection,
        })
    }
}

impl GltfScene {
    /// The camera to render with, as viewers choose it: the one `name` names (its name, or its
    /// index in the file's cameras when no camera has that name), else the first reached from
    /// the scene's nodes; `None` when the scene has no camera and no name was given. An absent
    /// name is an error listing the cameras there are.
    pub fn camera(&self, name: Option<&str>) -> Result<Option<GltfCamera>, String> {
        let Some(name) = name else {
            return self.cameras.first().map(CameraNode::placed).transpose();
        };
        let chosen = self
            .cameras
            .iter()
            .find(|c| c.name.as_deref() == Some(name))
            .or_else(|| {
                let index = name.parse::<usize>().ok()?;
                self.cameras.iter().find(|c| c.index == index)
            });
        match chosen {
            Some(camera) => camera.placed().map(Some),
            None => {
                // In the file's order, once each (two nodes may place one camera).
                let by_index: std::collections::BTreeMap<usize, String> = self
                    .cameras
                    .iter()
                    .map(|c| {
                        let label = match &c.name {
                            Some(n) => format!("{n:?}"),
                            None => format!("{} (unnamed)", c.index),
                        };
                        (c.index, label)
                    })
                    .collect();
                let listed: Vec<String> = by_index.into_values().collect();
                Err(format!(
                    "no camera named {name:?} in the default scene (cameras, by name or by \
                     index: {})",
                    if listed.is_empty() {
                        "none".to_string()
                    } else {
                        listed.join(", ")
                    }
                ))
            }
        }
    }
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

/// Image width of a glTF file rendered as a scene when the user gives no size; the height
/// follows the camera's aspect.
pub const DEFAULT_WIDTH: u32 = 960;

/// The image size the user asked for (`--width`, `--height`, or `render.width` and
/// `render.height` overrides), each side optional.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageSize {
    /// Width in pixels, if given.
    pub width: Option<u32>,
    /// Height in pixels, if given.
    pub height: Option<u32>,
}

impl ImageSize {
    /// Both sides: those given, a missing one from `aspect` (width over height), and
    /// `DEFAULT_WIDTH` wide when neither is given. A user's size wins over the camera's aspect.
    pub fn resolve(&self, aspect: f64) -> (u32, u32) {
        let fit = |v: f64| (v.round() as u32).max(1);
        match (self.width, self.height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, fit(w as f64 / aspect)),
            (None, Some(h)) => (fit(h as f64 * aspect), h),
            (None, None) => (DEFAULT_WIDTH, fit(DEFAULT_WIDTH as f64 / aspect)),
        }
    }
}

/// A glTF file as chambre scene text, so that `chambre render model.glb` renders it (with
/// `--set` overrides as for any scene): the file as one mesh shape with its own materials, the
/// camera `camera` names or the first reached from the scene's nodes (or one framing its bounds:
/// 40° vertical field of view, from above the front right, the bounds filling the view), its
/// lights (or, when it has none, a default key light: a directional light of irradiance 3 from
/// above the camera, and ambient 0.1 unless `path_traced`: the path tracer computes the
/// indirect light ambient light stands in for, and refuses it).
///
/// The image is `size` where the user gives it, a missing side from the camera's aspect (4:3
/// when it has none). The film (or an orthographic window) then takes the image's aspect,
/// keeping the camera's vertical extent, as glTF viewers do with a viewport of another shape:
/// `yfov` stays the vertical field of view, `2 ymag` the window's height.
pub fn scene_text(
    path: &Path,
    camera: Option<&str>,
    size: ImageSize,
    path_traced: bool,
) -> Result<String, String> {
    let mut scene = read_gltf(path)?;
    if scene.mesh.triangles.is_empty() {
        return Err("the file's default scene has no triangles".into());
    }
    // The scene text names the file as a mesh shape, whose loading checks the mesh again; a
    // fault found there would be placed at the `file` line of text the user never sees.
    scene.mesh = check_mesh(std::mem::take(&mut scene.mesh))?;
    let (lo, hi) = scene.mesh.positions.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(p.as_dvec3()), hi.max(p.as_dvec3())),
    );
    let chosen = scene.camera(camera)?;
    let camera_aspect = chosen.and_then(|c| c.projection.aspect());
    let (width, height) = size.resolve(camera_aspect.unwrap_or(4.0 / 3.0).clamp(0.05, 20.0));
    let aspect = width as f64 / height as f64;
    let camera = chosen.unwrap_or_else(|| framing_camera(lo, hi, aspect));
    let v = |d: DVec3| format!("[{:?}, {:?}, {:?}]", d.x, d.y, d.z);
    let projection = match camera.projection {
        GltfProjection::Perspective { vertical_fov, .. } => {
            format!(
                "vertical_fov = {vertical_fov:?}\nfilm = [{:?}, 24.0]\n",
                24.0 * aspect
            )
        }
        GltfProjection::Orthographic { ymag, .. } => format!(
            "projection = \"orthographic\"\nwindow = [{:?}, {:?}]\n",
            2.0 * ymag * aspect,
            2.0 * ymag
        ),
    };
    let absolute = std::path::absolute(path).map_err(|e| e.to_string())?;
    let mut text = format!(
        "[render]\nwidth = {width}\nheight = {height}\n{}\n\
         [camera]\nposition = {}\nlook_at = {}\nup = {}\n{projection}\n\
         [[shapes]]\ntype = \"mesh\"\nfile = {}\n",
        if scene.lights.is_empty() && !path_traced {
            "ambient = [0.1, 0.1, 0.1]\n"
        } else {
            ""
        },
        v(camera.position),
        v(camera.look_at),
        v(camera.up),
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
                // f32's pi/2, which `check_lights` lets through, is 90.0000025 degrees.
                outer_deg.min(90.0),
                inner_deg,
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

/// A camera that frames the box `lo..hi` in an image of `aspect` (width over height): 40°
/// vertical field of view, looking at its centre from the front right and above, far enough for
/// the bounding sphere to fit the narrower of the two fields of view.
fn framing_camera(lo: DVec3, hi: DVec3, aspect: f64) -> GltfCamera {
    let centre = (lo + hi) / 2.0;
    let radius = ((hi - lo).length() / 2.0).max(1e-6);
    let half_vertical = 20f64.to_radians();
    let half_horizontal = (half_vertical.tan() * aspect).atan();
    let distance = radius / half_vertical.min(half_horizontal).sin();
    let position = centre + DVec3::new(0.4, 0.3, 1.0).normalize() * distance;
    GltfCamera {
        position,
        look_at: centre,
        up: DVec3::Y,
        projection: GltfProjection::Perspective {
            vertical_fov: 40.0,
            aspect: None,
        },
    }
}
