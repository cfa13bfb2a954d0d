// Primary-ray generation: the view camera (pinhole or thin lens, with movements), or an
// orthographic camera (parallel rays from a window).
// Mirrors: src/camera/mod.rs (see there and docs/camera.md for the ray-transfer form; film
// and lens movements are folded into GpuCamera on the CPU).

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
