//! The GPU render backend: the scene uploaded, the render kernels built for the scene's
//! features, and batches of dispatches queued without waiting.
//!
//! A batch is one submission: its dispatches (whole rows of the image each, one `GpuPass` per
//! dispatch at its own dynamic offset of a uniform buffer), then copies of its status words and
//! timestamps to mappable buffers whose mapping is requested at once. The host waits only in
//! `finish`, for the oldest batch, while the next one is already queued.
//!
//! A dispatch runs the megakernel, or the wavefront render's kernels ([`PathKernels`]): the
//! same paths with the same random numbers, the same image.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::kernels::{self, Binding, Pipeline, ShaderChecks, slot};
use super::{GpuContext, wgpu_error_text};
use crate::error::{Error, Result};
use crate::layout::{
    GpuHit, GpuLight, GpuPass, GpuPath, GpuPathRay, GpuShadowRay, GpuShadowTerm, GpuWave,
    GpuWaveArgs, INTEGRATOR_PATH, MAX_WORKGROUPS_PER_DIMENSION, TRACE_WORKGROUP_SIZE, WF_COUNTERS,
    WORKGROUP_SIZE,
};
use crate::pack::FlatScene;
use crate::render::{
    AccumulationLayout, Backend, DispatchStatus, RayBound, RayBudgets, RenderPlan, plan_passes,
};

/// How the device runs a dispatch's camera samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathKernels {
    /// One kernel traces each sample's path whole (`render` in wgsl/render.wgsl), one
    /// invocation per pixel.
    #[default]
    Megakernel,
    /// The wavefront render (wgsl/wavefront.wgsl): paths in buffers, one kernel per stage of a
    /// path vertex, each traversal kernel one ray an invocation as the ray queries are.
    Wavefront,
}

impl PathKernels {
    /// The kernels a dispatch may run.
    pub fn kernels(self) -> &'static [&'static kernels::Kernel] {
        match self {
            PathKernels::Megakernel => &[&kernels::RENDER],
            PathKernels::Wavefront => &[
                &kernels::WF_CAMERA,
                &kernels::WF_CLOSEST,
                &kernels::WF_SHADE,
                &kernels::WF_PREPARE,
                &kernels::WF_OCCLUDED,
                &kernels::WF_RESOLVE,
                &kernels::WF_ACCUMULATE,
            ],
        }
    }

    /// The kernels for an adapter. A CPU implementation of the API (lavapipe) runs the
    /// megakernel, which it runs faster: it has few threads to fill, and every kernel boundary
    /// costs it a pass over memory (BENCHMARKS.md). A real GPU runs the wavefront render: on an
    /// H200 the megakernel traced the dragon's camera rays at 220-265 Mrays/s while the ray-query
    /// kernel traced the same rays at ~1,550, and the wavefront's traversal kernels are that one.
    pub fn for_adapter(is_cpu_adapter: bool) -> PathKernels {
        if is_cpu_adapter {
            PathKernels::Megakernel
        } else {
            PathKernels::Wavefront
        }
    }

    /// The kernels for `scene` on an adapter: the path tracer's bounces are the wavefront
    /// render's queue passes (the megakernel renders Whitted's integrator only), else
    /// [`PathKernels::for_adapter`].
    pub fn for_scene(scene: &FlatScene, is_cpu_adapter: bool) -> PathKernels {
        match scene.frame.integrator {
            INTEGRATOR_PATH => PathKernels::Wavefront,
            _ => PathKernels::for_adapter(is_cpu_adapter),
        }
    }

    /// The budgets renders with these kernels are planned with on an adapter whose storage
    /// bindings hold `binding_limit` bytes. The wavefront render traces one ray an invocation, so
    /// no invocation nears a loop limit; a dispatch's paths and shadow rays live in buffers,
    /// so its rays are bounded by what a binding holds (64 bytes a path or shadow ray at most).
    pub fn budgets(self, is_cpu_adapter: bool, binding_limit: u64) -> RayBudgets {
        match self {
            PathKernels::Megakernel => RayBudgets::for_adapter(is_cpu_adapter),
            PathKernels::Wavefront => RayBudgets {
                per_invocation: 1 << 10,
                loop_iterations_per_invocation: f64::INFINITY,
                per_dispatch: (1 << 23).min(binding_limit / 64),
                per_batch: 1 << 25,
                min_invocations_per_dispatch: 0,
            },
        }
    }
}

/// How a GPU renderer is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RendererOptions {
    /// The `layout::FEATURE_*` bits the kernels are built with (`FEATURES_ALL`: the general
    /// code); they must include every feature of the scene.
    pub features: u32,
    /// The megakernel or the wavefront render.
    pub kernels: PathKernels,
    /// The budgets renders are planned with; `None`: the kernels' own on this adapter.
    pub budgets: Option<RayBudgets>,
    /// wgpu's run-time checks the kernels are built with.
    pub checks: ShaderChecks,
}

