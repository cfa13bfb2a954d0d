//! The GPU render backend: the scene uploaded, the render kernel built for the scene's
//! features, and batches of dispatches queued without waiting.
//!
//! A batch is one submission: its dispatches (whole rows of the image each, one `GpuPass` per
//! dispatch at its own dynamic offset of a uniform buffer), then copies of its status words and
//! timestamps to mappable buffers whose mapping is requested at once. The host waits only in
//! `finish`, for the oldest batch, while the next one is already queued.
//!
//! A dispatch runs the megakernel, or the split kernels one after the other
//! ([`PathKernels`]): the same paths, the same image.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::kernels::{self, Pipeline};
use super::{GpuContext, wgpu_error_text};
use crate::error::{Error, Result};
use crate::layout::{GpuLight, GpuPass, GpuPrimaryHit, WORKGROUP_SIZE};
use crate::pack::FlatScene;
use crate::render::{AccumulationLayout, Backend, DispatchStatus, RayBudgets, plan_passes};

/// How the device runs a dispatch's camera samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathKernels {
    /// One kernel traces each sample's path whole (`render` in wgsl/render.wgsl).
    #[default]
    Megakernel,
    /// The camera rays' closest hits in a kernel of their own (`primary`), stored, then the
    /// paths from them (`render_split`): the traversal of the camera rays, most of a frame's
    /// work, runs apart from the shading's code and registers.
    Split,
}

impl PathKernels {
    /// The kernels a dispatch runs, in order.
    pub fn kernels(self) -> &'static [&'static kernels::Kernel] {
        match self {
            PathKernels::Megakernel => &[&kernels::RENDER],
            PathKernels::Split => &[&kernels::RENDER_PRIMARY, &kernels::RENDER_SPLIT],
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
    _passes: wgpu::Buffer,
    _status: wgpu::Buffer,
    _bind_groups: Vec<wgpu::BindGroup>,
}

/// The scene uploaded and the kernel compiled; runs batches into a device-side accumulation.
pub struct GpuRenderer {
    context: GpuContext,
    /// The kernels a dispatch runs, in order.
    pipelines: Vec<Pipeline>,
    /// The megakernel or the split kernels.
    path_kernels: PathKernels,
    /// Camera samples one dispatch may take (the split kernels' `primary_hits` hold as many).
    samples_per_dispatch: u64,
    /// Every buffer of the bind group but the per-batch `pass_info` and `status`.
    scene_buffers: Vec<(&'static str, wgpu::Buffer)>,
    /// The `layout::FEATURE_*` bits the kernel was built with.
    features: u32,
    /// Where the accumulation buffer keeps what.
    layout: AccumulationLayout,
    /// Bytes between consecutive `GpuPass` of a batch (the dynamic-offset alignment).
    pass_stride: u64,
    in_flight: VecDeque<Batch>,
    kernel_time: Option<Duration>,
    /// Chosen with the adapter ([`RayBudgets::for_adapter`]); the accumulation's scratch half
    /// exists when they split passes into light windows.
    budgets: RayBudgets,
}

impl GpuRenderer {
    /// Uploads `scene` and builds the render kernel specialised to the scene's features.
    pub fn new(context: GpuContext, scene: &FlatScene) -> Result<GpuRenderer> {
        GpuRenderer::with_features(context, scene, scene.features())
    }

    /// Like [`GpuRenderer::new`] with the kernel built for `features` (`layout::FEATURE_*`;
    /// `FEATURES_ALL` is the general kernel), which must include every feature of the scene.
    pub fn with_features(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
    ) -> Result<GpuRenderer> {
        let budgets = RayBudgets::for_adapter(context.is_cpu_adapter);
        GpuRenderer::with_budgets(context, scene, features, budgets)
    }

    /// Like [`GpuRenderer::with_features`], planning renders with `budgets` (`bench frame`
    /// measures dispatch shapes with it).
    pub fn with_budgets(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
        budgets: RayBudgets,
    ) -> Result<GpuRenderer> {
        GpuRenderer::with_kernels(context, scene, features, budgets, PathKernels::Megakernel)
    }

    /// Like [`GpuRenderer::with_budgets`], running each dispatch with `path_kernels`.
    pub fn with_kernels(
        context: GpuContext,
        scene: &FlatScene,
        features: u32,
        budgets: RayBudgets,
        path_kernels: PathKernels,
    ) -> Result<GpuRenderer> {
        let missing = scene.features() & !features;
        if missing != 0 {
            return Err(Error::Gpu(format!(
                "a kernel without features {missing:#x} cannot render this scene, which uses them"
            )));
        }
        let device = &context.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let allowed = device.limits().max_storage_buffers_per_shader_stage;
        for kernel in path_kernels.kernels() {
            let storage_buffers = kernel.storage_buffers();
            if allowed < storage_buffers {
                return Err(Error::Gpu(format!(
                    "the {} kernel reads {storage_buffers} storage buffers; this adapter \
                     allows {allowed} per shader stage (use --backend cpu)",
                    kernel.name
                )));
            }
        }
        let plan = plan_passes(scene, &budgets);
        let samples_per_dispatch = plan.samples_per_dispatch();
        let mut scene_buffers = upload_scene(&context, scene, &plan.layout)?;
        if path_kernels == PathKernels::Split {
            scene_buffers.push((
                "primary_hits",
                primary_hits_buffer(&context, samples_per_dispatch)?,
            ));
        }
        let pipelines = path_kernels
            .kernels()
            .iter()
            .map(|&kernel| kernels::build_pipeline(device, kernel, features))
            .collect();
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the render pipeline: {}",
                wgpu_error_text(&e)
            )));
        }
        let alignment = device.limits().min_uniform_buffer_offset_alignment as u64;
        let pass_stride = (size_of::<GpuPass>() as u64).div_ceil(alignment) * alignment;
        Ok(GpuRenderer {
            kernel_time: context.has_timestamps().then_some(Duration::ZERO),
            context,
            pipelines,
            path_kernels,
            samples_per_dispatch,
            scene_buffers,
            features,
            layout: plan.layout,
            pass_stride,
            in_flight: VecDeque::new(),
            budgets,
        })
    }

    /// The `layout::FEATURE_*` bits the kernel was built with.
    pub fn features(&self) -> u32 {
        self.features
    }

    /// The adapter rendering, as [`super::describe_adapter`] writes it.
    pub fn adapter_description(&self) -> &str {
        &self.context.adapter_description
    }

    fn buffer(&self, name: &str) -> &wgpu::Buffer {
        &self
            .scene_buffers
            .iter()
            .find(|(n, _)| *n == name)
            .expect("uploaded with the scene")
            .1
    }
}

