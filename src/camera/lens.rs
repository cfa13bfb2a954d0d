//! Real lenses: a prescription of spherical surfaces and a stop, read from pbrt's tabular lens
//! format, its paraxial properties by ray-transfer matrices, and exact rays traced through it
//! (Snell's law at each surface, total internal reflection and every clear aperture stopping a
//! ray), in f64 on the CPU: the reference for the exit-pupil bounds, the image circle and the
//! tests. The kernels' f32 camera rays through the lens ([`lens_ray`], twin `generate_lens_ray`
//! in wgsl/camera.wgsl) read the table [`LensSystem::kernel_table`] writes. Model and equations:
//! `docs/lens.md`.
//!
//! A prescription lists its surfaces from the object side to the image side, one per line:
//! `radius thickness index aperture` in millimetres, where a positive radius has its centre of
//! curvature on the image side, `thickness` is the axial distance to the next surface, `index`
//! is the refractive index of the medium after the surface (towards the image) and `aperture`
//! the clear diameter; a glass may add its dispersion (an Abbe number, or six Sellmeier terms:
//! [`super::glass`]), and a line `line e` says the indices are given at the e line rather than
//! d. A radius of 0 is the aperture stop (its index 0 or 1: it sits in air), its
//! diameter the stop's at the lens's widest f-number; a radius of `inf` (or `-inf`, `infinity`)
//! is a plane refracting surface (a flat face or cemented interface). The last thickness is
//! ignored: the film's distance is the camera's focus, not the lens's. `#` starts a comment.
//!
//! Placed in the lens frame, every plane (the stop and the plane glass surfaces) has radius 0
//! ([`PlacedSurface`], and the kernels' table): a plane refracts where its index ratio is not 1,
//! so the stop, in air on both sides, only clips. The stop is known by its index
//! ([`LensSystem::stop`]), not by its shape.
//!
//! The surfaces are placed in the camera's *lens frame* (optical axis +z towards the object,
//! lengths in mm) with the origin at the rear principal point H': the point the thin lens's
//! centre stands for, so that a film at `film_distance` = f behind it is focused at infinity
//! whatever the lens, and the movements turn the stack about it (in air the rear nodal point).

use std::path::Path;

use glam::{DVec2, DVec3, Vec2, Vec3};

use super::glass::{Glass, ReferenceLine};
use crate::error::{Error, Location, Result};
use crate::layout::{LENS_PUPIL_CELLS, SPECTRAL_MAX_NM, SPECTRAL_MIN_NM};

/// One surface of a prescription, as the file gives it (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrescriptionSurface {
    /// Radius of curvature; positive: the centre lies on the image side. 0: the aperture stop;
    /// infinite (either sign): a plane refracting surface.
    pub radius: f64,
    /// Axial distance to the next surface.
    pub thickness: f64,
    /// Refractive index of the medium after the surface (1 for air; the stop's is 1).
    pub index: f64,
    /// Clear aperture's diameter (the stop's at the widest f-number).
    pub aperture: f64,
    /// The medium after the surface against wavelength: its index at every wavelength when the
    /// file gives no dispersion.
    pub glass: Glass,
}

impl PrescriptionSurface {
    /// Whether this is the aperture stop.
    pub fn is_stop(&self) -> bool {
        self.radius == 0.0
    }

    /// Whether this is a plane refracting surface (an infinite radius).
    pub fn is_plane(&self) -> bool {
        self.radius.is_infinite()
    }
}

/// A lens prescription: its surfaces from the object side to the image side, with exactly one
/// stop.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescription {
    /// Surfaces, object side first.
    pub surfaces: Vec<PrescriptionSurface>,
    /// The line the indices (and Abbe numbers) are given at.
    pub line: ReferenceLine,
}

/// The column names of a prescription line, as errors name them: four, then an Abbe number or
/// six Sellmeier terms.
const COLUMNS: [&str; 10] = [
    "radius",
    "thickness",
    "index",
    "aperture",
    "B1",
    "C1",
    "B2",
    "C2",
    "B3",
    "C3",
];

/// How far a glass's Sellmeier index at the reference line may lie from its `index` column: the
/// paraxial properties come from the column, the spectral mode's rays from the terms.
const SELLMEIER_INDEX_TOLERANCE: f64 = 1e-4;

/// Indices above this are not glass (diamond is 2.42; the bound catches a column mistaken for
/// another, such as a thickness in the index column).
const MAX_INDEX: f64 = 4.0;

