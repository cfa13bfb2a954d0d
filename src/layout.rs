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
/// Workgroups a dispatch may have along one dimension (WebGPU's limit): a longer 1-D grid of
/// the wavefront render goes on in further rows of this many (`wgsl/wavefront.wgsl`).
pub const MAX_WORKGROUPS_PER_DIMENSION: u32 = 65535;
/// The wavefront render's counter of the paths queued for the next depth (`wf_counters`).
pub const WF_PATH_COUNTER: u32 = 0;
/// The wavefront render's counter of the shadow rays a depth's vertices emitted.
pub const WF_SHADOW_COUNTER: u32 = 1;
/// Words of the wavefront render's counters.
pub const WF_COUNTERS: u32 = 2;
/// Depth of the per-invocation BVH traversal stack. Deeper BVHs are refused before upload.
pub const BVH_STACK_SIZE: u32 = 64;
/// Node groups on the CWBVH traversal stack: one per level at most (`accel::cwbvh::build`
/// checks the tree's depth against it).
pub const CWBVH_STACK_SIZE: u32 = 32;
/// Finite stand-in for an unbounded ray: WGSL may assume infinities never occur.
pub const T_FAR: f32 = 1.0e30;
/// Marks "no primitive" / "no normals" in index fields.
pub const NONE: u32 = u32::MAX;

/// Primitive kinds (`GpuPrimitive::kind`; fields per kind on [`GpuPrimitive`]): a triangle.
pub const PRIM_TRIANGLE: u32 = 0;
/// A sphere.
pub const PRIM_SPHERE: u32 = 1;
/// A parallelogram (a quad shape, or an area light's emitting surface).
pub const PRIM_QUAD: u32 = 2;
/// An infinite plane, tested outside the BVH.
pub const PRIM_PLANE: u32 = 3;
/// An ellipsoid, turned about its centre.
pub const PRIM_ELLIPSOID: u32 = 4;
/// An open cylinder around an axis through its base centre.
pub const PRIM_CYLINDER: u32 = 5;
/// A torus around an axis through its centre.
pub const PRIM_TORUS: u32 = 6;

/// Whether the rays leaving a primitive of `kind` (shadow rays, mirror bounces) may skip it:
/// they cannot meet it again when it is flat, nor when it is convex (a sphere, an ellipsoid)
/// and they leave from its `outside`. A torus, a cylinder, or a convex shape's inside (a point
/// inside a sphere, lit from outside, is shadowed by the sphere itself) must be tested again.
pub const fn leaving_rays_skip(kind: u32, outside: bool) -> bool {
    match kind {
        PRIM_SPHERE | PRIM_ELLIPSOID => outside,
        PRIM_CYLINDER | PRIM_TORUS => false,
        _ => true,
    }
}

/// Newton steps (each falling back to bisection when it would leave its bracket) that find a
/// torus's root (`accel::curved`): 24 bisections alone narrow a bracket of the span (at most 2.5
/// in units of R + r) to f32's resolution, so the root is as precise as f32 allows when the
/// cap is reached, and reaching it is not an error to report.
pub const TORUS_ROOT_STEPS: u32 = 24;

/// Newton steps on the torus's signed distance that polish the quartic's root
/// (`accel::curved`): each squares the relative error of a simple root.
pub const TORUS_POLISH_STEPS: u32 = 2;

/// How far beyond its bounding sphere (in units of R + r) a ray's span is searched for a
/// torus's roots: the equator touches that sphere, and a hit there must not be lost to rounding.
pub const TORUS_MARGIN: f32 = 0.25;

/// The polish may move a torus's root by at most this many times the root's own error bound
/// (farther, Newton's step on the distance could leave for another root).
pub const TORUS_POLISH_REACH: f32 = 16.0;

/// `GpuReflector::kind`: a sphere.
pub const REFLECTOR_SPHERE: u32 = 0;
/// `GpuReflector::kind`: a torus around the vertical axis through its centre.
pub const REFLECTOR_TORUS: u32 = 1;
/// `GpuReflector::kind`: a bicubic Bézier patch (`GpuReflector::control`).
pub const REFLECTOR_PATCH: u32 = 2;
/// `GpuReflector::kind`: an ellipsoid with semi-axes `GpuReflector::radii` along the world axes.
pub const REFLECTOR_ELLIPSOID: u32 = 3;
/// `GpuReflector::kind`: a cylinder around the vertical axis through its centre, of
/// `GpuReflector::height` above it.
pub const REFLECTOR_CYLINDER: u32 = 4;

/// Material models (`GpuMaterial::model`); every model also carries a perfect-mirror term.
/// Lambert: diffuse only (BRDF diffuse / pi); the scene format's `mirror` model is Lambert too.
pub const MODEL_LAMBERT: u32 = 0;
/// Diffuse plus a normalised Phong lobe, ks (n + 2) / (2 pi) cos^n(alpha).
pub const MODEL_PHONG: u32 = 1;
/// Diffuse plus a normalised Blinn-Phong lobe, ks (n + 8) / (8 pi) cos^n(theta_h).
pub const MODEL_BLINN_PHONG: u32 = 2;
/// The one-sided emitting surface of an area light.
pub const MODEL_EMITTER: u32 = 3;
/// A smooth dielectric (glass): Fresnel reflection and refraction at `GpuMaterial::ior`, no
/// other term; the path tracer's only.
pub const MODEL_DIELECTRIC: u32 = 4;
/// A rough conductor: a GGX microfacet lobe with Smith's separable shadowing and a Fresnel
/// factor of 1, f = ks D G1(wo) G1(wi) / (4 cos_o cos_i), of reflectance `specular` and
/// roughness alpha in `shininess` (Mitsuba's `roughconductor` of material `none`).
pub const MODEL_ROUGH_CONDUCTOR: u32 = 5;

/// Focal surfaces (`GpuCamera::focus_surface`): the thin lens's plane.
pub const FOCUS_PLANE: u32 = 0;
/// A sphere centred on the lens (field curvature, as real lenses have).
pub const FOCUS_SPHERE: u32 = 1;
/// A cylinder whose axis is the lens's vertical through its centre.
pub const FOCUS_CYLINDER: u32 = 2;

/// Projections (`GpuCamera::projection`): rays through a lens centre (pinhole or thin lens).
pub const PROJECTION_PERSPECTIVE: u32 = 0;
/// Parallel rays along the viewing axis from a window (docs/camera.md, "Orthographic camera").
pub const PROJECTION_ORTHOGRAPHIC: u32 = 1;
/// Through a real lens's prescription (docs/lens.md): rays from the film traced through its
/// surfaces, each with the weight its exit-pupil bounds give it.
pub const PROJECTION_LENS: u32 = 2;
/// Cells across the film, in each direction, of a real lens's exit-pupil bounds table.
pub const LENS_PUPIL_CELLS: u32 = 16;
/// The spectral mode's wavelengths (nm, `camera.spectral`): a camera sample's wavelength is
/// drawn uniformly from [SPECTRAL_MIN_NM, SPECTRAL_MAX_NM] (docs/lens.md, "Spectral mode").
pub const SPECTRAL_MIN_NM: u32 = 380;
/// The longest wavelength drawn (nm).
pub const SPECTRAL_MAX_NM: u32 = 740;
/// Where the film's blue and green bands cross (nm): each band is a third of the range, and
/// neighbours cross over linearly across `SPECTRAL_CROSSOVER_NM` (camera::spectral).
pub const SPECTRAL_BLUE_GREEN_NM: u32 = 500;
/// Where the green and red bands cross (nm).
pub const SPECTRAL_GREEN_RED_NM: u32 = 620;
/// The width of each band's linear crossover (nm).
pub const SPECTRAL_CROSSOVER_NM: u32 = 40;

