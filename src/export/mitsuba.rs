//! A scene as Mitsuba 3 XML (`chambre export --mitsuba OUT.xml`), for rendering the same scene
//! with Mitsuba: the subset both renderers share, mapped so that Mitsuba computes the same image
//! in expectation (only the noise differs), and everything else refused by name. The mapping and
//! its reasons are in `docs/mitsuba.md`; `tests/export.rs` renders exports with Mitsuba and
//! compares them with chambre's images.
//!
//! Meshes are written as binary PLY files beside the XML, as chambre loaded them (in world
//! space, with the normals it shades with, one file per material), and named by paths relative
//! to the XML, which Mitsuba resolves against the XML's folder.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use glam::{DVec3, Vec2, Vec3};

use super::files;
use crate::camera::{CameraSpec, Focus, FocusSurface, Movements};
use crate::error::{Error, Result};
use crate::layout::{MODEL_BLINN_PHONG, MODEL_DIELECTRIC, MODEL_PHONG, MODEL_ROUGH_CONDUCTOR};
use crate::named::named_enum;
use crate::output::{OutputTarget, Protected};
use crate::sampler::SamplerName;
use crate::scene::surface::PATCH_QUADS;
use crate::scene::texture::Wrap;
use crate::scene::{
    CurvedPrimitive, Integrator, Light, Scene, Shape, TriangleMesh, field_location,
};

named_enum! {
    /// What Mitsuba computes (`chambre export --integrator`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum MitsubaIntegrator {
        /// chambre's direct light: Mitsuba's `direct` (light samples only), or its `path` with
        /// `max_depth + 2` where a mirror bounces.
        #[default]
        Direct = "direct",
        /// Mitsuba's `depth`: camera rays only (the distance to the first hit).
        Depth = "depth",
        /// Mitsuba's path tracer with `max_depth + 2`, whatever the materials.
        Path = "path",
    }
}

/// How to export.
#[derive(Clone, Debug, Default)]
pub struct MitsubaOptions {
    /// What Mitsuba computes.
    pub integrator: MitsubaIntegrator,
    /// Write the nearest Mitsuba has where it has no match (each change then a note), instead
    /// of refusing.
    pub approximate: bool,
    /// The `--set` overrides the scene was loaded with (refusals of the fields they set point
    /// at the command line).
    pub overrides: Vec<String>,
    /// Whether an existing write-protected XML is refused or replaced (`--force`).
    pub protected: Protected,
}

/// A scene as Mitsuba 3 XML.
#[derive(Clone, Debug)]
pub struct MitsubaExport {
    /// The scene file.
    pub xml: String,
    /// The files it names, to be written beside it: (file name, contents).
    pub files: Vec<(String, Vec<u8>)>,
    /// What a user should know, one sentence each: every approximation, and where Mitsuba's
    /// integrator computes more than chambre's.
    pub notes: Vec<String>,
    /// The Mitsuba integrator written.
    pub integrator: &'static str,
    /// The Mitsuba sampler written.
    pub sampler: &'static str,
}

/// An infinite plane is written as a square this many times the scene's size on a side's half,
/// centred under the camera: a ray along it misses the square only within
/// atan(1 / 1000) = 0.06 degrees of its horizon.
const PLANE_HALF_SIZE: f64 = 1e3;
/// The sensor's near clipping distance, in the scene's sizes: chambre has none.
const NEAR_CLIP: f64 = 1e-6;
/// The sensor's far clipping distance, in the scene's sizes: beyond the planes' squares.
const FAR_CLIP: f64 = 1e4;
/// A thin lens focused at infinity focuses this many scene sizes away: its rays from one film
/// point are then parallel in single precision, and their squared lengths still finite.
const INFINITE_FOCUS: f64 = 1e9;
/// Side of a spot light's falloff table, in texels.
const SPOT_TABLE_SIZE: u32 = 512;
/// Widest spot cone the table spans finely enough (it covers tan(outer) across its side).
const SPOT_TABLE_MAX_DEG: f32 = 85.0;
/// Samples per texel side from which a resampled environment map counts as faithful: Mitsuba's
/// radiance differs from chambre's on under 1/16 of the longitudes and 1/16 of the
/// colatitudes, and there only by a blend of two neighbouring texels (docs/lights.md).
pub const ENVMAP_FAITHFUL_FACTOR: u32 = 16;

/// Quads around and across an ellipsoid or torus written as a mesh (`--approximate`).
const CURVED_MESH_GRID: [u32; 2] = [256, 128];

/// The scene as Mitsuba 3 XML; files it names are called `{stem}-…`. Refuses, naming each
/// field and where it stands in the scene file, what Mitsuba cannot express (unless
/// `options.approximate`).
pub fn to_mitsuba(scene: &Scene, stem: &str, options: &MitsubaOptions) -> Result<MitsubaExport> {
    let mut export = Exporter::new(scene, stem, options);
    let sensor = export.sensor();
    export.shapes();
    export.lights();
    let (integrator_name, integrator) = export.integrator();
    let surroundings = export.surroundings(integrator_name);
    if !export.refusals.is_empty() {
        let refusals = export
            .refusals
            .iter()
            .map(|(field, message)| format!("{}: {message}", export.place(field)))
            .collect();
        return Err(Error::Unsupported {
            format: "Mitsuba 3".into(),
            refusals,
        });
    }
    let mut xml = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = writeln!(
        xml,
        "<!-- {} as Mitsuba 3 XML by chambre {} (docs/mitsuba.md) -->",
        comment(&scene.source.display().to_string()),
        env!("CARGO_PKG_VERSION")
    );
    xml += "<scene version=\"3.0.0\">\n";
    for part in [
        &integrator,
        &sensor.xml,
        &export.bsdfs,
        &export.shapes,
        &export.emitters,
        &surroundings,
    ] {
        xml += part;
    }
    xml += "</scene>\n";
    Ok(MitsubaExport {
        xml,
        files: export.files,
        notes: export.notes,
        integrator: integrator_name,
        sampler: sensor.sampler,
    })
}

/// [`to_mitsuba`] written to `out` (XML), with its files beside it, each atomically and the
/// XML last, so that an XML on disk never names a file that is not there.
pub fn write_mitsuba(scene: &Scene, out: &Path, options: &MitsubaOptions) -> Result<MitsubaExport> {
    OutputTarget::prepare_beside_with(out, options.protected)?;
    let stem = out
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let export = to_mitsuba(scene, &stem, options)?;
    let dir = out.parent().unwrap_or(Path::new(""));
    for (name, bytes) in &export.files {
        OutputTarget::write_beside(&dir.join(name), bytes)?;
    }
    OutputTarget::write_beside(out, export.xml.as_bytes())?;
    Ok(export)
}

