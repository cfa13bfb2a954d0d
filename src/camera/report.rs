//! The text `chambre camera SCENE` prints: what the camera's settings mean in object space.

use std::fmt::Write;

use glam::{DMat4, DVec3};

use super::glass::ReferenceLine;
use super::lens::LensSystem;
use super::lens_focus::{traced_focus, triangle_samples};
use super::optics::{Line, Plane};
use super::{CameraSpec, Focus};
use crate::layout::{SPECTRAL_MAX_NM, SPECTRAL_MIN_NM};

fn v3(v: DVec3) -> String {
    format!("[{:.6}, {:.6}, {:.6}]", v.x, v.y, v.z)
}

fn plane(p: Option<Plane>) -> String {
    match p {
        Some(p) => format!("point {}, normal {}", v3(p.point), v3(p.normal)),
        None => "at infinity".into(),
    }
}

fn line(l: Option<Line>) -> String {
    match l {
        Some(l) => format!("point {}, direction {}", v3(l.point), v3(l.direction)),
        None => "at infinity (lens and film are parallel)".into(),
    }
}

fn matrix(m: DMat4) -> String {
    (0..4)
        .map(|r| {
            let row = m.row(r);
            format!(
                "  [{:>14.8}, {:>14.8}, {:>14.8}, {:>14.8}]\n",
                row.x, row.y, row.z, row.w
            )
        })
        .collect()
}

/// The multi-line report for circle of confusion `coc_mm` and a far clipping plane `far`
/// (scene units) for the raster projection.
pub fn camera_report(camera: &CameraSpec, coc_mm: f64, far: f64) -> String {
    if camera.is_orthographic() {
        return orthographic_report(camera, far);
    }
    let thin = thin_lens_report(camera, coc_mm, far);
    match &camera.lens {
        Some(lens) => thin + &coverage_report(camera, lens),
        None => thin,
    }
}

/// The traced blur `focus_points` leaves through a real lens (`lens_focus`), at the points and
/// over their triangle.
fn traced_blur_line(camera: &CameraSpec, points: &[DVec3; 3]) -> String {
    match traced_focus(camera, &triangle_samples(points)) {
        Ok(traced) => {
            let um: Vec<String> = traced.iter().map(|t| format!("{:.1}", t.blur_um)).collect();
            format!(
                "  traced blur (RMS radius on the film): {} um at the points, {} um at their \
                 triangle's side midpoints and centroid",
                um[..3].join(", "),
                um[3..].join(", ")
            )
        }
        Err(e) => format!("  traced blur: {e}"),
    }
}

/// A real lens's part of `chambre camera`: the prescription's report, the light at the film's
/// corners and how far each movement may go inside the image circle.
fn coverage_report(camera: &CameraSpec, lens: &LensSystem) -> String {
    let mut out = String::from(
        "\nreal lens (paraxial and traced; the planes above are its paraxial ones, object \
         distances from H):\n",
    );
    out += &lens_report(lens);
    if camera.spectral {
        let _ = writeln!(
            out,
            "{:<28} on: each sample at its own wavelength, {SPECTRAL_MIN_NM}-{SPECTRAL_MAX_NM} nm",
            "spectral mode"
        );
    }
    if let Some(corners) = camera.corner_illumination() {
        let percent: Vec<String> = corners
            .iter()
            .map(|c| format!("{:.0}%", 100.0 * c))
            .collect();
        let _ = writeln!(
            out,
            "{:<28} {} (bottom left, bottom right, top right, top left)",
            "light at the film's corners",
            percent.join(", ")
        );
    }
    if let Some([bounded, whole]) = camera.passing_fractions() {
        let _ = writeln!(
            out,
            "{:<28} {:.0}% through the film cells' pupil bounds, {:.0}% aimed at the rear element",
            "camera rays that pass",
            100.0 * bounded,
            100.0 * whole
        );
    }
    let _ = writeln!(
        out,
        "how far each movement may go with every corner above half the axis's light:"
    );
    for (movement, limit) in camera.movement_limits() {
        let reach = match limit {
            Some(v) => format!("{v:.2}"),
            None => "none: a corner is already below half".to_string(),
        };
        let _ = writeln!(out, "  {:<34} {reach}", movement.label());
    }
    out
}

