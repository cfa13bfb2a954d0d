//! Ray queries on the GPU for the ray benchmark: a buffer of rays in, a distance per ray out,
//! through the `trace_closest` and `trace_any` kernels of the registry (BVH2), or their
//! `_cw` twins over the compressed wide BVH.
//!
//! Rays are uploaded once, in chunks that each fit one storage binding, and every chunk's
//! dispatch goes into one submission: the timed part is the device's work and one wait.

use std::time::{Duration, Instant};

use super::GpuContext;
use super::kernels::{self, Binding, Pipeline, SCENE_BINDINGS, ShaderChecks, slot};
use crate::accel::cwbvh::CwGeometry;
use crate::accel::ray::{Query, RaySet};
use crate::error::{Error, Result};
use crate::layout::{GpuPass, GpuRay, LOOP_CHECK_ITERATIONS, T_FAR, TRACE_WORKGROUP_SIZE};
use crate::pack::FlatScene;
use crate::render::{DispatchStatus, describe_status_flags};

/// Rays per chunk: 64 MiB of rays, half of lavapipe's largest binding, and
/// 32,768 workgroups, half of the largest dispatch.
const RAYS_PER_CHUNK: usize = 1 << 21;

struct Chunk {
    rays: usize,
    distances: wgpu::Buffer,
    closest: wgpu::BindGroup,
    any: wgpu::BindGroup,
}

/// The scene group of the ray queries: the frame and the geometry they read (`nodes` as both
/// BVHs' nodes: a kernel reads one), and `unread` in every other slot (the shading's).
fn trace_scene_group(
    device: &wgpu::Device,
    pipeline: &Pipeline,
    [frame, nodes, prims, unread]: [&wgpu::Buffer; 4],
) -> Result<Option<wgpu::BindGroup>> {
    let read = [
        (slot::FRAME, frame),
        (slot::CW_NODES, nodes),
        (slot::PRIMS, prims),
    ];
    let buffers: Vec<(Binding, &wgpu::Buffer)> = SCENE_BINDINGS
        .iter()
        .map(|&b| match read.iter().find(|(given, _)| *given == b) {
            Some(&(_, buffer)) => (b, buffer),
            None => {
                debug_assert!(!pipeline.kernel.bindings.contains(&b), "{}", b.name);
                (b, unread)
            }
        })
        .collect();
    pipeline.scene_bind_group(device, &buffers)
}

/// A scene's geometry and a ray set uploaded, ready to be traced many times.
pub struct GpuTracer {
    context: GpuContext,
    closest: Pipeline,
    any: Pipeline,
    status: wgpu::Buffer,
    /// The scene group, the same for both queries.
    scene_group: Option<wgpu::BindGroup>,
    chunks: Vec<Chunk>,
}

impl GpuTracer {
    /// Uploads `scene` and `rays`; the rays traverse the scene's BVH2, or `cwbvh` (made from
    /// it) when given.
    pub fn new(
        context: GpuContext,
        scene: &FlatScene,
        cwbvh: Option<&CwGeometry>,
        rays: &RaySet,
    ) -> Result<GpuTracer> {
        GpuTracer::with_checks(context, scene, cwbvh, rays, ShaderChecks::default())
    }

