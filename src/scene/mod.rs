//! The scene stage: scene file -> parse (`load`) -> validate (`validate`) -> [`Scene`].
//!
//! A [`Scene`] is validated and immutable: every number is finite and in range, every reference
//! resolved, every mesh loaded and transformed. Kernels never see unvalidated data, because WGSL
//! has no error channel and may assume NaN and infinity never occur.

pub mod builder;
pub mod environment;
pub mod format;
pub mod gltf;
mod load;
pub mod mesh;
pub mod mesh_file;
pub mod parametric;
pub mod surface;
pub mod texture;
mod validate;

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

use crate::adaptive::AdaptiveSettings;

pub use crate::camera::CameraSpec;
pub use crate::sampler::SamplerName;
pub use builder::SceneBuilder;
pub use format::Integrator;
pub use load::{merged_scene_text, parse_override};
pub use mesh::TriangleMesh;

use crate::error::{Error, Result};

/// A validated scene, ready to flatten (`pack::flatten`) and render.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file it came from (for messages).
    pub source: PathBuf,
    /// Image size, sampling and the radiance of the surroundings.
    pub render: RenderSettings,
    /// The view camera.
    pub camera: CameraSpec,
    /// Materials of the scene file, then those of OBJ material libraries.
    pub materials: Vec<Material>,
    /// The shapes, meshes loaded and transformed to world space.
    pub shapes: Vec<Shape>,
    /// The lights (emitting mesh triangles are found through their materials).
    pub lights: Vec<Light>,
    /// Each shape's velocity (scene units a second), in `shapes` order; empty when nothing
    /// moves.
    pub velocities: Vec<Vec3>,
    /// The shapes declared as parametric surfaces (tori, ellipsoids, cylinders, Bézier patches),
    /// each also in `shapes` as the ray tracers trace it (`surface::Surface::traced_shape`).
    pub surfaces: Vec<surface::CurvedSurface>,
}

/// The validated `[render]` section.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (under adaptive sampling, the most a pixel takes).
    pub spp: u32,
    /// Whitted's integrator or the path tracer.
    pub integrator: Integrator,
    /// Bounces allowed per path (Whitted: mirror bounces).
    pub max_depth: u32,
    /// The path tracer's first vertex whose bounce Russian roulette may end.
    pub rr_depth: u32,
    /// Seed of every random number of the render.
    pub seed: u32,
    /// Pattern of the pixel positions.
    pub pixel_sampler: SamplerName,
    /// Radiance of rays that escape the scene.
    pub background: Vec3,
    /// Ambient radiance L_a: each hit adds diffuse * L_a.
    pub ambient: Vec3,
    /// Pixels rendered: columns `crop[0]..crop[1]`, rows `crop[2]..crop[3]` (the whole image
    /// unless `render.crop` narrows it).
    pub crop: [u32; 4],
    /// Adaptive sampling, when `render.noise_target` asks for it.
    pub adaptive: Option<AdaptiveSettings>,
}

/// A validated material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Its name in the scene file, or `file.obj:name` for an OBJ library's.
    pub name: String,
    /// One of `layout::MODEL_*`.
    pub model: u32,
    /// Diffuse reflectance in [0, 1] per channel.
    pub diffuse: Vec3,
    /// Specular reflectance of the Phong or Blinn-Phong lobe, in [0, 1].
    pub specular: Vec3,
    /// Exponent of the Phong or Blinn-Phong lobe, in [0, 1e4].
    pub shininess: f32,
    /// Perfect-mirror reflectance in [0, 1] per channel.
    pub mirror: Vec3,
    /// Radiance of an emitting surface (an OBJ `.mtl`'s `Ke`); zero for scene materials.
    pub emission: Vec3,
    /// A dielectric's index of refraction (inside over outside); 1 for the others.
    pub ior: f32,
    /// A texture whose colour multiplies `diffuse` (glTF's base colour texture, an OBJ's
    /// `map_Kd`, a scene material's `diffuse_texture`).
    pub diffuse_texture: Option<std::sync::Arc<texture::Texture>>,
}