impl Prescription {
    /// Reads a prescription file.
    pub fn read(path: &Path) -> Result<Prescription> {
        let text = std::fs::read_to_string(path).map_err(|cause| Error::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        Prescription::parse(path, &text)
    }

    /// Parses a prescription's text; `path` names the file in errors, with the line and column.
    pub fn parse(path: &Path, text: &str) -> Result<Prescription> {
        let error = |line: usize, field: &str, message: String| Error::Scene {
            location: Location {
                file: path.to_path_buf(),
                line,
                column: 1,
                field: field.to_string(),
            },
            message,
        };
        let mut surfaces = Vec::new();
        let mut surface_lines = Vec::new();
        let mut stop_line = None;
        let mut reference = None;
        for (number, line) in text.lines().enumerate().map(|(i, l)| (i + 1, l)) {
            let content = line.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let words: Vec<&str> = content.split_whitespace().collect();
            if words[0] == "line" {
                reference = Some(
                    reference_line(&words, reference, !surfaces.is_empty())
                        .map_err(|m| error(number, "line", m))?,
                );
                continue;
            }
            if ![4, 5, 10].contains(&words.len()) {
                return Err(error(
                    number,
                    "",
                    format!(
                        "{} numbers where a surface has 4 (radius, thickness, index, aperture,                          in mm), 5 (and an Abbe number) or 10 (and Sellmeier's B1 C1 B2 C2 B3 C3)",
                        words.len()
                    ),
                ));
            }
            let mut values = [0.0; 10];
            for (k, word) in words.iter().enumerate() {
                let column = if words.len() == 5 && k == 4 {
                    "abbe"
                } else {
                    COLUMNS[k]
                };
                values[k] = parse_field(k, word).map_err(|m| error(number, column, m))?;
            }
            let [radius, thickness, index, aperture] = [values[0], values[1], values[2], values[3]];
            let index = if radius == 0.0 && index == 0.0 {
                1.0
            } else {
                index
            };
            let mut surface = PrescriptionSurface {
                radius,
                thickness,
                index,
                aperture,
                glass: Glass::constant(index),
            };
            check_surface(&surface, |field, message| error(number, field, message))?;
            let line = reference.unwrap_or_default();
            surface.glass = surface_glass(index, &values[4..words.len()], line)
                .map_err(|(field, m)| error(number, field, m))?;
            surface_lines.push(number);
            if surface.is_stop() {
                if let Some(first) = stop_line {
                    return Err(error(
                        number,
                        "radius",
                        format!("a second aperture stop (radius 0); the first is on line {first}"),
                    ));
                }
                stop_line = Some(number);
            }
            surfaces.push(surface);
        }
        if stop_line.is_none() {
            return Err(error(
                0,
                "radius",
                "no aperture stop: one surface must have radius 0".to_string(),
            ));
        }
        if surfaces.last().is_some_and(|s| s.index != 1.0) {
            return Err(error(
                0,
                "index",
                "the last surface must leave the lens into air (index 1)".to_string(),
            ));
        }
        let dispersive = surfaces.iter().position(|s| !s.glass.is_constant());
        let plain = surfaces
            .iter()
            .position(|s| s.index != 1.0 && s.glass.is_constant());
        if let (Some(dispersive), Some(plain)) = (dispersive, plain) {
            return Err(error(
                surface_lines[plain],
                "abbe",
                format!(
                    "this glass has no dispersion while line {}'s has: give every glass an Abbe \
                     number or Sellmeier terms, or none",
                    surface_lines[dispersive]
                ),
            ));
        }
        Ok(Prescription {
            surfaces,
            line: reference.unwrap_or_default(),
        })
    }

    /// Whether its glasses disperse (the file gives their Abbe numbers or Sellmeier terms).
    pub fn is_dispersive(&self) -> bool {
        self.surfaces.iter().any(|s| !s.glass.is_constant())
    }

    /// The prescription with every index at `nm` nanometres (its paraxial properties there).
    pub fn at_wavelength(&self, nm: f64) -> Prescription {
        let mut p = self.clone();
        for s in &mut p.surfaces {
            if !s.is_stop() {
                s.index = s.glass.index(nm);
            }
        }
        p
    }

    /// The stop's position in `surfaces`.
    pub fn stop(&self) -> usize {
        self.surfaces
            .iter()
            .position(|s| s.is_stop())
            .expect("a parsed prescription has a stop")
    }

    /// The paraxial properties (ray-transfer matrices in f64).
    pub fn paraxial(&self) -> Paraxial {
        Paraxial::of(self)
    }
}

/// Column `column`'s number from `word`: finite, or for a radius also `inf`, `-inf` or
/// `infinity` (any case: a plane); the error's message otherwise.
fn parse_field(column: usize, word: &str) -> std::result::Result<f64, String> {
    let value = word.parse::<f64>().ok();
    let infinity_word = matches!(
        word.trim_start_matches(['+', '-'])
            .to_ascii_lowercase()
            .as_str(),
        "inf" | "infinity"
    );
    match value {
        Some(v) if v.is_finite() => Ok(v),
        Some(v) if column == 0 && v.is_infinite() && infinity_word => Ok(v),
        _ if column == 0 => Err(format!(
            "`{word}` is not a radius: a finite number of mm (positive: centre on the image \
             side), 0 for the aperture stop, or inf (-inf, infinity) for a plane surface"
        )),
        _ => Err(format!("`{word}` is not a finite number")),
    }
}

/// The reference line a `line d` or `line e` directive names; refused when it repeats or comes
/// after a surface (whose Abbe number would have been read at the other line).
fn reference_line(
    words: &[&str],
    earlier: Option<ReferenceLine>,
    after_surfaces: bool,
) -> std::result::Result<ReferenceLine, String> {
    let line = match words {
        [_, name] => ReferenceLine::parse(name),
        _ => None,
    }
    .ok_or_else(|| "write `line d` or `line e`: the line the indices are given at".to_string())?;
    if earlier.is_some() || after_surfaces {
        return Err("`line` comes once, before the first surface".to_string());
    }
    Ok(line)
}

/// The medium after a surface of index `index`, from the line's columns after the aperture:
/// none (its index at every wavelength), an Abbe number (0 or none for air), or six Sellmeier
/// terms (their index at `line` within `SELLMEIER_INDEX_TOLERANCE` of `index`). The error names
/// its column.
fn surface_glass(
    index: f64,
    dispersion: &[f64],
    line: ReferenceLine,
) -> std::result::Result<Glass, (&'static str, String)> {
    match *dispersion {
        [] => Ok(Glass::constant(index)),
        [abbe] if index == 1.0 => match abbe {
            0.0 => Ok(Glass::AIR),
            _ => Err((
                "abbe",
                format!("{abbe}: air has no Abbe number here (write 0 or leave it out)"),
            )),
        },
        [abbe] => Glass::from_abbe(index, abbe, line).map_err(|m| ("abbe", m)),
        [b1, c1, b2, c2, b3, c3] => {
            let glass = Glass::sellmeier([[b1, c1], [b2, c2], [b3, c3]]).map_err(|m| ("B1", m))?;
            let at_line = glass.index(line.nm());
            if (at_line - index).abs() > SELLMEIER_INDEX_TOLERANCE {
                return Err((
                    "B1",
                    format!(
                        "the Sellmeier terms give n = {at_line:.6} at the {line:?} line \
                         ({:.2} nm), the index column {index}",
                        line.nm()
                    ),
                ));
            }
            Ok(glass)
        }
        _ => Err((
            "",
            "after the aperture: an Abbe number or six Sellmeier terms".to_string(),
        )),
    }
}

/// Refuses a surface whose numbers cannot describe glass and air.
fn check_surface(s: &PrescriptionSurface, error: impl Fn(&str, String) -> Error) -> Result<()> {
    if s.thickness < 0.0 {
        return Err(error(
            "thickness",
            format!("{} mm: a thickness is at least 0", s.thickness),
        ));
    }
    if s.aperture <= 0.0 {
        return Err(error(
            "aperture",
            format!("{} mm: a clear aperture is above 0", s.aperture),
        ));
    }
    if s.is_stop() && s.index != 1.0 {
        return Err(error(
            "index",
            format!(
                "{}: the stop (radius 0) sits in air, its index 0 or 1",
                s.index
            ),
        ));
    }
    if !(1.0..=MAX_INDEX).contains(&s.index) {
        return Err(error(
            "index",
            format!("{}: a refractive index lies in [1, {MAX_INDEX}]", s.index),
        ));
    }
    if s.radius != 0.0 && s.aperture > 2.0 * s.radius.abs() {
        return Err(error(
            "aperture",
            format!(
                "{} mm is wider than the surface's sphere (radius {} mm)",
                s.aperture, s.radius
            ),
        ));
    }
    Ok(())
}

/// A 2x2 ray-transfer matrix acting on (height, index x angle).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Transfer {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
}

impl Transfer {
    const IDENTITY: Transfer = Transfer {
        a: 1.0,
        b: 0.0,
        c: 0.0,
        d: 1.0,
    };

    /// Refraction at a sphere of radius `radius` from index `before` to `after`: power
    /// (after - before) / radius; a plane (the stop's radius 0, or an infinite one) has none.
    fn refraction(radius: f64, before: f64, after: f64) -> Transfer {
        let power = if radius == 0.0 || radius.is_infinite() {
            0.0
        } else {
            (after - before) / radius
        };
        Transfer {
            c: -power,
            ..Transfer::IDENTITY
        }
    }

    /// Travel over `distance` in a medium of index `index` (reduced distance distance / index).
    fn translation(distance: f64, index: f64) -> Transfer {
        Transfer {
            b: distance / index,
            ..Transfer::IDENTITY
        }
    }

    /// `self` after `first`: the matrix of `first` followed by `self`.
    fn after(self, first: Transfer) -> Transfer {
        Transfer {
            a: self.a * first.a + self.b * first.c,
            b: self.a * first.b + self.b * first.d,
            c: self.c * first.a + self.d * first.c,
            d: self.c * first.b + self.d * first.d,
        }
    }
}

