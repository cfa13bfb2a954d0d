//! Lights at infinity: the environment (a constant radiance, or an equirectangular map) and
//! the sun (a cone of uniform radiance). Twin: `wgsl/environment.wgsl`.
//!
//! A constant environment is sampled uniformly over the sphere, density 1 / (4 pi): the density
//! depends on the direction alone, so a BSDF ray that escapes gets its multiple-importance
//! weight from its own direction (the wavefront render keeps a path's BSDF density, not the
//! vertex it left), and a constant map's distribution is that same density. A map is sampled
//! by its texels' luminance times sin(theta) (`scene::environment`), texel by texel; a
//! direction's radiance is its texel's (nearest, no filtering), so the density a sample
//! reports and the density a lookup finds are the same piecewise-constant function. A sun is
//! sampled uniformly in its cone. Angles go through `sin_cos_turns`, polynomials after an exact
//! range reduction, so both paths draw the same directions. Equations: `docs/lights.md`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::tangents;
use crate::layout::{GpuLight, LIGHT_ENVIRONMENT, LIGHT_SUN};
use crate::math::sampling::{concentric_disk, cos_quarter, sin_quarter};

/// sin and cos of the angle `t` turns (2 pi t radians): reduced to the nearest quarter turn
/// and a remainder within pi/4, where the polynomials of `math::sampling` hold to 1e-8.
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    let t = t - t.floor();
    let quarter = (4.0 * t + 0.5).floor();
    let x = (t - 0.25 * quarter) * (2.0 * PI);
    let (s, c) = (sin_quarter(x), cos_quarter(x));
    match quarter as u32 {
        1 => (c, -s),
        2 => (-s, -c),
        3 => (-c, s),
        _ => (s, c),
    }
}

/// A direction uniform on the sphere from the unit square (density 1 / (4 pi)): the concentric
/// disk's squared radius r^2 is uniform, so y = 1 - 2 r^2 is, and the disk's angle is the
/// azimuth (Archimedes: a uniform height is a uniform point on the sphere).
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    let r2 = d[0] * d[0] + d[1] * d[1];
    let s = 2.0 * (1.0 - r2).max(0.0).sqrt();
    Vec3::new(d[0] * s, 1.0 - 2.0 * r2, d[1] * s)
}

/// The density of [`uniform_sphere`].
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// A direction an environment or a sun light sends light from: its radiance (before the
/// light's `color`) and the solid-angle density it was drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkySample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// Radiance along it, before the light's `color`.
    pub radiance: Vec3,
    /// Solid-angle density of drawing it.
    pub pdf: f32,
}

/// An environment map's size and where its parts lie in the packed array
/// (`EnvironmentMap::packed`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MapLayout {
    width: u32,
    height: u32,
    pdf: u32,
    marginal: u32,
    conditional: u32,
}

/// `light`'s map layout; width 0 for a constant environment.
fn map_layout(light: &GpuLight) -> MapLayout {
    let (width, height) = (light.p0[1] as u32, light.p0[2] as u32);
    let texels = width * height;
    MapLayout {
        width,
        height,
        pdf: 3 * texels,
        marginal: 4 * texels,
        conditional: 4 * texels + height + 1,
    }
}

/// The interval `i` of the `n`-interval CDF at `data[base..=base + n]` that `u` in [0, 1) falls
/// in (the last whose start is at most `u`: never an empty one), and where in it (in [0, 1)).
fn sample_cdf(data: &[f32], base: u32, n: u32, u: f32) -> (u32, f32) {
    let cdf = |i: u32| data[(base + i) as usize];
    let (mut lo, mut hi) = (0u32, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if cdf(mid) <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (start, end) = (cdf(lo), cdf(lo + 1));
    let offset = ((u - start) / (end - start)).clamp(0.0, 0.99999994);
    (lo, offset)
}

/// The map's radiance at texel (column, row).
fn texel(data: &[f32], map: &MapLayout, column: u32, row: u32) -> Vec3 {
    let k = 3 * (row * map.width + column) as usize;
    Vec3::new(data[k], data[k + 1], data[k + 2])
}

/// The unit direction at map coordinates (u, v) turned `turns` about +y, with sin(theta).
fn map_direction(u: f32, v: f32, turns: f32) -> (Vec3, f32) {
    let (sin_theta, cos_theta) = sin_cos_turns(0.5 * v);
    let (sin_phi, cos_phi) = sin_cos_turns(u + turns);
    (
        Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi),
        sin_theta,
    )
}

