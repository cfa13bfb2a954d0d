//! The registry of compute kernels and the one pipeline builder.
//!
//! A [`Kernel`] names its WGSL modules (composed after the generated constants of
//! `layout::wgsl_prelude` and the bindings of `wgsl/bindings.wgsl`), its entry point and the
//! bindings it reads. [`build_pipeline`] turns any kernel into a pipeline with an explicit bind
//! group layout made from its entries of [`BINDINGS`], specialised to the scene's features through
//! WGSL's pipeline-overridable constants (`layout::FEATURES`): a scene without mirrors gets a
//! kernel without the bounce, a pinhole one without lens sampling, and so on. Adding a kernel is
//! adding an entry to [`KERNELS`], not copying set-up code.

use crate::error::{Error, Result};
use crate::layout::{FEATURES, GpuPass, wgsl_prelude};

/// How a kernel accesses a binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`: a small struct of constants.
    Uniform,
    /// `var<storage, read>`: an array the kernel only reads.
    StorageRead,
    /// `var<storage, read_write>`: an array the kernel writes (or updates atomically).
    StorageReadWrite,
}

/// One binding of group 0: its number, its WGSL variable name, and its access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// `@binding(n)` in `wgsl/bindings.wgsl`.
    pub binding: u32,
    /// The WGSL variable's name, which `Pipeline::bind_group` looks buffers up by.
    pub name: &'static str,
    /// Uniform or storage, read-only or not.
    pub access: Access,
    /// Bytes of one element, for a binding bound at a dynamic offset into an array of them
    /// (one per dispatch of a batch); 0 for a binding of the whole buffer.
    pub dynamic_size: u64,
}

const fn binding(binding: u32, name: &'static str, access: Access) -> Binding {
    Binding {
        binding,
        name,
        access,
        dynamic_size: 0,
    }
}

/// Every binding of group 0, as `wgsl/bindings.wgsl` declares them.
pub const BINDINGS: [Binding; 24] = [
    binding(0, "camera", Access::Uniform),
    binding(1, "frame", Access::Uniform),
    // One GpuPass per dispatch of a batch, each at its own dynamic offset.
    Binding {
        dynamic_size: size_of::<GpuPass>() as u64,
        ..binding(2, "pass_info", Access::Uniform)
    },
    binding(3, "nodes", Access::StorageRead),
    binding(4, "prims", Access::StorageRead),
    binding(5, "normals", Access::StorageRead),
    binding(6, "materials", Access::StorageRead),
    binding(7, "lights", Access::StorageRead),
    binding(8, "accumulation", Access::StorageReadWrite),
    binding(9, "status", Access::StorageReadWrite),
    binding(10, "sample_table", Access::StorageRead),
    binding(11, "rays", Access::StorageRead),
    binding(12, "distances", Access::StorageReadWrite),
    binding(13, "cw_nodes", Access::StorageRead),
    binding(14, "pixel_list", Access::StorageRead),
    binding(15, "reflectors", Access::StorageRead),
    binding(16, "fermat_vertices", Access::StorageRead),
    binding(17, "reflections", Access::StorageReadWrite),
    binding(18, "primary_hits", Access::StorageReadWrite),
    binding(19, "reflected_triangles", Access::StorageRead),
    binding(20, "shown_indices", Access::StorageReadWrite),
    binding(21, "draw_args", Access::StorageReadWrite),
    binding(22, "fermat_starts", Access::StorageReadWrite),
    binding(23, "vertex_solves", Access::StorageRead),
];

/// The bindings of the render kernel: nine storage buffers, one more than WebGPU's baseline
/// (every Vulkan, Metal and D3D12 adapter allows more; `GpuRenderer` says so where one does not).
const RENDER_BINDINGS: [Binding; 12] = [
    BINDINGS[0],
    BINDINGS[1],
    BINDINGS[2],
    BINDINGS[4],
    BINDINGS[5],
    BINDINGS[6],
    BINDINGS[7],
    BINDINGS[8],
    BINDINGS[9],
    BINDINGS[10],
    BINDINGS[13],
    BINDINGS[14],
];

/// The bindings of a split render's first kernel (`primary`): what camera rays and their
/// traversal read, and where their hits go.
const PRIMARY_BINDINGS: [Binding; 9] = [
    BINDINGS[0],
    BINDINGS[1],
    BINDINGS[2],
    BINDINGS[4],
    BINDINGS[9],
    BINDINGS[10],
    BINDINGS[13],
    BINDINGS[14],
    BINDINGS[18],
];

