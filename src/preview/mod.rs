//! The raster preview's CPU side (`chambre preview`): the scene's primitives as triangles for
//! wgpu's render pipeline (`tessellate`: curved shapes cut as finely as the camera needs, quads
//! as two triangles, planes as large quads), and the view
//! camera's projection as the ray tracer defines it (`CameraSpec::raster_projection`: film tilt,
//! swing and shift are a rotation of the view and an off-axis frustum). The GPU side is
//! `gpu::preview`, its shader `wgsl/preview.wgsl`.
//!
//! What the preview leaves out, by design (it trades accuracy for speed): shadows unless asked
//! (`shadows`: hard ones, by shadow maps), specular
//! lobes, reflections other than curved mirrors' (spheres, tori, ellipsoids, cylinders and
//! Bézier patches, drawn by Fermat's principle, seed 004: `reflectors`, `ReflectedSet`;
//! mirrors reflect each other once, and a torus or a teapot itself where asked: a mirror seen in
//! a mirror reflects the background, or nothing where the scene's paths bounce once) and depth of field (a lens is drawn as a pinhole at its centre; lens tilt and swing do
//! not move a pinhole's rays). Area lights light it exactly where nothing occludes them
//! (Lambert's formula for a polygon).

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DQuat, DVec3, DVec4, Vec3};

use crate::camera::{CameraSpec, Projection};
use crate::layout::{
    GpuReflector, PRIM_SPHERE, REFLECTOR_CYLINDER, REFLECTOR_ELLIPSOID, REFLECTOR_PATCH,
    REFLECTOR_SPHERE, REFLECTOR_TORUS,
};
use crate::pack::FlatScene;
use crate::scene::Scene;
use crate::scene::surface::Surface;
use reflections::fermat::{
    BezierPatch, Cylinder, Ellipsoid, Reflector as _, TorusHalf, TorusSearch, anchored_on_patch,
    anchored_on_torus_half,
};

pub mod reflections;
pub mod renderer;
mod shadows;
mod tessellate;
pub mod window;

pub use renderer::{
    PreviewFrame, PreviewOptions, PreviewRenderer, SHADOW_SHADER, StageTimes, draw, draw_with,
    extent_and_far, eye_of, shader_source,
};
pub use shadows::{
    CUBE_FACES, SHADOW_MAP_SIZE, SHADOW_MEMORY, SHADOW_NORMAL_OFFSET, SMALLEST_SHADOW_MAP,
    ShadowLight, ShadowPlan, cube_face, shadow_map_size,
};
use tessellate::vertex;
pub use tessellate::{
    CurvedShapes, Cut, DEFAULT_TOLERANCE_PX, Detail, Grid, PATCH_QUADS, ROUND_QUADS, Seen,
    SurfaceAt, UNSEEN_QUADS, coarse_note, fitting_grid, flat_triangles, grid_deviation, tessellate,
};

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

/// What the reflection pass needs of one search (`ReflectorPass` in
/// wgsl/preview_reflect.wgsl; one per search of a batch, in a storage array).
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

/// The surfaces the Fermat kernel solves on (`wgsl/fermat.wgsl`).
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
/// mirrors, mirror triangles and quads of meshes are drawn with their diffuse term only: the
/// seed's method is for smooth curved reflectors). None where the scene's paths do not bounce
/// (`max_depth` 0): the ray tracer shows no reflection there either.
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
fn reflector_tags(scene: &FlatScene, reflectors: &[Reflector]) -> Vec<u32> {
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
/// the error small (the seed subdivides its floor 16x16).
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
        vertex(grid_point(positions, (i, j), n), normal, t[0].material)
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

/// A key of the interactive preview (`chambre preview --window`), from the keyboard or from a
/// `--keys` script.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposeKey {
    /// Arrow up: film tilt up by `TURN_STEP_DEG`.
    Up,
    /// Arrow down: film tilt down.
    Down,
    /// Arrow left: film swing left.
    Left,
    /// Arrow right: film swing right.
    Right,
    /// A character key (see [`Composer::apply`]).
    Char(char),
    /// Escape: quit.
    Escape,
}

