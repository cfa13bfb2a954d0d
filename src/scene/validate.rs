//! Format structs -> [`Scene`]: every range and reference check, each error naming its field.
//!
//! Numbers are checked in f64 before they are narrowed to the f32 the kernels use: finite,
//! inside f32, and coordinates within +-1e9 scene units (past that, f32 products in the
//! intersection routines could overflow; see `docs/scene-format.md`).

use std::path::Path;

use glam::{DVec3, Vec3};

use super::format::{
    CameraSection, DEFAULT_FILM, Exact, LensPivot, LightEntry, LightType, MaterialModel, Pair,
    RenderSection, SamplerName, Scale, SceneFile, ShapeEntry, ShapeType, Vec3 as F3,
};
use super::load::ParsedScene;
use super::mesh::{
    DEFAULT_IOR, IOR_RANGE, TriangleMesh, compute_vertex_normals, orientation_of, rotation_of,
    transform_mesh,
};
use super::mesh_file::load_mesh;
use super::parametric::{BezierPatch, Cylinder, Ellipsoid, Torus};
use super::surface::{CurvedSurface, Surface, load_bezier_patches, orient_outward};
use super::{CameraSpec, Integrator, Light, Material, RenderSettings, Scene, Shape};
use crate::adaptive::{AdaptiveSettings, DEFAULT_MIN_SPP};
use crate::camera::lens::{LensSystem, Prescription};
use crate::camera::lens_focus::refine_focus_points;
use crate::camera::optics::solve_focus_points;
use crate::camera::{Focus, FocusSurface, Movements, Projection};
use crate::error::{Error, Result};
use crate::layout;
use crate::sampler::{MAX_BLADES, MAX_TABLE_SPP};

/// Largest coordinate or length accepted, in scene units.
pub const MAX_COORDINATE: f64 = 1.0e9;
/// Largest image side: wgpu's default texture limit, and a bound on memory.
pub const MAX_IMAGE_SIDE: i64 = 16384;
pub const MAX_SPP: i64 = 1 << 20;
pub const MAX_DEPTH: i64 = 1024;
pub const MAX_LIGHT_SAMPLES: i64 = 4096;
/// How far from the lens its pivot may lie (mm): a base tilt's axis sits a standard's height
/// below it; farther, turning the lens mostly moves it.
const MAX_PIVOT_MM: f64 = 1000.0;

/// Film and lens rotations lie strictly inside +-90 degrees (at 90 a standard is edge-on).
pub const MAX_MOVEMENT_DEG: f64 = 90.0;
/// Edges sharper than this stay sharp when vertex normals are computed (Blender's default).
pub const DEFAULT_CREASE_ANGLE_DEG: f64 = 30.0;
/// Largest radiometric value (intensity, irradiance, radiance, background, ambient): the sum of
/// 2^20 samples, each through up to 1025 path vertices with BRDF values up to 1.6e3 (Phong at
/// shininess 1e4), stays below 2e32, far inside f32's 3.4e38. See `docs/scene-format.md`.
pub const MAX_RADIOMETRIC: f64 = 1.0e20;

/// A number as messages print it: plain in everyday magnitudes, in scientific notation beyond
/// them, so that 1e300 does not print as 301 digits.
fn num(v: f64) -> String {
    let magnitude = v.abs();
    if magnitude == 0.0 || !v.is_finite() || (1.0e-4..1.0e6).contains(&magnitude) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A computed ratio as messages print it: four decimals, unless it is extreme.
fn ratio(v: f64) -> String {
    if (1.0e-4..1.0e6).contains(&v.abs()) {
        format!("{v:.4}")
    } else {
        num(v)
    }
}

/// A vector as messages print it, each element through [`num`].
fn nums(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|&x| num(x)).collect();
    format!("[{}]", items.join(", "))
}

struct Checker<'a> {
    parsed: &'a ParsedScene,
}

impl Checker<'_> {
    fn err(&self, field: &str, message: impl Into<String>) -> Error {
        self.parsed.error(field, message)
    }

    fn finite(&self, field: &str, v: f64) -> Result<f64> {
        if !v.is_finite() {
            return Err(self.err(field, format!("must be a finite number, not {v}")));
        }
        if v.abs() > f32::MAX as f64 {
            return Err(self.err(field, format!("{} does not fit in a 32-bit float", num(v))));
        }
        Ok(v)
    }

    fn positive(&self, field: &str, v: f64) -> Result<f64> {
        let v = self.finite(field, v)?;
        if v <= 0.0 {
            return Err(self.err(field, format!("must be positive, got {}", num(v))));
        }
        Ok(v)
    }

    fn vector(&self, field: &str, v: F3) -> Result<DVec3> {
        for (i, c) in v.0.iter().enumerate() {
            self.finite(&format!("{field}[{i}]"), *c)?;
        }
        Ok(DVec3::from_array(v.0))
    }

    fn point(&self, field: &str, v: F3) -> Result<DVec3> {
        let p = self.vector(field, v)?;
        if p.abs().max_element() > MAX_COORDINATE {
            return Err(self.err(
                field,
                format!(
                    "{} lies beyond +-{MAX_COORDINATE:e} scene units (f32 precision limit)",
                    nums(&p.to_array())
                ),
            ));
        }
        Ok(p)
    }

    /// A non-zero direction or edge vector, returned as given.
    fn nonzero(&self, field: &str, v: F3) -> Result<DVec3> {
        let d = self.point(field, v)?;
        if d.length() == 0.0 {
            return Err(self.err(field, "is a zero-length vector"));
        }
        Ok(d)
    }

    fn color(&self, field: &str, v: F3) -> Result<DVec3> {
        let c = self.vector(field, v)?;
        if c.min_element() < 0.0 {
            return Err(self.err(
                field,
                format!("must not be negative, got {}", nums(&c.to_array())),
            ));
        }
        Ok(c)
    }

    fn reflectance(&self, field: &str, v: F3) -> Result<Vec3> {
        let c = self.color(field, v)?;
        if c.max_element() > 1.0 {
            return Err(self.err(
                field,
                format!("a reflectance lies in [0, 1], got {}", nums(&c.to_array())),
            ));
        }
        Ok(c.as_vec3())
    }

    /// A light's or the environment's radiometric value, bounded so sums stay inside f32.
    fn radiometric(&self, field: &str, v: F3) -> Result<Vec3> {
        let c = self.color(field, v)?;
        if c.max_element() > MAX_RADIOMETRIC {
            return Err(self.err(
                field,
                format!(
                    "{} exceeds {MAX_RADIOMETRIC:e}: sums of samples would overflow the 32-bit \
                     floats of the render",
                    nums(&c.to_array())
                ),
            ));
        }
        Ok(c.as_vec3())
    }

    fn integer(&self, field: &str, v: i64, min: i64, max: i64) -> Result<u32> {
        if v < min || v > max {
            return Err(self.err(
                field,
                format!("must lie in {min}..={max}, got {}", num(v as f64)),
            ));
        }
        Ok(v as u32)
    }

    fn require<T: Copy>(&self, field: &str, v: Option<T>, kind: &str) -> Result<T> {
        v.ok_or_else(|| self.err(field, format!("is required for a {kind}")))
    }

    /// Fields that belong to other shape or light types are errors, not silently ignored.
    fn forbid(&self, prefix: &str, kind: &str, present: &[(&str, bool)]) -> Result<()> {
        match present.iter().find(|(_, p)| *p) {
            Some((name, _)) => Err(self.err(
                &format!("{prefix}.{name}"),
                format!("does not apply to {} {kind}", article(kind)),
            )),
            None => Ok(()),
        }
    }
}

/// "a" or "an" before `word`.
fn article(word: &str) -> &'static str {
    match word.chars().next() {
        Some('a' | 'e' | 'i' | 'o' | 'u') => "an",
        _ => "a",
    }
}

pub fn validate(parsed: ParsedScene) -> Result<Scene> {
    let check = Checker { parsed: &parsed };
    let file: &SceneFile = &parsed.file;
    let meters_per_unit = match file.scene.meters_per_unit {
        Some(m) => check.positive("scene.meters_per_unit", m)?,
        None => 1.0,
    };
    let render = validate_render(&check, file)?;
    let camera = validate_camera(&check, file, &render, meters_per_unit)?;
    let materials = validate_materials(&check, file)?;
    let mut materials = materials;
    let (shapes, surfaces) = validate_shapes(&check, file, &mut materials)?;
    let lights = validate_lights(&check, file)?;
    let velocities = validate_velocities(&check, file, &shapes, &materials)?;
    Ok(Scene {
        source: parsed.path.clone(),
        render,
        camera,
        materials,
        shapes,
        lights,
        velocities,
        surfaces,
    })
}

/// `camera.shutter`: finite, opening before it closes.
fn shutter(check: &Checker, shutter: Option<Pair>) -> Result<[f64; 2]> {
    let Some(Exact([open, close])) = shutter else {
        return Ok([0.0, 0.0]);
    };
    let (open, close) = (
        check.finite("camera.shutter[0]", open)?,
        check.finite("camera.shutter[1]", close)?,
    );
    if close < open {
        return Err(check.err(
            "camera.shutter",
            format!("closes ({}) before it opens ({})", num(close), num(open)),
        ));
    }
    Ok([open, close])
}

