//! The ray tracer's GPU side: wgpu device set-up and the helpers every GPU stage shares; the
//! kernels' registry (`kernels`, which lists the preview's compute kernels too), the render
//! backend (`render`) and the ray queries (`trace`). The raster preview's GPU side is
//! `preview`'s.
//!
//! Errors never panic: wgpu's default uncaptured-error handler panics, so a handler of ours
//! records them, and every wait on the device has a timeout (lavapipe has no watchdog).

pub mod kernels;
pub mod render;
pub mod trace;

pub use render::GpuRenderer;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};

/// Longest wait for one submission (a batch of dispatches) before the render is declared
/// failed: a batch is planned to take seconds on lavapipe, milliseconds on a real GPU.
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

/// One line for `adapter`: name, backend, type, driver, and the limits that bound a scene.
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
pub(crate) fn over_binding_limit(what: &str, bytes: u64, limit: u64) -> Error {
    Error::BindingLimit {
        what: what.to_string(),
        bytes,
        limit,
        advice: "render it with --backend cpu (--backend auto falls back to the CPU by itself) \
                 or make the scene or image smaller"
            .into(),
    }
}

/// wgpu's own Display of a validation error is only "Validation Error"; the description
/// holds the cause.
pub(crate) fn wgpu_error_text(e: &wgpu::Error) -> String {
    match e {
        wgpu::Error::Validation { description, .. } | wgpu::Error::Internal { description, .. } => {
            description.trim().replace('\n', " ")
        }
        other => other.to_string(),
    }
}

/// Where a `map_async` callback leaves its result.
pub(crate) type Mapped = Arc<Mutex<Option<std::result::Result<(), wgpu::BufferAsyncError>>>>;

