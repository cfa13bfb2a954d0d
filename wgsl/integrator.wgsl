// The Whitted integrator: one camera sample -> radiance.
// Mirrors: src/integrator.rs (see there for the radiometry and the Phong normalisations).
// Reads the module-scope bindings `prims`, `normals`, `materials`, `lights`, `frame`, `camera`.

const PI: f32 = 3.14159265358979323846;

struct Surface {
    position: vec3<f32>,
    // Per-component bound on the rounding error of position (for offset_ray_origin).
    position_error: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    front_facing: bool,
}

struct PathCounters {
    rays: u32,
    truncated: u32,
}

fn surface_at(prim: GpuPrimitive, ray: RayQuery, hit: Hit) -> Surface {
    // Recompute the position from the primitive itself, with its error bound (see the Rust twin).
    var point: SurfacePoint;
    var normal: vec3<f32>;
    var shading: vec3<f32>;
    switch prim.kind {
        case PRIM_TRIANGLE: {
            point = triangle_point(prim.p0, prim.p1, prim.p2, hit.b1, hit.b2);
            normal = normalize(cross(prim.p1 - prim.p0, prim.p2 - prim.p0));
            shading = normal;
            if (prim.normals != NONE) {
                let n = normals[prim.normals].n;
                let b0 = 1.0 - hit.b1 - hit.b2;
                let interpolated = b0 * vec3<f32>(n[0], n[1], n[2])
                    + hit.b1 * vec3<f32>(n[3], n[4], n[5])
                    + hit.b2 * vec3<f32>(n[6], n[7], n[8]);
                let len = length(interpolated);
                if (len > 0.0) {
                    shading = interpolated / len;
                }
            }
        }
        case PRIM_SPHERE: {
            let sphere = sphere_surface_point(ray, hit, prim.p0, prim.p1.x);
            point = sphere.point;
            normal = sphere.outward;
            shading = sphere.outward;
        }
        case PRIM_QUAD: {
            normal = normalize(cross(prim.p1, prim.p2));
            point = quad_point(prim.p0, prim.p1, prim.p2, hit.b1, hit.b2);
            shading = normal;
        }
        case PRIM_PLANE: {
            point = plane_point(ray, hit.t, prim.p0, prim.p1);
            normal = prim.p1;
            shading = prim.p1;
        }
        default: {
            let curved = curved_surface_point(ray, hit.t, prim);
            point = curved.point;
            normal = curved.outward;
            shading = curved.outward;
        }
    }
    // Two-sided shading: turn both normals towards the incoming ray.
    let front_facing = dot(normal, ray.direction) < 0.0;
    var geometric_normal = -normal;
    var shading_normal = -shading;
    if (front_facing) {
        geometric_normal = normal;
        shading_normal = shading;
    }
    if (dot(shading_normal, geometric_normal) < 0.0) {
        shading_normal = -shading_normal;
    }
    return Surface(point.position, point.error, geometric_normal, shading_normal, front_facing);
}

fn eval_brdf(material: GpuMaterial, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var f = material.diffuse / PI;
    let exponent = material.shininess;
    if (material.model == MODEL_PHONG) {
        let reflected = 2.0 * dot(n, wi) * n - wi;
        let cos_alpha = dot(reflected, wo);
        if (cos_alpha > 0.0) {
            f += material.specular * ((exponent + 2.0) / (2.0 * PI)) * pow(cos_alpha, exponent);
        }
    } else if (material.model == MODEL_BLINN_PHONG) {
        let half = normalize(wi + wo);
        let cos_h = dot(n, half);
        if (cos_h > 0.0) {
            f += material.specular * ((exponent + 8.0) / (8.0 * PI)) * pow(cos_h, exponent);
        }
    } else if (material.model == MODEL_ROUGH_CONDUCTOR) {
        f += material.specular * ggx_reflection(exponent, n, wo, wi);
    }
    return f;
}