impl RendererOptions {
    /// The adapter's best for `scene`: code specialised to its features, the kernels the
    /// adapter runs best, their budgets, the default checks.
    pub fn for_scene(scene: &FlatScene, context: &GpuContext) -> RendererOptions {
        RendererOptions {
            features: scene.features(),
            kernels: PathKernels::for_scene(scene, context.is_cpu_adapter),
            budgets: None,
            checks: ShaderChecks::default(),
        }
    }
}

/// A buffer copied back to the host after a submission: the map is requested when the batch
/// is submitted, and read when the batch is finished.
struct Readback {
    buffer: wgpu::Buffer,
    mapped: super::Mapped,
}

impl Readback {
    fn new(device: &wgpu::Device, label: &str, size: u64) -> Readback {
        Readback {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            mapped: Arc::new(Mutex::new(None)),
        }
    }

    /// Asks for the mapping; it completes once the submission that fills the buffer is done.
    fn request(&self) {
        let signal = self.mapped.clone();
        self.buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                *signal.lock().expect("map signal poisoned") = Some(r);
            });
    }

    /// The bytes, once the device has been polled past the submission.
    fn bytes(&self, context: &GpuContext) -> Result<Vec<u8>> {
        context.await_mapping(&self.mapped)?;
        let bytes = self
            .buffer
            .slice(..)
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapping results: {e}")))?
            .to_vec();
        self.buffer.unmap();
        Ok(bytes)
    }
}

/// A batch on the device: what `finish` reads, and the buffers its commands use.
struct Batch {
    submission: wgpu::SubmissionIndex,
    status: Readback,
    timestamps: Option<Readback>,
    /// Each stage's kernel, in order, when its stages are timed one by one.
    stage_kernels: Vec<usize>,
    _uniforms: Vec<wgpu::Buffer>,
    _status: wgpu::Buffer,
    _bind_groups: Vec<wgpu::BindGroup>,
}

/// What the wavefront render sizes its buffers and dispatches with.
struct Wavefront {
    /// Paths the path buffers hold: the most camera samples one dispatch takes.
    path_capacity: u32,
    /// Shadow-ray slots the shadow buffers hold.
    shadow_capacity: u64,
    /// Path vertices a sample may reach (`RayBound::vertices`): the depths the host runs.
    vertices: u32,
    /// What may emit shadow rays at a vertex (`shadow_ray_sources`): whether it is a sampled
    /// light, and its samples.
    lights: Vec<(bool, u32)>,
}

impl Wavefront {
    /// Shadow rays one path vertex may emit in `pass`'s light window: one per punctual light
    /// in the first window, and the area lights' samples in the window.
    fn shadow_stride(&self, pass: &GpuPass) -> u32 {
        let window = crate::integrator::LightWindow::of_pass(pass);
        self.lights
            .iter()
            .map(|&(area, samples)| match area {
                true => window.clip(samples).len() as u32,
                false => window.is_first() as u32,
            })
            .sum()
    }
}

/// The scene uploaded and the kernels compiled; runs batches into a device-side accumulation.
pub struct GpuRenderer {
    context: GpuContext,
    /// The kernels a dispatch runs (`PathKernels::kernels`, in that order).
    pipelines: Vec<Pipeline>,
    /// The megakernel or the wavefront render's kernels.
    path_kernels: PathKernels,
    /// The wavefront render's sizes, when it runs.
    wavefront: Option<Wavefront>,
    /// Every buffer the kernels bind but the per-batch uniforms and `status`: the scene
    /// group's, and the kernels' own that live as long as the renderer.
    buffers: Vec<(Binding, wgpu::Buffer)>,
    /// The scene group, made once and bound by every kernel that reads the scene.
    scene_group: Option<wgpu::BindGroup>,
    /// The `layout::FEATURE_*` bits the kernels were built with.
    features: u32,
    /// Where the accumulation buffer keeps what.
    layout: AccumulationLayout,
    /// Bytes between consecutive `GpuPass` or `GpuWave` of a batch (the dynamic-offset
    /// alignment).
    uniform_stride: u64,
    in_flight: VecDeque<Batch>,
    kernel_time: Option<Duration>,
    /// Per kernel, its device time, when each stage is timed (`profile_stages`).
    stage_times: Option<Vec<StageTime>>,
    /// The mappable buffer the accumulation is read back through, kept between reads.
    staging: Option<wgpu::Buffer>,
    /// Chosen with the adapter and the kernels ([`PathKernels::budgets`]); the accumulation's
    /// scratch half exists when they split passes into light windows.
    budgets: RayBudgets,
}