/// A shape; `material` indexes [`Scene::materials`].
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre (scene units).
        center: Vec3,
        /// Radius (scene units), > 0.
        radius: f32,
        /// Index into the materials.
        material: u32,
    },
    /// A parallelogram.
    Quad {
        /// One corner (scene units).
        corner: Vec3,
        /// Edge from `corner` to the next corner; the normal is edge_u x edge_v.
        edge_u: Vec3,
        /// The other edge from `corner`.
        edge_v: Vec3,
        /// Index into the materials.
        material: u32,
    },
    /// An infinite plane, tested outside the BVH.
    Plane {
        /// A point on the plane (scene units).
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
        /// Index into the materials.
        material: u32,
    },
    /// An ellipsoid, cylinder or torus, intersected exactly (`accel::curved`); its surface,
    /// in double precision, is also among `Scene::surfaces`.
    Curved {
        /// The surface, in its own frame.
        primitive: CurvedPrimitive,
        /// The rotation about its centre (a cylinder's base) that turns its own frame into the
        /// world's; the identity leaves a cylinder's or torus's axis vertical and an
        /// ellipsoid's semi-axes along the world's axes.
        orientation: Quat,
        /// Index into the materials.
        material: u32,
    },
    /// A triangle mesh, already in world space.
    Mesh {
        /// Its triangles and vertex normals.
        mesh: TriangleMesh,
        /// Index into the materials of faces whose own material the mesh does not give.
        material: u32,
    },
}

/// A curved surface the ray tracers intersect exactly, in the precision they trace in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CurvedPrimitive {
    /// An ellipsoid with semi-axes along its frame's axes.
    Ellipsoid {
        /// Centre (scene units).
        center: Vec3,
        /// Semi-axes along x, y and z, > 0.
        radii: Vec3,
    },
    /// An open cylinder around its frame's y axis.
    Cylinder {
        /// The centre of its base circle (scene units).
        base: Vec3,
        /// Radius, > 0.
        radius: f32,
        /// Height above the base, > 0.
        height: f32,
    },
    /// A torus around its frame's y axis through its centre.
    Torus {
        /// Centre (scene units).
        center: Vec3,
        /// R: the radius of the tube's centre circle.
        major: f32,
        /// r: the tube's radius, below R.
        minor: f32,
    },
}

/// A validated light.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity (W/sr): irradiance I cos / r^2.
    Point {
        /// Position (scene units).
        position: Vec3,
        /// Radiant intensity (W/sr), linear RGB.
        intensity: Vec3,
    },
    /// `direction` is the unit direction the light travels; `irradiance` at normal incidence.
    Directional {
        /// Unit direction of travel.
        direction: Vec3,
        /// Irradiance on a surface facing the light.
        irradiance: Vec3,
    },
    /// One-sided emitting parallelogram, normal = edge_u x edge_v.
    Area {
        /// One corner (scene units).
        corner: Vec3,
        /// First edge from `corner`.
        edge_u: Vec3,
        /// Second edge from `corner`.
        edge_v: Vec3,
        /// Emitted radiance, from the front side only.
        radiance: Vec3,
        /// Shadow rays per shading point, >= 1.
        samples: u32,
    },
    /// A point light limited to a cone, with KHR_lights_punctual's falloff between its inner
    /// and outer angles.
    Spot {
        /// Position (scene units).
        position: Vec3,
        /// Unit direction it points along.
        direction: Vec3,
        /// Radiant intensity on its axis (W/sr), linear RGB.
        intensity: Vec3,
        /// Angle from the axis within which the light is full (degrees).
        inner_deg: f32,
        /// Angle from the axis where it ends (degrees).
        outer_deg: f32,
    },
    /// Radiance from every direction at infinity, seen by escaping rays (in place of
    /// `render.background`) and sampled by shadow rays.
    Environment {
        /// Constant radiance where there is no map; the map's multiplier (its `scale`) where
        /// there is one.
        radiance: Vec3,
        /// The equirectangular map, if any (`docs/lights.md` gives its directions).
        map: Option<std::sync::Arc<environment::EnvironmentMap>>,
        /// Degrees the map turns about +y, from -z towards +x.
        rotate_deg: f32,
        /// Shadow rays per shading point, >= 1.
        samples: u32,
    },
    /// A disc of uniform radiance at infinity (the sun), seen within a cone.
    Sun {
        /// Unit direction the light travels.
        direction: Vec3,
        /// Irradiance on a surface facing it.
        irradiance: Vec3,
        /// The cone's half-angle (degrees).
        angular_radius_deg: f64,
        /// Shadow rays per shading point, >= 1.
        samples: u32,
    },
}

