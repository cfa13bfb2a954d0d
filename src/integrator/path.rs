//! The path tracer: one camera sample -> radiance, with global illumination. Twin: the path
//! tracer's branch of `wf_shade` in `wgsl/wavefront.wgsl`, with `wgsl/bsdf.wgsl`.
//!
//! At each vertex: emission (weighted against the light samples that could have drawn the same
//! point, multiple importance sampling with the power heuristic), direct light through the same
//! shadow rays as Whitted's integrator (each light sample weighted against the BSDF), then one
//! direction drawn from the BSDF (`bsdf`), which Russian roulette may end from vertex
//! `rr_depth` on. After `max_depth` bounces the path takes one more, as Mitsuba's does, only to
//! see the emission its BSDF sample hits (the other half of the last vertex's multiple
//! importance sampling): `max_depth = 0` is direct light. Where few primitives emit, that
//! ray is tested against them and then, if it meets one, for what lies before it: most last
//! rays meet a wall, which a closest hit found at the cost of a traversal. Escaping rays see the background (a
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
    CameraHit, FirstHit, LightWindow, SampleStats, Surface, Vertex, direct_light, moved_surface_at,
    sky_seen, vertex_at, vertex_hit,
};
use crate::accel::intersect::{RayQuery, intersect_box, intersect_primitive, offset_ray_origin};
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