impl GpuRenderer {
    /// Uploads `scene` and builds the kernels the adapter runs best, specialised to the scene's
    /// features.
    pub fn new(context: GpuContext, scene: &FlatScene) -> Result<GpuRenderer> {
        GpuRenderer::with_features(context, scene, scene.features())
    }

    /// Like [`GpuRenderer::new`] with the kernels built for `features` (`layout::FEATURE_*`;
    /// `FEATURES_ALL` is the general kernel), which must include every feature of the scene.
    pub fn with_features(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
    ) -> Result<GpuRenderer> {
        let kernels = PathKernels::for_scene(scene, context.is_cpu_adapter);
        GpuRenderer::with_kernels(context, scene, features, kernels)
    }

    /// Like [`GpuRenderer::with_features`], running each dispatch with `path_kernels`, planned
    /// with their budgets on this adapter.
    pub fn with_kernels(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
        path_kernels: PathKernels,
    ) -> Result<GpuRenderer> {
        let options = RendererOptions {
            features,
            kernels: path_kernels,
            ..RendererOptions::for_scene(scene, &context)
        };
        GpuRenderer::with_options(context, scene, options)
    }

    /// Like [`GpuRenderer::with_kernels`], planning renders with `budgets` (`bench frame`
    /// measures dispatch shapes with it).
    pub fn with_budgets(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
        path_kernels: PathKernels,
        budgets: RayBudgets,
    ) -> Result<GpuRenderer> {
        let options = RendererOptions {
            features,
            kernels: path_kernels,
            budgets: Some(budgets),
            ..RendererOptions::for_scene(scene, &context)
        };
        GpuRenderer::with_options(context, scene, options)
    }

    /// Uploads `scene` and builds the kernels as `options` say.
    pub fn with_options(
        context: GpuContext,
        scene: &FlatScene,
        options: RendererOptions,
    ) -> Result<GpuRenderer> {
        let RendererOptions {
            features,
            kernels: path_kernels,
            budgets,
            checks,
        } = options;
        let limit = context.device.limits().max_storage_buffer_binding_size;
        let budgets =
            budgets.unwrap_or_else(|| path_kernels.budgets(context.is_cpu_adapter, limit));
        let missing = scene.features() & !features;
        if missing != 0 {
            return Err(Error::Gpu(format!(
                "a kernel without features {missing:#x} cannot render this scene, which uses them"
            )));
        }
        if path_kernels == PathKernels::Megakernel && scene.frame.integrator == INTEGRATOR_PATH {
            return Err(Error::Gpu(
                "the megakernel renders Whitted's integrator only: the path tracer runs as the \
                 wavefront render (--kernels wavefront or auto)"
                    .into(),
            ));
        }
        let device = &context.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let allowed = device.limits().max_storage_buffers_per_shader_stage;
        for kernel in path_kernels.kernels() {
            let storage_buffers = kernel.storage_buffers();
            if allowed < storage_buffers {
                return Err(Error::Gpu(format!(
                    "the {} kernel binds {storage_buffers} storage buffers; this adapter \
                     allows {allowed} per shader stage (use --backend cpu)",
                    kernel.name
                )));
            }
        }
        let plan = plan_passes(scene, &budgets);
        let mut buffers = upload_scene(&context, scene, &plan.layout)?;
        let wavefront = match path_kernels {
            PathKernels::Megakernel => None,
            PathKernels::Wavefront => {
                let wavefront = plan_wavefront(scene, &plan)?;
                buffers.extend(wavefront_buffers(&context, &wavefront, &plan.layout)?);
                Some(wavefront)
            }
        };
        let pipelines: Vec<Pipeline> = path_kernels
            .kernels()
            .iter()
            .map(|&kernel| kernels::build_pipeline_with(device, kernel, features, &[], checks))
            .collect();
        let scene_group = match pipelines.iter().find(|p| p.scene_layout.is_some()) {
            None => None,
            Some(pipeline) => {
                let given: Vec<_> = buffers.iter().map(|(b, buffer)| (*b, buffer)).collect();
                pipeline.scene_bind_group(device, &given)?
            }
        };
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the render pipelines: {}",
                wgpu_error_text(&e)
            )));
        }
        let alignment = device.limits().min_uniform_buffer_offset_alignment as u64;
        let largest = size_of::<GpuPass>().max(size_of::<GpuWave>()) as u64;
        let uniform_stride = largest.div_ceil(alignment) * alignment;
        Ok(GpuRenderer {
            kernel_time: context.has_timestamps().then_some(Duration::ZERO),
            context,
            pipelines,
            path_kernels,
            wavefront,
            buffers,
            scene_group,
            features,
            layout: plan.layout,
            uniform_stride,
            in_flight: VecDeque::new(),
            stage_times: None,
            staging: None,
            budgets,
        })
    }

    /// The `layout::FEATURE_*` bits the kernels were built with.
    pub fn features(&self) -> u32 {
        self.features
    }

    /// The kernels each dispatch runs.
    pub fn path_kernels(&self) -> PathKernels {
        self.path_kernels
    }

    /// The adapter rendering, as [`super::describe_adapter`] writes it.
    pub fn adapter_description(&self) -> &str {
        &self.context.adapter_description
    }

    fn buffer(&self, binding: Binding) -> &wgpu::Buffer {
        &self
            .buffers
            .iter()
            .find(|(b, _)| b.binding == binding.binding)
            .expect("uploaded with the scene")
            .1
    }
}