/// A spot light's falloff as KHR_lights_punctual defines it, saturate(cos θ · scale + offset)²
/// with θ the angle from its axis: `(scale, offset)` for the cone of `inner_deg` and
/// `outer_deg`. The kernels, the CPU path and exports all evaluate this one.
pub fn spot_falloff(inner_deg: f32, outer_deg: f32) -> (f32, f32) {
    let (cos_inner, cos_outer) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
    let scale = 1.0 / (cos_inner - cos_outer).max(1e-3);
    (scale, -cos_outer * scale)
}

/// The override that names the camera of a glTF file rendered as a scene.
pub const GLTF_CAMERA_KEY: &str = "gltf.camera";

impl Scene {
    /// Parse, apply `--set` overrides (`key=value`), and validate a scene file: chambre's TOML,
    /// or a glTF file (`.gltf`, `.glb`) rendered as a scene (`gltf::scene_text`, with the camera
    /// an override `gltf.camera=NAME` names; what its mapping left out is in its mesh's
    /// `notes`).
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scene> {
        let extension = path.extension().map(|e| e.to_ascii_lowercase());
        if extension
            .as_ref()
            .is_some_and(|e| e == "gltf" || e == "glb")
        {
            // `gltf.camera=NAME` picks the file's camera; the other overrides apply to the scene,
            // and the image size among them shapes its camera too.
            let (camera, overrides): (Vec<&String>, Vec<&String>) = overrides
                .iter()
                .partition(|o| o.trim_start().starts_with(GLTF_CAMERA_KEY));
            let name = camera.last().map(|o| {
                let value = o.split_once('=').map_or("", |(_, v)| v).trim();
                value.trim_matches('"').to_string()
            });
            let size = image_size_given(&overrides);
            let path_traced = path_traced_given(&overrides);
            let text =
                gltf::scene_text(path, name.as_deref(), size, path_traced).map_err(|message| {
                    Error::File {
                        path: path.to_path_buf(),
                        message,
                    }
                })?;
            let overrides: Vec<String> = overrides.into_iter().cloned().collect();
            return Scene::from_str(path, &text, &overrides).map_err(|e| match e {
                // The lines of the scene text made from the file mean nothing to its user (a
                // line of 0 is a `--set`'s, which says so itself).
                Error::Scene { location, message } if location.line != 0 => Error::File {
                    path: path.to_path_buf(),
                    message: format!(
                        "field `{}` (of the scene chambre reads it as): {message}",
                        location.field
                    ),
                },
                other => other,
            });
        }
        let parsed = load::parse_scene_file(path, overrides)?;
        validate::validate(parsed)
    }

    /// The width and height of the frame the image's aspect must match, as the scene file with
    /// `overrides` gives them before the rest is validated: a perspective camera's film (mm) or
    /// an orthographic camera's window. One side of the image given on the command line takes
    /// this aspect, whatever image size the scene itself names (the full load would refuse
    /// a film set to another aspect than that size's). A glTF file's frame is its camera's,
    /// which takes the image size given among `overrides`; a frame the file lacks or gives
    /// unusable sides is left to the full load's error.
    pub fn frame_given(path: &Path, overrides: &[String]) -> Result<[f64; 2]> {
        let extension = path.extension().map(|e| e.to_ascii_lowercase());
        let full = || Scene::load(path, overrides).map(|s| s.camera.film_mm);
        if extension.is_some_and(|e| e == "gltf" || e == "glb") {
            return full();
        }
        let camera = load::parse_scene_file(path, overrides)?.file.camera;
        let frame = match camera.projection {
            crate::camera::Projection::Orthographic => camera.window.map(|w| w.0),
            _ => Some(camera.film.map_or(format::DEFAULT_FILM, |f| f.0)),
        };
        match frame {
            Some([w, h]) if w > 0.0 && h > 0.0 && (w / h).is_normal() => Ok([w, h]),
            _ => full(),
        }
    }

