//! Focus through a real lens by tracing. A film point's rays, traced through the lens, meet in
//! object space near the point the film point images; their least-squares meeting point is its
//! *traced focus*. `focus_points` is first solved paraxially with the thick lens
//! (`optics::solve_focus_points`: the hinge rule from the front principal point); spherical
//! aberration and the stop's place then move the best focus of a wide-open lens off the paraxial
//! one, so the solution is refined until each point's traced focus lies on it, and what remains
//! is reported. CPU only, f64. Model and equations: `docs/lens.md`, "Focus".

use glam::{DMat2, DMat3, DVec2, DVec3};

use super::CameraSpec;
use super::lens::LensSystem;
use super::optics::FocusSolution;

/// Aims per side of the grid over a film point's exit-pupil bounds whose rays make its bundle.
const BUNDLE_GRID: usize = 12;

/// Newton passes for a point's image on the film, and for the refinement of the movements.
const NEWTON_PASSES: usize = 30;

/// Where a focus point's traced focus lies against the point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedFocus {
    /// The film point (image mm, x right, y up) whose traced focus lies on the point's line of
    /// sight.
    pub image_mm: DVec2,
    /// How far the traced focus lies beyond the point along the line of sight from the front
    /// principal point (scene units; negative: nearer the camera).
    pub defocus: f64,
    /// The point's distance from the front principal point (scene units).
    pub distance: f64,
    /// Rays of the bundle that passed the lens.
    pub rays: usize,
}

/// A point's bundle: the aims (on the rear vertex's plane) of the rays that pass from its first
/// film point, reused as the film point moves so that the traced focus moves smoothly.
struct Bundle {
    aims: Vec<DVec3>,
}

impl Bundle {
    fn new(lens: &LensSystem, film: DVec3) -> Option<Bundle> {
        let [lo, hi] = lens.pupil_bounds(&[film])?;
        let z = lens.rear_z();
        let aims: Vec<DVec3> = (0..BUNDLE_GRID * BUNDLE_GRID)
            .map(|k| {
                let t = DVec2::new(
                    (k % BUNDLE_GRID) as f64 + 0.5,
                    (k / BUNDLE_GRID) as f64 + 0.5,
                ) / BUNDLE_GRID as f64;
                (lo + t * (hi - lo)).extend(z)
            })
            .filter(|aim| {
                lens.trace_from_film(film, (*aim - film).normalize())
                    .is_ok()
            })
            .collect();
        (aims.len() >= 3).then_some(Bundle { aims })
    }

    /// The least-squares meeting point of the rays from `film` (lens frame) through the aims
    /// that pass: the Q minimising the summed squared distance to the rays, from
    /// sum(I - d d^T) Q = sum(I - d d^T) o. `None` when fewer than three pass or they are
    /// parallel.
    fn focus(&self, lens: &LensSystem, film: DVec3) -> Option<(DVec3, usize)> {
        let mut normal = DMat3::ZERO;
        let mut rhs = DVec3::ZERO;
        let mut rays = 0;
        for aim in &self.aims {
            let Ok((o, d)) = lens.trace_from_film(film, (*aim - film).normalize()) else {
                continue;
            };
            let projector = DMat3::IDENTITY - DMat3::from_cols(d * d.x, d * d.y, d * d.z);
            normal += projector;
            rhs += projector * o;
            rays += 1;
        }
        let det = normal.determinant();
        (rays >= 3 && det.abs() > 1e-12 * (rays as f64).powi(3))
            .then(|| (normal.inverse() * rhs, rays))
    }
}

/// Each focus point's traced focus with the camera as set: the film point whose bundle focuses
/// on the point's line of sight (found by Newton's method from the paraxial image), and how far
/// along it the focus falls from the point.
pub fn traced_focus(camera: &CameraSpec, points: &[DVec3; 3]) -> Result<[TracedFocus; 3], String> {
    traced_focus_with(camera, points, None)
}