/// The sensor's XML and the sampler it names.
struct Sensor {
    xml: String,
    sampler: &'static str,
}

/// The export under way: the XML's sections, the files, and what was noted or refused.
struct Exporter<'a> {
    scene: &'a Scene,
    options: &'a MitsubaOptions,
    stem: &'a str,
    /// The diagonal of everything bounded (shapes but planes, lights, the camera).
    extent: f64,
    /// Shared BSDFs, each defined once with an id.
    bsdfs: String,
    /// Ids of the materials defined in `bsdfs`.
    bsdf_ids: BTreeMap<u32, String>,
    shapes: String,
    emitters: String,
    files: Vec<(String, Vec<u8>)>,
    notes: Vec<String>,
    /// (field, why): what Mitsuba cannot express.
    refusals: Vec<(String, String)>,
    /// Whether a material that a shape uses reflects as a mirror.
    mirrors: bool,
    /// Light samples per shading point in chambre: each area light's `samples`, one for each
    /// punctual light and each emitting triangle.
    light_samples: u64,
    /// Whether the scene has a point, spot or directional light.
    punctual_lights: bool,
}

impl<'a> Exporter<'a> {
    fn new(scene: &'a Scene, stem: &'a str, options: &'a MitsubaOptions) -> Self {
        Exporter {
            scene,
            options,
            stem,
            extent: scene_extent(scene),
            bsdfs: String::new(),
            bsdf_ids: BTreeMap::new(),
            shapes: String::new(),
            emitters: String::new(),
            files: Vec::new(),
            notes: Vec::new(),
            refusals: Vec::new(),
            mirrors: false,
            light_samples: 0,
            punctual_lights: false,
        }
    }

    /// Where `field` stands: `file:line:column: field `…`` for a TOML scene.
    fn place(&self, field: &str) -> String {
        match field_location(&self.scene.source, &self.options.overrides, field) {
            Some(location) => location.to_string(),
            None => format!(
                "{}: field `{field}` (of the scene chambre reads it as)",
                self.scene.source.display()
            ),
        }
    }

    /// Mitsuba lacks `what` (at `field`): refused, or with `--approximate` written as
    /// `nearest` and noted.
    fn lossy(&mut self, field: &str, what: &str, nearest: &str) {
        if self.options.approximate {
            self.notes
                .push(format!("{field}: {what}; written as {nearest}"));
        } else {
            self.refusals.push((
                field.to_string(),
                format!("{what} (--approximate writes {nearest})"),
            ));
        }
    }

    /// The camera: Mitsuba's `perspective` (pinhole), `thinlens` or `orthographic`, with its
    /// sampler and film.
    fn sensor(&mut self) -> Sensor {
        let camera = &self.scene.camera;
        self.movements(camera);
        let lens = !camera.is_pinhole();
        if camera.lens.is_some() {
            self.lossy(
                "camera.lens",
                "a real lens's prescription: Mitsuba's cameras are a pinhole or a thin lens",
                "a thin lens of its focal length and f-number at its rear principal point",
            );
        }
        if lens && camera.aperture_blades >= 3 {
            self.lossy(
                "camera.aperture_blades",
                "a polygonal aperture: Mitsuba's thin lens is round",
                "a round aperture of the same f-number",
            );
        }
        if lens && camera.focus_surface != FocusSurface::Plane {
            self.lossy(
                "camera.focus_surface",
                "a curved surface of sharp focus: Mitsuba's thin lens focuses on a plane",
                "the plane at focus_distance",
            );
        }
        // The framing of the camera without movements (refused above when it has any).
        let straight = CameraSpec {
            movements: Movements::default(),
            ..camera.clone()
        };
        let mut xml = String::new();
        let kind = match (camera.is_orthographic(), lens) {
            (true, _) => "orthographic",
            (false, true) => "thinlens",
            (false, false) => "perspective",
        };
        let _ = writeln!(xml, "  <sensor type=\"{kind}\">");
        if !camera.is_orthographic() {
            let fov = straight.field_of_view_deg()[0];
            let _ = writeln!(xml, "    <string name=\"fov_axis\" value=\"x\"/>");
            let _ = writeln!(xml, "    <float name=\"fov\" value=\"{fov}\"/>");
        }
        if lens {
            let radius = camera.lens_radius_mm() * camera.units_per_mm;
            let _ = writeln!(
                xml,
                "    <float name=\"aperture_radius\" value=\"{radius}\"/>"
            );
            let focus = self.focus_distance(camera);
            let _ = writeln!(
                xml,
                "    <float name=\"focus_distance\" value=\"{focus}\"/>"
            );
        }
        let (near, far) = (NEAR_CLIP * self.extent, FAR_CLIP * self.extent);
        let _ = writeln!(xml, "    <float name=\"near_clip\" value=\"{near}\"/>");
        let _ = writeln!(xml, "    <float name=\"far_clip\" value=\"{far}\"/>");
        let _ = writeln!(xml, "    <transform name=\"to_world\">");
        if camera.is_orthographic() {
            let _ = writeln!(xml, "      {}", self.orthographic_window_scale(camera));
        }
        let _ = writeln!(
            xml,
            "      <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    </transform>",
            d3(camera.position),
            d3(camera.look_at),
            d3(camera.up)
        );
        let sampler = self.sampler_name();
        let render = &self.scene.render;
        let _ = writeln!(
            xml,
            "    <sampler type=\"{sampler}\">\n      <integer name=\"sample_count\" value=\"{}\"/>\n      <integer name=\"seed\" value=\"{}\"/>\n    </sampler>",
            render.spp, render.seed
        );
        if render.adaptive.is_some() {
            self.lossy(
                "render.noise_target",
                "adaptive sampling: Mitsuba samples every pixel alike",
                "spp samples in every pixel",
            );
        }
        let _ = writeln!(xml, "    <film type=\"hdrfilm\">");
        let _ = writeln!(
            xml,
            "      <integer name=\"width\" value=\"{}\"/>\n      <integer name=\"height\" value=\"{}\"/>",
            render.width, render.height
        );
        let [x0, x1, y0, y1] = render.crop;
        if [x0, x1, y0, y1] != [0, render.width, 0, render.height] {
            let _ = writeln!(
                xml,
                "      <integer name=\"crop_offset_x\" value=\"{x0}\"/>\n      <integer name=\"crop_offset_y\" value=\"{y0}\"/>\n      <integer name=\"crop_width\" value=\"{}\"/>\n      <integer name=\"crop_height\" value=\"{}\"/>",
                x1 - x0,
                y1 - y0
            );
        }
        // chambre's pixel is a box: each sample counts in the pixel it falls in, equally.
        let _ = writeln!(xml, "      <rfilter type=\"box\"/>");
        let _ = writeln!(xml, "      <string name=\"pixel_format\" value=\"rgb\"/>");
        let _ = writeln!(xml, "    </film>\n  </sensor>");
        Sensor { xml, sampler }
    }