/// Each shape's `velocity` (zero where not given); empty when none moves. A plane is unbounded
/// and an emitter is sampled where it stands, so neither may move.
fn validate_velocities(
    check: &Checker,
    file: &SceneFile,
    shapes: &[Shape],
    materials: &[Material],
) -> Result<Vec<Vec3>> {
    let mut velocities = Vec::with_capacity(shapes.len());
    for (i, (entry, shape)) in file.shapes.iter().zip(shapes).enumerate() {
        let field = format!("shapes[{i}].velocity");
        let Some(v) = entry.velocity else {
            velocities.push(Vec3::ZERO);
            continue;
        };
        let v = check.vector(&field, v)?.as_vec3();
        let emits = |m: u32| materials[m as usize].emission.max_element() > 0.0;
        let (moves_plane, moves_emitter) = match shape {
            Shape::Plane { .. } => (true, false),
            Shape::Mesh { mesh, material } => (
                false,
                emits(*material)
                    || mesh
                        .materials
                        .iter()
                        .any(|m| m.emission.max_element() > 0.0),
            ),
            Shape::Sphere { material, .. }
            | Shape::Quad { material, .. }
            | Shape::Curved { material, .. } => (false, emits(*material)),
        };
        if v != Vec3::ZERO && moves_plane {
            return Err(check.err(&field, "an infinite plane cannot move"));
        }
        if v != Vec3::ZERO && moves_emitter {
            return Err(check.err(&field, "an emitter cannot move (lights stand still)"));
        }
        velocities.push(v);
    }
    if velocities.iter().all(|&v| v == Vec3::ZERO) {
        velocities.clear();
    }
    Ok(velocities)
}

/// Table-based samplers store `spp` points per pattern; beyond MAX_TABLE_SPP use another.
fn check_sampler_spp(check: &Checker, field: &str, sampler: SamplerName, spp: i64) -> Result<()> {
    if sampler.uses_table() && spp > MAX_TABLE_SPP as i64 {
        return Err(check.err(
            field,
            format!(
                "{sampler:?} patterns are precomputed for at most {MAX_TABLE_SPP} samples per \
                 pixel, got spp = {spp}; use stratified or sobol"
            ),
        ));
    }
    Ok(())
}

fn validate_render(check: &Checker, file: &SceneFile) -> Result<RenderSettings> {
    let r = &file.render;
    check_sampler_spp(check, "render.pixel_sampler", r.pixel_sampler, r.spp)?;
    let width = check.integer("render.width", r.width, 1, MAX_IMAGE_SIDE)?;
    let height = check.integer("render.height", r.height, 1, MAX_IMAGE_SIDE)?;
    Ok(RenderSettings {
        width,
        height,
        crop: crop_window(check, r.crop.as_ref().map(|c| c.0), width, height)?,
        spp: check.integer("render.spp", r.spp, 1, MAX_SPP)?,
        integrator: r.integrator,
        max_depth: check.integer("render.max_depth", r.max_depth, 0, MAX_DEPTH)?,
        rr_depth: check.integer("render.rr_depth", r.rr_depth, 0, MAX_DEPTH)?,
        seed: check.integer("render.seed", r.seed, 0, u32::MAX as i64)?,
        pixel_sampler: r.pixel_sampler,
        background: check.radiometric("render.background", r.background)?,
        ambient: ambient(check, r)?,
        adaptive: adaptive_settings(check, r)?,
    })
}

/// `render.ambient`: Whitted's stand-in for indirect light, which the path tracer computes.
fn ambient(check: &Checker, r: &RenderSection) -> Result<Vec3> {
    let ambient = check.radiometric("render.ambient", r.ambient)?;
    if r.integrator == Integrator::Path && ambient.max_element() > 0.0 {
        return Err(check.err(
            "render.ambient",
            "the path tracer computes indirect light itself: ambient light is the Whitted \
             integrator's stand-in for it (set it to 0, or render.integrator = \"whitted\")",
        ));
    }
    Ok(ambient)
}

/// `render.noise_target` and `render.min_spp`: a positive target, and a first decision after at
/// least two samples (one per half) and at most `render.spp`.
fn adaptive_settings(check: &Checker, r: &RenderSection) -> Result<Option<AdaptiveSettings>> {
    let Some(target) = r.noise_target else {
        if r.min_spp.is_some() {
            return Err(check.err(
                "render.min_spp",
                "applies to adaptive sampling only: give render.noise_target (--noise-target)",
            ));
        }
        return Ok(None);
    };
    let noise_target = check.positive("render.noise_target", target)?;
    if noise_target < f32::MIN_POSITIVE as f64 || noise_target > 1e6 {
        return Err(check.err(
            "render.noise_target",
            format!("lies in [1e-37, 1e6], got {}", num(noise_target)),
        ));
    }
    let spp = r.spp.clamp(1, MAX_SPP);
    let min_spp = match r.min_spp {
        Some(n) => check.integer("render.min_spp", n, 2, spp.max(2))?,
        None => DEFAULT_MIN_SPP.min(spp as u32),
    };
    Ok(Some(AdaptiveSettings {
        noise_target: noise_target as f32,
        min_spp,
    }))
}

/// pbrt's crop window: fractions [x0, x1, y0, y1] of the image, to pixel bounds by rounding
/// up (`ceil(width * x0) .. ceil(width * x1)`), which must hold at least one pixel.
fn crop_window(
    check: &Checker,
    crop: Option<[f64; 4]>,
    width: u32,
    height: u32,
) -> Result<[u32; 4]> {
    let Some(window) = crop else {
        return Ok([0, width, 0, height]);
    };
    for (i, v) in window.iter().enumerate() {
        let v = check.finite(&format!("render.crop[{i}]"), *v)?;
        if !(0.0..=1.0).contains(&v) {
            return Err(check.err(
                &format!("render.crop[{i}]"),
                format!("a crop window bound lies in [0, 1], got {}", num(v)),
            ));
        }
    }
    let [x0, x1, y0, y1] = window;
    let to_pixels = |f: f64, side: u32| (f * side as f64).ceil() as u32;
    let bounds = [
        to_pixels(x0, width),
        to_pixels(x1, width),
        to_pixels(y0, height),
        to_pixels(y1, height),
    ];
    if bounds[0] >= bounds[1] || bounds[2] >= bounds[3] {
        return Err(check.err(
            "render.crop",
            format!(
                "[{}] holds no pixel of the {width}x{height} image ([x0, x1, y0, y1] with \
                 x0 < x1 and y0 < y1)",
                nums(&window)
            ),
        ));
    }
    Ok(bounds)
}

fn validate_camera(
    check: &Checker,
    file: &SceneFile,
    render: &RenderSettings,
    meters_per_unit: f64,
) -> Result<CameraSpec> {
    let c = &file.camera;
    let (position, look_at, up) = view(check, c)?;
    if c.projection == Projection::Orthographic {
        return validate_orthographic(check, c, render, meters_per_unit, [position, look_at, up]);
    }
    if c.window.is_some() {
        return Err(check.err(
            "camera.window",
            "only an orthographic camera (projection = \"orthographic\") has a window; a \
             perspective camera's is its `film`, in mm",
        ));
    }
    let [w, h] = c.film.map_or(DEFAULT_FILM, |f| f.0);
    let film = [
        check.positive("camera.film[0]", w)?,
        check.positive("camera.film[1]", h)?,
    ];
    check_aspect(check, "camera.film", film, "mm", render)?;
    let lens = real_lens(check, c)?;
    let (focal_length_mm, f_number, principal_gap) = match &lens {
        Some(lens) => (
            lens.paraxial.focal_length,
            lens.f_number,
            lens.principal_gap(),
        ),
        None => (focal_length(check, c, film)?, f_number(check, c)?, 0.0),
    };
    let units_per_mm = 0.001 / meters_per_unit;
    let focus = (f_number, focal_length_mm, units_per_mm, principal_gap);
    let focus_distance = focus_distance(check, c, focus)?;
    let movements = movements(check, c, lens.as_ref())?;
    let aperture_blades = aperture_blades(check, c)?;
    let mut camera = CameraSpec {
        projection: Projection::Perspective,
        position,
        look_at,
        up,
        focal_length_mm,
        film_mm: film,
        f_number,
        focus: Focus::Pinhole,
        film_distance_mm: focal_length_mm,
        movements,
        aperture_blades,
        aperture_rotation_deg: check.finite(
            "camera.aperture_rotation",
            c.aperture_rotation.unwrap_or(0.0),
        )?,
        lens_sampler: c.lens_sampler,
        units_per_mm,
        shutter: shutter(check, c.shutter)?,
        focus_surface: c.focus_surface.unwrap_or_default(),
        spectral: spectral(check, c, lens.as_ref())?,
        lens,
    };
    if f_number > 0.0 {
        check_sampler_spp(
            check,
            "camera.lens_sampler",
            c.lens_sampler,
            file.render.spp,
        )?;
    }
    place_focus(check, c, &mut camera, focus_distance)?;
    check_film_behind_lens(check, &camera)?;
    check_focus_surface(check, &camera)?;
    Ok(camera)
}

/// `camera.spectral`: only a real lens whose glasses disperse has colours to separate (a thin
/// lens, or glass of one index at every wavelength, would only add colour noise).
fn spectral(check: &Checker, c: &CameraSection, lens: Option<&LensSystem>) -> Result<bool> {
    let field = "camera.spectral";
    match (c.spectral.unwrap_or(false), lens) {
        (false, _) => Ok(false),
        (true, None) => Err(check.err(
            field,
            "the spectral mode traces a real lens's dispersion: give `lens` (a thin lens has \
             none)",
        )),
        (true, Some(lens)) if !lens.is_dispersive() => Err(check.err(
            field,
            "the lens file gives no dispersion: add each glass's Abbe number (a fifth column) \
             or Sellmeier terms (docs/lens.md)",
        )),
        (true, Some(_)) => Ok(true),
    }
}

