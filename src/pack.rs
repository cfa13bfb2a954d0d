//! The packing stage: [`Scene`] -> [`FlatScene`], every array the kernels read (and the CPU
//! reference renders from): materials, lights, the camera and frame constants, the sample
//! table, and the geometry that `accel` builds.

use std::time::Duration;

use glam::{Quat, Vec3};
use obvhs::bvh2::Bvh2;

use crate::accel::cwbvh::{self, CwGeometry};
use crate::accel::traverse::Tracer;
use crate::accel::wide::WideBvh;
use std::sync::Arc;

use crate::accel::{
    Geometry, Motion, Primitives, VertexAttributes, build_geometry, intersect, widened_bounds,
};
use crate::layout::*;
use crate::math::sampling::strata_columns;
use crate::sampler::SampleTable;
use crate::scene::mesh::TriangleMesh;
use crate::scene::texture::Texture;
use crate::scene::{CurvedPrimitive, Integrator, Light, Scene, Shape, spot_falloff};

/// Everything the kernels (and the CPU reference) read, ready to upload.
pub struct FlatScene {
    /// obvhs BVH over `prims[..frame.plane_start]`; leaves index `prims` directly.
    pub bvh: Bvh2,
    /// The BVH's nodes as the GPU reads them.
    pub nodes: Vec<GpuBvhNode>,
    /// Bounded primitives in BVH order (area lights' quads among them), then the planes.
    pub prims: Vec<GpuPrimitive>,
    /// Vertex normals of smooth triangles, indexed by `GpuPrimitive::normals`.
    pub normals: Vec<GpuNormals>,
    /// Texture coordinates of textured triangles, at their normals' index (empty when none).
    pub texcoords: Vec<GpuTexCoords>,
    /// The scene's materials, then one emitter per area light.
    pub materials: Vec<GpuMaterial>,
    /// The textures the materials read (`GpuMaterial::texture`).
    pub textures: Vec<GpuTexture>,
    /// Every texture's texels, one after another.
    pub texels: Vec<u32>,
    /// The environment light's map and its sampling distribution
    /// (`scene::environment::EnvironmentMap::packed`); empty without a map.
    pub environment: Vec<f32>,
    /// The scene's lights in order, then one per emitting triangle.
    pub lights: Vec<GpuLight>,
    /// What the CPU path's light samples need of each of `lights`, computed once here rather
    /// than at every path vertex.
    pub light_shapes: Vec<LightShape>,
    /// The camera as the kernels see it; its aperture polygon's vertices are in `sample_table`.
    pub camera: GpuCamera,
    /// Per-render constants: image size, samples, depth, samplers, light sample counts.
    pub frame: GpuFrame,
    /// Precomputed sample patterns and aperture vertices (`sampler::SampleTable`).
    pub sample_table: Vec<[f32; 2]>,
    /// Longest root-to-leaf path (nodes); bounds the traversal stack.
    pub bvh_depth: usize,
    /// Expected loop iterations of one traversal (`accel::build::expected_traversal_iterations`),
    /// planes included.
    pub traversal_iterations: f32,
    /// Triangles of the scene's meshes.
    pub triangle_count: usize,
    /// Wall-clock time of the BVH build.
    pub build_time: Duration,
    /// The pixels to render: columns `crop[0]..crop[1]`, rows `crop[2]..crop[3]`.
    pub crop: [u32; 4],
    /// Adaptive sampling, when the scene asks for it (`render.noise_target`).
    pub adaptive: Option<crate::adaptive::AdaptiveSettings>,
    /// The scene's parametric surfaces with their primitives (one exact primitive, or a Bézier
    /// shape's mesh triangles), for the raster preview's Fermat reflections; the ray tracers
    /// see only the primitives.
    pub surfaces: Vec<FlatSurface>,
    /// Whether renders also sum the first hits' depth, normal and albedo (`render::Aovs`);
    /// an output choice (`chambre render --aov`), false unless set.
    pub aovs: bool,
    /// The compressed wide BVH the GPU traverses, made on first use (CPU renders never need
    /// it) and kept for every later GPU render or ray query of the scene.
    cwbvh: std::sync::OnceLock<Result<CwGeometry, String>>,
    /// The CPU's wide BVH (`accel::wide`), made from the CWBVH on first use.
    wide: std::sync::OnceLock<Result<WideBvh, String>>,
    /// The primitives whose materials emit, in `prims`' order (the path tracer's last bounce
    /// tests them one by one where they are few, `integrator::path`).
    pub emitters: Vec<u32>,
    /// A box around every one of `emitters` (lower and upper corners), widened so that a ray
    /// that misses it misses them all; none where one is unbounded.
    pub emitter_bounds: Option<[Vec3; 2]>,
}

