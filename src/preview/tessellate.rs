//! The preview's triangles: the scene's flat primitives as they are (planes as large quads), and
//! its curved shapes (spheres, tori, ellipsoids, cylinders, Bézier patches) cut for the camera
//! that sees them. Each curved shape gets a coarse grid ([`fitting_grid`]) whose flat triangles
//! stray from the surface by at most a tolerance in pixels on the film ([`Detail`]), as
//! real-time renderers choose a level of detail: a shape near the camera gets more triangles
//! than the same shape far away, one the film does not show a fixed grid ([`UNSEEN_QUADS`]).
//! The ray tracers keep the exact surfaces (patches: their own fine mesh).

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};

use super::PreviewVertex;
use super::reflections::{reflector_tags, reflectors};
use crate::layout::{GpuPrimitive, PRIM_PLANE, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE};
use crate::pack::FlatScene;
use crate::scene::parametric::ParametricSurface as _;
use crate::scene::surface::{Surface, grids_cut_alike, patches_mesh_cut};

/// How far (pixels on the film) the preview's triangles may stray from a curved surface unless
/// told otherwise (`chambre preview --tessellation-tolerance`).
pub const DEFAULT_TOLERANCE_PX: f64 = 0.5;

/// The fewest and the most quads a sphere or a round surface is cut into, [around its axis,
/// across]. The fewest keep a solid however small the shape looks (with one quad across, a
/// sphere's would join its poles and vanish, a torus's tube flatten); a shape that would need
/// more than the most (or reaches the eye's plane) stops there and is reported
/// ([`Cut::within`]).
pub const ROUND_QUADS: [[u32; 2]; 2] = [[8, 4], [256, 128]];

/// The fewest and the most quads along each side of a Bézier patch (the most: the ray
/// tracers' mesh, `scene::surface::PATCH_QUADS`).
pub const PATCH_QUADS: [u32; 2] = [1, crate::scene::surface::PATCH_QUADS];

/// Every primitive and plane of `scene` as triangles, its curved shapes cut for `detail`;
/// `extent` sizes the planes (they reach `extent` from their point each way).
pub fn tessellate(scene: &FlatScene, extent: f32, detail: &Detail) -> Vec<PreviewVertex> {
    let curved = CurvedShapes::of(scene);
    let mut vertices = flat_triangles(scene, extent);
    vertices.extend(curved.triangles(&curved.cuts(detail)));
    vertices
}

/// The scene's triangles, quads and planes (reaching `extent` from their point each way) as
/// triangles: what does not change with the camera.
pub fn flat_triangles(scene: &FlatScene, extent: f32) -> Vec<PreviewVertex> {
    let end = (scene.frame.plane_start + scene.frame.plane_count) as usize;
    let tags = reflector_tags(scene, &reflectors(scene));
    let mut on_surface = vec![false; scene.prims.len()];
    for s in &scene.surfaces {
        s.prims.iter().for_each(|&p| on_surface[p as usize] = true);
    }
    let mut vertices = Vec::new();
    for (i, p) in scene.prims[..end].iter().enumerate() {
        if on_surface[i] || p.kind == PRIM_SPHERE {
            continue;
        }
        let normals = scene.normals.get(p.normals as usize);
        let first = vertices.len();
        match p.kind {
            PRIM_TRIANGLE => triangle(&mut vertices, p, normals.map(|n| n.n)),
            PRIM_QUAD => quad(&mut vertices, p),
            PRIM_PLANE => plane(&mut vertices, p, extent),
            _ => unreachable!("primitive {i} of kind {}", p.kind),
        }
        for v in &mut vertices[first..] {
            v.reflector = tags[i];
        }
    }
    vertices
}

/// What the preview tells the user when `shapes` curved shapes stray further than
/// `tolerance_px` at their finest grid.
pub fn coarse_note(shapes: usize, tolerance_px: f64) -> String {
    format!(
        "note: {shapes} curved shape(s) stray further than {tolerance_px} px from their \
         triangles at the finest grid the preview cuts ({} quads around a round shape, {} along \
         a patch's side), or reach the eye's plane",
        ROUND_QUADS[1][0], PATCH_QUADS[1]
    )
}