/// `camera.lens`: the prescription read and stopped to `f_number` (its widest when none is
/// given), with the fields a real lens replaces or does not have yet refused by name.
fn real_lens(check: &Checker, c: &CameraSection) -> Result<Option<LensSystem>> {
    let Some(name) = &c.lens else {
        return Ok(None);
    };
    let replaced = [
        (
            "focal_length",
            c.focal_length.is_some(),
            "the lens file sets the focal length",
        ),
        (
            "vertical_fov",
            c.vertical_fov.is_some(),
            "the lens file sets the focal length",
        ),
        (
            "aperture_blades",
            c.aperture_blades.is_some(),
            "a real lens's stop is round",
        ),
        (
            "aperture_rotation",
            c.aperture_rotation.is_some(),
            "a real lens's stop is round",
        ),
        (
            "focus_surface",
            c.focus_surface.is_some(),
            "a real lens's focal surface is its own",
        ),
    ];
    if let Some((field, _, why)) = replaced.iter().find(|(_, given, _)| *given) {
        return Err(check.err(
            &format!("camera.{field}"),
            format!("{why}: leave it out with `lens`"),
        ));
    }
    let folder = check
        .parsed
        .path
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let prescription = Prescription::read(&folder.join(name))?;
    let f_number = match c.f_number {
        Some(n) => Some(check.positive("camera.f_number", n)?),
        None => None,
    };
    let lens = LensSystem::new(&prescription, f_number).map_err(|e| {
        let field = if f_number.is_some() {
            "camera.f_number"
        } else {
            "camera.lens"
        };
        check.err(field, format!("{name}: {e}"))
    })?;
    Ok(Some(lens))
}

/// The focal length (mm): `focal_length`, or the one that gives `vertical_fov` on the film's
/// height, or 50 mm.
fn focal_length(check: &Checker, c: &CameraSection, film: [f64; 2]) -> Result<f64> {
    Ok(match (c.focal_length, c.vertical_fov) {
        (Some(_), Some(_)) => {
            return Err(check.err(
                "camera.vertical_fov",
                "give either focal_length or vertical_fov, not both",
            ));
        }
        (Some(f), None) => check.positive("camera.focal_length", f)?,
        (None, Some(fov)) => {
            let fov = check.finite("camera.vertical_fov", fov)?;
            if fov <= 0.0 || fov >= 180.0 {
                return Err(check.err(
                    "camera.vertical_fov",
                    format!("must lie in (0, 180) degrees, got {}", num(fov)),
                ));
            }
            0.5 * film[1] / (0.5 * fov.to_radians()).tan()
        }
        (None, None) => 50.0,
    })
}

/// `f_number`: 0 (a pinhole, the default) or positive.
fn f_number(check: &Checker, c: &CameraSection) -> Result<f64> {
    Ok(match c.f_number {
        Some(n) => {
            let n = check.finite("camera.f_number", n)?;
            if n < 0.0 {
                return Err(check.err(
                    "camera.f_number",
                    format!("must be 0 (pinhole) or positive, got {}", num(n)),
                ));
            }
            n
        }
        None => 0.0,
    })
}

/// `focus_distance` in scene units (`None`: infinity or not given), beyond the focal length
/// when there is a lens.
/// `focus_distance` (scene units from the lens centre), checked to lie beyond the front focal
/// point: the focal length from the front principal point, `principal_gap` mm ahead of the
/// lens centre (0 for the thin lens).
fn focus_distance(
    check: &Checker,
    c: &CameraSection,
    (f_number, focal_length_mm, units_per_mm, principal_gap): (f64, f64, f64, f64),
) -> Result<Option<f64>> {
    Ok(match c.focus_distance {
        Some(d) if d == f64::INFINITY => None,
        Some(d) => {
            let d = check.positive("camera.focus_distance", d)?;
            if f_number > 0.0 && d / units_per_mm - principal_gap <= focal_length_mm {
                return Err(check.err(
                    "camera.focus_distance",
                    format!(
                        "{} scene units ({} mm) is not beyond the focal length {} mm: \
                         no real image forms",
                        num(d),
                        num(d / units_per_mm),
                        num(focal_length_mm)
                    ),
                ));
            }
            Some(d)
        }
        None => None,
    })
}

/// The film's and the lens's tilt, swing and shift, and the lens's pivot.
fn movements(check: &Checker, c: &CameraSection, lens: Option<&LensSystem>) -> Result<Movements> {
    let angle = |field: &str, v: Option<f64>| movement_angle(check, field, v);
    let shift = |field: &str, v: Option<Pair>| movement_shift(check, field, v);
    Ok(Movements {
        film_tilt: angle("camera.film_tilt", c.film_tilt)?,
        film_swing: angle("camera.film_swing", c.film_swing)?,
        film_shift: shift("camera.film_shift", c.film_shift)?,
        lens_tilt: angle("camera.lens_tilt", c.lens_tilt)?,
        lens_swing: angle("camera.lens_swing", c.lens_swing)?,
        lens_shift: shift("camera.lens_shift", c.lens_shift)?,
        lens_pivot: lens_pivot(check, c, lens)?,
    })
}

/// `lens_pivot` (mm from the lens centre, unturned lens frame): a named point on the axis or a
/// point within `MAX_PIVOT_MM`.
fn lens_pivot(check: &Checker, c: &CameraSection, lens: Option<&LensSystem>) -> Result<[f64; 3]> {
    let field = "camera.lens_pivot";
    let on_axis = |z: f64| [0.0, 0.0, z];
    Ok(match &c.lens_pivot {
        None => on_axis(0.0),
        Some(LensPivot::Named(name)) => match name.as_str() {
            "rear_nodal" => on_axis(0.0),
            "front_nodal" => on_axis(lens.map_or(0.0, |l| l.principal_gap())),
            "stop" => on_axis(lens.map_or(0.0, |l| l.stop_z())),
            _ => {
                return Err(check.err(
                    field,
                    format!(
                        "unknown pivot \"{name}\": use \"rear_nodal\", \"front_nodal\", \"stop\" \
                         or a point [right, up, forward] in mm"
                    ),
                ));
            }
        },
        Some(LensPivot::Point(p)) => {
            let p = check.vector(field, *p)?;
            if p.abs().max_element() > MAX_PIVOT_MM {
                return Err(check.err(
                    field,
                    format!(
                        "{} lies more than {MAX_PIVOT_MM} mm from the lens",
                        nums(&p.to_array())
                    ),
                ));
            }
            p.to_array()
        }
    })
}

/// `aperture_blades`: 0 (a circle) or 3 to `MAX_BLADES`.
fn aperture_blades(check: &Checker, c: &CameraSection) -> Result<u32> {
    Ok(match c.aperture_blades {
        None | Some(0) => 0,
        Some(n) if (1..3).contains(&n) => {
            return Err(check.err(
                "camera.aperture_blades",
                format!("{n} blades make no aperture: use 0 (circle) or 3..={MAX_BLADES}"),
            ));
        }
        Some(n) => check.integer("camera.aperture_blades", n, 3, MAX_BLADES as i64)?,
    })
}

/// Where the camera focuses: one of `film_distance`, `focus_points` (the lens tilt and swing
/// solved from them) or `focus_distance` (infinity when none is given); a pinhole keeps its
/// film at the focal length.
fn place_focus(
    check: &Checker,
    c: &CameraSection,
    camera: &mut CameraSpec,
    focus_distance: Option<f64>,
) -> Result<()> {
    let (f_number, focal_length_mm, units_per_mm) =
        (camera.f_number, camera.focal_length_mm, camera.units_per_mm);
    let focus_fields = [
        ("focus_distance", c.focus_distance.is_some()),
        ("film_distance", c.film_distance.is_some()),
        ("focus_points", c.focus_points.is_some()),
    ];
    let given: Vec<&str> = focus_fields
        .iter()
        .filter(|(_, p)| *p)
        .map(|(n, _)| *n)
        .collect();
    if given.len() > 1 {
        return Err(check.err(
            &format!("camera.{}", given[1]),
            format!(
                "give one of focus_distance, film_distance, focus_points, not {}",
                given.join(" and ")
            ),
        ));
    }
    if let Some(d) = c.film_distance {
        let d = check.positive("camera.film_distance", d)?;
        if f_number > 0.0 && d < focal_length_mm {
            return Err(check.err(
                "camera.film_distance",
                format!(
                    "{} mm puts the film closer to the lens than its focal length \
                     {} mm: no real object is in focus there",
                    num(d),
                    num(focal_length_mm)
                ),
            ));
        }
        camera.film_distance_mm = d;
        camera.focus = Focus::FilmDistance;
    } else if let Some(points) = c.focus_points {
        let field = "camera.focus_points";
        if f_number == 0.0 {
            return Err(check.err(field, "needs a lens: set f_number (a pinhole has no focus)"));
        }
        for (name, present) in [
            ("lens_tilt", c.lens_tilt.is_some()),
            ("lens_swing", c.lens_swing.is_some()),
        ] {
            if present {
                return Err(check.err(
                    &format!("camera.{name}"),
                    "is solved from focus_points: give one or the other",
                ));
            }
        }
        let mut world = [DVec3::ZERO; 3];
        for (i, p) in points.0.iter().enumerate() {
            world[i] = check.point(&format!("{field}[{i}]"), *p)?;
        }
        let mut solution = solve_focus_points(camera, world).map_err(|e| check.err(field, e))?;
        if camera.lens.is_some() {
            solution =
                refine_focus_points(camera, &world, solution).map_err(|e| check.err(field, e))?;
        }
        camera.movements.lens_tilt = solution.lens_tilt;
        camera.movements.lens_swing = solution.lens_swing;
        camera.film_distance_mm = solution.film_distance_mm;
        camera.focus = Focus::Points(world);
    } else if f_number > 0.0 {
        let gap = camera.lens.as_ref().map_or(0.0, |l| l.principal_gap());
        camera.film_distance_mm = match focus_distance {
            Some(d) => 1.0 / (1.0 / focal_length_mm - 1.0 / (d / units_per_mm - gap)),
            None => focal_length_mm,
        };
        camera.focus = Focus::Distance(focus_distance);
    }
    Ok(())
}

