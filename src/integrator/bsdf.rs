//! The path tracer's BSDF sampling and multiple importance sampling. Twin: `wgsl/bsdf.wgsl`.
//!
//! A material is a sum of lobes: Lambert's `diffuse / pi`, a normalised Phong or Blinn-Phong
//! lobe (`integrator::eval_brdf`), and a perfect mirror. Sampling picks a lobe with probability
//! proportional to its largest reflectance component, then a direction from that lobe's own
//! density: cosine-weighted for Lambert, `(n + 1) / (2 pi) cos^n` about the mirror direction for
//! Phong, about the normal for Blinn-Phong's half vector (pbrt's and Mitsuba's `phong`). The
//! density of a non-mirror direction is the mixture of the non-mirror lobes' densities, so a
//! direction that several lobes can draw is weighted by all of them. Directions come from the
//! concentric disk (`math::sampling`): no `sin` or `cos`, whose WGSL precision is loose. A
//! smooth dielectric reflects with Fresnel's probability and refracts otherwise. The equations
//! and what each model conserves are in `docs/path.md`.

use std::f32::consts::PI;

use glam::Vec3;

use super::eval_brdf;
use crate::layout::{
    GpuMaterial, MODEL_BLINN_PHONG, MODEL_DIELECTRIC, MODEL_PHONG, MODEL_ROUGH_CONDUCTOR,
};
use crate::math::sampling::concentric_disk;

/// The probabilities of a material's lobes, summing to 1 (all 0 where nothing reflects).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobes {
    /// Lambert's.
    pub diffuse: f32,
    /// The Phong or Blinn-Phong lobe's.
    pub glossy: f32,
    /// The perfect mirror's.
    pub mirror: f32,
}

/// Each lobe in proportion to its largest reflectance component.
pub fn lobes(material: &GpuMaterial) -> Lobes {
    let diffuse = Vec3::from(material.diffuse).max_element();
    let glossy = match material.model {
        MODEL_PHONG | MODEL_BLINN_PHONG | MODEL_ROUGH_CONDUCTOR => {
            Vec3::from(material.specular).max_element()
        }
        _ => 0.0,
    };
    let mirror = Vec3::from(material.mirror).max_element();
    let total = diffuse + glossy + mirror;
    if total <= 0.0 {
        return Lobes {
            diffuse: 0.0,
            glossy: 0.0,
            mirror: 0.0,
        };
    }
    Lobes {
        diffuse: diffuse / total,
        glossy: glossy / total,
        mirror: mirror / total,
    }
}

impl Lobes {
    /// Whether a lobe is one light samples can meet (not only deltas): where none is, the
    /// path tracer casts no shadow ray.
    pub fn smooth(&self) -> bool {
        self.diffuse + self.glossy > 0.0
    }
}

/// Fresnel's reflectance of unpolarised light at a smooth interface, for the cosine `cos_i`
/// (>= 0) of the incident direction and `eta` = n_incident / n_transmitted; with the cosine of
/// the refracted direction (1 and 0 at total internal reflection).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_s * r_s + r_p * r_p), cos_t)
}

/// A smooth dielectric's sample: reflection with Fresnel's probability F (weight F / F = 1),
/// refraction otherwise, with the radiance's weight eta^2 (its solid angle is compressed going
/// into the denser side: pbrt's and Mitsuba's radiance transport). `entering`: `wo` is on the
/// side the outward normal leaves from.
fn sample_dielectric(
    material: &GpuMaterial,
    n: Vec3,
    ng: Vec3,
    wo: Vec3,
    entering: bool,
    u_lobe: f32,
) -> Option<BsdfSample> {
    let eta = if entering {
        1.0 / material.ior
    } else {
        material.ior
    };
    let cos_i = n.dot(wo).max(0.0);
    let (reflectance, cos_t) = fresnel_dielectric(cos_i, eta);
    if u_lobe < reflectance {
        let wi = reflect(wo, n).normalize();
        return (wi.dot(ng) > 0.0).then_some(BsdfSample {
            wi,
            weight: Vec3::ONE,
            pdf: 0.0,
            transmitted: false,
        });
    }
    let wi = (-eta * wo + (eta * cos_i - cos_t) * n).normalize();
    (wi.dot(ng) < 0.0).then_some(BsdfSample {
        wi,
        weight: Vec3::splat(eta * eta),
        pdf: 0.0,
        transmitted: true,
    })
}

