//! A pixel's camera samples eight at a time, for the common camera: a pinhole (no lens point
//! drawn), an instant shutter, a plane of focus, and random or stratified pixel positions with a
//! power-of-two sample count. Each step of [`camera_sample`](super::camera_sample) (the random stream's keys and
//! draws, the stratum's permutation, the film position, the ray) runs as a loop over the eight
//! lanes with the scalar code's operations in its order, which the compiler turns into 8-wide
//! vector instructions (AVX2 where the CPU has it); so each lane's ray is `camera_sample`'s, bit
//! for bit (`tests` below). The scalar code chains a division, a square root and another
//! division per ray and waits on each; eight lanes wait once.

use glam::{Vec2, Vec3};

use super::CameraRay;
use crate::accel::wide::PACKET;
use crate::camera::{Ray, generate_ray};
use crate::layout::{
    FEATURE_LENS, FOCUS_PLANE, PIXEL_DIMENSION, SAMPLER_RANDOM, SAMPLER_STRATIFIED, has,
};
use crate::math::rng::{Rng, draw_bits, stream_key};
use crate::pack::FlatScene;
use crate::sampler::{permute_round, pixel_hash, unit_float};

/// Whether [`camera_samples`] takes the scene's camera samples eight at a time (else they are
/// drawn one by one).
pub fn batches<const F: u32>(scene: &FlatScene) -> bool {
    let (frame, camera) = (&scene.frame, &scene.camera);
    let lens = has(F, FEATURE_LENS) && camera.lens_radius_mm > 0.0;
    let pattern = match frame.pixel_sampler {
        SAMPLER_RANDOM => true,
        SAMPLER_STRATIFIED => {
            frame.spp.is_power_of_two() && frame.pixel_strata_columns.is_power_of_two()
        }
        _ => false,
    };
    !lens && camera.shutter_span == 0.0 && camera.focus_surface == FOCUS_PLANE && pattern
}

/// Camera samples `first..first + PACKET` of pixel (x, y) and their random streams, as
/// [`camera_sample`](super::camera_sample) draws each (the streams left where it leaves them); the scene must be one
/// that [`batches`].
pub fn camera_samples<const F: u32>(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; PACKET],
    cameras: &mut [CameraRay; PACKET],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        return unsafe { camera_samples_avx2(scene, x, y, first, rngs, cameras) };
    }
    camera_samples_lanes(scene, x, y, first, rngs, cameras)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn camera_samples_avx2(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; PACKET],
    cameras: &mut [CameraRay; PACKET],
) {
    camera_samples_lanes(scene, x, y, first, rngs, cameras)
}