/// Light kinds (`GpuLight::kind`; fields per kind on [`GpuLight`]): a point light.
pub const LIGHT_POINT: u32 = 0;
/// A directional light (light from infinitely far away, one direction).
pub const LIGHT_DIRECTIONAL: u32 = 1;
/// A one-sided parallelogram area light, sampled with `GpuLight::samples` shadow rays.
pub const LIGHT_AREA: u32 = 2;
/// An emitting triangle (an OBJ face with `Ke`): `p0` a vertex, `p1` and `p2` the edges to
/// the others; sampled by folding the unit square onto the triangle.
pub const LIGHT_TRIANGLE: u32 = 3;
/// A spot light: a point light at `p0` pointing along the unit `p1`, its intensity scaled by
/// `saturate(cos * p2.x + p2.y)^2` with `cos` between `p1` and the direction to the lit point
/// (KHR_lights_punctual's falloff from the inner to the outer cone).
pub const LIGHT_SPOT: u32 = 4;
/// An environment light: radiance from every direction at infinity, `color` times either 1 (a
/// constant environment: `p0.y` = 0) or the texel of an equirectangular map of `p0.y` x `p0.z`
/// texels (`FlatScene::environment`) turned by `p0.x` turns about +y; sampled with `samples`
/// shadow rays (`integrator::environment`). `p1` is its mean radiance (the raster preview's).
pub const LIGHT_ENVIRONMENT: u32 = 5;
/// A sun: a disc of uniform radiance at infinity seen within a cone about the unit `p0`
/// (towards the sun), `color` its irradiance at normal incidence; `p1` = (1 - cos alpha,
/// radiance per irradiance 1 / (pi sin^2 alpha), the cone's sampling density), `p2.x` the
/// radiance over that density per irradiance, 1 / cos^2(alpha / 2); sampled with `samples`
/// shadow rays.
pub const LIGHT_SUN: u32 = 6;

/// Sample patterns (`GpuFrame::pixel_sampler`, `GpuFrame::lens_sampler`); see `src/sampler.rs`.
/// Random: independent uniform points.
pub const SAMPLER_RANDOM: u32 = 0;
/// Stratified: one jittered point per stratum, strata visited in a hashed per-pixel order.
pub const SAMPLER_STRATIFIED: u32 = 1;
/// Poisson disk: one of `POISSON_SETS` precomputed sets, shifted per pixel.
pub const SAMPLER_POISSON: u32 = 2;
/// Interleaved (Keller and Heidrich): a tile of precomputed jittered patterns, no per-pixel
/// randomness.
pub const SAMPLER_INTERLEAVED: u32 = 3;
/// Owen-scrambled 2-D Sobol points.
pub const SAMPLER_SOBOL: u32 = 4;
/// The generator matrix of Sobol dimension 1 (polynomial x + 1: v_k = v_{k-1} ^ (v_{k-1} >> 1)),
/// the pixel pattern's second coordinate; the WGSL twin runs the recurrence in registers.
pub const SOBOL_MATRIX_1: [u32; 32] = sobol_matrix(1, 0, [1, 0, 0]);
/// The generator matrices (direction numbers, most significant bit first) of Sobol dimensions
/// 2 and 3 (Joe and Kuo's table: s = 2, a = 1, m = 1 3; s = 3, a = 1, m = 1 3 1): the lens
/// coordinates of the joint pixel x lens Sobol pattern (`sampler::sobol_owen_lens`). The WGSL
/// twin makes the same numbers by the recurrence in registers (`sobol_dimension_2` and `_3`).
pub const SOBOL_MATRIX_2: [u32; 32] = sobol_matrix(2, 1, [1, 3, 0]);
/// Sobol dimension 3's generator matrix (see [`SOBOL_MATRIX_2`]).
pub const SOBOL_MATRIX_3: [u32; 32] = sobol_matrix(3, 1, [1, 3, 1]);

/// Direction numbers v_1..v_32 of a Sobol dimension of degree `s`, polynomial coefficients `a`
/// and initial numbers `m` (Joe and Kuo's recurrence), as 32-bit fractions.
const fn sobol_matrix(s: usize, a: u32, m: [u32; 3]) -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < s {
        v[k] = m[k] << (31 - k);
        k += 1;
    }
    while k < 32 {
        let mut x = v[k - s] ^ (v[k - s] >> s);
        let mut i = 1;
        while i < s {
            if (a >> (s - 1 - i)) & 1 != 0 {
                x ^= v[k - i];
            }
            i += 1;
        }
        v[k] = x;
        k += 1;
    }
    v
}

/// Cap on the cycle-walking loop of the stratified sampler's permutation (`sampler::permute`).
pub const PERMUTE_WALK_CAP: u32 = 64;
/// Random dimensions of the pixel position and of the lens point: the pixel position takes
/// dimensions 0 and 1.
pub const PIXEL_DIMENSION: u32 = 0;
/// First random dimension of the lens point (it takes 2 and 3).
pub const LENS_DIMENSION: u32 = 2;
/// The random dimensions of a camera sample's time (4; 5 unused), drawn only while the
/// shutter is open for a while (`GpuCamera::shutter_span`).
pub const TIME_DIMENSION: u32 = 4;
/// First random dimension of the area-light samples. Light sample `k` of the area light whose
/// samples start at `offset`, at path vertex `depth`, draws dimensions
/// `LIGHT_DIMENSION + 2 * (depth * frame.vertex_dimension_pairs + offset + k)` and the next
/// one: any window of light samples can then be evaluated on its own (`GpuPass`). The path
/// tracer's BSDF sample at vertex `depth` takes the pairs after the vertex's light samples
/// (`BSDF_PAIR`, `ROULETTE_PAIR`), and its choice of a light the next (`CHOICE_PAIR`).
pub const LIGHT_DIMENSION: u32 = 6;
/// Poisson-disk sets in the sample table; a pixel picks one by hash and shifts it.
pub const POISSON_SETS: u32 = 16;
/// The pair of a path vertex's dimensions (after its light samples) its BSDF sample's
/// direction draws.
pub const BSDF_PAIR: u32 = 0;
/// The pair after it: the BSDF's lobe (first) and Russian roulette's draw (second).
pub const ROULETTE_PAIR: u32 = 1;
/// The pair after it: the path tracer's choice of the area light a vertex samples (first;
/// the second is not drawn).
pub const CHOICE_PAIR: u32 = 2;
/// Dimension pairs a path tracer's vertex draws besides its light samples.
pub const PATH_VERTEX_PAIRS: u32 = 3;
/// `GpuFrame::integrator`: Whitted's integrator.
pub const INTEGRATOR_WHITTED: u32 = 0;
/// `GpuFrame::integrator`: the path tracer.
pub const INTEGRATOR_PATH: u32 = 1;
/// Interleaved sampling repeats a tile of INTERLEAVED_TILE x INTERLEAVED_TILE basis patterns.
pub const INTERLEAVED_TILE: u32 = 3;