/// The split kernels' store of camera-ray hits: one per camera sample of a dispatch.
fn primary_hits_buffer(context: &GpuContext, samples: u64) -> Result<wgpu::Buffer> {
    let size = samples.max(1) * size_of::<GpuPrimaryHit>() as u64;
    let limit = context.device.limits().max_storage_buffer_binding_size;
    if size > limit {
        let what = format!("the camera-ray hits of a dispatch ({samples} samples)");
        return Err(super::over_binding_limit(&what, size, limit));
    }
    Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("primary hits"),
        size,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    }))
}

/// Uploads what the render kernel reads, named by binding.
fn upload_scene(
    context: &GpuContext,
    scene: &FlatScene,
    layout: &AccumulationLayout,
) -> Result<Vec<(&'static str, wgpu::Buffer)>> {
    let uniform = |label: &str, bytes: &[u8]| context.uniform_buffer(label, bytes);
    let storage = |label: &str, bytes: &[u8]| context.storage_buffer(label, bytes);
    // The kernel traverses the compressed wide BVH, with the primitives in its order; a light's
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
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    Ok(vec![
        (
            "camera",
            uniform("camera", bytemuck::bytes_of(&scene.camera)),
        ),
        ("frame", uniform("frame", bytemuck::bytes_of(&scene.frame))),
        ("cw_nodes", cw_nodes),
        ("prims", prims),
        ("normals", normals),
        (
            "materials",
            storage("materials", bytemuck::cast_slice(&scene.materials))?,
        ),
        ("lights", storage("lights", bytemuck::cast_slice(&lights))?),
        ("accumulation", accumulation),
        (
            "sample_table",
            storage("sample table", bytemuck::cast_slice(&scene.sample_table))?,
        ),
        // Replaced by `set_pixel_list` in an adaptive render.
        ("pixel_list", storage("pixel list", &[0; 4])?),
    ])
}