    /// The scale that makes Mitsuba's orthographic window chambre's: Mitsuba's spans x in
    /// [-1, 1] and y in [-1/a, 1/a] before `to_world`, `a` the image's aspect, so the half
    /// width scales x and the half height times `a` scales y (the same number when the window
    /// has the image's aspect, as chambre checks it does). Its rays start at the near clip
    /// plane, `near_clip` in front of chambre's window: nothing is that close.
    fn orthographic_window_scale(&self, camera: &CameraSpec) -> String {
        let [w, h] = camera.window();
        let render = &self.scene.render;
        let aspect = render.width as f64 / render.height as f64;
        format!("<scale x=\"{}\" y=\"{}\"/>", 0.5 * w, 0.5 * h * aspect)
    }

    /// Refuses every film and lens movement by its field (a tilt solved from `focus_points`
    /// by that field).
    fn movements(&mut self, camera: &CameraSpec) {
        let m = camera.movements;
        let solved = matches!(camera.focus, Focus::Points(_));
        if solved && (m.lens_tilt != 0.0 || m.lens_swing != 0.0) {
            self.lossy(
                "camera.focus_points",
                &format!(
                    "they solve a lens tilt of {:.3} degrees and swing of {:.3} degrees: Mitsuba's \
                     thin lens has no movements",
                    m.lens_tilt, m.lens_swing
                ),
                "the untilted lens at the same film distance",
            );
        }
        let moved = [
            ("film_tilt", m.film_tilt != 0.0),
            ("film_swing", m.film_swing != 0.0),
            ("film_shift", m.film_shift != [0.0; 2]),
            ("lens_tilt", !solved && m.lens_tilt != 0.0),
            ("lens_swing", !solved && m.lens_swing != 0.0),
            ("lens_shift", m.lens_shift != [0.0; 2]),
        ];
        for (name, _) in moved.iter().filter(|(_, moved)| *moved) {
            self.lossy(
                &format!("camera.{name}"),
                &format!(
                    "a {}: Mitsuba's cameras have no film or lens movements",
                    name.replace('_', " ")
                ),
                "the camera without it",
            );
        }
    }

    /// The distance (scene units, along the optical axis) of the plane the lens focuses on.
    fn focus_distance(&self, camera: &CameraSpec) -> f64 {
        if let Focus::Distance(Some(d)) = camera.focus {
            return d;
        }
        // From the film distance s_i: 1/f = 1/s_i + 1/s_o.
        let (f, s_i) = (camera.focal_length_mm, camera.film_distance_mm);
        if s_i > f {
            f * s_i / (s_i - f) * camera.units_per_mm
        } else {
            INFINITE_FOCUS * self.extent
        }
    }