/// Tangents `(t, b)` completing the unit `n` to an orthonormal basis, without a branch on the
/// normal's direction but its z sign (Duff et al. 2017, "Building an orthonormal basis,
/// revisited").
pub fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The direction about `axis` with cosine `cos` and azimuth `(dx, dy) / |(dx, dy)|`.
fn about(axis: Vec3, disk: [f32; 2], cos: f32) -> Vec3 {
    let (t, b) = tangents(axis);
    let r = (disk[0] * disk[0] + disk[1] * disk[1]).sqrt();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (cx, cy) = if r > 0.0 {
        (disk[0] / r, disk[1] / r)
    } else {
        (1.0, 0.0)
    };
    t * (sin * cx) + b * (sin * cy) + axis * cos
}

/// A cosine-weighted direction about `n` (density `cos / pi`): the concentric disk's point
/// lifted onto the hemisphere (Malley's method).
pub fn cosine_direction(n: Vec3, u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d[0] * d[0] - d[1] * d[1]).max(0.0).sqrt();
    let (t, b) = tangents(n);
    t * d[0] + b * d[1] + n * z
}

/// A direction about `axis` with density `(e + 1) / (2 pi) cos^e`: the disk point's squared
/// radius is uniform, so `cos = r^(2 / (e + 1))`, and its angle is the azimuth.
pub fn power_cosine_direction(axis: Vec3, exponent: f32, u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    let r2 = d[0] * d[0] + d[1] * d[1];
    about(axis, d, r2.powf(1.0 / (exponent + 1.0)))
}

/// The density `(e + 1) / (2 pi) cos^e` of [`power_cosine_direction`] at cosine `cos`.
fn power_cosine_pdf(exponent: f32, cos: f32) -> f32 {
    match cos > 0.0 {
        true => (exponent + 1.0) / (2.0 * PI) * cos.powf(exponent),
        false => 0.0,
    }
}

/// GGX's distribution of microfacet normals of roughness `alpha` at the cosine `cos_h` of the
/// half vector: alpha^2 / (pi (cos_h^2 (alpha^2 - 1) + 1)^2), its denominator summed as
/// sin^2 + cos^2 alpha^2, whose parts are never negative: the textbook form cancels to 0 in
/// f32 at the peak of a narrow lobe (alpha 1e-4: infinity for D).
pub fn ggx_distribution(alpha: f32, cos_h: f32) -> f32 {
    let a2 = alpha * alpha;
    let c2 = cos_h * cos_h;
    let d = (1.0 - c2).max(0.0) + c2 * a2;
    a2 / (PI * d * d)
}

/// Smith's masking of GGX for a direction of cosine `cos` (> 0) to the normal, written
/// without tan: 2 cos / (cos + sqrt(alpha^2 + (1 - alpha^2) cos^2)).
pub fn ggx_masking(alpha: f32, cos: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * cos / (cos + (a2 + (1.0 - a2) * cos * cos).max(0.0).sqrt())
}

/// The rough conductor's lobe without its reflectance: D G1(wo) G1(wi) / (4 cos_o cos_i),
/// zero where either direction or the half vector lies below the surface.
pub fn ggx_reflection(alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return 0.0;
    }
    let half = (wo + wi).normalize();
    let cos_h = n.dot(half);
    if cos_h <= 0.0 || wo.dot(half) <= 0.0 {
        return 0.0;
    }
    let g = ggx_masking(alpha, cos_o) * ggx_masking(alpha, cos_i);
    ggx_distribution(alpha, cos_h) * g / (4.0 * cos_o * cos_i)
}

/// A GGX microfacet normal about `n` drawn with density D(h) cos_h: the disk point's squared
/// radius u gives tan(theta_h) = alpha sqrt(u / (1 - u)), its angle the azimuth.
pub fn ggx_half_vector(n: Vec3, alpha: f32, u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    let (t, b) = tangents(n);
    let r2 = d[0] * d[0] + d[1] * d[1];
    (t * (alpha * d[0]) + b * (alpha * d[1]) + n * (1.0 - r2).max(0.0).sqrt()).normalize()
}

