//! The Whitted integrator: one camera sample -> radiance. Twin: `wgsl/integrator.wgsl`. A
//! frame with `render.integrator = "path"` goes to the path tracer (`path`, `bsdf`) instead.
//!
//! Per hit: emission of a front-facing area light (which then ends the path: it reflects
//! nothing), ambient term diffuse * L_a, direct light from every light through shadow rays,
//! then a perfect-mirror bounce while the mirror reflectance is non-zero and depth < max_depth.
//! The bounce is a loop, not recursion, exactly as on the GPU. Radiometry follows pbrt:
//! Lambert = diffuse / pi; normalised Phong = ks (n + 2) / (2 pi) cos^n(alpha) with alpha between
//! the mirror direction of the light and the viewer; normalised Blinn-Phong = ks (n + 8) / (8 pi)
//! cos^n(theta_h).
//!
//! Like the GPU kernel, the integrator is specialised to the scene's features: the functions
//! take the `layout::FEATURE_*` bits as a const generic `F`, so code for a feature the scene
//! lacks is compiled out (`FEATURES_ALL` is the general integrator); `cpu.rs` picks the
//! instance for the scene. The CPU renders a pixel's samples with [`trace_pixel`], which traces
//! their camera rays in packets (`accel::wide::packet`), and then each path from its camera
//! ray's hit. The GPU's wavefront render runs [`trace_path`]'s loop a vertex at a time over all
//! of a dispatch's paths (`wgsl/wavefront.wgsl`): the same operations on each path, in the same
//! order.

use std::f32::consts::PI;
use std::mem::MaybeUninit;

use glam::{Vec2, Vec3};

use crate::accel::curved::curved_surface_point;
use crate::accel::intersect::{
    Hit, RayQuery, offset_ray_origin, plane_point, quad_point, shadow_ray_length,
    sphere_surface_point, triangle_point,
};
use crate::camera::spectral::{film_response, sample_wavelength};
use crate::camera::{Ray, film_position_mm, generate_lens_ray, generate_ray};
use crate::layout::*;
use crate::math::rng::Rng;
use crate::pack::{FlatScene, LightShape};
use crate::sampler::{
    PatternSource, light_sample_2d, permute, pixel_hash, sample_2d, sample_aperture,
};

use batch::BATCH;

mod batch;
pub mod bsdf;
pub mod environment;
mod path;
pub mod texture;

/// Counters a sample adds to (rays traced, paths cut off at `max_depth`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleStats {
    /// Rays traced: camera, shadow and mirror rays.
    pub rays: u64,
    /// Paths cut off at `max_depth` while they still reflected (drew their bounce there).
    pub truncated: u64,
    /// `STATUS_*` bits raised while sampling.
    pub flags: u32,
}

/// What a camera ray's first hit shows, for the AOV layers (zero where it hits nothing): the
/// distance along the ray, the shading normal (towards the ray), and the albedo (diffuse plus
/// mirror reflectance, at most 1; zero on an emitter). Twin: `FirstHit` in integrator.wgsl.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FirstHit {
    /// Distance along the camera ray, scene units.
    pub depth: f32,
    /// Shading normal in world space, facing the ray.
    pub normal: Vec3,
    /// Diffuse plus mirror reflectance, at most 1 per channel; zero on an emitter.
    pub albedo: Vec3,
}

impl FirstHit {
    fn of(t: f32, surface: &Surface, material: &GpuMaterial) -> FirstHit {
        let albedo = if material.model == MODEL_EMITTER {
            Vec3::ZERO
        } else if material.model == MODEL_DIELECTRIC {
            // Glass passes all light on: the albedo denoisers expect of it.
            Vec3::ONE
        } else {
            (Vec3::from(material.diffuse) + Vec3::from(material.mirror)).min(Vec3::ONE)
        };
        FirstHit {
            depth: t,
            normal: surface.shading_normal,
            albedo,
        }
    }
}

/// A surface point as shading needs it; normals face the side the ray came from.
struct Surface {
    position: Vec3,
    /// Per-component bound on the rounding error of `position` (for `offset_ray_origin`).
    position_error: Vec3,
    geometric_normal: Vec3,
    shading_normal: Vec3,
    front_facing: bool,
}