/// `chambre camera` for the thin lens (a real lens's camera as the thin lens at its H').
fn thin_lens_report(camera: &CameraSpec, coc_mm: f64, far: f64) -> String {
    let mut out = String::new();
    let m = &camera.movements;
    let fov = camera.field_of_view_deg();
    let w = &mut out;
    let _ = writeln!(
        w,
        "lens: f = {} mm, {}, aperture {}",
        camera.focal_length_mm,
        if camera.is_pinhole() {
            "pinhole".to_string()
        } else {
            format!(
                "f/{} ({:.4} mm)",
                camera.f_number,
                2.0 * camera.lens_radius_mm()
            )
        },
        if camera.aperture_blades == 0 {
            "circular".to_string()
        } else {
            format!(
                "{} blades, rotated {} deg",
                camera.aperture_blades, camera.aperture_rotation_deg
            )
        }
    );
    let _ = writeln!(
        w,
        "film: {} x {} mm at {:.6} mm behind the lens (along the rail)",
        camera.film_mm[0], camera.film_mm[1], camera.film_distance_mm
    );
    let _ = writeln!(
        w,
        "movements: film tilt {:.6}, swing {:.6} deg, shift {:?} mm; lens tilt {:.6}, swing {:.6} deg, shift {:?} mm",
        m.film_tilt, m.film_swing, m.film_shift, m.lens_tilt, m.lens_swing, m.lens_shift
    );
    if let Focus::Points(points) = camera.focus {
        let _ = writeln!(
            w,
            "focus_points {}, {}, {}: solved lens tilt {:.6} deg, lens swing {:.6} deg, film distance {:.6} mm",
            v3(points[0]),
            v3(points[1]),
            v3(points[2]),
            m.lens_tilt,
            m.lens_swing,
            camera.film_distance_mm
        );
        if camera.lens.is_some() {
            let _ = writeln!(w, "{}", traced_blur_line(camera, &points));
        }
    }
    if m.lens_pivot != [0.0; 3] {
        let _ = writeln!(
            w,
            "lens pivot: {:?} mm from the lens centre (unturned lens frame)",
            m.lens_pivot
        );
    }
    let _ = writeln!(w, "field of view: {:.4} x {:.4} deg", fov[0], fov[1]);
    if camera.is_pinhole() {
        let _ = writeln!(w, "focus: a pinhole renders everything sharp");
    } else {
        let focus = camera.focus_plane();
        let _ = writeln!(w, "plane of sharp focus: {}", plane(focus));
        if let Some(distance) = focus.and_then(|p| camera.distance_along_chief_ray(&p)) {
            let _ = writeln!(
                w,
                "  meets the image centre's chief ray at {distance:.6} units"
            );
        }
        let _ = writeln!(
            w,
            "lens-to-film angle: {:.6} deg",
            camera.lens_to_film_angle_deg()
        );
        let _ = writeln!(w, "hinge line: {}", line(camera.hinge_line()));
        if let Some(hinge) = camera.hinge_line() {
            let lens = camera.camera_to_world(camera.standards().lens_center);
            let _ = writeln!(
                w,
                "  at {:.6} units from the lens centre (f / sin(angle))",
                hinge.distance_to(lens)
            );
        }
        let _ = writeln!(w, "Scheimpflug line: {}", line(camera.scheimpflug_line()));
        if let Some((near, far_limit)) = camera.depth_of_field(coc_mm) {
            let _ = writeln!(w, "depth of field for a {coc_mm} mm circle of confusion:");
            let limit = |p: Option<Plane>, missing: &str| match p {
                None => missing.to_string(),
                Some(plane) => match camera.distance_along_chief_ray(&plane) {
                    Some(d) => format!(
                        "{} (at {d:.6} units along the image centre's chief ray)",
                        self::plane(Some(plane))
                    ),
                    None => format!(
                        "{} (not crossed by the image centre's chief ray)",
                        self::plane(Some(plane))
                    ),
                },
            };
            if coc_mm >= 2.0 * camera.lens_radius_mm() {
                let _ = writeln!(
                    w,
                    "  near limit: at the lens (the circle of confusion is not smaller than the aperture)"
                );
            } else {
                let _ = writeln!(w, "  near limit: {}", limit(near, "at infinity"));
            }
            let _ = writeln!(w, "  far limit:  {}", limit(far_limit, "beyond infinity"));
        }
    }
    let _ = writeln!(
        w,
        "raster equivalent of the film-tilted pinhole (OpenGL conventions, scene units):"
    );
    raster_section(w, camera, far, "frustum");
    out
}

