//! Reflection points on a sphere by Fermat's principle on the GPU: the `fermat` kernel of the
//! registry solves one scene vertex per invocation; `fermat::Solver` is its CPU twin (f64), and
//! `tests/fermat.rs` checks that they agree.

use glam::Vec3;

use super::GpuContext;
use super::kernels::{self, FERMAT};
use crate::error::{Error, Result};
use crate::layout::{GpuReflection, GpuReflector};

/// Vertices an invocation group of the kernel takes (its `@workgroup_size`).
const WORKGROUP: u32 = 64;

/// The reflection point of each of `vertices` seen from `eye` on the sphere of `center` and
/// `radius`.
pub fn reflections(
    context: &GpuContext,
    center: Vec3,
    radius: f32,
    eye: Vec3,
    vertices: &[Vec3],
) -> Result<Vec<GpuReflection>> {
    let device = &context.device;
    let count = vertices.len() as u32;
    if count == 0 {
        return Ok(Vec::new());
    }
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipeline = kernels::build_pipeline(device, &FERMAT, 0);
    let uniforms = GpuReflector {
        center: center.to_array(),
        radius,
        eye: eye.to_array(),
        count,
    };
    let reflector = context.uniform_buffer("reflector", bytemuck::bytes_of(&uniforms));
    let points: Vec<[f32; 4]> = vertices.iter().map(|v| v.extend(0.0).to_array()).collect();
    let input = context.storage_buffer("fermat vertices", bytemuck::cast_slice(&points))?;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("reflections"),
        size: (vertices.len() * size_of::<GpuReflection>()) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind_group = pipeline.bind_group(
        device,
        &[
            ("reflector", &reflector),
            ("fermat_vertices", &input),
            ("reflections", &output),
        ],
    )?;
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(count.div_ceil(WORKGROUP), 1, 1);
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!(
            "the fermat kernel: {}",
            super::wgpu_error_text(&e)
        )));
    }
    context.wait(context.queue.submit([encoder.finish()]))?;
    let bytes = context.read_buffer(&output)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