    /// What loading left out that the user should know (`TriangleMesh::notes`).
    pub fn notes(&self) -> Vec<String> {
        let meshes = self.shapes.iter().filter_map(|s| match s {
            Shape::Mesh { mesh, .. } => Some(mesh),
            _ => None,
        });
        meshes.flat_map(|m| m.notes.iter().cloned()).collect()
    }

    /// What loading went on without and the user should hear of: an OBJ's `mtllib` file that
    /// could not be read, where the scene does not need its materials.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        for shape in &self.shapes {
            let Shape::Mesh { mesh, material } = shape else {
                continue;
            };
            let instead = match mesh.face_materials.is_empty() {
                true => format!(
                    "the scene's material `{}` is used",
                    self.materials[*material as usize].name
                ),
                false => "no face of the mesh needs a material from it".to_string(),
            };
            for missing in &mesh.missing_libraries {
                warnings.push(format!("{missing}; going on without it: {instead}"));
            }
        }
        warnings.extend(self.camera.coverage_warning());
        warnings
    }

    /// Parse and validate scene text (meshes are resolved relative to `path`'s folder).
    pub fn from_str(path: &Path, text: &str, overrides: &[String]) -> Result<Scene> {
        let parsed = load::parse_scene_text(path, text, overrides)?;
        validate::validate(parsed)
    }

    /// Triangles in all meshes (other shapes count none).
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

/// The image size `render.width` and `render.height` overrides give (the last of each); one
/// that is not a pixel count is left to the scene's validation, which names it.
fn image_size_given(overrides: &[&String]) -> gltf::ImageSize {
    let mut size = gltf::ImageSize::default();
    for (key, value) in overrides.iter().filter_map(|o| parse_override(o).ok()) {
        let pixels = value
            .as_integer()
            .and_then(|v| u32::try_from(v).ok())
            .filter(|&v| v > 0);
        match key.as_str() {
            "render.width" => size.width = pixels,
            "render.height" => size.height = pixels,
            _ => {}
        }
    }
    size
}

/// Whether `overrides` choose the path tracer (`render.integrator = "path"`, as `--integrator
/// path` sets it), the last of them winning.
fn path_traced_given(overrides: &[&String]) -> bool {
    overrides
        .iter()
        .rev()
        .filter_map(|o| parse_override(o).ok())
        .find(|(key, _)| key == "render.integrator")
        .is_some_and(|(_, value)| value.as_str() == Some("path"))
}

/// Where `field` (a path such as `shapes[2].material`) stands in the scene file at `path` loaded
/// with `overrides`: its line, or the command line where an override set it. `None` for a file
/// that is not chambre's TOML (a glTF scene's fields are those of the scene it maps to).
pub fn field_location(
    path: &Path,
    overrides: &[String],
    field: &str,
) -> Option<crate::error::Location> {
    let is_toml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !is_toml {
        return None;
    }
    match load::parse_scene_file(path, overrides)
        .ok()?
        .error(field, "")
    {
        Error::Scene { location, .. } => Some(location),
        _ => None,
    }
}

/// Sample scene `name` of the project's `scenes/` with `overrides` (`--set` style), for unit
/// tests.
#[cfg(test)]
pub(crate) fn sample_scene(name: &str, overrides: &[&str]) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::load(&path, &overrides).unwrap_or_else(|e| panic!("{name}: {e}"))
}
