// Primary-ray generation: the view camera (pinhole or thin lens, with movements), or an
// orthographic camera (parallel rays from a window).
// Mirrors: src/camera/mod.rs (see there and docs/camera.md for the ray-transfer form; film
// and lens movements are folded into GpuCamera on the CPU), and src/camera/lens.rs for a real
// lens's rays (docs/lens.md).

struct Ray {
    origin: vec3<f32>,
    direction: vec3<f32>,
}

fn film_position_mm(camera: GpuCamera, width: u32, height: u32, raster: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(
        (raster.x / f32(width) - 0.5) * camera.film_width_mm,
        (0.5 - raster.y / f32(height)) * camera.film_height_mm,
    );
}

fn lens_to_world(camera: GpuCamera, v: vec3<f32>) -> vec3<f32> {
    return v.x * camera.lens_to_world_x + v.y * camera.lens_to_world_y + v.z * camera.lens_to_world_z;
}

// Where the chief ray of `film_point` meets a curved focal surface (Rust twin:
// camera::curved_focus_point).
fn curved_focus_point(surface: u32, radius_mm: f32, film_point: vec3<f32>) -> vec3<f32> {
    let chief = -normalize(film_point);
    var reach = 1.0;
    if (surface == FOCUS_CYLINDER) {
        reach = length(chief.xz);
    }
    return chief * (radius_mm / reach);
}

fn generate_ray(camera: GpuCamera, film_mm: vec2<f32>, lens_mm: vec2<f32>) -> Ray {
    let film_point = camera.film_center + film_mm.x * camera.film_u + film_mm.y * camera.film_v;
    if (camera.projection == PROJECTION_ORTHOGRAPHIC) {
        // Parallel rays along the lens frame's z, each from its window point. A uniform
        // branch: every invocation of a dispatch takes the same side.
        let origin_lens = film_point * camera.units_per_mm;
        return Ray(camera.lens_center + lens_to_world(camera, origin_lens), camera.lens_to_world_z);
    }
    var direction_lens: vec3<f32>;
    if (camera.focus_surface == FOCUS_PLANE) {
        // Thin-lens ray transfer: outgoing slope = incoming slope - h / f.
        let slope_in = (lens_mm - film_point.xy) / -film_point.z;
        let slope_out = slope_in - lens_mm * camera.inv_focal_length_mm;
        direction_lens = normalize(vec3<f32>(slope_out, 1.0));
    } else {
        let sharp = curved_focus_point(camera.focus_surface, camera.focus_radius_mm, film_point);
        direction_lens = normalize(sharp - vec3<f32>(lens_mm, 0.0));
    }
    let origin_lens = vec3<f32>(lens_mm, 0.0) * camera.units_per_mm;
    return Ray(camera.lens_center + lens_to_world(camera, origin_lens), lens_to_world(camera, direction_lens));
}

// A real lens's table entry k (GpuCamera::lens_table_offset; LensSystem::kernel_table).
fn lens_entry(k: u32) -> vec2<f32> {
    return sample_table[camera.lens_table_offset + k];
}

// Distance along a ray to a real lens's surface at `z` of radius `radius` (0: a plane),
// on its cap about the vertex; negative when it is missed (Rust twin: lens::surface_distance).
fn lens_surface_distance(z: f32, radius: f32, o: vec3<f32>, d: vec3<f32>) -> f32 {
    if (radius == 0.0) {
        let t = (z - o.z) / d.z;
        if (t >= 0.0 && abs(t) <= 3.0e38) {
            return t;
        }
        return -1.0;
    }
    let centre = vec3<f32>(0.0, 0.0, z - radius);
    let oc = o - centre;
    let b = dot(oc, d);
    let c = dot(oc, oc) - radius * radius;
    let discriminant = b * b - c;
    if (discriminant < 0.0) {
        return -1.0;
    }
    let root = sqrt(discriminant);
    var t = -b - root;
    if (radius > 0.0) {
        t = -b + root;
    }
    let p = o + t * d;
    if (t > 0.0 && (p.z - centre.z) * radius > 0.0) {
        return t;
    }
    return -1.0;
}

// A glass's index at `nm` nanometres from its Sellmeier terms (B, C) at table entry `k` and the
// two after it (Rust twin: lens::sellmeier_index).
fn lens_sellmeier_index(k: u32, nm: f32) -> f32 {
    let l2 = (nm * 1e-3) * (nm * 1e-3);
    var sum = 0.0;
    for (var term = 0u; term < 3u; term++) {
        let t = lens_entry(k + term);
        sum += t.x * l2 / (l2 - t.y);
    }
    return sqrt(1.0 + sum);
}

