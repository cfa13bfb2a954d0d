//! What the preview's shading reads and how it is specialised: the shader's source
//! ([`shader_source`]: `wgsl/preview/shading.wgsl` and `reflect.wgsl` after the generated
//! constants and the shared types), the shading variant a scene needs, and the bind group both
//! passes share (the uniforms, materials, lights and shadow maps).

use super::pipeline::{buffer_entry, sampler_entry, texture_entry};
use crate::gpu::kernels::Access::{ComparisonSampler, DepthTextureArray, StorageRead, Uniform};
use crate::gpu::kernels::Binding;
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

const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;

/// The uniforms (`PreviewUniforms`): the clip matrix for the vertices, the rest for shading.
pub const UNIFORMS: Binding =
    Binding::new(0, "preview", Uniform, wgpu::ShaderStages::VERTEX_FRAGMENT);
/// The scene's materials.
pub const MATERIALS: Binding = Binding::new(1, "preview_materials", StorageRead, FRAGMENT);
/// The scene's lights.
pub const LIGHTS: Binding = Binding::new(2, "preview_lights", StorageRead, FRAGMENT);
/// Every light's shadow maps, a layer each.
pub const SHADOW_MAPS: Binding = Binding::new(3, "shadow_maps", DepthTextureArray, FRAGMENT);
/// The maps' comparison sampler.
pub const SHADOW_SAMPLER: Binding = Binding::new(4, "shadow_sampler", ComparisonSampler, FRAGMENT);
/// Each layer's view.
pub const SHADOW_VIEWS: Binding = Binding::new(5, "shadow_views", StorageRead, FRAGMENT);
/// Each light's layers (`ShadowLight`).
pub const SHADOW_LIGHTS: Binding = Binding::new(6, "shadow_lights", StorageRead, FRAGMENT);
/// Where each cube of maps stands.
pub const SHADOW_ORIGINS: Binding = Binding::new(7, "shadow_origins", StorageRead, FRAGMENT);

/// What shading reads: group 0 of the main pass and of the reflection pass.
pub const SHADING_GROUP: &[Binding] = &[
    UNIFORMS,
    MATERIALS,
    LIGHTS,
    SHADOW_MAPS,
    SHADOW_SAMPLER,
    SHADOW_VIEWS,
    SHADOW_LIGHTS,
    SHADOW_ORIGINS,
];

/// What shading reads, the main pass's and the reflection passes' alike (their group 0).
#[derive(Clone, Copy)]
pub(crate) struct Shading<'a> {
    pub(crate) uniforms: &'a wgpu::Buffer,
    pub(crate) materials: &'a wgpu::Buffer,
    pub(crate) lights: &'a wgpu::Buffer,
    pub(crate) shadows: &'a Shadows,
}

impl Shading<'_> {
    /// Its bind group's entries, one per binding of [`SHADING_GROUP`].
    pub(crate) fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 8] {
        [
            buffer_entry(UNIFORMS, self.uniforms),
            buffer_entry(MATERIALS, self.materials),
            buffer_entry(LIGHTS, self.lights),
            texture_entry(SHADOW_MAPS, &self.shadows.maps),
            sampler_entry(SHADOW_SAMPLER, &self.shadows.sampler),
            buffer_entry(SHADOW_VIEWS, &self.shadows.views),
            buffer_entry(SHADOW_LIGHTS, &self.shadows.lights),
            buffer_entry(SHADOW_ORIGINS, &self.shadows.origins),
        ]
    }
}