fn surface_at(scene: &FlatScene, prim: &GpuPrimitive, ray: &RayQuery, hit: Hit) -> Surface {
    let (p0, p1, p2) = (
        Vec3::from(prim.p0),
        Vec3::from(prim.p1),
        Vec3::from(prim.p2),
    );
    // Recompute the position from the primitive itself: its error then scales with the
    // primitive's coordinates, not with the distance travelled, and is bounded (origin offsets
    // rely on the bound).
    let (point, normal, shading) = match prim.kind {
        PRIM_TRIANGLE => {
            let point = triangle_point([p0, p1, p2], hit.b1, hit.b2);
            let normal = (p1 - p0).cross(p2 - p0).normalize();
            let shading = if prim.normals == NONE {
                normal
            } else {
                let n = scene.normals[prim.normals as usize].n;
                let b0 = 1.0 - hit.b1 - hit.b2;
                let interpolated = b0 * Vec3::new(n[0], n[1], n[2])
                    + hit.b1 * Vec3::new(n[3], n[4], n[5])
                    + hit.b2 * Vec3::new(n[6], n[7], n[8]);
                let length = interpolated.length();
                if length > 0.0 {
                    interpolated / length
                } else {
                    normal
                }
            };
            (point, normal, shading)
        }
        PRIM_SPHERE => {
            let (point, outward) = sphere_surface_point(ray, hit, p0, p1.x);
            (point, outward, outward)
        }
        PRIM_QUAD => {
            let normal = p1.cross(p2).normalize();
            (quad_point(p0, p1, p2, hit.b1, hit.b2), normal, normal)
        }
        PRIM_PLANE => (plane_point(ray, hit.t, p0, p1), p1, p1),
        _ => {
            let (point, outward) = curved_surface_point(ray, hit.t, prim);
            (point, outward, outward)
        }
    };
    // Two-sided shading: turn both normals towards the incoming ray.
    let front_facing = normal.dot(ray.direction) < 0.0;
    let geometric_normal = if front_facing { normal } else { -normal };
    let mut shading_normal = if front_facing { shading } else { -shading };
    if shading_normal.dot(geometric_normal) < 0.0 {
        shading_normal = -shading_normal;
    }
    Surface {
        position: point.position,
        position_error: point.error,
        geometric_normal,
        shading_normal,
        front_facing,
    }
}

/// The surface of primitive `id` hit by `ray` at the ray's time: found in the primitive's own
/// frame (where it was built), then moved to where it is. Twin: `moved_surface_at` in
/// integrator.wgsl.
#[inline]
fn moved_surface_at(scene: &FlatScene, id: u32, ray: &RayQuery, hit: Hit) -> Surface {
    let prim = &scene.prims[id as usize];
    let offset = scene.primitives().offset(id, ray.time);
    if offset == Vec3::ZERO {
        return surface_at(scene, prim, ray, hit);
    }
    let mut surface = surface_at(scene, prim, &ray.relative_to(offset), hit);
    surface.position += offset;
    // The addition rounds once more: half an ULP of the larger magnitude, per component.
    surface.position_error += (surface.position.abs() + offset.abs()) * (0.5 * f32::EPSILON);
    surface
}

/// BRDF value for light arriving along `wi` and leaving along `wo` (both unit, away from p).
#[inline]
pub fn eval_brdf(material: &GpuMaterial, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let mut f = Vec3::from(material.diffuse) / PI;
    let specular = Vec3::from(material.specular);
    let exponent = material.shininess;
    if material.model == MODEL_PHONG {
        let reflected = 2.0 * n.dot(wi) * n - wi;
        let cos_alpha = reflected.dot(wo);
        if cos_alpha > 0.0 {
            f += specular * ((exponent + 2.0) / (2.0 * PI)) * cos_alpha.powf(exponent);
        }
    } else if material.model == MODEL_BLINN_PHONG {
        let half = (wi + wo).normalize();
        let cos_h = n.dot(half);
        if cos_h > 0.0 {
            f += specular * ((exponent + 8.0) / (8.0 * PI)) * cos_h.powf(exponent);
        }
    } else if material.model == MODEL_ROUGH_CONDUCTOR {
        f += specular * bsdf::ggx_reflection(exponent, n, wo, wi);
    }
    f
}

/// The window of every area light's shadow-ray samples that one dispatch evaluates (see
/// `GpuPass`): a light with more samples than one invocation can trace in a bounded number of
/// loop iterations is split over several dispatches, each summing its window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightWindow {
    /// Index of the window's first sample, in each area light's samples.
    pub start: u32,
    /// Samples of each light in the window (`u32::MAX`: to the last); a light with fewer
    /// stops at its own count.
    pub count: u32,
}

impl LightWindow {
    /// Every light sample in one go.
    pub const ALL: LightWindow = LightWindow {
        start: 0,
        count: u32::MAX,
    };

    /// The window a dispatch evaluates (`GpuPass::light_sample_start`, `light_sample_count`).
    pub fn of_pass(pass: &GpuPass) -> LightWindow {
        LightWindow {
            start: pass.light_sample_start,
            count: pass.light_sample_count,
        }
    }

    /// The first window also adds what does not depend on light samples.
    pub fn is_first(self) -> bool {
        self.start == 0
    }

    /// The samples of a light with `samples` samples that fall in the window.
    pub fn clip(self, samples: u32) -> std::ops::Range<u32> {
        let end = self.start.saturating_add(self.count.min(samples));
        self.start.min(samples)..end.min(samples)
    }
}

/// First random dimension of sample `k` of the area light whose samples start at `offset`
/// among the `layout::LIGHT_DIMENSION` block of path vertex `depth` (wrapping, as in WGSL).
fn light_dimension(frame: &GpuFrame, depth: u32, offset: u32, k: u32) -> u32 {
    let index = depth
        .wrapping_mul(frame.vertex_dimension_pairs)
        .wrapping_add(offset)
        .wrapping_add(k);
    LIGHT_DIMENSION.wrapping_add(index.wrapping_mul(2))
}

/// A shadow ray from a path vertex towards a light, and what it adds there where the light is
/// visible: `f`, before an area light's scale ([`light_total`]). Twin: `LightSample` in
/// integrator.wgsl, which the wavefront render stores per shadow ray.
struct LightSample {
    wi: Vec3,
    t_max: f32,
    /// The light's own primitive, which its shadow ray must not hit (`NONE`: a punctual light).
    skip: u32,
    f: Vec3,
    /// False where the vertex or the light faces away: no ray is traced, nothing is added.
    traced: bool,
}