/// Scene features a kernel variant can leave out. On the GPU each is a pipeline-overridable
/// `bool` constant of the same name (true in the general kernel); on the CPU a bit of the
/// integrator's const generic. A variant built without a feature the scene has is wrong, so the
/// bits are always computed from the scene (`pack::FlatScene::features`).
///
/// `FEATURE_LENS`: a thin lens (f_number > 0) rather than a pinhole, so lens points are sampled.
pub const FEATURE_LENS: u32 = 1;
/// Some material has a non-zero mirror reflectance: paths bounce.
pub const FEATURE_MIRRORS: u32 = 2;
/// Lights sampled with shadow-ray samples per vertex (`GpuLight::is_sampled`): area lights
/// (parallelograms or emitting triangles), environment lights and suns.
pub const FEATURE_AREA_LIGHTS: u32 = 4;
/// Point or directional lights.
pub const FEATURE_PUNCTUAL_LIGHTS: u32 = 8;
/// Triangles (meshes) among the primitives.
pub const FEATURE_TRIANGLES: u32 = 16;
/// Infinite planes (tested outside the BVH).
pub const FEATURE_PLANES: u32 = 32;
/// Ellipsoids, cylinders or tori (`accel::curved`), intersected exactly.
pub const FEATURE_CURVED: u32 = 64;
/// The path tracer (`GpuFrame::integrator`): BSDF sampling and multiple importance sampling.
pub const FEATURE_PATH: u32 = 128;
/// Every feature: the general kernel.
pub const FEATURES_ALL: u32 = 255;
/// Whether the feature set `features` has `bit` (a `FEATURE_*`); const, for the CPU
/// integrator's const generic.
pub const fn has(features: u32, bit: u32) -> bool {
    features & bit != 0
}

/// (WGSL override name, bit) of every feature.
pub const FEATURES: [(&str, u32); 8] = [
    ("FEATURE_LENS", FEATURE_LENS),
    ("FEATURE_MIRRORS", FEATURE_MIRRORS),
    ("FEATURE_AREA_LIGHTS", FEATURE_AREA_LIGHTS),
    ("FEATURE_PUNCTUAL_LIGHTS", FEATURE_PUNCTUAL_LIGHTS),
    ("FEATURE_TRIANGLES", FEATURE_TRIANGLES),
    ("FEATURE_PLANES", FEATURE_PLANES),
    ("FEATURE_CURVED", FEATURE_CURVED),
    ("FEATURE_PATH", FEATURE_PATH),
];

/// Bits of the status word: a kernel loop hit its cap (a traversal took more than
/// `GpuFrame::traversal_cap` steps).
pub const STATUS_TRAVERSAL_CAP: u32 = 1;
/// A BVH traversal stack (`BVH_STACK_SIZE`, `CWBVH_STACK_SIZE`) overflowed.
pub const STATUS_STACK_OVERFLOW: u32 = 2;
/// The stratified sampler's permutation walk hit `PERMUTE_WALK_CAP` (its sample order then
/// repeats a stratum).
pub const STATUS_PERMUTE_CAP: u32 = 4;
/// The driver stopped the kernel's loops early. lavapipe (Mesa's llvmpipe) ends every loop of
/// an invocation, silently, once 65535 loop iterations have run in total (its
/// LP_MAX_TGSI_LOOP_ITERATIONS); `render.wgsl` detects it with a loop of `LOOP_CHECK_ITERATIONS`
/// run-time iterations at the end of the kernel, which then runs fewer.
pub const STATUS_LOOP_LIMIT: u32 = 8;
/// A wavefront path vertex had more shadow rays than its slots (`GpuWave::shadow_stride`): the
/// plan undercounted them, and the rays beyond were dropped.
pub const STATUS_WAVE_OVERFLOW: u32 = 16;
/// Trip count of the loop-limit check (`GpuPass::loop_check`); any value above 1 works.
pub const LOOP_CHECK_ITERATIONS: u32 = 2;
/// Light samples follow the pixel pattern over all of a pixel's `spp x samples` light points
/// while there are at most this many (`sampler::light_sample_2d`); beyond, each camera sample's
/// light samples are stratified on their own.
pub const MAX_LIGHT_PATTERN_POINTS: u32 = 1 << 24;
/// Slots of the status buffer (`array<atomic<u32>, STATUS_WORDS>`): the `STATUS_*` bits
/// raised, ORed together.
pub const STATUS_FLAGS: u32 = 0;
/// Rays traced (camera, shadow and mirror rays), summed over invocations.
pub const STATUS_RAYS: u32 = 1;
/// Camera samples whose path was cut off at `max_depth` while it still reflected.
pub const STATUS_TRUNCATED: u32 = 2;
/// Words in the status buffer.
pub const STATUS_WORDS: u32 = 4;

/// A BVH node: obvhs's `Bvh2Node` without its spare fields. Inner node: `prim_count == 0` and
/// children at `first_index` and `first_index + 1`. Leaf: primitives
/// `first_index .. first_index + prim_count` of the primitive array, already in BVH order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    /// Lower corner of the node's box (scene units).
    pub min: [f32; 3],
    /// Primitives in a leaf; 0 marks an inner node.
    pub prim_count: u32,
    /// Upper corner of the node's box (scene units).
    pub max: [f32; 3],
    /// Inner node: index of the first of its two children. Leaf: index of its first primitive.
    pub first_index: u32,
}

/// A node of the compressed wide BVH (CWBVH, Ylitie et al. 2017): obvhs's `CwBvhNode`, its
/// bytes read as little-endian words. Eight children, each box quantised to 8 bits per plane on
/// the grid `p + q * 2^(e - 127)`; `child_meta` holds each child's byte (leaf: primitive offset and
/// unary count; inner: 24 + slot), `e_imask` the three exponents and the inner-child mask.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCwNode {
    /// Origin of the quantisation grid (scene units).
    pub p: [f32; 3],
    /// Bytes 0-2: the biased exponents `e` of the x, y and z grid steps; byte 3: the inner-child
    /// mask (bit per slot).
    pub e_imask: u32,
    /// Index of the node's first inner child; its inner children are consecutive.
    pub child_base: u32,
    /// Index of the first primitive of the node's leaves; each leaf's offset is in its meta byte.
    pub prim_base: u32,
    /// One byte per child slot: 0 empty; inner child: 24 + slot; leaf: primitive offset from
    /// `prim_base` (bits 0-4) and primitive count in unary (bits 5-7).
    pub child_meta: [u32; 2],
    /// Quantised lower x planes of the children's boxes, one byte per child.
    pub q_lo_x: [u32; 2],
    /// Quantised upper x planes, one byte per child.
    pub q_hi_x: [u32; 2],
    /// Quantised lower y planes, one byte per child.
    pub q_lo_y: [u32; 2],
    /// Quantised upper y planes, one byte per child.
    pub q_hi_y: [u32; 2],
    /// Quantised lower z planes, one byte per child.
    pub q_lo_z: [u32; 2],
    /// Quantised upper z planes, one byte per child.
    pub q_hi_z: [u32; 2],
}

