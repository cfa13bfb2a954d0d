//! The GPU path: wgpu device set-up, scene upload, and the tiled render dispatches.
//!
//! Errors never panic: wgpu's default uncaptured-error handler panics, so a handler of ours
//! records them, and every wait on the device has a timeout (lavapipe has no watchdog).

pub mod kernels;
pub mod trace;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use wgpu::util::DeviceExt;

use crate::accel::FlatScene;
use crate::error::{Error, Result};
use crate::layout::{BVH_STACK_SIZE, GpuPass, STATUS_WORDS, WORKGROUP_SIZE};
use crate::render::{Backend, TILE, TileStatus, plan_passes};

/// Longest wait for one dispatch before the render is declared failed.
const DISPATCH_TIMEOUT: Duration = Duration::from_secs(120);

fn instance() -> wgpu::Instance {
    let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    // Vulkan, Metal, DX12: the GL backend's compute support is not one we test.
    descriptor.backends = wgpu::Backends::PRIMARY;
    wgpu::Instance::new(descriptor)
}

/// One line per adapter: name, backend, type, driver, and the limits that bound a scene.
pub fn describe_adapters() -> Vec<String> {
    let adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::PRIMARY));
    adapters.iter().map(describe_adapter).collect()
}

pub fn describe_adapter(adapter: &wgpu::Adapter) -> String {
    let info = adapter.get_info();
    let limits = adapter.limits();
    format!(
        "{} ({:?}, {:?}; driver {} {}): max storage binding {} MiB, max buffer {} MiB, \
         {} storage buffers per stage, {} invocations per workgroup",
        info.name,
        info.backend,
        info.device_type,
        info.driver,
        info.driver_info,
        limits.max_storage_buffer_binding_size >> 20,
        limits.max_buffer_size >> 20,
        limits.max_storage_buffers_per_shader_stage,
        limits.max_compute_invocations_per_workgroup,
    )
}

/// The refusal of an array larger than one storage binding may hold on this adapter: what,
/// how large, the limit, and what to do.
fn over_binding_limit(what: &str, bytes: u64, limit: u64) -> Error {
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    Error::Gpu(format!(
        "{what} takes {:.1} MiB, more than this adapter's largest storage binding \
         (max_storage_buffer_binding_size = {:.1} MiB); render it with --backend cpu \
         (--backend auto falls back to the CPU by itself) or make the scene or image smaller",
        mib(bytes),
        mib(limit)
    ))
}

/// wgpu's own Display of a validation error is only "Validation Error"; the description
/// holds the cause.
fn wgpu_error_text(e: &wgpu::Error) -> String {
    match e {
        wgpu::Error::Validation { description, .. } | wgpu::Error::Internal { description, .. } => {
            description.trim().replace('\n', " ")
        }
        other => other.to_string(),
    }
}

/// A device ready to run chambre's kernels.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_description: String,
    /// The adapter's name alone (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
    pub adapter_name: String,
    /// Errors wgpu reported outside an error scope; checked after every dispatch.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl GpuContext {
    pub fn new() -> Result<GpuContext> {
        let adapter =
            pollster::block_on(instance().request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            }))
            .map_err(|e| Error::NoAdapter(e.to_string()))?;
        let adapter_limits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("chambre"),
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| Error::NoAdapter(format!("{}: {e}", adapter.get_info().name)))?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e.to_string());
            }
        }));
        Ok(GpuContext {
            device,
            queue,
            adapter_description: describe_adapter(&adapter),
            adapter_name: adapter.get_info().name,
            uncaptured,
        })
    }

    /// A uniform buffer holding `bytes`, writable later.
    pub(crate) fn uniform_buffer(&self, label: &str, bytes: &[u8]) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// A read-only storage buffer holding `bytes`, or the refusal of an array larger than one
    /// binding may hold on this adapter (`label` says what the array is).
    pub(crate) fn storage_buffer(&self, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer> {
        let limit = self.device.limits().max_storage_buffer_binding_size;
        if bytes.len() as u64 > limit {
            return Err(over_binding_limit(label, bytes.len() as u64, limit));
        }
        // wgpu refuses empty bindings: an empty array still gets one (unread) element.
        let padded;
        let contents = if bytes.is_empty() {
            padded = vec![0u8; 64];
            &padded[..]
        } else {
            bytes
        };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    fn take_uncaptured(&self) -> Result<()> {
        let errors = std::mem::take(&mut *self.uncaptured.lock().expect("error sink poisoned"));
        match errors.is_empty() {
            true => Ok(()),
            false => Err(Error::Gpu(errors.join("; "))),
        }
    }

    pub(crate) fn wait(&self, submission: wgpu::SubmissionIndex) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(submission),
                timeout: Some(DISPATCH_TIMEOUT),
            })
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        self.take_uncaptured()
    }

    /// Copies `buffer` back to the host (it must have COPY_SRC usage).
    pub(crate) fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: buffer.size(),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let mapped = Arc::new(Mutex::new(None));
        let signal = mapped.clone();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            *signal.lock().expect("map signal poisoned") = Some(r);
        });
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(DISPATCH_TIMEOUT),
            })
            .map_err(|e| Error::Gpu(format!("reading back results: {e}")))?;
        match mapped.lock().expect("map signal poisoned").take() {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(Error::Gpu(format!("mapping results: {e}"))),
            None => return Err(Error::Gpu("mapping results did not complete".into())),
        }
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapping results: {e}")))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