/// The bindings of a split render's second kernel (`render_split`): the megakernel's, then the
/// camera rays' hits.
const RENDER_SPLIT_BINDINGS: [Binding; 13] = {
    let mut list = [BINDINGS[18]; 13];
    let mut i = 0;
    while i < RENDER_BINDINGS.len() {
        list[i] = RENDER_BINDINGS[i];
        i += 1;
    }
    list
};

/// The bindings of the ray-query kernels.
const TRACE_BINDINGS: [Binding; 7] = [
    BINDINGS[1],
    BINDINGS[2],
    BINDINGS[3],
    BINDINGS[4],
    BINDINGS[9],
    BINDINGS[11],
    BINDINGS[12],
];

/// The bindings of the ray-query kernels over the compressed wide BVH.
const TRACE_CW_BINDINGS: [Binding; 7] = [
    BINDINGS[1],
    BINDINGS[2],
    BINDINGS[4],
    BINDINGS[9],
    BINDINGS[11],
    BINDINGS[12],
    BINDINGS[13],
];

/// The bindings of the Fermat kernel.
const FERMAT_BINDINGS: [Binding; 4] = [BINDINGS[15], BINDINGS[16], BINDINGS[17], BINDINGS[22]];

/// The bindings of the Fermat searches' eye-free start: the searches, the vertices, the starts.
const FERMAT_START_BINDINGS: [Binding; 3] = [BINDINGS[15], BINDINGS[16], BINDINGS[22]];

/// The bindings of the Fermat cull: the searches (their mirrors' ids), the solves' points
/// (whether each shows), the triangles and their vertices' solves, and the draw it writes.
const FERMAT_CULL_BINDINGS: [Binding; 6] = [
    BINDINGS[15],
    BINDINGS[17],
    BINDINGS[19],
    BINDINGS[20],
    BINDINGS[21],
    BINDINGS[23],
];

/// (file name, source) of every WGSL module a kernel may compose.
pub const MODULES: [(&str, &str); 15] = [
    ("types.wgsl", include_str!("../../wgsl/types.wgsl")),
    ("bindings.wgsl", include_str!("../../wgsl/bindings.wgsl")),
    ("status.wgsl", include_str!("../../wgsl/status.wgsl")),
    ("rng.wgsl", include_str!("../../wgsl/rng.wgsl")),
    ("sampling.wgsl", include_str!("../../wgsl/sampling.wgsl")),
    ("camera.wgsl", include_str!("../../wgsl/camera.wgsl")),
    ("intersect.wgsl", include_str!("../../wgsl/intersect.wgsl")),
    ("curved.wgsl", include_str!("../../wgsl/curved.wgsl")),
    ("traverse.wgsl", include_str!("../../wgsl/traverse.wgsl")),
    (
        "traverse_cwbvh.wgsl",
        include_str!("../../wgsl/traverse_cwbvh.wgsl"),
    ),
    ("sampler.wgsl", include_str!("../../wgsl/sampler.wgsl")),
    (
        "integrator.wgsl",
        include_str!("../../wgsl/integrator.wgsl"),
    ),
    ("render.wgsl", include_str!("../../wgsl/render.wgsl")),
    ("trace.wgsl", include_str!("../../wgsl/trace.wgsl")),
    ("fermat.wgsl", include_str!("../../wgsl/fermat.wgsl")),
];

/// A compute kernel: what it is made of and what it reads.
#[derive(Debug)]
pub struct Kernel {
    /// Label of its shader module, pipeline and bind group, and its name in messages.
    pub name: &'static str,
    /// Module file names (from [`MODULES`]), in composition order.
    pub modules: &'static [&'static str],
    /// The `@compute` function to run.
    pub entry_point: &'static str,
    /// The entries of [`BINDINGS`] it reads, in binding order.
    pub bindings: &'static [Binding],
}

impl Kernel {
    /// Storage buffers the kernel binds (adapters limit them per shader stage).
    pub fn storage_buffers(&self) -> u32 {
        let storage = |b: &&Binding| b.access != Access::Uniform;
        self.bindings.iter().filter(storage).count() as u32
    }
}

