//! The scene file format, version 1: a 1:1 image of the TOML file (serde), before validation.
//!
//! Every struct denies unknown fields, so a typo (`fnumber` for `f_number`) is an error with its
//! line, not a silently ignored value. Shapes and lights are flat structs with a `type` tag rather
//! than serde enums: serde buffers tagged enums, which would lose the position of a bad field.
//! Which fields each `type` takes is checked in `validate.rs`. See `docs/scene-format.md`.

use std::marker::PhantomData;

use crate::named::named_enum;
pub use crate::sampler::SamplerName;
use serde::Deserialize;
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};

/// A TOML array of exactly `N` elements. serde's own `[T; N]` stops reading after `N` and
/// ignores the rest, so `position = [2, 3, 3, 9]` would pass as a point; this counts them all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exact<T, const N: usize>(pub [T; N]);

/// A point, vector or colour: exactly three numbers.
pub type Vec3 = Exact<f64, 3>;
/// A [x, y] or [width, height] pair in millimetres.
pub type Pair = Exact<f64, 2>;

impl<const N: usize> Default for Exact<f64, N> {
    fn default() -> Self {
        Exact([0.0; N])
    }
}

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_seq(ExactVisitor(PhantomData))
    }
}

struct ExactVisitor<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for ExactVisitor<T, N> {
    type Value = Exact<T, N>;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "an array of exactly {N} elements")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut items = Vec::with_capacity(N);
        while let Some(item) = seq.next_element()? {
            if items.len() == N {
                // Count the surplus too, so the message says how many were given.
                let mut given = N + 1;
                while seq.next_element::<IgnoredAny>()?.is_some() {
                    given += 1;
                }
                return Err(de::Error::invalid_length(given, &self));
            }
            items.push(item);
        }
        let given = items.len();
        items
            .try_into()
            .map(Exact)
            .map_err(|_| de::Error::invalid_length(given, &self))
    }
}

/// A whole scene file: its sections and arrays of tables, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[scene]`: global settings (units).
    #[serde(default)]
    pub scene: SceneSection,
    /// `[render]`: image size, sampling and the radiance of the surroundings.
    pub render: RenderSection,
    /// `[camera]`: position, lens and view-camera movements.
    pub camera: CameraSection,
    /// `[[materials]]`: named materials, referred to by shapes.
    #[serde(default)]
    pub materials: Vec<MaterialEntry>,
    /// `[[shapes]]`: spheres, quads, planes and meshes.
    #[serde(default)]
    pub shapes: Vec<ShapeEntry>,
    /// `[[lights]]`: point, directional and area lights.
    #[serde(default)]
    pub lights: Vec<LightEntry>,
}

/// The `[scene]` section.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSection {
    /// Length of one scene unit in metres (default 1: scene units are metres).
    pub meters_per_unit: Option<f64>,
}

/// The `[render]` section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSection {
    /// Image width in pixels, 1..=16384.
    pub width: i64,
    /// Image height in pixels, 1..=16384.
    pub height: i64,
    /// Samples per pixel, 1..=2^20 (default 16); with `noise_target`, the most a pixel takes.
    #[serde(default = "default_spp")]
    pub spp: i64,
    /// "whitted" (default: direct light, shadows, perfect mirrors) or "path" (global
    /// illumination: `docs/path.md`).
    #[serde(default)]
    pub integrator: Integrator,
    /// Bounces, 0..=1024 (default 4): a Whitted path's mirror bounces, a path tracer's bounces
    /// of any kind (0: direct light only).
    #[serde(default = "default_max_depth")]
    pub max_depth: i64,
    /// The path tracer's first vertex (0: the camera ray's hit) whose bounce Russian roulette
    /// may end, 0..=1024 (default 5, as Mitsuba's `rr_depth`).
    #[serde(default = "default_rr_depth")]
    pub rr_depth: i64,
    /// Seed of the random numbers, 0..=2^32-1 (default 0).
    #[serde(default)]
    pub seed: i64,
    /// Pattern of the pixel positions (default stratified).
    #[serde(default)]
    pub pixel_sampler: SamplerName,
    /// Radiance of rays that escape the scene, linear RGB, 0..=1e20 (default 0).
    #[serde(default)]
    pub background: Vec3,
    /// Ambient radiance L_a: each hit adds diffuse * L_a; 0..=1e20 (default 0).
    #[serde(default)]
    pub ambient: Vec3,
    /// [x0, x1, y0, y1] in [0, 1]: render only this window of the image (pbrt's crop window)
    pub crop: Option<Exact<f64, 4>>,
    /// Adaptive sampling: a pixel stops once its error estimate is below this (`adaptive.rs`);
    /// `spp` is then the maximum.
    pub noise_target: Option<f64>,
    /// Samples every pixel receives before adaptive sampling's first decision.
    pub min_spp: Option<i64>,
}