/// `v` reflected about the unit `n`: `2 (n . v) n - v`.
fn reflect(v: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(v) * n - v
}

/// The glossy lobe's density of `wi` (unit, away from the surface) seen from `wo`.
fn glossy_pdf(material: &GpuMaterial, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    if material.model == MODEL_PHONG {
        return power_cosine_pdf(material.shininess, reflect(wo, n).dot(wi));
    }
    let half = (wo + wi).normalize();
    let cos_o = wo.dot(half);
    let cos_h = n.dot(half);
    if cos_o <= 0.0 {
        return 0.0;
    }
    match material.model {
        MODEL_ROUGH_CONDUCTOR if cos_h > 0.0 => {
            ggx_distribution(material.shininess, cos_h) * cos_h / (4.0 * cos_o)
        }
        MODEL_ROUGH_CONDUCTOR => 0.0,
        _ => power_cosine_pdf(material.shininess, cos_h) / (4.0 * cos_o),
    }
}

/// The solid-angle density with which [`sample_bsdf`] draws `wi` (not by the mirror, which
/// draws one direction).
#[inline]
pub fn bsdf_pdf(material: &GpuMaterial, lobes: &Lobes, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let mut pdf = 0.0;
    if lobes.diffuse > 0.0 {
        pdf += lobes.diffuse * n.dot(wi).max(0.0) / PI;
    }
    if lobes.glossy > 0.0 {
        pdf += lobes.glossy * glossy_pdf(material, n, wo, wi);
    }
    pdf
}

/// A direction drawn from a material, and what the path's throughput is multiplied by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The new direction, unit, away from the surface.
    pub wi: Vec3,
    /// `f cos / pdf`, or the mirror's reflectance over its lobe's probability.
    pub weight: Vec3,
    /// Its solid-angle density; 0 for a delta (a mirror's, a dielectric's).
    pub pdf: f32,
    /// Whether it goes through the surface (a dielectric's refraction).
    pub transmitted: bool,
}

/// A direction from `material` at a surface with shading normal `n` and geometric normal
/// `ng` (both towards `wo`; `front`: on the side the outward normal leaves from), drawn with
/// `u` (its direction) and `u_lobe` (its lobe among `lobes`, the material's); none where the
/// material reflects nothing or the direction would leave on the wrong side of the surface.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn sample_bsdf(
    material: &GpuMaterial,
    lobes: &Lobes,
    n: Vec3,
    ng: Vec3,
    wo: Vec3,
    front: bool,
    u: [f32; 2],
    u_lobe: f32,
) -> Option<BsdfSample> {
    if material.model == MODEL_DIELECTRIC {
        return sample_dielectric(material, n, ng, wo, front, u_lobe);
    }
    if lobes.mirror > 0.0 && u_lobe >= lobes.diffuse + lobes.glossy {
        let wi = reflect(wo, n).normalize();
        return (wi.dot(ng) > 0.0).then(|| BsdfSample {
            wi,
            weight: Vec3::from(material.mirror) / lobes.mirror,
            pdf: 0.0,
            transmitted: false,
        });
    }
    let wi = if lobes.glossy > 0.0 && u_lobe >= lobes.diffuse {
        match material.model {
            MODEL_PHONG => power_cosine_direction(reflect(wo, n), material.shininess, u),
            MODEL_ROUGH_CONDUCTOR => reflect(wo, ggx_half_vector(n, material.shininess, u)),
            _ => {
                let half = power_cosine_direction(n, material.shininess, u);
                reflect(wo, half)
            }
        }
    } else if lobes.diffuse > 0.0 {
        cosine_direction(n, u)
    } else {
        return None;
    };
    let cos = n.dot(wi);
    if cos <= 0.0 || wi.dot(ng) <= 0.0 {
        return None;
    }
    let pdf = bsdf_pdf(material, lobes, n, wo, wi);
    (pdf > 0.0).then(|| BsdfSample {
        wi,
        weight: eval_brdf(material, n, wo, wi) * (cos / pdf),
        pdf,
        transmitted: false,
    })
}

