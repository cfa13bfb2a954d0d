//! The raster preview's GPU side: a wgpu render pipeline (not a compute kernel: it rasterises)
//! that draws `preview::tessellate`'s triangles, indexed, through the view camera's clip matrix
//! into a float target with a depth buffer, and reads the image back. Shader:
//! `wgsl/preview.wgsl`, composed after the generated constants and the shared struct types, as
//! the kernels are.
//!
//! Curved mirrors (spheres, tori, ellipsoids, cylinders, Bézier patches) show reflections by
//! Fermat's principle (seed 004), all in one submission a frame: the `fermat` kernel finds each
//! reflected vertex's point on each mirror surface (a search each: a teapot has 32) and
//! `fermat_cull` lists the reflected triangles each shows, the main pass writes which mirror
//! each pixel sees (and the mirror's colour as if it reflected the background), and the
//! reflection pass draws each search's listed triangles over its mirror's pixels
//! (`wgsl/preview_reflect.wgsl`).
//!
//! With shadows (`PreviewOptions::shadows`), each light's shadow maps are drawn once from the
//! main pass's triangles (`Shadows`, `wgsl/preview_shadow.wgsl`) and read by the shading of both
//! passes.

use std::time::{Duration, Instant};

use wgpu::util::DeviceExt;

use crate::camera::CameraSpec;
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, wgpu_error_text};
use crate::layout::{GpuDrawArgs, GpuReflector, wgsl_prelude};
use crate::pack::FlatScene;
use crate::preview::reflections::kernel::{FermatCull, FermatPass, FermatSolve};
use crate::preview::{
    CurvedShapes, Cut, Detail, MirrorSurface, PreviewOptions, PreviewUniforms, PreviewVertex,
    ReflectedSet, Reflector, ReflectorPass, SHADOW_MEMORY, SHADOW_NORMAL_OFFSET,
    SMALLEST_SHADOW_MAP, ShadowPlan, bounded_sphere, clip_matrix, extent_and_far, eye_of,
    flat_triangles, reflectors, shadow_map_size,
};
use crate::render::Image;
use crate::scene::Scene;

/// The colour target: linear radiance, as the ray tracer's accumulation.
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Which reflector each pixel sees (1 + its index; 0 for none), and the f32 bits of the distance
/// from the eye it sees it at.
const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;

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