/// The scene uploaded and the kernel compiled; renders tiles into a device-side accumulation.
pub struct GpuRenderer {
    context: GpuContext,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// The `layout::FEATURE_*` bits the kernel was built with.
    features: u32,
    pass_buffer: wgpu::Buffer,
    accumulation: wgpu::Buffer,
    /// Pixels of the image: the accumulation buffer's first half when it holds a scratch half.
    pixel_count: usize,
    status: wgpu::Buffer,
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
        let missing = scene.features() & !features;
        if missing != 0 {
            return Err(Error::Gpu(format!(
                "a kernel without features {missing:#x} cannot render this scene, which uses them"
            )));
        }
        if scene.bvh_depth > BVH_STACK_SIZE as usize {
            return Err(Error::Gpu(format!(
                "the BVH is {} levels deep, more than the kernel's traversal stack of {}; \
                 render this scene with --backend cpu",
                scene.bvh_depth, BVH_STACK_SIZE
            )));
        }
        let device = &context.device;
        let limit = device.limits().max_storage_buffer_binding_size;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let uniform = |label: &str, bytes: &[u8]| context.uniform_buffer(label, bytes);
        let storage = |label: &str, bytes: &[u8]| context.storage_buffer(label, bytes);
        let camera = uniform("camera", bytemuck::bytes_of(&scene.camera));
        let frame = uniform("frame", bytemuck::bytes_of(&scene.frame));
        let pass_buffer = uniform("pass", bytemuck::bytes_of(&GpuPass::default()));
        let nodes = storage(
            &format!("the scene's {} BVH nodes", scene.nodes.len()),
            bytemuck::cast_slice(&scene.nodes),
        )?;
        let prims = storage(
            &format!(
                "the scene's {} primitives ({} triangles)",
                scene.prims.len(),
                scene.triangle_count
            ),
            bytemuck::cast_slice(&scene.prims),
        )?;
        let normals = storage(
            &format!(
                "the vertex normals of {} smooth triangles",
                scene.normals.len()
            ),
            bytemuck::cast_slice(&scene.normals),
        )?;
        let materials = storage("materials", bytemuck::cast_slice(&scene.materials))?;
        let lights = storage("lights", bytemuck::cast_slice(&scene.lights))?;
        let sample_table = storage("sample table", bytemuck::cast_slice(&scene.sample_table))?;
        let pixel_count = scene.frame.width as u64 * scene.frame.height as u64;
        // A pass split into light windows keeps its partial sums in a second half (scratch)
        // until it commits (see render.wgsl).
        let split_passes = plan_passes(scene, TILE * TILE).light_windows.len() > 1;
        let accumulation_size = pixel_count * 16 * if split_passes { 2 } else { 1 };
        if accumulation_size > limit {
            let what = format!(
                "the {}x{} image's accumulation buffer",
                scene.frame.width, scene.frame.height
            );
            return Err(over_binding_limit(&what, accumulation_size, limit));
        }
        let accumulation = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accumulation"),
            size: accumulation_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let status = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("status"),
            size: STATUS_WORDS as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pipeline = kernels::build_pipeline(device, &kernels::RENDER, features);
        let bind_group = pipeline.bind_group(
            device,
            &[
                ("camera", &camera),
                ("frame", &frame),
                ("pass_info", &pass_buffer),
                ("nodes", &nodes),
                ("prims", &prims),
                ("normals", &normals),
                ("materials", &materials),
                ("lights", &lights),
                ("accumulation", &accumulation),
                ("status", &status),
                ("sample_table", &sample_table),
            ],
        )?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the render pipeline: {}",
                wgpu_error_text(&e)
            )));
        }
        Ok(GpuRenderer {
            context,
            pipeline: pipeline.pipeline,
            bind_group,
            features,
            pass_buffer,
            accumulation,
            pixel_count: pixel_count as usize,
            status,
        })
    }

    /// The `layout::FEATURE_*` bits the kernel was built with.
    pub fn features(&self) -> u32 {
        self.features
    }

    pub fn adapter_description(&self) -> &str {
        &self.context.adapter_description
    }
}

impl Backend for GpuRenderer {
    fn render_tile(&mut self, pass: GpuPass) -> Result<TileStatus> {
        let context = &self.context;
        context
            .queue
            .write_buffer(&self.pass_buffer, 0, bytemuck::bytes_of(&pass));
        let mut encoder = context.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.status, 0, None);
        {
            let mut compute = encoder.begin_compute_pass(&Default::default());
            compute.set_pipeline(&self.pipeline);
            compute.set_bind_group(0, &self.bind_group, &[]);
            compute.dispatch_workgroups(
                pass.tile_width.div_ceil(WORKGROUP_SIZE),
                pass.tile_height.div_ceil(WORKGROUP_SIZE),
                1,
            );
        }
        let submission = context.queue.submit([encoder.finish()]);
        context.wait(submission)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&context.read_buffer(&self.status)?);
        Ok(TileStatus::from_words(&words))
    }

    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>> {
        let bytes = self.context.read_buffer(&self.accumulation)?;
        let mut sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
        sums.truncate(self.pixel_count);
        Ok(sums)
    }
}