// The window of every area light's shadow-ray samples one dispatch evaluates (see GpuPass).
struct LightWindow {
    start: u32,
    count: u32,
}

fn window_is_first(window: LightWindow) -> bool {
    return window.start == 0u;
}

fn light_dimension(depth: u32, offset: u32, k: u32) -> u32 {
    return LIGHT_DIMENSION + 2u * (depth * frame.vertex_dimension_pairs + offset + k);
}

// A shadow ray from a path vertex towards a light, and what it adds there where the light is
// visible: `f`, before an area light's scale (`light_total`). `traced` is false where the vertex
// or the light faces away (no ray is traced, nothing is added).
struct LightSample {
    wi: vec3<f32>,
    t_max: f32,
    // The light's own primitive, which its shadow ray must not hit (NONE for a punctual light).
    skip: u32,
    f: vec3<f32>,
    traced: bool,
}

// An area light's shape, as its samples need it.
struct AreaLight {
    normal: vec3<f32>,
    area: f32,
    triangle: bool,
}

fn area_light_of(light: GpuLight) -> AreaLight {
    let c = cross(light.p1, light.p2);
    let triangle = light.kind == LIGHT_TRIANGLE;
    return AreaLight(normalize(c), select(1.0, 0.5, triangle) * length(c), triangle);
}

// How a vertex came to sample a light (see the Rust twin): the probability it chose it with,
// and the samples a vertex takes of it on average, which the MIS weights count.
struct LightShare {
    chosen: f32,
    expected_samples: f32,
}

fn every_vertex_share(light: GpuLight) -> LightShare {
    return LightShare(1.0, f32(light.samples));
}

fn chooses_lights() -> bool {
    return frame.light_choice_start < frame.light_count;
}

// The probability a path vertex chooses the area light of radiance `color` and area `area`.
fn light_choice_probability(color: vec3<f32>, area: f32) -> f32 {
    if (!chooses_lights()) {
        return 1.0;
    }
    return dot(color, LUMINANCE_WEIGHTS) * area / frame.light_power_total;
}

// Entry `i` of the chosen lights' cumulative distribution.
fn choice_cdf(i: u32) -> f32 {
    return sample_table[frame.light_choice_offset + i / 2u][i % 2u];
}

// The path tracer's choice of a light at vertex `depth` (`CHOICE_PAIR`, after the BSDF's pairs).
fn choice_dimension(depth: u32) -> u32 {
    return LIGHT_DIMENSION
        + 2u * (depth * frame.vertex_dimension_pairs + frame.light_samples_per_vertex + CHOICE_PAIR);
}

// The area light path vertex `depth` samples, chosen in proportion to power: its index (NONE
// where the frame chooses no light) and its share.
struct LightChoice {
    light: u32,
    share: LightShare,
}

fn choose_light(depth: u32, rng: ptr<function, Rng>) -> LightChoice {
    if (!chooses_lights()) {
        return LightChoice(NONE, LightShare(1.0, 0.0));
    }
    rng_seek(rng, choice_dimension(depth));
    let u = rng_next_2d(rng).x;
    var low = 0u;
    var high = frame.light_count - frame.light_choice_start - 1u;
    while (low < high) {
        let middle = (low + high) / 2u;
        if (choice_cdf(middle) > u) {
            high = middle;
        } else {
            low = middle + 1u;
        }
    }
    var below = 0.0;
    if (low > 0u) {
        below = choice_cdf(low - 1u);
    }
    let index = frame.light_choice_start + low;
    let light = lights[index];
    let share = light_choice_probability(light.color, area_light_of(light).area);
    return LightChoice(index, LightShare(choice_cdf(low) - below, share * f32(light.samples)));
}

fn is_area_light(light: GpuLight) -> bool {
    return light.kind == LIGHT_AREA || light.kind == LIGHT_TRIANGLE;
}

// Whether the frame is path traced (by a kernel built with the path tracer).
fn path_traced() -> bool {
    return FEATURE_PATH && frame.integrator == INTEGRATOR_PATH;
}

