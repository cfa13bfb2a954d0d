//! Scenes built in Rust code: the fields of the scene file (`docs/scene-format.md`), typed,
//! checked by the very same validation as a file. An error names the field
//! (`shapes[1].radius`) of the scene as built.

use std::path::Path;

use toml::{Table, Value};

use super::Scene;
use crate::error::Result;

/// A scene under construction. Every method sets what the scene file's field of the same
/// name sets; [`SceneBuilder::build`] validates the whole.
///
/// ```no_run
/// use chambre::scene::SceneBuilder;
/// let scene = SceneBuilder::new(320, 240)
///     .spp(16)
///     .pinhole([0.0, 1.0, 4.0], [0.0, 0.5, 0.0], 40.0)
///     .lambert("white", [0.8, 0.8, 0.8])
///     .sphere([0.0, 0.5, 0.0], 0.5, "white")
///     .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "white")
///     .point_light([2.0, 4.0, 3.0], [30.0, 30.0, 30.0])
///     .build()
///     .unwrap();
/// ```
#[derive(Clone, Debug)]
pub struct SceneBuilder {
    render: Table,
    camera: Table,
    materials: Vec<Value>,
    shapes: Vec<Value>,
    lights: Vec<Value>,
}

fn vec3(v: [f64; 3]) -> Value {
    Value::Array(v.iter().map(|&c| Value::Float(c)).collect())
}

fn entry(fields: &[(&str, Value)]) -> Value {
    Value::Table(
        fields
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect(),
    )
}