/// How a vertex came to sample a light: the probability it chose it with (1 for a light
/// sampled at every vertex), and the samples a vertex takes of it on average, which the MIS
/// weights count (its samples times its power's share, the same share an emitter hit finds).
#[derive(Clone, Copy, Debug, PartialEq)]
struct LightShare {
    chosen: f32,
    expected_samples: f32,
}

impl LightShare {
    /// A light every vertex samples.
    fn every_vertex(light: &GpuLight) -> LightShare {
        LightShare {
            chosen: 1.0,
            expected_samples: light.samples as f32,
        }
    }
}

/// Entry `i` of the chosen lights' cumulative distribution (`GpuFrame::light_choice_offset`).
fn choice_cdf(scene: &FlatScene, i: u32) -> f32 {
    let point = scene.sample_table[(scene.frame.light_choice_offset + i / 2) as usize];
    point[(i % 2) as usize]
}

/// The area light path vertex `depth` samples, chosen in proportion to power
/// (`GpuFrame::light_choice_start`) by the first number of its `CHOICE_PAIR`: its index and its
/// share. None where the frame chooses no light. Twin: `choose_light` in integrator.wgsl.
fn choose_light(scene: &FlatScene, depth: u32, rng: &mut Rng) -> Option<(usize, LightShare)> {
    let frame = &scene.frame;
    if !frame.chooses_lights() {
        return None;
    }
    rng.seek(path::choice_dimension(frame, depth));
    let u = rng.next_2d()[0];
    // The first entry above u: the last is 1, above every u.
    let (mut low, mut high) = (0, frame.light_count - frame.light_choice_start - 1);
    while low < high {
        let middle = (low + high) / 2;
        match choice_cdf(scene, middle) > u {
            true => high = middle,
            false => low = middle + 1,
        }
    }
    let below = match low {
        0 => 0.0,
        _ => choice_cdf(scene, low - 1),
    };
    let index = (frame.light_choice_start + low) as usize;
    let share = LightShare {
        chosen: choice_cdf(scene, low) - below,
        expected_samples: scene.light_shapes[index].chosen_samples,
    };
    Some((index, share))
}

/// The point `square` of the unit square on an area light (folded onto a triangle light's
/// triangle), seen from `vertex`, over the probability the vertex chose the light with; under
/// the path tracer (a vertex with its lobes), weighted against the BSDF's sample of the same
/// direction.
// Inlined as it was before the light choice gave its caller two call sites: a call per
// sample cost Whitted's CPU frames about 4% of their instructions.
#[inline(always)]
fn area_light_sample(
    light: &GpuLight,
    shape: &LightShape,
    share: LightShare,
    square: [f32; 2],
    vertex: &Vertex,
) -> LightSample {
    let (surface, material, wo) = (vertex.surface, vertex.material, vertex.wo);
    let u = if light.kind == LIGHT_TRIANGLE && square[0] + square[1] > 1.0 {
        [1.0 - square[0], 1.0 - square[1]]
    } else {
        square
    };
    let n = surface.shading_normal;
    let point = Vec3::from(light.p0) + u[0] * Vec3::from(light.p1) + u[1] * Vec3::from(light.p2);
    let to_light = point - surface.position;
    let distance = to_light.length();
    let wi = to_light / distance;
    let cos_surface = n.dot(wi);
    let cos_light = -shape.normal.dot(wi);
    let traced = cos_surface > 0.0 && cos_light > 0.0 && surface.geometric_normal.dot(wi) > 0.0;
    let mut f = match traced {
        true => eval_brdf(material, n, wo, wi) * cos_surface * cos_light / (distance * distance),
        false => Vec3::ZERO,
    };
    if let (Some(lobes), true) = (&vertex.lobes, traced) {
        let bsdf_pdf = bsdf::bsdf_pdf(material, lobes, n, wo, wi);
        let distance2 = distance * distance;
        // A light is chosen only under the path tracer: Whitted's samples skip the division.
        f *= bsdf::light_sample_weight(
            share.expected_samples,
            distance2,
            cos_light,
            shape.area,
            bsdf_pdf,
        ) / share.chosen;
    }
    LightSample {
        wi,
        t_max: shadow_ray_length(distance),
        skip: light.prim,
        f,
        traced,
    }
}

/// A point, spot or directional light seen from `surface`: its whole contribution.
fn punctual_light_sample(
    light: &GpuLight,
    surface: &Surface,
    material: &GpuMaterial,
    wo: Vec3,
) -> LightSample {
    let (wi, distance, mut falloff) = if light.kind == LIGHT_DIRECTIONAL {
        (Vec3::from(light.p0), T_FAR, 1.0)
    } else {
        let to_light = Vec3::from(light.p0) - surface.position;
        let distance = to_light.length();
        (to_light / distance, distance, 1.0 / (distance * distance))
    };
    if light.kind == LIGHT_SPOT {
        let cos = -Vec3::from(light.p1).dot(wi);
        let cone = (cos * light.p2[0] + light.p2[1]).clamp(0.0, 1.0);
        falloff *= cone * cone;
    }
    let n = surface.shading_normal;
    let cos_surface = n.dot(wi);
    let traced = cos_surface > 0.0 && surface.geometric_normal.dot(wi) > 0.0;
    let f = match traced {
        true => eval_brdf(material, n, wo, wi) * Vec3::from(light.color) * (cos_surface * falloff),
        false => Vec3::ZERO,
    };
    LightSample {
        wi,
        t_max: shadow_ray_length(distance),
        skip: NONE,
        f,
        traced,
    }
}