// The point `u` of the unit square on an area light (folded onto a triangle light's triangle),
// seen from `vertex`, over the probability the vertex chose the light with; under the path tracer (`mis`), weighted against the BSDF's sample of the
// same direction.
fn area_light_sample(light: GpuLight, shape: AreaLight, share: LightShare, square: vec2<f32>,
                     vertex: Vertex, mis: bool) -> LightSample {
    let surface = vertex.surface;
    let material = vertex.material;
    let wo = vertex.wo;
    var u = square;
    if (shape.triangle && u.x + u.y > 1.0) {
        u = vec2<f32>(1.0) - u;
    }
    let n = surface.shading_normal;
    let to_light = light.p0 + u.x * light.p1 + u.y * light.p2 - surface.position;
    let distance = length(to_light);
    let wi = to_light / distance;
    let cos_surface = dot(n, wi);
    let cos_light = -dot(shape.normal, wi);
    let traced = cos_surface > 0.0 && cos_light > 0.0 && dot(surface.geometric_normal, wi) > 0.0;
    var f = vec3<f32>(0.0);
    if (traced) {
        f = eval_brdf(material, n, wo, wi) * cos_surface * cos_light / (distance * distance);
    }
    if (mis && traced) {
        let pdf = bsdf_pdf(material, material_lobes(material), n, wo, wi);
        // A light is chosen only under the path tracer: Whitted's samples skip the division.
        f *= light_sample_weight(share.expected_samples, distance * distance, cos_light, shape.area, pdf)
            / share.chosen;
    }
    return LightSample(wi, shadow_ray_length(distance), light.prim, f, traced);
}

// A point, spot or directional light seen from `surface`: its whole contribution.
fn punctual_light_sample(light: GpuLight, surface: Surface, material: GpuMaterial,
                         wo: vec3<f32>) -> LightSample {
    var wi = light.p0;
    var distance = T_FAR;
    var falloff = 1.0;
    if (light.kind != LIGHT_DIRECTIONAL) {
        let to_light = light.p0 - surface.position;
        distance = length(to_light);
        wi = to_light / distance;
        falloff = 1.0 / (distance * distance);
    }
    if (light.kind == LIGHT_SPOT) {
        let cone = clamp(-dot(light.p1, wi) * light.p2.x + light.p2.y, 0.0, 1.0);
        falloff *= cone * cone;
    }
    let n = surface.shading_normal;
    let cos_surface = dot(n, wi);
    let traced = cos_surface > 0.0 && dot(surface.geometric_normal, wi) > 0.0;
    var f = vec3<f32>(0.0);
    if (traced) {
        f = eval_brdf(material, n, wo, wi) * light.color * (cos_surface * falloff);
    }
    return LightSample(wi, shadow_ray_length(distance), NONE, f, traced);
}

// A direction drawn from sky light `light` with `square`, seen from `surface` (see the Rust twin).
fn sky_light_sample(light: GpuLight, square: vec2<f32>, vertex: Vertex, mis: bool) -> LightSample {
    let surface = vertex.surface;
    let material = vertex.material;
    let wo = vertex.wo;
    let sky = sky_sample(light, square);
    let n = surface.shading_normal;
    let cos_surface = dot(n, sky.wi);
    let traced = sky.pdf > 0.0 && cos_surface > 0.0 && dot(surface.geometric_normal, sky.wi) > 0.0;
    var radiance_over_pdf = vec3<f32>(1.0);
    if (light.kind != LIGHT_SUN) {
        radiance_over_pdf = sky.radiance / sky.pdf;
    }
    var f = vec3<f32>(0.0);
    if (traced) {
        f = eval_brdf(material, n, wo, sky.wi) * radiance_over_pdf * cos_surface;
    }
    if (mis && traced) {
        let pdf = bsdf_pdf(material, material_lobes(material), n, wo, sky.wi);
        f *= sky_sample_weight(light.samples, sky.pdf, pdf);
    }
    return LightSample(sky.wi, shadow_ray_length(T_FAR), NONE, f, traced);
}