/// An area light's shape as its samples see it, and its share of the samples when the path
/// tracer chooses one light a vertex: the same numbers the kernels compute at each sample
/// (`area_light_of` and `choose_light` in integrator.wgsl), by the same operations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightShape {
    /// The unit normal of its edges' cross product (a light of another kind: of its fields').
    pub normal: Vec3,
    /// Its area ([`GpuLight::area`]).
    pub area: f32,
    /// The samples a vertex takes of it on average where the vertex chooses one light by
    /// power: its samples times its share of the power (1 where the frame chooses none).
    pub chosen_samples: f32,
}

impl LightShape {
    fn of(light: &GpuLight, frame: &GpuFrame) -> LightShape {
        let cross = Vec3::from(light.p1).cross(Vec3::from(light.p2));
        let area = light.area();
        LightShape {
            normal: cross.normalize(),
            area,
            chosen_samples: frame.light_choice_probability(light.color, area)
                * light.samples as f32,
        }
    }
}

/// A parametric surface of the scene and its mesh's primitives in `FlatScene::prims`.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatSurface {
    /// The surface.
    pub surface: crate::scene::surface::Surface,
    /// The indices of its triangles in `FlatScene::prims` (BVH order).
    pub prims: Vec<u32>,
}

impl FlatScene {
    /// The scene's CWBVH (`accel::cwbvh::build`), built once; the error if the tree is refused.
    pub fn cwbvh(&self) -> Result<&CwGeometry, String> {
        self.cwbvh
            .get_or_init(|| cwbvh::build(self.primitives()))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The scene's wide BVH for the CPU (`accel::wide`), built once from the CWBVH.
    pub fn wide(&self) -> Result<&WideBvh, String> {
        self.tracer();
        self.wide
            .get()
            .expect("tracer() made it")
            .as_ref()
            .map_err(Clone::clone)
    }

    /// What the CPU path traverses: the wide BVH, built on first use, or the BVH2 where the
    /// scene has no CWBVH.
    pub fn tracer(&self) -> Tracer<'_> {
        let wide = self
            .wide
            .get_or_init(|| WideBvh::build(self.cwbvh()?, &self.prims, self.frame.motion_base));
        match wide {
            Ok(wide) => Tracer::Wide(wide),
            Err(_) => Tracer::Bvh2(self.primitives()),
        }
    }

    /// What a traversal reads.
    pub fn primitives(&self) -> Primitives<'_> {
        Primitives {
            bvh: &self.bvh,
            prims: &self.prims,
            plane_start: self.frame.plane_start,
            plane_count: self.frame.plane_count,
            motion_base: self.frame.motion_base,
            shutter: [
                self.camera.shutter_open,
                self.camera.shutter_open + self.camera.shutter_span,
            ],
        }
    }

    /// The `layout::FEATURE_*` bits this scene uses. A kernel built with these bits renders it
    /// exactly as the general kernel does: a feature left out is code the scene never runs.
    pub fn features(&self) -> u32 {
        let mut features = 0;
        let mut add = |present: bool, bit: u32| {
            if present {
                features |= bit;
            }
        };
        add(self.camera.lens_radius_mm > 0.0, FEATURE_LENS);
        add(
            self.materials
                .iter()
                .any(|m| m.mirror.iter().any(|&c| c > 0.0)),
            FEATURE_MIRRORS,
        );
        add(
            self.lights.iter().any(GpuLight::is_sampled),
            FEATURE_AREA_LIGHTS,
        );
        add(
            self.lights.iter().any(|l| !l.is_sampled()),
            FEATURE_PUNCTUAL_LIGHTS,
        );
        add(
            self.prims.iter().any(|p| p.kind == PRIM_TRIANGLE),
            FEATURE_TRIANGLES,
        );
        add(self.frame.plane_count > 0, FEATURE_PLANES);
        add(
            self.prims.iter().any(|p| p.kind >= PRIM_ELLIPSOID),
            FEATURE_CURVED,
        );
        add(self.frame.integrator == INTEGRATOR_PATH, FEATURE_PATH);
        features
    }
}