/// One primitive. Triangle: `p0, p1, p2` are its vertices, `normals` indexes `GpuNormals` or is
/// `NONE`. Sphere: `p0` centre, `p1.x` radius, `p1.y` |centre|^2 - radius^2 (rounded once from
/// f64). Quad: `p0` corner, `p1` edge_u, `p2` edge_v. Plane: `p0` a point, `p1` the unit normal.
/// Ellipsoid: `p0` centre, `p1` semi-axes. Cylinder: `p0` base centre, `p1.x` radius, `p1.y`
/// height. Torus: `p0` centre, `p1.x` major radius, `p1.y` minor radius. These three are given
/// in their own frame (a cylinder's and torus's axis along y), which the unit quaternion
/// `p2` = (x, y, z), w = `f32::from_bits(normals)` turns into the world's about `p0`.
/// Planes are unbounded and live after the BVH's primitives (`GpuFrame::plane_start`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPrimitive {
    /// First point (per `kind`, see above), scene units.
    pub p0: [f32; 3],
    /// A `PRIM_*` kind.
    pub kind: u32,
    /// Second point, edge, normal or (sphere) radius data, per `kind`.
    pub p1: [f32; 3],
    /// Index into the material array.
    pub material: u32,
    /// Third point or second edge, per `kind`; a curved shape's orientation's x, y, z; unused
    /// by spheres and planes.
    pub p2: [f32; 3],
    /// Triangle: index into the vertex-normal array, or `NONE` for flat shading; a curved
    /// shape's orientation's w, its bits.
    pub normals: u32,
}

/// Vertex normals of a smooth triangle, n0, n1, n2 packed as 9 floats.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNormals {
    /// Unit normals at the triangle's vertices p0, p1, p2, x y z each.
    pub n: [f32; 9],
}

/// Material parameters; radiometry as in pbrt: Lambert BRDF = diffuse / pi.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Diffuse reflectance in [0, 1] per channel (Lambert BRDF diffuse / pi).
    pub diffuse: [f32; 3],
    /// A `MODEL_*` model.
    pub model: u32,
    /// Specular reflectance ks of the Phong or Blinn-Phong lobe, in [0, 1].
    pub specular: [f32; 3],
    /// Exponent n of the Phong or Blinn-Phong lobe, in [0, 1e4]; a rough conductor's GGX
    /// alpha, in [1e-4, 1].
    pub shininess: f32,
    /// Perfect-mirror reflectance in [0, 1] per channel; non-zero makes paths bounce.
    pub mirror: [f32; 3],
    /// An emitter's samples per vertex as a light (0: no light samples it): the path tracer
    /// weighs a BSDF ray that hits it against them (multiple importance sampling).
    pub light_samples: u32,
    /// Emitted radiance from the front side: a `MODEL_EMITTER` surface's, or under the path
    /// tracer, an emitting surface's that also reflects by its model.
    pub emission: [f32; 3],
    /// A `MODEL_DIELECTRIC`'s index of refraction, inside over outside (the side its outward
    /// normal leaves from).
    pub ior: f32,
    /// 1 + the index in the texture array of the texture whose colour multiplies `diffuse`;
    /// 0 for none (so a zeroed material has none).
    pub texture: u32,
    /// Padding to the WGSL struct's 16-byte alignment.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// A texture's place in the texel array and how it is read: `width x height` texels, row by
/// row from the image's top row, from `offset` on, each RGBA8 packed in a `u32` (red in the
/// low byte) and sRGB-encoded; `wrap` holds the `WRAP_*` mode of u in its low byte and of v in
/// the next.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// Index of the texture's first texel in the texel array.
    pub offset: u32,
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `WRAP_*` of u | (`WRAP_*` of v) << 8.
    pub wrap: u32,
}

/// Texture coordinates of a textured triangle's vertices p0, p1, p2 (u0 v0 u1 v1 u2 v2), at the
/// same index as its `GpuNormals`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexCoords {
    /// (u, v) at p0, p1 and p2.
    pub uv: [f32; 6],
}

/// Texture wrap modes (glTF's sampler modes): the texture repeats.
pub const WRAP_REPEAT: u32 = 0;
/// Coordinates are clamped to the edge texels.
pub const WRAP_CLAMP: u32 = 1;
/// The texture repeats, every other copy mirrored.
pub const WRAP_MIRROR: u32 = 2;