/// The matrix from just before surface `from` to just after surface `to - 1`, with the
/// thicknesses between them.
fn transfer(p: &Prescription, from: usize, to: usize) -> Transfer {
    let mut m = Transfer::IDENTITY;
    for i in from..to {
        let s = &p.surfaces[i];
        let before = if i == 0 { 1.0 } else { p.surfaces[i - 1].index };
        if i > from {
            let previous = &p.surfaces[i - 1];
            m = Transfer::translation(previous.thickness, previous.index).after(m);
        }
        m = Transfer::refraction(s.radius, before, s.index).after(m);
    }
    m
}

/// A lens's paraxial (first-order) properties, in mm along the axis from the first surface's
/// vertex towards the image (the *axial* coordinate t: the first vertex at 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paraxial {
    /// Effective focal length f = -1/C.
    pub focal_length: f64,
    /// Back focal distance: from the last vertex to the rear focal point.
    pub back_focal_distance: f64,
    /// Front focal distance: from the front focal point to the first vertex.
    pub front_focal_distance: f64,
    /// Axial position of the front principal point H.
    pub front_principal: f64,
    /// Axial position of the rear principal point H' (the lens frame's origin).
    pub rear_principal: f64,
    /// Axial position of the last vertex.
    pub last_vertex: f64,
    /// Axial position of the entrance pupil (the stop's image through the surfaces before it).
    pub entrance_pupil: f64,
    /// Entrance pupil's diameter at the prescription's stop diameter.
    pub entrance_pupil_diameter: f64,
    /// Axial position of the exit pupil (the stop's image through the surfaces after it).
    pub exit_pupil: f64,
    /// Exit pupil's diameter at the prescription's stop diameter.
    pub exit_pupil_diameter: f64,
    /// The widest f-number: f / entrance pupil diameter.
    pub widest_f_number: f64,
}

impl Paraxial {
    fn of(p: &Prescription) -> Paraxial {
        let n = p.surfaces.len();
        let stop = p.stop();
        let last_vertex: f64 = p.surfaces[..n - 1].iter().map(|s| s.thickness).sum();
        let whole = transfer(p, 0, n);
        let focal_length = -1.0 / whole.c;
        let back_focal_distance = -whole.a / whole.c;
        let front_focal_distance = -whole.d / whole.c;
        let stop_diameter = p.surfaces[stop].aperture;
        // Entrance pupil: the plane at distance e before the first vertex conjugate to the stop,
        // M_front T(e) having B = 0 (e = -B/A), magnified by A (both ends in air).
        let front = match stop {
            0 => Transfer::IDENTITY,
            _ => {
                let before = &p.surfaces[stop - 1];
                Transfer::translation(before.thickness, before.index).after(transfer(p, 0, stop))
            }
        };
        let entrance_distance = -front.b / front.a;
        // Exit pupil: the plane at q after the last vertex conjugate to the stop, T(q) M_rear
        // having B = 0 (q = -B/D), magnified by 1/D.
        let rear = transfer_from_stop(p, stop);
        let exit_distance = -rear.b / rear.d;
        let entrance_pupil_diameter = stop_diameter / front.a.abs();
        Paraxial {
            focal_length,
            back_focal_distance,
            front_focal_distance,
            front_principal: focal_length - front_focal_distance,
            rear_principal: last_vertex + back_focal_distance - focal_length,
            last_vertex,
            entrance_pupil: -entrance_distance,
            entrance_pupil_diameter,
            exit_pupil: last_vertex + exit_distance,
            exit_pupil_diameter: stop_diameter * rear.d.abs().recip(),
            widest_f_number: focal_length / entrance_pupil_diameter,
        }
    }
}

/// The matrix from the stop's plane to just after the last surface.
fn transfer_from_stop(p: &Prescription, stop: usize) -> Transfer {
    let n = p.surfaces.len();
    if stop + 1 == n {
        return Transfer::IDENTITY;
    }
    let s = &p.surfaces[stop];
    transfer(p, stop + 1, n).after(Transfer::translation(s.thickness, s.index))
}

/// One surface placed in the lens frame (mm, axis +z towards the object).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSurface {
    /// The vertex's z.
    pub z: f64,
    /// Radius with the prescription's sign (positive: centre towards the image, at z - radius);
    /// 0 for a plane (the stop, or a plane glass surface: its normal is the axis).
    pub radius: f64,
    /// Clear aperture's radius (the stop's at the chosen f-number).
    pub aperture_radius: f64,
    /// Index on the image (film) side.
    pub index_behind: f64,
    /// Index on the object side.
    pub index_in_front: f64,
    /// The medium on the image side against wavelength.
    pub glass_behind: Glass,
    /// The medium on the object side against wavelength.
    pub glass_in_front: Glass,
}

impl PlacedSurface {
    /// Whether a ray crossing the surface bends: a sphere always does (in one medium too, where
    /// Snell's law leaves it as it was), a plane where the index changes. The stop, in air on
    /// both sides, only clips; one written right behind glass is that glass's plane face.
    fn refracts(&self) -> bool {
        self.radius != 0.0 || self.index_behind != self.index_in_front
    }
}

/// A lens placed in the lens frame at an f-number: its surfaces from the film side (the first
/// a ray from the film meets) to the object side.
#[derive(Clone, Debug, PartialEq)]
pub struct LensSystem {
    /// Surfaces, rearmost first.
    pub surfaces: Vec<PlacedSurface>,
    /// Paraxial properties of the prescription.
    pub paraxial: Paraxial,
    /// The f-number the stop is set to.
    pub f_number: f64,
    /// The stop's position in `surfaces` (rearmost 0).
    pub stop: usize,
    /// The prescription it was placed from (its paraxial properties at other wavelengths).
    pub prescription: Prescription,
}

/// Why a ray from the film does not leave the lens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lost {
    /// It misses a surface's sphere or meets it outside the clear aperture (or on the far half
    /// of its sphere): the barrel or the stop blocks it. The index of the surface, rearmost 0.
    Blocked(usize),
    /// Total internal reflection at a surface.
    TotalInternalReflection(usize),
}

impl LensSystem {
    /// The prescription placed with H' at the origin, its stop closed to `f_number` (the
    /// prescription's widest when `None`). Refuses an f-number wider than the lens opens.
    pub fn new(
        prescription: &Prescription,
        f_number: Option<f64>,
    ) -> std::result::Result<LensSystem, String> {
        let paraxial = prescription.paraxial();
        if !(paraxial.focal_length.is_finite() && paraxial.focal_length > 0.0) {
            return Err(format!(
                "the lens's focal length is {:.6} mm: chambre's cameras need a converging lens",
                paraxial.focal_length
            ));
        }
        let widest = paraxial.widest_f_number;
        let f_number = f_number.unwrap_or(widest);
        if f_number < widest * (1.0 - 1e-9) {
            return Err(format!(
                "f/{f_number}: this lens opens to f/{widest:.3} at most"
            ));
        }
        let stop_scale = widest / f_number;
        let mut axial = 0.0;
        let mut surfaces = Vec::with_capacity(prescription.surfaces.len());
        for (i, s) in prescription.surfaces.iter().enumerate() {
            let in_front = match i {
                0 => None,
                _ => Some(&prescription.surfaces[i - 1]),
            };
            surfaces.push(PlacedSurface {
                z: paraxial.rear_principal - axial,
                radius: if s.is_plane() { 0.0 } else { s.radius },
                aperture_radius: 0.5 * s.aperture * if s.is_stop() { stop_scale } else { 1.0 },
                index_behind: s.index,
                index_in_front: in_front.map_or(1.0, |f| f.index),
                glass_behind: s.glass,
                glass_in_front: in_front.map_or(Glass::AIR, |f| f.glass),
            });
            axial += s.thickness;
        }
        surfaces.reverse();
        Ok(LensSystem {
            stop: surfaces.len() - 1 - prescription.stop(),
            surfaces,
            paraxial,
            f_number,
            prescription: prescription.clone(),
        })
    }