impl SceneBuilder {
    /// An image of `width` x `height` pixels; a pinhole at the origin looking down -z until
    /// [`SceneBuilder::pinhole`] or [`SceneBuilder::camera_field`] says otherwise.
    pub fn new(width: u32, height: u32) -> SceneBuilder {
        let mut render = Table::new();
        render.insert("width".into(), Value::Integer(width as i64));
        render.insert("height".into(), Value::Integer(height as i64));
        let mut builder = SceneBuilder {
            render,
            camera: Table::new(),
            materials: Vec::new(),
            shapes: Vec::new(),
            lights: Vec::new(),
        };
        builder = builder.pinhole([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 45.0);
        builder
    }

    /// Any `[render]` field, e.g. `("pixel_sampler", "sobol".into())`.
    pub fn render_field(mut self, key: &str, value: Value) -> Self {
        self.render.insert(key.into(), value);
        self
    }

    /// Samples per pixel (`render.spp`).
    pub fn spp(self, spp: u32) -> Self {
        self.render_field("spp", Value::Integer(spp as i64))
    }

    /// Mirror bounces per path (`render.max_depth`).
    pub fn max_depth(self, depth: u32) -> Self {
        self.render_field("max_depth", Value::Integer(depth as i64))
    }

    /// Radiance of rays that escape the scene (`render.background`).
    pub fn background(self, radiance: [f64; 3]) -> Self {
        self.render_field("background", vec3(radiance))
    }

    /// Ambient radiance L_a (`render.ambient`): each hit adds diffuse * L_a.
    pub fn ambient(self, radiance: [f64; 3]) -> Self {
        self.render_field("ambient", vec3(radiance))
    }

    /// A pinhole camera at `position` looking at `look_at`, up +y, with a vertical field of
    /// view in degrees and a film of the image's aspect.
    pub fn pinhole(mut self, position: [f64; 3], look_at: [f64; 3], vertical_fov_deg: f64) -> Self {
        let aspect = |key: &str| {
            self.render
                .get(key)
                .and_then(Value::as_integer)
                .unwrap_or(1)
        };
        let (width, height) = (aspect("width") as f64, aspect("height") as f64);
        self.camera = Table::new();
        self.camera.insert("position".into(), vec3(position));
        self.camera.insert("look_at".into(), vec3(look_at));
        self.camera
            .insert("vertical_fov".into(), Value::Float(vertical_fov_deg));
        self.camera.insert(
            "film".into(),
            Value::Array(vec![
                Value::Float(36.0),
                Value::Float(36.0 * height / width),
            ]),
        );
        self
    }

    /// Any `[camera]` field: `("f_number", 2.8.into())`, `("lens_tilt", 5.0.into())`...
    pub fn camera_field(mut self, key: &str, value: Value) -> Self {
        self.camera.insert(key.into(), value);
        self
    }

    /// A Lambert material named `name` of diffuse reflectance `diffuse`.
    pub fn lambert(self, name: &str, diffuse: [f64; 3]) -> Self {
        self.add_materials(&[
            ("name", name.into()),
            ("model", "lambert".into()),
            ("diffuse", vec3(diffuse)),
        ])
    }

    /// A rough conductor of reflectance `specular` and perceptual `roughness` (GGX alpha =
    /// roughness²).
    pub fn rough_conductor(self, name: &str, specular: [f64; 3], roughness: f64) -> Self {
        self.add_materials(&[
            ("name", name.into()),
            ("model", "rough_conductor".into()),
            ("specular", vec3(specular)),
            ("roughness", roughness.into()),
        ])
    }

    /// A Blinn-Phong material: diffuse plus a lobe of reflectance `specular` and exponent
    /// `shininess`.
    pub fn blinn_phong(
        self,
        name: &str,
        diffuse: [f64; 3],
        specular: [f64; 3],
        shininess: f64,
    ) -> Self {
        self.add_materials(&[
            ("name", name.into()),
            ("model", "blinn_phong".into()),
            ("diffuse", vec3(diffuse)),
            ("specular", vec3(specular)),
            ("shininess", shininess.into()),
        ])
    }

    /// A perfect mirror of reflectance `reflectance` (no diffuse term).
    pub fn mirror(self, name: &str, reflectance: [f64; 3]) -> Self {
        self.add_materials(&[
            ("name", name.into()),
            ("model", "mirror".into()),
            ("mirror", vec3(reflectance)),
        ])
    }

    /// A smooth dielectric (glass) of index of refraction `ior`; the path tracer's only.
    pub fn dielectric(self, name: &str, ior: f64) -> Self {
        self.add_materials(&[
            ("name", name.into()),
            ("model", "dielectric".into()),
            ("ior", Value::Float(ior)),
        ])
    }

    /// A sphere (scene units) of the material named `material`.
    pub fn sphere(self, center: [f64; 3], radius: f64, material: &str) -> Self {
        self.add_shapes(&[
            ("type", "sphere".into()),
            ("center", vec3(center)),
            ("radius", radius.into()),
            ("material", material.into()),
        ])
    }

    /// A parallelogram with corner `corner` and edges `edge_u`, `edge_v` (scene units).
    pub fn quad(
        self,
        corner: [f64; 3],
        edge_u: [f64; 3],
        edge_v: [f64; 3],
        material: &str,
    ) -> Self {
        self.add_shapes(&[
            ("type", "quad".into()),
            ("corner", vec3(corner)),
            ("edge_u", vec3(edge_u)),
            ("edge_v", vec3(edge_v)),
            ("material", material.into()),
        ])
    }

    /// An infinite plane through `point` with normal `normal`.
    pub fn plane(self, point: [f64; 3], normal: [f64; 3], material: &str) -> Self {
        self.add_shapes(&[
            ("type", "plane".into()),
            ("point", vec3(point)),
            ("normal", vec3(normal)),
            ("material", material.into()),
        ])
    }

    /// A mesh file (OBJ or PLY, `.gz` too), relative to the working directory.
    pub fn mesh(self, file: &str, material: &str) -> Self {
        self.add_shapes(&[
            ("type", "mesh".into()),
            ("file", file.into()),
            ("material", material.into()),
        ])
    }

    /// A point light of radiant intensity `intensity` (W/sr).
    pub fn point_light(self, position: [f64; 3], intensity: [f64; 3]) -> Self {
        self.add_lights(&[
            ("type", "point".into()),
            ("position", vec3(position)),
            ("intensity", vec3(intensity)),
        ])
    }

    /// A directional light travelling along `direction`, of irradiance `irradiance`.
    pub fn directional_light(self, direction: [f64; 3], irradiance: [f64; 3]) -> Self {
        self.add_lights(&[
            ("type", "directional".into()),
            ("direction", vec3(direction)),
            ("irradiance", vec3(irradiance)),
        ])
    }

    /// A one-sided parallelogram light (shining towards edge_u x edge_v) of radiance `radiance`,
    /// sampled with `samples` shadow rays.
    pub fn area_light(
        self,
        corner: [f64; 3],
        edge_u: [f64; 3],
        edge_v: [f64; 3],
        radiance: [f64; 3],
        samples: u32,
    ) -> Self {
        self.add_lights(&[
            ("type", "area".into()),
            ("corner", vec3(corner)),
            ("edge_u", vec3(edge_u)),
            ("edge_v", vec3(edge_v)),
            ("radiance", vec3(radiance)),
            ("samples", Value::Integer(samples as i64)),
        ])
    }

    /// A constant environment light of radiance `radiance`, sampled with `samples` shadow rays.
    pub fn environment_light(self, radiance: [f64; 3], samples: u32) -> Self {
        self.add_lights(&[
            ("type", "environment".into()),
            ("radiance", vec3(radiance)),
            ("samples", Value::Integer(samples as i64)),
        ])
    }

    /// An environment light of the equirectangular map `file` times `scale`, turned `rotate`
    /// degrees about +y, sampled with `samples` shadow rays.
    pub fn environment_map(self, file: &str, scale: f64, rotate: f64, samples: u32) -> Self {
        self.add_lights(&[
            ("type", "environment".into()),
            ("file", file.into()),
            ("scale", Value::Float(scale)),
            ("rotate", Value::Float(rotate)),
            ("samples", Value::Integer(samples as i64)),
        ])
    }

    /// A sun whose light travels along `direction`, of irradiance `irradiance` from a disc of
    /// half-angle `angular_radius_deg`, sampled with `samples` shadow rays.
    pub fn sun(
        self,
        direction: [f64; 3],
        irradiance: [f64; 3],
        angular_radius_deg: f64,
        samples: u32,
    ) -> Self {
        self.add_lights(&[
            ("type", "sun".into()),
            ("direction", vec3(direction)),
            ("irradiance", vec3(irradiance)),
            ("angular_radius_deg", Value::Float(angular_radius_deg)),
            ("samples", Value::Integer(samples as i64)),
        ])
    }

    fn add_materials(mut self, fields: &[(&str, Value)]) -> Self {
        self.materials.push(entry(fields));
        self
    }

    fn add_shapes(mut self, fields: &[(&str, Value)]) -> Self {
        self.shapes.push(entry(fields));
        self
    }

    fn add_lights(mut self, fields: &[(&str, Value)]) -> Self {
        self.lights.push(entry(fields));
        self
    }

    /// The scene, validated as a scene file is.
    pub fn build(self) -> Result<Scene> {
        let mut table = Table::new();
        table.insert("render".into(), Value::Table(self.render));
        table.insert("camera".into(), Value::Table(self.camera));
        table.insert("materials".into(), Value::Array(self.materials));
        table.insert("shapes".into(), Value::Array(self.shapes));
        table.insert("lights".into(), Value::Array(self.lights));
        // Through the file's own reader and validation (the text is never shown: errors name
        // the field); meshes resolve from the working directory.
        let text = toml::to_string(&table).expect("a table of plain values serialises");
        Scene::from_str(Path::new("./scene built in code"), &text, &[])
    }
}