impl Backend for GpuRenderer {
    fn budgets(&self) -> RayBudgets {
        self.budgets
    }

    fn submit(&mut self, dispatches: &[GpuPass]) -> Result<()> {
        let samples =
            |p: &GpuPass| p.tile_width as u64 * p.tile_height as u64 * p.sample_count as u64;
        let split = self.path_kernels == PathKernels::Split;
        if let Some(pass) = dispatches
            .iter()
            .find(|&p| split && samples(p) > self.samples_per_dispatch)
        {
            return Err(Error::Gpu(format!(
                "a dispatch of {}x{} pixels and {} samples exceeds the {} camera-ray hits \
                 the split kernels store",
                pass.tile_width, pass.tile_height, pass.sample_count, self.samples_per_dispatch
            )));
        }
        let context = &self.context;
        let device = &context.device;
        let stride = self.pass_stride as usize;
        let mut pass_bytes = vec![0u8; stride * dispatches.len()];
        for (i, pass) in dispatches.iter().enumerate() {
            pass_bytes[i * stride..i * stride + size_of::<GpuPass>()]
                .copy_from_slice(bytemuck::bytes_of(pass));
        }
        let passes = context.uniform_buffer("passes", &pass_bytes);
        let status = context.status_buffer();
        let mut buffers: Vec<(&str, &wgpu::Buffer)> =
            self.scene_buffers.iter().map(|(n, b)| (*n, b)).collect();
        buffers.push(("pass_info", &passes));
        buffers.push(("status", &status));
        let bind_groups = self
            .pipelines
            .iter()
            .map(|pipeline| pipeline.bind_group(device, &buffers))
            .collect::<Result<Vec<_>>>()?;
        let queries = context.has_timestamps().then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            })
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let timestamp_writes =
                queries
                    .as_ref()
                    .map(|query_set| wgpu::ComputePassTimestampWrites {
                        query_set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    });
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render batch"),
                timestamp_writes,
            });
            for (i, pass) in dispatches.iter().enumerate() {
                // A split dispatch's kernels run in order: a compute pass orders the writes
                // of one dispatch before the reads of the next.
                for (pipeline, bind_group) in self.pipelines.iter().zip(&bind_groups) {
                    compute.set_pipeline(&pipeline.pipeline);
                    compute.set_bind_group(0, bind_group, &[(i * stride) as u32]);
                    compute.dispatch_workgroups(
                        pass.tile_width.div_ceil(WORKGROUP_SIZE),
                        pass.tile_height.div_ceil(WORKGROUP_SIZE),
                        1,
                    );
                }
            }
        }
        let status_readback = Readback::new(device, "status readback", status.size());
        encoder.copy_buffer_to_buffer(&status, 0, &status_readback.buffer, 0, status.size());
        let timestamps = queries.as_ref().map(|query_set| {
            let resolved = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(query_set, 0..2, &resolved, 0);
            let readback = Readback::new(device, "timestamp readback", 16);
            encoder.copy_buffer_to_buffer(&resolved, 0, &readback.buffer, 0, 16);
            readback
        });
        let submission = context.queue.submit([encoder.finish()]);
        status_readback.request();
        if let Some(t) = &timestamps {
            t.request();
        }
        self.in_flight.push_back(Batch {
            submission,
            status: status_readback,
            timestamps,
            _passes: passes,
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
            let ns = ticks[1].saturating_sub(ticks[0]) as f64 * period_ns;
            *total += Duration::from_nanos(ns as u64);
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

    /// Read after the batches in flight, like the snapshot.
    fn read_slots(&mut self, slots: std::ops::Range<usize>) -> Result<Vec<[f32; 4]>> {
        const SLOT: u64 = std::mem::size_of::<[f32; 4]>() as u64;
        let bytes = slots.start as u64 * SLOT..slots.end as u64 * SLOT;
        self.context.read_range(self.buffer("accumulation"), bytes)
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
            .scene_buffers
            .iter_mut()
            .find(|(name, _)| *name == "pixel_list")
            .expect("uploaded with the scene");
        slot.1 = buffer;
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
