//! Every struct and constant shared by the Rust reference path and the WGSL kernels.
//!
//! The CPU reference renders from the very same flattened arrays the GPU reads (pbrt's and
//! Mitsuba's "one scene, two traversals"), so a parity test compares two implementations of the
//! same scene, not two scenes. Each struct has a WGSL twin of the same name and field names in
//! `wgsl/types.wgsl`; `tests/wgsl.rs` checks sizes and offsets with naga, and the constants
//! below are emitted into every composed kernel by [`wgsl_prelude`], never written twice.

use bytemuck::{Pod, Zeroable};

/// Kernel workgroup edge: a workgroup covers `WORKGROUP_SIZE x WORKGROUP_SIZE` pixels.
pub const WORKGROUP_SIZE: u32 = 8;
/// Invocations per workgroup of the ray-query kernels (one ray each).
pub const TRACE_WORKGROUP_SIZE: u32 = 64;
/// Depth of the per-invocation BVH traversal stack. Deeper BVHs are refused before upload.
pub const BVH_STACK_SIZE: u32 = 64;
/// Node groups on the CWBVH traversal stack: one per level at most (`accel::cwbvh::build`
/// checks the tree's depth against it).
pub const CWBVH_STACK_SIZE: u32 = 32;
/// Finite stand-in for an unbounded ray: WGSL may assume infinities never occur.
pub const T_FAR: f32 = 1.0e30;
/// Marks "no primitive" / "no normals" in index fields.
pub const NONE: u32 = u32::MAX;

/// Primitive kinds (`GpuPrimitive::kind`).
pub const PRIM_TRIANGLE: u32 = 0;
pub const PRIM_SPHERE: u32 = 1;
pub const PRIM_QUAD: u32 = 2;
pub const PRIM_PLANE: u32 = 3;

/// Material models (`GpuMaterial::model`); every model also carries a perfect-mirror term.
pub const MODEL_LAMBERT: u32 = 0;
pub const MODEL_PHONG: u32 = 1;
pub const MODEL_BLINN_PHONG: u32 = 2;
/// The one-sided emitting surface of an area light.
pub const MODEL_EMITTER: u32 = 3;

/// Light kinds (`GpuLight::kind`).
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_DIRECTIONAL: u32 = 1;
pub const LIGHT_AREA: u32 = 2;
/// An emitting triangle (an OBJ face with `Ke`): `p0` a vertex, `p1` and `p2` the edges to
/// the others; sampled by folding the unit square onto the triangle.
pub const LIGHT_TRIANGLE: u32 = 3;

/// Sample patterns (`GpuFrame::pixel_sampler`, `GpuFrame::lens_sampler`); see `src/sampler.rs`.
pub const SAMPLER_RANDOM: u32 = 0;
pub const SAMPLER_STRATIFIED: u32 = 1;
pub const SAMPLER_POISSON: u32 = 2;
pub const SAMPLER_INTERLEAVED: u32 = 3;
pub const SAMPLER_SOBOL: u32 = 4;
/// Cap on the cycle-walking loop of the stratified sampler's permutation (`sampler::permute`).
pub const PERMUTE_WALK_CAP: u32 = 64;
/// Random dimensions of the pixel position and of the lens point.
pub const PIXEL_DIMENSION: u32 = 0;
pub const LENS_DIMENSION: u32 = 2;
/// First random dimension of the area-light samples. Light sample `k` of the area light whose
/// samples start at `offset`, at path vertex `depth`, draws dimensions
/// `LIGHT_DIMENSION + 2 * (depth * frame.light_samples_per_vertex + offset + k)` and the next
/// one: any window of light samples can then be evaluated on its own (`GpuPass`).
pub const LIGHT_DIMENSION: u32 = 4;
/// Poisson-disk sets in the sample table; a pixel picks one by hash and shifts it.
pub const POISSON_SETS: u32 = 16;
/// Interleaved sampling repeats a tile of INTERLEAVED_TILE x INTERLEAVED_TILE basis patterns.
pub const INTERLEAVED_TILE: u32 = 3;

/// Scene features a kernel variant can leave out. On the GPU each is a pipeline-overridable
/// `bool` constant of the same name (true in the general kernel); on the CPU a bit of the
/// integrator's const generic. A variant built without a feature the scene has is wrong, so the
/// bits are always computed from the scene (`pack::FlatScene::features`).
pub const FEATURE_LENS: u32 = 1;
pub const FEATURE_MIRRORS: u32 = 2;
pub const FEATURE_AREA_LIGHTS: u32 = 4;
pub const FEATURE_PUNCTUAL_LIGHTS: u32 = 8;
pub const FEATURE_TRIANGLES: u32 = 16;
pub const FEATURE_PLANES: u32 = 32;
/// Every feature: the general kernel.
pub const FEATURES_ALL: u32 = 63;
/// Whether the feature set `features` has `bit` (a `FEATURE_*`); const, for the CPU
/// integrator's const generic.
pub const fn has(features: u32, bit: u32) -> bool {
    features & bit != 0
}

