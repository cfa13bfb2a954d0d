//! The registry of compute kernels and the one pipeline builder.
//!
//! A [`Kernel`] names its WGSL modules (composed after the generated constants of
//! `layout::wgsl_prelude` and the bindings of `wgsl/bindings.wgsl`), its entry point and the
//! bindings it reads. The bindings fall in two groups: the scene's ([`SCENE_BINDINGS`], group
//! [`SCENE_GROUP`]: camera, geometry, materials, lights, textures, made once for a render and
//! shared by every kernel that reads any of it) and the kernel's own (group [`KERNEL_GROUP`]:
//! its queues, sums and per-dispatch uniforms). [`build_pipeline`] turns any kernel into a
//! pipeline with explicit bind group layouts made from those tables, specialised to the scene's features through
//! WGSL's pipeline-overridable constants (`layout::FEATURES`): a scene without mirrors gets a
//! kernel without the bounce, a pinhole one without lens sampling, and so on. Adding a kernel is
//! adding an entry to [`KERNELS`], not copying set-up code. The preview's render pipelines
//! describe their bindings with the same [`Binding`] (`preview::PIPELINES`).

use crate::error::{Error, Result};
use crate::layout::{FEATURES, wgsl_prelude};
use crate::named::named_enum;

/// How a shader accesses a binding: the kernels bind buffers only; the preview's render
/// pipelines (`preview::renderer::pipeline::RasterPipeline`) textures and a sampler too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`: a small struct of constants.
    Uniform,
    /// `var<storage, read>`: an array the kernel only reads.
    StorageRead,
    /// `var<storage, read_write>`: an array the kernel writes (or updates atomically).
    StorageReadWrite,
    /// `texture_2d<f32>`, read texel by texel (`textureLoad`), never filtered.
    FloatTexture,
    /// `texture_2d<u32>`, read texel by texel.
    UintTexture,
    /// `texture_depth_2d_array`, read through a comparison sampler.
    DepthTextureArray,
    /// `sampler_comparison`.
    ComparisonSampler,
}

impl Access {
    /// Whether it is a storage buffer (adapters limit them per shader stage).
    pub fn is_storage(self) -> bool {
        matches!(self, Access::StorageRead | Access::StorageReadWrite)
    }

    /// wgpu's binding type of it; `dynamic_offset` for a buffer bound at one.
    fn binding_type(self, dynamic_offset: bool) -> wgpu::BindingType {
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic_offset,
            min_binding_size: None,
        };
        let texture = |sample_type, view_dimension| wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        };
        let d2 = wgpu::TextureViewDimension::D2;
        match self {
            Access::Uniform => buffer(wgpu::BufferBindingType::Uniform),
            Access::StorageRead => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            Access::StorageReadWrite => {
                buffer(wgpu::BufferBindingType::Storage { read_only: false })
            }
            Access::FloatTexture => {
                texture(wgpu::TextureSampleType::Float { filterable: false }, d2)
            }
            Access::UintTexture => texture(wgpu::TextureSampleType::Uint, d2),
            Access::DepthTextureArray => texture(
                wgpu::TextureSampleType::Depth,
                wgpu::TextureViewDimension::D2Array,
            ),
            Access::ComparisonSampler => {
                wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison)
            }
        }
    }
}

/// One binding of a bind group: its number, its WGSL variable name, its access and the shader
/// stages that read it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// `@binding(n)` in `wgsl/bindings.wgsl` (or the preview's shader).
    pub binding: u32,
    /// The WGSL variable's name, which `Pipeline::bind_group` looks buffers up by.
    pub name: &'static str,
    /// Uniform or storage, read-only or not; a texture or a sampler.
    pub access: Access,
    /// The stages that read it: compute for a kernel's.
    pub visibility: wgpu::ShaderStages,
    /// Bytes of one element, for a binding bound at a dynamic offset into an array of them
    /// (one per dispatch of a batch); 0 for a binding of the whole buffer.
    pub dynamic_size: u64,
}

