//! The raster preview (`chambre preview`, `chambre bench preview`, `chambre bench fermat`): the
//! scene drawn by wgpu's render pipeline through the view camera, fast and approximate, to
//! compose a shot. Its parts, each a module:
//!
//! - `tessellate`: the scene's primitives as triangles (curved shapes cut as finely as the
//!   camera needs, quads as two triangles, planes as large quads);
//! - `shadows`: a light's shadow maps, planned (the views) and drawn (`shadows::maps`);
//! - `reflections`: curved mirrors' reflections by Fermat's principle: the solver, its GPU
//!   kernels and the passes that draw them;
//! - `renderer`: [`PreviewRenderer`], its pipelines, meshes, shading, stage timing and
//!   read-back; `options`: how it draws ([`PreviewOptions`]);
//! - `window`: the interactive window, and the keys and mouse that compose the shot.
//!
//! This root holds what they share: the vertex and uniforms the shaders read, the view
//! camera's projection as the ray tracer defines it (`CameraSpec::raster_projection`: film
//! tilt, swing and shift are a rotation of the view and an off-axis frustum), the scene's
//! bounds, and what the preview leaves out. Shaders: `wgsl/preview/`.
//!
//! What the preview leaves out, by design (it trades accuracy for speed): shadows unless asked
//! (`shadows`: hard ones, by shadow maps), specular lobes, reflections other than curved
//! mirrors' (spheres, tori, ellipsoids, cylinders and Bézier patches, drawn by Fermat's
//! principle: `reflectors`, `ReflectedSet`; mirrors reflect each other once, and a torus or a
//! teapot itself where asked: a mirror seen in a mirror reflects the background, or nothing
//! where the scene's paths bounce once) and depth of field (a lens is drawn as a pinhole at
//! its centre; lens tilt and swing do not move a pinhole's rays). Area lights light it exactly
//! where nothing occludes them (Lambert's formula for a polygon).

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec4, Vec3};

use crate::camera::CameraSpec;
use crate::pack::FlatScene;
use crate::scene::Scene;

mod options;
pub mod reflections;
pub mod renderer;
pub mod shadows;
mod tessellate;
pub mod window;

pub use options::PreviewOptions;
pub use reflections::{
    AUTO_PIECE, MAX_AUTO_PIECES, MirrorSurface, ReflectedSet, Reflector, ReflectorPass,
    SELF_REFLECTION_TOLERANCE_PX, grid_point, reflectors, self_reflections_note, sub_triangle,
};
pub use renderer::{
    PreviewFrame, PreviewRenderer, RasterPipeline, StageTimes, draw, draw_with, shader_source,
};
pub use shadows::{
    CUBE_FACES, SHADOW_MAP_SIZE, SHADOW_MEMORY, SHADOW_NORMAL_OFFSET, SHADOW_SHADER,
    SMALLEST_SHADOW_MAP, ShadowLight, ShadowPlan, cube_face, shadow_map_size,
};
pub use tessellate::{
    CurvedShapes, Cut, DEFAULT_TOLERANCE_PX, Detail, Grid, PATCH_QUADS, ROUND_QUADS, Seen,
    SurfaceAt, UNSEEN_QUADS, coarse_note, fitting_grid, flat_triangles, grid_deviation, tessellate,
};

/// Every render pipeline of the preview, by name and binding (its compute kernels, the Fermat
/// solves and cull, are in `gpu::kernels::KERNELS`); tests/wgsl.rs checks each against its
/// shader.
pub const PIPELINES: [&RasterPipeline; 4] = [
    &renderer::MAIN_PASS,
    &reflections::passes::REFLECTION_PASS,
    &shadows::maps::SHADOW_PASS,
    &window::PRESENT_PASS,
];

/// One vertex of the preview's triangle list.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PreviewVertex {
    /// World position.
    pub position: [f32; 3],
    /// Index of its material in the scene's materials.
    pub material: u32,
    /// Shading normal (world, unit).
    pub normal: [f32; 3],
    /// 0, or 1 + the index of the reflector (`reflectors`) this vertex belongs to: the main pass
    /// writes it to its id target so that reflections are drawn only where their reflector is
    /// visible (the Fermat pass's second level of hidden-surface removal).
    pub reflector: u32,
}

/// The preview's uniforms: the clip matrix and what shading needs of the frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PreviewUniforms {
    /// World to wgpu clip space (depth in [0, 1]), column-major.
    pub clip: [[f32; 4]; 4],
    /// Lights in the scene's light array.
    pub light_count: u32,
    /// The scene's `max_depth`: a mirror seen in a curved mirror (the reflection's one bounce)
    /// reflects the background only where the ray tracer would bounce again (2 or more).
    pub max_depth: u32,
    /// Padding to the WGSL layout.
    pub _pad: [u32; 2],
    /// Ambient radiance: each surface adds diffuse * ambient.
    pub ambient: [f32; 4],
    /// The eye (the lens centre), world space; `w` unused.
    pub eye: [f32; 4],
    /// The background radiance (`w` unused): what a mirror sphere's pixel reflects where no
    /// reflected triangle lands.
    pub background: [f32; 4],
}