/// A direction drawn from sky light `light` (an environment or a sun) with the unit-square
/// point `square`, seen from `vertex`: its term is the BRDF times the cosine times the
/// radiance over the density (a sun's radiance over density is its `light_total` scale); under
/// the path tracer (a vertex with its lobes), weighted against the BSDF's sample of the same
/// direction.
fn sky_light_sample(
    light: &GpuLight,
    environment_data: &[f32],
    square: [f32; 2],
    vertex: &Vertex,
) -> LightSample {
    let (surface, material, wo) = (vertex.surface, vertex.material, vertex.wo);
    let sky = environment::sky_sample(light, environment_data, square);
    let n = surface.shading_normal;
    let cos_surface = n.dot(sky.wi);
    let traced = sky.pdf > 0.0 && cos_surface > 0.0 && surface.geometric_normal.dot(sky.wi) > 0.0;
    let radiance_over_pdf = match light.kind {
        LIGHT_SUN => Vec3::ONE,
        _ => sky.radiance / sky.pdf,
    };
    let mut f = match traced {
        true => eval_brdf(material, n, wo, sky.wi) * radiance_over_pdf * cos_surface,
        false => Vec3::ZERO,
    };
    if let (Some(lobes), true) = (&vertex.lobes, traced) {
        let bsdf_pdf = bsdf::bsdf_pdf(material, lobes, n, wo, sky.wi);
        f *= bsdf::sky_sample_weight(light.samples, sky.pdf, bsdf_pdf);
    }
    LightSample {
        wi: sky.wi,
        t_max: shadow_ray_length(T_FAR),
        skip: NONE,
        f,
        traced,
    }
}

/// The radiance a ray that escapes along `direction` sees of the lights at infinity (not the
/// background), each weighted against its light samples where the ray was drawn by a BSDF with
/// density `bsdf_pdf` (0: a camera or mirror ray, weight 1).
fn sky_seen<const F: u32>(scene: &FlatScene, direction: Vec3, bsdf_pdf: f32) -> Vec3 {
    let mut total = Vec3::ZERO;
    if !has(F, FEATURE_AREA_LIGHTS) {
        return total;
    }
    for light in &scene.lights[..scene.frame.light_count as usize] {
        if light.is_sky() {
            let (radiance, pdf) = environment::sky_radiance(light, &scene.environment, direction);
            let weight = bsdf::sky_hit_weight(light.samples, pdf, bsdf_pdf);
            total += Vec3::from(light.color) * radiance * weight;
        }
    }
    total
}

/// A sampled light's scale of its samples' sum besides `color / samples`: an area light's
/// area, a sun's radiance over density per irradiance (`layout::LIGHT_SUN`), 1 for an
/// environment, whose terms carry their radiance over density.
fn light_scale(light: &GpuLight, shape: &LightShape) -> f32 {
    match light.kind {
        LIGHT_SUN => light.p2[0],
        LIGHT_ENVIRONMENT => 1.0,
        _ => shape.area,
    }
}

/// What a light of shape `shape` adds from `sum`, the sum of its visible samples' terms.
fn light_total(light: &GpuLight, shape: &LightShape, sum: Vec3) -> Vec3 {
    if light.is_sampled() {
        Vec3::from(light.color) * sum * (light_scale(light, shape) / light.samples as f32)
    } else {
        sum
    }
}

/// What a sampled light (an area or a sky light) adds at a vertex from its samples in
/// `window`, whose dimensions start at `offset` among the vertex's light samples: each sample
/// draws its numbers first, so both paths consume the same dimensions whatever the visibility.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sampled_light<const F: u32>(
    scene: &FlatScene,
    (light, shape): (&GpuLight, &LightShape),
    share: LightShare,
    offset: u32,
    vertex: &Vertex,
    window: LightWindow,
    rng: &mut Rng,
    stats: &mut SampleStats,
) -> Vec3 {
    let samples = window.clip(light.samples);
    let frame = &scene.frame;
    let key = pixel_hash(
        frame.seed,
        rng.pixel,
        light_dimension(frame, vertex.depth, offset, 0),
    );
    rng.seek(light_dimension(frame, vertex.depth, offset, samples.start));
    let mut sum = Vec3::ZERO;
    for k in samples {
        let square = light_sample_2d(
            frame,
            light.samples,
            light.strata_columns,
            rng.sample,
            k,
            key,
            rng.next_2d(),
            &mut stats.flags,
        );
        let s = match light.is_sky() {
            true => sky_light_sample(light, &scene.environment, square, vertex),
            false => area_light_sample(light, shape, share, square, vertex),
        };
        if s.traced && vertex.visible::<F>(scene, &s, stats) {
            sum += s.f;
        }
    }
    light_total(light, shape, sum)
}