/// An orthographic camera has no lens, focus or field of view: its window, the direction of
/// its rays against the window, and its raster equivalent.
fn orthographic_report(camera: &CameraSpec, far: f64) -> String {
    let mut out = String::new();
    let m = &camera.movements;
    let [width, height] = camera.window();
    let shift = m.film_shift.map(|v| v * camera.units_per_mm);
    let w = &mut out;
    let _ = writeln!(
        w,
        "projection: orthographic (parallel rays from a window; no lens, everything sharp)"
    );
    let _ = writeln!(
        w,
        "window: {width:.6} x {height:.6} scene units, square to the view, in the plane \
         through the camera position"
    );
    let _ = writeln!(
        w,
        "movements: film tilt {:.6}, swing {:.6} deg, shift [{:.6}, {:.6}] scene units",
        m.film_tilt, m.film_swing, shift[0], shift[1]
    );
    let _ = writeln!(
        w,
        "rays: direction {}, {:.6} deg from the window's normal{}",
        v3(camera.ray_direction()),
        camera.oblique_angle_deg(),
        if camera.oblique_angle_deg() == 0.0 {
            ""
        } else {
            " (an oblique projection: planes parallel to the window keep their true shape)"
        }
    );
    let _ = writeln!(
        w,
        "raster equivalent of the orthographic camera (OpenGL conventions, scene units; the \
         film tilt and swing shear it):"
    );
    raster_section(w, camera, far, "window");
    out
}

/// The raster projection's parameters and matrices; `what` names the first line's figures.
fn raster_section(w: &mut String, camera: &CameraSpec, far: f64, what: &str) {
    let raster = camera.raster_projection(far);
    let f = raster.frustum;
    let _ = writeln!(
        w,
        "  {what}: left {:.8}, right {:.8}, bottom {:.8}, top {:.8}, near {:.8}, far {}",
        f.left, f.right, f.bottom, f.top, f.near, f.far
    );
    let _ = write!(
        w,
        "  view matrix (world -> eye, rows):\n{}",
        matrix(raster.view)
    );
    let _ = write!(
        w,
        "  projection matrix (rows):\n{}",
        matrix(raster.projection)
    );
    let _ = write!(
        w,
        "  projection * view (rows):\n{}",
        matrix(raster.matrix())
    );
}

/// The camera in one line, as `chambre check` prints it.
pub fn camera_summary(camera: &CameraSpec) -> String {
    if camera.is_orthographic() {
        let [w, h] = camera.window();
        return format!(
            "camera: orthographic, window {w:.6} x {h:.6} scene units, rays {:.2} deg from its \
             normal",
            camera.oblique_angle_deg()
        );
    }
    let fov = camera.field_of_view_deg();
    format!(
        "camera: f = {:.2} mm, film at {:.3} mm, field of view {:.2} x {:.2} deg, {}",
        camera.focal_length_mm,
        camera.film_distance_mm,
        fov[0],
        fov[1],
        if camera.is_pinhole() {
            "pinhole".to_string()
        } else {
            format!("f/{}", camera.f_number)
        }
    )
}

