//! A pixel's camera samples eight at a time, for the common cameras: a perspective one with an
//! instant shutter, a plane of focus, and random or stratified pixel and lens points with a
//! power-of-two sample count (any count under adaptive sampling's progressive stratification)
//! (the aperture's shape is drawn lane by lane with the scalar function). Each step of [`camera_sample`](super::camera_sample) (the random stream's keys and
//! draws, the strata's permutation, the film position, the thin lens, the ray) runs as a loop over the eight
//! lanes with the scalar code's operations in its order, which the compiler turns into 8-wide
//! vector instructions (AVX2 where the CPU has it); so each lane's ray is `camera_sample`'s, bit
//! for bit (`tests` below). The scalar code chains a division, a square root and another
//! division per ray and waits on each; eight lanes wait once.

use glam::Vec3;

use super::CameraRay;
use crate::camera::Ray;
use crate::layout::{
    FEATURE_LENS, FOCUS_PLANE, LENS_DIMENSION, PIXEL_DIMENSION, PROJECTION_PERSPECTIVE,
    SAMPLER_RANDOM, SAMPLER_STRATIFIED, has,
};
use crate::math::rng::{Rng, draw_bits, stream_key};
use crate::pack::FlatScene;
use crate::sampler::{
    permute_round, pixel_hash, progressive_stratified, sample_aperture, unit_float,
};

/// Camera samples drawn together: one per lane of an AVX2 vector.
pub const BATCH: usize = 8;

/// Whether [`camera_samples`] takes the scene's camera samples eight at a time (else they are
/// drawn one by one).
pub fn batches<const F: u32>(scene: &FlatScene) -> bool {
    let (frame, camera) = (&scene.frame, &scene.camera);
    let lens = has(F, FEATURE_LENS) && camera.lens_radius_mm > 0.0;
    let pattern = |sampler: u32, columns: u32| match sampler {
        SAMPLER_RANDOM => true,
        SAMPLER_STRATIFIED => {
            frame.progressive != 0 || (frame.spp.is_power_of_two() && columns.is_power_of_two())
        }
        _ => false,
    };
    pattern(frame.pixel_sampler, frame.pixel_strata_columns)
        && (!lens || pattern(frame.lens_sampler, frame.lens_strata_columns))
        && camera.shutter_span == 0.0
        && camera.focus_surface == FOCUS_PLANE
        && camera.projection == PROJECTION_PERSPECTIVE
}

/// Camera samples `first..first + BATCH` of pixel (x, y) and their random streams, as
/// [`camera_sample`](super::camera_sample) draws each (the streams left where it leaves
/// them); the scene must be one that [`batches`].
pub fn camera_samples<const F: u32>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; BATCH],
    cameras: &mut [CameraRay; BATCH],
) {
    // The lens's code is compiled in only where there is a lens.
    let lens = has(F, FEATURE_LENS) && scene.camera.lens_radius_mm > 0.0;
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        return unsafe {
            match lens {
                true => camera_samples_avx2::<true>(scene, x, y, first, rngs, cameras),
                false => camera_samples_avx2::<false>(scene, x, y, first, rngs, cameras),
            }
        };
    }
    match lens {
        true => camera_samples_lanes::<true>(scene, x, y, first, rngs, cameras),
        false => camera_samples_lanes::<false>(scene, x, y, first, rngs, cameras),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn camera_samples_avx2<const LENS: bool>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; BATCH],
    cameras: &mut [CameraRay; BATCH],
) {
    camera_samples_lanes::<LENS>(scene, x, y, first, rngs, cameras)
}

/// `sample_2d`'s random or stratified point for each lane from dimensions `dim` and `dim + 1`
/// of its stream (`keys`), the pattern's columns `columns`: with a power-of-two sample count
/// the permutation's walk ends at its first round and the strata's divisions are shifts; the
/// progressive stratified pattern of an adaptive render takes any count.
#[inline(always)]
fn pattern_lanes(
    scene: &FlatScene,
    pixel: u32,
    (sampler, columns, dim): (u32, u32, u32),
    keys: &[u32; BATCH],
    samples: &[u32; BATCH],
) -> [[f32; 2]; BATCH] {
    let frame = &scene.frame;
    let mut u = [[0.0f32; 2]; BATCH];
    for k in 0..BATCH {
        u[k] = [
            unit_float(draw_bits(keys[k], dim)),
            unit_float(draw_bits(keys[k], dim + 1)),
        ];
    }
    if sampler == SAMPLER_STRATIFIED && frame.progressive != 0 {
        let key = pixel_hash(frame.seed, pixel, dim);
        for k in 0..BATCH {
            u[k] = progressive_stratified(samples[k], frame.spp, key, u[k]);
        }
    } else if sampler == SAMPLER_STRATIFIED {
        let key = pixel_hash(frame.seed, pixel, dim);
        let w = frame.spp - 1;
        let shift = columns.trailing_zeros();
        let rows = frame.spp >> shift;
        for k in 0..BATCH {
            let stratum = permute_round(samples[k], w, key).wrapping_add(key) & w;
            let (cy, cx) = (stratum >> shift, stratum & (columns - 1));
            u[k] = [
                (cx as f32 + u[k][0]) * (1.0 / columns as f32),
                (cy as f32 + u[k][1]) * (1.0 / rows as f32),
            ];
        }
    }
    u
}