/// What the area light vertex chooses adds (`choose_light`): only the path tracer chooses, so
/// only the integrators compiled with it (`FEATURE_PATH`) hold this code.
#[inline(always)]
fn chosen_light<const F: u32>(
    scene: &FlatScene,
    vertex: &Vertex,
    window: LightWindow,
    rng: &mut Rng,
    stats: &mut SampleStats,
) -> Vec3 {
    match choose_light(scene, vertex.depth, rng) {
        Some((l, share)) => {
            let light = (&scene.lights[l], &scene.light_shapes[l]);
            sampled_light::<F>(scene, light, share, 0, vertex, window, rng, stats)
        }
        None => Vec3::ZERO,
    }
}

/// A path vertex as its light samples see it: where its shadow rays start, at what time, and
/// the primitive they skip.
struct Vertex<'a> {
    surface: &'a Surface,
    material: &'a GpuMaterial,
    /// The material's lobes under the path tracer, whose light samples they weigh against the
    /// BSDF's (multiple importance sampling); none under Whitted's integrator, which has none.
    lobes: Option<bsdf::Lobes>,
    wo: Vec3,
    depth: u32,
    /// Where the shadow rays start: the surface point offset along its geometric normal
    /// (the reflected bounce leaves from there too).
    origin: Vec3,
    time: f32,
    own: u32,
}

impl<'a> Vertex<'a> {
    /// The vertex at `surface` (of `material`, whose lobes the path tracer passes), seen
    /// along `wo` at path vertex `depth` and `time`; its rays skip primitive `own`.
    #[inline(always)]
    fn new(
        surface: &'a Surface,
        material: &'a GpuMaterial,
        lobes: Option<bsdf::Lobes>,
        wo: Vec3,
        depth: u32,
        time: f32,
        own: u32,
    ) -> Vertex<'a> {
        let origin = offset_ray_origin(
            surface.position,
            surface.position_error,
            surface.geometric_normal,
        );
        Vertex {
            surface,
            material,
            lobes,
            wo,
            depth,
            origin,
            time,
            own,
        }
    }
}

impl Vertex<'_> {
    /// Whether light sample `s` reaches the vertex (a shadow ray, counted).
    #[inline]
    fn visible<const F: u32>(
        &self,
        scene: &FlatScene,
        s: &LightSample,
        stats: &mut SampleStats,
    ) -> bool {
        stats.rays += 1;
        let ray = RayQuery::new(self.origin, s.wi).at_time(self.time);
        !scene
            .tracer()
            .occluded::<F>(&ray, self.own, s.skip, s.t_max)
    }
}

/// Light reflected towards `vertex.wo` with shadow rays: under the path tracer, the samples
/// in `window` of the one area light the vertex chose (`GpuFrame::light_choice_start`); the
/// samples in `window` of every other sampled light; and the point and directional lights in
/// the first window.
// Inlined into both integrators' vertex loops: called out of line, passing the surface and
// material through memory cost Whitted frames about 15% of their time (cornell_direct).
#[inline(always)]
fn direct_light<const F: u32>(
    scene: &FlatScene,
    vertex: &Vertex,
    window: LightWindow,
    rng: &mut Rng,
    stats: &mut SampleStats,
) -> Vec3 {
    let (surface, material, wo) = (vertex.surface, vertex.material, vertex.wo);
    let frame = &scene.frame;
    let mut total = Vec3::ZERO;
    if has(F, FEATURE_AREA_LIGHTS) && has(F, FEATURE_PATH) && frame.chooses_lights() {
        total += chosen_light::<F>(scene, vertex, window, rng, stats);
    }
    let mut offset = frame.light_choice_pairs;
    let unchosen = ..frame.light_choice_start as usize;
    for (light, shape) in scene.lights[unchosen]
        .iter()
        .zip(&scene.light_shapes[unchosen])
    {
        if has(F, FEATURE_AREA_LIGHTS) && light.is_sampled() {
            let share = LightShare::every_vertex(light);
            let sampled = (light, shape);
            total += sampled_light::<F>(scene, sampled, share, offset, vertex, window, rng, stats);
            offset += light.samples;
        } else if has(F, FEATURE_PUNCTUAL_LIGHTS) && window.is_first() {
            let s = punctual_light_sample(light, surface, material, wo);
            if s.traced && vertex.visible::<F>(scene, &s, stats) {
                total += s.f;
            }
        }
    }
    total
}

/// Whether the frame is path traced by an integrator compiled with the path tracer.
fn path_traced<const F: u32>(frame: &GpuFrame) -> bool {
    has(F, FEATURE_PATH) && frame.integrator == INTEGRATOR_PATH
}

/// The closest hit of a path's ray at vertex `depth` (the camera ray's may be known), counted
/// as a ray traced.
#[inline(always)]
fn vertex_hit<const F: u32>(
    scene: &FlatScene,
    ray: &RayQuery,
    skip: u32,
    depth: u32,
    camera_hit: CameraHit,
    stats: &mut SampleStats,
) -> Option<(u32, Hit)> {
    stats.rays += 1;
    match (depth, camera_hit) {
        (0, CameraHit::Known(found)) => found,
        _ => scene.tracer().closest_hit::<F>(ray, skip, T_FAR),
    }
}