// A sampled light's sample: a sky light's or an area light's.
fn sampled_light_sample(light: GpuLight, shape: AreaLight, share: LightShare, square: vec2<f32>,
                        vertex: Vertex, mis: bool) -> LightSample {
    if (is_sky_light(light)) {
        return sky_light_sample(light, square, vertex, mis);
    }
    return area_light_sample(light, shape, share, square, vertex, mis);
}

// The radiance a ray escaping along `direction` sees of the lights at infinity, weighted against
// their light samples where a BSDF drew it with density `bsdf_pdf` (0: a camera or mirror ray).
fn sky_seen(direction: vec3<f32>, bsdf_pdf: f32) -> vec3<f32> {
    var total = vec3<f32>(0.0);
    if (!FEATURE_AREA_LIGHTS) {
        return total;
    }
    for (var l = 0u; l < frame.light_count; l += 1u) {
        let light = lights[l];
        if (is_sky_light(light)) {
            let seen = sky_radiance(light, direction);
            total += light.color * seen.xyz * sky_hit_weight(light.samples, seen.w, bsdf_pdf);
        }
    }
    return total;
}

fn is_sampled_light(light: GpuLight) -> bool {
    return is_area_light(light) || is_sky_light(light);
}

// A sampled light's scale of its samples' sum besides color / samples (see the Rust twin).
fn light_scale(light: GpuLight) -> f32 {
    if (light.kind == LIGHT_SUN) {
        return light.p2.x;
    }
    if (light.kind == LIGHT_ENVIRONMENT) {
        return 1.0;
    }
    return area_light_of(light).area;
}

// What a light adds from `sum`, the sum of its visible samples' terms.
fn light_total(light: GpuLight, sum: vec3<f32>) -> vec3<f32> {
    if (FEATURE_AREA_LIGHTS && is_sampled_light(light)) {
        return light.color * sum * (light_scale(light) / f32(light.samples));
    }
    return sum;
}

// The samples of a light with `samples` samples that fall in `window`: (first, end). A
// saturating end: start + count may exceed u32 (the whole-light window).
fn window_samples(window: LightWindow, samples: u32) -> vec2<u32> {
    return vec2<u32>(min(window.start, samples),
                     min(window.start + min(window.count, samples), samples));
}

// The pixel pattern's key of an area light's samples at path vertex `depth` (`offset`: the
// light's first sample among the vertex's), and `rng` moved to its sample `first`.
fn seek_light_samples(rng: ptr<function, Rng>, depth: u32, offset: u32, first: u32) -> u32 {
    let key = pixel_hash(frame.seed, (*rng).pixel, light_dimension(depth, offset, 0u));
    rng_seek(rng, light_dimension(depth, offset, first));
    return key;
}

// A path vertex as its light samples see it (see the Rust twin `Vertex`).
struct Vertex {
    surface: Surface,
    material: GpuMaterial,
    wo: vec3<f32>,
    depth: u32,
    origin: vec3<f32>,
    time: f32,
    own: u32,
}

// Whether light sample `s` reaches the vertex (a shadow ray, counted).
fn vertex_sees(vertex: Vertex, s: LightSample, counters: ptr<function, PathCounters>) -> bool {
    (*counters).rays += 1u;
    return !cw_occluded(ray_at_time(ray_query_new(vertex.origin, s.wi), vertex.time), vertex.own,
                        s.skip, s.t_max);
}

