// The path tracer's BSDF sampling and multiple importance sampling.
// Mirrors: src/integrator/bsdf.rs (see there for the lobes, their densities and the weights).

struct Lobes {
    diffuse: f32,
    glossy: f32,
    mirror: f32,
}

// The largest component, as glam's max_element orders the comparisons.
fn max3(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

fn material_lobes(material: GpuMaterial) -> Lobes {
    let diffuse = max3(material.diffuse);
    var glossy = 0.0;
    if (material.model == MODEL_PHONG || material.model == MODEL_BLINN_PHONG
        || material.model == MODEL_ROUGH_CONDUCTOR) {
        glossy = max3(material.specular);
    }
    let mirror = max3(material.mirror);
    let total = diffuse + glossy + mirror;
    if (total <= 0.0) {
        return Lobes(0.0, 0.0, 0.0);
    }
    return Lobes(diffuse / total, glossy / total, mirror / total);
}

fn has_smooth_lobes(material: GpuMaterial) -> bool {
    let lobes = material_lobes(material);
    return lobes.diffuse + lobes.glossy > 0.0;
}

// Fresnel's reflectance (x) and the refracted direction's cosine (y).
fn fresnel_dielectric(cos_i: f32, eta: f32) -> vec2<f32> {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return vec2<f32>(0.5 * (r_s * r_s + r_p * r_p), cos_t);
}

struct Tangents {
    t: vec3<f32>,
    b: vec3<f32>,
}

// Duff et al. 2017, "Building an orthonormal basis, revisited".
fn tangents(n: vec3<f32>) -> Tangents {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Tangents(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
                    vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn about(axis: vec3<f32>, disk: vec2<f32>, cos_theta: f32) -> vec3<f32> {
    let frame = tangents(axis);
    let r = sqrt(disk.x * disk.x + disk.y * disk.y);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    var c = vec2<f32>(1.0, 0.0);
    if (r > 0.0) {
        c = vec2<f32>(disk.x / r, disk.y / r);
    }
    return frame.t * (sin_theta * c.x) + frame.b * (sin_theta * c.y) + axis * cos_theta;
}

fn cosine_direction(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let d = concentric_disk(u);
    let z = sqrt(max(1.0 - d.x * d.x - d.y * d.y, 0.0));
    let frame = tangents(n);
    return frame.t * d.x + frame.b * d.y + n * z;
}

fn power_cosine_direction(axis: vec3<f32>, exponent: f32, u: vec2<f32>) -> vec3<f32> {
    let d = concentric_disk(u);
    let r2 = d.x * d.x + d.y * d.y;
    return about(axis, d, pow(r2, 1.0 / (exponent + 1.0)));
}

fn power_cosine_pdf(exponent: f32, cos_theta: f32) -> f32 {
    if (cos_theta > 0.0) {
        return (exponent + 1.0) / (2.0 * PI) * pow(cos_theta, exponent);
    }
    return 0.0;
}

// v reflected about the unit n: 2 (n . v) n - v (WGSL's reflect rounds otherwise).
fn reflect_about(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(n, v) * n - v;
}

fn ggx_distribution(alpha: f32, cos_h: f32) -> f32 {
    let a2 = alpha * alpha;
    let c2 = cos_h * cos_h;
    let d = max(1.0 - c2, 0.0) + c2 * a2;
    return a2 / (PI * d * d);
}

fn ggx_masking(alpha: f32, cos: f32) -> f32 {
    let a2 = alpha * alpha;
    return 2.0 * cos / (cos + sqrt(max(a2 + (1.0 - a2) * cos * cos, 0.0)));
}

fn ggx_reflection(alpha: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(n, wo);
    let cos_i = dot(n, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0) {
        return 0.0;
    }
    let half = normalize(wo + wi);
    let cos_h = dot(n, half);
    if (cos_h <= 0.0 || dot(wo, half) <= 0.0) {
        return 0.0;
    }
    let g = ggx_masking(alpha, cos_o) * ggx_masking(alpha, cos_i);
    return ggx_distribution(alpha, cos_h) * g / (4.0 * cos_o * cos_i);
}

fn ggx_half_vector(n: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let d = concentric_disk(u);
    let basis = tangents(n);
    let r2 = d.x * d.x + d.y * d.y;
    return normalize(basis.t * (alpha * d.x) + basis.b * (alpha * d.y) + n * sqrt(max(1.0 - r2, 0.0)));
}

fn glossy_pdf(material: GpuMaterial, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (material.model == MODEL_PHONG) {
        return power_cosine_pdf(material.shininess, dot(reflect_about(wo, n), wi));
    }
    let half = normalize(wo + wi);
    let cos_o = dot(wo, half);
    let cos_h = dot(n, half);
    if (cos_o <= 0.0) {
        return 0.0;
    }
    if (material.model == MODEL_ROUGH_CONDUCTOR) {
        if (cos_h > 0.0) {
            return ggx_distribution(material.shininess, cos_h) * cos_h / (4.0 * cos_o);
        }
        return 0.0;
    }
    return power_cosine_pdf(material.shininess, cos_h) / (4.0 * cos_o);
}

fn bsdf_pdf(material: GpuMaterial, lobes: Lobes, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    var pdf = 0.0;
    if (lobes.diffuse > 0.0) {
        pdf += lobes.diffuse * max(dot(n, wi), 0.0) / PI;
    }
    if (lobes.glossy > 0.0) {
        pdf += lobes.glossy * glossy_pdf(material, n, wo, wi);
    }
    return pdf;
}

// A direction drawn from a material; `valid` is false where it reflects nothing or the
// direction would leave below the surface.
struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    valid: bool,
    transmitted: bool,
}

fn no_bsdf_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false, false);
}