/// (WGSL override name, bit) of every feature.
pub const FEATURES: [(&str, u32); 6] = [
    ("FEATURE_LENS", FEATURE_LENS),
    ("FEATURE_MIRRORS", FEATURE_MIRRORS),
    ("FEATURE_AREA_LIGHTS", FEATURE_AREA_LIGHTS),
    ("FEATURE_PUNCTUAL_LIGHTS", FEATURE_PUNCTUAL_LIGHTS),
    ("FEATURE_TRIANGLES", FEATURE_TRIANGLES),
    ("FEATURE_PLANES", FEATURE_PLANES),
];

/// Bits of the status word: a kernel loop hit its cap.
pub const STATUS_TRAVERSAL_CAP: u32 = 1;
pub const STATUS_STACK_OVERFLOW: u32 = 2;
/// The stratified sampler's permutation walk hit `PERMUTE_WALK_CAP` (its sample order then
/// repeats a stratum).
pub const STATUS_PERMUTE_CAP: u32 = 4;
/// The driver stopped the kernel's loops early. lavapipe (Mesa's llvmpipe) ends every loop of
/// an invocation, silently, once 65535 loop iterations have run in total (its
/// LP_MAX_TGSI_LOOP_ITERATIONS); `render.wgsl` detects it with a loop of `LOOP_CHECK_ITERATIONS`
/// run-time iterations at the end of the kernel, which then runs fewer.
pub const STATUS_LOOP_LIMIT: u32 = 8;
/// Trip count of the loop-limit check (`GpuPass::loop_check`); any value above 1 works.
pub const LOOP_CHECK_ITERATIONS: u32 = 2;
/// Light samples follow the pixel pattern over all of a pixel's `spp x samples` light points
/// while there are at most this many (`sampler::light_sample_2d`); beyond, each camera sample's
/// light samples are stratified on their own.
pub const MAX_LIGHT_PATTERN_POINTS: u32 = 1 << 24;
/// Slots of the status buffer (`array<atomic<u32>, STATUS_WORDS>`).
pub const STATUS_FLAGS: u32 = 0;
pub const STATUS_RAYS: u32 = 1;
pub const STATUS_TRUNCATED: u32 = 2;
pub const STATUS_WORDS: u32 = 4;

/// A BVH node: obvhs's `Bvh2Node` without its spare fields. Inner node: `prim_count == 0` and
/// children at `first_index` and `first_index + 1`. Leaf: primitives
/// `first_index .. first_index + prim_count` of the primitive array, already in BVH order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    pub min: [f32; 3],
    pub prim_count: u32,
    pub max: [f32; 3],
    pub first_index: u32,
}

/// A node of the compressed wide BVH (CWBVH, Ylitie et al. 2017): obvhs's `CwBvhNode`, its
/// bytes read as little-endian words. Eight children, each box quantised to 8 bits per plane on
/// the grid `p + q * 2^(e - 127)`; `child_meta` holds each child's byte (leaf: primitive offset and
/// unary count; inner: 24 + slot), `e_imask` the three exponents and the inner-child mask.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCwNode {
    pub p: [f32; 3],
    pub e_imask: u32,
    pub child_base: u32,
    pub prim_base: u32,
    pub child_meta: [u32; 2],
    pub q_lo_x: [u32; 2],
    pub q_hi_x: [u32; 2],
    pub q_lo_y: [u32; 2],
    pub q_hi_y: [u32; 2],
    pub q_lo_z: [u32; 2],
    pub q_hi_z: [u32; 2],
}

/// One primitive. Triangle: `p0, p1, p2` are its vertices, `normals` indexes `GpuNormals` or is
/// `NONE`. Sphere: `p0` centre, `p1.x` radius, `p1.y` |centre|^2 - radius^2 (rounded once from
/// f64). Quad: `p0` corner, `p1` edge_u, `p2` edge_v. Plane: `p0` a point, `p1` the unit normal.
/// Planes are unbounded and live after the BVH's primitives (`GpuFrame::plane_start`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPrimitive {
    pub p0: [f32; 3],
    pub kind: u32,
    pub p1: [f32; 3],
    pub material: u32,
    pub p2: [f32; 3],
    pub normals: u32,
}

/// Vertex normals of a smooth triangle, n0, n1, n2 packed as 9 floats.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNormals {
    pub n: [f32; 9],
}