impl ComposeKey {
    /// A key named in a `--keys` script: `up`, `down`, `left`, `right`, `escape`, or one
    /// character.
    pub fn parse(name: &str) -> Option<ComposeKey> {
        Some(match name {
            "up" => ComposeKey::Up,
            "down" => ComposeKey::Down,
            "left" => ComposeKey::Left,
            "right" => ComposeKey::Right,
            "escape" | "esc" => ComposeKey::Escape,
            _ => {
                let mut chars = name.chars();
                match (chars.next(), chars.next()) {
                    (Some(c), None) => ComposeKey::Char(c.to_ascii_lowercase()),
                    _ => return None,
                }
            }
        })
    }
}

/// What a key asks of the window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposeAction {
    /// The camera changed: draw again.
    Changed,
    /// Save the composed scene.
    Save,
    /// Close the window.
    Quit,
    /// Nothing (a key without a meaning).
    Nothing,
}

/// Degrees a tilt, swing, pan or pitch key turns.
pub const TURN_STEP_DEG: f64 = 1.0;
/// Millimetres a shift key, or a notch of the mouse wheel, moves the film (an orthographic
/// camera's window: the same fraction of its height as of a 24 mm film's).
pub const SHIFT_STEP_MM: f64 = 1.0;
/// Degrees a mouse drag turns the camera or the film for each pixel the mouse moves: a drag
/// across a 320-pixel preview turns 32°.
pub const DRAG_DEG_PER_PX: f64 = 0.1;
/// Film tilt and swing, and the camera's pitch, stay within ± this (degrees): the scene
/// format's (−90°, 90°).
const TURN_LIMIT_DEG: f64 = 89.0;

/// What a drag of the mouse in the interactive preview moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    /// The left button: the camera pans and pitches after the mouse (right and up).
    Camera,
    /// The right button: the film swings and tilts after the mouse (right and up), as the
    /// arrow keys move it.
    Film,
}

/// The camera a user composes in the interactive preview: the scene's camera with film tilt,
/// swing and shift, and the camera turned (panned and pitched about its position). Keys:
/// arrows tilt and swing the film, `i`/`k` shift it up/down, `j`/`l` left/right, `a`/`d` pan
/// the camera, `w`/`x` pitch it, `r` resets, `s` saves, `q` or Escape quits. The mouse: a drag
/// with the left button turns the camera, with the right button the film (`Drag`), and the
/// wheel shifts the film.
#[derive(Clone, Debug)]
pub struct Composer {
    base: CameraSpec,
    /// Film tilt, swing (degrees) and shift (mm), as the scene fields are.
    pub film_tilt: f64,
    /// Film swing (degrees).
    pub film_swing: f64,
    /// Film shift [right, up] (mm).
    pub film_shift: [f64; 2],
    /// The camera turned right about its up direction (degrees).
    pub pan: f64,
    /// The camera turned up about its right direction (degrees).
    pub pitch: f64,
}

impl Composer {
    /// Starts from `camera` as the scene has it.
    pub fn new(camera: &CameraSpec) -> Composer {
        let m = &camera.movements;
        Composer {
            base: camera.clone(),
            film_tilt: m.film_tilt,
            film_swing: m.film_swing,
            film_shift: m.film_shift,
            pan: 0.0,
            pitch: 0.0,
        }
    }

