//! The preview's reflections in curved mirrors, by Fermat's principle: which shapes are
//! mirrors and the surfaces searched on each ([`reflectors`], [`MirrorSurface`]), the triangles
//! they reflect ([`ReflectedSet`]), the search (`fermat`: the solver's CPU side, f64), its GPU
//! kernels (`kernel`: the solves and the cull of the reflected triangles) and the passes that
//! draw the reflections over the main pass (`passes`). The method: docs/fermat.md.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::layout::{
    GpuReflector, PRIM_SPHERE, REFLECTOR_CYLINDER, REFLECTOR_ELLIPSOID, REFLECTOR_PATCH,
    REFLECTOR_SPHERE, REFLECTOR_TORUS,
};
use crate::pack::FlatScene;
use crate::preview::{PreviewVertex, bounded_radius};
use crate::scene::parametric::{BezierPatch, Cylinder, Ellipsoid};
use crate::scene::surface::Surface;
use fermat::{Reflector as _, TorusHalf, TorusSearch, anchored_on_patch, anchored_on_torus_half};

pub mod fermat;
pub mod kernel;
pub(crate) mod passes;

/// What the reflection pass needs of one search (`ReflectorPass` in
/// wgsl/preview/reflect.wgsl; one per search of a batch, in a storage array).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ReflectorPass {
    /// Reflected depths |P − V| are divided by this to land in [0, 1].
    pub far: f32,
    /// 1 + the index of the search's mirror: the id the main pass wrote where it is seen.
    pub id: u32,
    /// The mirror's material.
    pub material: u32,
    /// Vertices each search solves: the length of a search's row of reflection points.
    pub solves: u32,
}

/// A curved mirror the preview reflects in by Fermat's principle.
#[derive(Clone, Debug, PartialEq)]
pub struct Reflector {
    /// Its Fermat searches: one per surface of the mirror (a sphere's, each half of a torus,
    /// each of a teapot's patches); each can show a reflection of a point.
    pub searches: Vec<MirrorSurface>,
    /// Its primitives' indices in the flattened scene (a sphere's one, a torus's triangles).
    pub prims: Vec<usize>,
    /// Its material's index.
    pub material: u32,
    /// Its material's mirror reflectance per channel.
    pub mirror: Vec3,
}

impl Reflector {
    /// Whether a surface of the mirror can see the mirror itself (`MirrorSurface::sees_itself`).
    pub fn sees_itself(&self) -> bool {
        self.searches.iter().any(MirrorSurface::sees_itself)
    }
}

/// The surfaces the Fermat kernel solves on (`wgsl/preview/fermat.wgsl`).
// A scene has a handful (a teapot 32): copies of a patch's 384 bytes cost nothing, and Copy
// keeps the searches plain values.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MirrorSurface {
    /// A sphere (a primitive of its own).
    Sphere {
        /// Centre (scene units).
        center: Vec3,
        /// Radius (scene units).
        radius: f32,
    },
    /// One half of a torus (rendered as a mesh), whose images its search shows: a torus is
    /// searched twice (`TorusHalf`).
    Torus(TorusSearch),
    /// A bicubic Bézier patch (rendered with its neighbours as a mesh): reflections found
    /// outside its parameter square belong to a neighbour or to nothing.
    Patch(BezierPatch),
    /// An ellipsoid (rendered as a mesh).
    Ellipsoid(Ellipsoid),
    /// A cylinder `height` tall above its base circle (rendered as a mesh, open at both ends).
    Cylinder {
        /// Its base circle's centre, radius and orientation.
        cylinder: Cylinder,
        /// Its height (scene units).
        height: f64,
    },
}

impl MirrorSurface {
    /// Its `layout::REFLECTOR_*` kind (the fermat pipeline that solves on it).
    pub fn kind(&self) -> u32 {
        match self {
            MirrorSurface::Sphere { .. } => REFLECTOR_SPHERE,
            MirrorSurface::Torus(_) => REFLECTOR_TORUS,
            MirrorSurface::Patch(_) => REFLECTOR_PATCH,
            MirrorSurface::Ellipsoid(_) => REFLECTOR_ELLIPSOID,
            MirrorSurface::Cylinder { .. } => REFLECTOR_CYLINDER,
        }
    }

    /// Whether the surface can reflect points of its own mirror: a torus's inner ring and a
    /// teapot's spout, handle and lid see the rest of it; a sphere, an ellipsoid and a cylinder
    /// (seen from outside, as the search sees it) are convex.
    pub fn sees_itself(&self) -> bool {
        matches!(self, MirrorSurface::Torus(_) | MirrorSurface::Patch(_))
    }