/// Packs `scene` for the kernels: builds the BVH, turns area lights into emitting quads and
/// emitting mesh triangles into lights, and precomputes the sample table. No AOVs
/// (`FlatScene::aovs` false) and no CWBVH until first asked for.
pub fn flatten(scene: &Scene) -> FlatScene {
    let (mut materials, textures, texels) = pack_materials(scene);
    let PackedShapes {
        mut bounded,
        planes,
        triangle_lights,
        mut velocities,
        shape_prims,
        triangle_count,
    } = pack_shapes(scene);
    let mut lights = pack_lights(scene, &mut materials, &mut bounded);
    lights.extend(triangle_lights);
    // Area lights' quads stand still.
    velocities.resize(bounded.len(), Vec3::ZERO);
    let camera = &scene.camera;
    let motion = Motion {
        velocities: if scene.velocities.is_empty() {
            Vec::new()
        } else {
            velocities
        },
        shutter: camera.shutter.map(|t| t as f32),
    };
    let geometry = build_geometry(bounded, planes, &motion);
    let surfaces = scene
        .surfaces
        .iter()
        .map(|s| FlatSurface {
            surface: s.surface.clone(),
            prims: shape_prims[s.shape]
                .clone()
                .map(|i| geometry.new_index[i])
                .collect(),
        })
        .collect();
    // The area lights' quads and emitting triangles, now in BVH order.
    for light in &mut lights {
        if light.prim != NONE {
            light.prim = geometry.new_index[light.prim as usize];
        }
    }
    let choice = choose_lights_by_power(&mut lights, scene.render.integrator == Integrator::Path);
    let render = &scene.render;
    let lens_sampler = (!camera.is_pinhole()).then_some(camera.lens_sampler);
    let table = SampleTable::build(
        render.spp,
        render.seed,
        render.pixel_sampler,
        lens_sampler,
        camera.aperture_blades,
        camera.aperture_rotation_deg,
        render.adaptive.is_some(),
    );
    let lens_table = camera.lens_table();
    let choice_offset = (table.points.len() + lens_table.len()) as u32;
    let frame = frame_constants(scene, &lights, &geometry, &table, &choice, choice_offset);
    let emitters = emitting_prims(&geometry.prims, &materials);
    let emitter_bounds = widened_bounds(emitters.iter().map(|&i| &geometry.prims[i as usize]));
    FlatScene {
        light_shapes: lights
            .iter()
            .map(|light| LightShape::of(light, &frame))
            .collect(),
        frame,
        bvh: geometry.bvh,
        nodes: geometry.nodes,
        prims: geometry.prims,
        normals: geometry.normals,
        texcoords: geometry.texcoords,
        materials,
        textures,
        texels,
        environment: environment_data(scene),
        lights,
        camera: GpuCamera {
            lens_table_offset: match camera.lens {
                Some(_) => table.points.len() as u32,
                None => 0,
            },
            ..camera.to_gpu(table.aperture_offset)
        },
        sample_table: [table.points, lens_table, choice.table()].concat(),
        bvh_depth: geometry.bvh_depth,
        traversal_iterations: geometry.traversal_iterations,
        triangle_count,
        build_time: geometry.build_time,
        crop: render.crop,
        adaptive: render.adaptive,
        surfaces,
        aovs: false,
        cwbvh: std::sync::OnceLock::new(),
        wide: std::sync::OnceLock::new(),
        emitters,
        emitter_bounds,
    }
}

/// The indices of the primitives whose material emits.
fn emitting_prims(prims: &[GpuPrimitive], materials: &[GpuMaterial]) -> Vec<u32> {
    let emits = |prim: &GpuPrimitive| {
        let emission = Vec3::from(materials[prim.material as usize].emission);
        emission.max_element() > 0.0
    };
    (0..prims.len() as u32)
        .filter(|&i| emits(&prims[i as usize]))
        .collect()
}