#[inline(always)]
fn camera_samples_lanes(
    scene: &FlatScene,
    x: u32,
    y: u32,
    first: u32,
    rngs: &mut [Rng; PACKET],
    cameras: &mut [CameraRay; PACKET],
) {
    let (frame, camera) = (&scene.frame, &scene.camera);
    let pixel = y * frame.width + x;
    let lanes = std::array::from_fn::<u32, PACKET, _>(|k| first + k as u32);
    // `Rng::new`, then `next_2d`: dimensions 0 and 1.
    let keys = lanes.map(|sample| stream_key(frame.seed, pixel, sample));
    let mut u = [[0.0f32; 2]; PACKET];
    for k in 0..PACKET {
        u[k] = [
            unit_float(draw_bits(keys[k], 0)),
            unit_float(draw_bits(keys[k], 1)),
        ];
    }
    // `sample_2d`'s stratified pattern: a power-of-two count, so the permutation's walk ends
    // at its first round and the strata's divisions are shifts.
    if frame.pixel_sampler == SAMPLER_STRATIFIED {
        let key = pixel_hash(frame.seed, pixel, PIXEL_DIMENSION);
        let (n, columns) = (frame.spp, frame.pixel_strata_columns);
        let w = n - 1;
        let shift = columns.trailing_zeros();
        let rows = n >> shift;
        for k in 0..PACKET {
            let stratum = permute_round(lanes[k], w, key).wrapping_add(key) & w;
            let (cy, cx) = (stratum >> shift, stratum & (columns - 1));
            u[k] = [
                (cx as f32 + u[k][0]) * (1.0 / columns as f32),
                (cy as f32 + u[k][1]) * (1.0 / rows as f32),
            ];
        }
    }
    // `film_position_mm`, then `generate_ray` through the lens centre.
    let centre = Vec3::from(camera.film_center);
    let (film_u, film_v) = (Vec3::from(camera.film_u), Vec3::from(camera.film_v));
    let (to_x, to_y, to_z) = (
        Vec3::from(camera.lens_to_world_x),
        Vec3::from(camera.lens_to_world_y),
        Vec3::from(camera.lens_to_world_z),
    );
    let origin = generate_ray(camera, Vec2::ZERO, Vec2::ZERO).origin;
    let lens_term = 0.0 * camera.inv_focal_length_mm;
    for k in 0..PACKET {
        let raster = [x as f32 + u[k][0], y as f32 + u[k][1]];
        let film = [
            (raster[0] / frame.width as f32 - 0.5) * camera.film_width_mm,
            (0.5 - raster[1] / frame.height as f32) * camera.film_height_mm,
        ];
        let point = [0, 1, 2].map(|a| centre[a] + film[0] * film_u[a] + film[1] * film_v[a]);
        let slope = [0, 1].map(|a| (0.0 - point[a]) / -point[2] - lens_term);
        let d = [slope[0], slope[1], 1.0];
        let recip = 1.0 / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let d = d.map(|c| c * recip);
        let direction = [0, 1, 2].map(|a| d[0] * to_x[a] + d[1] * to_y[a] + d[2] * to_z[a]);
        cameras[k] = CameraRay {
            ray: Ray {
                origin,
                direction: Vec3::from(direction),
            },
            time: camera.shutter_open,
        };
        rngs[k] = Rng::with_key(keys[k], 2, pixel, lanes[k]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::camera_sample;
    use crate::layout::FEATURES_ALL;
    use crate::pack::flatten;
    use crate::scene::Scene;

    /// Every lane's ray, time and stream equal `camera_sample`'s bit for bit, through both
    /// builds, for the scenes' cameras (film tilt, swing, shift) and both patterns.
    #[test]
    fn eight_camera_samples_are_the_scalar_ones() {
        let cases: [(&str, &[&str]); 4] = [
            ("cornell_direct.toml", &[]),
            ("miniature.toml", &["camera.f_number=0"]),
            (
                "bunny.toml",
                &["render.pixel_sampler=\"random\"", "render.spp=8"],
            ),
            ("architecture.toml", &["render.spp=32"]),
        ];
        let mut batched = 0;
        for (name, overrides) in cases {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes")
                .join(name);
            let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            let flat = flatten(&Scene::load(&path, &overrides).unwrap());
            if !batches::<FEATURES_ALL>(&flat) {
                continue;
            }
            batched += 1;
            for (x, y) in [
                (0, 0),
                (17, 5),
                (flat.frame.width - 1, flat.frame.height - 1),
            ] {
                for first in (0..flat.frame.spp).step_by(PACKET) {
                    let mut rngs = [Rng::new(0, 0, 0); PACKET];
                    let mut cameras = [CameraRay::default(); PACKET];
                    let mut lanes_rngs = rngs;
                    let mut lanes_cameras = cameras;
                    camera_samples::<FEATURES_ALL>(&flat, x, y, first, &mut rngs, &mut cameras);
                    camera_samples_lanes(&flat, x, y, first, &mut lanes_rngs, &mut lanes_cameras);
                    for k in 0..PACKET {
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
        assert_eq!(batched, 4, "every case's camera is one the batch takes");
    }
}
