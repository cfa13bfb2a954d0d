//! The scene stage: scene file -> parse (`load`) -> validate (`validate`) -> [`Scene`].
//!
//! A [`Scene`] is validated and immutable: every number is finite and in range, every reference
//! resolved, every mesh loaded and transformed. Kernels never see unvalidated data, because WGSL
//! has no error channel and may assume NaN and infinity never occur.

pub mod builder;
pub mod format;
mod load;
pub mod mesh;
mod validate;

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::adaptive::AdaptiveSettings;

pub use crate::camera::CameraSpec;
pub use crate::sampler::SamplerName;
pub use builder::SceneBuilder;
pub use load::parse_override;
pub use mesh::TriangleMesh;

use crate::error::Result;

#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file it came from (for messages).
    pub source: PathBuf,
    pub render: RenderSettings,
    pub camera: CameraSpec,
    pub materials: Vec<Material>,
    pub shapes: Vec<Shape>,
    pub lights: Vec<Light>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub pixel_sampler: SamplerName,
    pub background: Vec3,
    pub ambient: Vec3,
    /// Pixels rendered: columns `crop[0]..crop[1]`, rows `crop[2]..crop[3]` (the whole image
    /// unless `render.crop` narrows it).
    pub crop: [u32; 4],
    /// Adaptive sampling, when `render.noise_target` asks for it.
    pub adaptive: Option<AdaptiveSettings>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// One of `layout::MODEL_*`.
    pub model: u32,
    pub diffuse: Vec3,
    pub specular: Vec3,
    pub shininess: f32,
    pub mirror: Vec3,
    /// Radiance of an emitting surface (an OBJ `.mtl`'s `Ke`); zero for scene materials.
    pub emission: Vec3,
}

/// A shape; `material` indexes [`Scene::materials`].
#[derive(Clone, Debug)]
pub enum Shape {
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
    },
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        material: u32,
    },
    Plane {
        point: Vec3,
        normal: Vec3,
        material: u32,
    },
    Mesh {
        mesh: TriangleMesh,
        material: u32,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity (W/sr): irradiance I cos / r^2.
    Point { position: Vec3, intensity: Vec3 },
    /// `direction` is the unit direction the light travels; `irradiance` at normal incidence.
    Directional { direction: Vec3, irradiance: Vec3 },
    /// One-sided emitting parallelogram, normal = edge_u x edge_v.
    Area {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        radiance: Vec3,
        samples: u32,
    },
}

impl Scene {
    /// Parse, apply `--set` overrides (`key=value`), and validate a scene file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scene> {
        let parsed = load::parse_scene_file(path, overrides)?;
        validate::validate(parsed)
    }

    /// Parse and validate scene text (meshes are resolved relative to `path`'s folder).
    pub fn from_str(path: &Path, text: &str, overrides: &[String]) -> Result<Scene> {
        let parsed = load::parse_scene_text(path, text, overrides)?;
        validate::validate(parsed)
    }

    pub fn triangle_count(&self) -> usize {
        self.shapes
            .iter()
            .map(|s| match s {
                Shape::Mesh { mesh, .. } => mesh.triangles.len(),
                _ => 0,
            })
            .sum()
    }
}
