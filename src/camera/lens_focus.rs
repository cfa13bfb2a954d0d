//! Focus through a real lens by tracing. `focus_points` is first solved paraxially with the
//! thick lens (`optics::solve_focus_points`: the hinge rule from the front principal point), which
//! is exact for rays near the axis; a wide-open lens's spherical aberration, field curvature and
//! astigmatism then blur the points. Each point's blur is traced: the film point whose rays,
//! traced out through the lens, pass closest to it (a fixed grid of aims over the exit pupil),
//! and their RMS distance from it scaled to the film by the magnification (by reciprocity, the
//! size of the point's image there). The lens tilt, swing and film distance are then refined to
//! the least summed squared blur over the triangle the points span (its corners, the midpoints
//! of its sides and its centroid), and what remains is reported: the lens's own aberration.
//! CPU only, f64. Model and equations: `docs/lens.md`, "Focus".

use glam::{DMat3, DVec2, DVec3};

use super::CameraSpec;
use super::lens::LensSystem;
use super::optics::FocusSolution;

/// Aims per side of the square grid whose points inside the exit pupil make a bundle.
const BUNDLE_GRID: usize = 16;

/// How much wider than the paraxial exit pupil the aims spread, so that an oblique film point's
/// real pupil (moved and stretched by pupil aberration) is covered; rays the stop or the barrel
/// block are dropped.
const BUNDLE_MARGIN: f64 = 1.25;

/// Newton passes for a point's image on the film.
const NEWTON_PASSES: usize = 30;

/// Evaluations the refinement's simplex search may spend.
const REFINE_EVALUATIONS: usize = 400;

/// A focus point's traced image with the camera as set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedFocus {
    /// The film point (image mm, x right, y up) whose bundle passes the point most closely
    /// (its least-squares meeting point lies on the point's line of sight).
    pub image_mm: DVec2,
    /// RMS distance of the bundle's rays from the point, scaled to the film by the
    /// magnification: the RMS radius of the point's image (micrometres on the film).
    pub blur_um: f64,
    /// Rays of the bundle that passed the lens.
    pub rays: usize,
}

/// The aims of a film point's bundle: a fixed grid over the lens's paraxial exit pupil (lens
/// frame), the same for every film point, so that the traced focus is one smooth function of
/// the film point and the movements (but where a ray's vignetting changes).
struct Bundle {
    aims: Vec<DVec3>,
}

