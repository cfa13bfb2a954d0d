//! The raster preview's renderer ([`PreviewRenderer`]): a wgpu render pipeline (not a compute
//! kernel: it rasterises) that draws `preview::tessellate`'s triangles, indexed (`mesh`),
//! through the view camera's clip matrix into a float target with a depth buffer, and reads
//! the image back (`readback`). Shader: `wgsl/preview/shading.wgsl`, composed after the
//! generated constants and the shared struct types, as the kernels are (`shading`); the
//! pipelines, targets and attachments: `pipeline`; a frame's stages and their times: `timing`.
//!
//! Curved mirrors (spheres, tori, ellipsoids, cylinders, Bézier patches) show reflections by
//! Fermat's principle, all in one submission a frame (`preview::reflections::passes`): the
//! `fermat` kernel finds each reflected vertex's point on each mirror surface (a search each: a
//! teapot has 32) and `fermat_cull` lists the reflected triangles each shows, the main pass
//! writes which mirror each pixel sees (and the mirror's colour as if it reflected the
//! background), and the reflection pass draws each search's listed triangles over its mirror's
//! pixels (`wgsl/preview/reflect.wgsl`).
//!
//! With shadows (`PreviewOptions::shadows`), each light's shadow maps are drawn once from the
//! main pass's triangles (`preview::shadows::maps`, `wgsl/preview/shadow.wgsl`) and read by the
//! shading of both passes.

use std::time::{Duration, Instant};

use crate::camera::CameraSpec;
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, wgpu_error_text};
use crate::pack::FlatScene;
use crate::preview::reflections::passes::{ReflectionSetup, Reflections, reflected_triangles};
use crate::preview::shadows::maps::{Shadows, shadow_plan};
use crate::preview::{
    CurvedShapes, Cut, Detail, PreviewOptions, PreviewUniforms, PreviewVertex, ReflectedSet,
    ShadowPlan, clip_matrix, extent_and_far, eye_of, flat_triangles, reflectors,
};
use crate::render::Image;
use crate::scene::Scene;
use mesh::MainMesh;
use pipeline::{
    COLOR_FORMAT, DEPTH_FORMAT, ID_FORMAT, color_attachment, depth_attachment, render_pipeline,
};
use readback::read_back;
use shading::{Shading, ShadingVariant};
use timing::Stage;

pub(crate) mod mesh;
pub(crate) mod pipeline;
mod readback;
pub(crate) mod shading;
mod timing;

pub use pipeline::RasterPipeline;
pub use shading::shader_source;
pub use timing::StageTimes;

/// A preview frame and how long drawing it took.
pub struct PreviewFrame {
    /// Linear radiance, row 0 at the top.
    pub image: Image,
    /// Triangles drawn.
    pub triangles: usize,
    /// Median time of the timed frames: the draw submitted and finished on the device, without
    /// the read-back.
    pub frame_time: Duration,
    /// Every timed frame's time, milliseconds.
    pub frame_times_ms: Vec<f64>,
    /// Reflected triangles a frame (Fermat reflections on curved mirrors), summed over the
    /// searches: what the cull considers.
    pub reflected_triangles: usize,
    /// Of those, the ones the last frame drew: the cull's lists.
    pub reflected_drawn: usize,
    /// Curved shapes (spheres, tori, ellipsoids, cylinders, Bézier shapes), cut for the camera.
    pub curved_shapes: usize,
    /// Of those, the ones cut as finely as allowed that still stray further than the tolerance
    /// (or reach the eye's plane).
    pub coarse_shapes: usize,
    /// Shadow maps drawn, texels along their side, and how long drawing them last took
    /// (submitted and finished on the device): once for a static camera, again where a camera
    /// change cuts curved shapes anew.
    pub shadow_maps: (usize, u32, Duration),
}

/// Draws `scene` (flattened as `flat`) `frames` times after one warm-up and returns the last
/// frame, read back.
pub fn draw(
    context: &GpuContext,
    scene: &Scene,
    flat: &FlatScene,
    frames: u32,
) -> Result<PreviewFrame> {
    draw_with(context, scene, flat, frames, PreviewOptions::default())
}