/// The scene's materials as the kernels read them (area lights add theirs after,
/// [`pack_lights`]), with the textures they read (each once, however many read it) and those
/// textures' texels.
fn pack_materials(scene: &Scene) -> (Vec<GpuMaterial>, Vec<GpuTexture>, Vec<u32>) {
    let path = scene.render.integrator == Integrator::Path;
    let mut read: Vec<Arc<Texture>> = Vec::new();
    let (mut textures, mut texels) = (Vec::new(), Vec::new());
    let mut texture_of = |texture: &Option<Arc<Texture>>| {
        let texture = texture.as_ref()?;
        if let Some(k) = read.iter().position(|t| Arc::ptr_eq(t, texture)) {
            return Some(k as u32 + 1);
        }
        read.push(texture.clone());
        textures.push(GpuTexture {
            offset: texels.len() as u32,
            width: texture.width,
            height: texture.height,
            wrap: texture.wrap[0].code() | texture.wrap[1].code() << 8,
        });
        texels.extend_from_slice(&texture.texels);
        Some(textures.len() as u32)
    };
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            // A material with emission (an OBJ `.mtl`'s `Ke`, a glTF `emissiveFactor`) is
            // carried by triangles only, each one a light of one sample. Whitted's integrator
            // renders it as an emitter lit by nothing; the path tracer lets it reflect too, as
            // pbrt's and Mitsuba's area lights on a reflecting surface do.
            let emits = m.emission.max_element() > 0.0;
            GpuMaterial {
                diffuse: m.diffuse.to_array(),
                model: if emits && !path {
                    MODEL_EMITTER
                } else {
                    m.model
                },
                specular: m.specular.to_array(),
                shininess: m.shininess,
                mirror: m.mirror.to_array(),
                light_samples: emits as u32,
                emission: m.emission.to_array(),
                ior: m.ior,
                texture: texture_of(&m.diffuse_texture).unwrap_or(0),
                ..Default::default()
            }
        })
        .collect();
    (materials, textures, texels)
}

/// The shapes' primitives, before the BVH orders them.
struct PackedShapes {
    /// The bounded primitives (and a triangle's vertex attributes), shape by shape.
    bounded: Vec<(GpuPrimitive, VertexAttributes)>,
    /// The unbounded planes.
    planes: Vec<GpuPrimitive>,
    /// Emitting triangles, each a light of one shadow-ray sample per hit (`prim`: its index in
    /// `bounded`).
    triangle_lights: Vec<GpuLight>,
    /// Each bounded primitive's velocity, in `bounded` order.
    velocities: Vec<Vec3>,
    /// Each shape's primitives in `bounded`.
    shape_prims: Vec<std::ops::Range<usize>>,
    /// Triangles of every mesh.
    triangle_count: usize,
}

/// Every shape's primitives, in the scene's order: spheres, quads and curved shapes as one
/// bounded primitive each, a mesh as its triangles, planes apart.
fn pack_shapes(scene: &Scene) -> PackedShapes {
    let mut packed = PackedShapes {
        bounded: Vec::new(),
        planes: Vec::new(),
        triangle_lights: Vec::new(),
        velocities: Vec::new(),
        shape_prims: Vec::with_capacity(scene.shapes.len()),
        triangle_count: 0,
    };
    for (shape_index, shape) in scene.shapes.iter().enumerate() {
        let velocity = scene
            .velocities
            .get(shape_index)
            .copied()
            .unwrap_or(Vec3::ZERO);
        let first = packed.bounded.len();
        match shape {
            Shape::Sphere {
                center,
                radius,
                material,
            } => packed.bounded.push((
                prim(
                    PRIM_SPHERE,
                    *material,
                    *center,
                    Vec3::new(
                        *radius,
                        intersect::sphere_origin_power(*center, *radius),
                        0.0,
                    ),
                    Vec3::ZERO,
                ),
                VertexAttributes::default(),
            )),
            Shape::Quad {
                corner,
                edge_u,
                edge_v,
                material,
            } => packed.bounded.push((
                prim(PRIM_QUAD, *material, *corner, *edge_u, *edge_v),
                VertexAttributes::default(),
            )),
            Shape::Curved {
                primitive,
                orientation,
                material,
            } => packed.bounded.push((
                curved_primitive(primitive, *orientation, *material),
                VertexAttributes::default(),
            )),
            Shape::Plane {
                point,
                normal,
                material,
            } => packed
                .planes
                .push(prim(PRIM_PLANE, *material, *point, *normal, Vec3::ZERO)),
            Shape::Mesh { mesh, material } => pack_mesh(scene, mesh, *material, &mut packed),
        }
        packed.velocities.resize(packed.bounded.len(), velocity);
        packed.shape_prims.push(first..packed.bounded.len());
    }
    packed
}