impl Binding {
    /// Binding `binding` called `name`, read by `visibility`'s stages, of its whole resource.
    pub const fn new(
        binding: u32,
        name: &'static str,
        access: Access,
        visibility: wgpu::ShaderStages,
    ) -> Binding {
        Binding {
            binding,
            name,
            access,
            visibility,
            dynamic_size: 0,
        }
    }

    /// Its entry of a bind group layout.
    pub fn layout_entry(&self) -> wgpu::BindGroupLayoutEntry {
        wgpu::BindGroupLayoutEntry {
            binding: self.binding,
            visibility: self.visibility,
            ty: self.access.binding_type(self.dynamic_size > 0),
            count: None,
        }
    }
}

/// The bind group layout of `bindings`, labelled `label`.
pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    bindings: &[Binding],
) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = bindings.iter().map(Binding::layout_entry).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// A kernel's binding: read by the compute stage.
const fn entry(binding: u32, name: &'static str, access: Access) -> Binding {
    Binding::new(binding, name, access, wgpu::ShaderStages::COMPUTE)
}

/// The kernels' bindings by name, as `wgsl/bindings.wgsl` declares them (same numbers, names,
/// access and groups: tests/wgsl.rs checks). Kernels list theirs by these names, and buffers
/// are handed to [`Pipeline::scene_bind_group`] and [`Pipeline::bind_group`] with them.
pub mod slot {
    use super::Access::{StorageRead, StorageReadWrite, Uniform};
    use super::{Binding, entry};
    use crate::layout::{GpuPass, GpuWave};

