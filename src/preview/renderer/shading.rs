//! What the preview's shading reads and how it is specialised: the shader's source
//! ([`shader_source`]: `wgsl/preview/shading.wgsl` and `reflect.wgsl` after the generated
//! constants and the shared types), the shading variant a scene needs, and the bind group both
//! passes share (the uniforms, materials, lights and shadow maps).

use super::pipeline::{buffer_entry, texture_entry};
use crate::layout::wgsl_prelude;
use crate::pack::FlatScene;
use crate::preview::shadows::maps::Shadows;
use crate::preview::{PreviewOptions, SHADOW_NORMAL_OFFSET};

/// The shader's source: constants, the shared types, the preview's stages and its reflection
/// stages.
pub fn shader_source() -> String {
    let types = crate::gpu::kernels::MODULES
        .iter()
        .find(|(name, _)| *name == "types.wgsl")
        .expect("types.wgsl is a module")
        .1;
    format!(
        "{}\nconst SHADOW_NORMAL_OFFSET: f32 = {SHADOW_NORMAL_OFFSET:?};\n{types}\n{}\n{}",
        wgsl_prelude(),
        include_str!("../../../wgsl/preview/shading.wgsl"),
        include_str!("../../../wgsl/preview/reflect.wgsl")
    )
}

/// The shading code a preview needs: Lambert's formula for area lights only where the scene
/// has some, the shadow maps' lookups only where it draws shadows (lavapipe runs a branch's
/// code for every fragment, masked, whichever way it goes: the formula in every pipeline made
/// the previews of scenes without area lights 2x slower).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadingVariant {
    area_lights: bool,
    shadows: bool,
}

impl ShadingVariant {
    pub(crate) fn of(flat: &FlatScene, options: &PreviewOptions) -> ShadingVariant {
        ShadingVariant {
            area_lights: flat.lights.iter().any(|l| l.is_area()),
            shadows: options.shadows,
        }
    }

    /// The pipeline-overridable constants of `wgsl/preview/shading.wgsl`.
    pub(crate) fn constants(&self) -> [(&'static str, f64); 2] {
        let flag = |on: bool| f64::from(u8::from(on));
        [
            ("PREVIEW_AREA_LIGHTS", flag(self.area_lights)),
            ("PREVIEW_SHADOWS", flag(self.shadows)),
        ]
    }
}

/// What shading reads, the main pass's and the reflection passes' alike (their group 0).
#[derive(Clone, Copy)]
pub(crate) struct Shading<'a> {
    pub(crate) uniforms: &'a wgpu::Buffer,
    pub(crate) materials: &'a wgpu::Buffer,
    pub(crate) lights: &'a wgpu::Buffer,
    pub(crate) shadows: &'a Shadows,
}

impl Shading<'_> {
    pub(crate) fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 8] {
        [
            buffer_entry(0, self.uniforms),
            buffer_entry(1, self.materials),
            buffer_entry(2, self.lights),
            texture_entry(3, &self.shadows.maps),
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(&self.shadows.sampler),
            },
            buffer_entry(5, &self.shadows.views),
            buffer_entry(6, &self.shadows.lights),
            buffer_entry(7, &self.shadows.origins),
        ]
    }
}