/// The power heuristic's weight (Veach, exponent 2) of a light sample, one of `samples` drawn
/// a vertex on average (a chosen light's samples times its choice's probability) with
/// solid-angle density `light_pdf`, against the BSDF's one sample with `bsdf_pdf`. The
/// light's density is passed as its parts, `distance^2 / (cos_light area)`, so neither ratio
/// overflows: the weight is `1 / (1 + (bsdf_pdf cos_light area / (samples distance^2))^2)`.
pub fn light_sample_weight(
    samples: f32,
    distance2: f32,
    cos_light: f32,
    area: f32,
    bsdf_pdf: f32,
) -> f32 {
    let ratio = bsdf_pdf * cos_light * area / (samples * distance2);
    1.0 / (1.0 + ratio * ratio)
}

/// The power heuristic's weight of a BSDF sample with density `bsdf_pdf` that hits an emitter
/// whose light draws `samples` points a vertex: 1 where no light sample could have drawn it (a
/// mirror's or camera ray, `bsdf_pdf` 0; an emitter no light samples).
pub fn emitter_hit_weight(
    samples: f32,
    distance2: f32,
    cos_light: f32,
    area: f32,
    bsdf_pdf: f32,
) -> f32 {
    if samples <= 0.0 || bsdf_pdf <= 0.0 {
        return 1.0;
    }
    let ratio = samples * distance2 / (bsdf_pdf * cos_light * area);
    1.0 / (1.0 + ratio * ratio)
}

/// The power heuristic's weight of one of `samples` directions drawn from a light at infinity
/// with solid-angle density `light_pdf`, against the BSDF's one sample with `bsdf_pdf`.
pub fn sky_sample_weight(samples: u32, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let ratio = bsdf_pdf / (samples as f32 * light_pdf);
    1.0 / (1.0 + ratio * ratio)
}