impl PreviewVertex {
    /// A vertex of `material` at `position` with the shading normal `normal`, on no reflector.
    pub fn new(position: Vec3, normal: Vec3, material: u32) -> PreviewVertex {
        PreviewVertex {
            position: position.to_array(),
            material,
            normal: normal.to_array(),
            reflector: 0,
        }
    }
}

/// The radius of the sphere around the scene's bounded primitives' box (half its diagonal;
/// 1 for a scene of planes only).
pub fn bounded_radius(scene: &FlatScene) -> f32 {
    bounded_sphere(scene).1
}

/// The sphere around the scene's bounded primitives' box: its centre and half its diagonal
/// (the origin and 1 for a scene of planes only).
pub fn bounded_sphere(scene: &FlatScene) -> (Vec3, f32) {
    let bounded = &scene.prims[..scene.frame.plane_start as usize];
    let (lo, hi) = bounded.iter().map(crate::accel::primitive_bounds).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), b| (lo.min(b.min.into()), hi.max(b.max.into())),
    );
    if lo.x > hi.x {
        return (Vec3::ZERO, 1.0);
    }
    ((lo + hi) / 2.0, ((hi - lo).length() / 2.0).max(1e-6))
}

/// How far the preview's planes reach from their point (`tessellate`'s `extent`) and its far
/// plane: planes reach 100 scene radii, and the far plane lies beyond them from anywhere near.
pub fn extent_and_far(scene: &Scene, flat: &FlatScene) -> (f32, f64) {
    let extent = 100.0 * (bounded_radius(flat) + eye_of(&scene.camera).length());
    (extent, 3.0 * extent as f64)
}

/// The camera's centre of projection (the lens centre), in scene units.
pub fn eye_of(camera: &CameraSpec) -> glam::Vec3 {
    camera
        .raster_projection(1.0)
        .view
        .inverse()
        .w_axis
        .truncate()
        .as_vec3()
}

/// The clip matrix of `camera` for wgpu (depth in [0, 1]), with the far plane `far`
/// scene units away: `CameraSpec::raster_projection`'s OpenGL matrix with its depth remapped.
pub fn clip_matrix(camera: &CameraSpec, far: f64) -> DMat4 {
    let gl = camera.raster_projection(far).matrix();
    // z' = (z + w) / 2: OpenGL's [-w, w] depth to wgpu's [0, w].
    let depth = DMat4::from_cols(
        DVec4::new(1.0, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.5, 0.0),
        DVec4::new(0.0, 0.0, 0.5, 1.0),
    );
    depth * gl
}

/// What the preview cannot show of `scene` (drawn with shadows, from n x n points of each area
/// light, where `shadows` is `Some(n)`), one sentence each (said to the user).
pub fn omissions(scene: &Scene, shadows: Option<u32>) -> Vec<String> {
    let camera = &scene.camera;
    let mut notes = vec![format!(
        "the preview has {} no specular lobes; curved mirrors (spheres, tori, ellipsoids, \
         cylinders, Bezier patches) reflect the scene by Fermat's principle (one reflection per \
         point and surface: a sphere, a torus's half, a Bezier patch; each other once, tori \
         and teapots themselves only with --self-reflections; a mirror seen in one reflects \
         the background, or nothing at max_depth 1), other mirrors show their diffuse term \
         only",
        match shadows {
            None => "no shadows (--shadows draws them by shadow maps) and".to_string(),
            Some(1) =>
                "hard shadows only (shadow maps; area lights' from their centres) and".into(),
            Some(n) => format!(
                "shadows by shadow maps (area lights' from {n}x{n} points of each, a penumbra \
                 of {} steps) and",
                n * n
            ),
        }
    )];
    if !camera.is_pinhole() {
        notes.push(format!(
            "the preview shows no depth of field: the f/{} lens is drawn as a pinhole at its \
             centre{}",
            camera.f_number,
            if camera.movements.lens_tilt != 0.0 || camera.movements.lens_swing != 0.0 {
                " (lens tilt and swing move only the plane of sharp focus, which it cannot show)"
            } else {
                ""
            }
        ));
    }
    if camera.is_orthographic() {
        notes.push(
            "the orthographic camera's geometry is drawn parallel, but its mirrors and highlights \
             are drawn as seen from its position (the preview's reflections need a centre of \
             projection)"
                .into(),
        );
    }
    if camera.shutter[1] > camera.shutter[0] {
        notes.push("the preview shows moving shapes where they stand at time 0, unblurred".into());
    }
    notes
}