/// `camera.position`, `look_at` and `up`: a viewing direction, and an up not along it.
fn view(check: &Checker, c: &CameraSection) -> Result<(DVec3, DVec3, DVec3)> {
    let position = check.point("camera.position", c.position)?;
    let look_at = check.point("camera.look_at", c.look_at)?;
    let up = check.nonzero("camera.up", c.up)?;
    let forward = look_at - position;
    if forward.length() <= 1e-12 * position.length().max(1.0) {
        return Err(check.err(
            "camera.look_at",
            "equals camera.position: no viewing direction",
        ));
    }
    if forward.normalize().cross(up.normalize()).length() < 1e-9 {
        return Err(check.err("camera.up", "is parallel to the viewing direction"));
    }
    Ok((position, look_at, up))
}

/// The film's (or window's) aspect must be the image's: whole pixels cannot always match it
/// exactly, so the aspect a side's rounding to the nearest pixel gives (or 0.1%, whichever is
/// larger) is allowed. A side of `n` pixels rounded from `n - δ`, `|δ| <= 1/2`, moves the
/// aspect by `δ / (n - δ)`: at most `1/2 / (n - 1/2)`.
fn check_aspect(
    check: &Checker,
    field: &str,
    size: [f64; 2],
    unit: &str,
    render: &RenderSettings,
) -> Result<()> {
    let aspect = size[0] / size[1];
    let image_aspect = render.width as f64 / render.height as f64;
    let rounding = 0.5 / (render.width.min(render.height) as f64 - 0.5);
    // The margin covers the rounding of the divisions above.
    if (aspect / image_aspect - 1.0).abs() > rounding.max(1e-3) * (1.0 + 1e-9) {
        return Err(check.err(
            field,
            format!(
                "{} aspect {} ({} x {} {unit}) does not match the image aspect {} ({} x {} \
                 pixels)",
                field.trim_start_matches("camera."),
                ratio(aspect),
                num(size[0]),
                num(size[1]),
                ratio(image_aspect),
                render.width,
                render.height
            ),
        ));
    }
    Ok(())
}

/// A film or lens rotation (degrees, 0 when absent), strictly inside +-`MAX_MOVEMENT_DEG`.
fn movement_angle(check: &Checker, field: &str, v: Option<f64>) -> Result<f64> {
    let a = check.finite(field, v.unwrap_or(0.0))?;
    if a.abs() >= MAX_MOVEMENT_DEG {
        return Err(check.err(
            field,
            format!(
                "{} degrees turns the standard edge-on or past it: movements lie strictly \
                 between -{MAX_MOVEMENT_DEG} and {MAX_MOVEMENT_DEG} degrees",
                num(a)
            ),
        ));
    }
    Ok(a)
}

/// A film or lens shift ([0, 0] when absent), finite.
fn movement_shift(check: &Checker, field: &str, v: Option<Pair>) -> Result<[f64; 2]> {
    let [x, y] = v.unwrap_or_default().0;
    Ok([
        check.finite(&format!("{field}[0]"), x)?,
        check.finite(&format!("{field}[1]"), y)?,
    ])
}

/// An orthographic camera: its `window` (scene units) with the image's aspect, the film tilt,
/// swing and shift (scene units) that move it, and none of the lens's fields: its rays are
/// parallel, so a lens, an aperture or a focus would mean nothing, and a field that asks for
/// one is refused by name rather than ignored.
fn validate_orthographic(
    check: &Checker,
    c: &CameraSection,
    render: &RenderSettings,
    meters_per_unit: f64,
    [position, look_at, up]: [DVec3; 3],
) -> Result<CameraSpec> {
    let lens_fields = [
        ("film", c.film.is_some()),
        ("focal_length", c.focal_length.is_some()),
        ("vertical_fov", c.vertical_fov.is_some()),
        ("f_number", c.f_number.is_some()),
        ("focus_distance", c.focus_distance.is_some()),
        ("film_distance", c.film_distance.is_some()),
        ("focus_points", c.focus_points.is_some()),
        ("lens_tilt", c.lens_tilt.is_some()),
        ("lens_swing", c.lens_swing.is_some()),
        ("lens_shift", c.lens_shift.is_some()),
        ("lens_pivot", c.lens_pivot.is_some()),
        ("aperture_blades", c.aperture_blades.is_some()),
        ("aperture_rotation", c.aperture_rotation.is_some()),
        ("focus_surface", c.focus_surface.is_some()),
        ("lens", c.lens.is_some()),
        ("spectral", c.spectral.is_some()),
    ];
    if let Some((name, _)) = lens_fields.iter().find(|(_, given)| *given) {
        let why = match *name {
            "film" => "an orthographic camera's film is its `window`, in scene units",
            _ => "an orthographic camera has no lens (its rays are parallel and all sharp)",
        };
        return Err(check.err(&format!("camera.{name}"), format!("{why}: leave it out")));
    }
    let Some(Exact([w, h])) = c.window else {
        return Err(check.err(
            "camera.projection",
            "an orthographic camera needs `window = [width, height]`, in scene units",
        ));
    };
    let mut window = [0.0; 2];
    for (i, v) in [w, h].into_iter().enumerate() {
        let field = format!("camera.window[{i}]");
        window[i] = check.positive(&field, v)?;
        if window[i] > MAX_COORDINATE {
            return Err(check.err(
                &field,
                format!("{} is wider than {MAX_COORDINATE:e} scene units", num(v)),
            ));
        }
    }
    check_aspect(check, "camera.window", window, "scene units", render)?;
    let units_per_mm = 0.001 / meters_per_unit;
    let shift = movement_shift(check, "camera.film_shift", c.film_shift)?;
    let movements = Movements {
        film_tilt: movement_angle(check, "camera.film_tilt", c.film_tilt)?,
        film_swing: movement_angle(check, "camera.film_swing", c.film_swing)?,
        film_shift: shift.map(|v| v / units_per_mm),
        ..Movements::default()
    };
    Ok(CameraSpec {
        projection: Projection::Orthographic,
        position,
        look_at,
        up,
        focal_length_mm: f64::INFINITY,
        film_mm: window.map(|v| v / units_per_mm),
        f_number: 0.0,
        focus: Focus::Pinhole,
        film_distance_mm: 0.0,
        movements,
        aperture_blades: 0,
        aperture_rotation_deg: 0.0,
        lens_sampler: c.lens_sampler,
        units_per_mm,
        shutter: shutter(check, c.shutter)?,
        focus_surface: FocusSurface::Plane,
        lens: None,
        spectral: false,
    })
}

/// A curved focal surface needs a lens focused at a distance (its radius), and no lens tilt or
/// swing: those tilt a plane of focus, which a sphere or cylinder about the lens does not have.
fn check_focus_surface(check: &Checker, camera: &CameraSpec) -> Result<()> {
    if camera.focus_surface == crate::camera::FocusSurface::Plane {
        return Ok(());
    }
    let field = "camera.focus_surface";
    if !matches!(camera.focus, Focus::Distance(Some(_))) {
        return Err(check.err(
            field,
            "a curved focal surface needs a lens (f_number) and focus_distance, its radius",
        ));
    }
    let m = &camera.movements;
    if m.lens_tilt != 0.0 || m.lens_swing != 0.0 {
        return Err(check.err(
            field,
            "a curved focal surface cannot be tilted: give lens_tilt and lens_swing 0 (or a \
             plane of focus)",
        ));
    }
    Ok(())
}

/// Every film corner must lie behind the lens plane, by a margin: a film that reaches the lens
/// plane would send rays sideways at infinite slope.
fn check_film_behind_lens(check: &Checker, camera: &CameraSpec) -> Result<()> {
    let margin = 0.01 * camera.focal_length_mm;
    // A real lens's back is its rear vertex, not H'.
    let back = camera.lens.as_ref().map_or(0.0, |l| l.rear_z().min(0.0));
    for corner in camera.film_corners_in_lens_frame() {
        if corner.z > back - margin {
            let m = &camera.movements;
            return Err(check.err(
                "camera",
                format!(
                    "with film_tilt {} and film_swing {} (film {} x {} mm at {} mm), \
                     lens_tilt {:.3} and lens_swing {:.3} degrees, a film corner reaches \
                     {} mm from the lens plane: no image can form; reduce the movements",
                    num(m.film_tilt),
                    num(m.film_swing),
                    num(camera.film_mm[0]),
                    num(camera.film_mm[1]),
                    num(camera.film_distance_mm),
                    m.lens_tilt,
                    m.lens_swing,
                    num(-corner.z)
                ),
            ));
        }
    }
    Ok(())
}