// What a sampled light adds from its samples in `window`, its dimensions from `offset` (numbers
// drawn before any test, so both paths consume the same dimensions whatever the visibility).
fn sampled_light(l: u32, share: LightShare, offset: u32, vertex: Vertex, window: LightWindow,
                 rng: ptr<function, Rng>, counters: ptr<function, PathCounters>) -> vec3<f32> {
    let light = lights[l];
    let shape = area_light_of(light);
    let range = window_samples(window, light.samples);
    let key = seek_light_samples(rng, vertex.depth, offset, range.x);
    var sum = vec3<f32>(0.0);
    for (var k = range.x; k < range.y; k += 1u) {
        let square = light_sample_2d(light.samples, light.strata_columns, (*rng).sample, k, key,
                                     rng_next_2d(rng));
        let s = sampled_light_sample(light, shape, share, square, vertex, path_traced());
        if (s.traced && vertex_sees(vertex, s, counters)) {
            sum += s.f;
        }
    }
    return light_total(light, sum);
}

// The chosen area light's samples (under the path tracer), every other sampled light's, and one
// shadow ray per punctual light (see the Rust twin).
fn direct_light(time: f32, surface: Surface, material: GpuMaterial, own: u32, wo: vec3<f32>,
                depth: u32, window: LightWindow,
                rng: ptr<function, Rng>, counters: ptr<function, PathCounters>) -> vec3<f32> {
    let origin = offset_ray_origin(surface.position, surface.position_error, surface.geometric_normal);
    let vertex = Vertex(surface, material, wo, depth, origin, time, own);
    var total = vec3<f32>(0.0);
    if (FEATURE_AREA_LIGHTS) {
        let choice = choose_light(depth, rng);
        if (choice.light != NONE) {
            total += sampled_light(choice.light, choice.share, 0u, vertex, window, rng, counters);
        }
    }
    var offset = frame.light_choice_pairs;
    for (var l = 0u; l < frame.light_choice_start; l += 1u) {
        let light = lights[l];
        if (FEATURE_AREA_LIGHTS && is_sampled_light(light)) {
            total += sampled_light(l, every_vertex_share(light), offset, vertex, window, rng, counters);
            offset += light.samples;
        } else if (FEATURE_PUNCTUAL_LIGHTS && window_is_first(window)) {
            let s = punctual_light_sample(light, surface, material, wo);
            if (s.traced && vertex_sees(vertex, s, counters)) {
                total += s.f;
            }
        }
    }
    return total;
}

// What the camera ray's first hit shows, for the AOV layers (zero where it hits nothing).
struct FirstHit {
    depth: f32,
    normal: vec3<f32>,
    albedo: vec3<f32>,
}

fn first_hit_of(t: f32, surface: Surface, material: GpuMaterial) -> FirstHit {
    var albedo = vec3<f32>(0.0);
    if (material.model == MODEL_DIELECTRIC) {
        albedo = vec3<f32>(1.0);
    } else if (material.model != MODEL_EMITTER) {
        albedo = min(material.diffuse + material.mirror, vec3<f32>(1.0));
    }
    return FirstHit(t, surface.shading_normal, albedo);
}

// The surface of primitive `id` hit by `ray` at the ray's time: found in the primitive's own
// frame, then moved to where it is. Twin: moved_surface_at in src/integrator.rs.
fn moved_surface_at(id: u32, ray: RayQuery, hit: Hit) -> Surface {
    let offset = prim_offset(id, ray.time);
    if (all(offset == vec3<f32>(0.0))) {
        return surface_at(prims[id], ray, hit);
    }
    var surface = surface_at(prims[id], ray_relative_to(ray, offset), hit);
    surface.position += offset;
    surface.position_error += (abs(surface.position) + abs(offset)) * 5.9604645e-8; // 2^-24
    return surface;
}

// The material of `prim` at `surface`, its diffuse reflectance times its texture's colour
// there where it has one. Twin: `material_at` in src/integrator.rs.
fn material_at(prim: GpuPrimitive, hit: Hit, surface: Surface) -> GpuMaterial {
    var material = materials[prim.material];
    if (material.texture != 0u) {
        let outward = select(-surface.geometric_normal, surface.geometric_normal, surface.front_facing);
        let uv = texture_coordinates(prim, hit, outward);
        material.diffuse *= texture_lookup(textures[material.texture - 1u], uv);
    }
    return material;
}

