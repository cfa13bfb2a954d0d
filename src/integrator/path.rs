//! The path tracer: one camera sample -> radiance, with global illumination. Twin: the path
//! tracer's branch of `wf_shade` in `wgsl/wavefront.wgsl`, with `wgsl/bsdf.wgsl`.
//!
//! At each vertex: emission (weighted against the light samples that could have drawn the same
//! point, multiple importance sampling with the power heuristic), direct light through the same
//! shadow rays as Whitted's integrator (each light sample weighted against the BSDF), then one
//! direction drawn from the BSDF (`bsdf`), which Russian roulette may end from vertex
//! `rr_depth` on. After `max_depth` bounces the path takes one more, as Mitsuba's does, only to
//! see the emission its BSDF sample hits (the other half of the last vertex's multiple
//! importance sampling): `max_depth = 0` is direct light. Escaping rays see the background (a
//! constant no light samples) and the lights at infinity (an environment, suns), weighted
//! against their light samples as emitters are. Equations and choices: `docs/path.md`,
//! `docs/lights.md`.
//!
//! The bounce's throughput factor is kept apart from the throughput until the next vertex, as
//! the GPU's wavefront render must keep it (its shadow rays are resolved after the bounce is
//! drawn, with the throughput they were cast with): the same products in the same order.

use std::mem::MaybeUninit;

use glam::Vec3;

use super::bsdf::{BsdfSample, Lobes, emitter_hit_weight, lobes, sample_bsdf};
use super::{
    CameraHit, FirstHit, LightWindow, SampleStats, Surface, Vertex, direct_light, sky_seen,
    vertex_at, vertex_hit,
};
use crate::accel::intersect::{RayQuery, offset_ray_origin};
use crate::camera::Ray;
use crate::layout::*;
use crate::math::rng::Rng;
use crate::pack::FlatScene;
use crate::sampler::{PatternSource, sample_2d};

/// The first random dimension of the path tracer's draws at vertex `depth`: the pairs after
/// its light samples (`layout::BSDF_PAIR`, `ROULETTE_PAIR`).
pub(super) fn bsdf_dimension(frame: &GpuFrame, depth: u32) -> u32 {
    let pair = depth
        .wrapping_mul(frame.vertex_dimension_pairs)
        .wrapping_add(frame.light_samples_per_vertex)
        .wrapping_add(BSDF_PAIR);
    LIGHT_DIMENSION.wrapping_add(pair.wrapping_mul(2))
}

/// The dimension whose number chooses the area light path vertex `depth` samples
/// (`layout::CHOICE_PAIR`).
pub(super) fn choice_dimension(frame: &GpuFrame, depth: u32) -> u32 {
    bsdf_dimension(frame, depth).wrapping_add(2 * (CHOICE_PAIR - BSDF_PAIR))
}

/// An emitting primitive's area, as its light's samples see it (a triangle light's is half
/// the parallelogram of its edges).
pub(super) fn emitter_area(prim: &GpuPrimitive) -> f32 {
    let (p0, p1, p2) = (
        Vec3::from(prim.p0),
        Vec3::from(prim.p1),
        Vec3::from(prim.p2),
    );
    match prim.kind {
        PRIM_TRIANGLE => 0.5 * (p1 - p0).cross(p2 - p0).length(),
        _ => p1.cross(p2).length(),
    }
}

/// The weight of the emission a ray from `origin` sees at `surface` of primitive `prim`, drawn
/// with density `bsdf_pdf` (0: a camera or mirror ray), against the samples a vertex takes of
/// its light on average: the light's samples times the probability a vertex chooses it.
pub(super) fn emission_weight(
    frame: &GpuFrame,
    prim: &GpuPrimitive,
    material: &GpuMaterial,
    surface: &Surface,
    origin: Vec3,
    direction: Vec3,
    bsdf_pdf: f32,
) -> f32 {
    if material.light_samples == 0 || bsdf_pdf <= 0.0 {
        return 1.0;
    }
    let distance2 = (surface.position - origin).length_squared();
    let cos_light = -surface.geometric_normal.dot(direction);
    let area = emitter_area(prim);
    let share = frame.light_choice_probability(material.emission, area);
    emitter_hit_weight(
        share * material.light_samples as f32,
        distance2,
        cos_light,
        area,
        bsdf_pdf,
    )
}

/// Where a bounce's ray starts (offset to the side it leaves on: a reflected ray from the
/// vertex's own `origin`) and the primitive it skips: a ray refracted into a sphere or an
/// ellipsoid must meet it again from inside.
pub(super) fn leaving(
    prim: &GpuPrimitive,
    prim_id: u32,
    vertex: &Vertex,
    transmitted: bool,
) -> (Vec3, u32) {
    let surface = vertex.surface;
    let (origin, outside) = match transmitted {
        true => {
            let inside = -surface.geometric_normal;
            let origin = offset_ray_origin(surface.position, surface.position_error, inside);
            (origin, !surface.front_facing)
        }
        false => (vertex.origin, surface.front_facing),
    };
    let skip = match leaving_rays_skip(prim.kind, outside) {
        true => prim_id,
        false => NONE,
    };
    (origin, skip)
}

/// The pixel pattern the first bounce's direction takes its points from, as the lens and the
/// shutter do (their own permutation of the pixel's strata, keyed by the dimension, so the
/// camera rays' and the bounces' strata are independent): the bounces off a pixel's first hits
/// then cover the hemisphere evenly. An interleaved pattern is the same for every dimension of
/// a pixel, so it would tie the bounce to the pixel position: those bounces draw at random.
pub(super) fn first_bounce_pattern(frame: &GpuFrame) -> Option<PatternSource> {
    (frame.pixel_sampler != SAMPLER_INTERLEAVED).then(|| PatternSource {
        dim: bsdf_dimension(frame, 0),
        ..PatternSource::pixel(frame)
    })
}

