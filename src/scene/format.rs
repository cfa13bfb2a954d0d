//! The scene file format, version 1: a 1:1 image of the TOML file (serde), before validation.
//!
//! Every struct denies unknown fields, so a typo (`fnumber` for `f_number`) is an error with its
//! line, not a silently ignored value. Shapes and lights are flat structs with a `type` tag rather
//! than serde enums: serde buffers tagged enums, which would lose the position of a bad field.
//! Which fields each `type` takes is checked in `validate.rs`. See `docs/scene-format.md`.

use serde::Deserialize;

pub type Vec3 = [f64; 3];

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    pub scene: SceneSection,
    pub render: RenderSection,
    pub camera: CameraSection,
    #[serde(default)]
    pub materials: Vec<MaterialEntry>,
    #[serde(default)]
    pub shapes: Vec<ShapeEntry>,
    #[serde(default)]
    pub lights: Vec<LightEntry>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSection {
    /// Length of one scene unit in metres (default 1: scene units are metres).
    pub meters_per_unit: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplerName {
    Random,
    #[default]
    Stratified,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSection {
    pub width: i64,
    pub height: i64,
    #[serde(default = "default_spp")]
    pub spp: i64,
    #[serde(default = "default_max_depth")]
    pub max_depth: i64,
    #[serde(default)]
    pub seed: i64,
    #[serde(default)]
    pub pixel_sampler: SamplerName,
    #[serde(default)]
    pub background: Vec3,
    #[serde(default)]
    pub ambient: Vec3,
}

fn default_spp() -> i64 {
    16
}
fn default_max_depth() -> i64 {
    4
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    pub position: Vec3,
    pub look_at: Vec3,
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// mm
    pub focal_length: Option<f64>,
    /// mm, width x height
    #[serde(default = "default_film")]
    pub film: [f64; 2],
    /// degrees; sets the focal length of a pinhole with this vertical field of view
    pub vertical_fov: Option<f64>,
    /// 0 or absent: pinhole
    pub f_number: Option<f64>,
    /// scene units along the optical axis; absent or `inf`: infinity
    pub focus_distance: Option<f64>,
}

fn default_up() -> Vec3 {
    [0.0, 1.0, 0.0]
}
fn default_film() -> [f64; 2] {
    [36.0, 24.0]
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialModel {
    Lambert,
    Phong,
    BlinnPhong,
    Mirror,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialEntry {
    pub name: String,
    pub model: MaterialModel,
    pub diffuse: Option<Vec3>,
    pub specular: Option<Vec3>,
    pub shininess: Option<f64>,
    pub mirror: Option<Vec3>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeType {
    Sphere,
    Quad,
    Plane,
    Mesh,
}

/// A uniform scale factor or one per axis.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f64),
    PerAxis(Vec3),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeEntry {
    #[serde(rename = "type")]
    pub kind: ShapeType,
    pub material: String,
    // sphere
    pub center: Option<Vec3>,
    pub radius: Option<f64>,
    // quad
    pub corner: Option<Vec3>,
    pub edge_u: Option<Vec3>,
    pub edge_v: Option<Vec3>,
    // plane
    pub point: Option<Vec3>,
    pub normal: Option<Vec3>,
    // mesh
    pub file: Option<String>,
    pub translate: Option<Vec3>,
    pub rotate: Option<Vec3>,
    pub scale: Option<Scale>,
    pub smooth: Option<bool>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    Point,
    Directional,
    Area,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightEntry {
    #[serde(rename = "type")]
    pub kind: LightType,
    // point
    pub position: Option<Vec3>,
    pub intensity: Option<Vec3>,
    // directional
    pub direction: Option<Vec3>,
    pub irradiance: Option<Vec3>,
    // area
    pub corner: Option<Vec3>,
    pub edge_u: Option<Vec3>,
    pub edge_v: Option<Vec3>,
    pub radiance: Option<Vec3>,
    pub samples: Option<i64>,
}