/// What may emit shadow rays at a path vertex, each as (sampled, samples): the lights sampled
/// at every vertex, and the one a vertex chooses among the rest (`GpuFrame::light_choice_start`)
/// with the most samples any of them has.
fn shadow_ray_sources(scene: &FlatScene) -> Vec<(bool, u32)> {
    let frame = &scene.frame;
    let every_vertex = &scene.lights[..frame.light_choice_start as usize];
    let chosen = frame
        .chooses_lights()
        .then_some((true, frame.light_choice_pairs));
    every_vertex
        .iter()
        .map(|l| (l.is_sampled(), l.samples))
        .chain(chosen)
        .collect()
}

/// The wavefront render's sizes for `plan`: paths for its largest dispatch, shadow-ray slots
/// for its widest light window.
fn plan_wavefront(scene: &FlatScene, plan: &RenderPlan) -> Result<Wavefront> {
    let paths = plan.samples_per_dispatch();
    let path_capacity = u32::try_from(paths)
        .map_err(|_| Error::Gpu(format!("{paths} camera samples in one dispatch")))?;
    let mut wavefront = Wavefront {
        path_capacity,
        shadow_capacity: 0,
        vertices: RayBound::of(scene).vertices as u32,
        lights: shadow_ray_sources(scene),
    };
    let widest = plan
        .dispatches(0)
        .iter()
        .map(|pass| wavefront.shadow_stride(pass))
        .max()
        .unwrap_or(0);
    wavefront.shadow_capacity = paths * widest as u64;
    Ok(wavefront)
}

/// A storage buffer of `count` elements of `T` (one at least: wgpu refuses empty bindings),
/// refused with its size over the binding limit.
fn wave_buffer<T>(
    context: &GpuContext,
    what: &str,
    count: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let size = count.max(1) * size_of::<T>() as u64;
    let limit = context.device.limits().max_storage_buffer_binding_size;
    if size > limit {
        return Err(super::over_binding_limit(what, size, limit));
    }
    Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size,
        usage: wgpu::BufferUsages::STORAGE | usage,
        mapped_at_creation: false,
    }))
}

/// The wavefront render's buffers (zeroed, as wgpu creates them: the counters start at zero).
fn wavefront_buffers(
    context: &GpuContext,
    wave: &Wavefront,
    layout: &AccumulationLayout,
) -> Result<Vec<(Binding, wgpu::Buffer)>> {
    let none = wgpu::BufferUsages::empty();
    let paths = wave.path_capacity as u64;
    let shadows = wave.shadow_capacity;
    let aovs = if layout.aovs { 2 * paths } else { 0 };
    let what = |thing: &str, count: u64| format!("the wavefront render's {count} {thing}");
    Ok(vec![
        (
            slot::WF_RAYS,
            wave_buffer::<GpuPathRay>(context, &what("path rays", paths), paths, none)?,
        ),
        (
            slot::WF_PATHS,
            wave_buffer::<GpuPath>(context, &what("paths", paths), paths, none)?,
        ),
        (
            slot::WF_HITS,
            wave_buffer::<GpuHit>(context, &what("path hits", paths), paths, none)?,
        ),
        (
            slot::WF_QUEUE,
            wave_buffer::<u32>(context, &what("queued paths", 2 * paths), 2 * paths, none)?,
        ),
        (
            slot::WF_COUNTERS,
            wave_buffer::<u32>(context, "counters", WF_COUNTERS as u64, none)?,
        ),
        (
            slot::WF_ARGS,
            wave_buffer::<GpuWaveArgs>(
                context,
                "indirect dispatches",
                wave.vertices as u64 + 1,
                wgpu::BufferUsages::INDIRECT,
            )?,
        ),
        (
            slot::WF_SHADOW_RAYS,
            wave_buffer::<GpuShadowRay>(context, &what("shadow rays", shadows), shadows, none)?,
        ),
        (
            slot::WF_SHADOW_TERMS,
            wave_buffer::<GpuShadowTerm>(context, &what("shadow terms", shadows), shadows, none)?,
        ),
        (
            slot::WF_SHADOW_QUEUE,
            wave_buffer::<u32>(context, &what("queued shadow rays", shadows), shadows, none)?,
        ),
        (
            slot::WF_AOVS,
            wave_buffer::<[f32; 4]>(context, &what("first hits", aovs), aovs, none)?,
        ),
    ])
}