    /// Applies one key; film tilt and swing stay inside the scene format's (−90°, 90°).
    pub fn apply(&mut self, key: ComposeKey) -> ComposeAction {
        let turn = |v: &mut f64, d: f64| *v = turned(*v, d);
        let step = self.shift_step_mm();
        match key {
            ComposeKey::Up => turn(&mut self.film_tilt, TURN_STEP_DEG),
            ComposeKey::Down => turn(&mut self.film_tilt, -TURN_STEP_DEG),
            ComposeKey::Left => turn(&mut self.film_swing, -TURN_STEP_DEG),
            ComposeKey::Right => turn(&mut self.film_swing, TURN_STEP_DEG),
            ComposeKey::Char('i') => self.film_shift[1] += step,
            ComposeKey::Char('k') => self.film_shift[1] -= step,
            ComposeKey::Char('j') => self.film_shift[0] -= step,
            ComposeKey::Char('l') => self.film_shift[0] += step,
            ComposeKey::Char('a') => self.pan -= TURN_STEP_DEG,
            ComposeKey::Char('d') => self.pan += TURN_STEP_DEG,
            ComposeKey::Char('w') => turn(&mut self.pitch, TURN_STEP_DEG),
            ComposeKey::Char('x') => turn(&mut self.pitch, -TURN_STEP_DEG),
            ComposeKey::Char('r') => *self = Composer::new(&self.base),
            ComposeKey::Char('s') => return ComposeAction::Save,
            ComposeKey::Char('q') | ComposeKey::Escape => return ComposeAction::Quit,
            ComposeKey::Char(_) => return ComposeAction::Nothing,
        }
        ComposeAction::Changed
    }

    /// Applies a drag of the mouse by `dx` pixels right and `dy` down (the window's cursor
    /// coordinates): what `drag` moves follows it, `DRAG_DEG_PER_PX` a pixel.
    pub fn drag(&mut self, drag: Drag, dx: f64, dy: f64) -> ComposeAction {
        if dx == 0.0 && dy == 0.0 {
            return ComposeAction::Nothing;
        }
        let (right, up) = (dx * DRAG_DEG_PER_PX, -dy * DRAG_DEG_PER_PX);
        match drag {
            Drag::Camera => {
                self.pan += right;
                self.pitch = turned(self.pitch, up);
            }
            Drag::Film => {
                self.film_swing = turned(self.film_swing, right);
                self.film_tilt = turned(self.film_tilt, up);
            }
        }
        ComposeAction::Changed
    }

    /// Applies a turn of the mouse wheel by `notches` (away from the user positive) and
    /// `across` (right positive, a wheel that tilts or a touchpad): the film shifts up and
    /// right, `SHIFT_STEP_MM` a notch.
    pub fn wheel(&mut self, across: f64, notches: f64) -> ComposeAction {
        if across == 0.0 && notches == 0.0 {
            return ComposeAction::Nothing;
        }
        let step = self.shift_step_mm();
        self.film_shift[0] += across * step;
        self.film_shift[1] += notches * step;
        ComposeAction::Changed
    }

    /// The point the turned camera looks at: the scene's `look_at` rotated about the camera's
    /// position, by `pan` about the scene's up and `pitch` about the camera's right.
    pub fn look_at(&self) -> DVec3 {
        let c = &self.base;
        let view = c.look_at - c.position;
        let up = c.up.normalize();
        let panned = DQuat::from_axis_angle(up, -self.pan.to_radians()) * view;
        let right = panned.cross(up).normalize();
        let pitched = DQuat::from_axis_angle(right, self.pitch.to_radians()) * panned;
        c.position + pitched
    }

    /// The scene's camera as composed. A focus solved from `focus_points` is kept as it was
    /// (the preview draws a pinhole; the saved scene solves it again).
    pub fn camera(&self) -> CameraSpec {
        let mut camera = self.base.clone();
        camera.look_at = self.look_at();
        camera.movements.film_tilt = self.film_tilt;
        camera.movements.film_swing = self.film_swing;
        camera.movements.film_shift = self.film_shift;
        camera
    }

