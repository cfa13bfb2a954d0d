//! How a real lens's image circle covers the film of a view camera with its movements: the
//! relative illumination at the film's corners, and how far each movement may go before a corner
//! falls below half the axis's light. CPU, f64, on the f64 tracer of [`super::lens`];
//! `chambre camera` prints it and a render warns when a corner is past the circle. docs/lens.md.

use glam::DVec2;

use super::CameraSpec;
use crate::layout::LENS_PUPIL_CELLS;

/// A corner below this fraction of the axis's irradiance is outside the image circle (the
/// radius `chambre lens` reports as "at half illumination").
pub const HALF_ILLUMINATION: f64 = 0.5;

/// The grid each corner's irradiance is summed over (`LensSystem::irradiance_on`).
const CORNER_GRID: usize = 48;

/// A movement whose reach `movement_limits` finds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Movement {
    /// `film_shift[1]` upwards (mm): a rising back, as a rising front frames higher.
    Rise,
    /// `film_shift[1]` downwards (mm).
    Fall,
    /// `film_shift[0]` to the right (mm).
    CrossShift,
    /// `lens_tilt` forwards (degrees).
    LensTilt,
    /// `lens_swing` to the right (degrees).
    LensSwing,
}

impl Movement {
    /// Every movement, in the order the report lists them.
    pub const ALL: [Movement; 5] = [
        Movement::Rise,
        Movement::Fall,
        Movement::CrossShift,
        Movement::LensTilt,
        Movement::LensSwing,
    ];

    /// How the report names it, with its unit.
    pub fn label(self) -> &'static str {
        match self {
            Movement::Rise => "rise (film_shift up, mm)",
            Movement::Fall => "fall (film_shift down, mm)",
            Movement::CrossShift => "cross shift (film_shift right, mm)",
            Movement::LensTilt => "lens tilt (degrees)",
            Movement::LensSwing => "lens swing (degrees)",
        }
    }

    /// The farthest it is searched: 100 mm of shift, 45 degrees of tilt or swing.
    fn range(self) -> f64 {
        match self {
            Movement::LensTilt | Movement::LensSwing => 45.0,
            _ => 100.0,
        }
    }

    /// `camera` with this movement set to `value`, the others as they are.
    fn applied(self, camera: &CameraSpec, value: f64) -> CameraSpec {
        let mut moved = camera.clone();
        let m = &mut moved.movements;
        match self {
            Movement::Rise => m.film_shift[1] = value,
            Movement::Fall => m.film_shift[1] = -value,
            Movement::CrossShift => m.film_shift[0] = value,
            Movement::LensTilt => m.lens_tilt = value,
            Movement::LensSwing => m.lens_swing = value,
        }
        moved
    }
}

impl CameraSpec {
    /// The relative illumination at the film's four corners (bottom left, bottom right, top
    /// right, top left): each corner's irradiance under a uniform radiance over the axis's at
    /// the film's distance. `None` without a real lens.
    pub fn corner_illumination(&self) -> Option<[f64; 4]> {
        let lens = self.lens.as_ref()?;
        let s = self.standards();
        let normal = s.lens.transpose() * s.film.z_axis;
        let axis_point = glam::DVec3::new(0.0, 0.0, -self.film_distance_mm);
        let axis = lens.irradiance(axis_point, CORNER_GRID);
        let [w, h] = self.film_mm.map(|v| 0.5 * v);
        Some([(-w, -h), (w, -h), (w, h), (-w, h)].map(|(x, y)| {
            let corner = s.to_lens_frame(s.film_point(DVec2::new(x, y)));
            lens.irradiance_on(corner, normal, CORNER_GRID) / axis
        }))
    }

    /// For each movement, the farthest it may go (the others as the scene sets them) with every
    /// film corner keeping half the axis's light, found by bisection to 1/1000 of its range;
    /// `None` for a movement the corners are already outside the circle at 0, and the range
    /// itself when the circle covers it all. Empty without a real lens.
    pub fn movement_limits(&self) -> Vec<(Movement, Option<f64>)> {
        if self.lens.is_none() {
            return Vec::new();
        }
        let covered = |camera: &CameraSpec| {
            camera
                .corner_illumination()
                .is_some_and(|c| c.iter().all(|&v| v >= HALF_ILLUMINATION))
        };
        Movement::ALL
            .iter()
            .map(|&movement| {
                let at = |value: f64| covered(&movement.applied(self, value));
                if !at(0.0) {
                    return (movement, None);
                }
                let range = movement.range();
                if at(range) {
                    return (movement, Some(range));
                }
                (
                    movement,
                    Some(super::bisect_edge(0.0, range, 1e-3 * range, at)),
                )
            })
            .collect()
    }

    /// How many camera rays pass the lens, over the film's points where any passes: aimed
    /// through each film cell's exit-pupil bounds as the kernels aim them, and aimed at the whole
    /// rear square (1.5 times the rear element) as without bounds. Sampled at the centres of the
    /// kernels' cells, each with its cell's bounds, on a 32 x 32 grid of aims. `None` without a
    /// real lens.
    pub fn passing_fractions(&self) -> Option<[f64; 2]> {
        let lens = self.lens.as_ref()?;
        let half = lens.rear_square();
        let square = [DVec2::splat(-half), DVec2::splat(half)];
        let (mut bounded, mut whole, mut lit) = (0.0, 0.0, 0usize);
        for j in 0..LENS_PUPIL_CELLS {
            for i in 0..LENS_PUPIL_CELLS {
                let points = self.pupil_cell_points(i, j);
                let Some(bounds) = lens.pupil_bounds(&points) else {
                    continue;
                };
                let centre = points[4];
                lit += 1;
                bounded += lens.passing_fraction(centre, bounds, lens.aim_z(), 32);
                whole += lens.passing_fraction(centre, square, lens.rear_z(), 32);
            }
        }
        (lit > 0).then(|| [bounded / lit as f64, whole / lit as f64])
    }

    /// A warning when a film corner gets less than half the axis's light: the movements (or
    /// the film's size) take it past the lens's image circle.
    pub fn coverage_warning(&self) -> Option<String> {
        let corners = self.corner_illumination()?;
        let darkest = corners.iter().copied().fold(f64::INFINITY, f64::min);
        (darkest < HALF_ILLUMINATION).then(|| {
            format!(
                "a film corner gets {:.0}% of the light on the axis: the film reaches past the \
                 lens's image circle (`chambre camera` says how far each movement may go)",
                100.0 * darkest
            )
        })
    }
}