    /// The Mitsuba sampler nearest to the pixel pattern that takes exactly `spp` samples
    /// (Mitsuba rounds a count its pattern cannot take): `independent` for `random`;
    /// `ldsampler` (a scrambled (0, 2)-sequence) for `sobol` at a power of four; else the
    /// jittered grid `stratified` at a square count, `multijitter` where its near-square grid
    /// holds the count, and `independent` otherwise. Only the noise depends on it.
    fn sampler_name(&self) -> &'static str {
        let spp = self.scene.render.spp;
        let root = (spp as f64).sqrt().floor() as u32;
        let square = root * root == spp;
        let multijitter = spp.div_ceil(root) * root == spp;
        let power_of_four = spp.is_power_of_two() && spp.trailing_zeros().is_multiple_of(2);
        match self.scene.render.pixel_sampler {
            SamplerName::Random => "independent",
            SamplerName::Sobol if power_of_four => "ldsampler",
            _ if square => "stratified",
            _ if multijitter => "multijitter",
            _ => "independent",
        }
    }

    /// Every shape, moved to where it stands when the shutter opens.
    fn shapes(&mut self) {
        for (i, shape) in self.scene.shapes.iter().enumerate() {
            let offset = self.motion_offset(i);
            match shape {
                Shape::Sphere {
                    center,
                    radius,
                    material,
                } => {
                    let bsdf = self.bsdf(*material, i);
                    let placement = match self.textured(*material) {
                        // Mitsuba's sphere has its pole on its z axis and its longitude from x
                        // towards y: turned so that they are chambre's (pole +y, longitude
                        // from +x towards -z), the same texture coordinates.
                        true => format!(
                            "    <transform name=\"to_world\">\n      <matrix value=\"{}\"/>\n    </transform>\n",
                            matrix([
                                DVec3::X * *radius as f64,
                                DVec3::NEG_Z * *radius as f64,
                                DVec3::Y * *radius as f64,
                                (*center + offset).as_dvec3(),
                            ])
                        ),
                        false => format!(
                            "    <point name=\"center\" value=\"{}\"/>\n    <float name=\"radius\" value=\"{radius}\"/>\n",
                            f3(*center + offset)
                        ),
                    };
                    let _ = writeln!(
                        self.shapes,
                        "  <shape type=\"sphere\">\n{placement}{bsdf}  </shape>"
                    );
                }
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    material,
                } => {
                    let bsdf = self.bsdf(*material, i);
                    let corner = *corner + offset;
                    // Mitsuba's rectangle has v = 0 on its corner's side, chambre's quad on the
                    // far side: a textured one is placed from the far edge (its two-sided BSDF
                    // does not see the normal this turns).
                    self.shapes += &match self.textured(*material) {
                        true => rectangle(corner + *edge_v, *edge_u, -*edge_v, &bsdf),
                        false => rectangle(corner, *edge_u, *edge_v, &bsdf),
                    };
                }
                Shape::Plane {
                    point,
                    normal,
                    material,
                } => {
                    let bsdf = self.bsdf(*material, i);
                    self.plane(*point, *normal, &bsdf);
                }
                Shape::Curved {
                    primitive,
                    orientation,
                    material,
                } => self.curved(i, primitive, *orientation, *material, offset),
                Shape::Mesh { mesh, material } => self.mesh(i, mesh, *material, offset),
            }
        }
    }

    /// Where shape `i` stands: its velocity times the mid-shutter time; refused when it moves
    /// while the shutter is open (Mitsuba's shapes stand still).
    fn motion_offset(&mut self, i: usize) -> Vec3 {
        let velocity = self.scene.velocities.get(i).copied().unwrap_or(Vec3::ZERO);
        let [open, close] = self.scene.camera.shutter;
        if velocity != Vec3::ZERO && close > open {
            self.lossy(
                &format!("shapes[{i}].velocity"),
                "it moves while the shutter is open: Mitsuba's shapes stand still (no motion blur)",
                "the shape where it stands mid-shutter",
            );
        }
        velocity * (0.5 * (open + close)) as f32
    }

    /// An infinite plane as a square of `PLANE_HALF_SIZE` scene sizes on a side's half,
    /// centred where the camera stands above it.
    fn plane(&mut self, point: Vec3, normal: Vec3, bsdf: &str) {
        let n = normal.as_dvec3().normalize();
        let camera = self.scene.camera.position;
        let center = camera - n * (camera - point.as_dvec3()).dot(n);
        let (a, _) = n.any_orthonormal_pair();
        let b = n.cross(a);
        let half = PLANE_HALF_SIZE * self.extent;
        let _ = writeln!(
            self.shapes,
            "  <!-- an infinite plane: a square {half} on a side's half, centred under the camera -->\n  <shape type=\"rectangle\">\n    <transform name=\"to_world\">\n      <matrix value=\"{}\"/>\n    </transform>\n{bsdf}  </shape>",
            matrix([a * half, b * half, n, center])
        );
    }

    /// A cylinder as Mitsuba's (open at both ends, as chambre's); an ellipsoid or torus, which
    /// Mitsuba has no shape for, refused (or a mesh of it).
    fn curved(
        &mut self,
        i: usize,
        primitive: &CurvedPrimitive,
        orientation: glam::Quat,
        material: u32,
        offset: Vec3,
    ) {
        // Its material is mapped (or refused) whether or not the shape is.
        let bsdf = self.bsdf(material, i);
        match *primitive {
            CurvedPrimitive::Cylinder {
                base,
                radius,
                height,
            } => {
                let p0 = base + offset;
                let p1 = p0 + orientation * Vec3::Y * height;
                let _ = writeln!(
                    self.shapes,
                    "  <shape type=\"cylinder\">\n    <point name=\"p0\" value=\"{}\"/>\n    <point name=\"p1\" value=\"{}\"/>\n    <float name=\"radius\" value=\"{radius}\"/>\n{bsdf}  </shape>",
                    f3(p0),
                    f3(p1)
                );
            }
            CurvedPrimitive::Ellipsoid { .. } | CurvedPrimitive::Torus { .. } => {
                let kind = match primitive {
                    CurvedPrimitive::Torus { .. } => "a torus",
                    _ => "an ellipsoid",
                };
                let [around, across] = CURVED_MESH_GRID;
                self.lossy(
                    &format!("shapes[{i}].type"),
                    &format!("{kind}: Mitsuba has no such shape"),
                    &format!("a mesh of {around} x {across} quads with the surface's normals"),
                );
                let surface = self.scene.surfaces.iter().find(|s| s.shape == i);
                if let (true, Some(surface)) = (self.options.approximate, surface) {
                    let mesh = surface.surface.mesh_of(CURVED_MESH_GRID, PATCH_QUADS);
                    self.mesh(i, &mesh, material, offset);
                }
            }
        }
    }

    /// A mesh as one PLY file per material its triangles use (Mitsuba gives a shape one BSDF),
    /// in world space with chambre's normals: the vertex normals it interpolates, or none
    /// (`face_normals`) where it shades flat and on emitters, whose front is their winding's.
    fn mesh(&mut self, i: usize, mesh: &TriangleMesh, material: u32, offset: Vec3) {
        let mut groups: BTreeMap<u32, Vec<[u32; 3]>> = BTreeMap::new();
        for (f, t) in mesh.triangles.iter().enumerate() {
            let m = mesh.face_materials.get(f).copied().unwrap_or(material);
            groups.entry(m).or_default().push(*t);
        }
        let several = groups.len() > 1;
        for (k, (m, triangles)) in groups.into_iter().enumerate() {
            let name = match several {
                true => format!("{}-shape{i}-{k}.ply", self.stem),
                false => format!("{}-shape{i}.ply", self.stem),
            };
            let emission = self.scene.materials[m as usize].emission;
            let emits = emission.max_element() > 0.0;
            let textured = self.scene.materials[m as usize].diffuse_texture.is_some();
            let (positions, normals, texcoords, triangles) = compact(
                mesh,
                &triangles,
                offset,
                !emits && mesh.normals.is_some(),
                textured,
            );
            let comment = format!(
                "chambre export: shapes[{i}] of {}, material `{}`",
                self.scene.source.display(),
                self.scene.materials[m as usize].name
            );
            let inside = match emits {
                true => {
                    self.light_samples += triangles.len() as u64;
                    // The path tracer lets an emitter reflect by its material too.
                    let surface = match self.scene.render.integrator {
                        Integrator::Path => self.reflecting_bsdf(m, i),
                        Integrator::Whitted => black_bsdf(),
                    };
                    surface + &area_emitter(emission, triangles.len() as u64)
                }
                false => self.bsdf(m, i),
            };
            self.files.push((
                name.clone(),
                files::ply(
                    &comment,
                    &positions,
                    normals.as_deref(),
                    texcoords.as_deref(),
                    &triangles,
                ),
            ));
            let _ = writeln!(
                self.shapes,
                "  <shape type=\"ply\">\n    <string name=\"filename\" value=\"{}\"/>\n    <boolean name=\"face_normals\" value=\"{}\"/>\n{inside}  </shape>",
                attribute(&name),
                normals.is_none()
            );
        }
    }

    /// The BSDF of material `k` for shape `shape`: a reference to its definition, written on
    /// first use. chambre's surfaces are two-sided (`twosided`); Lambert is `diffuse`, a
    /// perfect mirror `conductor` of material `none` (reflectance exactly its `mirror`), and
    /// both together a `blendbsdf` of the two, weighted so that each keeps its reflectance.
    fn bsdf(&mut self, k: u32, shape: usize) -> String {
        let m = &self.scene.materials[k as usize];
        let field = format!("shapes[{shape}].material");
        if m.emission.max_element() > 0.0 {
            self.refusals.push((
                field,
                format!(
                    "material `{}` emits, on a shape chambre shows but does not sample as a light \
                     (only emitting mesh triangles are)",
                    m.name
                ),
            ));
            return String::new();
        }
        self.reflecting_bsdf(k, shape)
    }

    /// [`Self::bsdf`] of a material whatever it emits: what it reflects.
    fn reflecting_bsdf(&mut self, k: u32, shape: usize) -> String {
        let m = &self.scene.materials[k as usize];
        let field = format!("shapes[{shape}].material");
        if m.mirror.max_element() > 0.0 {
            self.mirrors = true;
        }
        if let Some(id) = self.bsdf_ids.get(&k) {
            return format!("    <ref id=\"{id}\"/>\n");
        }
        let lobe = match m.model {
            MODEL_PHONG => Some("Phong"),
            MODEL_BLINN_PHONG => Some("Blinn-Phong"),
            _ => None,
        };
        if let Some(lobe) = lobe.filter(|_| m.specular.max_element() > 0.0) {
            let name = m.name.clone();
            self.lossy(
                &field,
                &format!("material `{name}` is {lobe}: Mitsuba has no {lobe} lobe"),
                "its diffuse (and mirror) part alone",
            );
        }
        let m = &self.scene.materials[k as usize];
        if m.model == MODEL_DIELECTRIC {
            // Mitsuba's dielectric tells the sides apart by the normal, as chambre's does.
            let id = format!("mat{k}");
            let _ = writeln!(
                self.bsdfs,
                "  <!-- materials: `{}` -->\n  <bsdf type=\"dielectric\" id=\"{id}\">\n    <float name=\"int_ior\" value=\"{}\"/>\n    <float name=\"ext_ior\" value=\"1\"/>\n  </bsdf>",
                comment(&m.name),
                m.ior
            );
            self.bsdf_ids.insert(k, id.clone());
            return format!("    <ref id=\"{id}\"/>\n");
        }
        if m.model == MODEL_ROUGH_CONDUCTOR {
            // The same lobe: GGX, Smith's separable shadowing, a Fresnel factor of 1.
            let id = format!("mat{k}");
            let _ = writeln!(
                self.bsdfs,
                "  <!-- materials: `{}` -->\n  <bsdf type=\"twosided\" id=\"{id}\">\n    <bsdf type=\"roughconductor\">\n      <string name=\"material\" value=\"none\"/>\n      <string name=\"distribution\" value=\"ggx\"/>\n      <float name=\"alpha\" value=\"{}\"/>\n      <rgb name=\"specular_reflectance\" value=\"{}\"/>\n    </bsdf>\n  </bsdf>",
                comment(&m.name),
                m.shininess,
                f3(m.specular)
            );
            self.bsdf_ids.insert(k, id.clone());
            return format!("    <ref id=\"{id}\"/>\n");
        }
        let (d, r) = (m.diffuse, m.mirror);
        let (max_d, max_r) = (d.max_element(), r.max_element());
        let textured = m.diffuse_texture.is_some();
        let inner = match (max_d > 0.0, max_r > 0.0) {
            _ if textured => self.textured_diffuse(k, shape),
            (_, false) => diffuse(d, "    "),
            (false, true) => conductor(r, "    "),
            (true, true) => {
                // f = (1 - w) f_diffuse + w f_mirror: each part divided by its weight. With this
                // w, both stay within [0, 1] whenever max(diffuse) + max(mirror) <= 1.
                let w = max_r / (max_d + max_r);
                format!(
                    "    <bsdf type=\"blendbsdf\">\n      <float name=\"weight\" value=\"{w}\"/>\n{}{}    </bsdf>\n",
                    diffuse(d / (1.0 - w), "      "),
                    conductor(r / w, "      ")
                )
            }
        };
        let id = format!("mat{k}");
        let _ = writeln!(
            self.bsdfs,
            "  <!-- materials: `{}` -->\n  <bsdf type=\"twosided\" id=\"{id}\">\n{inner}  </bsdf>",
            comment(&m.name)
        );
        self.bsdf_ids.insert(k, id.clone());
        format!("    <ref id=\"{id}\"/>\n")
    }

    /// Whether material `k` has a texture.
    fn textured(&self, k: u32) -> bool {
        self.scene.materials[k as usize].diffuse_texture.is_some()
    }

    /// The diffuse BSDF of textured material `k` (of shape `shape`): Mitsuba's `bitmap` of
    /// its texture, written as a PNG beside the XML (the same sRGB bytes), filtered bilinearly
    /// as chambre does. Mitsuba's `diffuse` has no factor to multiply a texture by: a grey
    /// factor k is a `blendbsdf` of weight k with black, a coloured one is lossy.
    fn textured_diffuse(&mut self, k: u32, shape: usize) -> String {
        let m = &self.scene.materials[k as usize];
        let Some(texture) = m.diffuse_texture.clone() else {
            return diffuse(m.diffuse, "    ");
        };
        let (name, factor) = (m.name.clone(), m.diffuse);
        let field = format!("shapes[{shape}].material");
        if m.mirror.max_element() > 0.0 {
            self.lossy(
                &field,
                &format!("material `{name}` has a texture and a mirror term"),
                "its textured diffuse part alone",
            );
        }
        if texture.wrap[0] != texture.wrap[1] {
            self.lossy(
                &field,
                &format!("material `{name}`'s texture wraps u and v differently: Mitsuba's bitmap has one mode"),
                "u's mode for both",
            );
        }
        if factor.max_element() - factor.min_element() > 0.0 {
            self.lossy(
                &field,
                &format!(
                    "material `{name}` multiplies its texture by a colour: Mitsuba's diffuse cannot"
                ),
                "the texture times the colour's largest channel",
            );
        }
        let file = format!("{}-texture{k}.png", self.stem);
        let mut png = Vec::new();
        let bytes: Vec<u8> = texture
            .texels
            .iter()
            .flat_map(|t| t.to_le_bytes())
            .collect();
        let image = image::RgbaImage::from_raw(texture.width, texture.height, bytes)
            .expect("a texture holds width x height texels");
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .expect("a PNG encodes in memory");
        self.files.push((file.clone(), png));
        let wrap = match texture.wrap[0] {
            Wrap::Repeat => "repeat",
            Wrap::Clamp => "clamp",
            Wrap::Mirror => "mirror",
        };
        let bitmap = format!(
            "<bsdf type=\"diffuse\">\n      <texture type=\"bitmap\" name=\"reflectance\">\n        <string name=\"filename\" value=\"{}\"/>\n        <string name=\"filter_type\" value=\"bilinear\"/>\n        <string name=\"wrap_mode\" value=\"{wrap}\"/>\n      </texture>\n    </bsdf>\n",
            attribute(&file)
        );
        match factor.max_element() {
            k if k >= 1.0 => format!("    {bitmap}"),
            k => format!(
                "    <bsdf type=\"blendbsdf\">\n      <float name=\"weight\" value=\"{k}\"/>\n{}      {bitmap}    </bsdf>\n",
                diffuse(Vec3::ZERO, "      ")
            ),
        }
    }

    /// Every light: point, directional and spot lights as Mitsuba's, area lights as emitting
    /// rectangles. Each is sampled in proportion to chambre's samples of it (`sampling_weight`).
    fn lights(&mut self) {
        for (i, light) in self.scene.lights.iter().enumerate() {
            self.punctual_lights |=
                !matches!(light, Light::Area { .. } | Light::Environment { .. });
            match *light {
                Light::Point {
                    position,
                    intensity,
                } => {
                    self.light_samples += 1;
                    let _ = writeln!(
                        self.emitters,
                        "  <emitter type=\"point\">\n    <point name=\"position\" value=\"{}\"/>\n    <rgb name=\"intensity\" value=\"{}\"/>\n    <float name=\"sampling_weight\" value=\"1\"/>\n  </emitter>",
                        f3(position),
                        f3(intensity)
                    );
                }
                Light::Directional {
                    direction,
                    irradiance,
                } => {
                    self.light_samples += 1;
                    let _ = writeln!(
                        self.emitters,
                        "  <emitter type=\"directional\">\n    <vector name=\"direction\" value=\"{}\"/>\n    <rgb name=\"irradiance\" value=\"{}\"/>\n    <float name=\"sampling_weight\" value=\"1\"/>\n  </emitter>",
                        f3(direction),
                        f3(irradiance)
                    );
                }
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    inner_deg,
                    outer_deg,
                } => {
                    self.light_samples += 1;
                    self.spot(i, position, direction, intensity, inner_deg, outer_deg);
                }
                Light::Area {
                    corner,
                    edge_u,
                    edge_v,
                    radiance,
                    samples,
                } => {
                    self.light_samples += samples as u64;
                    let inside = black_bsdf() + &area_emitter(radiance, samples as u64);
                    self.emitters += &rectangle(corner, edge_u, edge_v, &inside);
                }
                Light::Environment {
                    radiance,
                    ref map,
                    rotate_deg,
                    samples,
                } => {
                    self.light_samples += samples as u64;
                    self.environment(i, radiance, map.as_deref(), rotate_deg, samples);
                }
                Light::Sun {
                    direction,
                    irradiance,
                    samples,
                    ..
                } => {
                    self.light_samples += samples as u64;
                    self.sun(i, direction, irradiance, samples);
                }
            }
        }
    }

    /// A spot light. Mitsuba's falloff is linear in the angle, chambre's (KHR_lights_punctual's)
    /// the square of a ramp in the cosine: the cone is written with no falloff of its own
    /// (`beam_width` = `cutoff_angle` = the outer angle) and chambre's as a projected texture,
    /// a table over tan(angle) that Mitsuba interpolates bilinearly.
    fn spot(
        &mut self,
        i: usize,
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_deg: f32,
        outer_deg: f32,
    ) {
        let lookat = format!(
            "    <transform name=\"to_world\">\n      <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    </transform>",
            f3(position),
            f3(position + direction),
            f3(direction.any_orthonormal_vector())
        );
        let mut xml = format!(
            "  <emitter type=\"spot\">\n{lookat}\n    <rgb name=\"intensity\" value=\"{}\"/>\n    <float name=\"cutoff_angle\" value=\"{outer_deg}\"/>\n",
            f3(intensity)
        );
        if outer_deg > SPOT_TABLE_MAX_DEG {
            self.lossy(
                &format!("lights[{i}].outer_angle"),
                &format!(
                    "a spot cone wider than {SPOT_TABLE_MAX_DEG} degrees: its falloff table \
                     (over tan(angle)) would be too coarse near the axis"
                ),
                "Mitsuba's own falloff, linear in the angle from inner_angle to outer_angle",
            );
            let _ = writeln!(
                xml,
                "    <float name=\"beam_width\" value=\"{inner_deg}\"/>"
            );
        } else {
            let name = format!("{}-light{i}.pfm", self.stem);
            self.files
                .push((name.clone(), spot_table(inner_deg, outer_deg)));
            let _ = writeln!(
                xml,
                "    <float name=\"beam_width\" value=\"{outer_deg}\"/>\n    <texture type=\"bitmap\" name=\"texture\">\n      <string name=\"filename\" value=\"{}\"/>\n      <boolean name=\"raw\" value=\"true\"/>\n      <string name=\"wrap_mode\" value=\"clamp\"/>\n    </texture>",
                attribute(&name)
            );
        }
        let _ = writeln!(
            xml,
            "    <float name=\"sampling_weight\" value=\"1\"/>\n  </emitter>"
        );
        self.emitters += &xml;
    }

    /// The integrator and its XML. chambre's is Whitted's: at each hit the light of every
    /// light by shadow rays, and a perfect mirror's bounce up to `max_depth` times.
    fn integrator(&mut self) -> (&'static str, String) {
        let max_depth = self.scene.render.max_depth;
        // Mitsuba's depth counts the camera ray's hit as 0 and samples lights at depth d only
        // while d + 1 < max_depth: chambre's last vertex, after max_depth bounces, needs + 2;
        // Russian roulette from that depth on never starts.
        let path_with_roulette = |rr_depth: u64| {
            format!(
                "  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"{}\"/>\n    <integer name=\"rr_depth\" value=\"{rr_depth}\"/>\n  </integrator>\n",
                max_depth as u64 + 2
            )
        };
        let path = path_with_roulette(max_depth as u64 + 2);
        match self.options.integrator {
            MitsubaIntegrator::Depth => ("depth", "  <integrator type=\"depth\"/>\n".into()),
            // chambre's path tracer: the same depths, Russian roulette from the same vertex
            // (Mitsuba's depth d + 1 > rr_depth where chambre's vertex d >= rr_depth).
            _ if self.scene.render.integrator == Integrator::Path => (
                "path",
                path_with_roulette(self.scene.render.rr_depth as u64),
            ),
            MitsubaIntegrator::Path => ("path", path),
            MitsubaIntegrator::Direct if self.mirrors && max_depth > 0 => {
                self.notes.push(format!(
                    "a mirror bounces (render.max_depth = {max_depth}): written with Mitsuba's path \
                     tracer (max_depth = {}), which also bounces off diffuse surfaces: the image \
                     adds the indirect light chambre leaves out",
                    max_depth as u64 + 2
                ));
                ("path", path)
            }
            MitsubaIntegrator::Direct => {
                // Each shading point takes as many light samples as chambre's, each light
                // picked in proportion to its samples (`sampling_weight`); no BSDF samples, so
                // light is never counted twice. But Mitsuba's `direct` leaves a point, spot or
                // directional light's sample undivided by `emitter_samples` (its weight is 1
                // where a delta light's MIS weight would be): with one, n samples would count
                // it n times, so it takes one sample a hit, of a light picked as above.
                let samples = match self.punctual_lights {
                    true => 1,
                    false => self.light_samples.max(1),
                };
                if self.punctual_lights && self.light_samples > 1 {
                    self.notes.push(format!(
                        "Mitsuba's direct integrator takes one light sample a hit where chambre \
                         takes {}: with a point, spot or directional light more would count it \
                         several times (the same image, more noise)",
                        self.light_samples
                    ));
                }
                (
                    "direct",
                    format!(
                        "  <integrator type=\"direct\">\n    <integer name=\"emitter_samples\" value=\"{samples}\"/>\n    <integer name=\"bsdf_samples\" value=\"0\"/>\n  </integrator>\n"
                    ),
                )
            }
        }
    }

    /// An environment light: Mitsuba's `constant` of the same radiance, sampled in proportion
    /// to `samples`. A map is Mitsuba's `envmap` (and `scale`) of a bitmap written beside the
    /// XML that repeats each texel k x k times (`files::envmap_resampled`), so that Mitsuba's
    /// bilinear interpolation only blends neighbouring texels on strips 1/k of a texel wide at
    /// their edges. Where the map is too large for k >= `ENVMAP_FAITHFUL_FACTOR` within
    /// `files::ENVMAP_MAX_TEXELS`, the export is lossy (refused without `--approximate`).
    fn environment(
        &mut self,
        i: usize,
        radiance: Vec3,
        map: Option<&crate::scene::environment::EnvironmentMap>,
        rotate_deg: f32,
        samples: u32,
    ) {
        let weight = format!("    <float name=\"sampling_weight\" value=\"{samples}\"/>\n");
        let Some(map) = map else {
            let _ = writeln!(
                self.emitters,
                "  <emitter type=\"constant\">\n    <rgb name=\"radiance\" value=\"{}\"/>\n{weight}  </emitter>",
                f3(radiance)
            );
            return;
        };
        let field = format!("lights[{i}].file");
        let factor = files::envmap_factor(map.width, map.height);
        if factor < ENVMAP_FAITHFUL_FACTOR {
            self.lossy(
                &field,
                &format!(
                    "an environment map of {} x {} texels: Mitsuba's `envmap` interpolates \
                     bilinearly, and a bitmap of at most {} texels repeats each texel only \
                     {factor} x {factor} times (a faithful export needs {ENVMAP_FAITHFUL_FACTOR})",
                    map.width,
                    map.height,
                    files::ENVMAP_MAX_TEXELS
                ),
                "Mitsuba's envmap of that bitmap, blurred over 1/{factor} of each texel",
            );
            if !self.options.approximate {
                return;
            }
        }
        let (width, height, texels) =
            files::envmap_resampled(map.width, map.height, &map.texels, factor);
        let bytes = match files::exr_rgb(width, height, &texels) {
            Ok(bytes) => bytes,
            Err(e) => {
                self.refusals.push((field, e));
                return;
            }
        };
        let name = format!("{}-environment.exr", self.stem);
        self.files.push((name.clone(), bytes));
        let (sin, cos) = (rotate_deg as f64).to_radians().sin_cos();
        // Mitsuba's local direction at longitude phi is (sin phi, ., -cos phi), chambre's
        // (sin(phi + rotate), ., -cos(phi + rotate)): the turn about +y by rotate.
        let to_world = format!("{cos} 0 {} 0 0 1 0 0 {sin} 0 {cos} 0 0 0 0 1", -sin);
        let _ = writeln!(
            self.emitters,
            "  <emitter type=\"envmap\">\n    <string name=\"filename\" value=\"{}\"/>\n    <float name=\"scale\" value=\"{}\"/>\n    <transform name=\"to_world\">\n      <matrix value=\"{to_world}\"/>\n    </transform>\n{weight}  </emitter>",
            attribute(&name),
            radiance.x
        );
    }

    /// A sun: refused (with `--approximate`, Mitsuba's `directional` of the same irradiance,
    /// the limit of a vanishing disc).
    fn sun(&mut self, i: usize, direction: Vec3, irradiance: Vec3, samples: u32) {
        self.lossy(
            &format!("lights[{i}].type"),
            "a sun: Mitsuba 3 has no disc of uniform radiance at infinity",
            "a directional light of the same irradiance (the sun's limit as its disc vanishes)",
        );
        let _ = writeln!(
            self.emitters,
            "  <emitter type=\"directional\">\n    <vector name=\"direction\" value=\"{}\"/>\n    <rgb name=\"irradiance\" value=\"{}\"/>\n    <float name=\"sampling_weight\" value=\"{samples}\"/>\n  </emitter>",
            f3(direction),
            f3(irradiance)
        );
    }

    /// chambre's ambient term and background radiance. A depth image sees neither. Ambient
    /// light (diffuse x L_a at every hit, unshadowed) has no counterpart: a constant
    /// environment is shadowed. The background is what escaping rays see: Mitsuba's `constant`
    /// environment shows the same, and never lights a surface while light samples never pick
    /// it (`sampling_weight` 0, which needs a second emitter) and no BSDF sample is taken:
    /// under `direct` only.
    fn surroundings(&mut self, integrator: &str) -> String {
        if integrator == "depth" {
            return String::new();
        }
        let render = &self.scene.render;
        let (ambient, background) = (render.ambient, render.background);
        if ambient.max_element() > 0.0 {
            self.lossy(
                "render.ambient",
                "ambient light: Mitsuba has no ambient term (a constant environment would be \
                 shadowed, unlike chambre's diffuse x L_a at every hit)",
                "no ambient light",
            );
        }
        if background.max_element() <= 0.0 {
            return String::new();
        }
        // chambre's path tracer, like Mitsuba's, lights surfaces by the background through
        // their bounces; Whitted's mirrors only see it.
        if integrator != "direct" && render.integrator != Integrator::Path {
            self.lossy(
                "render.background",
                "a background seen but not lighting the scene: Mitsuba's path tracer lights \
                 diffuse surfaces by its environment through their bounces",
                "a constant environment of that radiance, which also lights the scene",
            );
        }
        let mut xml = format!(
            "  <!-- chambre's background: seen by escaping rays, never sampled as a light -->\n  <emitter type=\"constant\">\n    <rgb name=\"radiance\" value=\"{}\"/>\n    <float name=\"sampling_weight\" value=\"0\"/>\n  </emitter>\n",
            f3(background)
        );
        if self.emitters.is_empty() && !self.shapes.contains("type=\"area\"") {
            // Mitsuba samples a scene's only emitter whatever its weight.
            xml += "  <!-- a dark light, so that light samples never pick the environment -->\n  <emitter type=\"point\">\n    <point name=\"position\" value=\"0, 0, 0\"/>\n    <rgb name=\"intensity\" value=\"0, 0, 0\"/>\n  </emitter>\n";
        }
        xml
    }
}