/// A dielectric's fields: the path tracer's alone, Fresnel's equations its only terms, an index
/// of refraction in [0.1, 10]; 1 for other models, which take no `ior`.
fn dielectric_ior(check: &Checker, file: &SceneFile, i: usize) -> Result<f32> {
    let m = &file.materials[i];
    let at = |f: &str| format!("materials[{i}].{f}");
    if m.model != MaterialModel::Dielectric {
        if m.ior.is_some() {
            return Err(check.err(&at("ior"), "only dielectric materials refract"));
        }
        return Ok(1.0);
    }
    if file.render.integrator != Integrator::Path {
        return Err(check.err(
            &at("model"),
            "a dielectric (glass) refracts: render it with render.integrator = \"path\"",
        ));
    }
    if let Some(field) = [("diffuse", m.diffuse), ("mirror", m.mirror)]
        .iter()
        .find_map(|(name, v)| v.map(|_| *name))
    {
        return Err(check.err(
            &at(field),
            "a dielectric reflects and refracts by Fresnel's equations alone",
        ));
    }
    let ior = check.finite(&at("ior"), m.ior.unwrap_or(f64::from(DEFAULT_IOR)))?;
    if !IOR_RANGE.contains(&ior) {
        let (low, high) = (IOR_RANGE.start(), IOR_RANGE.end());
        return Err(check.err(
            &at("ior"),
            format!("must lie in [{low}, {high}], got {}", num(ior)),
        ));
    }
    Ok(ior as f32)
}

fn validate_materials(check: &Checker, file: &SceneFile) -> Result<Vec<Material>> {
    let mut materials: Vec<Material> = Vec::new();
    for (i, m) in file.materials.iter().enumerate() {
        let at = |f: &str| format!("materials[{i}].{f}");
        if materials.iter().any(|o| o.name == m.name) {
            return Err(check.err(&at("name"), format!("duplicate material name `{}`", m.name)));
        }
        let ior = dielectric_ior(check, file, i)?;
        let roughness = conductor_roughness(check, file, i)?;
        let is_mirror = m.model == MaterialModel::Mirror;
        let conductor = m.model == MaterialModel::RoughConductor;
        let no_diffuse = is_mirror || m.model == MaterialModel::Dielectric || conductor;
        let default_diffuse = Exact(if no_diffuse { [0.0; 3] } else { [0.8; 3] });
        let default_mirror = Exact(if is_mirror { [1.0; 3] } else { [0.0; 3] });
        let default_specular = Exact(if conductor { [0.9; 3] } else { [0.0; 3] });
        let specular =
            check.reflectance(&at("specular"), m.specular.unwrap_or(default_specular))?;
        let uses_lobe = matches!(m.model, MaterialModel::Phong | MaterialModel::BlinnPhong);
        let foreign_lobe = match (uses_lobe, conductor) {
            (true, _) => None,
            (false, true) => m.shininess.map(|_| "shininess"),
            (false, false) => [
                ("specular", m.specular.is_some()),
                ("shininess", m.shininess.is_some()),
            ]
            .iter()
            .find_map(|(name, given)| given.then_some(*name)),
        };
        if let Some(field) = foreign_lobe {
            return Err(check.err(
                &at(field),
                "only phong, blinn_phong and rough_conductor materials have a specular lobe \
                 (a rough conductor's is shaped by its roughness, not a shininess)",
            ));
        }
        let shininess = check.finite(&at("shininess"), m.shininess.unwrap_or(32.0))?;
        if !(0.0..=1.0e4).contains(&shininess) {
            return Err(check.err(
                &at("shininess"),
                format!("must lie in [0, 10000], got {}", num(shininess)),
            ));
        }
        materials.push(Material {
            name: m.name.clone(),
            model: match m.model {
                MaterialModel::Lambert | MaterialModel::Mirror => layout::MODEL_LAMBERT,
                MaterialModel::Phong => layout::MODEL_PHONG,
                MaterialModel::BlinnPhong => layout::MODEL_BLINN_PHONG,
                MaterialModel::Dielectric => layout::MODEL_DIELECTRIC,
                MaterialModel::RoughConductor => layout::MODEL_ROUGH_CONDUCTOR,
            },
            diffuse: check.reflectance(&at("diffuse"), m.diffuse.unwrap_or(default_diffuse))?,
            specular,
            shininess: roughness.map_or(shininess as f32, ggx_alpha),
            mirror: check.reflectance(&at("mirror"), m.mirror.unwrap_or(default_mirror))?,
            emission: Vec3::ZERO,
            ior,
            diffuse_texture: diffuse_texture(check, file, i)?,
        });
    }
    Ok(materials)
}

/// GGX's alpha for a perceptual `roughness` (glTF's and Disney's alpha = roughness²), kept at
/// 1e-4 or more: below it the lobe is a mirror in f32 (use the mirror model).
pub(super) fn ggx_alpha(roughness: f32) -> f32 {
    (roughness * roughness).max(1e-4)
}

/// A rough conductor's `roughness` in [0.01, 1] (default 0.3), which no other model takes; its
/// lobe is its only term (no `diffuse`, `mirror` or texture).
fn conductor_roughness(check: &Checker, file: &SceneFile, i: usize) -> Result<Option<f32>> {
    let m = &file.materials[i];
    let at = |f: &str| format!("materials[{i}].{f}");
    if m.model != MaterialModel::RoughConductor {
        return match m.roughness {
            Some(_) => Err(check.err(
                &at("roughness"),
                "only rough_conductor materials have a roughness",
            )),
            None => Ok(None),
        };
    }
    if let Some(field) = [
        ("diffuse", m.diffuse.is_some()),
        ("mirror", m.mirror.is_some()),
    ]
    .iter()
    .find_map(|(name, given)| given.then_some(*name))
    {
        return Err(check.err(
            &at(field),
            "a rough conductor reflects by its GGX lobe alone",
        ));
    }
    let roughness = check.finite(&at("roughness"), m.roughness.unwrap_or(0.3))?;
    if !(0.01..=1.0).contains(&roughness) {
        return Err(check.err(
            &at("roughness"),
            format!(
                "must lie in [0.01, 1] (0 is a mirror: use model = \"mirror\"), got {}",
                num(roughness)
            ),
        ));
    }
    Ok(Some(roughness as f32))
}

/// A material's `diffuse_texture`, read relative to the scene file, with its `texture_wrap`.
fn diffuse_texture(
    check: &Checker,
    file: &SceneFile,
    i: usize,
) -> Result<Option<std::sync::Arc<super::texture::Texture>>> {
    let m = &file.materials[i];
    let at = |f: &str| format!("materials[{i}].{f}");
    let Some(name) = &m.diffuse_texture else {
        if m.texture_wrap.is_some() {
            return Err(check.err(
                &at("texture_wrap"),
                "applies to a diffuse_texture, and there is none",
            ));
        }
        return Ok(None);
    };
    if matches!(
        m.model,
        MaterialModel::Mirror | MaterialModel::Dielectric | MaterialModel::RoughConductor
    ) {
        return Err(check.err(
            &at("diffuse_texture"),
            "the material has no diffuse reflectance to texture",
        ));
    }
    let folder = check
        .parsed
        .path
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let path = folder.join(name);
    let wrap = m.texture_wrap.unwrap_or_default();
    let texture = super::texture::Texture::read(&path)
        .map_err(|e| check.err(&at("diffuse_texture"), format!("{}: {e}", path.display())))?;
    Ok(Some(std::sync::Arc::new(super::texture::Texture {
        wrap: [wrap; 2],
        ..texture
    })))
}

fn validate_shapes(
    check: &Checker,
    file: &SceneFile,
    materials: &mut Vec<Material>,
) -> Result<(Vec<Shape>, Vec<CurvedSurface>)> {
    let scene_dir = check
        .parsed
        .path
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let (mut shapes, mut surfaces) = (Vec::new(), Vec::new());
    for (i, s) in file.shapes.iter().enumerate() {
        let prefix = format!("shapes[{i}]");
        let at = |f: &str| format!("{prefix}.{f}");
        let material =
            match &s.material {
                Some(name) => Some(materials.iter().position(|m| &m.name == name).ok_or_else(
                    || check.err(&at("material"), format!("unknown material `{name}`")),
                )? as u32),
                None => None,
            };
        let kind = shape_kind_name(s.kind);
        check.forbid(&prefix, kind, &foreign_fields(s))?;
        let required = || {
            material.ok_or_else(|| check.err(&at("material"), format!("is required for a {kind}")))
        };
        let shape = match s.kind {
            ShapeType::Sphere => sphere(check, &prefix, s, required()?)?,
            ShapeType::Quad => {
                let (corner, edge_u, edge_v) =
                    parallelogram(check, &prefix, s.corner, s.edge_u, s.edge_v, "quad")?;
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    material: required()?,
                }
            }
            ShapeType::Plane => plane(check, &prefix, s, required()?)?,
            ShapeType::Mesh => {
                let path = scene_dir.join(check.require(&at("file"), s.file.as_ref(), "mesh")?);
                let mut mesh = mesh(check, &prefix, s, &path)?;
                let material = match material {
                    // A scene material overrides the file's.
                    Some(m) => {
                        mesh.face_materials.clear();
                        m
                    }
                    None => {
                        adopt_mesh_materials(check, &at("material"), &path, &mut mesh, materials)?
                    }
                };
                Shape::Mesh { mesh, material }
            }
            ShapeType::Torus => {
                let surface = Surface::Torus(torus(check, &prefix, s)?);
                curved_shape(i, surface, required()?, &mut surfaces)
            }
            ShapeType::Ellipsoid | ShapeType::Cylinder => {
                let surface = round_surface(check, &prefix, s)?;
                curved_shape(i, surface, required()?, &mut surfaces)
            }
            ShapeType::Bezier => {
                let surface = Surface::Patches(bezier_patches(check, &prefix, s, scene_dir)?);
                curved_shape(i, surface, required()?, &mut surfaces)
            }
        };
        textures_have_coordinates(check, &prefix, kind, &shape, materials)?;
        shapes.push(shape);
    }
    Ok((shapes, surfaces))
}