#[inline(always)]
fn camera_samples_lanes<const LENS: bool>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; BATCH],
    cameras: &mut [CameraRay; BATCH],
) {
    let (frame, camera) = (&scene.frame, &scene.camera);
    let pixel = y * frame.width + x;
    let samples = std::array::from_fn::<u32, BATCH, _>(|k| first + k as u32);
    let keys = samples.map(|sample| stream_key(frame.seed, pixel, sample));
    // `Rng::new`, then the pixel's point (dimensions 0 and 1) and the lens's (2 and 3).
    let pixel_pattern = (
        frame.pixel_sampler,
        frame.pixel_strata_columns,
        PIXEL_DIMENSION,
    );
    let u = pattern_lanes(scene, pixel, pixel_pattern, &keys, &samples);
    if LENS {
        let lens_pattern = (
            frame.lens_sampler,
            frame.lens_strata_columns,
            LENS_DIMENSION,
        );
        let points = pattern_lanes(scene, pixel, lens_pattern, &keys, &samples);
        let lens = points.map(|u| sample_aperture(camera, &scene.sample_table, u));
        rays_lanes::<true>(scene, x, y, &u, &lens, cameras);
        for k in 0..BATCH {
            rngs[k] = Rng::with_key(keys[k], LENS_DIMENSION + 2, pixel, samples[k]);
        }
    } else {
        rays_lanes::<false>(scene, x, y, &u, &[[0.0; 2]; BATCH], cameras);
        for k in 0..BATCH {
            rngs[k] = Rng::with_key(keys[k], LENS_DIMENSION, pixel, samples[k]);
        }
    }
}