/// [`draw`], with reflections drawn as `options` say.
pub fn draw_with(
    context: &GpuContext,
    scene: &Scene,
    flat: &FlatScene,
    frames: u32,
    options: PreviewOptions,
) -> Result<PreviewFrame> {
    let renderer = PreviewRenderer::new(context, scene, flat, options)?;
    renderer.draw()?;
    let times = renderer.timed_frames(frames)?;
    renderer.frame(&times)
}

/// What to do when the Fermat reflections' arrays outgrow a storage binding: they grow with
/// the pieces each reflected triangle is cut into (n² per triangle, each vertex solved for each
/// curved surface).
const FERMAT_ARRAYS_ADVICE: &str = "draw it with a smaller --subdivision (each reflected \
     triangle is cut into n² pieces, every vertex solved for each curved surface)";

/// The preview's pipeline, its buffers and its targets: draws a scene's triangles through a
/// camera (set again with [`PreviewRenderer::set_camera`] as a user composes a shot) into a
/// linear float image.
pub struct PreviewRenderer {
    context: GpuContext,
    pipeline: wgpu::RenderPipeline,
    /// The triangles, quads and planes, drawn as they are whatever the camera.
    flat_mesh: Option<MainMesh>,
    /// The curved shapes, cut anew when the camera asks for other grids.
    curved_mesh: Option<MainMesh>,
    curved: CurvedShapes,
    cuts: Vec<Cut>,
    /// The flat mesh's triangles: with the curved shapes' present cut, what mirrors reflect.
    flat_triangles: Vec<PreviewVertex>,
    reflected_set: ReflectedSet,
    tolerance_px: f64,
    self_reflections: Option<f64>,
    uniform_buffer: wgpu::Buffer,
    uniforms: PreviewUniforms,
    far: f64,
    bind_group: wgpu::BindGroup,
    targets: Targets,
    background: wgpu::Color,
    reflections: Option<Reflections>,
    shadows: Shadows,
}