    /// Whether its search draws a reflected triangle whose corners' reflections show at
    /// parameters `uvs` (the CPU twin of `fermat_cull`'s anchoring): a patch's and a torus
    /// half's search draws those with a corner on its part of the mirror, the others all.
    pub fn anchors(&self, uvs: [glam::DVec2; 3]) -> bool {
        match self {
            MirrorSurface::Patch(_) => anchored_on_patch(uvs),
            MirrorSurface::Torus(search) => anchored_on_torus_half(uvs, search.half),
            _ => true,
        }
    }

    /// The Fermat kernel's uniforms for this surface, the eye at `eye`, `count` vertices.
    pub fn gpu(&self, eye: Vec3, count: u32) -> GpuReflector {
        let mut reflector = GpuReflector {
            eye: eye.to_array(),
            count,
            kind: self.kind(),
            orientation: glam::Quat::IDENTITY.to_array(),
            ..Default::default()
        };
        match *self {
            MirrorSurface::Sphere { center, radius } => {
                reflector.center = center.to_array();
                reflector.radius = radius;
            }
            MirrorSurface::Torus(TorusSearch { torus: t, half }) => {
                reflector.center = t.center.as_vec3().to_array();
                reflector.radius = t.major as f32;
                reflector.minor = t.minor as f32;
                reflector.orientation = t.orientation.as_quat().to_array();
                reflector.torus_half = (half == TorusHalf::Inner) as u32;
            }
            MirrorSurface::Patch(patch) => {
                for (k, p) in patch.points.iter().flatten().enumerate() {
                    reflector.control[k] = p.as_vec3().extend(0.0).to_array();
                }
                reflector.eye_uv = patch.crossing(eye.as_dvec3()).as_vec2().to_array();
            }
            MirrorSurface::Ellipsoid(e) => {
                reflector.center = e.center.as_vec3().to_array();
                reflector.radii = e.radii.as_vec3().extend(0.0).to_array();
                reflector.orientation = e.orientation.as_quat().to_array();
            }
            MirrorSurface::Cylinder { cylinder, height } => {
                reflector.center = cylinder.center.as_vec3().to_array();
                reflector.radius = cylinder.radius as f32;
                reflector.height = height as f32;
                reflector.orientation = cylinder.orientation.as_quat().to_array();
            }
        }
        reflector
    }
}

/// The scene's curved mirrors: mirror spheres in primitive order, then the scene's mirror
/// parametric surfaces (tori, ellipsoids, cylinders, Bézier shapes; flat
/// mirrors, mirror triangles and quads of meshes are drawn with their diffuse term only:
/// Roger and Holzschuch's Fermat search is for smooth curved reflectors). None where the
/// scene's paths do not bounce (`max_depth` 0): the ray tracer shows no reflection there
/// either.
pub fn reflectors(scene: &FlatScene) -> Vec<Reflector> {
    if scene.frame.max_depth == 0 {
        return Vec::new();
    }
    let mirror_of = |material: u32| Vec3::from(scene.materials[material as usize].mirror);
    let bounded = &scene.prims[..scene.frame.plane_start as usize];
    let spheres = bounded
        .iter()
        .enumerate()
        .filter(|(_, p)| p.kind == PRIM_SPHERE)
        .map(|(prim, p)| Reflector {
            searches: vec![MirrorSurface::Sphere {
                center: Vec3::from(p.p0),
                radius: p.p1[0],
            }],
            prims: vec![prim],
            material: p.material,
            mirror: mirror_of(p.material),
        });
    let surfaces = scene.surfaces.iter().filter_map(|s| {
        let material = scene.prims[*s.prims.first()? as usize].material;
        Some(Reflector {
            searches: match &s.surface {
                Surface::Torus(torus) => [TorusHalf::Outer, TorusHalf::Inner]
                    .map(|half| {
                        MirrorSurface::Torus(TorusSearch {
                            torus: *torus,
                            half,
                        })
                    })
                    .to_vec(),
                Surface::Patches(patches) => {
                    patches.iter().map(|&p| MirrorSurface::Patch(p)).collect()
                }
                Surface::Ellipsoid(e) => vec![MirrorSurface::Ellipsoid(*e)],
                Surface::Cylinder { cylinder, height } => vec![MirrorSurface::Cylinder {
                    cylinder: *cylinder,
                    height: *height,
                }],
            },
            prims: s.prims.iter().map(|&p| p as usize).collect(),
            material,
            mirror: mirror_of(material),
        })
    });
    spheres
        .chain(surfaces)
        .filter(|r| r.mirror.max_element() > 0.0)
        .collect()
}