/// The primitive, material (a textured one written to `textured`) and surface a path's ray
/// hit; the camera ray's hit also goes to `first_hit`.
#[inline(always)]
fn vertex_at<'a>(
    scene: &'a FlatScene,
    prim_id: u32,
    ray: &RayQuery,
    hit: Hit,
    depth: u32,
    first_hit: &mut FirstHit,
    textured: &'a mut MaybeUninit<GpuMaterial>,
) -> (&'a GpuPrimitive, &'a GpuMaterial, Surface) {
    let prim = &scene.prims[prim_id as usize];
    let surface = moved_surface_at(scene, prim_id, ray, hit);
    let material = material_at(scene, prim, hit, &surface, textured);
    if depth == 0 {
        *first_hit = FirstHit::of(hit.t, &surface, material);
    }
    (prim, material, surface)
}

/// The material of `prim` at `surface`: the scene's own, or where it has a texture, a copy in
/// `textured` whose diffuse reflectance is multiplied by the texture's colour there. (Copying
/// the material at every vertex, textured or not, cost untextured frames 2% of their
/// instructions.) Twin: `material_at` in integrator.wgsl.
fn material_at<'a>(
    scene: &'a FlatScene,
    prim: &GpuPrimitive,
    hit: Hit,
    surface: &Surface,
    textured: &'a mut MaybeUninit<GpuMaterial>,
) -> &'a GpuMaterial {
    let material = &scene.materials[prim.material as usize];
    if material.texture == 0 {
        return material;
    }
    let outward = match surface.front_facing {
        true => surface.geometric_normal,
        false => -surface.geometric_normal,
    };
    let uv = texture::texture_coordinates(prim, hit, outward, &scene.texcoords);
    let texture = &scene.textures[material.texture as usize - 1];
    let colour = texture::texture_lookup(texture, &scene.texels, uv);
    textured.write(GpuMaterial {
        diffuse: (Vec3::from(material.diffuse) * colour).to_array(),
        ..*material
    })
}

/// The camera ray's closest hit, as a path starts: traced by the path itself, or already
/// known (traced in a packet with the pixel's other samples; on the GPU, by a split render's
/// `primary` kernel).
#[derive(Clone, Copy, Debug)]
pub enum CameraHit {
    /// The path traces its camera ray.
    Trace,
    /// The camera ray's closest hit (primitive, hit), none for a miss.
    Known(Option<(u32, Hit)>),
}

/// Radiance along one path that starts with `camera_ray` (whose closest hit `camera_hit` may
/// already know), with the area-light samples in `window` (the path itself is deterministic:
/// every window retraces the same rays), at `time` (seconds: moving primitives are where they
/// are then); what its first hit shows goes to `first_hit`.
#[allow(clippy::too_many_arguments)]
pub fn trace_path<const F: u32>(
    scene: &FlatScene,
    camera_ray: Ray,
    camera_hit: CameraHit,
    time: f32,
    window: LightWindow,
    rng: &mut Rng,
    stats: &mut SampleStats,
    first_hit: &mut FirstHit,
) -> Vec3 {
    if path_traced::<F>(&scene.frame) {
        return path::trace_path::<F>(
            scene, camera_ray, camera_hit, time, window, rng, stats, first_hit,
        );
    }
    let first = window.is_first();
    let frame = &scene.frame;
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let mut ray = RayQuery::new(camera_ray.origin, camera_ray.direction).at_time(time);
    let mut skip = NONE;
    for depth in 0..=frame.max_depth {
        let Some((prim_id, hit)) = vertex_hit::<F>(scene, &ray, skip, depth, camera_hit, stats)
        else {
            if first {
                radiance += throughput * Vec3::from(frame.background);
                radiance += throughput * sky_seen::<F>(scene, ray.direction, 0.0);
            }
            break;
        };
        let mut textured = MaybeUninit::uninit();
        let (prim, material, surface) =
            vertex_at(scene, prim_id, &ray, hit, depth, first_hit, &mut textured);
        // An area light shows its radiance from the front, is black from behind, reflects nothing.
        if material.model == MODEL_EMITTER {
            if surface.front_facing && first {
                radiance += throughput * Vec3::from(material.emission);
            }
            break;
        }
        let wo = -ray.direction;
        if first {
            radiance += throughput * Vec3::from(material.diffuse) * Vec3::from(frame.ambient);
        }
        // Rays leaving a flat primitive skip it; a curved one may shadow or reflect itself.
        let own = match leaving_rays_skip(prim.kind, surface.front_facing) {
            true => prim_id,
            false => NONE,
        };
        let vertex = Vertex::new(&surface, material, None, wo, depth, time, own);
        radiance += throughput * direct_light::<F>(scene, &vertex, window, rng, stats);
        // Perfect mirror bounce.
        let mirror = Vec3::from(material.mirror);
        if !has(F, FEATURE_MIRRORS) || mirror.max_element() <= 0.0 {
            break;
        }
        if depth == frame.max_depth {
            if first {
                stats.truncated += 1;
            }
            break;
        }
        let n = surface.shading_normal;
        let reflected = ray.direction - 2.0 * ray.direction.dot(n) * n;
        if reflected.dot(surface.geometric_normal) <= 0.0 {
            break;
        }
        throughput *= mirror;
        ray = RayQuery::new(vertex.origin, reflected.normalize()).at_time(time);
        skip = own;
    }
    radiance
}

/// A camera sample: the ray and the time it is traced at.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraRay {
    /// The ray from the lens.
    pub ray: Ray,
    /// Seconds into the shutter (its opening when the shutter is instant).
    pub time: f32,
    /// What the ray's radiance counts for: 1, or through a real lens the exit-pupil sample's
    /// weight (0: the ray was lost in the lens).
    pub weight: f32,
    /// Its wavelength in the spectral mode (nm; 0 outside it).
    pub wavelength_nm: f32,
}