impl PreviewRenderer {
    /// The pipeline and buffers of `scene` (flattened as `flat`), drawn through its camera;
    /// curved mirrors' reflections drawn as `options` say.
    pub fn new(
        context: &GpuContext,
        scene: &Scene,
        flat: &FlatScene,
        options: PreviewOptions,
    ) -> Result<PreviewRenderer> {
        let device = &context.device;
        let size = (flat.frame.width, flat.frame.height);
        let eye = eye_of(&scene.camera);
        let (extent, far) = extent_and_far(scene, flat);
        let clip = clip_matrix(&scene.camera, far);
        let curved = CurvedShapes::of(flat);
        let cuts = curved.cuts(&Detail::new(clip, size, options.tolerance_px));
        let uniforms = frame_uniforms(flat, clip, eye);
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("preview"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let variant = ShadingVariant::of(flat, &options);
        let pipeline = main_pipeline(device, &module, &variant);
        let flat_triangles = flat_triangles(flat, extent);
        let curved_triangles = curved.triangles(&cuts);
        let flat_mesh = MainMesh::new(device, &flat_triangles);
        let curved_mesh = MainMesh::new(device, &curved_triangles);
        let mirrors = reflectors(flat);
        let reflected_set = ReflectedSet::new(
            flat,
            options.subdivision,
            options.self_reflections.is_some(),
        );
        let reflected = match mirrors.is_empty() {
            true => Vec::new(),
            false => reflected_set.of(&reflected_triangles(
                &flat_triangles,
                &curved_triangles,
                &curved,
                options
                    .self_reflections
                    .map(|px| Detail::new(clip, size, px)),
            )),
        };
        let uniform_buffer =
            context.uniform_buffer("preview uniforms", bytemuck::bytes_of(&uniforms));
        let materials =
            context.storage_buffer("materials", bytemuck::cast_slice(&flat.materials))?;
        let lights = context.storage_buffer("lights", bytemuck::cast_slice(&flat.lights))?;
        let shadows = Shadows::new(context, planned_shadows(flat, &options)?)?;
        shadows.draw(context, [&flat_mesh, &curved_mesh])?;
        let shading = Shading {
            uniforms: &uniform_buffer,
            materials: &materials,
            lights: &lights,
            shadows: &shadows,
        };
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("preview"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &shading.entries(),
        });
        let targets = Targets::new(device, size);
        let reflections = Reflections::new(
            context,
            &ReflectionSetup {
                module: &module,
                variant,
                shading,
                color_view: &targets.color_view,
                id_view: &targets.id_view,
                eye,
                far,
                size: targets.color.size(),
            },
            mirrors,
            &reflected,
            options,
        )
        .map_err(|e| e.with_advice(FERMAT_ARRAYS_ADVICE))?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the preview pipeline: {}",
                wgpu_error_text(&e)
            )));
        }
        let [r, g, b] = preview_background(flat).map(f64::from);
        Ok(PreviewRenderer {
            context: context.clone(),
            pipeline,
            flat_mesh,
            curved_mesh,
            curved,
            cuts,
            flat_triangles,
            reflected_set,
            tolerance_px: options.tolerance_px,
            self_reflections: options.self_reflections,
            uniform_buffer,
            uniforms,
            far,
            bind_group,
            targets,
            background: wgpu::Color { r, g, b, a: 1.0 },
            reflections,
            shadows,
        })
    }

    /// Draws through `camera` from now on (the scene's geometry and lights stay; its curved
    /// shapes are cut anew where the camera needs other grids, in the main pass and as mirrors
    /// reflect them, a mirror's own reflected triangles with them, their shadows drawn anew). Fails where the reflected triangles, cut anew,
    /// outgrow the device's buffers (the renderer then draws as it did before the call), or
    /// where the device fails drawing the shadow maps.
    pub fn set_camera(&mut self, camera: &CameraSpec) -> Result<()> {
        let eye = eye_of(camera);
        let clip = clip_matrix(camera, self.far);
        let cuts = self
            .curved
            .cuts(&Detail::new(clip, self.image_size(), self.tolerance_px));
        if cuts != self.cuts {
            let curved_triangles = self.curved.triangles(&cuts);
            let own_detail = self
                .self_reflections
                .map(|px| Detail::new(clip, self.image_size(), px));
            if let Some(reflections) = &mut self.reflections {
                let triangles = reflected_triangles(
                    &self.flat_triangles,
                    &curved_triangles,
                    &self.curved,
                    own_detail,
                );
                reflections
                    .load(&self.context, &self.reflected_set.of(&triangles), eye)
                    .map_err(|e| e.with_advice(FERMAT_ARRAYS_ADVICE))?;
            }
            self.curved_mesh = MainMesh::new(&self.context.device, &curved_triangles);
            self.cuts = cuts;
            // The curved shapes cast their shadows as cut now.
            self.shadows
                .draw(&self.context, [&self.flat_mesh, &self.curved_mesh])?;
        }
        self.uniforms.clip = clip.as_mat4().to_cols_array_2d();
        self.uniforms.eye = [eye.x, eye.y, eye.z, 0.0];
        self.context.queue.write_buffer(
            &self.uniform_buffer,
            0,
            bytemuck::bytes_of(&self.uniforms),
        );
        if let Some(reflections) = &self.reflections {
            reflections.set_eye(&self.context, eye);
        }
        Ok(())
    }

    /// Draws one frame into the image and waits for the device.
    pub fn draw(&self) -> Result<()> {
        let mut encoder = self
            .context
            .device
            .create_command_encoder(&Default::default());
        for stage in Stage::ALL {
            self.encode_stage(&mut encoder, stage);
        }
        self.context
            .wait(self.context.queue.submit([encoder.finish()]))
    }

    /// Records one stage of a frame: the Fermat solves, their cull, the main pass or the
    /// reflection pass (a frame records all four in this order).
    fn encode_stage(&self, encoder: &mut wgpu::CommandEncoder, stage: Stage) {
        match (stage, &self.reflections) {
            (Stage::Solve, Some(reflections)) => reflections.solve(encoder),
            (Stage::Cull, Some(reflections)) => reflections.cull(encoder),
            (Stage::Reflect, Some(reflections)) => reflections.draw(encoder),
            (Stage::Main, _) => self.encode_main(encoder),
            (_, None) => {}
        }
    }

    /// Records the main pass: the scene, and the id target the reflections are drawn over.
    fn encode_main(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("preview"),
            color_attachments: &[
                color_attachment(
                    &self.targets.color_view,
                    wgpu::LoadOp::Clear(self.background),
                ),
                color_attachment(
                    &self.targets.id_view,
                    wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                ),
            ],
            depth_stencil_attachment: depth_attachment(
                &self.targets.depth_view,
                wgpu::StoreOp::Store,
            ),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        for mesh in [&self.flat_mesh, &self.curved_mesh].into_iter().flatten() {
            mesh.draw(&mut pass);
        }
    }

    /// Where a frame's time goes: `frames` frames (at least one), each stage submitted alone
    /// and waited for, timed on the host; each stage's median over the frames. Each figure
    /// includes a submission's round trip (on lavapipe about 0.1 ms), which a frame, one
    /// submission, pays once. (Timestamp queries around the passes of one submission would
    /// leave the round trips out, but on lavapipe they did not bracket the work: a teapot's
    /// solves read 0.06 ms at 12 steps and 0.25 ms at one, their time in the passes after.)
    pub fn stage_times(&self, frames: u32) -> Result<StageTimes> {
        let mut samples = Vec::new();
        for _ in 0..frames.max(1) {
            let mut times = StageTimes::default();
            for stage in Stage::ALL {
                let start = Instant::now();
                let mut encoder = self
                    .context
                    .device
                    .create_command_encoder(&Default::default());
                self.encode_stage(&mut encoder, stage);
                self.context
                    .wait(self.context.queue.submit([encoder.finish()]))?;
                times.add(stage, start.elapsed().as_secs_f64() * 1e3);
            }
            samples.push(times);
        }
        Ok(StageTimes::median(&samples))
    }

    /// Draws `frames` frames (at least one), each timed alone: submitted and finished on the
    /// device.
    pub fn timed_frames(&self, frames: u32) -> Result<Vec<Duration>> {
        (0..frames.max(1))
            .map(|_| {
                let start = Instant::now();
                self.draw()?;
                Ok(start.elapsed())
            })
            .collect()
    }

    /// The last frame drawn, read back, with `times` (at least one) those of its timed frames.
    pub fn frame(&self, times: &[Duration]) -> Result<PreviewFrame> {
        let mut sorted = times.to_vec();
        sorted.sort();
        Ok(PreviewFrame {
            image: self.image()?,
            triangles: self.triangles(),
            frame_time: sorted[sorted.len() / 2],
            frame_times_ms: times.iter().map(|t| t.as_secs_f64() * 1e3).collect(),
            reflected_triangles: self.reflected_triangles(),
            reflected_drawn: self.reflected_drawn()?,
            curved_shapes: self.cuts.len(),
            coarse_shapes: self.coarse_shapes(),
            shadow_maps: self.shadow_maps(),
        })
    }

    /// The image (linear radiance) as last drawn, read back.
    pub fn image(&self) -> Result<Image> {
        let size = self.targets.color.size();
        read_back(&self.context, &self.targets.color, size.width, size.height)
    }

    /// The image's width and height in pixels.
    pub fn image_size(&self) -> (u32, u32) {
        let size = self.targets.color.size();
        (size.width, size.height)
    }

    /// The image as a texture view (linear radiance, `Rgba32Float`).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.targets.color_view
    }

    /// Shadow maps, texels along their side, and how long drawing them last took.
    pub fn shadow_maps(&self) -> (usize, u32, Duration) {
        let shadows = &self.shadows;
        (shadows.layers.len(), shadows.side, shadows.drawn_in.get())
    }

    /// Triangles drawn a frame.
    pub fn triangles(&self) -> usize {
        [&self.flat_mesh, &self.curved_mesh]
            .into_iter()
            .flatten()
            .map(|mesh| mesh.index_count as usize / 3)
            .sum()
    }

    /// Curved shapes cut as finely as allowed that still stray further than the tolerance (or
    /// reach the eye's plane).
    pub fn coarse_shapes(&self) -> usize {
        self.cuts.iter().filter(|c| !c.within).count()
    }

    /// The reflected triangles the last frame drew, summed over the searches (the cull's
    /// counts, read back).
    pub fn reflected_drawn(&self) -> Result<usize> {
        self.reflections
            .as_ref()
            .map_or(Ok(0), |r| r.drawn(&self.context))
    }

    /// Reflected triangles a frame, summed over the curved mirrors' searches: each search's
    /// cull considers them all, and the draw runs for those whose reflection shows.
    pub fn reflected_triangles(&self) -> usize {
        self.reflections.as_ref().map_or(0, Reflections::triangles)
    }
}