/// The shadow maps' shader (`wgsl/preview_shadow.wgsl`): positions through a light's view.
pub const SHADOW_SHADER: &str = include_str!("../../../wgsl/preview/shadow.wgsl");

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
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    id_view: wgpu::TextureView,
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
        let (width, height) = (flat.frame.width, flat.frame.height);
        let eye = eye_of(&scene.camera);
        let (extent, far) = extent_and_far(scene, flat);
        let clip = clip_matrix(&scene.camera, far);
        let detail = Detail::new(clip, (width, height), options.tolerance_px);
        let curved = CurvedShapes::of(flat);
        let cuts = curved.cuts(&detail);
        let uniforms = PreviewUniforms {
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
            background: [
                flat.frame.background[0],
                flat.frame.background[1],
                flat.frame.background[2],
                0.0,
            ],
            ..Default::default()
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("preview"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: size_of::<PreviewVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![
                0 => Float32x3, 1 => Uint32, 2 => Float32x3, 3 => Uint32
            ],
        };
        let variant = ShadingVariant::of(flat, &options);
        let pipeline = render_pipeline(
            device,
            &module,
            ("preview_vertex", "preview_fragment"),
            &[Some(vertex_layout)],
            &[Some(COLOR_FORMAT.into()), Some(ID_FORMAT.into())],
            &variant,
        );
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
                    .map(|px| Detail::new(clip, (width, height), px)),
            )),
        };
        let uniform_buffer =
            context.uniform_buffer("preview uniforms", bytemuck::bytes_of(&uniforms));
        let materials =
            context.storage_buffer("materials", bytemuck::cast_slice(&flat.materials))?;
        let lights = context.storage_buffer("lights", bytemuck::cast_slice(&flat.lights))?;
        let plan = match options.shadows {
            true => shadow_plan(flat, options.area_shadow_samples)?,
            false => ShadowPlan::none(flat.lights.len()),
        };
        let shadows = Shadows::new(context, plan)?;
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
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let target = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("preview target"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        // Sampled too: the interactive window shows it (`gpu::window`).
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
        let (color_view, depth_view, id_view) = (
            color.create_view(&Default::default()),
            depth.create_view(&Default::default()),
            id.create_view(&Default::default()),
        );
        let reflections = Reflections::new(
            context,
            &ReflectionSetup {
                module: &module,
                variant,
                shading,
                color_view: &color_view,
                id_view: &id_view,
                eye,
                far,
                size,
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
        let [r, g, b] = flat.frame.background.map(f64::from);
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
            color,
            color_view,
            depth_view,
            id_view,
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
                color_attachment(&self.color_view, wgpu::LoadOp::Clear(self.background)),
                color_attachment(&self.id_view, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)),
            ],
            depth_stencil_attachment: depth_attachment(&self.depth_view, wgpu::StoreOp::Store),
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
        let size = self.color.size();
        read_back(&self.context, &self.color, size.width, size.height)
    }

    /// The image's width and height in pixels.
    pub fn image_size(&self) -> (u32, u32) {
        let size = self.color.size();
        (size.width, size.height)
    }

    /// The image as a texture view (linear radiance, `Rgba32Float`).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.color_view
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
        let Some(reflections) = &self.reflections else {
            return Ok(0);
        };
        let mut drawn = 0;
        for batch in &reflections.geometry.batches {
            let args = self.context.read_buffer::<GpuDrawArgs>(&batch.cull.args)?[0];
            drawn += args.index_count as usize / 3;
        }
        Ok(drawn)
    }

    /// Reflected triangles a frame, summed over the curved mirrors' searches: each search's
    /// cull considers them all, and the draw runs for those whose reflection shows.
    pub fn reflected_triangles(&self) -> usize {
        self.reflections.as_ref().map_or(0, |r| {
            r.geometry.vertex_count as usize / 3 * r.searches.len()
        })
    }
}

/// Triangles of the main pass, drawn indexed.
struct MainMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}