// The wavelength (nm) of a spectral sample whose pattern point is `u` (Rust twin:
// camera::spectral::sample_wavelength).
fn sample_wavelength(u: f32) -> f32 {
    return f32(SPECTRAL_MIN_NM) + u * f32(SPECTRAL_MAX_NM - SPECTRAL_MIN_NM);
}

// What an RGB radiance counts for in each channel at wavelength `nm`: the film's three bands
// (Rust twin: camera::spectral::film_response).
fn film_response(nm: f32) -> vec3<f32> {
    let half = 0.5 * f32(SPECTRAL_CROSSOVER_NM);
    let width = f32(SPECTRAL_CROSSOVER_NM);
    let blue = clamp((f32(SPECTRAL_BLUE_GREEN_NM) + half - nm) / width, 0.0, 1.0);
    let red = clamp((nm - (f32(SPECTRAL_GREEN_RED_NM) - half)) / width, 0.0, 1.0);
    return 3.0 * vec3<f32>(red, 1.0 - blue - red, blue);
}

// Snell's law for `d` through a surface of normal `n` facing against it, index ratio `eta`
// (incident / transmitted); a zero vector on total internal reflection (Rust twin:
// lens::refract_f32).
fn lens_refract(d: vec3<f32>, n: vec3<f32>, eta: f32) -> vec3<f32> {
    let cos_i = -dot(n, d);
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if (sin2_t >= 1.0) {
        return vec3<f32>(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return normalize(eta * d + (eta * cos_i - cos_t) * n);
}

// A camera ray through a real lens and its weight (0: lost in the lens, the ray then the chief
// ray through the lens centre).
struct LensRay {
    ray: Ray,
    weight: f32,
}

// The ray from image-plane point `film_mm` through a real lens, aimed at the point `u` of its
// film cell's exit-pupil bounds, at `wavelength` nm in the spectral mode (0: the reference
// line's indices) (Rust twin: camera::generate_lens_ray and lens::lens_ray).
fn generate_lens_ray(film_mm: vec2<f32>, u: vec2<f32>, wavelength: f32) -> LensRay {
    let film_point = camera.film_center + film_mm.x * camera.film_u + film_mm.y * camera.film_v;
    let cells = f32(LENS_PUPIL_CELLS);
    let cell = vec2<u32>(
        u32(clamp((film_mm.x / camera.film_width_mm + 0.5) * cells, 0.0, cells - 1.0)),
        u32(clamp((film_mm.y / camera.film_height_mm + 0.5) * cells, 0.0, cells - 1.0)),
    );
    let chief = LensRay(Ray(camera.lens_center, lens_to_world(camera, -normalize(film_point))), 0.0);
    let count = camera.lens_surface_count;
    let bounds = 1u + 2u * count + 2u * (cell.y * LENS_PUPIL_CELLS + cell.x);
    let lo = lens_entry(bounds);
    let hi = lens_entry(bounds + 1u);
    if (hi.x < lo.x) {
        return chief;
    }
    let aim = vec3<f32>(lo + u * (hi - lo), lens_entry(0u).y);
    let to = aim - film_point;
    let distance2 = dot(to, to);
    var d = to / sqrt(distance2);
    var o = film_point;
    let glasses = 1u + 2u * count + 2u * LENS_PUPIL_CELLS * LENS_PUPIL_CELLS;
    var index_behind = 1.0;
    for (var i = 0u; i < count; i++) {
        let shape = lens_entry(1u + 2u * i);
        let glass = lens_entry(2u + 2u * i);
        let t = lens_surface_distance(shape.x, shape.y, o, d);
        if (t < 0.0) {
            return chief;
        }
        o += t * d;
        if (o.x * o.x + o.y * o.y > glass.x * glass.x) {
            return chief;
        }
        var eta = glass.y;
        if (wavelength > 0.0) {
            let index_in_front = lens_sellmeier_index(glasses + 3u * i, wavelength);
            eta = index_behind / index_in_front;
            index_behind = index_in_front;
        }
        // A sphere always refracts; a plane (radius 0) where the index changes: the stop, in
        // air on both sides, only clips.
        if (shape.y != 0.0 || eta != 1.0) {
            var n = vec3<f32>(0.0, 0.0, 1.0);
            if (shape.y != 0.0) {
                n = normalize(o - vec3<f32>(0.0, 0.0, shape.x - shape.y));
            }
            if (dot(n, d) > 0.0) {
                n = -n;
            }
            d = lens_refract(d, n, eta);
            if (all(d == vec3<f32>(0.0))) {
                return chief;
            }
        }
    }
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    let cosines = abs(dot(cross(camera.film_u, camera.film_v), to)) * to.z / (distance2 * distance2);
    let origin = camera.lens_center + lens_to_world(camera, o * camera.units_per_mm);
    return LensRay(Ray(origin, lens_to_world(camera, d)), lens_entry(0u).x * area * cosines);
}