/// The uniforms of the first frame: `flat`'s lights, depth, ambient and background, seen from
/// `eye` through `clip`.
fn frame_uniforms(flat: &FlatScene, clip: glam::DMat4, eye: glam::Vec3) -> PreviewUniforms {
    PreviewUniforms {
        clip: clip.as_mat4().to_cols_array_2d(),
        light_count: flat.frame.light_count,
        max_depth: flat.frame.max_depth,
        ambient: [
            flat.frame.ambient[0],
            flat.frame.ambient[1],
            flat.frame.ambient[2],
            0.0,
        ],
        eye: [eye.x, eye.y, eye.z, 0.0],
        background: {
            let [r, g, b] = preview_background(flat);
            [r, g, b, 0.0]
        },
        ..Default::default()
    }
}

/// What the preview shows where nothing is: the background, or an environment light's mean
/// radiance (`layout::LIGHT_ENVIRONMENT`), which the preview draws no map of.
fn preview_background(flat: &FlatScene) -> [f32; 3] {
    let environment = flat
        .lights
        .iter()
        .find(|l| l.kind == crate::layout::LIGHT_ENVIRONMENT);
    match environment {
        Some(l) => (glam::Vec3::from(l.color) * glam::Vec3::from(l.p1)).to_array(),
        None => flat.frame.background,
    }
}