/// What the emitting `surface` of primitive `prim` and `material` (if it emits, and from its
/// front) adds to `radiance` with `throughput`, seen along `ray` drawn with density
/// `bsdf_pdf` ([`emission_weight`]).
// Inlined: at every vertex of the path loop, a call passing the surface through memory would
// cost more than the test it makes.
#[inline(always)]
fn add_emission(
    frame: &GpuFrame,
    (prim, material, surface): (&GpuPrimitive, &GpuMaterial, &Surface),
    ray: &RayQuery,
    bsdf_pdf: f32,
    throughput: Vec3,
    radiance: &mut Vec3,
) {
    let emission = Vec3::from(material.emission);
    if surface.front_facing && emission.max_element() > 0.0 {
        let (origin, direction) = (ray.origin, ray.direction);
        let weight = emission_weight(frame, prim, material, surface, origin, direction, bsdf_pdf);
        *radiance += throughput * emission * weight;
    }
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

/// Up to this many emitting primitives, the path's last ray is tested against each of them
/// instead of traced through the BVH ([`last_ray_seen`]).
const FEW_EMITTERS: usize = 8;

/// What the path's ray past `max_depth` (there only to see emission, module docs) adds to
/// `radiance` with `throughput`, found without its closest hit where the scene has few
/// emitters and nothing moves: the nearest emitter along the ray, then whether anything lies
/// before it (an any-hit query); where no emitter lies along it, whether it escapes to the
/// background and the lights at infinity, asked only where they shine. Most last rays of a
/// lit interior meet a wall, which the closest hit found at the cost of a traversal. The same
/// radiance as the traced ray finds, in the same operations, but at an exact tie (another
/// primitive at the emitter's very distance, which the closest hit may pick). False where the
/// ray must be traced.
fn last_ray_seen<const F: u32>(
    scene: &FlatScene,
    ray: &RayQuery,
    skip: u32,
    bsdf_pdf: f32,
    throughput: Vec3,
    radiance: &mut Vec3,
) -> bool {
    let frame = &scene.frame;
    if scene.emitters.len() > FEW_EMITTERS || frame.motion_base != 0 {
        return false;
    }
    let tracer = scene.tracer();
    let mut nearest = None;
    let mut t_max = T_FAR;
    let emitters = match scene.emitter_bounds {
        Some([lo, hi]) if intersect_box(ray, lo, hi, T_FAR) >= T_FAR => &[][..],
        _ => &scene.emitters[..],
    };
    for &id in emitters.iter().filter(|&&id| id != skip) {
        let hit = intersect_primitive::<F>(ray, &scene.prims[id as usize], t_max);
        if hit.t < t_max {
            t_max = hit.t;
            nearest = Some((id, hit));
        }
    }
    match nearest {
        Some((id, hit)) if !tracer.occluded::<F>(ray, skip, id, hit.t) => {
            let prim = &scene.prims[id as usize];
            let material = &scene.materials[prim.material as usize];
            let surface = moved_surface_at(scene, id, ray, hit);
            add_emission(
                frame,
                (prim, material, &surface),
                ray,
                bsdf_pdf,
                throughput,
                radiance,
            );
        }
        Some(_) => {}
        None => {
            let background = Vec3::from(frame.background);
            let sky = sky_seen::<F>(scene, ray.direction, bsdf_pdf);
            let shines = background.max_element() > 0.0 || sky.max_element() > 0.0;
            if shines && !tracer.occluded::<F>(ray, skip, NONE, T_FAR) {
                *radiance += throughput * background;
                *radiance += throughput * sky;
            }
        }
    }
    true
}

/// Whether the path's vertex past `max_depth` on primitive `prim_id` ends without its surface:
/// its material emits nothing and has no texture, so it adds nothing (module docs).
fn dark_last_vertex(scene: &FlatScene, prim_id: u32) -> bool {
    let material = &scene.materials[scene.prims[prim_id as usize].material as usize];
    material.texture == 0 && Vec3::from(material.emission).max_element() <= 0.0
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
        if depth > frame.max_depth && !first {
            // The last ray only sees emission, which the first window alone adds.
            stats.rays += 1;
            break;
        }
        if depth > frame.max_depth
            && last_ray_seen::<F>(scene, &ray, skip, bsdf_pdf, throughput, &mut radiance)
        {
            stats.rays += 1;
            break;
        }
        let Some((prim_id, hit)) = vertex_hit::<F>(scene, &ray, skip, depth, camera_hit, stats)
        else {
            if first {
                radiance += throughput * Vec3::from(frame.background);
                radiance += throughput * sky_seen::<F>(scene, ray.direction, bsdf_pdf);
            }
            break;
        };
        if depth > frame.max_depth && dark_last_vertex(scene, prim_id) {
            break;
        }
        let mut textured = MaybeUninit::uninit();
        let (prim, material, surface) =
            vertex_at(scene, prim_id, &ray, hit, depth, first_hit, &mut textured);
        if first {
            let seen = (prim, material, &surface);
            add_emission(frame, seen, &ray, bsdf_pdf, throughput, &mut radiance);
        }
        if material.model == MODEL_EMITTER {
            break;
        }
        if depth > frame.max_depth {
            break;
        }
        let lobes = lobes(material);
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
        // Cut off while it still reflects: the path would go on (as Whitted's mirror bounce
        // at max_depth counts).
        if depth == frame.max_depth && first {
            stats.truncated += 1;
        }
        bounce_weight = sample.weight;
        bsdf_pdf = sample.pdf;
        let (origin, skipped) = leaving(prim, prim_id, &vertex, sample.transmitted);
        ray = RayQuery::new(origin, sample.wi).at_time(time);
        skip = skipped;
    }
    radiance
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pack::flatten;
    use crate::scene::sample_scene;

    /// What the last ray adds when traced, as `trace_path`'s loop found it before
    /// [`last_ray_seen`]: its closest hit's emission, or the background and the lights at
    /// infinity where it escapes.
    fn traced(scene: &FlatScene, ray: &RayQuery, skip: u32, bsdf_pdf: f32) -> Vec3 {
        let throughput = Vec3::new(0.7, 0.5, 0.3);
        let mut radiance = Vec3::new(0.01, 0.02, 0.03);
        let Some((id, hit)) = scene.tracer().closest_hit::<FEATURES_ALL>(ray, skip, T_FAR) else {
            radiance += throughput * Vec3::from(scene.frame.background);
            radiance += throughput * sky_seen::<FEATURES_ALL>(scene, ray.direction, bsdf_pdf);
            return radiance;
        };
        let prim = &scene.prims[id as usize];
        let material = &scene.materials[prim.material as usize];
        let surface = moved_surface_at(scene, id, ray, hit);
        let seen = (prim, material, &surface);
        add_emission(&scene.frame, seen, ray, bsdf_pdf, throughput, &mut radiance);
        radiance
    }

    /// The last ray tested against the few emitters adds what the traced ray adds, bit for
    /// bit, whether it meets an emitter, meets one behind something, grazes one's edge (the
    /// rim of the box that passes over them), leaves an emitter (which it skips), or escapes
    /// to a background or a sky map; rays from points inside the scenes, every way.
    #[test]
    fn the_last_ray_tested_against_the_emitters_adds_what_the_traced_ray_adds() {
        let cases: [(&str, &[&str], [Vec3; 2]); 2] = [
            (
                "cornell_box.toml",
                &[
                    "render.integrator=\"path\"",
                    "render.background=[0.2,0.3,0.4]",
                ],
                [Vec3::new(-0.9, 0.1, -0.9), Vec3::new(0.9, 1.97, 1.5)],
            ),
            (
                "sky.toml",
                &[],
                [Vec3::new(-3.0, 0.1, -2.0), Vec3::new(3.0, 2.0, 2.0)],
            ),
        ];
        for (name, overrides, [low, high]) in cases {
            let scene = flatten(&sample_scene(name, overrides));
            assert!(scene.emitters.len() <= FEW_EMITTERS, "{name}");
            let mut rng = Rng::new(11, 0, 0);
            let (mut lit, mut escaped) = (0, 0);
            for i in 0..20_000 {
                let [a, b] = rng.next_2d();
                let c = rng.next_f32();
                let origin = low + (high - low) * Vec3::new(a, b, c);
                let [u, v] = rng.next_2d();
                let z = 1.0 - 2.0 * u;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * std::f32::consts::PI * v;
                let mut direction = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                // Every third ray aims at a point on an emitter's edge, where a hit is on the
                // rim of the emitters' box.
                if let (1, Some(&id)) = (i % 3, scene.emitters.get(i % 7)) {
                    let prim = &scene.prims[id as usize];
                    let (p0, p1) = (Vec3::from(prim.p0), Vec3::from(prim.p1));
                    let rim = match prim.kind {
                        PRIM_QUAD => p0 + u * p1,
                        _ => p0 + u * (p1 - p0),
                    };
                    direction = (rim - origin).normalize();
                }
                let ray = RayQuery::new(origin, direction);
                // Every fourth ray leaves an emitter, as a bounce off an emitting surface does.
                let skip = match (i % 4, scene.emitters.first()) {
                    (0, Some(&id)) => id,
                    _ => NONE,
                };
                let bsdf_pdf = [0.0, 0.4][i % 2];
                let expected = traced(&scene, &ray, skip, bsdf_pdf);
                let throughput = Vec3::new(0.7, 0.5, 0.3);
                let mut radiance = Vec3::new(0.01, 0.02, 0.03);
                assert!(last_ray_seen::<FEATURES_ALL>(
                    &scene,
                    &ray,
                    skip,
                    bsdf_pdf,
                    throughput,
                    &mut radiance
                ));
                assert_eq!(
                    radiance.to_array().map(f32::to_bits),
                    expected.to_array().map(f32::to_bits),
                    "{name}: ray {i} from {origin} along {direction}: {radiance} against {expected}"
                );
                let missed = scene
                    .tracer()
                    .closest_hit::<FEATURES_ALL>(&ray, skip, T_FAR)
                    .is_none();
                escaped += missed as u32;
                lit += (!missed && expected != Vec3::new(0.01, 0.02, 0.03)) as u32;
            }
            // Both branches are exercised: rays that meet a light, rays that escape.
            assert!(escaped > 100, "{name}: {escaped} escaped");
            if !scene.emitters.is_empty() {
                assert!(lit > 100, "{name}: {lit} met a light");
            }
        }
    }
}
