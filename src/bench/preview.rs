//! The raster preview's shadows traded against time (`chambre bench preview`): each scene
//! previewed without and with `--shadows` (and, where it has area lights, with n x n cubes of
//! shadow maps over each), the frame time (median of the timed frames, the ways interleaved),
//! the shadow maps' one-off drawing time, and FLIP of the whole image against the ray
//! tracer's (CPU path) at many samples per pixel. Both previews leave out what
//! the preview always does (specular lobes, depth of field, mirrors but curved ones): what
//! moves between the two rows is what the shadows buy.

use serde::Serialize;

use super::Spread;
use super::frame::{Way, render_once};
use crate::error::Result;
use crate::gpu::GpuContext;
use crate::layout::{LIGHT_AREA, LIGHT_TRIANGLE};
use crate::metrics::flip;
use crate::pack::flatten;
use crate::preview::{PreviewOptions, PreviewRenderer};
use crate::scene::Scene;

/// One scene previewed one way.
#[derive(Clone, Debug, Serialize)]
pub struct PreviewRow {
    /// The sample scene's name (`bench::sample_scene`: a file of `scenes/`).
    pub scene: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Lights in the scene.
    pub lights: usize,
    /// Whether the preview drew shadows.
    pub shadows: bool,
    /// With shadows: an area light's cubes along each side of it.
    pub area_shadow_samples: u32,
    /// Frame time, milliseconds.
    pub frame_ms: Spread,
    /// Shadow maps drawn.
    pub shadow_maps: usize,
    /// Texels along a shadow map's side.
    pub shadow_map_side: u32,
    /// The one drawing of the shadow maps, milliseconds.
    pub shadow_maps_ms: f64,
    /// FLIP of the whole image against the ray-traced reference.
    pub flip: f64,
}

/// The comparison's rows, two or three a scene.
#[derive(Clone, Debug, Serialize)]
pub struct PreviewReport {
    /// Samples per pixel of the ray-traced reference.
    pub reference_spp: u32,
    /// Timed frames each way.
    pub frames: u32,
    /// Rows a scene: without shadows, with, and with area lights' several cubes where it has
    /// area lights.
    pub rows: Vec<PreviewRow>,
}

/// Previews each of `scenes` (names in `scenes/`) `frames` times each way, interleaved, against
/// a ray-traced reference at `reference_spp`; area lights' shadows also from
/// `area_shadow_samples`² cubes.
pub fn run(
    context: &GpuContext,
    scenes: &[String],
    overrides: &[String],
    frames: u32,
    reference_spp: u32,
    area_shadow_samples: u32,
) -> Result<PreviewReport> {
    let mut rows = Vec::new();
    for name in scenes {
        let path = super::sample_scene(name);
        let scene = Scene::load(&path, overrides)?;
        let flat = flatten(&scene);
        let reference: Vec<String> = overrides
            .iter()
            .cloned()
            .chain([format!("render.spp={reference_spp}")])
            .collect();
        let reference = flatten(&Scene::load(&path, &reference)?);
        let features = reference.features();
        let reference = render_once(&reference, Way::Cpu { features }, None)?.image;
        let has_area_lights = flat
            .lights
            .iter()
            .any(|l| l.kind == LIGHT_AREA || l.kind == LIGHT_TRIANGLE);
        let mut ways = vec![(false, 1), (true, 1)];
        if has_area_lights && area_shadow_samples > 1 {
            ways.push((true, area_shadow_samples));
        }
        let renderers = ways
            .iter()
            .map(|&(shadows, area_shadow_samples)| {
                let options = PreviewOptions {
                    shadows,
                    area_shadow_samples,
                    ..Default::default()
                };
                PreviewRenderer::new(context, &scene, &flat, options)
            })
            .collect::<Result<Vec<_>>>()?;
        let mut times = vec![Vec::new(); ways.len()];
        for frame in 0..=frames.max(1) {
            for (renderer, times) in renderers.iter().zip(&mut times) {
                let start = std::time::Instant::now();
                renderer.draw()?;
                if frame > 0 {
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
        }
        for ((renderer, times), (shadows, area_shadow_samples)) in
            renderers.iter().zip(&times).zip(ways)
        {
            let (maps, side, drawn_in) = renderer.shadow_maps();
            rows.push(PreviewRow {
                scene: name.clone(),
                width: flat.frame.width,
                height: flat.frame.height,
                lights: flat.lights.len(),
                shadows,
                area_shadow_samples,
                frame_ms: Spread::of(times),
                shadow_maps: maps,
                shadow_map_side: side,
                shadow_maps_ms: drawn_in.as_secs_f64() * 1e3,
                flip: flip(&renderer.image()?, &reference),
            });
        }
    }
    Ok(PreviewReport {
        reference_spp,
        frames,
        rows,
    })
}

impl PreviewReport {
    /// The Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut out = format!(
            "The raster preview without and with shadows, against the ray tracer at {} spp \
             (CPU path); frame times over {} frames, the two interleaved\n\n\
             | scene | size | lights | shadows | preview frame (ms) | shadow maps, drawn once | \
             FLIP vs {} spp |\n|---|---|---|---|---|---|---|\n",
            self.reference_spp, self.frames, self.reference_spp
        );
        for r in &self.rows {
            let maps = match r.shadow_maps {
                0 => "-".to_string(),
                n => format!(
                    "{n} of {}² in {:.1} ms",
                    r.shadow_map_side, r.shadow_maps_ms
                ),
            };
            out += &format!(
                "| {} | {}x{} | {} | {} | {:.2} ({:.2}–{:.2}) | {maps} | {:.4} |\n",
                r.scene,
                r.width,
                r.height,
                r.lights,
                match (r.shadows, r.area_shadow_samples) {
                    (false, _) => "no".to_string(),
                    (true, 1) => "yes".to_string(),
                    (true, n) => format!("yes, area lights {n}x{n} cubes"),
                },
                r.frame_ms.median,
                r.frame_ms.min,
                r.frame_ms.max,
                r.flip
            );
        }
        out
    }
}