/// A textured material on a shape without texture coordinates is refused: a plane, a curved
/// surface, or a mesh whose file gives none.
fn textures_have_coordinates(
    check: &Checker,
    prefix: &str,
    kind: &str,
    shape: &Shape,
    materials: &[Material],
) -> Result<()> {
    let textured = |m: u32| materials[m as usize].diffuse_texture.is_some();
    let (material, has_coordinates) = match shape {
        Shape::Sphere { material, .. } | Shape::Quad { material, .. } => (*material, true),
        Shape::Plane { material, .. } | Shape::Curved { material, .. } => (*material, false),
        Shape::Mesh { mesh, material } => {
            let face = mesh.face_materials.iter().copied().find(|&m| textured(m));
            (face.unwrap_or(*material), mesh.texcoords.is_some())
        }
    };
    if !textured(material) || has_coordinates {
        return Ok(());
    }
    let why = match shape {
        Shape::Mesh { .. } => "its file gives its vertices no texture coordinates".to_string(),
        _ => format!("{} {kind} has no texture coordinates", article(kind)),
    };
    Err(check.err(
        &format!("{prefix}.material"),
        format!(
            "material `{}` has a diffuse texture, but {why}",
            materials[material as usize].name
        ),
    ))
}

/// A shape type as the scene file spells it.
fn shape_kind_name(kind: ShapeType) -> &'static str {
    match kind {
        ShapeType::Sphere => "sphere",
        ShapeType::Quad => "quad",
        ShapeType::Plane => "plane",
        ShapeType::Mesh => "mesh",
        ShapeType::Torus => "torus",
        ShapeType::Ellipsoid => "ellipsoid",
        ShapeType::Cylinder => "cylinder",
        ShapeType::Bezier => "bezier",
    }
}

/// The geometric fields a shape of `kind` takes; every other one is refused.
fn own_fields(kind: ShapeType) -> &'static [&'static str] {
    match kind {
        ShapeType::Sphere => &["center", "radius"],
        ShapeType::Quad => &["corner", "edge_u", "edge_v"],
        ShapeType::Plane => &["point", "normal"],
        ShapeType::Mesh => &[
            "file",
            "translate",
            "rotate",
            "scale",
            "smooth",
            "crease_angle",
        ],
        ShapeType::Torus => &["center", "major_radius", "minor_radius", "rotate"],
        ShapeType::Ellipsoid => &["center", "radii", "rotate"],
        ShapeType::Cylinder => &["center", "radius", "height", "rotate"],
        ShapeType::Bezier => &["file", "translate", "rotate", "scale"],
    }
}

/// The geometric fields `s` gives that its type does not take, in the order a refusal names
/// the first of them.
fn foreign_fields(s: &ShapeEntry) -> Vec<(&'static str, bool)> {
    let given = [
        ("center", s.center.is_some()),
        ("radius", s.radius.is_some()),
        ("corner", s.corner.is_some()),
        ("edge_u", s.edge_u.is_some()),
        ("edge_v", s.edge_v.is_some()),
        ("point", s.point.is_some()),
        ("normal", s.normal.is_some()),
        ("file", s.file.is_some()),
        ("translate", s.translate.is_some()),
        ("rotate", s.rotate.is_some()),
        ("scale", s.scale.is_some()),
        ("smooth", s.smooth.is_some()),
        ("crease_angle", s.crease_angle.is_some()),
        ("major_radius", s.major_radius.is_some()),
        ("minor_radius", s.minor_radius.is_some()),
        ("radii", s.radii.is_some()),
        ("height", s.height.is_some()),
    ];
    let own = own_fields(s.kind);
    given
        .into_iter()
        .filter(|(name, _)| !own.contains(name))
        .collect()
}

fn sphere(check: &Checker, prefix: &str, s: &ShapeEntry, material: u32) -> Result<Shape> {
    let at = |f: &str| format!("{prefix}.{f}");
    let center = check.point(
        &at("center"),
        check.require(&at("center"), s.center, "sphere")?,
    )?;
    let radius = check.positive(
        &at("radius"),
        check.require(&at("radius"), s.radius, "sphere")?,
    )?;
    if radius > MAX_COORDINATE {
        return Err(check.err(&at("radius"), format!("exceeds {MAX_COORDINATE:e}")));
    }
    Ok(Shape::Sphere {
        center: center.as_vec3(),
        radius: radius as f32,
        material,
    })
}

fn plane(check: &Checker, prefix: &str, s: &ShapeEntry, material: u32) -> Result<Shape> {
    let at = |f: &str| format!("{prefix}.{f}");
    let point = check.point(&at("point"), check.require(&at("point"), s.point, "plane")?)?;
    let normal = check.nonzero(
        &at("normal"),
        check.require(&at("normal"), s.normal, "plane")?,
    )?;
    Ok(Shape::Plane {
        point: point.as_vec3(),
        normal: normal.normalize().as_vec3(),
        material,
    })
}

