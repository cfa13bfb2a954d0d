// Lights at infinity: the environment (constant, or an equirectangular map sampled by its texels'
// luminance) and the sun (a cone). Reads `environment` (the packed map) and the light itself.
// Mirrors: src/integrator/environment.rs (the densities, conventions and reasons are there).

const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

// sin and cos of the angle `turns` turns, by an exact reduction to within pi/4 of a quarter turn.
fn sin_cos_turns(turns: f32) -> vec2<f32> {
    let t = turns - floor(turns);
    let quarter = floor(4.0 * t + 0.5);
    let x = (t - 0.25 * quarter) * (2.0 * PI);
    let s = sin_quarter(x);
    let c = cos_quarter(x);
    switch u32(quarter) {
        case 1u: { return vec2<f32>(c, -s); }
        case 2u: { return vec2<f32>(-s, -c); }
        case 3u: { return vec2<f32>(-c, s); }
        default: { return vec2<f32>(s, c); }
    }
}

fn uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let d = concentric_disk(u);
    let r2 = d.x * d.x + d.y * d.y;
    let s = 2.0 * sqrt(max(1.0 - r2, 0.0));
    return vec3<f32>(d.x * s, 1.0 - 2.0 * r2, d.y * s);
}

// A direction from a light at infinity: radiance before the light's colour, solid-angle density.
struct SkySample {
    wi: vec3<f32>,
    radiance: vec3<f32>,
    pdf: f32,
}

struct MapLayout {
    width: u32,
    height: u32,
    pdf: u32,
    marginal: u32,
    conditional: u32,
}

fn map_layout(light: GpuLight) -> MapLayout {
    let width = u32(light.p0.y);
    let height = u32(light.p0.z);
    let texels = width * height;
    return MapLayout(width, height, 3u * texels, 4u * texels, 4u * texels + height + 1u);
}

// The interval of the n-interval CDF at environment[base..=base + n] that `u` falls in, and
// where in it.
fn sample_cdf(base: u32, n: u32, u: f32) -> vec2<f32> {
    var lo = 0u;
    var hi = n;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (environment[base + mid] <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let start = environment[base + lo];
    let end = environment[base + lo + 1u];
    let offset = clamp((u - start) / (end - start), 0.0, 0.99999994);
    return vec2<f32>(f32(lo), offset);
}

fn map_texel(map: MapLayout, column: u32, row: u32) -> vec3<f32> {
    let k = 3u * (row * map.width + column);
    return vec3<f32>(environment[k], environment[k + 1u], environment[k + 2u]);
}

// The direction at map coordinates (u, v) turned `turns` about +y (xyz), and sin(theta) (w).
fn map_direction(u: f32, v: f32, turns: f32) -> vec4<f32> {
    let theta = sin_cos_turns(0.5 * v);
    let phi = sin_cos_turns(u + turns);
    return vec4<f32>(theta.x * phi.x, theta.y, -theta.x * phi.y, theta.x);
}

fn map_solid_angle_pdf(pdf_uv: f32, sin_theta: f32) -> f32 {
    if (sin_theta > 0.0) {
        return pdf_uv / (2.0 * PI * PI * sin_theta);
    }
    return 0.0;
}

fn environment_sample(light: GpuLight, u: vec2<f32>) -> SkySample {
    let map = map_layout(light);
    if (map.width == 0u) {
        return SkySample(uniform_sphere(u), vec3<f32>(1.0), UNIFORM_SPHERE_PDF);
    }
    let row_sample = sample_cdf(map.marginal, map.height, u.y);
    let row = u32(row_sample.x);
    let column_sample = sample_cdf(map.conditional + row * (map.width + 1u), map.width, u.x);
    let column = u32(column_sample.x);
    let map_u = (column_sample.x + column_sample.y) / f32(map.width);
    let map_v = (row_sample.x + row_sample.y) / f32(map.height);
    let direction = map_direction(map_u, map_v, light.p0.x);
    let pdf_uv = environment[map.pdf + row * map.width + column];
    return SkySample(direction.xyz, map_texel(map, column, row),
                     map_solid_angle_pdf(pdf_uv, direction.w));
}

// Map coordinates (u, v) of unit direction `d` on a map turned `turns` about +y.
fn map_coordinates(d: vec3<f32>, turns: f32) -> vec2<f32> {
    let u = atan2(d.x, -d.z) / (2.0 * PI) - turns;
    let sin_theta = sqrt(d.x * d.x + d.z * d.z);
    return vec2<f32>(u - floor(u), atan2(sin_theta, d.y) / PI);
}

// Radiance (before the colour) and density along `d` of an environment light: xyz, w.
fn environment_radiance(light: GpuLight, d: vec3<f32>) -> vec4<f32> {
    let map = map_layout(light);
    if (map.width == 0u) {
        return vec4<f32>(vec3<f32>(1.0), UNIFORM_SPHERE_PDF);
    }
    let uv = map_coordinates(d, light.p0.x);
    let column = min(u32(uv.x * f32(map.width)), map.width - 1u);
    let row = min(u32(uv.y * f32(map.height)), map.height - 1u);
    let pdf_uv = environment[map.pdf + row * map.width + column];
    let sin_theta = sqrt(d.x * d.x + d.z * d.z);
    return vec4<f32>(map_texel(map, column, row), map_solid_angle_pdf(pdf_uv, sin_theta));
}

fn sun_direction(light: GpuLight, u: vec2<f32>) -> vec3<f32> {
    let axis = light.p0;
    let d = concentric_disk(u);
    let r2 = d.x * d.x + d.y * d.y;
    let t = r2 * light.p1.x;
    let sin_theta = sqrt(max(t * (2.0 - t), 0.0));
    var azimuth = vec2<f32>(1.0, 0.0);
    if (r2 > 0.0) {
        let r = sqrt(r2);
        azimuth = vec2<f32>(d.x / r, d.y / r);
    }
    let frame = tangents(axis);
    return frame.t * (sin_theta * azimuth.x) + frame.b * (sin_theta * azimuth.y) + axis * (1.0 - t);
}

fn sun_sees(light: GpuLight, d: vec3<f32>) -> bool {
    let chord = d - light.p0;
    return dot(chord, chord) <= 2.0 * light.p1.x;
}

fn is_sky_light(light: GpuLight) -> bool {
    return light.kind == LIGHT_ENVIRONMENT || light.kind == LIGHT_SUN;
}

fn sky_sample(light: GpuLight, u: vec2<f32>) -> SkySample {
    if (light.kind == LIGHT_SUN) {
        return SkySample(sun_direction(light, u), vec3<f32>(light.p1.y), light.p1.z);
    }
    return environment_sample(light, u);
}

// What a sky light sends along -d (xyz, before its colour) and the density of drawing d (w).
fn sky_radiance(light: GpuLight, d: vec3<f32>) -> vec4<f32> {
    if (light.kind == LIGHT_ENVIRONMENT) {
        return environment_radiance(light, d);
    }
    if (sun_sees(light, d)) {
        return vec4<f32>(vec3<f32>(light.p1.y), light.p1.z);
    }
    return vec4<f32>(0.0);
}