// The camera ray's query: what the path's first closest-hit search traces.
fn camera_query(camera_ray: CameraRay) -> RayQuery {
    return ray_at_time(ray_query_new(camera_ray.origin, camera_ray.direction), camera_ray.time);
}

// Radiance along the path of `camera_ray`, which traces every ray itself: its loop has one
// traversal call site, which lavapipe runs 15-25% faster on mirror scenes than a loop whose
// traversal is skipped at depth 0 for a camera ray's hit passed in. The CPU twin (trace_path in src/integrator.rs) may be given
// the camera ray's hit (`CameraHit`): its `trace_pixel` traces a pixel's camera rays in packets.
fn trace_path(camera_ray: CameraRay, window: LightWindow, rng: ptr<function, Rng>,
              counters: ptr<function, PathCounters>, first_hit: ptr<function, FirstHit>) -> vec3<f32> {
    let first = window_is_first(window);
    let time = camera_ray.time;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var ray = camera_query(camera_ray);
    var skip = NONE;
    for (var depth = 0u; depth <= frame.max_depth; depth += 1u) {
        (*counters).rays += 1u;
        let found = cw_closest_hit(ray, skip, T_FAR);
        if (found.prim == NONE) {
            if (first) {
                radiance += throughput * frame.background;
                radiance += throughput * sky_seen(ray.direction, 0.0);
            }
            break;
        }
        let prim = prims[found.prim];
        let surface = moved_surface_at(found.prim, ray, found.hit);
        let material = material_at(prim, found.hit, surface);
        if (depth == 0u) {
            *first_hit = first_hit_of(found.hit.t, surface, material);
        }
        // An area light shows its radiance from the front, is black from behind, reflects nothing.
        if (material.model == MODEL_EMITTER) {
            if (surface.front_facing && first) {
                radiance += throughput * material.emission;
            }
            break;
        }
        let wo = -ray.direction;
        if (first) {
            radiance += throughput * material.diffuse * frame.ambient;
        }
        // Rays leaving a flat primitive skip it; a curved one may shadow or reflect itself.
        let own = select(NONE, found.prim, leaving_rays_skip(prim.kind, surface.front_facing));
        radiance += throughput * direct_light(time, surface, material, own, wo, depth, window, rng, counters);
        // Perfect mirror bounce.
        if (!FEATURE_MIRRORS || max(max(material.mirror.x, material.mirror.y), material.mirror.z) <= 0.0) {
            break;
        }
        if (depth == frame.max_depth) {
            if (first) {
                (*counters).truncated += 1u;
            }
            break;
        }
        let n = surface.shading_normal;
        let reflected = ray.direction - 2.0 * dot(ray.direction, n) * n;
        if (dot(reflected, surface.geometric_normal) <= 0.0) {
            break;
        }
        throughput *= material.mirror;
        ray = ray_at_time(ray_query_new(offset_ray_origin(surface.position, surface.position_error, surface.geometric_normal), normalize(reflected)), time);
        skip = own;
    }
    return radiance;
}

// A camera sample: the ray and the time it is traced at.
// `weight`: what its radiance counts for (1, or through a real lens its exit-pupil sample's
// weight, 0 when lost in the lens); `wavelength`: nm in the spectral mode, 0 outside it.
struct CameraRay {
    origin: vec3<f32>,
    direction: vec3<f32>,
    time: f32,
    weight: f32,
    wavelength: f32,
}

// What a camera sample's RGB radiance counts for in each channel: its weight, times the film's
// response at its wavelength in the spectral mode (Rust twin: CameraRay::counts_for).
fn camera_counts_for(weight: f32, wavelength: f32) -> vec3<f32> {
    if (wavelength > 0.0) {
        return weight * film_response(wavelength);
    }
    return vec3<f32>(weight);
}

