//! The preview's render targets and pipelines: the targets' formats, how a render pipeline is
//! described ([`RasterPipeline`]: its shader, entry points and bindings by name, as the kernel
//! registry describes a kernel) and made (a depth test that keeps the nearest fragment), its
//! passes' attachments and bind group entries.

use crate::gpu::kernels::{Binding, bind_group_layout};

/// The colour target: linear radiance, as the ray tracer's accumulation.
pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Which reflector each pixel sees (1 + its index; 0 for none), and the f32 bits of the distance
/// from the eye it sees it at.
pub(crate) const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;

/// A render pipeline of the preview: its shader, its entry points and the bindings of each of
/// its bind groups by name (`gpu::kernels::Binding`), as `gpu::kernels::Kernel` describes a
/// compute kernel. Its layout is made from these ([`RasterPipeline::layout`]); tests/wgsl.rs
/// checks them against what the shader declares and each entry point reads.
#[derive(Debug)]
pub struct RasterPipeline {
    /// Label of its pipeline and layouts.
    pub name: &'static str,
    /// Its shader's complete source.
    pub source: fn() -> String,
    /// The `@vertex` function.
    pub vertex: &'static str,
    /// The `@fragment` function, if any (a depth-only pass has none).
    pub fragment: Option<&'static str>,
    /// Each bind group's bindings, group 0 first.
    pub groups: &'static [&'static [Binding]],
}

impl RasterPipeline {
    /// Its pipeline layout: a bind group layout per group, made from its bindings (a bind
    /// group for group `i` is made with `pipeline.get_bind_group_layout(i)`).
    pub fn layout(&self, device: &wgpu::Device) -> wgpu::PipelineLayout {
        let groups: Vec<wgpu::BindGroupLayout> = self
            .groups
            .iter()
            .map(|bindings| bind_group_layout(device, self.name, bindings))
            .collect();
        let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(Some).collect();
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.name),
            bind_group_layouts: &groups,
            immediate_size: 0,
        })
    }
}

/// The render pipeline `description` of the preview's `module`: a depth test against
/// `DEPTH_FORMAT` that keeps the nearest, the fragment stage's override `constants`
/// (`ShadingVariant::constants`), the layout made from its bindings.
pub(crate) fn render_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    description: &RasterPipeline,
    buffers: &[Option<wgpu::VertexBufferLayout>],
    targets: &[Option<wgpu::ColorTargetState>],
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(description.name),
        layout: Some(&description.layout(device)),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(description.vertex),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth_test(Default::default()),
        multisample: Default::default(),
        fragment: description.fragment.map(|fragment| wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The nearer fragment wins and is written, its depth moved by `bias`.
pub(crate) fn depth_test(bias: wgpu::DepthBiasState) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias,
    })
}

/// A colour attachment loaded as `load` and stored.
pub(crate) fn color_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A depth attachment cleared to the far plane.
pub(crate) fn depth_attachment(
    view: &wgpu::TextureView,
    store: wgpu::StoreOp,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store,
        }),
        stencil_ops: None,
    })
}

/// `binding` of a group: all of `buffer`.
pub(crate) fn buffer_entry(binding: Binding, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding: binding.binding,
        resource: buffer.as_entire_binding(),
    }
}

/// `binding` of a group: the texture `view`.
pub(crate) fn texture_entry(
    binding: Binding,
    view: &wgpu::TextureView,
) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding: binding.binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// `binding` of a group: `sampler`.
pub(crate) fn sampler_entry(binding: Binding, sampler: &wgpu::Sampler) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding: binding.binding,
        resource: wgpu::BindingResource::Sampler(sampler),
    }
}