/// The megakernel: camera samples to accumulated radiance, one invocation per pixel.
pub const RENDER: Kernel = Kernel {
    name: "render",
    modules: &[
        "types.wgsl",
        "bindings.wgsl",
        "status.wgsl",
        "rng.wgsl",
        "sampling.wgsl",
        "camera.wgsl",
        "intersect.wgsl",
        "curved.wgsl",
        "traverse_cwbvh.wgsl",
        "sampler.wgsl",
        "integrator.wgsl",
        "render.wgsl",
    ],
    entry_point: "render",
    bindings: &RENDER_BINDINGS,
};

/// A split render's first kernel: each camera ray's closest hit, stored for `RENDER_SPLIT`.
pub const RENDER_PRIMARY: Kernel = Kernel {
    name: "render_primary",
    modules: RENDER.modules,
    entry_point: "primary",
    bindings: &PRIMARY_BINDINGS,
};

/// A split render's second kernel: the megakernel's paths from the stored camera-ray hits.
pub const RENDER_SPLIT: Kernel = Kernel {
    name: "render_split",
    modules: RENDER.modules,
    entry_point: "render_split",
    bindings: &RENDER_SPLIT_BINDINGS,
};

const TRACE_MODULES: &[&str] = &[
    "types.wgsl",
    "bindings.wgsl",
    "status.wgsl",
    "intersect.wgsl",
    "curved.wgsl",
    "traverse.wgsl",
    "traverse_cwbvh.wgsl",
    "trace.wgsl",
];

/// Closest hit of each ray of a buffer (the ray benchmark).
pub const TRACE_CLOSEST: Kernel = Kernel {
    name: "trace_closest",
    modules: TRACE_MODULES,
    entry_point: "trace_closest",
    bindings: &TRACE_BINDINGS,
};

/// Any hit of each ray of a buffer (the ray benchmark).
pub const TRACE_ANY: Kernel = Kernel {
    name: "trace_any",
    modules: TRACE_MODULES,
    entry_point: "trace_any",
    bindings: &TRACE_BINDINGS,
};

/// Closest hit of each ray of a buffer through the compressed wide BVH (the ray benchmark).
pub const TRACE_CLOSEST_CW: Kernel = Kernel {
    name: "trace_closest_cw",
    modules: TRACE_MODULES,
    entry_point: "trace_closest_cw",
    bindings: &TRACE_CW_BINDINGS,
};

/// Any hit of each ray of a buffer through the compressed wide BVH (the ray benchmark).
pub const TRACE_ANY_CW: Kernel = Kernel {
    name: "trace_any_cw",
    modules: TRACE_MODULES,
    entry_point: "trace_any_cw",
    bindings: &TRACE_CW_BINDINGS,
};

/// Reflection points of vertices on a curved mirror by Fermat's principle, one invocation per
/// vertex, one pipeline per kind of mirror (`gpu::fermat`; CPU twin `fermat::Solver`).
pub const FERMAT: Kernel = Kernel {
    name: "fermat",
    modules: &["types.wgsl", "bindings.wgsl", "fermat.wgsl"],
    entry_point: "fermat",
    bindings: &FERMAT_BINDINGS,
};

/// A Bézier patch's corner B for each vertex, where the segment from the vertex to the patch's
/// inside point O crosses it (`fermat::BezierPatch::crossing`): Newton's steps that depend on
/// the vertex and the patch, not on the eye, so run once for a set of vertices rather than in
/// every frame's `fermat` (`gpu::fermat::FermatPass::solve`).
pub const FERMAT_START: Kernel = Kernel {
    name: "fermat_start",
    modules: FERMAT.modules,
    entry_point: "fermat_start",
    bindings: &FERMAT_START_BINDINGS,
};

/// The preview's reflected triangles whose three vertices' reflections show on one curved
/// mirror, listed for an indirect draw, one invocation per triangle (CPU twin:
/// `fermat::drawn_in_preview` per vertex): the draw then runs the vertex stage for those only.
pub const FERMAT_CULL: Kernel = Kernel {
    name: "fermat_cull",
    modules: FERMAT.modules,
    entry_point: "fermat_cull",
    bindings: &FERMAT_CULL_BINDINGS,
};