/// The lateral colour seen from a film point `height` mm off the axis on the film focused at
/// infinity: the chief rays at `short` and `long` nm leave at different angles, and f times the
/// difference of their slopes is how far apart the two colours of one distant point land.
fn lateral_colour(lens: &LensSystem, height: f64, short: f64, long: f64) -> String {
    let film = DVec3::new(0.0, height, -lens.paraxial.focal_length);
    let slope = |nm: f64| {
        lens.at_wavelength(nm)
            .chief_ray(film)
            .map(|(_, d)| d.y / d.z)
    };
    match (slope(short), slope(long)) {
        (Some(a), Some(b)) => format!(
            "{:+.2} µm between {short:.1} and {long:.1} nm, {height:.2} mm off the axis (chief rays)",
            1e3 * lens.paraxial.focal_length * (a - b)
        ),
        _ => format!("the chief ray {height:.2} mm off the axis does not pass"),
    }
}

/// What `chambre lens` prints: a prescription's paraxial properties (mm, along the axis from the
/// first vertex towards the film) and its image circle at the f-number it is set to, for a film
/// focused at infinity.
pub fn lens_report(lens: &LensSystem) -> String {
    let p = &lens.paraxial;
    let f = p.focal_length;
    let circle = lens.image_circle(f, f / 400.0, 4.0 * f);
    let mut out = String::new();
    let mut line = |label: &str, value: String| {
        let _ = writeln!(out, "{label:<28} {value}");
    };
    line("surfaces", lens.surfaces.len().to_string());
    line("focal length", format!("{f:.4} mm"));
    line(
        "back focal distance",
        format!("{:.4} mm", p.back_focal_distance),
    );
    line(
        "front focal distance",
        format!("{:.4} mm", p.front_focal_distance),
    );
    line(
        "front principal point H",
        format!("{:.4} mm", p.front_principal),
    );
    line(
        "rear principal point H'",
        format!("{:.4} mm", p.rear_principal),
    );
    line("last vertex", format!("{:.4} mm", p.last_vertex));
    let stop_scale = p.widest_f_number / lens.f_number;
    line(
        "entrance pupil",
        format!(
            "at {:.4} mm, diameter {:.4} mm",
            p.entrance_pupil,
            p.entrance_pupil_diameter * stop_scale
        ),
    );
    line(
        "exit pupil",
        format!(
            "at {:.4} mm, diameter {:.4} mm",
            p.exit_pupil,
            p.exit_pupil_diameter * stop_scale
        ),
    );
    line(
        "f-number",
        format!("f/{:.3} (widest f/{:.3})", lens.f_number, p.widest_f_number),
    );
    if lens.is_dispersive() {
        let names = match lens.prescription.line {
            ReferenceLine::D => ["d", "F", "C"],
            ReferenceLine::E => ["e", "F'", "C'"],
        };
        let (short, long) = lens.prescription.line.abbe_span();
        let at = |nm: f64| lens.prescription.at_wavelength(nm).paraxial();
        let (blue, red) = (at(short), at(long));
        line(
            "glass dispersion",
            format!(
                "indices at the {} line ({:.2} nm); spectral mode available",
                names[0],
                lens.prescription.line.nm()
            ),
        );
        line(
            "axial colour",
            format!(
                "back focal distance {:+.4} mm from {} ({short:.1} nm) to {} ({long:.1} nm); \
                 focal length {:.4} to {:.4} mm",
                red.back_focal_distance - blue.back_focal_distance,
                names[1],
                names[2],
                blue.focal_length,
                red.focal_length
            ),
        );
        line(
            "lateral colour",
            lateral_colour(lens, 0.7 * circle.half_radius, short, long),
        );
    }
    // The search stops at 4 f from the axis: a circle reaching that far is reported as such.
    let reach = 4.0 * f;
    let edge = |radius: f64, what: &str| match radius >= reach {
        true => format!("beyond {:.2} mm {what}", 2.0 * reach),
        false => format!("{:.2} mm {what}", 2.0 * radius),
    };
    line(
        "image circle at infinity",
        format!(
            "diameter {}, {} (cos^4 and vignetting)",
            edge(circle.half_radius, "at half illumination"),
            edge(circle.dark_radius, "to dark")
        ),
    );
    out
}