/// A mesh's triangles (with their vertex normals), each emitting one also a light.
fn pack_mesh(scene: &Scene, mesh: &TriangleMesh, material: u32, packed: &mut PackedShapes) {
    packed.triangle_count += mesh.triangles.len();
    for (f, t) in mesh.triangles.iter().enumerate() {
        let material = mesh.face_materials.get(f).copied().unwrap_or(material);
        let emission = scene.materials[material as usize].emission;
        let emitting = emission.max_element() > 0.0;
        let refracting = scene.materials[material as usize].model == MODEL_DIELECTRIC;
        // Vertices in the order the watertight test relies on; an emitter keeps its winding,
        // which says which side it shines from, and glass its, which says which side is inside.
        let order = match emitting || refracting {
            true => [0, 1, 2],
            false => intersect::lexicographic_order(t.map(|i| mesh.positions[i as usize])),
        };
        let t = order.map(|k| t[k]);
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normals = mesh.normals.as_ref().map(|n| {
            let [na, nb, nc] = t.map(|i| n[i as usize]);
            GpuNormals {
                n: [na.x, na.y, na.z, nb.x, nb.y, nb.z, nc.x, nc.y, nc.z],
            }
        });
        // Texture coordinates go only with the triangles whose material reads them.
        let textured = scene.materials[material as usize].diffuse_texture.is_some();
        let texcoords = mesh.texcoords.as_ref().filter(|_| textured).map(|uv| {
            let [ta, tb, tc] = t.map(|i| uv[i as usize]);
            GpuTexCoords {
                uv: [ta.x, ta.y, tb.x, tb.y, tc.x, tc.y],
            }
        });
        let attributes = VertexAttributes { normals, texcoords };
        packed
            .bounded
            .push((prim(PRIM_TRIANGLE, material, a, b, c), attributes));
        if emitting {
            packed.triangle_lights.push(GpuLight {
                p0: a.to_array(),
                kind: LIGHT_TRIANGLE,
                p1: (b - a).to_array(),
                samples: 1,
                p2: (c - a).to_array(),
                // Its index in `bounded`, remapped after the BVH build (`flatten`).
                prim: packed.bounded.len() as u32 - 1,
                color: emission.to_array(),
                strata_columns: 1,
            });
        }
    }
}

/// The lights as the kernels read them, in the scene's order. Area lights are surfaces too: a
/// one-sided emitting quad each, with a material of its own, added to `bounded` and
/// `materials`.
fn pack_lights(
    scene: &Scene,
    materials: &mut Vec<GpuMaterial>,
    bounded: &mut Vec<(GpuPrimitive, VertexAttributes)>,
) -> Vec<GpuLight> {
    let mut lights = Vec::new();
    for light in &scene.lights {
        lights.push(match *light {
            Light::Point {
                position,
                intensity,
            } => GpuLight {
                p0: position.to_array(),
                kind: LIGHT_POINT,
                color: intensity.to_array(),
                prim: NONE,
                ..Default::default()
            },
            Light::Spot {
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
            } => {
                let (scale, offset) = spot_falloff(inner_deg, outer_deg);
                GpuLight {
                    p0: position.to_array(),
                    kind: LIGHT_SPOT,
                    p1: direction.to_array(),
                    p2: [scale, offset, 0.0],
                    color: intensity.to_array(),
                    prim: NONE,
                    ..Default::default()
                }
            }
            Light::Directional {
                direction,
                irradiance,
            } => GpuLight {
                p0: (-direction).to_array(),
                kind: LIGHT_DIRECTIONAL,
                color: irradiance.to_array(),
                prim: NONE,
                ..Default::default()
            },
            Light::Area {
                corner,
                edge_u,
                edge_v,
                radiance,
                samples,
            } => {
                materials.push(GpuMaterial {
                    model: MODEL_EMITTER,
                    emission: radiance.to_array(),
                    light_samples: samples,
                    ..Default::default()
                });
                let material = materials.len() as u32 - 1;
                let quad = prim(PRIM_QUAD, material, corner, edge_u, edge_v);
                bounded.push((quad, VertexAttributes::default()));
                GpuLight {
                    p0: corner.to_array(),
                    kind: LIGHT_AREA,
                    p1: edge_u.to_array(),
                    samples,
                    p2: edge_v.to_array(),
                    // Its index in `bounded`, remapped after the BVH build (`flatten`).
                    prim: bounded.len() as u32 - 1,
                    color: radiance.to_array(),
                    strata_columns: strata_columns(samples),
                }
            }
            Light::Environment {
                radiance,
                ref map,
                rotate_deg,
                samples,
            } => {
                let (width, height, mean) = match map {
                    Some(m) => (m.width, m.height, m.mean()),
                    None => (0, 0, [1.0; 3]),
                };
                GpuLight {
                    p0: [rotate_deg / 360.0, width as f32, height as f32],
                    kind: LIGHT_ENVIRONMENT,
                    p1: mean,
                    samples,
                    prim: NONE,
                    color: radiance.to_array(),
                    strata_columns: strata_columns(samples),
                    ..Default::default()
                }
            }
            Light::Sun {
                direction,
                irradiance,
                angular_radius_deg,
                samples,
            } => GpuLight {
                p0: (-direction).to_array(),
                kind: LIGHT_SUN,
                p1: sun_cone(angular_radius_deg),
                samples,
                p2: [sun_radiance_over_density(angular_radius_deg), 0.0, 0.0],
                prim: NONE,
                color: irradiance.to_array(),
                strata_columns: strata_columns(samples),
            },
        });
    }
    lights
}