/// The camera curved shapes are cut for, and how far (pixels on the film) their triangles may
/// stray from them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detail {
    /// World to clip space (`super::clip_matrix`).
    clip: DMat4,
    /// Half the image's width and height in pixels: what clip x and y of 1 span.
    half_size: DVec2,
    tolerance_px: f64,
}

impl Detail {
    /// Shapes seen through the clip matrix `clip` in an image `size` pixels wide and high,
    /// within `tolerance_px` pixels.
    pub fn new(clip: DMat4, (width, height): (u32, u32), tolerance_px: f64) -> Detail {
        Detail {
            clip,
            half_size: DVec2::new(width as f64, height as f64) / 2.0,
            tolerance_px,
        }
    }

    /// The length (scene units) the tolerance spans where a shape sampled at `points` is seen
    /// largest: [`Seen::At`] 0 where some reach the eye's plane, [`Seen::OffFilm`] where the
    /// film does not show them.
    pub fn tolerance_over(&self, points: impl IntoIterator<Item = DVec3>) -> Seen {
        match self.pixels_per_unit(points) {
            None => Seen::OffFilm,
            Some(pixels) => Seen::At(self.tolerance_px / pixels),
        }
    }

    /// The most pixels one scene unit spans on the film over `points` (infinite where one lies
    /// at or behind the eye's plane), or `None` where the film shows none of them: every one
    /// behind the eye's plane, or every one beyond the same edge of the image.
    pub fn pixels_per_unit(&self, points: impl IntoIterator<Item = DVec3>) -> Option<f64> {
        let (mut most, mut before) = (0.0f64, false);
        // Per edge (right, left, top, bottom): whether every point so far lies beyond it.
        let mut beyond = [true; 4];
        for p in points {
            let c = self.clip * p.extend(1.0);
            before |= c.w > 0.0;
            let outside = [c.x > c.w, c.x < -c.w, c.y > c.w, c.y < -c.w].map(|o| o && c.w > 0.0);
            beyond = [0, 1, 2, 3].map(|k| beyond[k] && outside[k]);
            most = most.max(self.stretch(c));
        }
        (before && !beyond.contains(&true)).then_some(most)
    }

    /// Pixels per scene unit in the direction magnified most at the point of clip coordinates
    /// `c`: the largest singular value of the projection's Jacobian there (infinite at or
    /// behind the eye's plane).
    fn stretch(&self, c: DVec4) -> f64 {
        if c.w <= 0.0 {
            return f64::INFINITY;
        }
        let row = |i| self.clip.row(i).truncate();
        // d(x/w)/dp = (w ∂x/∂p − x ∂w/∂p) / w², in pixels.
        let jx = (row(0) * c.w - row(3) * c.x) * (self.half_size.x / (c.w * c.w));
        let jy = (row(1) * c.w - row(3) * c.y) * (self.half_size.y / (c.w * c.w));
        let (a, b, d) = (jx.dot(jx), jx.dot(jy), jy.dot(jy));
        ((a + d) / 2.0 + (((a - d) / 2.0).powi(2) + b * b).sqrt()).sqrt()
    }
}

/// Where the camera sees a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Seen {
    /// In front of the eye: the tolerance there (scene units; 0 where it reaches the eye's
    /// plane).
    At(f64),
    /// Not on the film (wholly behind the eye's plane, or beyond an edge of the image): only
    /// mirrors may show it.
    OffFilm,
}

/// A grid [`fitting_grid`] found: `quads` along u and along v, and whether its triangles keep
/// within the tolerance (false: it stopped at the most quads allowed, as where the surface
/// reaches the eye's plane).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Quads along u and along v.
    pub quads: [u32; 2],
    /// Whether the triangles keep within the tolerance.
    pub within: bool,
}

/// A surface's point and unit normal (zero where it has none, as at a pole) at (u, v).
pub type SurfaceAt<'a> = &'a dyn Fn(DVec2) -> (DVec3, DVec3);