/// The vertices of a mesh's triangles as a PLY file holds them: positions, normals and
/// texture coordinates when written, and the triangles indexing them.
type Compacted = (
    Vec<Vec3>,
    Option<Vec<Vec3>>,
    Option<Vec<Vec2>>,
    Vec<[u32; 3]>,
);

/// The vertices triangles `triangles` of `mesh` use, moved by `offset`, with their normals
/// when `normals` and their texture coordinates when `texcoords`, and the triangles indexing
/// them.
fn compact(
    mesh: &TriangleMesh,
    triangles: &[[u32; 3]],
    offset: Vec3,
    normals: bool,
    texcoords: bool,
) -> Compacted {
    let mut index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let mut kept = Vec::new();
    let out: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize] + offset);
                    kept.push(v);
                }
                index[v as usize]
            })
        })
        .collect();
    let normals = match (normals, &mesh.normals) {
        (true, Some(n)) => Some(kept.iter().map(|&v| n[v as usize]).collect()),
        _ => None,
    };
    let texcoords = match (texcoords, &mesh.texcoords) {
        (true, Some(t)) => Some(kept.iter().map(|&v| t[v as usize]).collect()),
        _ => None,
    };
    (positions, normals, texcoords, out)
}

/// A parallelogram as Mitsuba's `rectangle` ([-1, 1]² in z = 0, normal +z) placed by the
/// affine map whose columns are the half edges, the unit normal edge_u x edge_v and the centre.
fn rectangle(corner: Vec3, edge_u: Vec3, edge_v: Vec3, inside: &str) -> String {
    let (u, v) = (edge_u.as_dvec3(), edge_v.as_dvec3());
    let center = corner.as_dvec3() + 0.5 * (u + v);
    format!(
        "  <shape type=\"rectangle\">\n    <transform name=\"to_world\">\n      <matrix value=\"{}\"/>\n    </transform>\n{inside}  </shape>\n",
        matrix([0.5 * u, 0.5 * v, u.cross(v).normalize(), center])
    )
}