/// A light. Point: `p0` position, `color` intensity (W/sr). Directional: `p0` unit vector
/// towards the light, `color` irradiance. Area: `p0` corner, `p1` edge_u, `p2` edge_v, `color`
/// radiance, `samples` shadow rays, `prim` its emitting quad (skipped by its own shadow rays).
/// Environment and sun: see `LIGHT_ENVIRONMENT` and `LIGHT_SUN`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Position, direction towards the light, or corner / vertex, per `kind`.
    pub p0: [f32; 3],
    /// A `LIGHT_*` kind.
    pub kind: u32,
    /// Area and triangle lights: the first edge (scene units).
    pub p1: [f32; 3],
    /// Area and triangle lights: shadow rays per path vertex (1 for a triangle).
    pub samples: u32,
    /// Area and triangle lights: the second edge (scene units).
    pub p2: [f32; 3],
    /// The light's emitting primitive in the primitive array, or `NONE` (point, directional).
    pub prim: u32,
    /// Intensity (W/sr), irradiance or radiance, per `kind`; linear RGB.
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
    /// The lens frame's x axis (right) in world space.
    pub lens_to_world_x: [f32; 3],
    /// Focal length (mm); 0 for an orthographic camera.
    pub focal_length_mm: f32,
    /// The lens frame's y axis (up) in world space.
    pub lens_to_world_y: [f32; 3],
    /// Radius of the aperture (focal length / (2 N), mm); 0 for a pinhole.
    pub lens_radius_mm: f32,
    /// The lens frame's z axis (the optical axis) in world space.
    pub lens_to_world_z: [f32; 3],
    /// Scene units per millimetre (lens points are in mm, ray origins in scene units).
    pub units_per_mm: f32,
    /// The lens centre in world space (scene units): the lens frame's origin.
    pub lens_center: [f32; 3],
    /// 1 / focal length (1/mm): the ray-transfer refraction term; 0 for an orthographic camera.
    pub inv_focal_length_mm: f32,
    /// The film centre in the lens frame (mm).
    pub film_center: [f32; 3],
    /// Film width (mm).
    pub film_width_mm: f32,
    /// Unit direction of the film's x axis (image right) in the lens frame.
    pub film_u: [f32; 3],
    /// Film height (mm).
    pub film_height_mm: f32,
    /// Unit direction of the film's y axis (image up) in the lens frame.
    pub film_v: [f32; 3],
    /// 0: circular aperture; n >= 3: regular polygon whose unit-circle vertices are
    /// `sample_table[aperture_table_offset ..= aperture_table_offset + n]` (first one repeated).
    pub aperture_blades: u32,
    /// Where the aperture polygon's vertices start in the sample table.
    pub aperture_table_offset: u32,
    /// When the shutter opens (seconds): a camera sample's time is
    /// `shutter_open + u * shutter_span` for a pattern point `u` in [0, 1).
    pub shutter_open: f32,
    /// How long it stays open (seconds); 0: every sample at `shutter_open`, no time drawn.
    pub shutter_span: f32,
    /// The surface of sharp focus: `FOCUS_PLANE` (the thin lens's, tilted by the lens
    /// movements), or `FOCUS_SPHERE` / `FOCUS_CYLINDER` of radius `focus_radius_mm` about the
    /// lens centre (the cylinder's axis the lens's vertical).
    pub focus_surface: u32,
    /// The curved focal surface's radius (mm in the lens frame).
    pub focus_radius_mm: f32,
    /// `PROJECTION_PERSPECTIVE`, or `PROJECTION_ORTHOGRAPHIC`: rays parallel to the lens
    /// frame's z axis (the rays' direction), each from its film point (the film then is the
    /// window, in mm as scene units / `units_per_mm`; no lens, the focal length 0).
    pub projection: u32,
    /// A real lens's surfaces (`PROJECTION_LENS`); 0 otherwise.
    pub lens_surface_count: u32,
    /// Where a real lens's table starts in the sample table: its exposure, its surfaces
    /// rearmost first and its exit-pupil bounds (`camera::lens::LensSystem::kernel_table`).
    pub lens_table_offset: u32,
    /// 1: the spectral mode (`camera.spectral`, a real lens only): each sample traced at its own
    /// wavelength through the lens's dispersive glass and weighted by the film's response
    /// (`camera::spectral`); 0: every sample at the prescription's reference line.
    pub spectral: u32,
    /// Padding to the WGSL struct's 16-byte alignment.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// Settings constant over one render.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuFrame {
    /// Image width in pixels (the full image, also when cropped).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (the most a pixel takes under adaptive sampling).
    pub spp: u32,
    /// Mirror bounces allowed per path.
    pub max_depth: u32,
    /// Seed of every random number of the render.
    pub seed: u32,
    /// `SAMPLER_*` pattern of the pixel positions.
    pub pixel_sampler: u32,
    /// Entries in the light array.
    pub light_count: u32,
    /// Nodes in the BVH node array.
    pub node_count: u32,
    /// Index of the first plane in the primitive array (the bounded primitives come first).
    pub plane_start: u32,
    /// Planes at the end of the primitive array.
    pub plane_count: u32,
    /// Node-pair visits allowed per traversal before the kernel gives up and flags it.
    pub traversal_cap: u32,
    /// Columns of the pixel-sample strata (`math::sampling::strata_columns(spp)`).
    pub pixel_strata_columns: u32,
    /// `SAMPLER_*` pattern of the lens points.
    pub lens_sampler: u32,
    /// Columns of the lens-sample strata (`math::sampling::strata_columns(spp)`).
    pub lens_strata_columns: u32,
    /// Where the pixel / lens sampler's precomputed patterns start in the sample table.
    pub pixel_table_offset: u32,
    /// Where the lens sampler's precomputed patterns start in the sample table.
    pub lens_table_offset: u32,
    /// Radiance of rays that escape the scene.
    pub background: [f32; 3],
    /// Shadow-ray samples of all area lights at one path vertex (the sum of their `samples`).
    pub light_samples_per_vertex: u32,
    /// Ambient radiance L_a: each hit adds diffuse * L_a.
    pub ambient: [f32; 3],
    /// 0 for a static scene; else where the velocity records start in the primitive array:
    /// primitive `i` moves with velocity `prims[motion_base + i].p0` (scene units a second).
    pub motion_base: u32,
    /// 1 in an adaptive render: every prefix of a pixel's samples must be stratified, so the
    /// stratified pattern and the light samples take progressive orders (`sampler.rs`).
    pub progressive: u32,
    /// `INTEGRATOR_WHITTED` or `INTEGRATOR_PATH`.
    pub integrator: u32,
    /// The path tracer's first vertex whose bounce Russian roulette may end.
    pub rr_depth: u32,
    /// Random dimension pairs of one path vertex: its light samples
    /// (`light_samples_per_vertex`), and the path tracer's `PATH_VERTEX_PAIRS`.
    pub vertex_dimension_pairs: u32,
    /// The lights from this index on are chosen among, one per path vertex in proportion to
    /// its power (the path tracer's area lights); those before it are sampled at every vertex.
    /// `light_count` where no light is chosen (Whitted's integrator).
    pub light_choice_start: u32,
    /// The dimension pairs a vertex keeps for the chosen light's samples, first among its
    /// light samples: the most samples of a light chosen among.
    pub light_choice_pairs: u32,
    /// Where the chosen lights' cumulative distribution starts in the sample table: entry `i`
    /// (of `light_count - light_choice_start`) is component `i % 2` of point `offset + i / 2`.
    pub light_choice_offset: u32,
    /// The lights chosen among's total power, luminance x area: a light is chosen with
    /// probability `luminance(color) * area / light_power_total`.
    pub light_power_total: f32,
}

/// What one dispatch renders: a rectangle of pixels (whole rows: a band), a range of sample
/// indices, and a window of every area light's shadow-ray samples. A pass whose light samples
/// need several windows (dispatches) sums them in a scratch buffer and commits the sum to the
/// accumulation with the last window, so the accumulation is a valid mean after every dispatch
/// (see `render.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPass {
    /// First column of the band (pixels).
    pub tile_x: u32,
    /// First row of the band (pixels), or of the pixel list's rows.
    pub tile_y: u32,
    /// Columns of the band (pixels), or entries per row of the pixel list.
    pub tile_width: u32,
    /// Rows of the band.
    pub tile_height: u32,
    /// First sample index of the pass.
    pub sample_start: u32,
    /// Samples per pixel in this pass (the ray benchmark: rays in the buffer).
    pub sample_count: u32,
    /// Light samples `light_sample_start .. light_sample_start + light_sample_count` of each
    /// area light; the window starting at 0 also adds everything else (emission, ambient,
    /// point and directional lights, background).
    pub light_sample_start: u32,
    /// Light samples of each area light in this window.
    pub light_sample_count: u32,
    /// 1 when this window is the pass's last: the scratch sum is committed.
    pub commit: u32,
    /// Always `LOOP_CHECK_ITERATIONS`; a uniform so no compiler can fold the check away.
    pub loop_check: u32,
    /// 0: the invocations cover the band's pixels. Otherwise the band's rows (`tile_width`
    /// entries each) index a list of this many pixels (adaptive sampling's unconverged ones).
    pub listed_pixels: u32,
    /// Where (in pixels) the scratch sums of a pass split into light windows live.
    pub scratch_offset: u32,
    /// Where (in pixels) the AOV layers start (`render::AccumulationLayout`); 0: no AOVs.
    pub aov_offset: u32,
    /// Padding to the WGSL layout.
    pub _pad1: u32,
    /// Padding to the WGSL layout.
    pub _pad2: u32,
    /// Padding to the WGSL layout.
    pub _pad3: u32,
}

impl GpuPass {
    /// Whether this window starts at light sample 0, and so also adds everything other than
    /// area-light samples.
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
            | FEATURE_CURVED
            | FEATURE_PATH
);
/// A ray of the ray benchmark's buffer (`wgsl/trace.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    /// Ray origin (scene units).
    pub origin: [f32; 3],
    /// Farthest distance along the ray a hit counts at (`T_FAR`: unbounded).
    pub t_max: f32,
    /// Unit direction of travel.
    pub direction: [f32; 3],
    /// Padding to the WGSL layout.
    pub _pad0: u32,
}

/// A ray's closest hit as the wavefront render stores it between its closest-hit and shading
/// kernels (`wgsl/wavefront.wgsl`): the primitive (`NONE`: a miss) and `intersect::Hit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHit {
    /// The primitive hit, in the CWBVH's order, or `NONE`.
    pub prim: u32,
    /// Distance along the ray.
    pub t: f32,
    /// The hit's first surface coordinate (`Hit::b1`).
    pub b1: f32,
    /// The hit's second surface coordinate (`Hit::b2`).
    pub b2: f32,
}

/// The ray a wavefront path traces next (`wgsl/wavefront.wgsl`): what the closest-hit kernel
/// reads, apart from the rest of the path so that it reads 32 bytes a ray, as the ray queries do.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPathRay {
    /// Ray origin (scene units).
    pub origin: [f32; 3],
    /// The camera sample's time (seconds), at which moving primitives are intersected.
    pub time: f32,
    /// Unit direction of travel.
    pub direction: [f32; 3],
    /// The primitive the ray leaves and must not hit (`NONE`: none).
    pub skip: u32,
}