/// Material parameters; radiometry as in pbrt: Lambert BRDF = diffuse / pi.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub diffuse: [f32; 3],
    pub model: u32,
    pub specular: [f32; 3],
    pub shininess: f32,
    pub mirror: [f32; 3],
    pub _pad0: u32,
    pub emission: [f32; 3],
    pub _pad1: u32,
}

/// A light. Point: `p0` position, `color` intensity (W/sr). Directional: `p0` unit vector
/// towards the light, `color` irradiance. Area: `p0` corner, `p1` edge_u, `p2` edge_v, `color`
/// radiance, `samples` shadow rays, `prim` its emitting quad (skipped by its own shadow rays).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub p0: [f32; 3],
    pub kind: u32,
    pub p1: [f32; 3],
    pub samples: u32,
    pub p2: [f32; 3],
    pub prim: u32,
    pub color: [f32; 3],
    /// Columns of the area light's sample strata (`math::sampling::strata_columns(samples)`).
    pub strata_columns: u32,
}

/// The camera as ray generation needs it (see `docs/camera.md`). Lengths on the film and lens are
/// in millimetres in the *lens frame* (lens plane z = 0, optical axis +z, x right, y up);
/// `lens_to_world_*` are the lens frame's axes in world space and `lens_center` its origin.
/// A film point for image coordinates (x, y) in mm is `film_center + x * film_u + y * film_v`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    pub lens_to_world_x: [f32; 3],
    pub focal_length_mm: f32,
    pub lens_to_world_y: [f32; 3],
    pub lens_radius_mm: f32,
    pub lens_to_world_z: [f32; 3],
    /// Scene units per millimetre (lens points are in mm, ray origins in scene units).
    pub units_per_mm: f32,
    pub lens_center: [f32; 3],
    /// 1 / focal length (1/mm): the ray-transfer refraction term.
    pub inv_focal_length_mm: f32,
    pub film_center: [f32; 3],
    pub film_width_mm: f32,
    pub film_u: [f32; 3],
    pub film_height_mm: f32,
    pub film_v: [f32; 3],
    /// 0: circular aperture; n >= 3: regular polygon whose unit-circle vertices are
    /// `sample_table[aperture_table_offset ..= aperture_table_offset + n]` (first one repeated).
    pub aperture_blades: u32,
    pub aperture_table_offset: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Settings constant over one render.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuFrame {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub pixel_sampler: u32,
    pub light_count: u32,
    pub node_count: u32,
    pub plane_start: u32,
    pub plane_count: u32,
    /// Node-pair visits allowed per traversal before the kernel gives up and flags it.
    pub traversal_cap: u32,
    /// Columns of the pixel-sample strata (`math::sampling::strata_columns(spp)`).
    pub pixel_strata_columns: u32,
    pub lens_sampler: u32,
    pub lens_strata_columns: u32,
    /// Where the pixel / lens sampler's precomputed patterns start in the sample table.
    pub pixel_table_offset: u32,
    pub lens_table_offset: u32,
    pub background: [f32; 3],
    /// Shadow-ray samples of all area lights at one path vertex (the sum of their `samples`).
    pub light_samples_per_vertex: u32,
    pub ambient: [f32; 3],
    pub _pad2: u32,
}

/// What one dispatch renders: a rectangle of pixels (whole rows: a band), a range of sample
/// indices, and a window of every area light's shadow-ray samples. A pass whose light samples
/// need several windows (dispatches) sums them in a scratch buffer and commits the sum to the
/// accumulation with the last window, so the accumulation is a valid mean after every dispatch
/// (see `render.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPass {
    pub tile_x: u32,
    pub tile_y: u32,
    pub tile_width: u32,
    pub tile_height: u32,
    pub sample_start: u32,
    pub sample_count: u32,
    /// Light samples `light_sample_start .. light_sample_start + light_sample_count` of each
    /// area light; the window starting at 0 also adds everything else (emission, ambient,
    /// point and directional lights, background).
    pub light_sample_start: u32,
    pub light_sample_count: u32,
    /// 1 when this window is the pass's last: the scratch sum is committed.
    pub commit: u32,
    /// Always `LOOP_CHECK_ITERATIONS`; a uniform so no compiler can fold the check away.
    pub loop_check: u32,
    /// 0: the invocations cover the band's pixels. Otherwise the band's rows (`tile_width`
    /// entries each) index a list of this many pixels (adaptive sampling's unconverged ones).
    pub listed_pixels: u32,
    /// Where in the accumulation buffer (in pixels) the committed sums go: the first or the
    /// second half of an adaptive render (`render::AccumulationLayout`).
    pub accumulation_offset: u32,
    /// Where (in pixels) the scratch sums of a pass split into light windows live.
    pub scratch_offset: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl GpuPass {
    pub fn is_first_light_window(&self) -> bool {
        self.light_sample_start == 0
    }
}