fn default_spp() -> i64 {
    16
}
fn default_max_depth() -> i64 {
    4
}
fn default_rr_depth() -> i64 {
    5
}

named_enum! {
    /// The light transport a render computes.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Integrator {
        /// Whitted's: emission, ambient, direct light through shadow rays, perfect-mirror
        /// bounces.
        #[default]
        Whitted = "whitted",
        /// A path tracer: next-event estimation and BSDF sampling combined by multiple
        /// importance sampling, Russian roulette (`docs/path.md`).
        Path = "path",
    }
}

/// The `[camera]` section; the model and conventions are in `docs/camera.md`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// Where the camera stands (scene units): the lens centre before any lens shift.
    pub position: Vec3,
    /// The point the camera looks at (scene units); distinct from `position`.
    pub look_at: Vec3,
    /// The world's up direction for the view (default [0, 1, 0]); not parallel to the view.
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// "perspective" (default: the view camera) or "orthographic" (parallel rays, no lens)
    #[serde(default)]
    pub projection: crate::camera::Projection,
    /// scene units, width x height: an orthographic camera's window (required by it)
    pub window: Option<Pair>,
    /// mm
    pub focal_length: Option<f64>,
    /// mm, width x height (default 36 x 24); a perspective camera's only
    pub film: Option<Pair>,
    /// degrees; sets the focal length of a pinhole with this vertical field of view
    pub vertical_fov: Option<f64>,
    /// 0 or absent: pinhole
    pub f_number: Option<f64>,
    /// scene units along the optical axis; absent or `inf`: infinity
    pub focus_distance: Option<f64>,
    /// mm from the lens centre to the film along the rail (the bellows extension)
    pub film_distance: Option<f64>,
    /// three world points the plane of sharp focus must pass through
    pub focus_points: Option<Exact<Vec3, 3>>,
    /// degrees: film rotation about the horizontal axis (corrects a camera pitched up by it)
    pub film_tilt: Option<f64>,
    /// degrees: film rotation about the vertical axis (corrects a camera yawed right by it)
    pub film_swing: Option<f64>,
    /// mm: [right, up] movement of the framing (rear standard shift, rise/fall); scene units
    /// for an orthographic camera's window
    pub film_shift: Option<Pair>,
    /// degrees: positive turns the plane of sharp focus down towards the ground
    pub lens_tilt: Option<f64>,
    /// degrees: positive turns the plane of sharp focus towards the right
    pub lens_swing: Option<f64>,
    /// mm: [right, up] movement of the lens (front standard shift)
    pub lens_shift: Option<Pair>,
    /// What the lens turns about when tilted or swung: "rear_nodal" (default: the lens centre,
    /// a real lens's H'), "front_nodal", "stop", or a point [right, up, forward] in mm from the
    /// lens centre in the unturned lens (e.g. [0, -100, 0]: a base tilt 100 mm below the axis).
    pub lens_pivot: Option<LensPivot>,
    /// 0: circular; n >= 3: regular n-gon inscribed in the f/N circle
    pub aperture_blades: Option<i64>,
    /// degrees, counter-clockwise in the image
    pub aperture_rotation: Option<f64>,
    /// Pattern of the lens points (default stratified).
    #[serde(default)]
    pub lens_sampler: SamplerName,
    /// [open, close] (seconds): the interval the shutter is open; each camera sample takes a
    /// time in it (default [0, 0]: no motion blur).
    pub shutter: Option<Pair>,
    /// The surface of sharp focus: "plane" (default), or "sphere" / "cylinder" of radius
    /// `focus_distance` about the lens centre.
    pub focus_surface: Option<crate::camera::FocusSurface>,
    /// A real lens's prescription (pbrt's tabular format, relative to the scene file), traced
    /// in place of the thin lens: its focal length and widest f-number come from it.
    pub lens: Option<String>,
    /// true: the spectral mode: each sample traced at its own wavelength through the lens's
    /// dispersive glass (lateral and axial colour); a real lens whose file gives its glasses'
    /// dispersion only (default false).
    pub spectral: Option<bool>,
}

/// `camera.lens_pivot`: a named point on the optical axis, or a point in mm.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum LensPivot {
    /// "rear_nodal", "front_nodal" or "stop".
    Named(String),
    /// [right, up, forward] in mm from the lens centre, in the unturned lens.
    Point(Vec3),
}

fn default_up() -> Vec3 {
    Exact([0.0, 1.0, 0.0])
}
/// A perspective camera's film when the scene gives none (mm): 35 mm film's frame.
pub const DEFAULT_FILM: [f64; 2] = [36.0, 24.0];