/// How finely a curved shape is cut: `grids` holds a sphere's or round surface's grid, or
/// each patch's of a Bézier shape ([along u, along v] quads); `within`, whether its triangles
/// keep within the tolerance (false: some stopped at the most quads allowed, or reach the
/// eye's plane).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cut {
    /// The grid of each part.
    pub grids: Vec<[u32; 2]>,
    /// Whether the triangles keep within the tolerance.
    pub within: bool,
}

/// A coarse grid, from `least` to `most` quads, over the parameter rectangle `span` (lowest
/// and highest (u, v)) whose triangles keep within `tolerance` of the surface `at` (as
/// [`grid_deviation`] measures them): each round aims at the tolerance from the deviation's
/// fall with the square of the step and rounds up, so the grid may be a little finer than the
/// coarsest (the tests bound it: three quarters of it strays too far).
pub fn fitting_grid(
    at: SurfaceAt,
    span: [DVec2; 2],
    tolerance: f64,
    least: [u32; 2],
    most: [u32; 2],
) -> Grid {
    let mut quads = least;
    loop {
        let [along_u, along_v, anywhere] = grid_deviation(at, span, quads);
        if anywhere <= tolerance {
            return Grid {
                quads,
                within: true,
            };
        }
        // The deviation falls as the square of the step: aim each direction's at half the
        // tolerance (a quad's centre strays by about the sum of the two); where that asks
        // nothing more (its diagonals stray most), cut both finer.
        let aim = |n: u32, e: f64| ((n as f64 * (2.0 * e / tolerance).sqrt()).ceil() as u32).max(n);
        let clamp = |n: [u32; 2]| [0, 1].map(|k| n[k].clamp(least[k], most[k]));
        let mut next = clamp([aim(quads[0], along_u), aim(quads[1], along_v)]);
        if next == quads {
            let finer = (anywhere / tolerance).sqrt();
            next = clamp(quads.map(|n| ((n as f64 * finer).ceil() as u32).max(n + 1)));
        }
        if next == quads {
            return Grid {
                quads,
                within: false,
            };
        }
        quads = next;
    }
}

/// How far the triangles of a grid of `quads` over `span` stray from the surface `at`: the
/// largest distance, along the surface's normal, between a point of the flat triangles and the
/// surface point of the same parameters (the whole distance where the normal vanishes), at the
/// midpoints of the edges along u, at those along v, and anywhere sampled (those, both
/// diagonals' midpoints and the centroids of the four triangles a quad can be cut into, so
/// that the measure does not depend on the diagonal a mesh chooses). Along the normal, as a
/// flat point's drift along the surface (a patch's parameters do not run at an even speed)
/// moves no silhouette.
pub fn grid_deviation(at: SurfaceAt, span: [DVec2; 2], [nu, nv]: [u32; 2]) -> [f64; 3] {
    let step = (span[1] - span[0]) / DVec2::new(nu as f64, nv as f64);
    let uv = |i: f64, j: f64| span[0] + step * DVec2::new(i, j);
    let mut corners = Vec::with_capacity(((nu + 1) * (nv + 1)) as usize);
    for i in 0..=nu {
        for j in 0..=nv {
            corners.push(at(uv(i as f64, j as f64)).0);
        }
    }
    let corner = |i: u32, j: u32| corners[(i * (nv + 1) + j) as usize];
    let off = |flat: DVec3, i: f64, j: f64| {
        let (surface, normal) = at(uv(i, j));
        match normal == DVec3::ZERO {
            true => flat.distance(surface),
            false => (flat - surface).dot(normal).abs(),
        }
    };
    let (mut along_u, mut along_v, mut anywhere) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..=nu {
        for j in 0..=nv {
            let (fi, fj) = (i as f64, j as f64);
            if i < nu {
                let mid = (corner(i, j) + corner(i + 1, j)) / 2.0;
                along_u = along_u.max(off(mid, fi + 0.5, fj));
            }
            if j < nv {
                let mid = (corner(i, j) + corner(i, j + 1)) / 2.0;
                along_v = along_v.max(off(mid, fi, fj + 0.5));
            }
            if i == nu || j == nv {
                continue;
            }
            let [a, b, c, d] = [
                corner(i, j),
                corner(i + 1, j),
                corner(i + 1, j + 1),
                corner(i, j + 1),
            ];
            let (third, two) = (1.0 / 3.0, 2.0 / 3.0);
            for (flat, du, dv) in [
                ((a + c) / 2.0, 0.5, 0.5),
                ((b + d) / 2.0, 0.5, 0.5),
                ((a + b + c) / 3.0, two, third),
                ((a + c + d) / 3.0, third, two),
                ((a + b + d) / 3.0, third, third),
                ((b + c + d) / 3.0, two, two),
            ] {
                anywhere = anywhere.max(off(flat, fi + du, fj + dv));
            }
        }
    }
    [along_u, along_v, anywhere.max(along_u).max(along_v)]
}