    /// The view camera (`GpuCamera`).
    pub const CAMERA: Binding = entry(0, "camera", Uniform);
    /// The render's constants (`GpuFrame`).
    pub const FRAME: Binding = entry(1, "frame", Uniform);
    /// One `GpuPass` per dispatch of a batch, each at its own dynamic offset.
    pub const PASS_INFO: Binding = Binding {
        dynamic_size: size_of::<GpuPass>() as u64,
        ..entry(2, "pass_info", Uniform)
    };
    /// The BVH2's nodes (the ray benchmark's BVH2 queries).
    pub const NODES: Binding = entry(3, "nodes", StorageRead);
    /// The primitives, in the order of the BVH traversed.
    pub const PRIMS: Binding = entry(4, "prims", StorageRead);
    /// Smooth triangles' vertex normals.
    pub const NORMALS: Binding = entry(5, "normals", StorageRead);
    /// The materials.
    pub const MATERIALS: Binding = entry(6, "materials", StorageRead);
    /// The lights.
    pub const LIGHTS: Binding = entry(7, "lights", StorageRead);
    /// The per-pixel sums (`render::AccumulationLayout`).
    pub const ACCUMULATION: Binding = entry(8, "accumulation", StorageReadWrite);
    /// The status words every kernel reports through.
    pub const STATUS: Binding = entry(9, "status", StorageReadWrite);
    /// Precomputed sample patterns (Poisson-disk sets, interleaved tiles, apertures).
    pub const SAMPLE_TABLE: Binding = entry(10, "sample_table", StorageRead);
    /// The ray benchmark's rays.
    pub const RAYS: Binding = entry(11, "rays", StorageRead);
    /// The ray benchmark's per-ray results.
    pub const DISTANCES: Binding = entry(12, "distances", StorageReadWrite);
    /// The compressed wide BVH's nodes.
    pub const CW_NODES: Binding = entry(13, "cw_nodes", StorageRead);
    /// The pixels an adaptive pass samples.
    pub const PIXEL_LIST: Binding = entry(14, "pixel_list", StorageRead);
    /// The Fermat searches: a mirror and an eye each.
    pub const REFLECTORS: Binding = entry(15, "reflectors", StorageRead);
    /// The vertices the Fermat searches reflect.
    pub const FERMAT_VERTICES: Binding = entry(16, "fermat_vertices", StorageRead);
    /// The Fermat searches' reflection points.
    pub const REFLECTIONS: Binding = entry(17, "reflections", StorageReadWrite);
    /// The wavefront render's closest hit of each path's current ray.
    pub const WF_HITS: Binding = entry(18, "wf_hits", StorageReadWrite);
    /// The preview's reflected triangles.
    pub const REFLECTED_TRIANGLES: Binding = entry(19, "reflected_triangles", StorageRead);
    /// The index triples of the reflected triangles shown.
    pub const SHOWN_INDICES: Binding = entry(20, "shown_indices", StorageReadWrite);
    /// The one indirect draw of the reflected triangles.
    pub const DRAW_ARGS: Binding = entry(21, "draw_args", StorageReadWrite);
    /// A Bézier patch search's corner B per vertex.
    pub const FERMAT_STARTS: Binding = entry(22, "fermat_starts", StorageReadWrite);
    /// The Fermat solve of each distinct reflected vertex.
    pub const VERTEX_SOLVES: Binding = entry(23, "vertex_solves", StorageRead);
    /// One `GpuWave` per stage dispatch of a wavefront batch, each at its own dynamic offset.
    pub const WAVE: Binding = Binding {
        dynamic_size: size_of::<GpuWave>() as u64,
        ..entry(24, "wave", Uniform)
    };
    /// Each path's current ray (`GpuPathRay`).
    pub const WF_RAYS: Binding = entry(25, "wf_rays", StorageReadWrite);
    /// Each path's state between stages (`GpuPath`).
    pub const WF_PATHS: Binding = entry(26, "wf_paths", StorageReadWrite);
    /// The paths each depth's stages take, two lists used in turn.
    pub const WF_QUEUE: Binding = entry(27, "wf_queue", StorageReadWrite);
    /// The live counters of the queues being filled.
    pub const WF_COUNTERS: Binding = entry(28, "wf_counters", StorageReadWrite);
    /// Each depth's indirect dispatch arguments, as `wf_prepare` writes them.
    pub const WF_ARGS: Binding = entry(29, "wf_args", StorageReadWrite);
    /// The same arguments, read by the stages they size.
    pub const WF_ARGS_IN: Binding = entry(30, "wf_args_in", StorageRead);
    /// The shadow rays of a depth's path vertices.
    pub const WF_SHADOW_RAYS: Binding = entry(31, "wf_shadow_rays", StorageReadWrite);
    /// What each shadow ray adds where the light is visible.
    pub const WF_SHADOW_TERMS: Binding = entry(32, "wf_shadow_terms", StorageReadWrite);
    /// The shadow rays emitted, compacted.
    pub const WF_SHADOW_QUEUE: Binding = entry(33, "wf_shadow_queue", StorageReadWrite);
    /// The camera ray's first hit of each path, for the AOV layers.
    pub const WF_AOVS: Binding = entry(34, "wf_aovs", StorageReadWrite);
    /// Textured triangles' texture coordinates.
    pub const TEXCOORDS: Binding = entry(35, "texcoords", StorageRead);
    /// The textures the materials read.
    pub const TEXTURES: Binding = entry(36, "textures", StorageRead);
    /// Every texture's texels.
    pub const TEXELS: Binding = entry(37, "texels", StorageRead);
    /// The environment light's map and sampling distribution (`FlatScene::environment`).
    pub const ENVIRONMENT: Binding = entry(38, "environment", StorageRead);
}

use slot::*;

/// The bind group of the scene's bindings: `@group(0)` in `wgsl/bindings.wgsl`.
pub const SCENE_GROUP: u32 = 0;

/// The bind group of a kernel's own bindings: `@group(1)` in `wgsl/bindings.wgsl`.
pub const KERNEL_GROUP: u32 = 1;