/// A black surface: Whitted's emitters reflect nothing.
fn black_bsdf() -> String {
    "    <bsdf type=\"diffuse\">\n      <rgb name=\"reflectance\" value=\"0, 0, 0\"/>\n    </bsdf>\n".into()
}

/// A one-sided area emitter of `radiance` (from the shape's front, as chambre's), picked by
/// light samples in proportion to `weight`.
fn area_emitter(radiance: Vec3, weight: u64) -> String {
    format!(
        "    <emitter type=\"area\">\n      <rgb name=\"radiance\" value=\"{}\"/>\n      <float name=\"sampling_weight\" value=\"{weight}\"/>\n    </emitter>\n",
        f3(radiance)
    )
}

fn diffuse(reflectance: Vec3, indent: &str) -> String {
    format!(
        "{indent}<bsdf type=\"diffuse\">\n{indent}  <rgb name=\"reflectance\" value=\"{}\"/>\n{indent}</bsdf>\n",
        f3(reflectance)
    )
}

fn conductor(reflectance: Vec3, indent: &str) -> String {
    format!(
        "{indent}<bsdf type=\"conductor\">\n{indent}  <string name=\"material\" value=\"none\"/>\n{indent}  <rgb name=\"specular_reflectance\" value=\"{}\"/>\n{indent}</bsdf>\n",
        f3(reflectance)
    )
}