/// The solid-angle density of a map texel of (u, v) density `pdf_uv` at sin(theta):
/// (u, v) -> (phi, theta) scales areas by 2 pi^2, and d omega = sin(theta) d theta d phi.
fn map_solid_angle_pdf(pdf_uv: f32, sin_theta: f32) -> f32 {
    match sin_theta > 0.0 {
        true => pdf_uv / (2.0 * PI * PI * sin_theta),
        false => 0.0,
    }
}

/// A direction drawn from environment light `light` (whose map, if any, is `data`) with the
/// unit-square point `u`.
pub fn environment_sample(light: &GpuLight, data: &[f32], u: [f32; 2]) -> SkySample {
    let map = map_layout(light);
    if map.width == 0 {
        return SkySample {
            wi: uniform_sphere(u),
            radiance: Vec3::ONE,
            pdf: UNIFORM_SPHERE_PDF,
        };
    }
    let (row, dv) = sample_cdf(data, map.marginal, map.height, u[1]);
    let conditional = map.conditional + row * (map.width + 1);
    let (column, du) = sample_cdf(data, conditional, map.width, u[0]);
    let map_u = (column as f32 + du) / map.width as f32;
    let map_v = (row as f32 + dv) / map.height as f32;
    let (wi, sin_theta) = map_direction(map_u, map_v, light.p0[0]);
    let pdf_uv = data[(map.pdf + row * map.width + column) as usize];
    SkySample {
        wi,
        radiance: texel(data, &map, column, row),
        pdf: map_solid_angle_pdf(pdf_uv, sin_theta),
    }
}

/// The map coordinates (u, v) of unit direction `d` on a map turned `turns` about +y: u the
/// longitude from -z towards +x over 2 pi, v the angle from +y over pi: Mitsuba's and pbrt's
/// orientation, in which a map seen from inside the scene shows its image as it is (a
/// sphere's texture, seen from outside, runs the other way: `texture::sphere_coordinates`).
pub fn map_coordinates(d: Vec3, turns: f32) -> (f32, f32) {
    let u = d.x.atan2(-d.z) / (2.0 * PI) - turns;
    let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
    (u - u.floor(), sin_theta.atan2(d.y) / PI)
}

/// The radiance (before `color`) environment light `light` sends from unit direction `d`
/// towards the scene, and the density with which [`environment_sample`] draws `d`.
pub fn environment_radiance(light: &GpuLight, data: &[f32], d: Vec3) -> (Vec3, f32) {
    let map = map_layout(light);
    if map.width == 0 {
        return (Vec3::ONE, UNIFORM_SPHERE_PDF);
    }
    let (u, v) = map_coordinates(d, light.p0[0]);
    let column = ((u * map.width as f32) as u32).min(map.width - 1);
    let row = ((v * map.height as f32) as u32).min(map.height - 1);
    let pdf_uv = data[(map.pdf + row * map.width + column) as usize];
    let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
    (
        texel(data, &map, column, row),
        map_solid_angle_pdf(pdf_uv, sin_theta),
    )
}

/// A direction drawn uniformly in sun `light`'s cone with the unit-square point `u`: the disk's
/// squared radius scales 1 - cos(theta) (uniform in [0, 1 - cos alpha]), its angle is the
/// azimuth; sin(theta) from 1 - cos(theta) = t as sqrt(t (2 - t)), exact for tiny cones.
pub fn sun_direction(light: &GpuLight, u: [f32; 2]) -> Vec3 {
    let axis = Vec3::from(light.p0);
    let d = concentric_disk(u);
    let r2 = d[0] * d[0] + d[1] * d[1];
    let t = r2 * light.p1[0];
    let sin_theta = (t * (2.0 - t)).max(0.0).sqrt();
    let (cx, cy) = match r2 > 0.0 {
        true => {
            let r = r2.sqrt();
            (d[0] / r, d[1] / r)
        }
        false => (1.0, 0.0),
    };
    let (tangent, bitangent) = tangents(axis);
    tangent * (sin_theta * cx) + bitangent * (sin_theta * cy) + axis * (1.0 - t)
}