/// A wavefront path's state between its kernels: one camera sample's path (`trace_path` in
/// `src/integrator.rs` is its twin, vertex by vertex).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPath {
    /// The path's throughput at its current vertex.
    pub throughput: [f32; 3],
    /// The pixel (`y * width + x`) it samples; `NONE` where the dispatch's grid runs past the
    /// end of a pixel list.
    pub pixel: u32,
    /// The radiance gathered so far.
    pub radiance: [f32; 3],
    /// Its camera sample's index.
    pub sample: u32,
    /// What its last bounce multiplies the throughput by at the next vertex (after the
    /// current vertex's shadow rays are resolved with the throughput they were cast with): a
    /// mirror's reflectance, or the path tracer's BSDF weight over Russian roulette's odds.
    pub bounce_weight: [f32; 3],
    /// Rays it traced: camera, mirror and shadow rays (`DispatchStatus::rays`).
    pub rays: u32,
    /// Shadow rays its current vertex emitted (`GpuShadowRay`s from `index * stride`).
    pub shadow_count: u32,
    /// 1 once it was cut off at `max_depth` while it still reflected.
    pub truncated: u32,
    /// The path tracer: the solid-angle density its last bounce's direction was drawn with
    /// (0: a camera ray or a mirror's, which no light sample could have drawn).
    pub bsdf_pdf: f32,
    /// What its radiance counts for (`CameraRay::weight`): 1, or a real lens's exit-pupil
    /// sample's weight, applied as the sample is accumulated (Russian roulette sees the
    /// throughput alone, as on the CPU).
    pub camera_weight: f32,
}

/// A shadow ray of a wavefront path vertex, traced by the any-hit kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadowRay {
    /// Origin, offset from the surface by its error bound.
    pub origin: [f32; 3],
    /// Where the light is (`shadow_ray_length`): hits beyond do not shadow.
    pub t_max: f32,
    /// Unit direction towards the light.
    pub direction: [f32; 3],
    /// The camera sample's time (seconds).
    pub time: f32,
    /// The primitive the ray leaves (`NONE`: none).
    pub skip_a: u32,
    /// The light's own primitive (`NONE`: a punctual light).
    pub skip_b: u32,
    /// Padding to the WGSL layout.
    pub _pad0: u32,
    /// Padding to the WGSL layout.
    pub _pad1: u32,
}

/// What a shadow ray adds where its light is visible, before the light's scale (an area
/// light's `color * area / samples`; a punctual light's term is whole); the any-hit kernel zeroes
/// it where the light is blocked.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadowTerm {
    /// The unshadowed term.
    pub f: [f32; 3],
    /// The light's index in the light array.
    pub light: u32,
}

/// What one stage dispatch of a wavefront batch works on, at its own dynamic offset.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWave {
    /// The path vertex the stage works on: 0 for the camera rays' hits.
    pub depth: u32,
    /// Shadow-ray slots of each path (`GpuShadowRay`s of path `i` from `i * shadow_stride`):
    /// the most its vertex may emit in the pass's light window.
    pub shadow_stride: u32,
    /// Paths the path buffers hold: each of the two queues' length.
    pub path_capacity: u32,
    /// Padding to the WGSL layout.
    pub _pad0: u32,
}

/// The indirect dispatches of one path depth, as `wf_prepare` writes them: workgroups
/// `(x, y, 1)` and, last, the count of entries they cover.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWaveArgs {
    /// The paths the depth's closest-hit, shading and resolve kernels take.
    pub paths: [u32; 4],
    /// The shadow rays of the depth's vertices.
    pub shadows: [u32; 4],
}

/// A Fermat solve's reflector and eye (`wgsl/preview/fermat.wgsl`): a sphere, a torus (around the
/// vertical axis through its centre), a bicubic Bézier patch, an ellipsoid or a cylinder, and how many vertices the `fermat_vertices` buffer holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuReflector {
    /// The sphere's, torus's or ellipsoid's centre, the centre of a cylinder's base circle
    /// (scene units).
    pub center: [f32; 3],
    /// The sphere's or cylinder's radius, or the torus's major radius R (scene units).
    pub radius: f32,
    /// The eye E (scene units).
    pub eye: [f32; 3],
    /// Vertices to solve.
    pub count: u32,
    /// One of `REFLECTOR_*`: picks the fermat pipeline,
    /// whose `REFLECTOR_KIND` is specialised to it.
    pub kind: u32,
    /// The torus's tube radius r (scene units); 0 for a sphere.
    pub minor: f32,
    /// A cylinder's height (scene units); 0 for the others.
    pub height: f32,
    /// 1 + the index of the mirror this surface belongs to (the id the preview's main pass
    /// writes): the cull (`fermat_cull`) leaves out the mirror's own triangles. 0 where no
    /// triangles are culled.
    pub mirror: u32,
    /// An ellipsoid's semi-axes along its own x, y, z (w unused); zero for the others.
    pub radii: [f32; 4],
    /// The unit quaternion (x, y, z, w) that turns a torus's, ellipsoid's or cylinder's own
    /// frame into the world's about `center`: the kernel searches in the own frame. The
    /// identity for the others.
    pub orientation: [f32; 4],
    /// A patch's control points P_ij at index 4i + j (w unused); zero for other kinds.
    pub control: [[f32; 4]; 16],
    /// 1 where the mirror's own triangles are drawn reflected in this surface (a torus's or a
    /// teapot's, with the preview's self-reflections on): the cull keeps those whose corners
    /// stand clear of their points (`SELF_REFLECTION_CLEARANCE`) instead of leaving them out.
    pub sees_itself: u32,
    /// A torus's search: 0 for its outer half, 1 for its inner half (`fermat::TorusHalf`):
    /// where the search starts, and which triangles it draws. 0 for the other kinds.
    pub torus_half: u32,
    /// A patch's corner A, where the segment from the eye to O crosses it
    /// (`fermat::BezierPatch::crossing`): the same for every vertex, so found once a frame on
    /// the CPU, in f64, rather than by Newton's steps in every invocation. Zero for the other
    /// kinds, whose crossings are closed forms (a sphere's in each vertex's frame).
    pub eye_uv: [f32; 2],
}

/// One vertex's reflection point, as the Fermat kernel finds it (`fermat::Solver` is its CPU
/// twin).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuReflection {
    /// P, on the reflector (scene units).
    pub point: [f32; 3],
    /// Steps taken.
    pub steps: u32,
    /// The reflector's outward unit normal at P.
    pub normal: [f32; 3],
    /// 1 where the preview draws this reflection (E and V see P from outside and the law of
    /// reflection holds to `REFLECTION_TOLERANCE`; CPU twin `fermat::drawn_in_preview`), else 0.
    pub shown: u32,
    /// P's parameters (u, v) in the vertex's facing frame (`scene::parametric::Sphere::facing`); a
    /// patch's own (u, v), which the cull reads to tell a corner on the patch from one in its
    /// seam band.
    pub uv: [f32; 2],
    /// |P − V|, the reflected point's depth for hidden-surface removal among reflections.
    pub depth: f32,
    /// 1 where the step system was singular (the search stopped there).
    pub degenerate: u32,
}