/// chambre's spot falloff, saturate(cos * scale + offset)² (`scene::spot_falloff`), as a
/// `SPOT_TABLE_SIZE`² table over Mitsuba's projection of the cone: texel (u, v) is the
/// direction (2u − 1, 2v − 1) tan(outer) in x / z and y / z.
fn spot_table(inner_deg: f32, outer_deg: f32) -> Vec<u8> {
    let (scale, offset) = crate::scene::spot_falloff(inner_deg, outer_deg);
    let (scale, offset) = (scale as f64, offset as f64);
    let reach = (outer_deg as f64).to_radians().tan();
    let n = SPOT_TABLE_SIZE;
    files::pfm_gray(n, |column, row| {
        let at = |k: u32| (2.0 * (k as f64 + 0.5) / n as f64 - 1.0) * reach;
        let (x, y) = (at(column), at(row));
        let cos = 1.0 / (1.0 + x * x + y * y).sqrt();
        let cone = (cos * scale + offset).clamp(0.0, 1.0);
        (cone * cone) as f32
    })
}

/// The diagonal of the box around the camera, every bounded shape and every light (1 when
/// that box is a point).
fn scene_extent(scene: &Scene) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut add = |p: DVec3, r: f64| {
        lo = lo.min(p - r);
        hi = hi.max(p + r);
    };
    add(scene.camera.position, 0.0);
    for shape in &scene.shapes {
        match shape {
            Shape::Sphere { center, radius, .. } => add(center.as_dvec3(), *radius as f64),
            Shape::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => {
                for p in [
                    *corner,
                    *corner + *edge_u,
                    *corner + *edge_v,
                    *corner + *edge_u + *edge_v,
                ] {
                    add(p.as_dvec3(), 0.0);
                }
            }
            Shape::Plane { point, .. } => add(point.as_dvec3(), 0.0),
            Shape::Curved { primitive, .. } => match *primitive {
                CurvedPrimitive::Ellipsoid { center, radii } => {
                    add(center.as_dvec3(), radii.max_element() as f64)
                }
                CurvedPrimitive::Cylinder {
                    base,
                    radius,
                    height,
                } => add(base.as_dvec3(), (radius + height) as f64),
                CurvedPrimitive::Torus {
                    center,
                    major,
                    minor,
                } => add(center.as_dvec3(), (major + minor) as f64),
            },
            Shape::Mesh { mesh, .. } => {
                for p in &mesh.positions {
                    add(p.as_dvec3(), 0.0);
                }
            }
        }
    }
    for light in &scene.lights {
        match *light {
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                add(position.as_dvec3(), 0.0)
            }
            Light::Area {
                corner,
                edge_u,
                edge_v,
                ..
            } => {
                add(corner.as_dvec3(), 0.0);
                add((corner + edge_u + edge_v).as_dvec3(), 0.0);
            }
            Light::Directional { .. } | Light::Environment { .. } | Light::Sun { .. } => {}
        }
    }
    let diagonal = (hi - lo).length();
    if diagonal.is_finite() && diagonal > 0.0 {
        diagonal
    } else {
        1.0
    }
}

/// A 4 x 4 affine matrix, row by row, from its columns (three axes and the translation).
fn matrix([x, y, z, t]: [DVec3; 4]) -> String {
    format!(
        "{} {} {} {} {} {} {} {} {} {} {} {} 0 0 0 1",
        x.x, y.x, z.x, t.x, x.y, y.y, z.y, t.y, x.z, y.z, z.z, t.z
    )
}

fn f3(v: Vec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

fn d3(v: DVec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

/// `text` inside an XML attribute value.
fn attribute(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// `text` inside an XML comment, which may not hold `--`.
fn comment(text: &str) -> String {
    text.replace("--", "- -")
}