/// The scene group's bindings, in binding order: what a render uploads once and every kernel
/// of it may read. A kernel reading any of them takes the whole group (one layout, so one bind
/// group serves every kernel); every other binding is a kernel's own.
pub const SCENE_BINDINGS: [Binding; 12] = [
    CAMERA,
    FRAME,
    PRIMS,
    NORMALS,
    MATERIALS,
    LIGHTS,
    SAMPLE_TABLE,
    CW_NODES,
    TEXCOORDS,
    TEXTURES,
    TEXELS,
    ENVIRONMENT,
];

/// The bind group `binding` belongs to: [`SCENE_GROUP`] or [`KERNEL_GROUP`].
pub fn group_of(binding: &Binding) -> u32 {
    match SCENE_BINDINGS.contains(binding) {
        true => SCENE_GROUP,
        false => KERNEL_GROUP,
    }
}

/// Every binding of the kernels, as `wgsl/bindings.wgsl` declares them.
pub const BINDINGS: [Binding; 39] = [
    CAMERA,
    FRAME,
    PASS_INFO,
    NODES,
    PRIMS,
    NORMALS,
    MATERIALS,
    LIGHTS,
    ACCUMULATION,
    STATUS,
    SAMPLE_TABLE,
    RAYS,
    DISTANCES,
    CW_NODES,
    PIXEL_LIST,
    REFLECTORS,
    FERMAT_VERTICES,
    REFLECTIONS,
    WF_HITS,
    REFLECTED_TRIANGLES,
    SHOWN_INDICES,
    DRAW_ARGS,
    FERMAT_STARTS,
    VERTEX_SOLVES,
    WAVE,
    WF_RAYS,
    WF_PATHS,
    WF_QUEUE,
    WF_COUNTERS,
    WF_ARGS,
    WF_ARGS_IN,
    WF_SHADOW_RAYS,
    WF_SHADOW_TERMS,
    WF_SHADOW_QUEUE,
    WF_AOVS,
    TEXCOORDS,
    TEXTURES,
    TEXELS,
    ENVIRONMENT,
];

/// The bindings of the megakernel: thirteen storage buffers, five more than WebGPU's baseline
/// (every Vulkan, Metal and D3D12 adapter allows more; `GpuRenderer` says so where one does not).
const RENDER_BINDINGS: &[Binding] = &[
    CAMERA,
    FRAME,
    PASS_INFO,
    PRIMS,
    NORMALS,
    MATERIALS,
    LIGHTS,
    ACCUMULATION,
    STATUS,
    SAMPLE_TABLE,
    CW_NODES,
    PIXEL_LIST,
    TEXCOORDS,
    TEXTURES,
    TEXELS,
    ENVIRONMENT,
];

/// The bindings of the ray-query kernels.
const TRACE_BINDINGS: &[Binding] = &[FRAME, PASS_INFO, NODES, PRIMS, STATUS, RAYS, DISTANCES];

/// The bindings of the ray-query kernels over the compressed wide BVH.
const TRACE_CW_BINDINGS: &[Binding] = &[FRAME, PASS_INFO, PRIMS, STATUS, RAYS, DISTANCES, CW_NODES];

/// The bindings of the Fermat kernel.
const FERMAT_BINDINGS: &[Binding] = &[REFLECTORS, FERMAT_VERTICES, REFLECTIONS, FERMAT_STARTS];

/// The bindings of the Fermat searches' eye-free start: the searches, the vertices, the starts.
const FERMAT_START_BINDINGS: &[Binding] = &[REFLECTORS, FERMAT_VERTICES, FERMAT_STARTS];

/// The bindings of the Fermat cull: the searches (their mirrors' ids), the solves' points
/// (whether each shows), the triangles and their vertices' solves, and the draw it writes.
const FERMAT_CULL_BINDINGS: &[Binding] = &[
    REFLECTORS,
    REFLECTIONS,
    REFLECTED_TRIANGLES,
    SHOWN_INDICES,
    DRAW_ARGS,
    VERTEX_SOLVES,
];