/// Uploads what the render kernels read, by binding.
fn upload_scene(
    context: &GpuContext,
    scene: &FlatScene,
    layout: &AccumulationLayout,
) -> Result<Vec<(Binding, wgpu::Buffer)>> {
    let uniform = |label: &str, bytes: &[u8]| context.uniform_buffer(label, bytes);
    let storage = |label: &str, bytes: &[u8]| context.storage_buffer(label, bytes);
    // The kernels traverse the compressed wide BVH, with the primitives in its order; a light's
    // primitive index follows them.
    let cw = scene.cwbvh().map_err(Error::Gpu)?;
    let (cw_nodes, prims) = context.cwbvh_buffers(cw)?;
    let lights: Vec<GpuLight> = scene
        .lights
        .iter()
        .map(|l| GpuLight {
            prim: cw.new_index(l.prim),
            ..*l
        })
        .collect();
    let normals = storage(
        &format!(
            "the vertex normals of {} smooth triangles",
            scene.normals.len()
        ),
        bytemuck::cast_slice(&scene.normals),
    )?;
    let accumulation_size = layout.len() as u64 * 16;
    let limit = context.device.limits().max_storage_buffer_binding_size;
    if accumulation_size > limit {
        let what = format!(
            "the {}x{} image's accumulation buffer",
            scene.frame.width, scene.frame.height
        );
        return Err(super::over_binding_limit(&what, accumulation_size, limit));
    }
    let accumulation = context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("accumulation"),
        size: accumulation_size,
        // Read back (COPY_SRC), cleared before each render (COPY_DST).
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    Ok(vec![
        (
            slot::CAMERA,
            uniform("camera", bytemuck::bytes_of(&scene.camera)),
        ),
        (
            slot::FRAME,
            uniform("frame", bytemuck::bytes_of(&scene.frame)),
        ),
        (slot::CW_NODES, cw_nodes),
        (slot::PRIMS, prims),
        (slot::NORMALS, normals),
        (
            slot::MATERIALS,
            storage("materials", bytemuck::cast_slice(&scene.materials))?,
        ),
        (
            slot::LIGHTS,
            storage("lights", bytemuck::cast_slice(&lights))?,
        ),
        (slot::ACCUMULATION, accumulation),
        (
            slot::SAMPLE_TABLE,
            storage("sample table", bytemuck::cast_slice(&scene.sample_table))?,
        ),
        // Replaced by `set_pixel_list` in an adaptive render.
        (slot::PIXEL_LIST, storage("pixel list", &[0; 4])?),
        (
            slot::TEXCOORDS,
            storage(
                &format!(
                    "the texture coordinates of {} triangles",
                    scene.texcoords.len()
                ),
                bytemuck::cast_slice(&scene.texcoords),
            )?,
        ),
        (
            slot::TEXTURES,
            storage("textures", bytemuck::cast_slice(&scene.textures))?,
        ),
        (
            slot::TEXELS,
            storage(
                &format!("the texels of {} textures", scene.textures.len()),
                bytemuck::cast_slice(&scene.texels),
            )?,
        ),
        (
            slot::ENVIRONMENT,
            storage(
                "the environment map (lights[].file) with its sampling distribution",
                bytemuck::cast_slice(&scene.environment),
            )?,
        ),
    ])
}

/// The workgroups of a 1-D grid over `count` invocations, in rows of at most
/// `MAX_WORKGROUPS_PER_DIMENSION` (`wave_groups` in wgsl/wavefront.wgsl).
fn wave_grid(count: u32) -> (u32, u32) {
    let groups = count.div_ceil(TRACE_WORKGROUP_SIZE);
    (
        groups.min(MAX_WORKGROUPS_PER_DIMENSION),
        groups.div_ceil(MAX_WORKGROUPS_PER_DIMENSION),
    )
}

/// A uniform buffer of `values`, each at its own multiple of `stride` bytes.
fn uniform_array<T: bytemuck::Pod>(
    context: &GpuContext,
    label: &str,
    values: &[T],
    stride: u64,
) -> wgpu::Buffer {
    let stride = stride as usize;
    let mut bytes = vec![0u8; stride * values.len().max(1)];
    for (i, value) in values.iter().enumerate() {
        bytes[i * stride..i * stride + size_of::<T>()].copy_from_slice(bytemuck::bytes_of(value));
    }
    context.uniform_buffer(label, &bytes)
}