/// The main pass: the meshes' vertices shaded (`wgsl/preview/shading.wgsl`).
pub const MAIN_PASS: RasterPipeline = RasterPipeline {
    name: "preview",
    source: shader_source,
    vertex: "preview_vertex",
    fragment: Some("preview_fragment"),
    groups: &[shading::SHADING_GROUP],
};

/// The main pass's pipeline: the meshes' vertices (`PreviewVertex`) shaded into the colour and
/// the id target.
fn main_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    variant: &ShadingVariant,
) -> wgpu::RenderPipeline {
    let vertex_layout = wgpu::VertexBufferLayout {
        array_stride: size_of::<PreviewVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Uint32, 2 => Float32x3, 3 => Uint32
        ],
    };
    render_pipeline(
        device,
        module,
        &MAIN_PASS,
        &[Some(vertex_layout)],
        &[Some(COLOR_FORMAT.into()), Some(ID_FORMAT.into())],
        &variant.constants(),
    )
}

/// The shadow maps `options` ask for: every light's where it draws shadows, else none.
fn planned_shadows(flat: &FlatScene, options: &PreviewOptions) -> Result<ShadowPlan> {
    match options.shadows {
        true => shadow_plan(flat, options.area_shadow_samples),
        false => Ok(ShadowPlan::none(flat.lights.len())),
    }
}

/// The main pass's targets: the colour (linear radiance, read back and shown by the window),
/// the depth buffer, and the id of the mirror each pixel sees (the reflection passes read it).
struct Targets {
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    id_view: wgpu::TextureView,
}

impl Targets {
    fn new(device: &wgpu::Device, (width, height): (u32, u32)) -> Targets {
        let target = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("preview target"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        // Sampled too: the interactive window shows it (`preview::window`).
        let color = target(
            COLOR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let depth = target(DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let id = target(
            ID_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        Targets {
            color_view: color.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            id_view: id.create_view(&Default::default()),
            color,
        }
    }
}