/// A sun's cone of half-angle `alpha_deg` as its light reads it (`layout::LIGHT_SUN`): 1 -
/// cos alpha (as 2 sin^2(alpha / 2), exact for the smallest cones), the radiance per unit of
/// irradiance 1 / (pi sin^2 alpha), and the density 1 / (2 pi (1 - cos alpha)) of a direction
/// drawn uniformly in the cone; in f64, rounded once.
pub fn sun_cone(alpha_deg: f64) -> [f32; 3] {
    use std::f64::consts::PI;
    let alpha = alpha_deg.to_radians();
    let one_minus_cos = 2.0 * (0.5 * alpha).sin().powi(2);
    [
        one_minus_cos as f32,
        (1.0 / (PI * alpha.sin().powi(2))) as f32,
        (1.0 / (2.0 * PI * one_minus_cos)) as f32,
    ]
}

/// A sun's radiance over its cone's sampling density, per unit of irradiance:
/// 2 pi (1 - cos alpha) / (pi sin^2 alpha) = 1 / cos^2(alpha / 2), which stays exact where
/// both factors are extreme.
pub fn sun_radiance_over_density(alpha_deg: f64) -> f32 {
    (1.0 / (0.5 * alpha_deg.to_radians()).cos().powi(2)) as f32
}

/// How the path tracer's vertices choose their area light (`GpuFrame::light_choice_start`).
struct LightChoice {
    /// The first light chosen among.
    start: u32,
    /// The most samples of a light chosen among.
    pairs: u32,
    /// The cumulative distribution of the lights chosen among, by power (the last entry 1).
    cdf: Vec<f32>,
    /// Their total power, luminance x area.
    total: f32,
}

impl LightChoice {
    /// The cumulative distribution as sample-table points, two entries a point.
    fn table(&self) -> Vec<[f32; 2]> {
        self.cdf
            .chunks(2)
            .map(|c| [c[0], c.get(1).copied().unwrap_or(1.0)])
            .collect()
    }
}

/// Orders `lights` for the path tracer's light choice: the lights sampled at every vertex
/// (punctual and sky lights) first, then the area lights, one of which a vertex chooses in
/// proportion to its power, luminance x area (an emitting mesh's triangles by their areas, as
/// Mitsuba samples a mesh emitter): a vertex then traces one area light's samples however many
/// emitting triangles the scene has. Whitted's integrator keeps the scene's order and samples
/// every light. The distribution is summed in f64 and rounded once per entry: a vertex divides
/// by the probability its entry gives, so the choice stays unbiased where rounding moved it
/// from the power's share (a light below 2^-25 of the total power may have none).
fn choose_lights_by_power(lights: &mut [GpuLight], path: bool) -> LightChoice {
    let no_choice = |lights: &[GpuLight]| LightChoice {
        start: lights.len() as u32,
        pairs: 0,
        cdf: Vec::new(),
        total: 0.0,
    };
    if !path {
        return no_choice(lights);
    }
    lights.sort_by_key(GpuLight::is_area);
    let start = lights.partition_point(|l| !l.is_area());
    let chosen = &lights[start..];
    let power: Vec<f64> = chosen
        .iter()
        .map(|l| luminance_f32(l.color) as f64 * l.area() as f64)
        .collect();
    let total: f64 = power.iter().sum();
    if chosen.is_empty() || !(total as f32 > 0.0 && (total as f32).is_finite()) {
        return no_choice(lights);
    }
    let mut sum = 0.0;
    let mut cdf: Vec<f32> = power
        .iter()
        .map(|p| {
            sum += p;
            (sum / total) as f32
        })
        .collect();
    *cdf.last_mut().expect("at least one light is chosen among") = 1.0;
    LightChoice {
        start: start as u32,
        pairs: chosen.iter().map(|l| l.samples).max().unwrap_or(0),
        cdf,
        total: total as f32,
    }
}