/// How a stage dispatch is sized: the megakernel's tiles of pixels, a grid over a count the host
/// knows, or the paths or shadow rays a depth queued, read from the indirect arguments.
#[derive(Clone, Copy, Debug)]
enum Grid {
    Tiles(u32, u32),
    Direct(u32),
    QueuedPaths(u32),
    QueuedShadows(u32),
}

/// One kernel dispatch of a batch: the kernel (its index in `PathKernels::kernels`), the
/// batch's dispatch (`GpuPass`) it works on, the path depth (its `GpuWave`), and its grid.
#[derive(Clone, Copy, Debug)]
struct Stage {
    kernel: usize,
    dispatch: usize,
    depth: u32,
    grid: Grid,
}

/// The stages of one wavefront dispatch, in order.
fn wavefront_stages(wave: &Wavefront, dispatch: usize, pass: &GpuPass) -> Vec<Stage> {
    const CAMERA: usize = 0;
    const CLOSEST: usize = 1;
    const SHADE: usize = 2;
    const PREPARE: usize = 3;
    const OCCLUDED: usize = 4;
    const RESOLVE: usize = 5;
    const ACCUMULATE: usize = 6;
    let stage = |kernel, depth, grid| Stage {
        kernel,
        dispatch,
        depth,
        grid,
    };
    let entries = pass.tile_width * pass.tile_height;
    let paths = entries * pass.sample_count;
    let shadows = wave.shadow_stride(pass) > 0;
    let mut stages = vec![stage(CAMERA, 0, Grid::Direct(paths))];
    for depth in 0..wave.vertices {
        let grid = match depth {
            0 => Grid::Direct(paths),
            _ => Grid::QueuedPaths(depth),
        };
        stages.push(stage(CLOSEST, depth, grid));
        stages.push(stage(SHADE, depth, grid));
        // The next depth's queue, or this depth's shadow rays, need their counts.
        if shadows || depth + 1 < wave.vertices {
            stages.push(stage(PREPARE, depth, Grid::Direct(1)));
        }
        if shadows {
            stages.push(stage(OCCLUDED, depth, Grid::QueuedShadows(depth)));
            stages.push(stage(RESOLVE, depth, grid));
        }
    }
    stages.push(stage(ACCUMULATE, 0, Grid::Direct(entries)));
    stages
}

/// Timestamp queries a query set may hold (wgpu's limit): a profiled batch times at most half
/// as many stages.
const MAX_QUERIES: usize = 4096;

impl GpuRenderer {
    /// The stages of `dispatches`, in order.
    fn batch_stages(&self, dispatches: &[GpuPass]) -> Vec<Stage> {
        match &self.wavefront {
            None => dispatches
                .iter()
                .enumerate()
                .map(|(dispatch, pass)| Stage {
                    kernel: 0,
                    dispatch,
                    depth: 0,
                    grid: Grid::Tiles(pass.tile_width, pass.tile_height),
                })
                .collect(),
            Some(wave) => dispatches
                .iter()
                .enumerate()
                .flat_map(|(i, pass)| wavefront_stages(wave, i, pass))
                .collect(),
        }
    }

    /// Records one stage; `GpuWave` `dispatch * vertices + depth` of the batch's wave array is
    /// its dispatch's at its depth.
    fn record_stage(
        &self,
        compute: &mut wgpu::ComputePass<'_>,
        stage: Stage,
        bind_groups: &[wgpu::BindGroup],
    ) {
        let pipeline = &self.pipelines[stage.kernel];
        let vertices = self.wavefront.as_ref().map_or(1, |w| w.vertices) as u64;
        let wave_index = stage.dispatch as u64 * vertices + stage.depth as u64;
        let offsets = pipeline.dynamic_offsets(|b| {
            let index = match b.binding == slot::WAVE.binding {
                true => wave_index,
                false => stage.dispatch as u64,
            };
            (index * self.uniform_stride) as u32
        });
        compute.set_pipeline(&pipeline.pipeline);
        let scene = self.scene_group.as_ref();
        pipeline.set_bind_groups(compute, scene, &bind_groups[stage.kernel], &offsets);
        let args_size = size_of::<GpuWaveArgs>() as u64;
        match stage.grid {
            Grid::Tiles(width, height) => compute.dispatch_workgroups(
                width.div_ceil(WORKGROUP_SIZE),
                height.div_ceil(WORKGROUP_SIZE),
                1,
            ),
            Grid::Direct(count) => {
                let (x, y) = wave_grid(count);
                compute.dispatch_workgroups(x, y, 1);
            }
            Grid::QueuedPaths(depth) => {
                let args = self.buffer(slot::WF_ARGS);
                compute.dispatch_workgroups_indirect(args, depth as u64 * args_size);
            }
            Grid::QueuedShadows(depth) => {
                let args = self.buffer(slot::WF_ARGS);
                compute.dispatch_workgroups_indirect(args, depth as u64 * args_size + 16);
            }
        }
    }