/// (file name, source) of every WGSL module a kernel may compose.
pub const MODULES: [(&str, &str); 20] = [
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
    ("bsdf.wgsl", include_str!("../../wgsl/bsdf.wgsl")),
    ("texture.wgsl", include_str!("../../wgsl/texture.wgsl")),
    (
        "environment.wgsl",
        include_str!("../../wgsl/environment.wgsl"),
    ),
    ("path.wgsl", include_str!("../../wgsl/path.wgsl")),
    (
        "integrator.wgsl",
        include_str!("../../wgsl/integrator.wgsl"),
    ),
    ("render.wgsl", include_str!("../../wgsl/render.wgsl")),
    ("wavefront.wgsl", include_str!("../../wgsl/wavefront.wgsl")),
    ("trace.wgsl", include_str!("../../wgsl/trace.wgsl")),
    (
        "preview/fermat.wgsl",
        include_str!("../../wgsl/preview/fermat.wgsl"),
    ),
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
    /// Whether it reads any of the scene group's bindings, and so takes that group.
    pub fn reads_scene(&self) -> bool {
        self.bindings.iter().any(|b| group_of(b) == SCENE_GROUP)
    }

    /// Its own bindings: those of its group [`KERNEL_GROUP`], in binding order.
    pub fn own_bindings(&self) -> impl Iterator<Item = &'static Binding> {
        self.bindings.iter().filter(|b| group_of(b) == KERNEL_GROUP)
    }

    /// Storage buffers its pipeline layout binds, the whole scene group's included (adapters
    /// limit them per shader stage, counted over the layout, not over what the shader reads).
    pub fn storage_buffers(&self) -> u32 {
        let scene = match self.reads_scene() {
            true => SCENE_BINDINGS
                .iter()
                .filter(|b| b.access.is_storage())
                .count(),
            false => 0,
        };
        (scene
            + self
                .own_bindings()
                .filter(|b| b.access.is_storage())
                .count()) as u32
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
        "bsdf.wgsl",
        "texture.wgsl",
        "environment.wgsl",
        "integrator.wgsl",
        "render.wgsl",
    ],
    entry_point: "render",
    bindings: RENDER_BINDINGS,
};

/// The wavefront render's modules: the megakernel's, whose functions its stages share, and its own.
const WAVEFRONT_MODULES: &[&str] = &[
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
    "bsdf.wgsl",
    "texture.wgsl",
    "environment.wgsl",
    "path.wgsl",
    "integrator.wgsl",
    "render.wgsl",
    "wavefront.wgsl",
];

/// The wavefront render's camera rays: one path per camera sample of the dispatch.
pub const WF_CAMERA: Kernel = Kernel {
    name: "wf_camera",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_camera",
    bindings: &[
        CAMERA,
        FRAME,
        PASS_INFO,
        STATUS,
        SAMPLE_TABLE,
        PIXEL_LIST,
        WAVE,
        WF_RAYS,
        WF_PATHS,
        WF_QUEUE,
        WF_ARGS_IN,
    ],
};

/// The wavefront render's closest hits: one ray an invocation, as the ray queries trace them.
pub const WF_CLOSEST: Kernel = Kernel {
    name: "wf_closest",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_closest",
    bindings: &[
        FRAME, PASS_INFO, PRIMS, STATUS, CW_NODES, WF_HITS, WAVE, WF_RAYS, WF_QUEUE, WF_ARGS_IN,
    ],
};