/// The scene's curved shapes, which the preview cuts anew for each camera: its spheres and
/// parametric surfaces, each with its material and reflector tag.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvedShapes(Vec<CurvedShape>);

#[derive(Clone, Debug, PartialEq)]
struct CurvedShape {
    form: CurvedForm,
    material: u32,
    /// 0, or 1 + the index of the reflector it is (`PreviewVertex::reflector`).
    reflector: u32,
}

#[derive(Clone, Debug, PartialEq)]
enum CurvedForm {
    Sphere { center: DVec3, radius: f64 },
    Surface(Surface),
}

impl CurvedShapes {
    /// The spheres (in primitive order) and parametric surfaces of `scene`.
    pub fn of(scene: &FlatScene) -> CurvedShapes {
        let tags = reflector_tags(scene, &reflectors(scene));
        let bounded = &scene.prims[..scene.frame.plane_start as usize];
        let spheres = bounded
            .iter()
            .zip(&tags)
            .filter(|(p, _)| p.kind == PRIM_SPHERE)
            .map(|(p, &reflector)| CurvedShape {
                form: CurvedForm::Sphere {
                    center: Vec3::from(p.p0).as_dvec3(),
                    radius: p.p1[0] as f64,
                },
                material: p.material,
                reflector,
            });
        let surfaces = scene.surfaces.iter().filter_map(|s| {
            let first = *s.prims.first()? as usize;
            Some(CurvedShape {
                form: CurvedForm::Surface(s.surface.clone()),
                material: scene.prims[first].material,
                reflector: tags[first],
            })
        });
        CurvedShapes(spheres.chain(surfaces).collect())
    }

    /// How finely each shape is cut for `detail`, in order.
    pub fn cuts(&self, detail: &Detail) -> Vec<Cut> {
        self.0.iter().map(|s| s.form.cut(detail)).collect()
    }

    /// The shapes cut as `cuts` (from [`CurvedShapes::cuts`]) say.
    pub fn triangles(&self, cuts: &[Cut]) -> Vec<PreviewVertex> {
        let mut out = Vec::new();
        for (shape, cut) in self.0.iter().zip(cuts) {
            let first = out.len();
            match &shape.form {
                CurvedForm::Sphere { center, radius } => {
                    sphere(&mut out, (*center, *radius), cut.grids[0], shape.material);
                }
                CurvedForm::Surface(surface) => {
                    let mesh = match surface {
                        Surface::Patches(patches) => patches_mesh_cut(patches, &cut.grids),
                        round => round.mesh_of(cut.grids[0], 1),
                    };
                    let normals = mesh.normals.as_deref().unwrap_or_default();
                    for &k in mesh.triangles.iter().flatten() {
                        let (p, n) = (mesh.positions[k as usize], normals[k as usize]);
                        out.push(PreviewVertex::new(p, n, shape.material));
                    }
                }
            }
            for v in &mut out[first..] {
                v.reflector = shape.reflector;
            }
        }
        out
    }
}