/// The bounce that leaves vertex `depth` of a path with throughput `throughput`: the BSDF's
/// direction and the factor the throughput takes at the next vertex, divided by Russian
/// roulette's odds of going on from vertex `rr_depth`; none where the path ends there.
#[allow(clippy::too_many_arguments)]
pub(super) fn bounce(
    scene: &FlatScene,
    material: &GpuMaterial,
    lobes: &Lobes,
    surface: &Surface,
    wo: Vec3,
    depth: u32,
    throughput: Vec3,
    rng: &mut Rng,
    flags: &mut u32,
) -> Option<BsdfSample> {
    let frame = &scene.frame;
    let dim = bsdf_dimension(frame, depth);
    rng.seek(dim);
    let u = match (depth, first_bounce_pattern(frame)) {
        (0, Some(source)) => {
            let (x, y) = (rng.pixel % frame.width, rng.pixel / frame.width);
            let table = &scene.sample_table;
            sample_2d(frame, table, source, x, y, rng.sample, rng, flags)
        }
        _ => rng.next_2d(),
    };
    rng.seek(dim + 2 * (ROULETTE_PAIR - BSDF_PAIR));
    let [u_lobe, u_roulette] = rng.next_2d();
    let n = surface.shading_normal;
    let ng = surface.geometric_normal;
    let mut sample = sample_bsdf(material, lobes, n, ng, wo, surface.front_facing, u, u_lobe)?;
    if depth >= frame.rr_depth {
        let survival = (throughput * sample.weight).max_element().min(0.95);
        if u_roulette >= survival {
            return None;
        }
        sample.weight /= survival;
    }
    Some(sample)
}

/// The vertex past `max_depth` is there only to see emission: where its primitive's material
/// emits nothing and has no texture (which could change whether it reflects), the path ends
/// there without the surface's geometry (most of the last bounces of a lit interior meet a
/// wall). Whether the material still reflects (the path was cut off), or none where the
/// vertex needs its surface.
fn dark_last_vertex(scene: &FlatScene, prim_id: u32) -> Option<bool> {
    let material = &scene.materials[scene.prims[prim_id as usize].material as usize];
    let dark = material.texture == 0 && Vec3::from(material.emission).max_element() <= 0.0;
    dark.then(|| material.model != MODEL_EMITTER && lobes(material).reflect(material.model))
}

/// Radiance along one path that starts with `camera_ray` (whose closest hit `camera_hit` may
/// already know), as `super::trace_path` but with bounces of every kind.
#[allow(clippy::too_many_arguments)]
pub(super) fn trace_path<const F: u32>(
    scene: &FlatScene,
    camera_ray: Ray,
    camera_hit: CameraHit,
    time: f32,
    window: LightWindow,
    rng: &mut Rng,
    stats: &mut SampleStats,
    first_hit: &mut FirstHit,
) -> Vec3 {
    let first = window.is_first();
    let frame = &scene.frame;
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let mut bounce_weight = Vec3::ONE;
    let mut bsdf_pdf = 0.0;
    let mut ray = RayQuery::new(camera_ray.origin, camera_ray.direction).at_time(time);
    let mut skip = NONE;
    for depth in 0..=frame.max_depth + 1 {
        throughput *= bounce_weight;
        let Some((prim_id, hit)) = vertex_hit::<F>(scene, &ray, skip, depth, camera_hit, stats)
        else {
            if first {
                radiance += throughput * Vec3::from(frame.background);
                radiance += throughput * sky_seen::<F>(scene, ray.direction, bsdf_pdf);
            }
            break;
        };
        if depth > frame.max_depth
            && let Some(reflects) = dark_last_vertex(scene, prim_id)
        {
            stats.truncated += u64::from(first && reflects);
            break;
        }
        let mut textured = MaybeUninit::uninit();
        let (prim, material, surface) =
            vertex_at(scene, prim_id, &ray, hit, depth, first_hit, &mut textured);
        let emission = Vec3::from(material.emission);
        if first && surface.front_facing && emission.max_element() > 0.0 {
            let weight = emission_weight(
                frame,
                prim,
                material,
                &surface,
                ray.origin,
                ray.direction,
                bsdf_pdf,
            );
            radiance += throughput * emission * weight;
        }
        if material.model == MODEL_EMITTER {
            break;
        }
        let lobes = lobes(material);
        if depth > frame.max_depth {
            if first && lobes.reflect(material.model) {
                stats.truncated += 1;
            }
            break;
        }
        let wo = -ray.direction;
        let own = match leaving_rays_skip(prim.kind, surface.front_facing) {
            true => prim_id,
            false => NONE,
        };
        let vertex = Vertex::new(&surface, material, Some(lobes), wo, depth, time, own);
        // A material of deltas alone (a mirror, glass) meets no light sample.
        if lobes.smooth() {
            radiance += throughput * direct_light::<F>(scene, &vertex, window, rng, stats);
        }
        let flags = &mut stats.flags;
        let sample = bounce(
            scene, material, &lobes, &surface, wo, depth, throughput, rng, flags,
        );
        let Some(sample) = sample else {
            break;
        };
        bounce_weight = sample.weight;
        bsdf_pdf = sample.pdf;
        let (origin, skipped) = leaving(prim, prim_id, &vertex, sample.transmitted);
        ray = RayQuery::new(origin, sample.wi).at_time(time);
        skip = skipped;
    }
    radiance
}