/// A material's reflection model (`materials[].model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialModel {
    /// Diffuse only: BRDF diffuse / pi.
    Lambert,
    /// Diffuse plus a normalised Phong lobe (`specular`, `shininess`).
    Phong,
    /// Diffuse plus a normalised Blinn-Phong lobe (`specular`, `shininess`).
    BlinnPhong,
    /// A perfect mirror: `diffuse` defaults to 0 and `mirror` to 1.
    Mirror,
    /// A smooth dielectric (glass) of index of refraction `ior`: Fresnel reflection and
    /// refraction, nothing else; the path tracer renders it.
    Dielectric,
    /// A rough metal: a GGX microfacet lobe of reflectance `specular` and `roughness`
    /// (docs/path.md).
    RoughConductor,
}

/// One `[[materials]]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialEntry {
    /// Unique name shapes refer to it by.
    pub name: String,
    /// Reflection model.
    pub model: MaterialModel,
    /// Diffuse reflectance in [0, 1] per channel (default 0.8; mirror: 0).
    pub diffuse: Option<Vec3>,
    /// Specular reflectance of the lobe in [0, 1] (default 0); phong and blinn_phong only.
    pub specular: Option<Vec3>,
    /// Exponent of the lobe in [0, 1e4] (default 32); phong and blinn_phong only.
    pub shininess: Option<f64>,
    /// Perfect-mirror reflectance in [0, 1] per channel (default 0; mirror: 1).
    pub mirror: Option<Vec3>,
    /// Index of refraction inside over outside, in [0.1, 10] (default 1.5); dielectric only.
    pub ior: Option<f64>,
    /// A rough conductor's roughness in [0.01, 1] (GGX alpha = roughness², glTF's and
    /// Disney's convention; default 0.3).
    pub roughness: Option<f64>,
    /// A PNG or JPEG image (relative to the scene file) whose colour multiplies `diffuse`.
    pub diffuse_texture: Option<String>,
    /// How `diffuse_texture` continues beyond [0, 1] along u and v (default "repeat").
    pub texture_wrap: Option<crate::scene::texture::Wrap>,
}

/// The `type` of a `[[shapes]]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeType {
    /// A sphere: `center`, `radius`.
    Sphere,
    /// A parallelogram: `corner`, `edge_u`, `edge_v`.
    Quad,
    /// An infinite plane: `point`, `normal`.
    Plane,
    /// A triangle mesh read from `file` (OBJ or PLY, optionally gzipped).
    Mesh,
    /// A torus around the vertical axis through `center`: `major_radius`, `minor_radius`;
    /// `rotate` turns it about `center`.
    Torus,
    /// Bicubic Bézier patches read from `file` (Newell's format), placed as a mesh is.
    Bezier,
    /// An ellipsoid: `center`, semi-axes `radii` along x, y, z; `rotate` turns it about
    /// `center`.
    Ellipsoid,
    /// A cylinder around the vertical axis through `center` (its base circle's centre):
    /// `radius`, `height`; open at both ends; `rotate` turns it about `center`.
    Cylinder,
}

/// A uniform scale factor or one per axis.
#[derive(Debug, Clone, Copy)]
pub enum Scale {
    /// The same factor on every axis.
    Uniform(f64),
    /// Factors [sx, sy, sz].
    PerAxis(Vec3),
}

/// By hand rather than `#[serde(untagged)]`: an untagged enum buffers the value and reports
/// only "did not match any variant", losing why a per-axis array was refused.
impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ScaleVisitor)
    }
}

struct ScaleVisitor;

impl<'de> Visitor<'de> for ScaleVisitor {
    type Value = Scale;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a number or an array of 3 numbers")
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v as f64))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v as f64))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Scale, A::Error> {
        ExactVisitor(PhantomData).visit_seq(seq).map(Scale::PerAxis)
    }
}