    /// How far a shift key moves the film (mm): `SHIFT_STEP_MM`, or for an orthographic
    /// camera the same fraction of its window's height as of a 24 mm film.
    fn shift_step_mm(&self) -> f64 {
        match self.base.projection {
            Projection::Perspective => SHIFT_STEP_MM,
            Projection::Orthographic => SHIFT_STEP_MM * self.base.film_mm[1] / 24.0,
        }
    }

    /// The film shift in the scene file's units, and their name: mm, or scene units for an
    /// orthographic camera's window.
    fn shift_as_given(&self) -> ([f64; 2], &'static str) {
        match self.base.projection {
            Projection::Perspective => (self.film_shift, "mm"),
            Projection::Orthographic => (
                self.film_shift.map(|v| v * self.base.units_per_mm),
                "scene units",
            ),
        }
    }

    /// The scene overrides (`--set` syntax) that give a scene this composition.
    pub fn overrides(&self) -> Vec<String> {
        // `{:?}` writes 1.0 as `1.0`, which TOML reads as a float, as the fields are.
        let [x, y, z] = self.look_at().to_array();
        let (shift, _) = self.shift_as_given();
        vec![
            format!("camera.film_tilt={:?}", self.film_tilt),
            format!("camera.film_swing={:?}", self.film_swing),
            format!("camera.film_shift=[{:?}, {:?}]", shift[0], shift[1]),
            format!("camera.look_at=[{x:?}, {y:?}, {z:?}]"),
        ]
    }

    /// The movements and turns, for the window's title and the terminal.
    pub fn figures(&self) -> String {
        let (shift, unit) = self.shift_as_given();
        format!(
            "film tilt {:+.1}°, swing {:+.1}°, shift [{:+.1}, {:+.1}] {unit}; camera pan \
             {:+.1}°, pitch {:+.1}°",
            self.film_tilt, self.film_swing, shift[0], shift[1], self.pan, self.pitch
        )
    }
}