    /// The lens as it refracts light of `nm` nanometres: every index from its glass, the surfaces
    /// where the reference line placed them (H' stays the origin: the focus is set at the
    /// reference line, as a photographer focuses by eye).
    pub fn at_wavelength(&self, nm: f64) -> LensSystem {
        let mut lens = self.clone();
        for s in &mut lens.surfaces {
            s.index_behind = s.glass_behind.index(nm);
            s.index_in_front = s.glass_in_front.index(nm);
        }
        lens
    }

    /// The chief ray from `film_point` (lens frame, mm): the ray through the stop's centre,
    /// found by Newton's method on its aim until a step moves it by less than 1e-12 mm (then
    /// crossing the stop within 1e-7 mm of its centre), as it leaves the front surface; `None`
    /// when it does not pass or the search does not settle in 50 steps.
    pub fn chief_ray(&self, film_point: DVec3) -> Option<(DVec3, DVec3)> {
        // The surfaces behind the stop, and the ray's line carried on to the stop's plane (a stop
        // flush with a vertex would meet the ray a rounding error behind it on the axis).
        let behind_stop = LensSystem {
            surfaces: self.surfaces[..self.stop].to_vec(),
            ..self.clone()
        };
        let (z, stop_z) = (self.aim_z(), self.stop_z());
        let aim = |p: DVec2| (p.extend(z) - film_point).normalize();
        let crossing = |p: DVec2| {
            let (o, d) = behind_stop.trace_from_film(film_point, aim(p)).ok()?;
            Some((o + d * ((stop_z - o.z) / d.z)).truncate())
        };
        // Start where the straight line from the film point to the stop's centre crosses the
        // aim plane.
        let stop = DVec3::new(0.0, 0.0, stop_z);
        let t = (z - film_point.z) / (stop.z - film_point.z);
        let mut p = (film_point + t * (stop - film_point)).truncate();
        let step = 1e-6 * self.surfaces[self.stop].aperture_radius.max(1.0);
        for _ in 0..50 {
            let at = crossing(p)?;
            let dx = (crossing(p + DVec2::X * step)? - at) / step;
            let dy = (crossing(p + DVec2::Y * step)? - at) / step;
            let determinant = dx.x * dy.y - dy.x * dx.y;
            if determinant.abs() < 1e-300 {
                return None;
            }
            // Solve [dx dy] delta = -at.
            let delta =
                DVec2::new(at.x * dy.y - dy.x * at.y, dx.x * at.y - at.x * dx.y) / determinant;
            p -= delta;
            if delta.length() < 1e-12 {
                let at = crossing(p)?;
                if at.length() >= 1e-7 {
                    return None;
                }
                // On from the stop's centre through the surfaces before it.
                let in_front = LensSystem {
                    surfaces: self.surfaces[self.stop + 1..].to_vec(),
                    ..self.clone()
                };
                let (_, d) = behind_stop.trace_from_film(film_point, aim(p)).ok()?;
                return in_front.trace_from_film(at.extend(stop_z), d).ok();
            }
        }
        None
    }

    /// Whether its glasses disperse.
    pub fn is_dispersive(&self) -> bool {
        self.surfaces.iter().any(|s| !s.glass_behind.is_constant())
    }

    /// How far the front principal point H lies ahead of H' (mm, along +z): object distances
    /// from the lens centre (H') less this are the thick lens's object distances from H.
    pub fn principal_gap(&self) -> f64 {
        self.paraxial.rear_principal - self.paraxial.front_principal
    }

    /// The stop's z (mm, lens frame).
    pub fn stop_z(&self) -> f64 {
        self.surfaces[self.stop].z
    }

    /// The rear surface's vertex z (the lens's back, towards the film).
    pub fn rear_z(&self) -> f64 {
        self.surfaces[0].z
    }

    /// The ray from `origin` (behind the lens, lens frame, mm) along `direction` (unit, +z
    /// component) traced through every surface: the ray leaving the front surface, or why it
    /// is lost.
    pub fn trace_from_film(
        &self,
        origin: DVec3,
        direction: DVec3,
    ) -> std::result::Result<(DVec3, DVec3), Lost> {
        let (mut o, mut d) = (origin, direction);
        for (i, s) in self.surfaces.iter().enumerate() {
            let t = intersect(s, o, d).ok_or(Lost::Blocked(i))?;
            let p = o + t * d;
            if p.x * p.x + p.y * p.y > s.aperture_radius * s.aperture_radius {
                return Err(Lost::Blocked(i));
            }
            o = p;
            if s.refracts() {
                let normal = surface_normal(s, p, d);
                d = refract(d, normal, s.index_behind / s.index_in_front)
                    .ok_or(Lost::TotalInternalReflection(i))?;
            }
        }
        Ok((o, d))
    }
}

/// How far from the axis a film at one distance stays lit: the radii (mm on the film) where the
/// relative illumination falls to one half and to 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageCircle {
    /// Where the relative illumination falls to 0.5.
    pub half_radius: f64,
    /// The first radius where no ray passes.
    pub dark_radius: f64,
}

/// The square grid over the disk the illumination integrals sum over: this many cells across.
pub const ILLUMINATION_GRID: usize = 96;

/// How much wider than the rear element's clear aperture the square of directions is: a ray from
/// far off the axis reaches the rear surface's rim through the vertex plane outside the
/// aperture's own radius (pbrt's `BoundExitPupil` widens it by the same factor).
const REAR_DISK_MARGIN: f64 = 1.5;

impl LensSystem {
    /// Half the side of the square on the rear vertex's plane that every ray leaving the film
    /// through the lens crosses (mm): 1.5 times the rear element's clear radius.
    pub fn rear_square(&self) -> f64 {
        REAR_DISK_MARGIN * self.surfaces[0].aperture_radius
    }

    /// The plane (z, lens frame) camera rays are aimed through: the paraxial exit pupil's, where
    /// the pupil seen from neighbouring film points barely moves, so that a film cell's bounds
    /// stay tight; the rear vertex's when the exit pupil lies behind it (a ray would meet the
    /// rear surface before the plane it is aimed through).
    pub fn aim_z(&self) -> f64 {
        (self.paraxial.rear_principal - self.paraxial.exit_pupil).max(self.rear_z())
    }

    /// Half the side of the square on the aim plane that every ray from `film_points` through the
    /// lens crosses: the rear square projected from each film point onto the aim plane, which
    /// magnifies it by k = (z_aim - z_film) / (z_rear - z_film) about the film point, moving its
    /// centre outwards by |film_xy| (k - 1).
    fn aim_square(&self, film_points: &[DVec3]) -> f64 {
        let (rear, aim) = (self.rear_z(), self.aim_z());
        film_points
            .iter()
            .map(|f| {
                let k = (aim - f.z) / (rear - f.z);
                f.truncate().abs().max_element() * (k - 1.0) + self.rear_square() * k
            })
            .fold(self.rear_square(), f64::max)
    }