impl CurvedForm {
    fn cut(&self, detail: &Detail) -> Cut {
        let grid = match self {
            CurvedForm::Sphere { center, radius } => {
                let at = |uv| {
                    let normal = sphere_point(DVec3::ZERO, 1.0, uv);
                    (center + radius * normal, normal)
                };
                // Its point nearest the eye's plane, where a perspective magnifies most, beside
                // a grid of its points.
                let toward_eye = -detail.clip.row(3).truncate().normalize_or_zero();
                let points = samples(&at, sphere_span()).chain([center + radius * toward_eye]);
                let seen = detail.tolerance_over(points);
                fit(seen, &at, sphere_span(), ROUND_QUADS, UNSEEN_QUADS[0])
            }
            CurvedForm::Surface(Surface::Patches(patches)) => return patches_cut(patches, detail),
            CurvedForm::Surface(surface) => {
                let round = surface
                    .round_grid()
                    .expect("every surface but patches is round");
                let at = |uv| (round.surface.point(uv), round.surface.outward_normal(uv));
                let seen = detail.tolerance_over(samples(&at, round.span()));
                fit(seen, &at, round.span(), ROUND_QUADS, UNSEEN_QUADS[0])
            }
        };
        Cut {
            grids: vec![grid.quads],
            within: grid.within,
        }
    }
}

/// The grids of a shape the film does not show (behind the eye's plane or beyond an edge of the
/// image), which only mirrors show and which gives no tolerance there: a round shape's and a patch's fixed grids from before the preview cut
/// shapes for the camera.
pub const UNSEEN_QUADS: [[u32; 2]; 2] = [[64, 32], [8, 8]];

/// The fitting grid where the shape is `seen`, between the fewest and the most quads of
/// `range`; `unseen` off the film.
fn fit(
    seen: Seen,
    at: SurfaceAt,
    span: [DVec2; 2],
    [least, most]: [[u32; 2]; 2],
    unseen: [u32; 2],
) -> Grid {
    match seen {
        Seen::At(tolerance) => fitting_grid(at, span, tolerance, least, most),
        Seen::OffFilm => Grid {
            quads: unseen,
            within: true,
        },
    }
}

