//! Reflection points on a sphere or a torus by Fermat's principle on the GPU: the `fermat`
//! kernel of the registry solves one scene vertex per invocation; `fermat::Solver` is its CPU
//! twin (f64), and `tests/fermat.rs` checks that they agree. The raster preview encodes it
//! before its draws (`gpu::preview`), one dispatch per curved mirror, with no host wait between
//! them.

use glam::Vec3;

use super::GpuContext;
use super::kernels::{self, FERMAT};
use crate::error::{Error, Result};
use crate::layout::{GpuReflection, GpuReflector};
use crate::preview::MirrorSurface;

/// The seed's step count ("4–5 steps"), the kernel's default.
pub const SEED_STEPS: u32 = 5;

/// Vertices an invocation group of the kernel takes (its `@workgroup_size`).
const WORKGROUP: u32 = 64;

/// The fermat kernel's pipeline, and the buffers of one reflector's solve.
pub struct FermatPass {
    pipeline: kernels::Pipeline,
}

/// One reflector's inputs and output on the device.
pub struct FermatSolve {
    /// The reflector, the eye and the vertex count (`GpuReflector`); the eye is rewritten as the
    /// camera moves.
    pub reflector: wgpu::Buffer,
    /// One `GpuReflection` per vertex.
    pub output: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    count: u32,
}

impl FermatPass {
    /// Builds the kernel to take at most `steps` steps (validation errors surface through the
    /// caller's error scope).
    pub fn new(context: &GpuContext, steps: u32) -> FermatPass {
        FermatPass {
            pipeline: kernels::build_pipeline_with(
                &context.device,
                &FERMAT,
                0,
                &[("FERMAT_STEPS", steps as f64)],
            ),
        }
    }

    /// The buffers that solve `vertices` (positions, w unused) for `reflector`.
    pub fn solve(
        &self,
        context: &GpuContext,
        reflector: GpuReflector,
        vertices: &wgpu::Buffer,
    ) -> Result<FermatSolve> {
        let uniforms = context.uniform_buffer("reflector", bytemuck::bytes_of(&reflector));
        let output = context.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reflections"),
            size: (reflector.count.max(1) as usize * size_of::<GpuReflection>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = self.pipeline.bind_group(
            &context.device,
            &[
                ("reflector", &uniforms),
                ("fermat_vertices", vertices),
                ("reflections", &output),
            ],
        )?;
        Ok(FermatSolve {
            reflector: uniforms,
            output,
            bind_group,
            count: reflector.count,
        })
    }

    /// Records the solve of `solve`'s vertices into `encoder`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, solve: &FermatSolve) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &solve.bind_group, &[]);
        pass.dispatch_workgroups(solve.count.div_ceil(WORKGROUP), 1, 1);
    }
}

/// The vertices' positions as the kernel reads them (w unused), in a storage buffer.
pub fn vertex_buffer(context: &GpuContext, vertices: &[Vec3]) -> Result<wgpu::Buffer> {
    let points: Vec<[f32; 4]> = vertices.iter().map(|v| v.extend(0.0).to_array()).collect();
    context.storage_buffer("fermat vertices", bytemuck::cast_slice(&points))
}

/// The reflection point of each of `vertices` seen from `eye` on `surface`, found in at most
/// `steps` steps.
pub fn reflections(
    context: &GpuContext,
    surface: MirrorSurface,
    eye: Vec3,
    vertices: &[Vec3],
    steps: u32,
) -> Result<Vec<GpuReflection>> {
    if vertices.is_empty() {
        return Ok(Vec::new());
    }
    let device = &context.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pass = FermatPass::new(context, steps);
    let input = vertex_buffer(context, vertices)?;
    let reflector = surface.gpu(eye, vertices.len() as u32);
    let solve = pass.solve(context, reflector, &input)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    pass.encode(&mut encoder, &solve);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!(
            "the fermat kernel: {}",
            super::wgpu_error_text(&e)
        )));
    }
    context.wait(context.queue.submit([encoder.finish()]))?;
    let bytes = context.read_buffer(&solve.output)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