    /// The irradiance at `film_point` (lens frame, mm) on a film square to the axis, under a
    /// uniform radiance of 1 beyond the lens: the sum over a `grid` x `grid` of points on the
    /// aim plane ([`Self::aim_z`]) of cos(theta)^2 / distance^2 times the cell's area, for the rays that
    /// pass (cos^4 falloff and vignetting by every aperture, the stop included). The grid spans
    /// the point's own `pupil_bounds`, so a small stop is resolved as finely as a wide one.
    pub fn irradiance(&self, film_point: DVec3, grid: usize) -> f64 {
        self.irradiance_on(film_point, DVec3::Z, grid)
    }

    /// [`irradiance`](Self::irradiance) on a film whose unit normal (towards the lens) is
    /// `film_normal`: cos(film) = |normal . direction| in place of the direction's z.
    pub fn irradiance_on(&self, film_point: DVec3, film_normal: DVec3, grid: usize) -> f64 {
        let Some([lo, hi]) = self.pupil_bounds(&[film_point]) else {
            return 0.0;
        };
        let z = self.aim_z();
        let cell = (hi - lo) / grid as f64;
        let mut sum = 0.0;
        for i in 0..grid {
            for j in 0..grid {
                let p = lo + DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * cell;
                let to = p.extend(z) - film_point;
                let distance2 = to.length_squared();
                let direction = to / distance2.sqrt();
                if self.trace_from_film(film_point, direction).is_ok() {
                    sum += film_normal.dot(direction).abs() * direction.z / distance2;
                }
            }
        }
        sum * cell.x * cell.y
    }

    /// Irradiance at `radius` mm from the axis on a film square to it at `film_distance` mm
    /// behind H', relative to the irradiance on the axis.
    pub fn relative_illumination(&self, radius: f64, film_distance: f64, grid: usize) -> f64 {
        let at = |r: f64| self.irradiance(DVec3::new(r, 0.0, -film_distance), grid);
        at(radius) / at(0.0)
    }

    /// The image circle on a film square to the axis at `film_distance` mm behind H', found by
    /// stepping out from the axis by `step` mm (to `limit` mm at most: then `dark_radius` is
    /// `limit`, the circle reaching past it). The dark edge is then found apart from the
    /// illumination grids, which lose the last rays when they pass through a sliver of the
    /// pupil ([`Self::last_lit_radius`]).
    pub fn image_circle(&self, film_distance: f64, step: f64, limit: f64) -> ImageCircle {
        let centre = self.irradiance(DVec3::new(0.0, 0.0, -film_distance), ILLUMINATION_GRID);
        let relative = |r: f64| {
            self.irradiance(DVec3::new(r, 0.0, -film_distance), ILLUMINATION_GRID) / centre
        };
        let (mut previous, mut half_radius) = (1.0, None);
        let mut r = step;
        while r < limit {
            let value = relative(r);
            if half_radius.is_none() && value <= 0.5 {
                // Linear between the two radii around one half.
                half_radius = Some(r - step * (0.5 - value) / (previous - value));
            }
            if value == 0.0 {
                return ImageCircle {
                    half_radius: half_radius.unwrap_or(r),
                    dark_radius: self.last_lit_radius(film_distance, r - step, r, limit),
                };
            }
            previous = value;
            r += step;
        }
        ImageCircle {
            half_radius: half_radius.unwrap_or(limit),
            dark_radius: limit,
        }
    }
}

/// Aims along the meridian a clearance search tries before refining the best.
const CLEARANCE_GRID: usize = 400;

impl LensSystem {
    /// How far inside every clear aperture the ray from `origin` along `direction` passes (mm,
    /// the least over the surfaces of aperture radius less the hit's distance from the axis;
    /// negative where an aperture blocks it), traced on past the apertures so that it varies
    /// continuously with the ray; `None` where a sphere is missed or the ray is totally
    /// reflected.
    pub fn clearance(&self, origin: DVec3, direction: DVec3) -> Option<f64> {
        let (mut o, mut d) = (origin, direction);
        let mut least = f64::INFINITY;
        for s in &self.surfaces {
            o += intersect(s, o, d)? * d;
            least = least.min(s.aperture_radius - o.truncate().length());
            if s.refracts() {
                d = refract(
                    d,
                    surface_normal(s, o, d),
                    s.index_behind / s.index_in_front,
                )?;
            }
        }
        Some(least)
    }

    /// The largest clearance of a ray from `film_point` (on the x axis of the film, lens frame)
    /// aimed through the meridian y = 0 of the aim plane: a grid over the aim square, then a
    /// golden-section search about its best point. The last rays to pass a film point far off
    /// the axis cross the meridian: the lens and the point are symmetric about it.
    fn meridional_clearance(&self, film_point: DVec3) -> f64 {
        let (z, half) = (self.aim_z(), self.aim_square(&[film_point]));
        let clearance = |x: f64| {
            let direction = (DVec3::new(x, 0.0, z) - film_point).normalize();
            self.clearance(film_point, direction)
                .unwrap_or(f64::NEG_INFINITY)
        };
        let step = 2.0 * half / CLEARANCE_GRID as f64;
        let best = (0..=CLEARANCE_GRID)
            .map(|i| -half + i as f64 * step)
            .max_by(|a, b| clearance(*a).total_cmp(&clearance(*b)))
            .unwrap_or(0.0);
        let (mut lo, mut hi) = (best - step, best + step);
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let (a, b) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
            if clearance(a) < clearance(b) {
                lo = a;
            } else {
                hi = b;
            }
        }
        clearance(best).max(clearance(0.5 * (lo + hi)))
    }

    /// The radius on a film square to the axis at `film_distance` mm beyond which no ray passes
    /// the lens: from `lit` (where rays were found) and `dark` (where the grids found none),
    /// outwards in steps of their gap while a ray still passes at `dark` (to `limit`), then by
    /// bisection on whether any meridional ray passes, to 1e-9 of the radius.
    fn last_lit_radius(&self, film_distance: f64, lit: f64, dark: f64, limit: f64) -> f64 {
        let passes = |r: f64| self.meridional_clearance(DVec3::new(r, 0.0, -film_distance)) > 0.0;
        let (mut lo, mut hi) = (lit, dark);
        let step = dark - lit;
        while passes(hi) {
            if hi >= limit {
                return limit;
            }
            (lo, hi) = (hi, hi + step);
        }
        super::bisect_edge(lo, hi, 1e-9 * hi, passes)
    }
}

/// Points across a pupil-bounds search's grid on the rear square, in each direction.
const PUPIL_SEARCH_GRID: usize = 32;

/// The bounds of an empty cell (no ray passes): a rectangle whose low corner lies above its
/// high one, which the kernels read as weight 0.
const EMPTY_BOUNDS: [[f32; 2]; 2] = [[1.0, 1.0], [-1.0, -1.0]];