impl Bundle {
    fn new(lens: &LensSystem) -> Bundle {
        let p = &lens.paraxial;
        let z = p.rear_principal - p.exit_pupil;
        let radius =
            0.5 * BUNDLE_MARGIN * p.exit_pupil_diameter * p.widest_f_number / lens.f_number;
        let aims = (0..BUNDLE_GRID * BUNDLE_GRID)
            .map(|k| {
                let t = DVec2::new(
                    (k % BUNDLE_GRID) as f64 + 0.5,
                    (k / BUNDLE_GRID) as f64 + 0.5,
                ) / BUNDLE_GRID as f64;
                (2.0 * t - 1.0) * radius
            })
            .filter(|a| a.length() <= radius)
            .map(|a| a.extend(z))
            .collect();
        Bundle { aims }
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

    /// RMS distance (mm) of the rays from `film` from the object point `q` (lens frame).
    fn rms_miss(&self, lens: &LensSystem, film: DVec3, q: DVec3) -> f64 {
        let (mut sum, mut rays) = (0.0, 0);
        for aim in &self.aims {
            if let Ok((o, d)) = lens.trace_from_film(film, (*aim - film).normalize()) {
                sum += (q - o).reject_from_normalized(d).length_squared();
                rays += 1;
            }
        }
        (sum / rays.max(1) as f64).sqrt()
    }
}

/// Each focus point's traced image with the camera as set: the film point whose bundle's
/// least-squares meeting point lies on the point's line of sight (Newton's method from the
/// paraxial image), and the blur there.
pub fn traced_focus(camera: &CameraSpec, points: &[DVec3]) -> Result<Vec<TracedFocus>, String> {
    let lens = camera.lens.as_ref().ok_or("the camera has no real lens")?;
    let bundle = Bundle::new(lens);
    let s = camera.standards();
    let front_principal = DVec3::new(0.0, 0.0, camera.principal_gap());
    let film_u = s.lens.transpose() * s.film_u;
    let film_v = s.lens.transpose() * s.film_v;
    let film_centre = s.to_lens_frame(s.film_center);
    let film_normal = s.lens.transpose() * s.film.z_axis;
    let film = |u: DVec2| film_centre + u.x * film_u + u.y * film_v;
    let mut out = Vec::with_capacity(points.len());
    for (i, point) in points.iter().enumerate() {
        let q = s.to_lens_frame(camera.world_to_camera(*point));
        let sight = (q - front_principal).normalize();
        // The paraxial image lies on the line from H' parallel to the line of sight (the nodal
        // points of a lens in air are its principal points).
        let t = film_normal.dot(film_centre) / film_normal.dot(-sight);
        let paraxial = -sight * t - film_centre;
        let mut u = DVec2::new(paraxial.dot(film_u), paraxial.dot(film_v));
        // Two directions across the line of sight: the lateral error Newton drives to zero.
        let across_x = sight.any_orthonormal_vector();
        let across_y = sight.cross(across_x);
        let lateral = |u: DVec2| -> Option<(DVec2, usize)> {
            let (focus, rays) = bundle.focus(lens, film(u))?;
            let r = focus - q;
            Some((DVec2::new(r.dot(across_x), r.dot(across_y)), rays))
        };
        let lost = || format!("the rays of focus point {i} are lost while its image is sought");
        let scale = q.length();
        let mut rays = None;
        for _ in 0..NEWTON_PASSES {
            let (e, n) = lateral(u).ok_or_else(lost)?;
            if e.length() <= 1e-10 * scale {
                rays = Some(n);
                break;
            }
            let h = 1e-4;
            let (ex, _) = lateral(u + DVec2::X * h).ok_or_else(lost)?;
            let (ey, _) = lateral(u + DVec2::Y * h).ok_or_else(lost)?;
            let jacobian = glam::DMat2::from_cols((ex - e) / h, (ey - e) / h);
            if jacobian.determinant().abs() < 1e-30 {
                return Err(lost());
            }
            u -= jacobian.inverse() * e;
        }
        let rays = rays.ok_or_else(|| {
            format!("the image of focus point {i} does not settle in {NEWTON_PASSES} passes")
        })?;
        let magnification = film(u).length() / (q - front_principal).length();
        out.push(TracedFocus {
            image_mm: u,
            blur_um: 1e3 * magnification * bundle.rms_miss(lens, film(u), q),
            rays,
        });
    }
    Ok(out)
}

/// The three points, the midpoints of their triangle's sides, and its centroid: where the
/// refinement weighs the blur, so that the plane the points span is sharp, not the points alone.
pub fn triangle_samples(points: &[DVec3; 3]) -> [DVec3; 7] {
    let [a, b, c] = *points;
    [
        a,
        b,
        c,
        0.5 * (a + b),
        0.5 * (b + c),
        0.5 * (c + a),
        (a + b + c) / 3.0,
    ]
}

/// The summed squared blur (um^2) of traced points.
fn total_blur(traced: &[TracedFocus]) -> f64 {
    traced.iter().map(|t| t.blur_um * t.blur_um).sum()
}

/// The paraxial `solution` refined to the least summed squared blur over the points' triangle
/// ([`triangle_samples`]): a
/// Nelder-Mead simplex search over the lens tilt, swing and film distance (the blur is smooth
/// but for rays that the barrel starts or stops blocking, which derivatives would trip on),
/// started at the paraxial solution with steps of 0.05 degrees and 0.2% of the film distance;
/// the paraxial solution is kept when the search does not improve on it.
pub fn refine_focus_points(
    camera: &CameraSpec,
    points: &[DVec3; 3],
    solution: FocusSolution,
) -> Result<FocusSolution, String> {
    let apply = |x: [f64; 3]| {
        let mut c = camera.clone();
        c.movements.lens_tilt = x[0];
        c.movements.lens_swing = x[1];
        c.film_distance_mm = x[2];
        c
    };
    let start = [
        solution.lens_tilt,
        solution.lens_swing,
        solution.film_distance_mm,
    ];
    let samples = triangle_samples(points);
    let paraxial = traced_focus(&apply(start), &samples)?;
    // A trial the tracing cannot image (a point's rays all blocked) counts as infinitely blurred.
    let cost =
        |x: [f64; 3]| traced_focus(&apply(x), &samples).map_or(f64::INFINITY, |t| total_blur(&t));
    let steps = [0.05, 0.05, 2e-3 * solution.film_distance_mm];
    let best = nelder_mead(cost, start, steps, REFINE_EVALUATIONS);
    // A NaN or an equal blur is no improvement either.
    if best.1.partial_cmp(&total_blur(&paraxial)) != Some(std::cmp::Ordering::Less) {
        return Ok(solution);
    }
    let x = best.0;
    Ok(FocusSolution {
        lens_tilt: x[0],
        lens_swing: x[1],
        film_distance_mm: x[2],
    })
}

/// The minimum of `f` near `start` found by the Nelder-Mead simplex method (reflection 1,
/// expansion 2, contraction 1/2, shrink 1/2) within `evaluations`, stopping once the simplex's
/// values agree to 1e-12 of the best: the point and its value.
fn nelder_mead(
    f: impl Fn([f64; 3]) -> f64,
    start: [f64; 3],
    steps: [f64; 3],
    evaluations: usize,
) -> ([f64; 3], f64) {
    let add =
        |a: [f64; 3], b: [f64; 3], k: f64| [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let mut simplex: Vec<([f64; 3], f64)> = Vec::with_capacity(4);
    simplex.push((start, f(start)));
    for k in 0..3 {
        let mut x = start;
        x[k] += steps[k];
        simplex.push((x, f(x)));
    }
    let mut spent = 4;
    while spent < evaluations {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0].1, simplex[3].1);
        if worst - best <= 1e-12 * best.abs() {
            break;
        }
        let centroid = simplex[..3]
            .iter()
            .fold([0.0; 3], |c, (x, _)| add(c, *x, 1.0 / 3.0));
        let toward = sub(centroid, simplex[3].0);
        let reflected = add(centroid, toward, 1.0);
        let fr = f(reflected);
        spent += 1;
        if fr < best {
            let expanded = add(centroid, toward, 2.0);
            let fe = f(expanded);
            spent += 1;
            simplex[3] = if fe < fr {
                (expanded, fe)
            } else {
                (reflected, fr)
            };
        } else if fr < simplex[2].1 {
            simplex[3] = (reflected, fr);
        } else {
            let contracted = add(centroid, toward, -0.5);
            let fc = f(contracted);
            spent += 1;
            if fc < worst {
                simplex[3] = (contracted, fc);
            } else {
                let anchor = simplex[0].0;
                for vertex in simplex.iter_mut().skip(1) {
                    let x = add(anchor, sub(vertex.0, anchor), 0.5);
                    *vertex = (x, f(x));
                    spent += 1;
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex[0]
}