/// The surface points of a 32 x 16 grid over `span`: where a shape's magnification is sampled.
fn samples(at: SurfaceAt<'_>, span: [DVec2; 2]) -> impl Iterator<Item = DVec3> + '_ {
    (0..=32).flat_map(move |i| {
        (0..=16).map(move |j| {
            at(span[0] + (span[1] - span[0]) * DVec2::new(i as f64 / 32.0, j as f64 / 16.0)).0
        })
    })
}

/// The patches of a Bézier shape each cut as coarsely as its tolerance allows, then each
/// direction as finely as any other it must match ([`grids_cut_alike`]): neighbours meet without
/// cracks, and a patch far from the finest (most of the teapot, beside its spout) is not cut
/// as finely.
fn patches_cut(patches: &[crate::scene::parametric::BezierPatch], detail: &Detail) -> Cut {
    let unit_square = [DVec2::ZERO, DVec2::ONE];
    let [least, most] = PATCH_QUADS.map(|n| [n; 2]);
    let surface = |k: usize| {
        let patch = patches[k];
        move |uv| (patch.point(uv), patch.outward_normal(uv))
    };
    let seen: Vec<Seen> = (0..patches.len())
        .map(|k| detail.tolerance_over(samples(&surface(k), unit_square)))
        .collect();
    let own: Vec<Grid> = (0..patches.len())
        .map(|k| {
            fit(
                seen[k],
                &surface(k),
                unit_square,
                [least, most],
                UNSEEN_QUADS[1],
            )
        })
        .collect();
    let grids = grids_cut_alike(patches, &own.iter().map(|g| g.quads).collect::<Vec<_>>());
    // A finer grid strays less, but measure rather than assume.
    let within = (0..patches.len()).all(|k| match seen[k] {
        Seen::At(tolerance) => {
            own[k].within && grid_deviation(&surface(k), unit_square, grids[k])[2] <= tolerance
        }
        Seen::OffFilm => true,
    });
    Cut { grids, within }
}

/// A sphere's parameters: u the azimuth around y, v the angle from +y.
fn sphere_span() -> [DVec2; 2] {
    [
        DVec2::ZERO,
        DVec2::new(std::f64::consts::TAU, std::f64::consts::PI),
    ]
}

fn sphere_point(center: DVec3, radius: f64, uv: DVec2) -> DVec3 {
    let (sin_v, cos_v) = uv.y.sin_cos();
    center + radius * DVec3::new(sin_v * uv.x.cos(), cos_v, sin_v * uv.x.sin())
}

/// A sphere as `around` x `down` quads over `sphere_span`, its exact normals at the vertices.
fn sphere(
    out: &mut Vec<PreviewVertex>,
    (center, radius): (DVec3, f64),
    [around, down]: [u32; 2],
    material: u32,
) {
    let step = sphere_span()[1] / DVec2::new(around as f64, down as f64);
    let uv = |i: u32, j: u32| step * DVec2::new(i as f64, j as f64);
    for j in 0..down {
        for i in 0..around {
            let corners = [uv(i, j), uv(i + 1, j), uv(i + 1, j + 1), uv(i, j + 1)];
            for k in [0, 1, 2, 0, 2, 3] {
                let normal = sphere_point(DVec3::ZERO, 1.0, corners[k]);
                let p = sphere_point(center, radius, corners[k]);
                out.push(PreviewVertex::new(p.as_vec3(), normal.as_vec3(), material));
            }
        }
    }
}

fn triangle(out: &mut Vec<PreviewVertex>, p: &GpuPrimitive, normals: Option<[f32; 9]>) {
    let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3::from);
    let face = (b - a).cross(c - a).normalize_or_zero();
    for (k, v) in [a, b, c].into_iter().enumerate() {
        let n = normals.map_or(face, |n| Vec3::from_slice(&n[3 * k..3 * k + 3]));
        out.push(PreviewVertex::new(v, n, p.material));
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
        out.push(PreviewVertex::new(point, n, p.material));
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
        out.push(PreviewVertex::new(q, n, p.material));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::f64::consts::{PI, TAU};

    /// A pinhole at the origin looking down −z, 50 mm on a 36 x 24 mm film, 360 x 240 pixels:
    /// 500 pixels per unit length across the view one unit away.
    fn detail(tolerance_px: f64) -> Detail {
        let text = r#"
[render]
width = 360
height = 240
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
focal_length = 50.0
film = [36.0, 24.0]
"#;
        let scene = Scene::from_str(std::path::Path::new("detail.toml"), text, &[]).unwrap();
        Detail::new(
            super::super::clip_matrix(&scene.camera, 100.0),
            (360, 240),
            tolerance_px,
        )
    }

    fn unit_sphere(uv: DVec2) -> (DVec3, DVec3) {
        let n = sphere_point(DVec3::ZERO, 1.0, uv);
        (n, n)
    }

    #[test]
    fn the_projection_magnifies_as_a_pinhole_does() {
        let d = detail(0.5);
        let at = |p: [f64; 3]| d.pixels_per_unit([DVec3::from(p)]).unwrap();
        assert!((at([0.0, 0.0, -10.0]) - 50.0).abs() < 1e-9);
        // Off the axis, a step along the ray's depth moves the image too: the x row of the
        // Jacobian is (f / z)(1, 0, x / z).
        assert!((at([2.0, 0.0, -10.0]) - 50.0 * 1.04f64.sqrt()).abs() < 1e-9);
        // The most over the points given.
        let both = [DVec3::new(0.0, 0.0, -10.0), DVec3::new(0.0, 0.0, -8.0)];
        assert!((d.pixels_per_unit(both).unwrap() - 62.5).abs() < 1e-9);
        let Seen::At(tolerance) = d.tolerance_over(both) else {
            panic!("in front of the eye")
        };
        assert!((tolerance - 0.5 / 62.5).abs() < 1e-15);
        // Reaching the eye's plane: no tolerance; wholly behind it, or beyond one edge of the
        // image (x / w > 1 at x > 0.36 z), off the film; across the image, on it.
        let across = [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 0.0, 1.0)];
        assert_eq!(d.tolerance_over(across), Seen::At(0.0));
        assert_eq!(d.tolerance_over([DVec3::new(0.0, 0.0, 5.0)]), Seen::OffFilm);
        let right = [DVec3::new(4.0, 0.0, -10.0), DVec3::new(9.0, 5.0, -10.0)];
        assert_eq!(d.tolerance_over(right), Seen::OffFilm);
        let wide = [DVec3::new(4.0, 0.0, -10.0), DVec3::new(-4.0, 0.0, -10.0)];
        assert!(matches!(d.tolerance_over(wide), Seen::At(t) if t > 0.0));
    }

    /// The step that refines one direction when the other is at its most: a thin torus needs
    /// 256 quads around, then more across, not a report that 256 x 32 strays.
    #[test]
    fn a_direction_at_its_most_leaves_the_other_to_be_refined() {
        let (major, minor) = (1.0, 0.01);
        let torus = |uv: DVec2| {
            let (su, cu) = uv.x.sin_cos();
            let (sv, cv) = uv.y.sin_cos();
            let normal = DVec3::new(cv * cu, sv, cv * su);
            (
                DVec3::new(major * cu, 0.0, major * su) + minor * normal,
                normal,
            )
        };
        let span = [DVec2::ZERO, DVec2::splat(TAU)];
        let grid = fitting_grid(&torus, span, 1e-4, ROUND_QUADS[0], ROUND_QUADS[1]);
        assert!(grid.within && grid.quads[0] == 256, "{grid:?}");
        assert!(grid_deviation(&torus, span, grid.quads)[2] <= 1e-4);
    }

    #[test]
    fn a_spheres_edges_stray_by_their_sagitta() {
        let span = sphere_span();
        for [nu, nv] in [[8, 4], [36, 18], [64, 32]] {
            let [along_u, along_v, anywhere] = grid_deviation(&unit_sphere, span, [nu, nv]);
            // The longest edges along u lie on the equator; every edge along v on a great circle.
            let sagitta = |n: u32, angle: f64| 1.0 - (angle / n as f64 / 2.0).cos();
            assert!(
                (along_u - sagitta(nu, TAU)).abs() < 1e-12,
                "{nu}: {along_u}"
            );
            assert!((along_v - sagitta(nv, PI)).abs() < 1e-12, "{nv}: {along_v}");
            // A quad's centre strays further: about the two sagittas together.
            let both = sagitta(nu, TAU) + sagitta(nv, PI);
            assert!(
                anywhere > along_u.max(along_v) && anywhere < 1.1 * both,
                "{anywhere}"
            );
        }
    }

    #[test]
    fn the_grid_found_is_within_the_tolerance_and_not_much_finer() {
        let span = sphere_span();
        for tolerance in [1e-1, 1e-2, 1e-3, 1e-4] {
            let grid = fitting_grid(&unit_sphere, span, tolerance, [8, 1], [4096, 2048]);
            assert!(grid.within, "{tolerance}");
            let [nu, nv] = grid.quads;
            assert!(grid_deviation(&unit_sphere, span, grid.quads)[2] <= tolerance);
            let coarser = [(nu * 3 / 4).max(8), (nv * 3 / 4).max(1)];
            assert!(
                grid_deviation(&unit_sphere, span, coarser)[2] > tolerance,
                "{tolerance}: {:?} would do",
                coarser
            );
        }
    }

    #[test]
    fn a_straight_direction_is_not_cut() {
        // A cylinder of radius 1 and height 3: straight along v.
        let cylinder = |uv: DVec2| {
            let n = DVec3::new(uv.x.cos(), 0.0, uv.x.sin());
            (n + DVec3::Y * uv.y, n)
        };
        let span = [DVec2::ZERO, DVec2::new(TAU, 3.0)];
        let grid = fitting_grid(&cylinder, span, 1e-3, [8, 1], [256, 128]);
        assert_eq!(grid.quads[1], 1);
        assert!(grid.within && grid.quads[0] > 8);
    }

    /// A sphere far smaller than the tolerance keeps the fewest quads, a solid of them (one
    /// quad across would join its poles: every triangle flat, the sphere gone).
    #[test]
    fn a_sphere_below_the_tolerance_stays_a_solid() {
        let tiny = CurvedForm::Sphere {
            center: DVec3::new(0.0, 0.0, -100.0),
            radius: 1e-3,
        };
        let cut = tiny.cut(&detail(0.5));
        assert_eq!(cut.grids, vec![ROUND_QUADS[0]]);
        let mut triangles = Vec::new();
        sphere(&mut triangles, (DVec3::ZERO, 1e-3), cut.grids[0], 0);
        let area: f32 = triangles
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(t[k].position));
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        // An octagonal bipyramid-like solid: most of the sphere's 4π r² area.
        assert!(area > 0.7 * 4.0 * std::f32::consts::PI * 1e-6, "{area}");
    }

    /// Newell's teapot 16 units before the camera, in view: every patch within the tolerance, the
    /// patches' grids not all alike, and every pair of directions that must match cut alike.
    #[test]
    fn each_patch_is_cut_for_itself_and_its_shared_edges_alike() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/teapot.bpt");
        let mut patches = crate::scene::surface::load_bezier_patches(&path).unwrap();
        for patch in &mut patches {
            patch.points = patch
                .points
                .map(|row| row.map(|p| p + DVec3::new(0.0, 0.0, -16.0)));
        }
        let d = detail(0.5);
        let cut = patches_cut(&patches, &d);
        assert!(cut.within);
        let distinct: std::collections::HashSet<_> = cut.grids.iter().collect();
        assert!(distinct.len() > 3, "{:?}", cut.grids);
        for (patch, grid) in patches.iter().zip(&cut.grids) {
            let at = |uv| (patch.point(uv), patch.outward_normal(uv));
            let square = [DVec2::ZERO, DVec2::ONE];
            let Seen::At(tolerance) = d.tolerance_over(samples(&at, square)) else {
                panic!("the teapot is before the camera")
            };
            assert!(grid_deviation(&at, square, *grid)[2] <= tolerance);
        }
        let classes = crate::scene::surface::alike_sides(&patches);
        for (k, a) in classes.iter().enumerate() {
            for (l, b) in classes.iter().enumerate() {
                for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    if a[i] == b[j] {
                        assert_eq!(cut.grids[k][i], cut.grids[l][j], "patches {k} and {l}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_shape_at_the_eye_is_cut_finest_and_said_to_stray() {
        let d = detail(0.5);
        let at_eye = CurvedForm::Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
        assert_eq!(
            at_eye.cut(&d),
            Cut {
                grids: vec![ROUND_QUADS[1]],
                within: false
            }
        );
        // Farther, or with a looser tolerance: never finer.
        let at = |z: f64| CurvedForm::Sphere {
            center: DVec3::new(0.0, 0.0, z),
            radius: 1.0,
        };
        let (near, far) = (at(-5.0).cut(&d), at(-20.0).cut(&d));
        assert!(near.within && far.within);
        let around = |cut: &Cut| cut.grids[0][0];
        assert!(around(&far) < around(&near) * 3 / 4);
        assert!(around(&at(-5.0).cut(&detail(2.0))) < around(&near));
        // Wholly behind the eye, or beside the view: only mirrors show it; the fixed grid, not
        // a report.
        let beside = CurvedForm::Sphere {
            center: DVec3::new(8.0, 0.0, -5.0),
            radius: 1.0,
        };
        assert_eq!(beside.cut(&d), at(20.0).cut(&d));
        assert_eq!(
            at(20.0).cut(&d),
            Cut {
                grids: vec![UNSEEN_QUADS[0]],
                within: true
            }
        );
    }
}