impl LensSystem {
    /// The rectangle (low and high corners) on the aim plane ([`Self::aim_z`]) that holds every point a
    /// ray from one of `film_points` passes the lens through, or `None` when none passes. A first
    /// search on a 33 x 33 grid over the rear square as the film points see it on that plane (or, when it finds nothing, the points
    /// where the rays towards the paraxial exit pupil's centre cross the plane, for a stop too
    /// small for that grid) gives a rectangle; a second search on a 33 x 33 grid over it, widened
    /// by the first grid's step, refines it; the result is widened by the second grid's step
    /// (clamped to the square).
    pub fn pupil_bounds(&self, film_points: &[DVec3]) -> Option<[DVec2; 2]> {
        let half = self.aim_square(film_points);
        let square = [DVec2::splat(-half), DVec2::splat(half)];
        let coarse_step = 2.0 * half / PUPIL_SEARCH_GRID as f64;
        let (found, step) = match self.passing_within(film_points, square) {
            Some(found) => (found, coarse_step),
            None => {
                let seed = self.chief_crossings(film_points)?;
                let stop_scale = self.paraxial.widest_f_number / self.f_number;
                let pupil = self.paraxial.exit_pupil_diameter * stop_scale;
                (seed, pupil.min(coarse_step))
            }
        };
        let clamp = |[lo, hi]: [DVec2; 2], margin: f64| {
            [(lo - margin).max(square[0]), (hi + margin).min(square[1])]
        };
        let region = clamp(found, step);
        let fine_step = (region[1] - region[0]).max_element() / PUPIL_SEARCH_GRID as f64;
        let refined = self.passing_within(film_points, region).unwrap_or(found);
        Some(clamp(refined, fine_step))
    }

    /// The smallest rectangle holding the points of a 33 x 33 grid over `region` (on the rear
    /// vertex's plane) through which a ray from one of `film_points` passes.
    fn passing_within(&self, film_points: &[DVec3], region: [DVec2; 2]) -> Option<[DVec2; 2]> {
        let z = self.aim_z();
        let [lo, hi] = region;
        let mut bounds: Option<[DVec2; 2]> = None;
        for i in 0..=PUPIL_SEARCH_GRID {
            for j in 0..=PUPIL_SEARCH_GRID {
                let t = DVec2::new(i as f64, j as f64) / PUPIL_SEARCH_GRID as f64;
                let p = lo + t * (hi - lo);
                let passes = film_points.iter().any(|&film| {
                    let direction = (p.extend(z) - film).normalize();
                    self.trace_from_film(film, direction).is_ok()
                });
                if passes {
                    bounds = Some(match bounds {
                        None => [p, p],
                        Some([lo, hi]) => [lo.min(p), hi.max(p)],
                    });
                }
            }
        }
        bounds
    }

    /// Where the rays from `film_points` towards the paraxial exit pupil's centre cross the rear
    /// vertex's plane, for those that pass: the rectangle holding them.
    fn chief_crossings(&self, film_points: &[DVec3]) -> Option<[DVec2; 2]> {
        let z = self.aim_z();
        let pupil = DVec3::new(
            0.0,
            0.0,
            self.paraxial.rear_principal - self.paraxial.exit_pupil,
        );
        let mut bounds: Option<[DVec2; 2]> = None;
        for &film in film_points {
            let direction = (pupil - film).normalize();
            if self.trace_from_film(film, direction).is_err() {
                continue;
            }
            let p = (film + direction * ((z - film.z) / direction.z)).truncate();
            bounds = Some(match bounds {
                None => [p, p],
                Some([lo, hi]) => [lo.min(p), hi.max(p)],
            });
        }
        bounds
    }

    /// The fraction of rays from `film_point` aimed uniformly at the rectangle `bounds` on the
    /// plane at `z` (lens frame) that pass the lens, on a `grid` x `grid` of aims.
    pub fn passing_fraction(
        &self,
        film_point: DVec3,
        bounds: [DVec2; 2],
        z: f64,
        grid: usize,
    ) -> f64 {
        let [lo, hi] = bounds;
        let mut passed = 0usize;
        for i in 0..grid {
            for j in 0..grid {
                let t = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) / grid as f64;
                let aim = (lo + t * (hi - lo)).extend(z);
                if self
                    .trace_from_film(film_point, (aim - film_point).normalize())
                    .is_ok()
                {
                    passed += 1;
                }
            }
        }
        passed as f64 / (grid * grid) as f64
    }

    /// The lens as the kernels read it from the sample table (`GpuCamera::lens_table_offset`),
    /// in f32 pairs: the exposure (1 / the irradiance on the axis at `film_distance`, so a
    /// uniform radiance of 1 exposes the axis to 1) with the aim plane's z ([`Self::aim_z`]),
    /// the surfaces rearmost first as (z, radius)
    /// (radius 0: a plane) and (clear radius, index behind / index in front: a plane refracts
    /// where it is not 1), then for each of the film's
    /// `LENS_PUPIL_CELLS`^2 cells (rows from the bottom, image coordinates) the low and high
    /// corners of its `pupil_bounds`. `cell_points(i, j)` gives the film points (lens frame) whose
    /// rays bound cell (column i, row j).
    ///
    /// `spectral` (the spectral mode): each cell's bounds hold the passing rays at the range's
    /// two ends and at the reference line (dispersion moves the pupil a little with
    /// wavelength), and the table ends with each surface's object-side glass, rearmost first,
    /// as its three Sellmeier terms (B, C): the medium a ray from the film enters there.
    pub fn kernel_table(
        &self,
        film_distance: f64,
        cell_points: impl Fn(u32, u32) -> Vec<DVec3> + Sync,
        spectral: bool,
    ) -> Vec<[f32; 2]> {
        use rayon::prelude::*;
        let axis = self.irradiance(DVec3::new(0.0, 0.0, -film_distance), ILLUMINATION_GRID);
        let mut table = vec![[(1.0 / axis) as f32, self.aim_z() as f32]];
        for s in &self.surfaces {
            table.push([s.z as f32, s.radius as f32]);
            table.push([
                s.aperture_radius as f32,
                (s.index_behind / s.index_in_front) as f32,
            ]);
        }
        let colours = match spectral {
            true => vec![
                self.at_wavelength(SPECTRAL_MIN_NM as f64),
                self.clone(),
                self.at_wavelength(SPECTRAL_MAX_NM as f64),
            ],
            false => vec![self.clone()],
        };
        let cells = LENS_PUPIL_CELLS;
        let bounds: Vec<[[f32; 2]; 2]> = (0..cells * cells)
            .into_par_iter()
            .map(|c| {
                let points = cell_points(c % cells, c / cells);
                let found = colours.iter().filter_map(|lens| lens.pupil_bounds(&points));
                match found.reduce(|[lo, hi], [l, h]| [lo.min(l), hi.max(h)]) {
                    Some([lo, hi]) => [lo.as_vec2().to_array(), hi.as_vec2().to_array()],
                    None => EMPTY_BOUNDS,
                }
            })
            .collect();
        table.extend(bounds.into_iter().flatten());
        if spectral {
            for s in &self.surfaces {
                table.extend(s.glass_in_front.kernel_terms());
            }
        }
        table
    }
}

/// A camera ray through a real lens: the ray leaving the front surface (lens frame, mm) and its
/// weight; a ray lost in the lens has weight 0 and the chief ray's direction through H' (so the
/// first-hit layers see what the lens images).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensRay {
    /// Origin in the lens frame (mm).
    pub origin: Vec3,
    /// Unit direction in the lens frame.
    pub direction: Vec3,
    /// The sample's weight: the bounds' area times cos(film) cos(rear) / distance^2, times the
    /// exposure; 0 when the ray is lost.
    pub weight: f32,
}