    /// The batch's `GpuWave`s: one per dispatch and depth.
    fn waves(&self, dispatches: &[GpuPass]) -> Result<Vec<GpuWave>> {
        let Some(wave) = &self.wavefront else {
            return Ok(Vec::new());
        };
        let mut waves = Vec::with_capacity(dispatches.len() * wave.vertices as usize);
        for pass in dispatches {
            let paths = pass.tile_width as u64 * pass.tile_height as u64 * pass.sample_count as u64;
            let shadow_stride = wave.shadow_stride(pass);
            if paths > wave.path_capacity as u64
                || paths * shadow_stride as u64 > wave.shadow_capacity
            {
                return Err(Error::Gpu(format!(
                    "a dispatch of {paths} paths with {shadow_stride} shadow rays each exceeds \
                     the wavefront render's {} paths and {} shadow rays",
                    wave.path_capacity, wave.shadow_capacity
                )));
            }
            waves.extend((0..wave.vertices).map(|depth| GpuWave {
                depth,
                shadow_stride,
                path_capacity: wave.path_capacity,
                _pad0: 0,
            }));
        }
        Ok(waves)
    }

    /// Times each kernel apart from the next (`stage_times`), on adapters with timestamps:
    /// every stage then runs in a compute pass of its own, which costs a little time itself.
    pub fn profile_stages(&mut self) {
        if self.context.has_timestamps() {
            self.stage_times = Some(vec![StageTime::default(); self.pipelines.len()]);
        }
    }

    /// Device time of each kernel over the finished batches, when `profile_stages` was asked
    /// for and the adapter has timestamps: (kernel name, its stages' time).
    pub fn stage_times(&self) -> Option<Vec<(&'static str, StageTime)>> {
        let times = self.stage_times.as_ref()?;
        Some(
            self.pipelines
                .iter()
                .zip(times)
                .map(|(pipeline, time)| (pipeline.kernel.name, *time))
                .collect(),
        )
    }
}

/// A kernel's share of the device time of a profiled render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTime {
    /// Its stages' time, summed.
    pub time: Duration,
    /// Its stages timed.
    pub stages: u64,
    /// Its stages recorded past the query set's room, so not timed.
    pub untimed: u64,
}

impl Backend for GpuRenderer {
    fn budgets(&self) -> RayBudgets {
        self.budgets
    }