impl CameraRay {
    /// What its RGB radiance counts for in each channel: its weight, times the film's response
    /// at its wavelength in the spectral mode.
    pub fn counts_for(&self) -> Vec3 {
        match self.wavelength_nm > 0.0 {
            true => self.weight * film_response(self.wavelength_nm),
            false => Vec3::splat(self.weight),
        }
    }
}

/// The wavelength of camera sample `sample` of pixel (x, y) in the spectral mode (0 outside
/// it), drawn from random dimension `TIME_DIMENSION + 1` of its own stream (a pure function of
/// the sample, so a wavefront path finds it again when it is accumulated). Under the
/// stratified pattern each of the pixel's samples takes its own stratum of the range, one of
/// spp (the second coordinate of the 2-D pattern would give only √spp strata, and the bands'
/// crossovers then leave a colour noise of about 1% a pixel at 64 samples); the other patterns
/// give the second coordinate of their point at `TIME_DIMENSION` (Sobol's is a (0,1)-sequence).
/// Twin: `camera_wavelength` in wgsl/integrator.wgsl.
pub fn camera_wavelength(scene: &FlatScene, x: u32, y: u32, sample: u32, flags: &mut u32) -> f32 {
    let frame = &scene.frame;
    if scene.camera.spectral == 0 {
        return 0.0;
    }
    let pixel = y * frame.width + x;
    let mut rng = Rng::new(frame.seed, pixel, sample);
    rng.seek(TIME_DIMENSION);
    let u = match frame.pixel_sampler == SAMPLER_STRATIFIED && frame.progressive == 0 {
        true => {
            let key = pixel_hash(frame.seed, pixel, TIME_DIMENSION + 1);
            let stratum = permute(sample, frame.spp, key).unwrap_or_else(|| {
                *flags |= STATUS_PERMUTE_CAP;
                sample
            });
            (stratum as f32 + rng.next_2d()[1]) / frame.spp as f32
        }
        false => {
            let source = PatternSource {
                dim: TIME_DIMENSION,
                ..PatternSource::pixel(frame)
            };
            sample_2d(
                frame,
                &scene.sample_table,
                source,
                x,
                y,
                sample,
                &mut rng,
                flags,
            )[1]
        }
    };
    sample_wavelength(u)
}

/// Camera sample `sample` of pixel (x, y): position in the pixel (random dimensions 0-1),
/// lens point (2-3, drawn only by a lens), time (4, drawn only while the shutter is open a
/// while; from the pixel pattern) and wavelength (5, [`camera_wavelength`]), drawn from `rng`,
/// which the path then goes on drawing from.
/// Twin: `camera_sample` in wgsl/integrator.wgsl.
pub fn camera_sample<const F: u32>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    sample: u32,
    rng: &mut Rng,
    flags: &mut u32,
) -> CameraRay {
    let frame = &scene.frame;
    let camera = &scene.camera;
    let jitter = sample_2d(
        frame,
        &scene.sample_table,
        PatternSource::pixel(frame),
        x,
        y,
        sample,
        rng,
        flags,
    );
    let raster = Vec2::new(x as f32 + jitter[0], y as f32 + jitter[1]);
    let film = film_position_mm(camera, frame.width, frame.height, raster);
    let mut lens = Vec2::ZERO;
    if has(F, FEATURE_LENS) && camera.lens_radius_mm > 0.0 {
        let u = sample_2d(
            frame,
            &scene.sample_table,
            PatternSource::lens(frame),
            x,
            y,
            sample,
            rng,
            flags,
        );
        lens = match camera.projection {
            PROJECTION_LENS => Vec2::from(u),
            _ => Vec2::from(sample_aperture(camera, &scene.sample_table, u)),
        };
    }
    let mut time = camera.shutter_open;
    if camera.shutter_span > 0.0 {
        rng.seek(TIME_DIMENSION);
        let source = PatternSource {
            dim: TIME_DIMENSION,
            ..PatternSource::pixel(frame)
        };
        let u = sample_2d(frame, &scene.sample_table, source, x, y, sample, rng, flags);
        time += u[0] * camera.shutter_span;
    }
    let wavelength_nm = camera_wavelength(scene, x, y, sample, flags);
    let (ray, weight) = match camera.projection {
        PROJECTION_LENS => generate_lens_ray(
            camera,
            &scene.sample_table,
            film,
            lens.to_array(),
            wavelength_nm,
        ),
        _ => (generate_ray(camera, film, lens), 1.0),
    };
    CameraRay {
        ray,
        time,
        weight,
        wavelength_nm,
    }
}

/// Radiance of sample `sample` of pixel (x, y): its camera ray ([`camera_sample`]), then the
/// path with the light samples in `window` (its first hit to `first_hit`).
pub fn trace_sample<const F: u32>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    sample: u32,
    window: LightWindow,
    stats: &mut SampleStats,
    first_hit: &mut FirstHit,
) -> Vec3 {
    let frame = &scene.frame;
    let mut rng = Rng::new(frame.seed, y * frame.width + x, sample);
    let camera = camera_sample::<F>(scene, x, y, sample, &mut rng, &mut stats.flags);
    let radiance = trace_path::<F>(
        scene,
        camera.ray,
        CameraHit::Trace,
        camera.time,
        window,
        &mut rng,
        stats,
        first_hit,
    );
    radiance * camera.counts_for()
}