/// The arguments of an indexed indirect draw (wgpu's `DrawIndexedIndirectArgs`): the
/// `fermat_cull` kernel writes the indices of the reflected triangles that show and counts
/// them, and the preview draws that many.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuDrawArgs {
    /// Indices to draw: three per triangle the cull kept (counted atomically).
    pub index_count: u32,
    /// 1.
    pub instance_count: u32,
    /// 0.
    pub first_index: u32,
    /// 0.
    pub base_vertex: i32,
    /// 0.
    pub first_instance: u32,
}

impl GpuLight {
    /// An area light, parallelogram or triangle: sampled with `samples` shadow rays.
    pub fn is_area(&self) -> bool {
        self.kind == LIGHT_AREA || self.kind == LIGHT_TRIANGLE
    }

    /// An area light's area: its edges' parallelogram, half of it for a triangle. Twin:
    /// `area_light_of` in integrator.wgsl.
    pub fn area(&self) -> f32 {
        let cross = glam::Vec3::from(self.p1).cross(glam::Vec3::from(self.p2));
        match self.kind {
            LIGHT_TRIANGLE => 0.5 * cross.length(),
            _ => cross.length(),
        }
    }

    /// A light at infinity that escaping rays see: an environment or a sun.
    pub fn is_sky(&self) -> bool {
        self.kind == LIGHT_ENVIRONMENT || self.kind == LIGHT_SUN
    }

    /// A light sampled with `samples` shadow rays per path vertex, each drawing its own random
    /// dimensions (`integrator::light_dimension`): an area light or a sky light.
    pub fn is_sampled(&self) -> bool {
        self.is_area() || self.is_sky()
    }
}

/// Rec. 709 luminance weights of linear RGB (`LUMINANCE_WEIGHTS` in WGSL).
pub const LUMINANCE_WEIGHTS: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance of linear RGB, in f32 as the kernels compute it.
pub fn luminance_f32(c: [f32; 3]) -> f32 {
    glam::Vec3::from(c).dot(glam::Vec3::from(LUMINANCE_WEIGHTS))
}

impl GpuFrame {
    /// Whether a path vertex chooses one area light to sample (`light_choice_start`).
    pub fn chooses_lights(&self) -> bool {
        self.light_choice_start < self.light_count
    }

    /// The probability a path vertex chooses the area light of radiance `color` and area
    /// `area` (for an emitter hit, its material's emission and its primitive's area), in
    /// proportion to its power; 1 where the frame chooses no light. Twin:
    /// `light_choice_probability` in integrator.wgsl.
    pub fn light_choice_probability(&self, color: [f32; 3], area: f32) -> f32 {
        match self.chooses_lights() {
            true => luminance_f32(color) * area / self.light_power_total,
            false => 1.0,
        }
    }
}

const _: () = assert!(size_of::<GpuRay>() == 32);
const _: () = assert!(size_of::<GpuReflector>() == 352);
const _: () = assert!(size_of::<GpuReflection>() == 48);
const _: () = assert!(size_of::<GpuBvhNode>() == 32);
const _: () = assert!(size_of::<GpuCwNode>() == 80);
const _: () = assert!(size_of::<GpuPrimitive>() == 48);
const _: () = assert!(size_of::<GpuNormals>() == 36);
const _: () = assert!(size_of::<GpuMaterial>() == 80);
const _: () = assert!(size_of::<GpuTexture>() == 16);
const _: () = assert!(size_of::<GpuTexCoords>() == 24);
const _: () = assert!(size_of::<GpuLight>() == 64);
const _: () = assert!(size_of::<GpuCamera>() == 160);
const _: () = assert!(size_of::<GpuFrame>() == 128);
const _: () = assert!(size_of::<GpuPass>() == 64);

/// The raster preview draws a vertex's Fermat reflection only where the law of reflection holds
/// at its point to this angle (radians): a search that stopped short leaves its triangles out
/// rather than drawing them displaced. 1e-2 rad moves a point of a sphere of radius R seen
/// from distance D by about 1e-2 R / D radians of view, a fraction of a pixel for the preview's
/// scenes; 2e-3 rejects many points f32's search cannot refine further.
pub const REFLECTION_TOLERANCE: f32 = 1e-2;

/// The Fermat search's initial corner C stands off the middle of AB by this many lengths of AB
/// (Roger and Holzschuch ask only for a triangle that is not flat).
pub const FERMAT_C_OFFSET: f32 = 0.25;

/// A sphere's (or ellipsoid's, in its unit sphere's coordinates) point O, which the initial
/// corners A and B aim at, lies this fraction of the radius from the centre toward the bisector
/// of E and V (the facing frame's x axis): A and B then cross the surface near the reflection,
/// which lies between them, instead of at E's and V's own directions. At the centre (the
/// Roger and Holzschuch's figure) 96.9% of the test's random configurations converged within 5 steps; here
/// 99.9% (docs/fermat.md).
pub const FERMAT_INSIDE: f32 = 0.9;

/// Where the crossings A and B are closer than this (radians of the parameters), the initial
/// triangle is spread by it instead, so the search still starts from a triangle.
pub const FERMAT_SPREAD: f32 = 1e-3;

/// A step's new point replaces the corner farthest from it unless that leaves a flat triangle:
/// twice its area below this fraction of its longest side squared (a height under 1/1000 of the
/// side). Then the next farthest goes. On a sphere d(u, v) is separable in the facing frame:
/// A, B and every point the search finds lie on the equator, and replacing C there left three
/// collinear corners whose gradients' system is singular, the next step noise. Roger and Holzschuch warn
/// that flat triangles break the step's system.
pub const FERMAT_FLAT: f32 = 1e-3;

/// A reflection found on a Bézier patch lies on it where its (u, v) lies in the patch's square
/// widened by this much: beyond, the point belongs to a neighbouring patch (whose own search
/// finds it) or to none, and anchors no reflected triangle (`PATCH_SEAM`). On a cylinder, a
/// reflection counts where its height lies within [0, height] widened by this fraction of the
/// height.
pub const PATCH_MARGIN: f32 = 1e-4;

/// A mirror's own vertex V is drawn reflected in it (a teapot's spout in its body) only where
/// |P − V| exceeds this fraction of the eye's distance to P: a vertex on the searched surface
/// itself has P = V (d's minimum |E − V|), no reflection, and its triangle would cover the
/// mirror's true reflection at depth 0. 1e-3 of the view distance is about a third of a pixel
/// at the preview scenes' 40 mm focal length over 320 pixels; the nearest real self-reflections
/// there (the teapot's knob over its lid) stand 10x farther off.
pub const SELF_REFLECTION_CLEARANCE: f32 = 1e-3;

/// A reflection found on a Bézier patch's smooth continuation, its (u, v) beyond the square by
/// at most this much, still shows as a corner of a reflected triangle with another corner on
/// the patch itself (the kernel's zero normal beyond the band; `fermat::anchored_on_patch`): a triangle whose
/// corners reflect on two neighbouring patches was drawn by neither, and a teapot's seams
/// showed holes (the features drawn at subdivision 4: 917 of 1,277 with none, 1,053 with
/// 0.03, 1,111 with 0.1; BENCHMARKS.md).
pub const PATCH_SEAM: f32 = 0.1;

/// A search on a Bézier patch stops once a step leaves the patch's square widened by this much
/// (`fermat::Reflector::beyond_reach`).
pub const PATCH_REACH: f32 = 1.0;

/// The Newton steps that find where a segment crosses a Bézier patch (the search's initial
/// corners A and B) stop once a step moves (u, v, t) less than this: f32's rounding keeps
/// later steps from improving on it, and each costs a patch evaluation.
pub const PATCH_CROSSING_DONE: f32 = 1e-6;