    fn submit(&mut self, dispatches: &[GpuPass]) -> Result<()> {
        let context = &self.context;
        let device = &context.device;
        let waves = self.waves(dispatches)?;
        let passes = uniform_array(context, "passes", dispatches, self.uniform_stride);
        let wave_array = uniform_array(context, "waves", &waves, self.uniform_stride);
        let status = context.status_buffer();
        let mut buffers: Vec<(Binding, &wgpu::Buffer)> = self
            .buffers
            .iter()
            .map(|(b, buffer)| (*b, buffer))
            .collect();
        buffers.push((slot::PASS_INFO, &passes));
        buffers.push((slot::WAVE, &wave_array));
        if self.wavefront.is_some() {
            // Read by the stages the indirect arguments size, written by `wf_prepare`.
            buffers.push((slot::WF_ARGS_IN, self.buffer(slot::WF_ARGS)));
        }
        buffers.push((slot::STATUS, &status));
        let bind_groups = self
            .pipelines
            .iter()
            .map(|pipeline| pipeline.bind_group(device, &buffers))
            .collect::<Result<Vec<_>>>()?;
        let stages = self.batch_stages(dispatches);
        // Profiled: a pair of timestamps per stage (as many as fit); else one pair for all.
        let timed = match (&self.stage_times, context.has_timestamps()) {
            (_, false) => 0,
            (Some(_), true) => stages.len().min(MAX_QUERIES / 2),
            (None, true) => 1,
        };
        let queries = (timed > 0).then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * timed as u32,
            })
        });
        let timestamp_writes = |pair: usize| {
            queries.as_ref().and_then(|query_set| {
                (pair < timed).then(|| wgpu::ComputePassTimestampWrites {
                    query_set,
                    beginning_of_pass_write_index: Some(2 * pair as u32),
                    end_of_pass_write_index: Some(2 * pair as u32 + 1),
                })
            })
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        if self.stage_times.is_some() {
            for (i, &stage) in stages.iter().enumerate() {
                let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(self.pipelines[stage.kernel].kernel.name),
                    timestamp_writes: timestamp_writes(i),
                });
                self.record_stage(&mut compute, stage, &bind_groups);
            }
        } else {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render batch"),
                timestamp_writes: timestamp_writes(0),
            });
            // A compute pass orders each dispatch's writes before the next dispatch's reads.
            for &stage in &stages {
                self.record_stage(&mut compute, stage, &bind_groups);
            }
        }
        let status_readback = Readback::new(device, "status readback", status.size());
        encoder.copy_buffer_to_buffer(&status, 0, &status_readback.buffer, 0, status.size());
        let timestamps = queries.as_ref().map(|query_set| {
            let size = 16 * timed as u64;
            let resolved = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(query_set, 0..2 * timed as u32, &resolved, 0);
            let readback = Readback::new(device, "timestamp readback", size);
            encoder.copy_buffer_to_buffer(&resolved, 0, &readback.buffer, 0, size);
            readback
        });
        let submission = context.queue.submit([encoder.finish()]);
        status_readback.request();
        if let Some(t) = &timestamps {
            t.request();
        }
        let stage_kernels = match self.stage_times {
            Some(_) => stages.iter().map(|stage| stage.kernel).collect(),
            None => Vec::new(),
        };
        self.in_flight.push_back(Batch {
            submission,
            status: status_readback,
            timestamps,
            stage_kernels,
            _uniforms: vec![passes, wave_array],
            _status: status,
            _bind_groups: bind_groups,
        });
        Ok(())
    }

    fn finish(&mut self) -> Result<DispatchStatus> {
        let Some(batch) = self.in_flight.pop_front() else {
            return Ok(DispatchStatus::default());
        };
        self.context.wait(batch.submission)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&batch.status.bytes(&self.context)?);
        if let (Some(readback), Some(total)) = (&batch.timestamps, &mut self.kernel_time) {
            let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&readback.bytes(&self.context)?);
            let period_ns = self.context.queue.get_timestamp_period() as f64;
            let times: Vec<Duration> = ticks
                .chunks_exact(2)
                .map(|pair| {
                    Duration::from_nanos(
                        (pair[1].saturating_sub(pair[0]) as f64 * period_ns) as u64,
                    )
                })
                .collect();
            *total += times.iter().sum::<Duration>();
            if let Some(stage_times) = &mut self.stage_times {
                for (i, &kernel) in batch.stage_kernels.iter().enumerate() {
                    match times.get(i) {
                        Some(&time) => {
                            stage_times[kernel].time += time;
                            stage_times[kernel].stages += 1;
                        }
                        None => stage_times[kernel].untimed += 1,
                    }
                }
            }
        }
        Ok(DispatchStatus::from_words(&words))
    }

    fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>> {
        let halves = self.read_slots(0..self.layout.image_len())?;
        Ok(self.layout.image_sums(halves))
    }

    /// Read after the batches in flight, like the snapshot, through a staging buffer kept for
    /// the next read (snapshots, adaptive decisions and the image read the same slots again).
    fn read_slots(&mut self, slots: std::ops::Range<usize>) -> Result<Vec<[f32; 4]>> {
        const SLOT: u64 = std::mem::size_of::<[f32; 4]>() as u64;
        let bytes = slots.start as u64 * SLOT..slots.end as u64 * SLOT;
        let size = bytes.end - bytes.start;
        if self.staging.as_ref().is_none_or(|s| s.size() < size) {
            self.staging = Some(self.context.staging_buffer(size));
        }
        let staging = self.staging.as_ref().expect("made above");
        self.context
            .read_range_through(self.buffer(slot::ACCUMULATION), bytes, staging)
    }

    /// A new buffer: the batches in flight keep the one they were bound with.
    fn set_pixel_list(&mut self, pixels: &[u32]) -> Result<()> {
        let label = format!("the {} pixels of an adaptive pass", pixels.len());
        let bytes: &[u8] = if pixels.is_empty() {
            &[0; 4]
        } else {
            bytemuck::cast_slice(pixels)
        };
        let buffer = self.context.storage_buffer(&label, bytes)?;
        let slot = self
            .buffers
            .iter_mut()
            .find(|(b, _)| b.binding == slot::PIXEL_LIST.binding)
            .expect("uploaded with the scene");
        slot.1 = buffer;
        Ok(())
    }

    /// Queued after the batches in flight: a renderer renders the scene again from zero, its
    /// kernels' times too.
    fn clear(&mut self) -> Result<()> {
        if let Some(time) = &mut self.kernel_time {
            *time = Duration::ZERO;
        }
        if let Some(times) = &mut self.stage_times {
            times.fill(StageTime::default());
        }
        let mut encoder = self
            .context
            .device
            .create_command_encoder(&Default::default());
        encoder.clear_buffer(self.buffer(slot::ACCUMULATION), 0, None);
        self.context.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The copy is queued after the batches in flight, so it holds them too.
    fn snapshot(&mut self) -> Result<Vec<[f32; 4]>> {
        self.accumulation()
    }

    fn kernel_time(&self) -> Option<Duration> {
        self.kernel_time
    }
}