/// The packed map of the scene's environment light, if it has one with a map.
fn environment_data(scene: &Scene) -> Vec<f32> {
    scene
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Environment { map: Some(m), .. } => Some(m.packed()),
            _ => None,
        })
        .unwrap_or_default()
}

/// The frame's constants: image, samples, lights, the BVH's extent and sample tables.
fn frame_constants(
    scene: &Scene,
    lights: &[GpuLight],
    geometry: &Geometry,
    table: &SampleTable,
    choice: &LightChoice,
    choice_offset: u32,
) -> GpuFrame {
    let (render, camera) = (&scene.render, &scene.camera);
    let light_samples_per_vertex = choice.pairs
        + lights[..choice.start as usize]
            .iter()
            .filter(|l| l.is_sampled())
            .map(|l| l.samples)
            .sum::<u32>();
    let path = render.integrator == Integrator::Path;
    GpuFrame {
        width: render.width,
        height: render.height,
        spp: render.spp,
        max_depth: render.max_depth,
        seed: render.seed,
        pixel_sampler: render.pixel_sampler.code(),
        light_count: lights.len() as u32,
        node_count: geometry.nodes.len() as u32,
        plane_start: geometry.plane_start,
        plane_count: geometry.plane_count,
        traversal_cap: 2 * geometry.nodes.len() as u32 + 64,
        pixel_strata_columns: strata_columns(render.spp),
        lens_sampler: camera.lens_sampler.code(),
        lens_strata_columns: strata_columns(render.spp),
        pixel_table_offset: table.pixel_offset,
        lens_table_offset: table.lens_offset,
        background: render.background.to_array(),
        light_samples_per_vertex,
        ambient: render.ambient.to_array(),
        motion_base: geometry.motion_base,
        progressive: render.adaptive.is_some() as u32,
        integrator: match path {
            true => INTEGRATOR_PATH,
            false => INTEGRATOR_WHITTED,
        },
        rr_depth: render.rr_depth,
        vertex_dimension_pairs: light_samples_per_vertex + if path { PATH_VERTEX_PAIRS } else { 0 },
        light_choice_start: choice.start,
        light_choice_pairs: choice.pairs,
        light_choice_offset: choice_offset,
        light_power_total: choice.total,
    }
}

/// The primitive of an ellipsoid, cylinder or torus turned by `orientation` (the fields per kind
/// on `layout::GpuPrimitive`): the orientation's x, y, z in p2 and w's bits in `normals`, as
/// `accel::curved::orientation` reads them.
pub fn curved_primitive(
    primitive: &CurvedPrimitive,
    orientation: Quat,
    material: u32,
) -> GpuPrimitive {
    let (kind, p0, p1) = match *primitive {
        CurvedPrimitive::Ellipsoid { center, radii } => (PRIM_ELLIPSOID, center, radii),
        CurvedPrimitive::Cylinder {
            base,
            radius,
            height,
        } => (PRIM_CYLINDER, base, Vec3::new(radius, height, 0.0)),
        CurvedPrimitive::Torus {
            center,
            major,
            minor,
        } => (PRIM_TORUS, center, Vec3::new(major, minor, 0.0)),
    };
    let mut curved = prim(kind, material, p0, p1, orientation.xyz());
    curved.normals = orientation.w.to_bits();
    curved
}

fn prim(kind: u32, material: u32, p0: Vec3, p1: Vec3, p2: Vec3) -> GpuPrimitive {
    GpuPrimitive {
        p0: p0.to_array(),
        kind,
        p1: p1.to_array(),
        material,
        p2: p2.to_array(),
        normals: NONE,
    }
}