/// The wavefront render's shading: what a vertex adds without shadow rays, its shadow rays and
/// its mirror bounce, queued.
pub const WF_SHADE: Kernel = Kernel {
    name: "wf_shade",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_shade",
    bindings: &[
        FRAME,
        PASS_INFO,
        PRIMS,
        NORMALS,
        MATERIALS,
        LIGHTS,
        STATUS,
        SAMPLE_TABLE,
        WF_HITS,
        WAVE,
        WF_RAYS,
        WF_PATHS,
        WF_QUEUE,
        WF_COUNTERS,
        WF_ARGS_IN,
        WF_SHADOW_RAYS,
        WF_SHADOW_TERMS,
        WF_SHADOW_QUEUE,
        WF_AOVS,
        TEXCOORDS,
        TEXTURES,
        TEXELS,
        ENVIRONMENT,
    ],
};

/// The wavefront render's indirect dispatches of a depth, from its queues' counters.
pub const WF_PREPARE: Kernel = Kernel {
    name: "wf_prepare",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_prepare",
    bindings: &[WAVE, WF_COUNTERS, WF_ARGS],
};

/// The wavefront render's shadow rays: one any-hit query an invocation.
pub const WF_OCCLUDED: Kernel = Kernel {
    name: "wf_occluded",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_occluded",
    bindings: &[
        FRAME,
        PASS_INFO,
        PRIMS,
        STATUS,
        CW_NODES,
        WAVE,
        WF_ARGS_IN,
        WF_SHADOW_RAYS,
        WF_SHADOW_TERMS,
        WF_SHADOW_QUEUE,
    ],
};

/// The wavefront render's direct light: each path vertex's visible shadow terms, summed.
pub const WF_RESOLVE: Kernel = Kernel {
    name: "wf_resolve",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_resolve",
    bindings: &[
        PASS_INFO,
        LIGHTS,
        STATUS,
        WAVE,
        WF_PATHS,
        WF_QUEUE,
        WF_ARGS_IN,
        WF_SHADOW_TERMS,
    ],
};

/// The wavefront render's pixel sums: a pixel's samples added in order and committed.
pub const WF_ACCUMULATE: Kernel = Kernel {
    name: "wf_accumulate",
    modules: WAVEFRONT_MODULES,
    entry_point: "wf_accumulate",
    bindings: &[
        CAMERA,
        FRAME,
        PASS_INFO,
        ACCUMULATION,
        STATUS,
        SAMPLE_TABLE,
        PIXEL_LIST,
        WF_PATHS,
        WF_AOVS,
    ],
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
    bindings: TRACE_BINDINGS,
};

/// Any hit of each ray of a buffer (the ray benchmark).
pub const TRACE_ANY: Kernel = Kernel {
    name: "trace_any",
    modules: TRACE_MODULES,
    entry_point: "trace_any",
    bindings: TRACE_BINDINGS,
};

/// Closest hit of each ray of a buffer through the compressed wide BVH (the ray benchmark).
pub const TRACE_CLOSEST_CW: Kernel = Kernel {
    name: "trace_closest_cw",
    modules: TRACE_MODULES,
    entry_point: "trace_closest_cw",
    bindings: TRACE_CW_BINDINGS,
};

/// Any hit of each ray of a buffer through the compressed wide BVH (the ray benchmark).
pub const TRACE_ANY_CW: Kernel = Kernel {
    name: "trace_any_cw",
    modules: TRACE_MODULES,
    entry_point: "trace_any_cw",
    bindings: TRACE_CW_BINDINGS,
};

/// Reflection points of vertices on a curved mirror by Fermat's principle, one invocation per
/// vertex, one pipeline per kind of mirror (`preview::reflections::kernel`; CPU twin `fermat::Solver`).
pub const FERMAT: Kernel = Kernel {
    name: "fermat",
    modules: &["types.wgsl", "bindings.wgsl", "preview/fermat.wgsl"],
    entry_point: "fermat",
    bindings: FERMAT_BINDINGS,
};