/// `v` turned by `d` degrees, kept within `TURN_LIMIT_DEG`.
fn turned(v: f64, d: f64) -> f64 {
    (v + d).clamp(-TURN_LIMIT_DEG, TURN_LIMIT_DEG)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn camera() -> CameraSpec {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/architecture.toml");
        Scene::load(&path, &[]).unwrap().camera
    }

    #[test]
    fn keys_move_the_film_and_turn_the_camera_by_their_steps() {
        let start = camera();
        let mut composer = Composer::new(&start);
        for key in ["up", "up", "left", "i", "l", "l", "d", "w"] {
            let key = ComposeKey::parse(key).unwrap();
            assert_eq!(composer.apply(key), ComposeAction::Changed);
        }
        let m = &start.movements;
        assert_eq!(composer.film_tilt, m.film_tilt + 2.0);
        assert_eq!(composer.film_swing, m.film_swing - 1.0);
        assert_eq!(
            composer.film_shift,
            [m.film_shift[0] + 2.0, m.film_shift[1] + 1.0]
        );
        // Turning keeps the distance to the point looked at, and turns by the angle asked.
        let before = start.look_at - start.position;
        let after = composer.look_at() - start.position;
        assert!((after.length() - before.length()).abs() < 1e-9 * before.length());
        let angle = before.angle_between(after).to_degrees();
        assert!(angle > 1.0 && angle < 2.0, "{angle}");
        assert_eq!(composer.apply(ComposeKey::Char('s')), ComposeAction::Save);
        assert_eq!(composer.apply(ComposeKey::Escape), ComposeAction::Quit);
        assert_eq!(
            composer.apply(ComposeKey::Char('z')),
            ComposeAction::Nothing
        );
        composer.apply(ComposeKey::Char('r'));
        assert_eq!(composer.film_tilt, m.film_tilt);
        assert!((composer.look_at() - start.look_at).length() < 1e-12);
    }

    #[test]
    fn the_mouse_turns_what_it_drags_after_it_and_its_wheel_shifts_the_film() {
        let start = camera();
        let m = &start.movements;
        let mut composer = Composer::new(&start);
        // 50 px right and 20 px up with the left button: the camera pans right 5° and pitches
        // up 2°; the film stays.
        assert_eq!(
            composer.drag(Drag::Camera, 50.0, -20.0),
            ComposeAction::Changed
        );
        assert_eq!((composer.pan, composer.pitch), (5.0, 2.0));
        assert_eq!(
            (composer.film_tilt, composer.film_swing),
            (m.film_tilt, m.film_swing)
        );
        let mut keyed = Composer::new(&start);
        for _ in 0..5 {
            keyed.apply(ComposeKey::Char('d'));
        }
        for _ in 0..2 {
            keyed.apply(ComposeKey::Char('w'));
        }
        let (dragged, typed) = (composer.look_at(), keyed.look_at());
        assert!((dragged - typed).length() < 1e-12, "{dragged} {typed}");
        // The right button moves the film as the arrow keys do: 30 px left and 10 px down.
        composer.drag(Drag::Film, -30.0, 10.0);
        assert_eq!(composer.film_swing, m.film_swing - 3.0);
        assert_eq!(composer.film_tilt, m.film_tilt - 1.0);
        // Two notches away from the user and one to the right.
        assert_eq!(composer.wheel(1.0, 2.0), ComposeAction::Changed);
        assert_eq!(
            composer.film_shift,
            [m.film_shift[0] + 1.0, m.film_shift[1] + 2.0]
        );
        // A move that moves nothing asks for no frame; a drag's tilt stops as a key's does.
        assert_eq!(composer.drag(Drag::Film, 0.0, 0.0), ComposeAction::Nothing);
        assert_eq!(composer.wheel(0.0, 0.0), ComposeAction::Nothing);
        composer.drag(Drag::Film, 0.0, -1e6);
        assert_eq!(composer.film_tilt, TURN_LIMIT_DEG);
        composer.drag(Drag::Camera, 0.0, 1e6);
        assert_eq!(composer.pitch, -TURN_LIMIT_DEG);
    }

    #[test]
    fn film_tilt_stops_short_of_a_right_angle() {
        let mut composer = Composer::new(&camera());
        for _ in 0..200 {
            composer.apply(ComposeKey::Up);
        }
        assert_eq!(composer.film_tilt, 89.0);
    }

    #[test]
    fn the_overrides_give_the_composed_camera() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/architecture.toml");
        let mut composer = Composer::new(&camera());
        for key in ["down", "down", "right", "k", "a", "x"] {
            composer.apply(ComposeKey::parse(key).unwrap());
        }
        let reloaded = Scene::load(&path, &composer.overrides()).unwrap().camera;
        let composed = composer.camera();
        assert_eq!(reloaded.movements, composed.movements);
        assert!((reloaded.look_at - composed.look_at).length() < 1e-9);
    }

    #[test]
    fn an_orthographic_composition_saves_its_shift_in_scene_units() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elevation.toml");
        let camera = Scene::load(&path, &[]).unwrap().camera;
        let mut composer = Composer::new(&camera);
        for key in ["i", "i", "l", "up"] {
            composer.apply(ComposeKey::parse(key).unwrap());
        }
        // A step is 1/24 of the 48-unit window's height: 2 units.
        let [x, y] = camera.movements.film_shift.map(|v| v * camera.units_per_mm);
        assert!(composer.figures().contains(&format!(
            "shift [{:+.1}, {:+.1}] scene units",
            x + 2.0,
            y + 4.0
        )));
        let reloaded = Scene::load(&path, &composer.overrides()).unwrap().camera;
        let composed = composer.camera();
        for (a, b) in reloaded
            .movements
            .film_shift
            .iter()
            .zip(composed.movements.film_shift)
        {
            assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "{a} against {b}");
        }
        assert_eq!(reloaded.movements.film_tilt, composed.movements.film_tilt);
    }

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
        let t = corners.map(|p| vertex(p, normal.normalize(), 3));
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