/// Whether unit direction `d` lies in sun `light`'s cone: its chord to the axis,
/// |d - axis|^2 = 2 (1 - cos theta), within 2 (1 - cos alpha) (no cosine near 1 to round).
pub fn sun_sees(light: &GpuLight, d: Vec3) -> bool {
    let chord = d - Vec3::from(light.p0);
    chord.dot(chord) <= 2.0 * light.p1[0]
}

/// A direction drawn from sky light `light` (an environment or a sun) with `u`.
pub fn sky_sample(light: &GpuLight, data: &[f32], u: [f32; 2]) -> SkySample {
    match light.kind {
        LIGHT_SUN => SkySample {
            wi: sun_direction(light, u),
            radiance: Vec3::splat(light.p1[1]),
            pdf: light.p1[2],
        },
        _ => environment_sample(light, data, u),
    }
}

/// What sky light `light` sends along unit direction `-d` (seen looking along `d`), before
/// its `color`, and the density with which [`sky_sample`] draws `d`: zero outside a sun.
pub fn sky_radiance(light: &GpuLight, data: &[f32], d: Vec3) -> (Vec3, f32) {
    match light.kind {
        LIGHT_ENVIRONMENT => environment_radiance(light, data, d),
        _ if sun_sees(light, d) => (Vec3::splat(light.p1[1]), light.p1[2]),
        _ => (Vec3::ZERO, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomial sine and cosine are the library's to 1e-6 over several turns, both
    /// signs, and at the quarter turns where the reduction changes quadrant.
    #[test]
    fn sin_cos_turns_is_sin_and_cos() {
        let mut worst = 0f64;
        for k in -4000..=4000 {
            let t = k as f32 / 997.0;
            for t in [t, (k as f32) * 0.125] {
                let (s, c) = sin_cos_turns(t);
                let angle = 2.0 * std::f64::consts::PI * t as f64;
                worst = worst
                    .max((s as f64 - angle.sin()).abs())
                    .max((c as f64 - angle.cos()).abs());
            }
        }
        assert!(worst < 1e-6, "{worst}");
    }

    /// A map direction's coordinates are the (u, v) it was made from, turned or not.
    #[test]
    fn map_coordinates_invert_map_direction() {
        for (u, v) in [(0.1f32, 0.3f32), (0.7, 0.9), (0.999, 0.5), (0.25, 0.01)] {
            for turns in [0.0f32, 0.3, 0.75] {
                let (d, _) = map_direction(u, v, turns);
                let (u2, v2) = map_coordinates(d, turns);
                let du = (u2 - u).abs().min(1.0 - (u2 - u).abs());
                assert!(
                    du < 2e-6 && (v2 - v).abs() < 2e-6,
                    "{u} {v} {turns}: {u2} {v2}"
                );
            }
        }
        // u = 0 is -z, u = 1/4 is +x (Mitsuba's envmap), v = 0 is +y.
        assert!((map_direction(0.0, 0.5, 0.0).0 + Vec3::Z).length() < 1e-6);
        assert!((map_direction(0.25, 0.5, 0.0).0 - Vec3::X).length() < 1e-6);
        assert!((map_direction(0.3, 0.0, 0.0).0 - Vec3::Y).length() < 1e-6);
    }

    /// Uniform sphere directions are unit and spread evenly: each octant gets an eighth.
    #[test]
    fn uniform_sphere_fills_each_octant_equally() {
        let mut rng = crate::math::rng::Rng::new(3, 1, 0);
        let mut octants = [0u32; 8];
        let n = 80_000;
        for _ in 0..n {
            let d = uniform_sphere(rng.next_2d());
            assert!((d.length() - 1.0).abs() < 1e-5);
            let k =
                (d.x > 0.0) as usize | ((d.y > 0.0) as usize) << 1 | ((d.z > 0.0) as usize) << 2;
            octants[k] += 1;
        }
        for count in octants {
            assert!(
                (count as f64 / n as f64 - 0.125).abs() < 0.005,
                "{octants:?}"
            );
        }
    }
}