/// A Bézier patch's corner B for each vertex, where the segment from the vertex to the patch's
/// inside point O crosses it (`fermat::BezierPatch::crossing`): Newton's steps that depend on
/// the vertex and the patch, not on the eye, so run once for a set of vertices rather than in
/// every frame's `fermat` (`preview::reflections::kernel::FermatPass::solve`).
pub const FERMAT_START: Kernel = Kernel {
    name: "fermat_start",
    modules: FERMAT.modules,
    entry_point: "fermat_start",
    bindings: FERMAT_START_BINDINGS,
};

/// The preview's reflected triangles whose three vertices' reflections show on one curved
/// mirror, listed for an indirect draw, one invocation per triangle (CPU twin:
/// `fermat::drawn_in_preview` per vertex): the draw then runs the vertex stage for those only.
pub const FERMAT_CULL: Kernel = Kernel {
    name: "fermat_cull",
    modules: FERMAT.modules,
    entry_point: "fermat_cull",
    bindings: FERMAT_CULL_BINDINGS,
};

/// Every kernel chambre builds.
pub const KERNELS: [&Kernel; 15] = [
    &RENDER,
    &WF_CAMERA,
    &WF_CLOSEST,
    &WF_SHADE,
    &WF_PREPARE,
    &WF_OCCLUDED,
    &WF_RESOLVE,
    &WF_ACCUMULATE,
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

/// A pipeline and the layouts of the bind groups it takes.
pub struct Pipeline {
    /// The kernel compiled for one feature set.
    pub pipeline: wgpu::ComputePipeline,
    /// The scene group's layout, made from [`SCENE_BINDINGS`], where the kernel reads the
    /// scene: the same for every kernel (wgpu pools equal layouts), so one bind group made
    /// with any kernel's serves them all.
    pub scene_layout: Option<wgpu::BindGroupLayout>,
    /// Made from the kernel's own bindings: group [`KERNEL_GROUP`] of the pipeline.
    pub kernel_layout: wgpu::BindGroupLayout,
    /// The kernel it was built from.
    pub kernel: &'static Kernel,
}

named_enum! {
    /// Which of the checks wgpu adds to a shader at run time a kernel is built with.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
    pub enum ShaderChecks {
        /// wgpu's own: every array index bounded (beyond what the driver's robust buffer access
        /// already bounds), every loop bounded by a counter, every integer division guarded.
        #[default]
        All = "all",
        /// All but the loop counters: every loop of chambre's kernels ends by construction (a
        /// traversal by `GpuFrame::traversal_cap`, which it reports; a bit loop when its bits run
        /// out; the others at a count from a uniform), so the counter only costs time.
        NoLoopBounding = "no-loop-bounding",
        /// None of them: for measuring what the checks cost, not for rendering.
        None = "none",
    }
}

impl ShaderChecks {
    fn runtime_checks(self) -> wgpu::ShaderRuntimeChecks {
        let mut checks = wgpu::ShaderRuntimeChecks::checked();
        match self {
            ShaderChecks::All => {}
            ShaderChecks::NoLoopBounding => checks.force_loop_bounding = false,
            ShaderChecks::None => {
                checks.force_loop_bounding = false;
                checks.bounds_checks = false;
                checks.int_div_checks = false;
            }
        }
        checks
    }
}

/// Builds `kernel` specialised to `features`. Validation errors come back through the
/// device's error handling (see `GpuContext`), not as panics.
pub fn build_pipeline(device: &wgpu::Device, kernel: &'static Kernel, features: u32) -> Pipeline {
    build_pipeline_with(device, kernel, features, &[], ShaderChecks::default())
}

/// [`build_pipeline`], with values for the kernel's own override constants too (e.g. the
/// fermat kernel's `FERMAT_STEPS`), and the shader checks `checks`.
pub fn build_pipeline_with(
    device: &wgpu::Device,
    kernel: &'static Kernel,
    features: u32,
    overrides: &[(&'static str, f64)],
    checks: ShaderChecks,
) -> Pipeline {
    let descriptor = wgpu::ShaderModuleDescriptor {
        label: Some(kernel.name),
        source: wgpu::ShaderSource::Wgsl(kernel_source(kernel).into()),
    };
    // SAFETY: the checks left out are those `ShaderChecks` documents as unneeded: chambre's
    // loops all end (the loop counters), and `ShaderChecks::None` only measures.
    let module =
        unsafe { device.create_shader_module_trusted(descriptor, checks.runtime_checks()) };
    let scene_layout = kernel
        .reads_scene()
        .then(|| bind_group_layout(device, "scene", &SCENE_BINDINGS));
    let own: Vec<Binding> = kernel.own_bindings().copied().collect();
    let kernel_layout = bind_group_layout(device, kernel.name, &own);
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(kernel.name),
        bind_group_layouts: &[scene_layout.as_ref(), Some(&kernel_layout)],
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
        scene_layout,
        kernel_layout,
        kernel,
    }
}

/// The entries of a bind group of `bindings`, each from `buffers` (binding, buffer; any order,
/// more than needed allowed); `whose` names the bind group in the error for a missing one.
fn bind_group_entries<'b, 'a>(
    bindings: impl Iterator<Item = &'b Binding>,
    buffers: &[(Binding, &'a wgpu::Buffer)],
    whose: &str,
) -> Result<Vec<wgpu::BindGroupEntry<'a>>> {
    let mut entries = Vec::new();
    for b in bindings {
        let (_, buffer) = buffers
            .iter()
            .find(|(given, _)| given.binding == b.binding)
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "{whose}: no buffer for binding {} `{}`",
                    b.binding, b.name
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
    Ok(entries)
}

impl Pipeline {
    /// The scene group of `buffers` (binding, buffer; any order, more than the group holds
    /// allowed): every binding of [`SCENE_BINDINGS`] must be given, those the kernel does not
    /// read too (the group serves every kernel). `None` for a kernel that reads no scene.
    pub fn scene_bind_group(
        &self,
        device: &wgpu::Device,
        buffers: &[(Binding, &wgpu::Buffer)],
    ) -> Result<Option<wgpu::BindGroup>> {
        let Some(layout) = &self.scene_layout else {
            return Ok(None);
        };
        let entries = bind_group_entries(SCENE_BINDINGS.iter(), buffers, "the scene group")?;
        Ok(Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout,
            entries: &entries,
        })))
    }

    /// The kernel's own group of `buffers` (binding, buffer; any order, more than the kernel
    /// reads allowed); every binding of it must be given.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        buffers: &[(Binding, &wgpu::Buffer)],
    ) -> Result<wgpu::BindGroup> {
        let whose = format!("kernel {}", self.kernel.name);
        let entries = bind_group_entries(self.kernel.own_bindings(), buffers, &whose)?;
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.kernel.name),
            layout: &self.kernel_layout,
            entries: &entries,
        }))
    }

    /// Binds `scene` (where the kernel reads it) and the kernel's own `group` at `offsets`
    /// (`dynamic_offsets`) for the dispatches that follow on `compute`. A kernel that reads the
    /// scene dispatched without its group is a validation error wgpu reports, not a panic.
    pub fn set_bind_groups(
        &self,
        compute: &mut wgpu::ComputePass<'_>,
        scene: Option<&wgpu::BindGroup>,
        group: &wgpu::BindGroup,
        offsets: &[u32],
    ) {
        if let (Some(_), Some(scene)) = (&self.scene_layout, scene) {
            compute.set_bind_group(SCENE_GROUP, scene, &[]);
        }
        compute.set_bind_group(KERNEL_GROUP, group, offsets);
    }

    /// The dynamic offsets of the kernel's own bind group, in binding order: `offset` of each
    /// of its bindings bound at a dynamic offset (the scene group has none).
    pub fn dynamic_offsets(&self, offset: impl Fn(&Binding) -> u32) -> Vec<u32> {
        self.kernel
            .own_bindings()
            .filter(|b| b.dynamic_size > 0)
            .map(offset)
            .collect()
    }
}