    /// [`GpuTracer::new`] with the kernels built with `checks`.
    pub fn with_checks(
        context: GpuContext,
        scene: &FlatScene,
        cwbvh: Option<&CwGeometry>,
        rays: &RaySet,
        checks: ShaderChecks,
    ) -> Result<GpuTracer> {
        let device = &context.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let features = scene.features();
        let (closest_kernel, any_kernel) = match cwbvh {
            None => (&kernels::TRACE_CLOSEST, &kernels::TRACE_ANY),
            Some(_) => (&kernels::TRACE_CLOSEST_CW, &kernels::TRACE_ANY_CW),
        };
        let closest = kernels::build_pipeline_with(device, closest_kernel, features, &[], checks);
        let any = kernels::build_pipeline_with(device, any_kernel, features, &[], checks);
        let frame = context.uniform_buffer("frame", bytemuck::bytes_of(&scene.frame));
        let (nodes, prims) = match cwbvh {
            None => context.geometry_buffers(scene)?,
            Some(cw) => context.cwbvh_buffers(cw)?,
        };
        let status = context.status_buffer();
        let unread = context.unread_buffer();
        let scene_group = trace_scene_group(device, &closest, [&frame, &nodes, &prims, &unread])?;
        let mut chunks = Vec::new();
        for start in (0..rays.len()).step_by(RAYS_PER_CHUNK) {
            let end = (start + RAYS_PER_CHUNK).min(rays.len());
            let gpu_rays: Vec<GpuRay> = (start..end)
                .map(|i| GpuRay {
                    origin: rays.origins[i].to_array(),
                    t_max: T_FAR,
                    direction: rays.directions[i].to_array(),
                    _pad0: 0,
                })
                .collect();
            let ray_buffer = context.storage_buffer("rays", bytemuck::cast_slice(&gpu_rays))?;
            let distances = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("distances"),
                size: (end - start) as u64 * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let pass = GpuPass {
                sample_count: (end - start) as u32,
                loop_check: LOOP_CHECK_ITERATIONS,
                ..Default::default()
            };
            let pass_info = context.uniform_buffer("pass", bytemuck::bytes_of(&pass));
            let buffers = [
                (slot::PASS_INFO, &pass_info),
                (slot::NODES, &nodes),
                (slot::STATUS, &status),
                (slot::RAYS, &ray_buffer),
                (slot::DISTANCES, &distances),
            ];
            chunks.push(Chunk {
                rays: end - start,
                closest: closest.bind_group(device, &buffers)?,
                any: any.bind_group(device, &buffers)?,
                distances,
            });
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the ray-query kernels: {}",
                super::wgpu_error_text(&e)
            )));
        }
        Ok(GpuTracer {
            context,
            closest,
            any,
            status,
            scene_group,
            chunks,
        })
    }

    /// Traces every ray once; returns the time from submission to completion. Any status flag
    /// the kernel raised (a loop cap) is an error: its distances would be wrong.
    pub fn trace(&self, query: Query) -> Result<Duration> {
        let context = &self.context;
        let pipeline = match query {
            Query::ClosestHit => &self.closest,
            Query::AnyHit => &self.any,
        };
        let mut encoder = context.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.status, 0, None);
        {
            let mut compute = encoder.begin_compute_pass(&Default::default());
            compute.set_pipeline(&pipeline.pipeline);
            for chunk in &self.chunks {
                let bind_group = match query {
                    Query::ClosestHit => &chunk.closest,
                    Query::AnyHit => &chunk.any,
                };
                pipeline.set_bind_groups(&mut compute, self.scene_group.as_ref(), bind_group, &[0]);
                compute.dispatch_workgroups(
                    (chunk.rays as u32).div_ceil(TRACE_WORKGROUP_SIZE),
                    1,
                    1,
                );
            }
        }
        let start = Instant::now();
        let submission = context.queue.submit([encoder.finish()]);
        context.wait(submission)?;
        let elapsed = start.elapsed();
        let words: Vec<u32> = context.read_buffer(&self.status)?;
        if let Some(reason) = describe_status_flags(DispatchStatus::from_words(&words).flags) {
            return Err(Error::Gpu(format!("the ray-query kernel: {reason}")));
        }
        Ok(elapsed)
    }

    /// The distances of the last `trace`, in ray order.
    pub fn distances(&self) -> Result<Vec<f32>> {
        let mut all = Vec::new();
        for chunk in &self.chunks {
            all.extend(self.context.read_buffer::<f32>(&chunk.distances)?);
        }
        Ok(all)
    }

    /// The adapter's name alone (`GpuContext::adapter_name`).
    pub fn adapter_name(&self) -> &str {
        &self.context.adapter_name
    }
}