/// The ray from film point `film_point` (lens frame, mm) through the point `u` of its cell's
/// exit-pupil bounds, traced through the lens in f32. `film_normal` is the film's unit normal
/// (towards the lens); `cell` the film cell (column, row); `wavelength_nm` the sample's
/// wavelength in the spectral mode (the indices then from the table's glasses), 0 for the
/// reference line's indices. Twin: `generate_lens_ray` in wgsl/camera.wgsl.
#[allow(clippy::too_many_arguments)]
pub fn lens_ray(
    table: &[[f32; 2]],
    offset: u32,
    count: u32,
    film_point: Vec3,
    film_normal: Vec3,
    cell: [u32; 2],
    u: [f32; 2],
    wavelength_nm: f32,
) -> LensRay {
    let chief = LensRay {
        origin: Vec3::ZERO,
        direction: -film_point.normalize(),
        weight: 0.0,
    };
    let at = |k: u32| Vec2::from(table[(offset + k) as usize]);
    let bounds = 1 + 2 * count + 2 * (cell[1] * LENS_PUPIL_CELLS + cell[0]);
    let (lo, hi) = (at(bounds), at(bounds + 1));
    if hi.x < lo.x {
        return chief;
    }
    let aim = (lo + Vec2::from(u) * (hi - lo)).extend(at(0).y);
    let to = aim - film_point;
    let distance2 = to.length_squared();
    let mut d = to / distance2.sqrt();
    let mut o = film_point;
    let glasses = 1 + 2 * count + 2 * LENS_PUPIL_CELLS * LENS_PUPIL_CELLS;
    let mut index_behind = 1.0;
    for i in 0..count {
        let shape = at(1 + 2 * i);
        let glass = at(2 + 2 * i);
        let Some(t) = surface_distance(shape.x, shape.y, o, d) else {
            return chief;
        };
        o += t * d;
        if o.x * o.x + o.y * o.y > glass.x * glass.x {
            return chief;
        }
        let mut eta = glass.y;
        if wavelength_nm > 0.0 {
            let terms = glasses + 3 * i;
            let index_in_front =
                sellmeier_index([at(terms), at(terms + 1), at(terms + 2)], wavelength_nm);
            eta = index_behind / index_in_front;
            index_behind = index_in_front;
        }
        // As `PlacedSurface::refracts`: a plane refracts where the index changes.
        if shape.y != 0.0 || eta != 1.0 {
            let mut n = Vec3::Z;
            if shape.y != 0.0 {
                n = (o - Vec3::new(0.0, 0.0, shape.x - shape.y)).normalize();
            }
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let Some(refracted) = refract_f32(d, n, eta) else {
                return chief;
            };
            d = refracted;
        }
    }
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    let cosines = film_normal.dot(to).abs() * to.z / (distance2 * distance2);
    LensRay {
        origin: o,
        direction: d,
        weight: at(0).x * area * cosines,
    }
}

/// `Glass::index` in f32 from the table's terms (B, C) at `nm` nanometres. Twin:
/// `lens_sellmeier_index` in wgsl/camera.wgsl.
fn sellmeier_index(terms: [Vec2; 3], nm: f32) -> f32 {
    let l2 = (nm * 1e-3) * (nm * 1e-3);
    let sum: f32 = terms.iter().map(|t| t.x * l2 / (l2 - t.y)).sum();
    (1.0 + sum).sqrt()
}

/// [`intersect`] in f32 for a surface at `z` of radius `radius` (0: a plane).
fn surface_distance(z: f32, radius: f32, o: Vec3, d: Vec3) -> Option<f32> {
    if radius == 0.0 {
        let t = (z - o.z) / d.z;
        return (t.is_finite() && t >= 0.0).then_some(t);
    }
    let centre = Vec3::new(0.0, 0.0, z - radius);
    let oc = o - centre;
    let b = oc.dot(d);
    let c = oc.length_squared() - radius * radius;
    let discriminant = b * b - c;
    if discriminant < 0.0 {
        return None;
    }
    let root = discriminant.sqrt();
    let t = if radius > 0.0 { -b + root } else { -b - root };
    let p = o + t * d;
    (t > 0.0 && (p.z - centre.z) * radius > 0.0).then_some(t)
}