const _: () = assert!(
    FEATURES_ALL
        == FEATURE_LENS
            | FEATURE_MIRRORS
            | FEATURE_AREA_LIGHTS
            | FEATURE_PUNCTUAL_LIGHTS
            | FEATURE_TRIANGLES
            | FEATURE_PLANES
);
/// A ray of the ray benchmark's buffer (`wgsl/trace.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    pub origin: [f32; 3],
    pub t_max: f32,
    pub direction: [f32; 3],
    pub _pad0: u32,
}

impl GpuLight {
    /// An area light, parallelogram or triangle: sampled with `samples` shadow rays.
    pub fn is_area(&self) -> bool {
        self.kind == LIGHT_AREA || self.kind == LIGHT_TRIANGLE
    }
}

const _: () = assert!(size_of::<GpuRay>() == 32);
const _: () = assert!(size_of::<GpuBvhNode>() == 32);
const _: () = assert!(size_of::<GpuCwNode>() == 80);
const _: () = assert!(size_of::<GpuPrimitive>() == 48);
const _: () = assert!(size_of::<GpuNormals>() == 36);
const _: () = assert!(size_of::<GpuMaterial>() == 64);
const _: () = assert!(size_of::<GpuLight>() == 64);
const _: () = assert!(size_of::<GpuCamera>() == 128);
const _: () = assert!(size_of::<GpuFrame>() == 96);
const _: () = assert!(size_of::<GpuPass>() == 64);

/// WGSL `const` declarations for every constant above, emitted at the top of each kernel.
pub fn wgsl_prelude() -> String {
    let u32s = [
        ("WORKGROUP_SIZE", WORKGROUP_SIZE),
        ("TRACE_WORKGROUP_SIZE", TRACE_WORKGROUP_SIZE),
        ("BVH_STACK_SIZE", BVH_STACK_SIZE),
        ("CWBVH_STACK_SIZE", CWBVH_STACK_SIZE),
        ("MAX_LIGHT_PATTERN_POINTS", MAX_LIGHT_PATTERN_POINTS),
        ("NONE", NONE),
        ("PRIM_TRIANGLE", PRIM_TRIANGLE),
        ("PRIM_SPHERE", PRIM_SPHERE),
        ("PRIM_QUAD", PRIM_QUAD),
        ("PRIM_PLANE", PRIM_PLANE),
        ("MODEL_LAMBERT", MODEL_LAMBERT),
        ("MODEL_PHONG", MODEL_PHONG),
        ("MODEL_BLINN_PHONG", MODEL_BLINN_PHONG),
        ("MODEL_EMITTER", MODEL_EMITTER),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("LIGHT_AREA", LIGHT_AREA),
        ("LIGHT_TRIANGLE", LIGHT_TRIANGLE),
        ("SAMPLER_RANDOM", SAMPLER_RANDOM),
        ("SAMPLER_STRATIFIED", SAMPLER_STRATIFIED),
        ("SAMPLER_POISSON", SAMPLER_POISSON),
        ("SAMPLER_INTERLEAVED", SAMPLER_INTERLEAVED),
        ("SAMPLER_SOBOL", SAMPLER_SOBOL),
        ("POISSON_SETS", POISSON_SETS),
        ("PERMUTE_WALK_CAP", PERMUTE_WALK_CAP),
        ("PIXEL_DIMENSION", PIXEL_DIMENSION),
        ("LENS_DIMENSION", LENS_DIMENSION),
        ("LIGHT_DIMENSION", LIGHT_DIMENSION),
        ("INTERLEAVED_TILE", INTERLEAVED_TILE),
        ("STATUS_TRAVERSAL_CAP", STATUS_TRAVERSAL_CAP),
        ("STATUS_STACK_OVERFLOW", STATUS_STACK_OVERFLOW),
        ("STATUS_PERMUTE_CAP", STATUS_PERMUTE_CAP),
        ("STATUS_LOOP_LIMIT", STATUS_LOOP_LIMIT),
        ("STATUS_FLAGS", STATUS_FLAGS),
        ("STATUS_RAYS", STATUS_RAYS),
        ("STATUS_TRUNCATED", STATUS_TRUNCATED),
        ("STATUS_WORDS", STATUS_WORDS),
    ];
    let mut out = String::from("// Generated from src/layout.rs: do not edit.\n");
    for (name, value) in u32s {
        out += &format!("const {name}: u32 = {value}u;\n");
    }
    out += &format!("const T_FAR: f32 = {T_FAR:e};\n");
    for (name, _) in FEATURES {
        out += &format!("override {name}: bool = true;\n");
    }
    out
}