/// [`traced_focus`], with each point's bundle of aims given (`Some`), or found from its
/// paraxial image (`None`).
fn traced_focus_with(
    camera: &CameraSpec,
    points: &[DVec3; 3],
    bundles: Option<&[Bundle]>,
) -> Result<[TracedFocus; 3], String> {
    let lens = camera.lens.as_ref().ok_or("the camera has no real lens")?;
    let s = camera.standards();
    let gap = camera.principal_gap();
    let front_principal = DVec3::new(0.0, 0.0, gap);
    let film_u = s.lens.transpose() * s.film_u;
    let film_v = s.lens.transpose() * s.film_v;
    let film_centre = s.to_lens_frame(s.film_center);
    let film_normal = s.lens.transpose() * s.film.z_axis;
    let film = |u: DVec2| film_centre + u.x * film_u + u.y * film_v;
    let mut out = [TracedFocus {
        image_mm: DVec2::ZERO,
        defocus: 0.0,
        distance: 0.0,
        rays: 0,
    }; 3];
    for (i, point) in points.iter().enumerate() {
        let q = s.to_lens_frame(camera.world_to_camera(*point));
        let sight = (q - front_principal).normalize();
        // The paraxial image lies on the line from H' parallel to the line of sight (the nodal
        // points of a lens in air are its principal points).
        let t = film_normal.dot(film_centre) / film_normal.dot(-sight);
        let paraxial = -sight * t - film_centre;
        let mut u = DVec2::new(paraxial.dot(film_u), paraxial.dot(film_v));
        let found;
        let bundle = match bundles {
            Some(bundles) => &bundles[i],
            None => {
                found = Bundle::new(lens, film(u)).ok_or_else(|| {
                    format!("no ray from the image of focus point {i} passes the lens")
                })?;
                &found
            }
        };
        // Two directions across the line of sight: the lateral error Newton drives to zero.
        let across_x = sight.any_orthonormal_vector();
        let across_y = sight.cross(across_x);
        let lateral = |u: DVec2| -> Option<(DVec2, DVec3, usize)> {
            let (focus, rays) = bundle.focus(lens, film(u))?;
            let r = focus - q;
            Some((DVec2::new(r.dot(across_x), r.dot(across_y)), r, rays))
        };
        let lost = || format!("the bundle of focus point {i} is lost while its image is sought");
        let scale = q.length();
        let mut settled = None;
        for _ in 0..NEWTON_PASSES {
            let (e, r, rays) = lateral(u).ok_or_else(lost)?;
            if e.length() <= 1e-10 * scale {
                settled = Some((r, rays));
                break;
            }
            let h = 1e-4;
            let (ex, ..) = lateral(u + DVec2::X * h).ok_or_else(lost)?;
            let (ey, ..) = lateral(u + DVec2::Y * h).ok_or_else(lost)?;
            let jacobian = DMat2::from_cols((ex - e) / h, (ey - e) / h);
            if jacobian.determinant().abs() < 1e-30 {
                return Err(lost());
            }
            u -= jacobian.inverse() * e;
        }
        let (r, rays) = settled.ok_or_else(|| {
            format!("the image of focus point {i} does not settle in {NEWTON_PASSES} passes")
        })?;
        out[i] = TracedFocus {
            image_mm: u,
            defocus: r.dot(sight) * camera.units_per_mm,
            distance: (q - front_principal).length() * camera.units_per_mm,
            rays,
        };
    }
    Ok(out)
}

/// The bundles [`traced_focus`] would build for `points` with the camera as set.
fn bundles(camera: &CameraSpec, points: &[DVec3; 3]) -> Result<Vec<Bundle>, String> {
    let lens = camera.lens.as_ref().ok_or("the camera has no real lens")?;
    let s = camera.standards();
    let traced = traced_focus(camera, points)?;
    traced
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let film = s.to_lens_frame(s.film_point(t.image_mm));
            Bundle::new(lens, film)
                .ok_or_else(|| format!("no ray from the image of focus point {i} passes the lens"))
        })
        .collect()
}

/// A refined focus and its largest remaining defocus, as a fraction of the point's distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefinedFocus {
    /// The lens tilt, swing and film distance.
    pub solution: FocusSolution,
    /// max |defocus| / distance over the three points after refinement.
    pub residual: f64,
}

/// The paraxial `solution` refined until each point's traced focus lies on it: Newton's method
/// on the lens tilt, swing and film distance, each point's bundle of aims fixed (so that the
/// defocus moves smoothly with them), stopped when the largest defocus falls below 1e-10 of its
/// distance or stops shrinking; the best pass is kept.
pub fn refine_focus_points(
    camera: &CameraSpec,
    points: &[DVec3; 3],
    solution: FocusSolution,
) -> Result<RefinedFocus, String> {
    let apply = |x: [f64; 3]| {
        let mut c = camera.clone();
        c.movements.lens_tilt = x[0];
        c.movements.lens_swing = x[1];
        c.film_distance_mm = x[2];
        c
    };
    let mut x = [
        solution.lens_tilt,
        solution.lens_swing,
        solution.film_distance_mm,
    ];
    let bundles = bundles(&apply(x), points)?;
    let residual = |x: [f64; 3]| -> Result<DVec3, String> {
        let traced = traced_focus_with(&apply(x), points, Some(&bundles))?;
        Ok(DVec3::from_array(traced.map(|t| t.defocus / t.distance)))
    };
    let as_solution = |x: [f64; 3]| FocusSolution {
        lens_tilt: x[0],
        lens_swing: x[1],
        film_distance_mm: x[2],
    };
    let steps = [1e-6, 1e-6, 1e-7 * solution.film_distance_mm];
    let mut best = RefinedFocus {
        solution,
        residual: f64::INFINITY,
    };
    for _ in 0..NEWTON_PASSES {
        let r = residual(x)?;
        let size = r.abs().max_element();
        if size >= 0.5 * best.residual {
            if size < best.residual {
                best = RefinedFocus {
                    solution: as_solution(x),
                    residual: size,
                };
            }
            break;
        }
        best = RefinedFocus {
            solution: as_solution(x),
            residual: size,
        };
        if size <= 1e-10 {
            break;
        }
        let mut columns = [DVec3::ZERO; 3];
        for (k, column) in columns.iter_mut().enumerate() {
            let mut moved = x;
            moved[k] += steps[k];
            *column = (residual(moved)? - r) / steps[k];
        }
        let jacobian = DMat3::from_cols(columns[0], columns[1], columns[2]);
        if jacobian.determinant().abs() < 1e-30 {
            return Err("the traced focus does not respond to the lens movements".into());
        }
        let step = jacobian.inverse() * r;
        x = [x[0] - step.x, x[1] - step.y, x[2] - step.z];
    }
    Ok(best)
}