// The wavelength of camera sample `sample` of pixel (x, y) in the spectral mode (0 outside it),
// from dimension TIME_DIMENSION + 1 of its own stream: under the stratified pattern one of spp
// strata of the range per sample, else the second coordinate of the pattern's point at
// TIME_DIMENSION. Twin: camera_wavelength in src/integrator.rs.
fn camera_wavelength(x: u32, y: u32, sample: u32) -> f32 {
    if (camera.spectral == 0u) {
        return 0.0;
    }
    var rng = sample_rng(x, y, sample);
    rng_seek(&rng, TIME_DIMENSION);
    if (frame.pixel_sampler == SAMPLER_STRATIFIED && frame.progressive == 0u) {
        let key = pixel_hash(frame.seed, y * frame.width + x, TIME_DIMENSION + 1u);
        let stratum = permute(sample, frame.spp, key);
        return sample_wavelength((f32(stratum) + rng_next_2d(&rng).y) / f32(frame.spp));
    }
    let source = PatternSource(frame.pixel_sampler, frame.pixel_strata_columns, frame.pixel_table_offset, TIME_DIMENSION);
    return sample_wavelength(sample_2d(source, x, y, sample, &rng).y);
}

// Camera sample `sample` of pixel (x, y): position in the pixel (random dimensions 0-1), lens
// point (2-3, drawn only by a lens), time (4, drawn only while the shutter is open a while),
// wavelength (5, camera_wavelength), drawn from `rng`, which the path then goes on drawing
// from. Twin: camera_sample in src/integrator.rs.
fn camera_sample(x: u32, y: u32, sample: u32, rng: ptr<function, Rng>) -> CameraRay {
    let pixel_source = PatternSource(frame.pixel_sampler, frame.pixel_strata_columns, frame.pixel_table_offset, PIXEL_DIMENSION);
    let jitter = sample_2d(pixel_source, x, y, sample, rng);
    let raster = vec2<f32>(f32(x) + jitter.x, f32(y) + jitter.y);
    let film = film_position_mm(camera, frame.width, frame.height, raster);
    var lens = vec2<f32>(0.0, 0.0);
    if (FEATURE_LENS && camera.lens_radius_mm > 0.0) {
        let lens_source = PatternSource(frame.lens_sampler, frame.lens_strata_columns, frame.lens_table_offset, LENS_DIMENSION);
        let u = sample_2d(lens_source, x, y, sample, rng);
        if (camera.projection == PROJECTION_LENS) {
            lens = u;
        } else {
            lens = sample_aperture(u);
        }
    }
    var time = camera.shutter_open;
    if (camera.shutter_span > 0.0) {
        rng_seek(rng, TIME_DIMENSION);
        let time_source = PatternSource(frame.pixel_sampler, frame.pixel_strata_columns, frame.pixel_table_offset, TIME_DIMENSION);
        time += sample_2d(time_source, x, y, sample, rng).x * camera.shutter_span;
    }
    let wavelength = camera_wavelength(x, y, sample);
    if (camera.projection == PROJECTION_LENS) {
        let traced = generate_lens_ray(film, lens, wavelength);
        return CameraRay(traced.ray.origin, traced.ray.direction, time, traced.weight, wavelength);
    }
    let ray = generate_ray(camera, film, lens);
    return CameraRay(ray.origin, ray.direction, time, 1.0, wavelength);
}

// The random numbers of camera sample `sample` of pixel (x, y).
fn sample_rng(x: u32, y: u32, sample: u32) -> Rng {
    return rng_new(frame.seed, y * frame.width + x, sample);
}

// Radiance of camera sample `sample` of pixel (x, y), its path traced whole.
fn trace_sample(x: u32, y: u32, sample: u32, window: LightWindow,
                counters: ptr<function, PathCounters>, first_hit: ptr<function, FirstHit>) -> vec3<f32> {
    var rng = sample_rng(x, y, sample);
    let camera_ray = camera_sample(x, y, sample, &rng);
    return trace_path(camera_ray, window, &rng, counters, first_hit)
        * camera_counts_for(camera_ray.weight, camera_ray.wavelength);
}
