//! Reflection points on curved mirrors (sphere, torus, ellipsoid, cylinder, Bézier patch) by
//! Fermat's principle on the GPU: the `fermat` kernel of the registry solves one scene vertex
//! per invocation; `fermat::Solver` is its CPU
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

/// The fermat kernel's pipelines, one per kind of reflector (`layout::REFLECTOR_*`, the
/// kernel's `REFLECTOR_KIND`): specialised, a sphere's search carries none of a patch's code
/// (on lavapipe the general kernel took a sphere's preview frame from 4 to 12 ms).
pub struct FermatPass {
    pipelines: Vec<(u32, kernels::Pipeline)>,
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
    /// Its pipeline's index in `FermatPass::pipelines`.
    pipeline: usize,
}

impl FermatPass {
    /// Builds the kernel for each of `kinds` of reflector, to take at most `steps` steps
    /// (validation errors surface through the caller's error scope).
    pub fn new(context: &GpuContext, steps: u32, kinds: &[u32]) -> FermatPass {
        let mut kinds = kinds.to_vec();
        kinds.sort_unstable();
        kinds.dedup();
        let pipelines = kinds
            .into_iter()
            .map(|kind| {
                let overrides = [
                    ("FERMAT_STEPS", steps as f64),
                    ("REFLECTOR_KIND", kind as f64),
                ];
                let pipeline =
                    kernels::build_pipeline_with(&context.device, &FERMAT, 0, &overrides);
                (kind, pipeline)
            })
            .collect();
        FermatPass { pipelines }
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
        let pipeline = self
            .pipelines
            .iter()
            .position(|(kind, _)| *kind == reflector.kind)
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "no fermat pipeline for reflector kind {}",
                    reflector.kind
                ))
            })?;
        let bind_group = self.pipelines[pipeline].1.bind_group(
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
            pipeline,
        })
    }

    /// Records the solve of `solve`'s vertices into `encoder`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, solve: &FermatSolve) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipelines[solve.pipeline].1.pipeline);
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
    let reflector = surface.gpu(eye, vertices.len() as u32);
    let pass = FermatPass::new(context, steps, &[reflector.kind]);
    let input = vertex_buffer(context, vertices)?;
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