/// A mesh shape's file read, transformed (scale, then rotation, then translation) and given
/// vertex normals where it is smooth and has none; every vertex within the coordinate limit.
fn mesh(check: &Checker, prefix: &str, s: &ShapeEntry, path: &Path) -> Result<TriangleMesh> {
    let at = |f: &str| format!("{prefix}.{f}");
    let mut mesh = load_mesh(path).map_err(|e| check.err(&at("file"), e))?;
    let scale = match s.scale.unwrap_or(Scale::Uniform(1.0)) {
        Scale::Uniform(k) => DVec3::splat(check.finite(&at("scale"), k)?),
        Scale::PerAxis(v) => check.vector(&at("scale"), v)?,
    };
    if scale.min_element() == 0.0 || scale.abs().min_element() == 0.0 {
        return Err(check.err(&at("scale"), "a zero scale flattens the mesh"));
    }
    let rotate = check.vector(&at("rotate"), s.rotate.unwrap_or_default())?;
    let translate = check.point(&at("translate"), s.translate.unwrap_or_default())?;
    if !s.smooth.unwrap_or(true) {
        mesh.normals = None;
    }
    transform_mesh(
        &mut mesh,
        scale.as_vec3(),
        rotate.as_vec3(),
        translate.as_vec3(),
    );
    let crease = check.finite(
        &at("crease_angle"),
        s.crease_angle.unwrap_or(DEFAULT_CREASE_ANGLE_DEG),
    )?;
    if !(0.0..=180.0).contains(&crease) {
        return Err(check.err(
            &at("crease_angle"),
            format!("must lie in [0, 180] degrees, got {}", num(crease)),
        ));
    }
    if s.smooth.unwrap_or(true) && mesh.normals.is_none() {
        compute_vertex_normals(&mut mesh, crease as f32);
    }
    if let Some((v, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !within_coordinate_limit(**p))
    {
        return Err(check.err(
            &at("file"),
            format!(
                "{}: vertex {v} lies at {} after transformation, beyond \
                 +-{MAX_COORDINATE:e} scene units",
                path.display(),
                nums(&p.as_dvec3().to_array())
            ),
        ));
    }
    Ok(mesh)
}

/// Shape `index`, the curved `surface` as the ray tracers trace it, the surface kept in
/// `surfaces` for the preview.
fn curved_shape(
    index: usize,
    surface: Surface,
    material: u32,
    surfaces: &mut Vec<CurvedSurface>,
) -> Shape {
    let shape = surface.traced_shape(material);
    surfaces.push(CurvedSurface {
        shape: index,
        surface,
    });
    shape
}

/// A `bezier` shape's patches: read from `file`, scaled, rotated and translated as a mesh is
/// (an affine map moves a Bézier patch exactly by its control points), each oriented outward
/// (`surface::orient_outward`).
fn bezier_patches(
    check: &Checker,
    prefix: &str,
    s: &ShapeEntry,
    scene_dir: &std::path::Path,
) -> Result<Vec<BezierPatch>> {
    let at = |f: &str| format!("{prefix}.{f}");
    let name = check.require(&at("file"), s.file.as_ref(), "bezier")?;
    let mut patches =
        load_bezier_patches(&scene_dir.join(name)).map_err(|e| check.err(&at("file"), e))?;
    let scale = match s.scale.unwrap_or(Scale::Uniform(1.0)) {
        Scale::Uniform(k) => DVec3::splat(check.finite(&at("scale"), k)?),
        Scale::PerAxis(v) => check.vector(&at("scale"), v)?,
    };
    if scale.abs().min_element() == 0.0 {
        return Err(check.err(&at("scale"), "a zero scale flattens the patches"));
    }
    let rotate = check.vector(&at("rotate"), s.rotate.unwrap_or_default())?;
    let translate = check.point(&at("translate"), s.translate.unwrap_or_default())?;
    let linear = rotation_of(rotate.as_vec3()).as_dmat3() * glam::DMat3::from_diagonal(scale);
    for p in patches
        .iter_mut()
        .flat_map(|p| p.points.iter_mut().flatten())
    {
        *p = linear * *p + translate;
        if p.abs().max_element() > MAX_COORDINATE {
            return Err(check.err(
                &at("file"),
                format!(
                    "a control point lies at {} after transformation, beyond \
                     +-{MAX_COORDINATE:e} scene units",
                    nums(&p.to_array())
                ),
            ));
        }
    }
    orient_outward(&mut patches);
    Ok(patches)
}

/// An ellipsoid's fields (centre, positive semi-axes) or a cylinder's (base centre, positive
/// radius and height), each within the coordinate limit.
fn round_surface(check: &Checker, prefix: &str, s: &ShapeEntry) -> Result<Surface> {
    let at = |f: &str| format!("{prefix}.{f}");
    let (kind, field) = match s.kind {
        ShapeType::Ellipsoid => ("ellipsoid", "radii"),
        _ => ("cylinder", "height"),
    };
    let center = check.point(&at("center"), check.require(&at("center"), s.center, kind)?)?;
    let positive = |name: &str, value: Option<f64>| -> Result<f64> {
        check.positive(&at(name), check.require(&at(name), value, kind)?)
    };
    let (surface, reach) = match s.kind {
        ShapeType::Ellipsoid => {
            let radii = check.vector(&at("radii"), check.require(&at("radii"), s.radii, kind)?)?;
            if radii.min_element() <= 0.0 {
                return Err(check.err(
                    &at("radii"),
                    format!("must all be positive, got {}", nums(&radii.to_array())),
                ));
            }
            let ellipsoid = Ellipsoid {
                orientation: orientation(check, prefix, s)?,
                ..Ellipsoid::new(center, radii)
            };
            (Surface::Ellipsoid(ellipsoid), radii.max_element())
        }
        _ => {
            let radius = positive("radius", s.radius)?;
            let height = positive("height", s.height)?;
            let cylinder = Cylinder {
                orientation: orientation(check, prefix, s)?,
                ..Cylinder::new(center, radius)
            };
            (Surface::Cylinder { cylinder, height }, radius + height)
        }
    };
    if center.abs().max_element() + reach > MAX_COORDINATE {
        return Err(check.err(
            &at(field),
            format!("the {kind} reaches beyond +-{MAX_COORDINATE:e} scene units"),
        ));
    }
    Ok(surface)
}

/// A torus's fields: a centre within the coordinate limit, 0 < minor_radius < major_radius
/// (a spindle or horn torus passes through itself and its axis) and the whole torus within
/// the limit too.
fn torus(check: &Checker, prefix: &str, s: &ShapeEntry) -> Result<Torus> {
    let at = |f: &str| format!("{prefix}.{f}");
    let center = check.point(
        &at("center"),
        check.require(&at("center"), s.center, "torus")?,
    )?;
    let major = check.positive(
        &at("major_radius"),
        check.require(&at("major_radius"), s.major_radius, "torus")?,
    )?;
    let minor = check.positive(
        &at("minor_radius"),
        check.require(&at("minor_radius"), s.minor_radius, "torus")?,
    )?;
    if minor >= major {
        return Err(check.err(
            &at("minor_radius"),
            format!(
                "must be below major_radius ({}), got {}: such a torus passes through itself",
                num(major),
                num(minor)
            ),
        ));
    }
    if center.abs().max_element() + major + minor > MAX_COORDINATE {
        return Err(check.err(
            &at("major_radius"),
            format!("the torus reaches beyond +-{MAX_COORDINATE:e} scene units"),
        ));
    }
    Ok(Torus {
        orientation: orientation(check, prefix, s)?,
        ..Torus::new(center, major, minor)
    })
}

/// A torus's, ellipsoid's or cylinder's `rotate` (degrees about x, then y, then z, as a mesh's),
/// its orientation about its centre; none leaves it unturned.
fn orientation(check: &Checker, prefix: &str, s: &ShapeEntry) -> Result<glam::DQuat> {
    let at = format!("{prefix}.rotate");
    Ok(orientation_of(
        check.vector(&at, s.rotate.unwrap_or_default())?,
    ))
}

/// NaN compares false, so finiteness is tested first and explicitly.
fn within_coordinate_limit(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() as f64 <= MAX_COORDINATE
}

/// A mesh that brings its own materials (OBJ `.mtl`) without a scene material: its materials
/// join the scene's, named `file:material`, and each face takes its own. Every face must have
/// one. Returns the material of the first face (the shape's, for messages).
fn adopt_mesh_materials(
    check: &Checker,
    field: &str,
    path: &std::path::Path,
    mesh: &mut super::mesh::TriangleMesh,
    materials: &mut Vec<Material>,
) -> Result<u32> {
    use super::mesh::NO_MATERIAL;
    let without = mesh.face_materials.is_empty() || mesh.face_materials.contains(&NO_MATERIAL);
    if without && let Some(missing) = mesh.missing_libraries.first() {
        return Err(check.err(
            field,
            format!(
                "is required: {missing}, and {} faces have no material without it (give the \
                 mesh a scene material, or put the library beside the OBJ)",
                path.display()
            ),
        ));
    }
    if without {
        return Err(check.err(
            field,
            format!(
                "is required: {} gives {} faces no material of its own",
                path.display(),
                if mesh.face_materials.is_empty() {
                    "its"
                } else {
                    "some of its"
                }
            ),
        ));
    }
    let first = materials.len() as u32;
    let file = path
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let path_traced = check.parsed.file.render.integrator == Integrator::Path;
    for m in &mesh.materials {
        let e = m.emission;
        if !(e.is_finite() && e.min_element() >= 0.0 && e.max_element() as f64 <= MAX_RADIOMETRIC) {
            return Err(check.err(
                field,
                format!(
                    "{}: material {:?} emits ({}, {}, {}) (its library's `Ke`): an emitted \
                     radiance is finite, non-negative and at most {MAX_RADIOMETRIC:e}",
                    path.display(),
                    m.name,
                    num(e.x as f64),
                    num(e.y as f64),
                    num(e.z as f64)
                ),
            ));
        }
        let lobe = m.specular.max_element() > 0.0;
        let material = Material {
            name: format!("{file}:{}", m.name),
            model: match (m.conductor_roughness, lobe) {
                (Some(_), _) => layout::MODEL_ROUGH_CONDUCTOR,
                (None, true) => layout::MODEL_BLINN_PHONG,
                (None, false) => layout::MODEL_LAMBERT,
            },
            diffuse: m.diffuse,
            specular: m.specular,
            shininess: m.conductor_roughness.map_or(m.shininess, ggx_alpha),
            mirror: m.mirror,
            emission: m.emission,
            ior: 1.0,
            diffuse_texture: m.diffuse_texture.clone(),
        };
        materials.push(match m.ior {
            // Glass (`illum` 4, 6, 7) is the path tracer's; Whitted's integrator keeps its
            // lobes. Its `Tf` and `d` are not read: a clear dielectric.
            Some(ior) if path_traced && m.emission.max_element() <= 0.0 => Material {
                model: layout::MODEL_DIELECTRIC,
                diffuse: Vec3::ZERO,
                specular: Vec3::ZERO,
                mirror: Vec3::ZERO,
                ior,
                diffuse_texture: None,
                ..material
            },
            _ => material,
        });
    }
    for id in &mut mesh.face_materials {
        *id += first;
    }
    Ok(mesh.face_materials[0])
}

/// Corner and two non-parallel, non-zero edges of a quad or an area light.
fn parallelogram(
    check: &Checker,
    prefix: &str,
    corner: Option<F3>,
    edge_u: Option<F3>,
    edge_v: Option<F3>,
    kind: &str,
) -> Result<(Vec3, Vec3, Vec3)> {
    let at = |f: &str| format!("{prefix}.{f}");
    let corner = check.point(&at("corner"), check.require(&at("corner"), corner, kind)?)?;
    let u = check.nonzero(&at("edge_u"), check.require(&at("edge_u"), edge_u, kind)?)?;
    let v = check.nonzero(&at("edge_v"), check.require(&at("edge_v"), edge_v, kind)?)?;
    if u.normalize().cross(v.normalize()).length() < 1e-9 {
        return Err(check.err(
            &at("edge_v"),
            "is parallel to edge_u: the parallelogram has no area",
        ));
    }
    Ok((corner.as_vec3(), u.as_vec3(), v.as_vec3()))
}

/// A light's validator, by its type.
type LightValidator = fn(&Checker, &str, &LightEntry) -> Result<Light>;

fn validate_lights(check: &Checker, file: &SceneFile) -> Result<Vec<Light>> {
    let mut lights = Vec::new();
    for (i, l) in file.lights.iter().enumerate() {
        let prefix = format!("lights[{i}]");
        let (kind, validate): (_, LightValidator) = match l.kind {
            LightType::Point => ("point light", point_light),
            LightType::Directional => ("directional light", directional_light),
            LightType::Spot => ("spot light", spot_light),
            LightType::Area => ("area light", area_light),
            LightType::Environment => ("environment light", environment_light),
            LightType::Sun => ("sun", sun_light),
        };
        check.forbid(&prefix, kind, &foreign_light_fields(l))?;
        lights.push(validate(check, &prefix, l)?);
    }
    one_environment(check, file)?;
    Ok(lights)
}

/// At most one environment light (as in Mitsuba: two would be one with their sum), and none
/// beside a non-zero `render.background`, which it replaces for escaping rays.
fn one_environment(check: &Checker, file: &SceneFile) -> Result<()> {
    let mut environments = file
        .lights
        .iter()
        .enumerate()
        .filter(|(_, l)| l.kind == LightType::Environment)
        .map(|(i, _)| i);
    let Some(first) = environments.next() else {
        return Ok(());
    };
    if let Some(second) = environments.next() {
        return Err(check.err(
            &format!("lights[{second}].type"),
            format!("a second environment light (lights[{first}] is one): a scene has one"),
        ));
    }
    if file.render.background.0.iter().any(|&c| c != 0.0) {
        return Err(check.err(
            "render.background",
            format!(
                "is what escaping rays see where there is no environment light; lights[{first}] \
                 is one: set the background to 0 (the environment replaces it)"
            ),
        ));
    }
    Ok(())
}

/// The fields `l` gives that its type does not take, in the order a refusal names the first.
fn foreign_light_fields(l: &LightEntry) -> Vec<(&'static str, bool)> {
    let given = [
        ("position", l.position.is_some()),
        ("intensity", l.intensity.is_some()),
        ("direction", l.direction.is_some()),
        ("irradiance", l.irradiance.is_some()),
        ("corner", l.corner.is_some()),
        ("edge_u", l.edge_u.is_some()),
        ("edge_v", l.edge_v.is_some()),
        ("radiance", l.radiance.is_some()),
        ("samples", l.samples.is_some()),
        ("outer_angle", l.outer_angle.is_some()),
        ("inner_angle", l.inner_angle.is_some()),
        ("file", l.file.is_some()),
        ("scale", l.scale.is_some()),
        ("rotate", l.rotate.is_some()),
        ("angular_radius_deg", l.angular_radius_deg.is_some()),
    ];
    let own: &[&str] = match l.kind {
        LightType::Point => &["position", "intensity"],
        LightType::Directional => &["direction", "irradiance"],
        LightType::Spot => &[
            "position",
            "intensity",
            "direction",
            "outer_angle",
            "inner_angle",
        ],
        LightType::Area => &["corner", "edge_u", "edge_v", "radiance", "samples"],
        LightType::Environment => &["radiance", "file", "scale", "rotate", "samples"],
        LightType::Sun => &["direction", "irradiance", "angular_radius_deg", "samples"],
    };
    given
        .into_iter()
        .filter(|(name, _)| !own.contains(name))
        .collect()
}

/// A point light: its position and intensity (W/sr).
fn point_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    Ok(Light::Point {
        position: check
            .point(
                &at("position"),
                check.require(&at("position"), l.position, "point light")?,
            )?
            .as_vec3(),
        intensity: check.radiometric(
            &at("intensity"),
            check.require(&at("intensity"), l.intensity, "point light")?,
        )?,
    })
}