/// A teapot's own point searched again on a patch (`fermat::solve_on_patch`) starts from the
/// sampled point A that fails the law of reflection least and B = A + (this, half this) in the
/// patch's parameters.
pub const SAMPLED_START_SIDE: f32 = 0.2;

/// The points along each side of a patch's parameter square that `sampled_start` tries: its
/// corners and the points between at even steps (4: the corners and the thirds).
pub const SAMPLED_START_GRID: u32 = 4;

/// WGSL `const` declarations for every constant above, emitted at the top of each kernel.
pub fn wgsl_prelude() -> String {
    let u32s = [
        ("WORKGROUP_SIZE", WORKGROUP_SIZE),
        ("TRACE_WORKGROUP_SIZE", TRACE_WORKGROUP_SIZE),
        ("MAX_WORKGROUPS_PER_DIMENSION", MAX_WORKGROUPS_PER_DIMENSION),
        ("WF_PATH_COUNTER", WF_PATH_COUNTER),
        ("WF_SHADOW_COUNTER", WF_SHADOW_COUNTER),
        ("WF_COUNTERS", WF_COUNTERS),
        ("BVH_STACK_SIZE", BVH_STACK_SIZE),
        ("CWBVH_STACK_SIZE", CWBVH_STACK_SIZE),
        ("MAX_LIGHT_PATTERN_POINTS", MAX_LIGHT_PATTERN_POINTS),
        ("NONE", NONE),
        ("PRIM_TRIANGLE", PRIM_TRIANGLE),
        ("PRIM_SPHERE", PRIM_SPHERE),
        ("PRIM_QUAD", PRIM_QUAD),
        ("PRIM_PLANE", PRIM_PLANE),
        ("PRIM_ELLIPSOID", PRIM_ELLIPSOID),
        ("PRIM_CYLINDER", PRIM_CYLINDER),
        ("PRIM_TORUS", PRIM_TORUS),
        ("TORUS_ROOT_STEPS", TORUS_ROOT_STEPS),
        ("TORUS_POLISH_STEPS", TORUS_POLISH_STEPS),
        ("REFLECTOR_SPHERE", REFLECTOR_SPHERE),
        ("REFLECTOR_TORUS", REFLECTOR_TORUS),
        ("REFLECTOR_PATCH", REFLECTOR_PATCH),
        ("REFLECTOR_ELLIPSOID", REFLECTOR_ELLIPSOID),
        ("REFLECTOR_CYLINDER", REFLECTOR_CYLINDER),
        ("MODEL_LAMBERT", MODEL_LAMBERT),
        ("MODEL_PHONG", MODEL_PHONG),
        ("MODEL_BLINN_PHONG", MODEL_BLINN_PHONG),
        ("MODEL_EMITTER", MODEL_EMITTER),
        ("MODEL_DIELECTRIC", MODEL_DIELECTRIC),
        ("MODEL_ROUGH_CONDUCTOR", MODEL_ROUGH_CONDUCTOR),
        ("WRAP_REPEAT", WRAP_REPEAT),
        ("WRAP_CLAMP", WRAP_CLAMP),
        ("WRAP_MIRROR", WRAP_MIRROR),
        ("INTEGRATOR_WHITTED", INTEGRATOR_WHITTED),
        ("INTEGRATOR_PATH", INTEGRATOR_PATH),
        ("BSDF_PAIR", BSDF_PAIR),
        ("ROULETTE_PAIR", ROULETTE_PAIR),
        ("CHOICE_PAIR", CHOICE_PAIR),
        ("PATH_VERTEX_PAIRS", PATH_VERTEX_PAIRS),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("LIGHT_SPOT", LIGHT_SPOT),
        ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
        ("LIGHT_SUN", LIGHT_SUN),
        ("FOCUS_PLANE", FOCUS_PLANE),
        ("FOCUS_SPHERE", FOCUS_SPHERE),
        ("FOCUS_CYLINDER", FOCUS_CYLINDER),
        ("PROJECTION_PERSPECTIVE", PROJECTION_PERSPECTIVE),
        ("PROJECTION_ORTHOGRAPHIC", PROJECTION_ORTHOGRAPHIC),
        ("PROJECTION_LENS", PROJECTION_LENS),
        ("LENS_PUPIL_CELLS", LENS_PUPIL_CELLS),
        ("SPECTRAL_MIN_NM", SPECTRAL_MIN_NM),
        ("SPECTRAL_MAX_NM", SPECTRAL_MAX_NM),
        ("SPECTRAL_BLUE_GREEN_NM", SPECTRAL_BLUE_GREEN_NM),
        ("SPECTRAL_GREEN_RED_NM", SPECTRAL_GREEN_RED_NM),
        ("SPECTRAL_CROSSOVER_NM", SPECTRAL_CROSSOVER_NM),
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
        ("TIME_DIMENSION", TIME_DIMENSION),
        ("INTERLEAVED_TILE", INTERLEAVED_TILE),
        ("STATUS_TRAVERSAL_CAP", STATUS_TRAVERSAL_CAP),
        ("STATUS_STACK_OVERFLOW", STATUS_STACK_OVERFLOW),
        ("STATUS_PERMUTE_CAP", STATUS_PERMUTE_CAP),
        ("STATUS_LOOP_LIMIT", STATUS_LOOP_LIMIT),
        ("STATUS_WAVE_OVERFLOW", STATUS_WAVE_OVERFLOW),
        ("STATUS_FLAGS", STATUS_FLAGS),
        ("STATUS_RAYS", STATUS_RAYS),
        ("STATUS_TRUNCATED", STATUS_TRUNCATED),
        ("STATUS_WORDS", STATUS_WORDS),
        ("SAMPLED_START_GRID", SAMPLED_START_GRID),
    ];
    let mut out = String::from("// Generated from src/layout.rs: do not edit.\n");
    for (name, value) in u32s {
        out += &format!("const {name}: u32 = {value}u;\n");
    }
    out += &format!("const T_FAR: f32 = {T_FAR:e};\n");
    out += &format!("const REFLECTION_TOLERANCE: f32 = {REFLECTION_TOLERANCE:e};\n");
    for (name, value) in [
        ("FERMAT_C_OFFSET", FERMAT_C_OFFSET),
        ("FERMAT_INSIDE", FERMAT_INSIDE),
        ("FERMAT_SPREAD", FERMAT_SPREAD),
        ("FERMAT_FLAT", FERMAT_FLAT),
        ("PATCH_MARGIN", PATCH_MARGIN),
        ("PATCH_SEAM", PATCH_SEAM),
        ("SELF_REFLECTION_CLEARANCE", SELF_REFLECTION_CLEARANCE),
        ("PATCH_REACH", PATCH_REACH),
        ("PATCH_CROSSING_DONE", PATCH_CROSSING_DONE),
        ("SAMPLED_START_SIDE", SAMPLED_START_SIDE),
        ("TORUS_MARGIN", TORUS_MARGIN),
        ("TORUS_POLISH_REACH", TORUS_POLISH_REACH),
    ] {
        out += &format!("const {name}: f32 = {value:e};\n");
    }
    let [r, g, b] = LUMINANCE_WEIGHTS;
    out += &format!("const LUMINANCE_WEIGHTS: vec3<f32> = vec3<f32>({r:e}, {g:e}, {b:e});\n");
    for (name, _) in FEATURES {
        out += &format!("override {name}: bool = true;\n");
    }
    out
}