/// What `--self-reflections` cannot do in `scene`, said to the user: `None` where a curved
/// mirror of it can see itself (a torus, Bézier patches); else why it changes nothing.
pub fn self_reflections_note(scene: &FlatScene) -> Option<String> {
    let mirrors = reflectors(scene);
    match (
        mirrors.is_empty(),
        mirrors.iter().any(Reflector::sees_itself),
    ) {
        (_, true) => None,
        (true, false) => Some(
            "--self-reflections changes nothing here: the scene has no curved mirror to \
             reflect in (or max_depth 0)"
                .into(),
        ),
        (false, false) => Some(
            "--self-reflections changes nothing here: the scene's curved mirrors are spheres, \
             ellipsoids or cylinders, convex from outside, which cannot see themselves"
                .into(),
        ),
    }
}

/// Per primitive of `scene`, 1 + the index of the reflector it belongs to, or 0.
pub(crate) fn reflector_tags(scene: &FlatScene, reflectors: &[Reflector]) -> Vec<u32> {
    let mut tags = vec![0; scene.prims.len()];
    for (r, reflector) in reflectors.iter().enumerate() {
        for &p in &reflector.prims {
            tags[p] = r as u32 + 1;
        }
    }
    tags
}

/// How the reflectors' triangles are made from the main pass's (`tessellate`): every one not
/// on a reflector, each cut into n² triangles, n pieces along each edge (and, where the scene
/// has several curved mirrors or one that can see itself, the mirrors' own triangles uncut:
/// each mirror reflects the others, and a torus or a teapot reflects itself, once, showing
/// them as the ray tracer's last bounce does): n = `subdivision`, or where it is `None`, the fewest pieces that
/// leave no edge longer than `AUTO_PIECE` of the scene's radius (at most `MAX_AUTO_PIECES`).
/// The raster pipeline draws a reflected triangle straight between its vertices' reflection
/// points, where the true reflection of a straight edge is curved: subdividing is what keeps
/// the error small (Roger and Holzschuch subdivide their floor 16x16).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectedSet {
    longest: f32,
    mirrors_reflected: bool,
    subdivision: Option<u32>,
}

impl ReflectedSet {
    /// The reflected set of `scene`'s mirrors, its triangles cut as `subdivision` says;
    /// with `self_reflections`, a mirror that can see itself reflects its own triangles.
    pub fn new(
        scene: &FlatScene,
        subdivision: Option<u32>,
        self_reflections: bool,
    ) -> ReflectedSet {
        let mirrors = reflectors(scene);
        ReflectedSet {
            longest: AUTO_PIECE * bounded_radius(scene),
            mirrors_reflected: mirrors.len() > 1
                || (self_reflections && mirrors.iter().any(Reflector::sees_itself)),
            subdivision,
        }
    }

    /// The reflected triangles made from `triangles`: a triangle's pieces depend on it alone,
    /// so the set of a mesh's triangles is the sets of its parts, in their order.
    pub fn of(&self, triangles: &[PreviewVertex]) -> Vec<PreviewVertex> {
        let mut out = Vec::new();
        for t in triangles.chunks_exact(3) {
            if t[0].reflector != 0 {
                // A mirror's triangles, cut for the camera, are reflected as they are (a convex
                // mirror's own searches leave its own out: `fermat_cull`); a lone convex mirror
                // reflects none.
                if self.mirrors_reflected {
                    out.extend_from_slice(t);
                }
                continue;
            }
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec3::from(v.position));
            let edge = a.distance(b).max(b.distance(c)).max(c.distance(a));
            let n = self
                .subdivision
                .unwrap_or_else(|| ((edge / self.longest).ceil() as u32).clamp(1, MAX_AUTO_PIECES));
            subdivide(&mut out, [t[0], t[1], t[2]], n.max(1));
        }
        out
    }
}

/// The tolerance (pixels on the film) a mirror's own triangles are cut for where it reflects
/// itself and the user names none (`--self-reflections` alone), as the command lines write it.
pub const SELF_REFLECTION_TOLERANCE_PX: &str = "2";

/// The automatic subdivision's longest edge, in scene radii (`bounded_radius`).
pub const AUTO_PIECE: f32 = 1.0 / 16.0;
/// The automatic subdivision's most pieces along an edge (planes, which reach far, stop there).
pub const MAX_AUTO_PIECES: u32 = 32;