/// The power heuristic's weight of a BSDF sample with density `bsdf_pdf` that escapes towards
/// a light at infinity whose `samples` light samples draw its direction with `light_pdf`: 1
/// where they cannot (a camera or mirror ray, `bsdf_pdf` 0; outside a sun, `light_pdf` 0).
pub fn sky_hit_weight(samples: u32, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    if bsdf_pdf <= 0.0 || light_pdf <= 0.0 {
        return 1.0;
    }
    let ratio = samples as f32 * light_pdf / bsdf_pdf;
    1.0 / (1.0 + ratio * ratio)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::MODEL_LAMBERT;
    use crate::math::rng::Rng;

    fn material(
        model: u32,
        diffuse: f32,
        specular: f32,
        shininess: f32,
        mirror: f32,
    ) -> GpuMaterial {
        GpuMaterial {
            model,
            diffuse: [diffuse; 3],
            specular: [specular; 3],
            shininess,
            mirror: [mirror; 3],
            ..Default::default()
        }
    }

    /// Every sampled direction's density is what `bsdf_pdf` says, and the mean of the weights
    /// is the albedo: `E[f cos / pdf]` over the sampled directions equals the integral of
    /// `f cos`, estimated independently by uniform hemisphere sampling.
    #[test]
    fn sampled_weights_average_to_the_albedo_each_lobe_reflects() {
        let n = Vec3::new(0.3, 0.2, 0.9).normalize();
        let wo = Vec3::new(-0.5, 0.1, 0.6).normalize();
        let cases = [
            material(MODEL_LAMBERT, 0.8, 0.0, 1.0, 0.0),
            material(MODEL_PHONG, 0.3, 0.6, 20.0, 0.0),
            material(MODEL_BLINN_PHONG, 0.2, 0.7, 50.0, 0.0),
            material(MODEL_PHONG, 0.0, 0.9, 60.0, 0.0),
            material(MODEL_ROUGH_CONDUCTOR, 0.0, 0.9, 0.2, 0.0),
            material(MODEL_ROUGH_CONDUCTOR, 0.0, 1.0, 0.6, 0.0),
            material(MODEL_ROUGH_CONDUCTOR, 0.0, 0.7, 1.0, 0.0),
        ];
        for m in cases {
            let lobes = lobes(&m);
            let mut rng = Rng::new(7, 3, 1);
            let (mut sampled, mut uniform) = (0.0f64, 0.0f64);
            let count = 1_000_000;
            for _ in 0..count {
                let [a, b] = rng.next_2d();
                if let Some(s) = sample_bsdf(&m, &lobes, n, n, wo, true, [a, b], rng.next_f32()) {
                    let pdf = bsdf_pdf(&m, &lobes, n, wo, s.wi);
                    assert!(
                        (pdf - s.pdf).abs() <= 1e-4 * pdf,
                        "{m:?}: {pdf} vs {}",
                        s.pdf
                    );
                    sampled += s.weight.x as f64;
                }
                // Uniform on the hemisphere: density 1 / (2 pi).
                let [c, d] = rng.next_2d();
                let z = c;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * d;
                let (t, bt) = tangents(n);
                let wi = t * (r * phi.cos()) + bt * (r * phi.sin()) + n * z;
                uniform += (eval_brdf(&m, n, wo, wi).x * z * 2.0 * PI) as f64;
            }
            let (sampled, uniform) = (sampled / count as f64, uniform / count as f64);
            assert!(
                (sampled - uniform).abs() < 0.02 * uniform.max(0.05),
                "{m:?}: sampled {sampled}, uniform {uniform}"
            );
        }
    }

    /// GGX's normals are a distribution: D(h) cos_h integrates to 1 over the hemisphere, from a
    /// near-mirror alpha of 1e-2 to 1 (quadrature in cos_h^2, fine where the peak is narrow).
    #[test]
    fn the_ggx_distribution_is_normalised_over_its_range_of_roughness() {
        for alpha in [1e-2f32, 0.05, 0.3, 0.7, 1.0] {
            let steps = 2_000_000;
            let mut integral = 0.0f64;
            // d(omega) = 2 pi d(cos), and with c2 = cos^2: d(cos) = d(c2) / (2 cos).
            for k in 0..steps {
                let c2 = (k as f64 + 0.5) / steps as f64;
                let cos = c2.sqrt() as f32;
                let d = ggx_distribution(alpha, cos) as f64;
                integral +=
                    d * cos as f64 * 2.0 * std::f64::consts::PI / (2.0 * cos as f64) / steps as f64;
            }
            assert!((integral - 1.0).abs() < 2e-3, "alpha {alpha}: {integral}");
        }
    }

    /// A white rough conductor never reflects more than it receives, at any angle or roughness
    /// (it loses what bounces between microfacets: Smith's model has no multiple scattering),
    /// and its lobe stays finite at the extremes: alpha 1e-4, grazing directions.
    #[test]
    fn a_white_rough_conductor_conserves_at_most_the_energy_it_receives() {
        let n = Vec3::Z;
        for alpha in [1e-4f32, 0.1, 0.5, 1.0] {
            for cos_o in [1.0f32, 0.5, 0.1, 1e-4] {
                let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
                let m = material(MODEL_ROUGH_CONDUCTOR, 0.0, 1.0, alpha, 0.0);
                let mut rng = Rng::new(3, 1, 2);
                let count = 200_000;
                let mut albedo = 0.0f64;
                for _ in 0..count {
                    if let Some(s) = sample_bsdf(&m, &lobes(&m), n, n, wo, true, rng.next_2d(), 0.5)
                    {
                        assert!(
                            s.weight.is_finite() && s.pdf.is_finite(),
                            "{alpha} {cos_o}: {s:?}"
                        );
                        albedo += s.weight.x as f64;
                    }
                }
                let albedo = albedo / count as f64;
                assert!(
                    albedo <= 1.0 + 1e-3,
                    "alpha {alpha}, cos_o {cos_o}: albedo {albedo}"
                );
                if alpha <= 0.1 && cos_o >= 0.5 {
                    assert!(
                        albedo > 0.95,
                        "alpha {alpha}, cos_o {cos_o}: albedo {albedo}"
                    );
                }
            }
            let peak = ggx_reflection(alpha, n, n, n);
            assert!(peak.is_finite() && peak > 0.0, "alpha {alpha}: peak {peak}");
        }
    }

    /// A mirror-only material reflects exactly, with its reflectance as the weight.
    #[test]
    fn a_mirror_reflects_about_the_normal_with_its_reflectance() {
        let m = material(MODEL_LAMBERT, 0.0, 0.0, 1.0, 0.7);
        let n = Vec3::Z;
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = sample_bsdf(&m, &lobes(&m), n, n, wo, true, [0.3, 0.9], 0.5).unwrap();
        assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        assert_eq!((s.weight, s.pdf), (Vec3::splat(0.7), 0.0));
    }

    /// Fresnel's reflectance: ((n - 1) / (n + 1))^2 at normal incidence, 1 at grazing
    /// incidence and beyond the critical angle, the same from both sides along a refracted
    /// pair (reciprocity), and Snell's law for the refracted direction.
    #[test]
    fn a_dielectric_reflects_by_fresnel_and_refracts_by_snell() {
        let ior = 1.5f32;
        let (r0, cos_t) = fresnel_dielectric(1.0, 1.0 / ior);
        assert!(
            (r0 - 0.04).abs() < 1e-7 && (cos_t - 1.0).abs() < 1e-7,
            "{r0} {cos_t}"
        );
        assert!((fresnel_dielectric(0.0, 1.0 / ior).0 - 1.0).abs() < 1e-6);
        let critical = (1.0 - 1.0 / (ior * ior)).sqrt();
        assert_eq!(fresnel_dielectric(critical * 0.999, ior), (1.0, 0.0));
        for cos_i in [0.9f32, 0.5, 0.2] {
            let (outside, cos_t) = fresnel_dielectric(cos_i, 1.0 / ior);
            let (inside, _) = fresnel_dielectric(cos_t, ior);
            assert!(
                (outside - inside).abs() < 1e-6,
                "{cos_i}: {outside} vs {inside}"
            );
        }
        let m = GpuMaterial {
            model: MODEL_DIELECTRIC,
            ior,
            ..Default::default()
        };
        let n = Vec3::Z;
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let t = sample_dielectric(&m, n, n, wo, true, 0.99).unwrap();
        assert!(t.transmitted && t.wi.z < 0.0);
        let sin_t = (1.0 - t.wi.z * t.wi.z).sqrt();
        assert!((sin_t * ior - 0.6).abs() < 1e-6, "Snell: {sin_t}");
        assert!(
            (t.weight - Vec3::splat(1.0 / (ior * ior)))
                .abs()
                .max_element()
                < 1e-7
        );
        let r = sample_dielectric(&m, n, n, wo, true, 0.0).unwrap();
        assert!(!r.transmitted && (r.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
    }

    /// The basis is orthonormal for normals near both poles and along the axes.
    #[test]
    fn tangents_complete_any_normal_to_an_orthonormal_basis() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1e-7, -1e-7, -1.0).normalize(),
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ];
        for n in normals {
            let (t, b) = tangents(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-6, "{n}");
            }
            for v in [t, b] {
                assert!((v.length() - 1.0).abs() < 1e-6, "{n}");
            }
        }
    }

    /// The two weights of one direction sum to 1 (the power heuristic is a partition of
    /// unity), and stay finite at the extremes of distance, density and of the samples a vertex
    /// takes on average (a light chosen once in ten million vertices).
    #[test]
    fn the_two_strategies_weights_partition_unity_at_the_extremes() {
        for (samples, d2, cos, area, pdf) in [
            (1.0, 1.0, 1.0, 1.0, 1.0),
            (4.0, 1e-12, 1e-6, 1e6, 1e4),
            (16.0, 1e12, 1.0, 1e-6, 1e-4),
            (1.0, 3.0, 0.2, 0.5, 7.0),
            (1e-7, 1e-12, 1e-6, 1e6, 1e4),
            (2.7e-4, 1e6, 1e-3, 1e-6, 1e3),
        ] {
            let a = light_sample_weight(samples, d2, cos, area, pdf);
            let b = emitter_hit_weight(samples, d2, cos, area, pdf);
            assert!(a.is_finite() && b.is_finite());
            assert!((a + b - 1.0).abs() < 1e-5, "{a} + {b}");
        }
        assert_eq!(emitter_hit_weight(4.0, 1.0, 1.0, 1.0, 0.0), 1.0);
        assert_eq!(emitter_hit_weight(0.0, 1.0, 1.0, 1.0, 3.0), 1.0);
    }
}
