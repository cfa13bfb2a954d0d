//! The raster preview's CPU side (`chambre preview`): the scene's primitives as triangles for
//! wgpu's render pipeline (spheres and quads tessellated, planes as large quads), and the view
//! camera's projection as the ray tracer defines it (`CameraSpec::raster_projection`: film tilt,
//! swing and shift are a rotation of the view and an off-axis frustum). The GPU side is
//! `gpu::preview`, its shader `wgsl/preview.wgsl`.
//!
//! What the preview leaves out, by design (it trades accuracy for speed): shadows, mirror
//! reflections, specular lobes and depth of field (a lens is drawn as a pinhole at its centre;
//! lens tilt and swing do not move a pinhole's rays). Area lights light it as points at their
//! centres with their power's cosine falloff.

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec4, Vec3};

use crate::layout::{GpuPrimitive, PRIM_PLANE, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE};
use crate::pack::FlatScene;
use crate::scene::Scene;

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
    /// Unused: keeps the vertex 32 bytes.
    pub _pad: u32,
}

/// Segments around a tessellated sphere (and half as many from pole to pole).
pub const SPHERE_SEGMENTS: u32 = 64;

/// The preview's uniforms: the clip matrix and what shading needs of the frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PreviewUniforms {
    /// World to wgpu clip space (depth in [0, 1]), column-major.
    pub clip: [[f32; 4]; 4],
    /// Lights in the scene's light array.
    pub light_count: u32,
    /// Padding to the WGSL layout.
    pub _pad: [u32; 3],
    /// Ambient radiance: each surface adds diffuse * ambient.
    pub ambient: [f32; 4],
    /// The eye (the lens centre), world space; `w` unused.
    pub eye: [f32; 4],
}

/// Every bounded primitive and plane of `scene` as triangles; `extent` sizes the planes (they
/// reach `extent` from their point each way).
pub fn tessellate(scene: &FlatScene, extent: f32) -> Vec<PreviewVertex> {
    let end = (scene.frame.plane_start + scene.frame.plane_count) as usize;
    let mut vertices = Vec::new();
    for (i, p) in scene.prims[..end].iter().enumerate() {
        let normals = scene.normals.get(p.normals as usize);
        match p.kind {
            PRIM_TRIANGLE => triangle(&mut vertices, p, normals.map(|n| n.n)),
            PRIM_QUAD => quad(&mut vertices, p),
            PRIM_SPHERE => sphere(&mut vertices, p),
            PRIM_PLANE => plane(&mut vertices, p, extent),
            _ => unreachable!("primitive {i} of kind {}", p.kind),
        }
    }
    vertices
}

fn vertex(position: Vec3, normal: Vec3, material: u32) -> PreviewVertex {
    PreviewVertex {
        position: position.to_array(),
        material,
        normal: normal.to_array(),
        _pad: 0,
    }
}

fn triangle(out: &mut Vec<PreviewVertex>, p: &GpuPrimitive, normals: Option<[f32; 9]>) {
    let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3::from);
    let face = (b - a).cross(c - a).normalize_or_zero();
    for (k, v) in [a, b, c].into_iter().enumerate() {
        let n = normals.map_or(face, |n| Vec3::from_slice(&n[3 * k..3 * k + 3]));
        out.push(vertex(v, n, p.material));
    }
}

fn quad(out: &mut Vec<PreviewVertex>, p: &GpuPrimitive) {
    let [corner, u, v] = [p.p0, p.p1, p.p2].map(Vec3::from);
    let n = u.cross(v).normalize_or_zero();
    for point in [
        corner,
        corner + u,
        corner + u + v,
        corner,
        corner + u + v,
        corner + v,
    ] {
        out.push(vertex(point, n, p.material));
    }
}

fn sphere(out: &mut Vec<PreviewVertex>, p: &GpuPrimitive) {
    let (centre, radius) = (Vec3::from(p.p0), p.p1[0]);
    let (around, down) = (SPHERE_SEGMENTS, SPHERE_SEGMENTS / 2);
    let at = |i: u32, j: u32| {
        let phi = std::f32::consts::TAU * i as f32 / around as f32;
        let theta = std::f32::consts::PI * j as f32 / down as f32;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    };
    for j in 0..down {
        for i in 0..around {
            let corners = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            for k in [0, 1, 2, 0, 2, 3] {
                let n = corners[k];
                out.push(vertex(centre + radius * n, n, p.material));
            }
        }
    }
}

fn plane(out: &mut Vec<PreviewVertex>, p: &GpuPrimitive, extent: f32) {
    let (point, n) = (Vec3::from(p.p0), Vec3::from(p.p1).normalize());
    let u = n.any_orthonormal_vector() * extent;
    let v = n.cross(u);
    let corner = point - u - v;
    let (u2, v2) = (2.0 * u, 2.0 * v);
    for q in [
        corner,
        corner + u2,
        corner + u2 + v2,
        corner,
        corner + u2 + v2,
        corner + v2,
    ] {
        out.push(vertex(q, n, p.material));
    }
}

/// The radius of the scene's bounded primitives around their centre (at least 1e-6).
pub fn bounded_radius(scene: &FlatScene) -> f32 {
    let bounded = &scene.prims[..scene.frame.plane_start as usize];
    let points = bounded.iter().flat_map(|p| match p.kind {
        PRIM_SPHERE => {
            let (c, r) = (Vec3::from(p.p0), p.p1[0]);
            vec![c - Vec3::splat(r), c + Vec3::splat(r)]
        }
        PRIM_QUAD => {
            let [c, u, v] = [p.p0, p.p1, p.p2].map(Vec3::from);
            vec![c, c + u, c + v, c + u + v]
        }
        _ => vec![Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2)],
    });
    let (lo, hi) = points.fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), q| (lo.min(q), hi.max(q)),
    );
    if lo.x > hi.x {
        return 1.0;
    }
    ((hi - lo).length() / 2.0).max(1e-6)
}

/// The clip matrix of the scene's camera for wgpu (depth in [0, 1]), with the far plane `far`
/// scene units away: `CameraSpec::raster_projection`'s OpenGL matrix with its depth remapped.
pub fn clip_matrix(scene: &Scene, far: f64) -> DMat4 {
    let gl = scene.camera.raster_projection(far).matrix();
    // z' = (z + w) / 2: OpenGL's [-w, w] depth to wgpu's [0, w].
    let depth = DMat4::from_cols(
        DVec4::new(1.0, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.5, 0.0),
        DVec4::new(0.0, 0.0, 0.5, 1.0),
    );
    depth * gl
}

/// What the preview cannot show of `scene`'s camera, one sentence each (said to the user).
pub fn omissions(scene: &Scene) -> Vec<String> {
    let camera = &scene.camera;
    let mut notes = vec!["the preview has no shadows, mirror reflections or specular lobes".into()];
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
    if camera.shutter[1] > camera.shutter[0] {
        notes.push("the preview shows moving shapes where they stand at time 0, unblurred".into());
    }
    notes
}