/// Cuts triangle `t` into `n`² triangles on the barycentric grid of step 1/n, normals
/// interpolated.
fn subdivide(out: &mut Vec<PreviewVertex>, t: [PreviewVertex; 3], n: u32) {
    let positions = t.map(|v| Vec3::from(v.position));
    let normals = t.map(|v| Vec3::from(v.normal));
    let at = |i: u32, j: u32| {
        let normal = grid_point(normals, (i, j), n).normalize_or(normals[0]);
        PreviewVertex::new(grid_point(positions, (i, j), n), normal, t[0].material)
    };
    for j in 0..n {
        for i in 0..n - j {
            out.extend([at(i, j), at(i + 1, j), at(i, j + 1)]);
            if i + j + 1 < n {
                out.extend([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
}

/// The point (or normal) of `corners` at grid corner (i, j) of a triangle cut `n` times along
/// each edge: barycentrics (1 − i/n − j/n, i/n, j/n), as `subdivide` places its vertices.
pub fn grid_point(corners: [Vec3; 3], (i, j): (u32, u32), n: u32) -> Vec3 {
    let (a, b) = (i as f32 / n as f32, j as f32 / n as f32);
    corners[0] * (1.0 - a - b) + corners[1] * a + corners[2] * b
}

/// The sub-triangle of a triangle cut `n` times along each edge (as
/// `subdivide` cuts it) holding the point of barycentrics (1 − a − b, a, b):
/// its corners on the grid of step 1/n and the point's weights on them.
pub fn sub_triangle(a: f32, b: f32, n: u32) -> ([(u32, u32); 3], [f32; 3]) {
    let (x, y) = (a * n as f32, b * n as f32);
    let i = (x.floor() as u32).min(n - 1);
    let j = (y.floor() as u32).min(n - 1 - i);
    let (fa, fb) = (x - i as f32, y - j as f32);
    if fa + fb <= 1.0 {
        ([(i, j), (i + 1, j), (i, j + 1)], [1.0 - fa - fb, fa, fb])
    } else {
        (
            [(i + 1, j), (i + 1, j + 1), (i, j + 1)],
            [1.0 - fb, fa + fb - 1.0, 1.0 - fa],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle cut n times along each edge gives n² triangles of the same orientation that
    /// tile it: their areas sum to its area, and every corner lies in its plane.
    #[test]
    fn subdividing_tiles_the_triangle() {
        let corners = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.5),
            Vec3::new(0.3, 1.5, -0.2),
        ];
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let t = corners.map(|p| PreviewVertex::new(p, normal.normalize(), 3));
        for n in [1, 2, 5, 16] {
            let mut out = Vec::new();
            subdivide(&mut out, t, n);
            assert_eq!(out.len(), 3 * (n * n) as usize);
            let mut area = 0.0;
            for piece in out.chunks_exact(3) {
                let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(piece[k].position));
                let cross = (b - a).cross(c - a);
                assert!(cross.dot(normal) > 0.0, "n = {n}: a piece is flipped");
                area += cross.length() / 2.0;
                assert!(piece.iter().all(|v| v.material == 3 && v.reflector == 0));
            }
            assert!(
                (area - normal.length() / 2.0).abs() < 1e-5,
                "n = {n}: {area}"
            );
        }
    }

    /// Every point of the triangle falls in a sub-triangle with non-negative weights summing
    /// to 1 that put it back where it was.
    #[test]
    fn a_point_is_the_mix_of_its_sub_triangles_corners() {
        for n in [1, 2, 3, 16] {
            for (a, b) in [
                (0.0, 0.0),
                (1.0, 0.0),
                (0.0, 1.0),
                (0.3, 0.7),
                (0.41, 0.2),
                (0.9, 0.05),
            ] {
                let (corners, w) = sub_triangle(a, b, n);
                assert!(w.iter().all(|&w| w >= -1e-6), "{n} {a} {b}: {w:?}");
                assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
                let mix = |f: fn((u32, u32)) -> u32| {
                    corners
                        .iter()
                        .zip(w)
                        .map(|(&c, w)| f(c) as f32 / n as f32 * w)
                        .sum::<f32>()
                };
                assert!((mix(|c| c.0) - a).abs() < 1e-5, "{n} {a} {b}");
                assert!((mix(|c| c.1) - b).abs() < 1e-5, "{n} {a} {b}");
                assert!(corners.iter().all(|&(i, j)| i + j <= n));
            }
        }
    }
}