/// Every kernel chambre builds.
pub const KERNELS: [&Kernel; 10] = [
    &RENDER,
    &RENDER_PRIMARY,
    &RENDER_SPLIT,
    &TRACE_CLOSEST,
    &TRACE_ANY,
    &TRACE_CLOSEST_CW,
    &TRACE_ANY_CW,
    &FERMAT,
    &FERMAT_START,
    &FERMAT_CULL,
];

/// The complete source of `kernel`, with a marker comment where each module starts.
pub fn kernel_source(kernel: &Kernel) -> String {
    let mut source = wgsl_prelude();
    for name in kernel.modules {
        let (_, text) = MODULES
            .iter()
            .find(|(file, _)| file == name)
            .unwrap_or_else(|| panic!("kernel {}: no module {name}", kernel.name));
        source += &format!("\n// ---- {name} ----\n");
        source += text;
    }
    source
}

/// The values of the feature constants for a kernel specialised to `features`
/// (`layout::FEATURE_*` bits): 1.0 for a feature kept, 0.0 for one left out.
pub fn feature_constants(features: u32) -> Vec<(&'static str, f64)> {
    FEATURES
        .iter()
        .map(|&(name, bit)| (name, if features & bit != 0 { 1.0 } else { 0.0 }))
        .collect()
}

/// A pipeline and the layout of the bind group it takes.
pub struct Pipeline {
    /// The kernel compiled for one feature set.
    pub pipeline: wgpu::ComputePipeline,
    /// Made from the kernel's bindings: group 0 of the pipeline.
    pub bind_group_layout: wgpu::BindGroupLayout,
    /// The kernel it was built from.
    pub kernel: &'static Kernel,
}

fn layout_entry(b: &Binding) -> wgpu::BindGroupLayoutEntry {
    let ty = match b.access {
        Access::Uniform => wgpu::BufferBindingType::Uniform,
        Access::StorageRead => wgpu::BufferBindingType::Storage { read_only: true },
        Access::StorageReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
    };
    wgpu::BindGroupLayoutEntry {
        binding: b.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: b.dynamic_size > 0,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Builds `kernel` specialised to `features`. Validation errors come back through the
/// device's error handling (see `GpuContext`), not as panics.
pub fn build_pipeline(device: &wgpu::Device, kernel: &'static Kernel, features: u32) -> Pipeline {
    build_pipeline_with(device, kernel, features, &[])
}

/// [`build_pipeline`], with values for the kernel's own override constants too (e.g. the
/// fermat kernel's `FERMAT_STEPS`).
pub fn build_pipeline_with(
    device: &wgpu::Device,
    kernel: &'static Kernel,
    features: u32,
    overrides: &[(&'static str, f64)],
) -> Pipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(kernel.name),
        source: wgpu::ShaderSource::Wgsl(kernel_source(kernel).into()),
    });
    let entries: Vec<_> = kernel.bindings.iter().map(layout_entry).collect();
    let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(kernel.name),
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(kernel.name),
        bind_group_layouts: &[Some(&bind_group_layout)],
        immediate_size: 0,
    });
    let mut constants = feature_constants(features);
    constants.extend_from_slice(overrides);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(kernel.name),
        layout: Some(&layout),
        module: &module,
        entry_point: Some(kernel.entry_point),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        },
        cache: None,
    });
    Pipeline {
        pipeline,
        bind_group_layout,
        kernel,
    }
}

impl Pipeline {
    /// A bind group with `buffers` (binding name, buffer) in the kernel's binding order; every
    /// binding the kernel reads must be given.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        buffers: &[(&str, &wgpu::Buffer)],
    ) -> Result<wgpu::BindGroup> {
        let mut entries = Vec::with_capacity(self.kernel.bindings.len());
        for b in self.kernel.bindings {
            let (_, buffer) = buffers
                .iter()
                .find(|(name, _)| *name == b.name)
                .ok_or_else(|| {
                    Error::Gpu(format!(
                        "kernel {}: no buffer for binding {} `{}`",
                        self.kernel.name, b.binding, b.name
                    ))
                })?;
            let resource = match std::num::NonZeroU64::new(b.dynamic_size) {
                None => buffer.as_entire_binding(),
                Some(size) => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: 0,
                    size: Some(size),
                }),
            };
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource,
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.kernel.name),
            layout: &self.bind_group_layout,
            entries: &entries,
        }))
    }
}