/// [`refract`] in f32.
fn refract_f32(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Distance along the ray to the surface (its cap about the vertex), if it is ahead.
fn intersect(s: &PlacedSurface, o: DVec3, d: DVec3) -> Option<f64> {
    if s.radius == 0.0 {
        // A plane: the stop or a plane glass surface. One in the plane of the vertex before it
        // (no thickness between) is met at t = 0.
        let t = (s.z - o.z) / d.z;
        return (t.is_finite() && t >= 0.0).then_some(t);
    }
    let centre = DVec3::new(0.0, 0.0, s.z - s.radius);
    let oc = o - centre;
    let b = oc.dot(d);
    let c = oc.length_squared() - s.radius * s.radius;
    let discriminant = b * b - c;
    if discriminant < 0.0 {
        return None;
    }
    let root = discriminant.sqrt();
    // Travelling towards +z, a ray meets a surface whose centre lies behind its vertex (radius
    // > 0) where it leaves that sphere, and one whose centre lies ahead where it enters it.
    let t = if s.radius > 0.0 { -b + root } else { -b - root };
    let p = o + t * d;
    // The cap about the vertex: on the vertex's side of the centre.
    let on_cap = (p.z - centre.z) * s.radius > 0.0;
    (t > 0.0 && on_cap).then_some(t)
}

/// The unit normal at `p`, facing against the ray (a plane's is the axis).
fn surface_normal(s: &PlacedSurface, p: DVec3, d: DVec3) -> DVec3 {
    let n = if s.radius == 0.0 {
        DVec3::Z
    } else {
        (p - DVec3::new(0.0, 0.0, s.z - s.radius)).normalize()
    };
    if n.dot(d) > 0.0 { -n } else { n }
}

/// Snell's law: `d` through a surface of normal `n` (facing against `d`) with index ratio
/// `eta` = incident / transmitted; `None` on total internal reflection.
pub fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Prescription> {
        Prescription::parse(Path::new("test.dat"), text)
    }

    /// A biconvex lens of index 1.5 with no thickness whose lensmaker's focal length is `f`,
    /// its stop of diameter 10 mm in front: paraxial only (its edges would cross).
    fn thin(f: f64) -> Prescription {
        parse(&format!("0 0 1 10\n{f} 0 1.5 20\n{} 0 1 20\n", -f)).unwrap()
    }

    /// [`thin`] with the centre thickness its 20 mm aperture needs: a lens rays can cross.
    fn biconvex(f: f64) -> Prescription {
        let sag = f - (f * f - 100.0).sqrt();
        parse(&format!(
            "0 0 1 10\n{f} {} 1.5 20\n{} 0 1 20\n",
            2.0 * sag + 0.1,
            -f
        ))
        .unwrap()
    }

    #[test]
    fn a_thin_biconvex_lens_has_the_lensmakers_focal_length_and_no_principal_gap() {
        let p = thin(100.0).paraxial();
        assert!((p.focal_length - 100.0).abs() < 1e-9, "{p:?}");
        assert!((p.back_focal_distance - 100.0).abs() < 1e-9);
        assert!(p.front_principal.abs() < 1e-9 && p.rear_principal.abs() < 1e-9);
        assert!((p.widest_f_number - 10.0).abs() < 1e-9);
        assert!(p.entrance_pupil.abs() < 1e-12 && (p.entrance_pupil_diameter - 10.0).abs() < 1e-9);
    }

    #[test]
    fn errors_name_the_line_and_the_column() {
        let cases = [
            ("10 1 1.5 5\n0 1 0 4\n-10 0 1\n", 3, ""),
            ("10 1 1.5 5\n0 1 0 4\n-10 x 1 5\n", 3, "thickness"),
            ("10 1 1.5 5\n0 1 1.5 4\n-10 0 1 5\n", 2, "index"),
            ("10 1 1.5 25\n0 1 0 4\n-10 0 1 5\n", 1, "aperture"),
            ("10 -1 1.5 5\n0 1 0 4\n-10 0 1 5\n", 1, "thickness"),
            (
                "# c\n10 1 1.5 5\n0 1 0 4\n0 1 0 4\n-10 0 1 5\n",
                4,
                "radius",
            ),
            ("10 1 1.5 5\n0 1 0 4\nNaN 0 1 5\n", 3, "radius"),
            ("10 1 1.5 5\n0 1 0 4\n-10 0 nan 5\n", 3, "index"),
            ("inf inf 1.5 5\n0 1 0 4\n-10 0 1 5\n", 1, "thickness"),
            ("10 1 1.5 -inf\n0 1 0 4\n-10 0 1 5\n", 1, "aperture"),
            // Past f64's range: a typing slip, not a plane.
            ("1e400 1 1.5 5\n0 1 0 4\n-10 0 1 5\n", 1, "radius"),
            ("10 1 1.5 5\n0 1 0 4\ninfinite 0 1 5\n", 3, "radius"),
        ];
        for (text, line, field) in cases {
            match parse(text) {
                Err(Error::Scene { location, .. }) => {
                    assert_eq!(
                        (location.line, location.field.as_str()),
                        (line, field),
                        "{text}"
                    )
                }
                other => panic!("{text}: {other:?}"),
            }
        }
        assert!(parse("10 1 1.5 5\n-10 0 1 5\n").is_err(), "no stop");
        let message = parse("10 1 1.5 5\n0 1 0 4\nnan 0 1 5\n")
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("0 for the aperture stop, or inf"),
            "{message}"
        );
    }

    /// A glass's dispersion: an Abbe number (at the d line, or the e line after `line e`) or
    /// Sellmeier terms; refusals name the line and the column.
    #[test]
    fn dispersion_columns_give_each_glass_its_index_against_wavelength() {
        let abbe = parse("line e\n0 0 0 10 0\n50 4 1.6 20 40\n-50 0 1 20\n").unwrap();
        assert_eq!(abbe.line, ReferenceLine::E);
        let glass = abbe.surfaces[1].glass;
        let (short, long) = ReferenceLine::E.abbe_span();
        let nu =
            (glass.index(ReferenceLine::E.nm()) - 1.0) / (glass.index(short) - glass.index(long));
        assert!((nu - 40.0).abs() < 1e-9 && abbe.is_dispersive(), "{nu}");
        assert!(abbe.at_wavelength(450.0).paraxial().focal_length < abbe.paraxial().focal_length);
        let lens = LensSystem::new(&abbe, None).unwrap();
        assert!(lens.is_dispersive());
        let blue = lens.at_wavelength(450.0);
        assert!(blue.surfaces[1].index_behind > lens.surfaces[1].index_behind);
        assert_eq!(
            blue.surfaces[1].index_in_front,
            blue.surfaces[0].index_behind
        );
        let plain = parse("0 0 0 10\n50 4 1.6 20\n-50 0 1 20\n").unwrap();
        assert!(!plain.is_dispersive() && plain.line == ReferenceLine::D);
        let sellmeier = "0 0 0 10\n50 4 1.5168 20 1.03961212 0.00600069867 0.231792344 \
                         0.0200179144 1.01046945 103.560653\n-50 0 1 20\n";
        assert!(parse(sellmeier).unwrap().is_dispersive());
        let cases = [
            // A glass without dispersion beside one with it.
            (
                "0 0 0 10\n50 4 1.6 20 40\n-50 2 1.5 20\n30 0 1 20\n",
                3,
                "abbe",
            ),
            // An Abbe number on air.
            ("0 0 0 10\n50 4 1.6 20 40\n-50 0 1 20 30\n", 3, "abbe"),
            ("0 0 0 10\n50 4 1.6 20 -3\n-50 0 1 20\n", 2, "abbe"),
            // Terms that miss the index column at the d line.
            (&sellmeier.replace("1.5168", "1.52"), 2, "B1"),
            ("0 0 0 10\n50 4 1.6 20 40 1\n-50 0 1 20\n", 2, ""),
            ("0 0 0 10\nline e\n50 4 1.6 20 40\n-50 0 1 20\n", 2, "line"),
            ("line f\n0 0 0 10\n50 4 1.6 20 40\n-50 0 1 20\n", 1, "line"),
        ];
        for (text, line, field) in cases {
            match parse(text) {
                Err(Error::Scene { location, .. }) => assert_eq!(
                    (location.line, location.field.as_str()),
                    (line, field),
                    "{text}"
                ),
                other => panic!("{text}: {other:?}"),
            }
        }
    }

    /// `inf`, `-inf` and `infinity` in any case, signed or not, are a plane's radius: its power
    /// is 0, and placed it has radius 0 like the stop, which the lens still knows by its index.
    #[test]
    fn an_infinite_radius_is_a_plane_surface() {
        for word in ["inf", "-inf", "+inf", "Infinity", "-INFINITY"] {
            let p = parse(&format!("0 0 1 10\n50 4 1.5 20\n{word} 0 1 20\n")).unwrap();
            assert!(
                p.surfaces[2].is_plane() && !p.surfaces[2].is_stop(),
                "{word}"
            );
            let f = p.paraxial().focal_length;
            assert!((f - 100.0).abs() < 1e-9, "{word}: f = {f}");
            let lens = LensSystem::new(&p, None).unwrap();
            assert_eq!(lens.surfaces[0].radius, 0.0, "{word}");
            assert!(lens.surfaces[0].refracts() && !lens.surfaces[lens.stop].refracts());
            // The stop is the first vertex: at t = 0, z = t_H'.
            assert_eq!(lens.stop, 2);
            assert_eq!(lens.stop_z(), lens.paraxial.rear_principal);
        }
    }

    #[test]
    fn an_f_number_wider_than_the_lens_opens_is_refused() {
        let lens = thin(100.0);
        assert!(LensSystem::new(&lens, Some(5.0)).is_err());
        let stopped = LensSystem::new(&lens, Some(20.0)).unwrap();
        let stop = stopped.surfaces[stopped.stop];
        assert!((stop.aperture_radius - 2.5).abs() < 1e-12);
    }

    #[test]
    fn a_ray_outside_the_stop_or_past_the_critical_angle_is_lost() {
        let lens = LensSystem::new(&biconvex(100.0), None).unwrap();
        let from = DVec3::new(0.0, 0.0, -100.0);
        assert!(lens.trace_from_film(from, DVec3::Z).is_ok());
        let steep = DVec3::new(0.0, 6.0, 100.0).normalize();
        assert_eq!(lens.trace_from_film(from, steep), Err(Lost::Blocked(2)));
        // Inside glass, a ray at 60 degrees to the normal cannot leave into air.
        let glass = PlacedSurface {
            z: 0.0,
            radius: -1e6,
            aperture_radius: 100.0,
            index_behind: 1.5,
            index_in_front: 1.0,
            glass_behind: Glass::constant(1.5),
            glass_in_front: Glass::AIR,
        };
        let d = DVec3::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let n = surface_normal(&glass, DVec3::ZERO, d);
        assert!(refract(d, n, 1.5).is_none());
        assert!(refract(d, n, 1.0 / 1.5).is_some());
    }
}
