//! The shadow maps on the device: the plan's depth maps in one texture array, the comparison
//! sampler and the views and lights the shading reads ([`Shadows`]), and the depth-only pipeline
//! that draws them from the main pass's meshes (`wgsl/preview/shadow.wgsl`).

use std::time::{Duration, Instant};

use super::{SHADOW_MEMORY, SMALLEST_SHADOW_MAP, ShadowPlan, shadow_map_size};
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::{Access, Binding};
use crate::pack::FlatScene;
use crate::preview::renderer::mesh::MainMesh;
use crate::preview::renderer::pipeline::{
    DEPTH_FORMAT, RasterPipeline, buffer_entry, depth_attachment, depth_test,
};
use crate::preview::{PreviewVertex, bounded_sphere};

/// The shadow maps' shader (`wgsl/preview/shadow.wgsl`): positions through a light's view.
pub const SHADOW_SHADER: &str = include_str!("../../../wgsl/preview/shadow.wgsl");

/// A layer's view: world to the light's clip space.
pub const LIGHT_VIEW: Binding =
    Binding::new(0, "light_view", Access::Uniform, wgpu::ShaderStages::VERTEX);

/// The shadow maps' pass: the main pass's triangles, depth only, through one layer's view.
pub const SHADOW_PASS: RasterPipeline = RasterPipeline {
    name: "shadow map",
    source: || SHADOW_SHADER.to_string(),
    vertex: "shadow_vertex",
    fragment: None,
    groups: &[&[LIGHT_VIEW]],
};

/// The shadow maps of `flat`'s lights, `area_samples`² cubes for an area light, as large as
/// `SHADOW_MEMORY` holds; refused where not even the smallest fit.
pub(crate) fn shadow_plan(flat: &FlatScene, area_samples: u32) -> Result<ShadowPlan> {
    let layers = ShadowPlan::layers(&flat.lights, area_samples);
    let side = shadow_map_size(layers).ok_or_else(|| {
        Error::Gpu(format!(
            "--shadows: the scene's {} lights need {layers} shadow maps (a cube of six for \
             each light but a directional one, {area_samples}² cubes for an area light), more \
             than {} MiB holds at {} texels a side; preview it without --shadows or with fewer \
             --area-shadow-samples",
            flat.lights.len(),
            SHADOW_MEMORY >> 20,
            SMALLEST_SHADOW_MAP
        ))
    })?;
    Ok(ShadowPlan::new(
        &flat.lights,
        bounded_sphere(flat),
        side,
        area_samples,
    ))
}

/// The lights' shadow maps (`preview::ShadowPlan`; one unread texel where the preview draws no
/// shadows), their views and lights as the shading reads them, and what draws them.
pub(crate) struct Shadows {
    pub(crate) maps: wgpu::TextureView,
    pub(crate) sampler: wgpu::Sampler,
    pub(crate) views: wgpu::Buffer,
    pub(crate) lights: wgpu::Buffer,
    pub(crate) origins: wgpu::Buffer,
    /// Per layer: its depth target and its view's uniforms.
    pub(crate) layers: Vec<(wgpu::TextureView, wgpu::BindGroup)>,
    /// Texels along a map's side.
    pub(crate) side: u32,
    pipeline: Option<wgpu::RenderPipeline>,
    /// How long the last drawing of the maps took.
    pub(crate) drawn_in: std::cell::Cell<Duration>,
}

impl Shadows {
    /// The maps `plan` asks for, not yet drawn; refused where they need more layers than a
    /// texture of this device holds.
    pub(crate) fn new(context: &GpuContext, plan: ShadowPlan) -> Result<Shadows> {
        let device = &context.device;
        let layers = plan.views.len() as u32;
        let most = device.limits().max_texture_array_layers;
        if layers > most {
            return Err(Error::Gpu(format!(
                "--shadows: the scene's {} lights need {layers} shadow maps (a cube of six for \
                 each light but a directional one, several for an area light with \
                 --area-shadow-samples), more than this device holds in one texture \
                 (max_texture_array_layers = {most}); preview it without --shadows or with \
                 fewer --area-shadow-samples",
                plan.lights.len()
            )));
        }
        let side = plan.side;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow maps"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: layers.max(1),
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let maps = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow maps"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let pipeline = (layers > 0).then(|| shadow_pipeline(device));
        let layers = match &pipeline {
            None => Vec::new(),
            Some(pipeline) => (0..layers)
                .map(|k| {
                    let target = texture.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: k,
                        array_layer_count: Some(1),
                        ..Default::default()
                    });
                    let view = plan.views[k as usize].to_cols_array_2d();
                    let uniforms = context.uniform_buffer("shadow view", bytemuck::bytes_of(&view));
                    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("shadow view"),
                        layout: &pipeline.get_bind_group_layout(0),
                        entries: &[buffer_entry(LIGHT_VIEW, &uniforms)],
                    });
                    (target, group)
                })
                .collect(),
        };
        let views: Vec<[[f32; 4]; 4]> = plan.views.iter().map(|v| v.to_cols_array_2d()).collect();
        Ok(Shadows {
            maps,
            sampler,
            views: context.storage_buffer("shadow views", bytemuck::cast_slice(&views))?,
            lights: context.storage_buffer("shadow lights", bytemuck::cast_slice(&plan.lights))?,
            origins: context
                .storage_buffer("shadow origins", bytemuck::cast_slice(&plan.origins))?,
            layers,
            side,
            pipeline,
            drawn_in: Default::default(),
        })
    }

    /// Draws every map from `meshes` (the main pass's) and waits for the device.
    pub(crate) fn draw(&self, context: &GpuContext, meshes: [&Option<MainMesh>; 2]) -> Result<()> {
        let Some(pipeline) = &self.pipeline else {
            return Ok(());
        };
        let start = Instant::now();
        let mut encoder = context.device.create_command_encoder(&Default::default());
        for (target, group) in &self.layers {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: depth_attachment(target, wgpu::StoreOp::Store),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            for mesh in meshes.into_iter().flatten() {
                mesh.draw(&mut pass);
            }
        }
        context.wait(context.queue.submit([encoder.finish()]))?;
        self.drawn_in.set(start.elapsed());
        Ok(())
    }
}

/// The shadow maps' pipeline: positions only, depth only, with a slope-scaled bias so that a
/// surface at a grazing angle to the light does not shadow itself.
fn shadow_pipeline(device: &wgpu::Device) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("preview shadows"),
        source: wgpu::ShaderSource::Wgsl(SHADOW_SHADER.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(SHADOW_PASS.name),
        layout: Some(&SHADOW_PASS.layout(device)),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(SHADOW_PASS.vertex),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: size_of::<PreviewVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3],
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth_test(wgpu::DepthBiasState {
            constant: 0,
            slope_scale: 2.0,
            clamp: 0.0,
        }),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}
