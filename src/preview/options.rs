//! How the raster preview draws ([`PreviewOptions`]): the tolerance it cuts curved shapes to,
//! its reflections in curved mirrors and its shadows.

use super::DEFAULT_TOLERANCE_PX;

/// How the preview draws: how finely it cuts curved shapes, and the reflections of curved
/// mirrors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewOptions {
    /// How far (pixels on the film) the triangles of a curved shape may stray from it
    /// (`preview::Detail`).
    pub tolerance_px: f64,
    /// Pieces each edge of a reflected triangle is cut into; `None`: as many as keep every
    /// piece under 1/16 of the scene's radius (`preview::ReflectedSet`).
    pub subdivision: Option<u32>,
    /// The Fermat search's steps at most (the seed: 4–5).
    pub steps: u32,
    /// Searches (surfaces of mirrors: a teapot has 32) solved, and culled, in one dispatch at
    /// most; `None`: as many as the bindings hold (`preview::reflections::kernel::searches_per_solve`). One a
    /// dispatch is how the preview ran before it batched them (BENCHMARKS.md measures both).
    pub searches_per_dispatch: Option<usize>,
    /// Shadows from every light, by shadow maps (`preview::ShadowPlan`).
    pub shadows: bool,
    /// With shadows: an area light's cubes of shadow maps along each side of it (n² cubes).
    pub area_shadow_samples: u32,
    /// Where a mirror can see itself (a torus's inner ring, a teapot's spout in its body), it
    /// reflects its own triangles, cut for this tolerance (pixels on the film, as
    /// `tolerance_px`); `None`: mirrors do not reflect themselves.
    pub self_reflections: Option<f64>,
}

impl Default for PreviewOptions {
    /// Curved shapes within half a pixel; automatic subdivision; 12 steps, where Roger and Holzschuch's 5
    /// leave 13% of a fine floor's vertices unconverged (holes in the reflection) and 12 leave
    /// 0.5% (docs/fermat.md).
    fn default() -> PreviewOptions {
        PreviewOptions {
            tolerance_px: DEFAULT_TOLERANCE_PX,
            subdivision: None,
            steps: 12,
            searches_per_dispatch: None,
            shadows: false,
            area_shadow_samples: 1,
            self_reflections: None,
        }
    }
}