/// A device ready to run chambre's kernels. Clones share the device: a process makes one and
/// hands clones to its renderers (with NVIDIA's driver 580, a benchmark that made a device per
/// render stopped finding any adapter partway through, and each device costs milliseconds).
#[derive(Clone)]
pub struct GpuContext {
    /// The instance the adapter came from: a window's surface must come from it too.
    pub instance: wgpu::Instance,
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device, its errors caught by our handler rather than wgpu's panicking one.
    pub device: wgpu::Device,
    /// The device's queue, which every submission goes to.
    pub queue: wgpu::Queue,
    /// The adapter as [`describe_adapter`] writes it, for reports and CSV comments.
    pub adapter_description: String,
    /// The adapter's name alone (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
    pub adapter_name: String,
    /// The adapter is a CPU implementation of the API (lavapipe/llvmpipe, SwiftShader).
    pub is_cpu_adapter: bool,
    /// Errors wgpu reported outside an error scope; checked after every dispatch.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl GpuContext {
    /// Opens the high-performance adapter (Vulkan, Metal or DX12) with its largest storage
    /// limits, and timestamp queries where it has them.
    pub fn new() -> Result<GpuContext> {
        let instance = instance();
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| Error::NoAdapter(e.to_string()))?;
        let adapter_limits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            // The render kernel reads nine (`kernels::RENDER`).
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage,
            ..wgpu::Limits::default()
        };
        // Kernel time is measured with timestamps where the adapter offers them.
        let required_features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("chambre"),
            required_limits,
            required_features,
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
            instance,
            device,
            queue,
            adapter_description: describe_adapter(&adapter),
            adapter_name: adapter.get_info().name,
            is_cpu_adapter: adapter.get_info().device_type == wgpu::DeviceType::Cpu,
            adapter,
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

    /// The BVH nodes and primitives every traversal kernel reads, each refused with its size
    /// when it is over the binding limit.
    pub(crate) fn geometry_buffers(
        &self,
        scene: &crate::pack::FlatScene,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer)> {
        let nodes = self.storage_buffer(
            &format!("the scene's {} BVH nodes", scene.nodes.len()),
            bytemuck::cast_slice(&scene.nodes),
        )?;
        let prims = self.storage_buffer(
            &format!(
                "the scene's {} primitives ({} triangles)",
                scene.prims.len(),
                scene.triangle_count
            ),
            bytemuck::cast_slice(&scene.prims),
        )?;
        Ok((nodes, prims))
    }

    /// The compressed wide BVH's nodes and the primitives in its order, refused like
    /// [`GpuContext::geometry_buffers`].
    pub(crate) fn cwbvh_buffers(
        &self,
        cw: &crate::accel::cwbvh::CwGeometry,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer)> {
        let nodes = self.storage_buffer(
            &format!("the scene's {} CWBVH nodes", cw.nodes.len()),
            bytemuck::cast_slice(&cw.nodes),
        )?;
        let prims = self.storage_buffer(
            &format!("the scene's {} primitives", cw.prims.len()),
            bytemuck::cast_slice(&cw.prims),
        )?;
        Ok((nodes, prims))
    }

    /// A buffer for the scene group's bindings a kernel does not read (the ray queries read
    /// its geometry only): uniform and storage, larger than any struct the group binds.
    pub(crate) fn unread_buffer(&self) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("unread"),
            size: 1024,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    }

    /// The status words a kernel reports through (`layout::STATUS_*`), readable back.
    pub(crate) fn status_buffer(&self) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("status"),
            size: crate::layout::STATUS_WORDS as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
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

    /// Whether the device can time kernels (timestamp queries).
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Waits until the `map_async` callback that fills `mapped` has run. A poll that finds the
    /// work done can return while another thread sharing the device (the tests do) is still
    /// running the callbacks it collected, so the signal is awaited, not assumed.
    pub(crate) fn await_mapping(&self, mapped: &Mapped) -> Result<()> {
        let start = std::time::Instant::now();
        loop {
            match mapped.lock().expect("map signal poisoned").take() {
                Some(Ok(())) => return Ok(()),
                Some(Err(e)) => return Err(Error::Gpu(format!("mapping results: {e}"))),
                None => {}
            }
            if start.elapsed() > DISPATCH_TIMEOUT {
                return Err(Error::Gpu("mapping results did not complete".into()));
            }
            self.device
                .poll(wgpu::PollType::Poll)
                .map_err(|e| Error::Gpu(format!("reading back results: {e}")))?;
            std::thread::yield_now();
        }
    }

    /// Copies `buffer`'s values back to the host (it must have COPY_SRC usage).
    pub(crate) fn read_buffer<T: bytemuck::Pod + Send + Sync>(
        &self,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<T>> {
        self.read_range(buffer, 0..buffer.size())
    }

    /// Copies the values in bytes `range` of `buffer` back to the host (it must have COPY_SRC
    /// usage; the range a multiple of 4 bytes, as copies are), through a staging buffer as large
    /// as the range.
    pub(crate) fn read_range<T: bytemuck::Pod + Send + Sync>(
        &self,
        buffer: &wgpu::Buffer,
        range: std::ops::Range<u64>,
    ) -> Result<Vec<T>> {
        let size = range.end - range.start;
        if size == 0 {
            return Ok(Vec::new());
        }
        let staging = self.staging_buffer(size);
        self.read_range_through(buffer, range, &staging)
    }

    /// A mappable buffer of `size` bytes to read results back through.
    pub(crate) fn staging_buffer(&self, size: u64) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        })
    }

    /// [`GpuContext::read_range`] through `staging` (at least as large as the range), which a
    /// caller reading the same range again keeps: a new mappable buffer costs the driver an
    /// allocation and the host a page fault per page on first touch. The values are collected
    /// out of the mapping once, on all cores. (Reading the whole buffer, then casting and
    /// cutting it, copied an image's sums three times: 0.43 s of a 2560x1920 frame's 3.29 s on
    /// lavapipe, and nearly all of it on an H200.)
    pub(crate) fn read_range_through<T: bytemuck::Pod + Send + Sync>(
        &self,
        buffer: &wgpu::Buffer,
        range: std::ops::Range<u64>,
        staging: &wgpu::Buffer,
    ) -> Result<Vec<T>> {
        let size = range.end - range.start;
        if size == 0 {
            return Ok(Vec::new());
        }
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, range.start, staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..size);
        let mapped: Mapped = Arc::new(Mutex::new(None));
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
        self.await_mapping(&mapped)?;
        let values = collect_values(
            &slice
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("mapping results: {e}")))?,
        );
        staging.unmap();
        Ok(values)
    }
}

/// The values in `bytes`, copied out on all cores into aligned storage (the mapping's alignment
/// is not `T`'s to rely on); the new vector's pages are first touched in parallel too.
fn collect_values<T: bytemuck::Pod + Send + Sync>(bytes: &[u8]) -> Vec<T> {
    use rayon::prelude::*;
    const CHUNK: usize = 1 << 16;
    let size = size_of::<T>();
    let mut values = vec![T::zeroed(); bytes.len() / size];
    values
        .par_chunks_mut(CHUNK)
        .zip(bytes.par_chunks(CHUNK * size))
        .for_each(|(out, input)| bytemuck::cast_slice_mut::<T, u8>(out).copy_from_slice(input));
    values
}