/// A directional light: the direction it shines along and its irradiance.
fn directional_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    let direction = check.nonzero(
        &at("direction"),
        check.require(&at("direction"), l.direction, "directional light")?,
    )?;
    Ok(Light::Directional {
        direction: direction.normalize().as_vec3(),
        irradiance: check.radiometric(
            &at("irradiance"),
            check.require(&at("irradiance"), l.irradiance, "directional light")?,
        )?,
    })
}

/// A spot light: a point light whose intensity falls off between `inner_angle` and `outer_angle` about its direction.
fn spot_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    let direction = check.nonzero(
        &at("direction"),
        check.require(&at("direction"), l.direction, "spot light")?,
    )?;
    let outer = check.finite(&at("outer_angle"), l.outer_angle.unwrap_or(45.0))?;
    if !(outer > 0.0 && outer <= 90.0) {
        return Err(check.err(
            &at("outer_angle"),
            format!("lies in (0, 90] degrees, got {}", num(outer)),
        ));
    }
    let inner = check.finite(&at("inner_angle"), l.inner_angle.unwrap_or(0.0))?;
    if !(0.0..outer).contains(&inner) {
        return Err(check.err(
            &at("inner_angle"),
            format!(
                "lies in [0, outer_angle = {}) degrees, got {}",
                num(outer),
                num(inner)
            ),
        ));
    }
    Ok(Light::Spot {
        position: check
            .point(
                &at("position"),
                check.require(&at("position"), l.position, "spot light")?,
            )?
            .as_vec3(),
        direction: direction.normalize().as_vec3(),
        intensity: check.radiometric(
            &at("intensity"),
            check.require(&at("intensity"), l.intensity, "spot light")?,
        )?,
        inner_deg: inner as f32,
        outer_deg: outer as f32,
    })
}

/// An area light: a parallelogram of uniform radiance, sampled `samples` times a shading point.
fn area_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    let (corner, edge_u, edge_v) =
        parallelogram(check, prefix, l.corner, l.edge_u, l.edge_v, "area light")?;
    Ok(Light::Area {
        corner,
        edge_u,
        edge_v,
        radiance: check.radiometric(
            &at("radiance"),
            check.require(&at("radiance"), l.radiance, "area light")?,
        )?,
        samples: check.integer(&at("samples"), l.samples.unwrap_or(1), 1, MAX_LIGHT_SAMPLES)?,
    })
}

/// An environment light: a constant `radiance`, or a map `file` (relative to the scene file)
/// times `scale`, turned `rotate` degrees about +y.
fn environment_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    let samples = check.integer(&at("samples"), l.samples.unwrap_or(1), 1, MAX_LIGHT_SAMPLES)?;
    let Some(name) = &l.file else {
        for (field, given) in [("scale", l.scale.is_some()), ("rotate", l.rotate.is_some())] {
            if given {
                return Err(check.err(
                    &at(field),
                    "applies to an environment map `file`, and there is none",
                ));
            }
        }
        let radiance = check.require(
            &at("radiance"),
            l.radiance,
            "constant environment light (or give a map `file`)",
        )?;
        return Ok(Light::Environment {
            radiance: check.radiometric(&at("radiance"), radiance)?,
            map: None,
            rotate_deg: 0.0,
            samples,
        });
    };
    if l.radiance.is_some() {
        return Err(check.err(
            &at("radiance"),
            "does not apply to an environment map, whose texels give the radiance (use `scale`)",
        ));
    }
    let scale = check.positive(&at("scale"), l.scale.unwrap_or(1.0))?;
    let rotate = check.finite(&at("rotate"), l.rotate.unwrap_or(0.0))?;
    let folder = check
        .parsed
        .path
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let path = folder.join(name);
    let map = super::environment::EnvironmentMap::read(&path)
        .map_err(|e| check.err(&at("file"), format!("{}: {e}", path.display())))?;
    let (brightest, texel) = map
        .texels
        .iter()
        .enumerate()
        .map(|(i, t)| (t.iter().fold(0f64, |m, &c| m.max(c as f64)), i))
        .fold(
            (0f64, 0),
            |best, texel| if texel.0 > best.0 { texel } else { best },
        );
    let peak = brightest * scale;
    if peak > MAX_RADIOMETRIC {
        // The file's own texel when no scale raised it; the scale when it did.
        let field = match l.scale {
            Some(s) if s > 1.0 => at("scale"),
            _ => at("file"),
        };
        let width = map.width as usize;
        return Err(check.err(
            &field,
            format!(
                "{}: the texel at column {}, row {} is {} times scale {} = {} (over \
                 {MAX_RADIOMETRIC:e}): sums of samples would overflow the 32-bit floats of the \
                 render",
                path.display(),
                texel % width,
                texel / width,
                num(brightest),
                num(scale),
                num(peak)
            ),
        ));
    }
    Ok(Light::Environment {
        radiance: glam::Vec3::splat(scale as f32),
        map: Some(std::sync::Arc::new(map)),
        rotate_deg: rotate.rem_euclid(360.0) as f32,
        samples,
    })
}

/// Smallest and largest half-angle of a sun (degrees): below 1e-4 the cone's radiance
/// E / (pi sin^2 alpha) nears f32's range for bright suns; above 45 it is no longer a sun.
pub const SUN_ANGLE_RANGE: [f64; 2] = [1e-4, 45.0];

/// A sun: the direction its light travels, its irradiance and its angular radius.
fn sun_light(check: &Checker, prefix: &str, l: &LightEntry) -> Result<Light> {
    let at = |f: &str| format!("{prefix}.{f}");
    let direction = check.nonzero(
        &at("direction"),
        check.require(&at("direction"), l.direction, "sun")?,
    )?;
    let irradiance = check.radiometric(
        &at("irradiance"),
        check.require(&at("irradiance"), l.irradiance, "sun")?,
    )?;
    let alpha = check.finite(
        &at("angular_radius_deg"),
        l.angular_radius_deg.unwrap_or(0.2675),
    )?;
    let [low, high] = SUN_ANGLE_RANGE;
    if !(low..=high).contains(&alpha) {
        return Err(check.err(
            &at("angular_radius_deg"),
            format!("lies in [{low:e}, {high}] degrees, got {}", num(alpha)),
        ));
    }
    let radiance =
        irradiance.max_element() as f64 / (std::f64::consts::PI * alpha.to_radians().sin().powi(2));
    if radiance > MAX_RADIOMETRIC {
        return Err(check.err(
            &at("irradiance"),
            format!(
                "seen through a disc of {} degrees is a radiance of {} (over {MAX_RADIOMETRIC:e}): \
                 sums of samples would overflow the 32-bit floats of the render",
                num(alpha),
                num(radiance)
            ),
        ));
    }
    Ok(Light::Sun {
        direction: direction.normalize().as_vec3(),
        irradiance,
        angular_radius_deg: alpha,
        samples: check.integer(&at("samples"), l.samples.unwrap_or(1), 1, MAX_LIGHT_SAMPLES)?,
    })
}