fn sample_dielectric(material: GpuMaterial, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>,
                     entering: bool, u_lobe: f32) -> BsdfSample {
    var eta = material.ior;
    if (entering) {
        eta = 1.0 / material.ior;
    }
    let cos_i = max(dot(n, wo), 0.0);
    let fresnel = fresnel_dielectric(cos_i, eta);
    if (u_lobe < fresnel.x) {
        let wi = normalize(reflect_about(wo, n));
        return BsdfSample(wi, vec3<f32>(1.0), 0.0, dot(wi, ng) > 0.0, false);
    }
    let wi = normalize(-eta * wo + (eta * cos_i - fresnel.y) * n);
    return BsdfSample(wi, vec3<f32>(eta * eta), 0.0, dot(wi, ng) < 0.0, true);
}

fn sample_bsdf(material: GpuMaterial, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, front: bool,
               u: vec2<f32>, u_lobe: f32) -> BsdfSample {
    if (material.model == MODEL_DIELECTRIC) {
        return sample_dielectric(material, n, ng, wo, front, u_lobe);
    }
    let lobes = material_lobes(material);
    if (lobes.mirror > 0.0 && u_lobe >= lobes.diffuse + lobes.glossy) {
        let wi = normalize(reflect_about(wo, n));
        return BsdfSample(wi, material.mirror / lobes.mirror, 0.0, dot(wi, ng) > 0.0, false);
    }
    var wi: vec3<f32>;
    if (lobes.glossy > 0.0 && u_lobe >= lobes.diffuse) {
        if (material.model == MODEL_PHONG) {
            wi = power_cosine_direction(reflect_about(wo, n), material.shininess, u);
        } else if (material.model == MODEL_ROUGH_CONDUCTOR) {
            wi = reflect_about(wo, ggx_half_vector(n, material.shininess, u));
        } else {
            wi = reflect_about(wo, power_cosine_direction(n, material.shininess, u));
        }
    } else if (lobes.diffuse > 0.0) {
        wi = cosine_direction(n, u);
    } else {
        return no_bsdf_sample();
    }
    let cos_theta = dot(n, wi);
    if (cos_theta <= 0.0 || dot(wi, ng) <= 0.0) {
        return no_bsdf_sample();
    }
    let pdf = bsdf_pdf(material, lobes, n, wo, wi);
    if (pdf <= 0.0) {
        return no_bsdf_sample();
    }
    return BsdfSample(wi, eval_brdf(material, n, wo, wi) * (cos_theta / pdf), pdf, true, false);
}

fn light_sample_weight(samples: f32, distance2: f32, cos_light: f32, area: f32, pdf: f32) -> f32 {
    let ratio = pdf * cos_light * area / (samples * distance2);
    return 1.0 / (1.0 + ratio * ratio);
}

fn emitter_hit_weight(samples: f32, distance2: f32, cos_light: f32, area: f32, pdf: f32) -> f32 {
    if (samples <= 0.0 || pdf <= 0.0) {
        return 1.0;
    }
    let ratio = samples * distance2 / (pdf * cos_light * area);
    return 1.0 / (1.0 + ratio * ratio);
}

fn sky_sample_weight(samples: u32, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let ratio = bsdf_pdf / (f32(samples) * light_pdf);
    return 1.0 / (1.0 + ratio * ratio);
}

fn sky_hit_weight(samples: u32, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    if (bsdf_pdf <= 0.0 || light_pdf <= 0.0) {
        return 1.0;
    }
    let ratio = f32(samples) * light_pdf / bsdf_pdf;
    return 1.0 / (1.0 + ratio * ratio);
}