/// `film_position_mm`, then `generate_ray`, for the lanes' pixel points `u` and lens points
/// `lens` (all zero unless `LENS`; without it the origin and the lens's term of the slope are
/// the same for every lane, computed once).
#[inline(always)]
fn rays_lanes<const LENS: bool>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    u: &[[f32; 2]; BATCH],
    lens: &[[f32; 2]; BATCH],
    cameras: &mut [CameraRay; BATCH],
) {
    let (frame, camera) = (&scene.frame, &scene.camera);
    let centre = Vec3::from(camera.film_center);
    let (film_u, film_v) = (Vec3::from(camera.film_u), Vec3::from(camera.film_v));
    let lens_centre = Vec3::from(camera.lens_center);
    let to_world = [
        Vec3::from(camera.lens_to_world_x),
        Vec3::from(camera.lens_to_world_y),
        Vec3::from(camera.lens_to_world_z),
    ];
    let turn = |v: [f32; 3]| {
        [0, 1, 2].map(|a| v[0] * to_world[0][a] + v[1] * to_world[1][a] + v[2] * to_world[2][a])
    };
    // `lens_mm.extend(0.0) * units_per_mm` taken to the world, and `lens_mm / f`.
    let origin_of = |lens: [f32; 2]| {
        let local = [lens[0], lens[1], 0.0].map(|c| c * camera.units_per_mm);
        lens_centre + Vec3::from(turn(local))
    };
    let bend = |lens: f32| lens * camera.inv_focal_length_mm;
    let (centre_origin, centre_bend) = (origin_of([0.0; 2]), bend(0.0));
    for k in 0..BATCH {
        let raster = [x as f32 + u[k][0], y as f32 + u[k][1]];
        let film = [
            (raster[0] / frame.width as f32 - 0.5) * camera.film_width_mm,
            (0.5 - raster[1] / frame.height as f32) * camera.film_height_mm,
        ];
        let point = [0, 1, 2].map(|a| centre[a] + film[0] * film_u[a] + film[1] * film_v[a]);
        // The thin lens: outgoing slope = incoming slope - h / f.
        let slope = [0, 1].map(|a| {
            let h = lens[k][a];
            (h - point[a]) / -point[2] - if LENS { bend(h) } else { centre_bend }
        });
        let d = [slope[0], slope[1], 1.0];
        let recip = 1.0 / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        cameras[k] = CameraRay {
            ray: Ray {
                origin: if LENS {
                    origin_of(lens[k])
                } else {
                    centre_origin
                },
                direction: Vec3::from(turn(d.map(|c| c * recip))),
            },
            time: camera.shutter_open,
            weight: 1.0,
            wavelength_nm: 0.0,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::camera_sample;
    use crate::layout::FEATURES_ALL;
    use crate::pack::flatten;
    use crate::scene::sample_scene;

    /// Every lane's ray, time and stream equal `camera_sample`'s bit for bit, through both
    /// builds, for the scenes' cameras (film tilt, swing, shift) and both patterns (and the
    /// progressive stratified one of adaptive sampling).
    #[test]
    fn eight_camera_samples_are_the_scalar_ones() {
        let cases: [(&str, &[&str]); 8] = [
            ("cornell_direct.toml", &[]),
            // Adaptive sampling's progressive stratification, at a count no power of two.
            (
                "thin_lens.toml",
                &["render.noise_target=0.05", "render.spp=24"],
            ),
            // A pinhole with film and lens movements.
            ("miniature.toml", &["camera.f_number=0"]),
            (
                "bunny.toml",
                &["render.pixel_sampler=\"random\"", "render.spp=8"],
            ),
            ("architecture.toml", &["render.spp=32"]),
            // A lens: a disk, tilted with the film moved, a hexagon; random and stratified.
            ("thin_lens.toml", &[]),
            ("miniature.toml", &["camera.lens_sampler=\"random\""]),
            ("bokeh.toml", &["render.spp=16"]),
        ];
        let mut batched = 0;
        for (name, overrides) in cases {
            let flat = flatten(&sample_scene(name, overrides));
            if !batches::<FEATURES_ALL>(&flat) {
                continue;
            }
            batched += 1;
            for (x, y) in [
                (0, 0),
                (17, 5),
                (flat.frame.width - 1, flat.frame.height - 1),
            ] {
                for first in (0..flat.frame.spp).step_by(BATCH) {
                    let mut rngs = [Rng::new(0, 0, 0); BATCH];
                    let mut cameras = [CameraRay::default(); BATCH];
                    let mut lanes_rngs = rngs;
                    let mut lanes_cameras = cameras;
                    camera_samples::<FEATURES_ALL>(&flat, x, y, first, &mut rngs, &mut cameras);
                    let (lanes_rngs_ref, lanes_cameras_ref) = (&mut lanes_rngs, &mut lanes_cameras);
                    match flat.camera.lens_radius_mm > 0.0 {
                        true => camera_samples_lanes::<true>(
                            &flat,
                            x,
                            y,
                            first,
                            lanes_rngs_ref,
                            lanes_cameras_ref,
                        ),
                        false => camera_samples_lanes::<false>(
                            &flat,
                            x,
                            y,
                            first,
                            lanes_rngs_ref,
                            lanes_cameras_ref,
                        ),
                    }
                    for k in 0..BATCH {
                        let sample = first + k as u32;
                        let mut rng = Rng::new(flat.frame.seed, y * flat.frame.width + x, sample);
                        let mut flags = 0;
                        let alone = camera_sample::<FEATURES_ALL>(
                            &flat, x, y, sample, &mut rng, &mut flags,
                        );
                        assert_eq!(flags, 0);
                        for (build, cameras, rngs) in [
                            ("vector", &cameras, &rngs),
                            ("lanes", &lanes_cameras, &lanes_rngs),
                        ] {
                            let what = format!("{name} ({x}, {y}) sample {sample}, {build}");
                            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                            assert_eq!(
                                bits(cameras[k].ray.origin),
                                bits(alone.ray.origin),
                                "{what}"
                            );
                            assert_eq!(
                                bits(cameras[k].ray.direction),
                                bits(alone.ray.direction),
                                "{what}"
                            );
                            assert_eq!(cameras[k].time.to_bits(), alone.time.to_bits(), "{what}");
                            // The streams go on alike.
                            let (mut a, mut b) = (rngs[k], rng);
                            assert_eq!(
                                (a.next_u32(), a.sample, a.pixel),
                                (b.next_u32(), b.sample, b.pixel),
                                "{what}"
                            );
                        }
                    }
                }
            }
        }
        assert_eq!(batched, 8, "every case's camera is one the batch takes");
    }

    /// An orthographic camera's parallel rays are drawn one by one, by `generate_ray`.
    #[test]
    fn an_orthographic_camera_is_not_batched() {
        let flat = flatten(&sample_scene("elevation.toml", &["render.spp=8"]));
        assert!(!batches::<FEATURES_ALL>(&flat));
    }
}