/// [`trace_sample`] for samples `samples` of pixel (x, y), each sample's radiance and first
/// hit given to `add` in order: the same paths, their camera rays traced in packets of
/// `BATCH` (a pixel's samples are nearly one ray; packets trace them about twice as fast
/// through the wide BVH). Only at an exact tie (a camera ray through the edge two triangles
/// share) may a sample see the other primitive than [`trace_sample`] does, at the same
/// distance.
pub fn trace_pixel<const F: u32>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    window: LightWindow,
    stats: &mut SampleStats,
    add: &mut dyn FnMut(Vec3, &FirstHit),
) {
    let frame = &scene.frame;
    let pixel = y * frame.width + x;
    let batches = batch::batches::<F>(scene);
    let mut start = samples.start;
    while start < samples.end {
        let count = (samples.end - start).min(BATCH as u32) as usize;
        // Placeholders, each set below (hashing a stream here would be wasted).
        let mut rngs = [Rng::with_key(0, 0, pixel, start); BATCH];
        let mut cameras = [CameraRay::default(); BATCH];
        if batches && count == BATCH {
            batch::camera_samples::<F>(scene, x, y, start, &mut rngs, &mut cameras);
        } else {
            for k in 0..count {
                let sample = start + k as u32;
                rngs[k] = Rng::new(frame.seed, pixel, sample);
                cameras[k] =
                    camera_sample::<F>(scene, x, y, sample, &mut rngs[k], &mut stats.flags);
            }
        }
        let mut queries = [RayQuery::default(); BATCH];
        for k in 0..count {
            let ray = cameras[k].ray;
            queries[k] = RayQuery::new(ray.origin, ray.direction).at_time(cameras[k].time);
        }
        let mut hits = [None; BATCH];
        scene
            .tracer()
            .closest_hits::<F>(&queries[..count], T_FAR, &mut hits[..count]);
        for k in 0..count {
            let mut first_hit = FirstHit::default();
            let camera = cameras[k];
            let radiance = trace_path::<F>(
                scene,
                camera.ray,
                CameraHit::Known(hits[k]),
                camera.time,
                window,
                &mut rngs[k],
                stats,
                &mut first_hit,
            );
            add(radiance * camera.counts_for(), &first_hit);
        }
        start += count as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pack::flatten;
    use crate::scene::sample_scene;

    /// Each sample [`trace_pixel`] traces (camera rays in packets) has the radiance and first
    /// hit [`trace_sample`] gives it alone, bit for bit but at a tie: on triangles (packed
    /// octets), quads and spheres, through a lens, with motion blur (one ray at a time in
    /// leaves that are not packed), and path traced, over ranges that do not start at 0 or
    /// fill the last packet.
    #[test]
    fn a_pixels_samples_traced_in_packets_are_those_traced_alone() {
        let cases: [(&str, &[&str]); 6] = [
            ("bunny.toml", &[]),
            // Path traced: bounces, Russian roulette, multiple importance sampling.
            (
                "cornell_box.toml",
                &[
                    "render.integrator=\"path\"",
                    "render.max_depth=4",
                    "render.rr_depth=2",
                ],
            ),
            (
                "tabletop.toml",
                &[
                    "render.integrator=\"path\"",
                    "render.ambient=[0,0,0]",
                    "render.max_depth=3",
                ],
            ),
            ("cornell_direct.toml", &[]),
            ("thin_lens.toml", &[]),
            (
                "tabletop.toml",
                &[
                    "shapes[2].velocity=[0.3,0.0,0.1]",
                    "camera.shutter=[0.0,1.0]",
                ],
            ),
        ];
        for (name, overrides) in cases {
            let mut scene = sample_scene(name, overrides);
            scene.render.width = 24;
            scene.render.height = 16;
            let flat = flatten(&scene);
            let (mut samples, mut differing) = (0, 0);
            for y in 0..flat.frame.height {
                for x in 0..flat.frame.width {
                    let range = 3..3 + 13;
                    let mut packed = Vec::new();
                    let mut stats = SampleStats::default();
                    trace_pixel::<FEATURES_ALL>(
                        &flat,
                        x,
                        y,
                        range.clone(),
                        LightWindow::ALL,
                        &mut stats,
                        &mut |radiance, hit| packed.push((radiance, *hit)),
                    );
                    let mut alone_stats = SampleStats::default();
                    for (k, sample) in range.enumerate() {
                        let mut hit = FirstHit::default();
                        let radiance = trace_sample::<FEATURES_ALL>(
                            &flat,
                            x,
                            y,
                            sample,
                            LightWindow::ALL,
                            &mut alone_stats,
                            &mut hit,
                        );
                        samples += 1;
                        if packed[k] != (radiance, hit) {
                            // Only a tie may differ: the same distance, another primitive.
                            assert_eq!(packed[k].1.depth, hit.depth, "{name} ({x}, {y}) {sample}");
                            differing += 1;
                        }
                    }
                    assert_eq!(stats, alone_stats, "{name} ({x}, {y})");
                }
            }
            assert_eq!(samples, 24 * 16 * 13);
            assert!(differing <= 2, "{name}: {differing} samples differ");
        }
    }
}