/// One `[[shapes]]` table: the fields its `type` takes are checked in `validate.rs`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeEntry {
    /// The `type` field.
    #[serde(rename = "type")]
    pub kind: ShapeType,
    /// Required, except on a mesh whose file brings its own materials (OBJ `.mtl`).
    pub material: Option<String>,
    // sphere
    /// Sphere, torus or ellipsoid: centre; cylinder: its base circle's centre (scene units).
    pub center: Option<Vec3>,
    /// Sphere or cylinder: radius (scene units), > 0.
    pub radius: Option<f64>,
    // torus (and `center`)
    /// Torus: the radius of its tube's centre circle (scene units), > 0.
    pub major_radius: Option<f64>,
    /// Torus: the tube's radius (scene units), in (0, major_radius).
    pub minor_radius: Option<f64>,
    /// Ellipsoid: semi-axes along x, y and z (scene units), each > 0.
    pub radii: Option<Vec3>,
    /// Cylinder: height above its base circle (scene units), > 0.
    pub height: Option<f64>,
    // quad
    /// Quad: one corner (scene units).
    pub corner: Option<Vec3>,
    /// Quad: the edge from `corner` to the next corner; non-zero.
    pub edge_u: Option<Vec3>,
    /// Quad: the other edge from `corner`; non-zero, not parallel to `edge_u`.
    pub edge_v: Option<Vec3>,
    // plane
    /// Plane: a point on it (scene units).
    pub point: Option<Vec3>,
    /// Plane: its normal; non-zero.
    pub normal: Option<Vec3>,
    // mesh
    /// Mesh: the OBJ or PLY file (`.gz` too), relative to the scene file's directory; Bézier
    /// patches: the patch file.
    pub file: Option<String>,
    /// Mesh or Bézier patches: translation (scene units), applied last.
    pub translate: Option<Vec3>,
    /// Mesh or Bézier patches: rotation in degrees about x, then y, then z; applied after `scale`.
    /// Torus, ellipsoid or cylinder: the same rotation about its `center`.
    pub rotate: Option<Vec3>,
    /// Mesh or Bézier patches: scale factor, uniform or per axis; applied first.
    pub scale: Option<Scale>,
    /// Mesh: smooth shading with vertex normals, the file's or computed (default true).
    pub smooth: Option<bool>,
    /// degrees: with `smooth` and no normals in the file, edges sharper than this stay sharp
    pub crease_angle: Option<f64>,
    /// Linear motion (scene units a second): at time `t` the shape is moved by `velocity * t`;
    /// with the camera's `shutter`, motion blur. Not on planes or emitters.
    pub velocity: Option<Vec3>,
}

/// The `type` of a `[[lights]]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    /// A point light: `position`, `intensity`.
    Point,
    /// A directional light: `direction`, `irradiance`.
    Directional,
    /// A one-sided parallelogram light: `corner`, `edge_u`, `edge_v`, `radiance`, `samples`.
    Area,
    /// A spot light: `position`, `direction` (where it points), `intensity` on its axis,
    /// `outer_angle` and `inner_angle`.
    Spot,
    /// Light from every direction at infinity: a constant `radiance`, or an equirectangular
    /// map `file` times `scale`, turned `rotate` degrees about +y; `samples`.
    Environment,
    /// The sun: a disc at infinity of half-angle `angular_radius_deg` about `direction` (where
    /// its light travels), giving `irradiance` at normal incidence; `samples`.
    Sun,
}

/// One `[[lights]]` table: the fields its `type` takes are checked in `validate.rs`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightEntry {
    /// The `type` field.
    #[serde(rename = "type")]
    pub kind: LightType,
    // point
    /// Point: position (scene units).
    pub position: Option<Vec3>,
    /// Point: radiant intensity (W/sr), 0..=1e20; irradiance I cos(theta) / r^2.
    pub intensity: Option<Vec3>,
    // directional
    /// Directional: the direction the light travels in; non-zero.
    pub direction: Option<Vec3>,
    /// Directional: irradiance on a surface facing the light, 0..=1e20.
    pub irradiance: Option<Vec3>,
    // area
    /// Area: one corner (scene units).
    pub corner: Option<Vec3>,
    /// Area: the first edge from `corner`; the light shines towards edge_u x edge_v.
    pub edge_u: Option<Vec3>,
    /// Area: the second edge from `corner`.
    pub edge_v: Option<Vec3>,
    /// Area: emitted radiance, 0..=1e20; environment: its constant radiance.
    pub radiance: Option<Vec3>,
    /// Area, environment, sun: shadow rays per shading point (default 1).
    pub samples: Option<i64>,
    // environment
    /// Environment: an equirectangular map of linear RGB radiance (OpenEXR or Radiance HDR),
    /// relative to the scene file.
    pub file: Option<String>,
    /// Environment: the map's radiance multiplier, > 0 (default 1).
    pub scale: Option<f64>,
    /// Environment: degrees the map turns about +y (from -z towards +x; default 0).
    pub rotate: Option<f64>,
    // sun
    /// Sun: the half-angle (degrees) of the disc, [1e-4, 45] (default 0.2675, the sun's).
    pub angular_radius_deg: Option<f64>,
    // spot
    /// Spot: angle (degrees) from its axis where the light ends, (0, 90]; default 45.
    pub outer_angle: Option<f64>,
    /// Spot: angle (degrees) from its axis within which the light is full, [0, outer_angle);
    /// default 0.
    pub inner_angle: Option<f64>,
}