impl MainMesh {
    /// `triangles` in a vertex and an index buffer; `None` for none (wgpu refuses an empty
    /// slice: a scene without shapes draws the background only).
    fn new(device: &wgpu::Device, triangles: &[PreviewVertex]) -> Option<MainMesh> {
        if triangles.is_empty() {
            return None;
        }
        let (distinct, indices) = indexed(triangles);
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        Some(MainMesh {
            vertices: buffer(
                "preview vertices",
                bytemuck::cast_slice(&distinct),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer(
                "preview indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX,
            ),
            index_count: indices.len() as u32,
        })
    }

    fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// The shadow maps of `flat`'s lights, `area_samples`² cubes for an area light, as large as
/// `SHADOW_MEMORY` holds; refused where not even the smallest fit.
fn shadow_plan(flat: &FlatScene, area_samples: u32) -> Result<ShadowPlan> {
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

/// The shading code a preview needs: Lambert's formula for area lights only where the scene
/// has some, the shadow maps' lookups only where it draws shadows (lavapipe runs a branch's
/// code for every fragment, masked, whichever way it goes: the formula in every pipeline made
/// the previews of scenes without area lights 2x slower).
#[derive(Clone, Copy, Debug)]
struct ShadingVariant {
    area_lights: bool,
    shadows: bool,
}

impl ShadingVariant {
    fn of(flat: &FlatScene, options: &PreviewOptions) -> ShadingVariant {
        ShadingVariant {
            area_lights: flat.lights.iter().any(|l| l.is_area()),
            shadows: options.shadows,
        }
    }

    /// The pipeline-overridable constants of `wgsl/preview.wgsl`.
    fn constants(&self) -> [(&'static str, f64); 2] {
        let flag = |on: bool| f64::from(u8::from(on));
        [
            ("PREVIEW_AREA_LIGHTS", flag(self.area_lights)),
            ("PREVIEW_SHADOWS", flag(self.shadows)),
        ]
    }
}

/// What shading reads, the main pass's and the reflection passes' alike (their group 0).
#[derive(Clone, Copy)]
struct Shading<'a> {
    uniforms: &'a wgpu::Buffer,
    materials: &'a wgpu::Buffer,
    lights: &'a wgpu::Buffer,
    shadows: &'a Shadows,
}

impl Shading<'_> {
    fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 8] {
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

/// The lights' shadow maps (`preview::ShadowPlan`; one unread texel where the preview draws no
/// shadows), their views and lights as the shading reads them, and what draws them.
struct Shadows {
    maps: wgpu::TextureView,
    sampler: wgpu::Sampler,
    views: wgpu::Buffer,
    lights: wgpu::Buffer,
    origins: wgpu::Buffer,
    /// Per layer: its depth target and its view's uniforms.
    layers: Vec<(wgpu::TextureView, wgpu::BindGroup)>,
    /// Texels along a map's side.
    side: u32,
    pipeline: Option<wgpu::RenderPipeline>,
    /// How long the last drawing of the maps took.
    drawn_in: std::cell::Cell<Duration>,
}

impl Shadows {
    /// The maps `plan` asks for, not yet drawn; refused where they need more layers than a
    /// texture of this device holds.
    fn new(context: &GpuContext, plan: ShadowPlan) -> Result<Shadows> {
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
                        entries: &[buffer_entry(0, &uniforms)],
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
    fn draw(&self, context: &GpuContext, meshes: [&Option<MainMesh>; 2]) -> Result<()> {
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
        label: Some("shadow_vertex"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("shadow_vertex"),
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

/// What the reflection passes share with the main pass.
struct ReflectionSetup<'a> {
    module: &'a wgpu::ShaderModule,
    variant: ShadingVariant,
    shading: Shading<'a>,
    color_view: &'a wgpu::TextureView,
    id_view: &'a wgpu::TextureView,
    eye: glam::Vec3,
    far: f64,
    size: wgpu::Extent3d,
}

/// The reflection passes of the curved mirrors: the Fermat solves (a search per surface of
/// each mirror, all in one dispatch per kind of surface), the cull of the reflected triangles
/// for every search in one dispatch, the reflected triangles' pipeline and its own depth buffer
/// (|P − V|); it draws over the main pass's colour target, the shown triangles of all the
/// searches by one indirect draw. (Searches come in batches where their buffers would outgrow a
/// binding: a solve, a cull and a draw per batch.) The reflected triangles can be replaced
/// ([`Reflections::load`]) where the main pass cuts its curved shapes anew.
struct Reflections {
    fermat: FermatPass,
    /// Per search: 1 + its mirror's index (the id the main pass wrote), and its surface.
    searches: Vec<(u32, MirrorSurface)>,
    /// Per mirror: its material.
    materials: Vec<u32>,
    searches_per_dispatch: Option<usize>,
    /// Whether mirrors that can see themselves draw their own triangles reflected.
    self_reflections: bool,
    pipeline: wgpu::RenderPipeline,
    shared_group: wgpu::BindGroup,
    far: f64,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    id_view: wgpu::TextureView,
    geometry: ReflectedGeometry,
}

/// The reflected triangles' buffers and the searches' batches over them.
#[derive(Default)]
struct ReflectedGeometry {
    batches: Vec<SearchBatch>,
    /// Per batch, what its draw reads.
    batch_groups: Vec<wgpu::BindGroup>,
    vertex_count: u32,
    /// Distinct reflected vertices: one Fermat solve each.
    solve_count: u32,
}

impl Reflections {
    /// `None` where the scene has no curved mirror or nothing to reflect.
    fn new(
        context: &GpuContext,
        setup: &ReflectionSetup,
        reflectors: Vec<Reflector>,
        triangles: &[PreviewVertex],
        options: PreviewOptions,
    ) -> Result<Option<Reflections>> {
        if reflectors.is_empty() || triangles.is_empty() {
            return Ok(None);
        }
        let device = &context.device;
        let kinds: Vec<u32> = reflectors
            .iter()
            .flat_map(|r| r.searches.iter().map(MirrorSurface::kind))
            .collect();
        let searches: Vec<(u32, MirrorSurface)> = reflectors
            .iter()
            .enumerate()
            .flat_map(|(k, r)| r.searches.iter().map(move |&s| (k as u32 + 1, s)))
            .collect();
        let pipeline = render_pipeline(
            device,
            setup.module,
            ("reflected_vertex", "reflected_fragment"),
            &[],
            &[Some(COLOR_FORMAT.into())],
            &setup.variant,
        );
        let shared_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("preview reflections"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &setup.shading.entries(),
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("preview reflections"),
            size: setup.size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let mut reflections = Reflections {
            fermat: FermatPass::new(
                context,
                options.steps,
                &kinds,
                options.self_reflections.is_some(),
            ),
            searches,
            materials: reflectors.iter().map(|r| r.material).collect(),
            searches_per_dispatch: options.searches_per_dispatch,
            self_reflections: options.self_reflections.is_some(),
            pipeline,
            shared_group,
            far: setup.far,
            color_view: setup.color_view.clone(),
            depth_view: depth.create_view(&Default::default()),
            id_view: setup.id_view.clone(),
            geometry: ReflectedGeometry::default(),
        };
        reflections.load(context, triangles, setup.eye)?;
        Ok(Some(reflections))
    }

    /// Reflects `triangles` (not empty) from now on, the eye at `eye`: their buffers, and the
    /// searches' batches over them.
    fn load(
        &mut self,
        context: &GpuContext,
        triangles: &[PreviewVertex],
        eye: glam::Vec3,
    ) -> Result<()> {
        // The draw is indexed: each distinct reflected vertex (position, normal, material) runs
        // the vertex stage once for each search, however many shown triangles share it; and
        // the distinct vertices at one position share one solve.
        let (distinct, vertex_of) = indexed(triangles);
        let (positions, vertex_solves) = shared_positions(&distinct);
        // The mirror each solved vertex lies on: a teapot's own points search on.
        let mut mirrors = vec![0; positions.len()];
        for (&solve, v) in vertex_solves.iter().zip(&distinct) {
            mirrors[solve as usize] = mirrors[solve as usize].max(v.reflector);
        }
        let fermat_vertices =
            crate::preview::reflections::kernel::vertex_buffer(context, &positions, &mirrors)?;
        let solve_buffer =
            context.storage_buffer("vertex solves", bytemuck::cast_slice(&vertex_solves))?;
        let vertices =
            context.storage_buffer("reflected vertices", bytemuck::cast_slice(&distinct))?;
        let table: Vec<[u32; 4]> = vertex_of
            .chunks(3)
            .zip(triangles.chunks(3))
            .map(|(v, t)| [v[0], v[1], v[2], t[0].reflector])
            .collect();
        let table = context.storage_buffer(
            &format!("the {} reflected triangles", table.len()),
            bytemuck::cast_slice(&table),
        )?;
        let triangle_count = triangles.len() as u32 / 3;
        let fitting = crate::preview::reflections::kernel::searches_per_solve(
            context,
            positions.len() as u32,
            triangle_count,
        );
        let per_batch = self
            .searches_per_dispatch
            .map_or(fitting, |n| n.clamp(1, fitting));
        let batches = (0..self.searches.len())
            .step_by(per_batch)
            .map(|first| {
                let range = first..(first + per_batch).min(self.searches.len());
                let uniforms = search_uniforms(
                    &self.searches[range.clone()],
                    eye,
                    positions.len(),
                    self.self_reflections,
                );
                let solve = self.fermat.solve(context, &uniforms, &fermat_vertices)?;
                let cull =
                    self.fermat
                        .cull(context, &solve, (&table, &solve_buffer), triangle_count)?;
                Ok(SearchBatch {
                    solve,
                    cull,
                    searches: range,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let batch_groups = batches
            .iter()
            .map(|batch| {
                let passes: Vec<ReflectorPass> = self.searches[batch.searches.clone()]
                    .iter()
                    .map(|&(id, _)| ReflectorPass {
                        far: self.far as f32,
                        id,
                        material: self.materials[id as usize - 1],
                        solves: positions.len() as u32,
                    })
                    .collect();
                let passes =
                    context.storage_buffer("reflector passes", bytemuck::cast_slice(&passes))?;
                Ok(context
                    .device
                    .create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("reflector batch"),
                        layout: &self.pipeline.get_bind_group_layout(1),
                        entries: &[
                            buffer_entry(0, &vertices),
                            buffer_entry(1, &batch.solve.output),
                            buffer_entry(2, &passes),
                            buffer_entry(4, &solve_buffer),
                            texture_entry(3, &self.id_view),
                        ],
                    }))
            })
            .collect::<Result<Vec<_>>>()?;
        self.geometry = ReflectedGeometry {
            batches,
            batch_groups,
            vertex_count: triangles.len() as u32,
            solve_count: positions.len() as u32,
        };
        Ok(())
    }

    /// Every reflector's solves see the eye at `eye` from the next frame on.
    fn set_eye(&self, context: &GpuContext, eye: glam::Vec3) {
        for batch in &self.geometry.batches {
            let searches = &self.searches[batch.searches.clone()];
            let count = self.geometry.solve_count as usize;
            let reflectors = search_uniforms(searches, eye, count, self.self_reflections);
            context.queue.write_buffer(
                &batch.solve.reflectors,
                0,
                bytemuck::cast_slice(&reflectors),
            );
        }
    }

    /// Records the Fermat solves of every search.
    fn solve(&self, encoder: &mut wgpu::CommandEncoder) {
        for batch in &self.geometry.batches {
            self.fermat.encode(encoder, &batch.solve);
        }
    }

    /// Records the cull of every search's triangles, after their solves.
    fn cull(&self, encoder: &mut wgpu::CommandEncoder) {
        for batch in &self.geometry.batches {
            self.fermat.encode_cull(encoder, &batch.cull);
        }
    }

    /// Records the reflection passes, after the main pass: reflected fragments replace the
    /// colour of the sphere's pixels they land on (the nearest |P − V| last).
    fn draw(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("preview reflections"),
            color_attachments: &[color_attachment(&self.color_view, wgpu::LoadOp::Load)],
            // One depth buffer serves every reflector: a pixel shows one reflector only.
            depth_stencil_attachment: depth_attachment(&self.depth_view, wgpu::StoreOp::Discard),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.shared_group, &[]);
        for (group, batch) in self
            .geometry
            .batch_groups
            .iter()
            .zip(&self.geometry.batches)
        {
            pass.set_bind_group(1, group, &[]);
            pass.set_index_buffer(batch.cull.shown.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed_indirect(&batch.cull.args, 0);
        }
    }
}

/// The stages of a preview frame, each one or more passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// The Fermat kernel's solves (`fermat`).
    Solve,
    /// Their cull (`fermat_cull`).
    Cull,
    /// The main pass: the scene and the id target.
    Main,
    /// The reflection pass.
    Reflect,
}

impl Stage {
    /// A frame's stages, in the order it records them.
    const ALL: [Stage; 4] = [Stage::Solve, Stage::Cull, Stage::Main, Stage::Reflect];
}

/// Time of each stage of a preview frame, milliseconds (`PreviewRenderer::stage_times`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// The Fermat solves.
    pub solve_ms: f64,
    /// The cull of the reflected triangles.
    pub cull_ms: f64,
    /// The main pass.
    pub main_ms: f64,
    /// The reflection pass.
    pub reflect_ms: f64,
}

impl StageTimes {
    fn add(&mut self, stage: Stage, ms: f64) {
        *match stage {
            Stage::Solve => &mut self.solve_ms,
            Stage::Cull => &mut self.cull_ms,
            Stage::Main => &mut self.main_ms,
            Stage::Reflect => &mut self.reflect_ms,
        } += ms;
    }

    /// Each stage's median over `samples` (not empty).
    fn median(samples: &[StageTimes]) -> StageTimes {
        let of = |f: fn(&StageTimes) -> f64| {
            let mut values: Vec<f64> = samples.iter().map(f).collect();
            values.sort_by(f64::total_cmp);
            values[values.len() / 2]
        };
        StageTimes {
            solve_ms: of(|t| t.solve_ms),
            cull_ms: of(|t| t.cull_ms),
            main_ms: of(|t| t.main_ms),
            reflect_ms: of(|t| t.reflect_ms),
        }
    }
}

/// Searches solved and culled together: their rows of the solve's and the cull's buffers.
struct SearchBatch {
    solve: FermatSolve,
    cull: FermatCull,
    /// The searches (indices into `Reflections::searches`), row after row.
    searches: std::ops::Range<usize>,
}

/// The Fermat kernel's searches: each surface of `searches` as a part of its mirror (1 + the
/// mirror's index, with it), seen from `eye`, solving `count` vertices.
fn search_uniforms(
    searches: &[(u32, MirrorSurface)],
    eye: glam::Vec3,
    count: usize,
    self_reflections: bool,
) -> Vec<GpuReflector> {
    searches
        .iter()
        .map(|&(id, search)| GpuReflector {
            mirror: id,
            sees_itself: (self_reflections && search.sees_itself()) as u32,
            ..search.gpu(eye, count as u32)
        })
        .collect()
}

/// The triangles the mirrors reflect, before `ReflectedSet::of` cuts them: the flat ones and
/// the curved shapes as the main pass cuts them (`curved_triangles`), but where mirrors
/// reflect themselves (`own_detail`), the mirrors' own triangles cut for that detail: a
/// convex mirror shows what it reflects smaller than the eye sees it, so a coarser cut than the
/// main pass's serves, at a fraction of the solves.
fn reflected_triangles(
    flat_triangles: &[PreviewVertex],
    curved_triangles: &[PreviewVertex],
    curved: &CurvedShapes,
    own_detail: Option<Detail>,
) -> Vec<PreviewVertex> {
    let Some(detail) = own_detail else {
        return [flat_triangles, curved_triangles].concat();
    };
    let on_mirror = |t: &&[PreviewVertex]| t[0].reflector != 0;
    let others = curved_triangles.chunks_exact(3).filter(|t| !on_mirror(t));
    let mirrors = curved.triangles(&curved.cuts(&detail));
    let mirrors = mirrors.chunks_exact(3).filter(on_mirror);
    let mut out = flat_triangles.to_vec();
    out.extend(others.chain(mirrors).flatten());
    out
}

/// The colour target's pixels, rows padded to wgpu's 256-byte copy alignment on the way.
fn read_back(
    context: &GpuContext,
    color: &wgpu::Texture,
    width: u32,
    height: u32,
) -> Result<Image> {
    let row = (width * 16).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("preview pixels"),
        size: row as u64 * height as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut encoder = context.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        color.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        color.size(),
    );
    context.wait(context.queue.submit([encoder.finish()]))?;
    let bytes: Vec<u8> = context.read_buffer(&buffer)?;
    let pixels = bytes
        .chunks(row as usize)
        .flat_map(|r| {
            let floats: Vec<f32> = bytemuck::pod_collect_to_vec(&r[..width as usize * 16]);
            floats
                .chunks(4)
                .map(|p| glam::Vec3::new(p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// A render pipeline of the preview's module: `entry_points` (vertex, fragment), a depth test
/// against `DEPTH_FORMAT` that keeps the nearest, the bind group layouts derived from the
/// stages.
fn render_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    (vertex, fragment): (&str, &str),
    buffers: &[Option<wgpu::VertexBufferLayout>],
    targets: &[Option<wgpu::ColorTargetState>],
    shading: &ShadingVariant,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(vertex),
        layout: None,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth_test(Default::default()),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &shading.constants(),
                ..Default::default()
            },
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The nearer fragment wins and is written, its depth moved by `bias`.
fn depth_test(bias: wgpu::DepthBiasState) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias,
    })
}

/// A colour attachment loaded as `load` and stored.
fn color_attachment(
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
fn depth_attachment(
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

/// The distinct positions of `vertices` and, per vertex, the index of its position: a vertex
/// shared by the triangles around it (n² pieces of a subdivided triangle share most of theirs),
/// or by faces of other normals or materials, is solved once. Positions are equal when their
/// bits are.
fn shared_positions(vertices: &[PreviewVertex]) -> (Vec<glam::Vec3>, Vec<u32>) {
    let (distinct, solve_of) = distinct_by(vertices, |v| v.position.map(f32::to_bits));
    let positions = distinct
        .iter()
        .map(|v| glam::Vec3::from(v.position))
        .collect();
    (positions, solve_of)
}

/// `triangles`' distinct vertices and, per corner, the index of its vertex: the main pass and
/// the reflection pass draw them indexed, so a corner shared by several triangles (six around a tessellated
/// sphere's or patch's vertex) is shaded once (lavapipe: the teapot's 4,066 triangles 1.55 →
/// 0.73 ms a frame, `BENCHMARKS.md`). Vertices are equal when their bits are.
fn indexed(triangles: &[PreviewVertex]) -> (Vec<PreviewVertex>, Vec<u32>) {
    distinct_by(triangles, |v| bytemuck::cast::<PreviewVertex, [u32; 8]>(*v))
}

/// The first of each class of `items` with equal keys, in order, and per item the index of its
/// class.
fn distinct_by<T: Copy, K: std::hash::Hash + Eq>(
    items: &[T],
    key: impl Fn(&T) -> K,
) -> (Vec<T>, Vec<u32>) {
    let mut index = std::collections::HashMap::new();
    let mut distinct = Vec::new();
    let indices = items
        .iter()
        .map(|item| {
            *index.entry(key(item)).or_insert_with(|| {
                distinct.push(*item);
                distinct.len() as u32 - 1
            })
        })
        .collect();
    (distinct, indices)
}

fn buffer_entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

fn texture_entry(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Indexing loses no corner: the indices give back the triangle list, vertex for vertex,
    /// and each distinct vertex is stored once.
    #[test]
    fn indexing_gives_back_every_corner() {
        let corner = |x: f32, material| PreviewVertex {
            position: [x, 0.0, 1.0],
            material,
            normal: [0.0, 0.0, 1.0],
            reflector: 0,
        };
        // Two triangles sharing an edge; the fourth corner differs from the first only by its
        // material, which keeps it apart.
        let triangles = [
            corner(0.0, 0),
            corner(1.0, 0),
            corner(2.0, 0),
            corner(2.0, 0),
            corner(1.0, 0),
            corner(0.0, 1),
        ];
        let (distinct, indices) = indexed(&triangles);
        assert_eq!(distinct.len(), 4);
        assert_eq!(indices, [0, 1, 2, 2, 1, 3]);
        let rebuilt: Vec<PreviewVertex> = indices.iter().map(|&i| distinct[i as usize]).collect();
        assert_eq!(rebuilt, triangles);
        let (positions, solve_of) = shared_positions(&triangles);
        assert_eq!(positions.len(), 3);
        assert_eq!(solve_of, [0, 1, 2, 2, 1, 0]);
    }
}
