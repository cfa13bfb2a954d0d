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
    Poisson,
    Interleaved,
    Sobol,
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
    /// mm from the lens centre to the film along the rail (the bellows extension)
    pub film_distance: Option<f64>,
    /// three world points the plane of sharp focus must pass through
    pub focus_points: Option<[Vec3; 3]>,
    /// degrees: film rotation about the horizontal axis (corrects a camera pitched up by it)
    pub film_tilt: Option<f64>,
    /// degrees: film rotation about the vertical axis (corrects a camera yawed right by it)
    pub film_swing: Option<f64>,
    /// mm: [right, up] movement of the framing (rear standard shift, rise/fall)
    pub film_shift: Option<[f64; 2]>,
    /// degrees: positive turns the plane of sharp focus down towards the ground
    pub lens_tilt: Option<f64>,
    /// degrees: positive turns the plane of sharp focus towards the right
    pub lens_swing: Option<f64>,
    /// mm: [right, up] movement of the lens (front standard shift)
    pub lens_shift: Option<[f64; 2]>,
    /// 0: circular; n >= 3: regular n-gon inscribed in the f/N circle
    pub aperture_blades: Option<i64>,
    /// degrees, counter-clockwise in the image
    pub aperture_rotation: Option<f64>,
    #[serde(default)]
    pub lens_sampler: SamplerName,
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
