//! Smooth parametric surfaces a scene declares (`type = "torus"`, `"ellipsoid"`, `"cylinder"`,
//! `"bezier"`): the ray tracers intersect the first three exactly and trace Bézier patches as a
//! fine mesh with the patches' own normals at its vertices; the raster preview draws a mesh
//! of each cut for its camera and reflects in them by Fermat's principle (`preview::reflections`). Their geometry is
//! `scene::parametric`'s.

use std::path::Path;

use glam::{DVec2, DVec3};

use super::parametric::{BezierPatch, Cylinder, Ellipsoid, ParametricSurface, Torus};
use super::{CurvedPrimitive, Shape, TriangleMesh};

/// Quads along each side of a Bézier patch: a quarter circle cut 32 times (the teapot's body
/// patches) lies within 1 − cos(π/128) ≈ 3.0e-4 of its radius of the mesh.
pub const PATCH_QUADS: u32 = 32;

/// Control points a patch file may hold, and patches (a bound on what a file can ask).
const MAX_PATCH_POINTS: usize = 1 << 20;

/// A scene's parametric surface and the shape that renders it.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvedSurface {
    /// Its index in `Scene::shapes` (`Surface::traced_shape`).
    pub shape: usize,
    /// The surface.
    pub surface: Surface,
}

/// The parametric surfaces a scene can declare.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// A torus, its axis turned by its orientation.
    Torus(Torus),
    /// Bicubic Bézier patches (Newell's teapot), each oriented with f_u × f_v outward.
    Patches(Vec<BezierPatch>),
    /// An ellipsoid, its semi-axes turned by its orientation.
    Ellipsoid(Ellipsoid),
    /// A cylinder around its (turned) axis, `height` tall above its base circle, open at both
    /// ends.
    Cylinder {
        /// The base circle's centre and radius.
        cylinder: Cylinder,
        /// Its height (scene units), > 0.
        height: f64,
    },
}

impl Surface {
    /// The shape the ray tracers trace, with `material`: a torus, ellipsoid or cylinder as
    /// itself, intersected exactly (`accel::curved`); Bézier patches as a mesh of
    /// `PATCH_QUADS` quads along each side, with the patches' normals at its vertices.
    pub fn traced_shape(&self, material: u32) -> Shape {
        let primitive = match self {
            Surface::Patches(patches) => {
                return Shape::Mesh {
                    mesh: patches_mesh(patches, PATCH_QUADS),
                    material,
                };
            }
            Surface::Torus(t) => (
                CurvedPrimitive::Torus {
                    center: t.center.as_vec3(),
                    major: t.major as f32,
                    minor: t.minor as f32,
                },
                t.orientation,
            ),
            Surface::Ellipsoid(e) => (
                CurvedPrimitive::Ellipsoid {
                    center: e.center.as_vec3(),
                    radii: e.radii.as_vec3(),
                },
                e.orientation,
            ),
            Surface::Cylinder { cylinder, height } => (
                CurvedPrimitive::Cylinder {
                    base: cylinder.center.as_vec3(),
                    radius: cylinder.radius as f32,
                    height: *height as f32,
                },
                cylinder.orientation,
            ),
        };
        let (primitive, orientation) = primitive;
        Shape::Curved {
            primitive,
            orientation: orientation.as_quat(),
            material,
        }
    }

    /// The surface as a mesh of `round` quads around and across a round surface, `patch`
    /// quads along each side of a patch.
    pub fn mesh_of(&self, round: [u32; 2], patch: u32) -> TriangleMesh {
        match (self, self.round_grid()) {
            (Surface::Patches(patches), _) => patches_mesh(patches, patch),
            (_, Some(grid)) => grid_mesh(grid.surface, round, grid.across, grid.inward),
            (_, None) => unreachable!("every surface but patches is round"),
        }
    }

    /// How `mesh_of` grids a round surface (a torus, ellipsoid or cylinder); `None` for
    /// patches, each gridded over its own unit square.
    pub fn round_grid(&self) -> Option<RoundGrid<'_>> {
        use std::f64::consts::{PI, TAU};
        let (surface, across, inward): (&dyn ParametricSurface, _, _) = match self {
            Surface::Patches(_) => return None,
            Surface::Torus(torus) => (torus, Across::Around(TAU), true),
            Surface::Ellipsoid(e) => (e, Across::Span(0.0, PI), false),
            Surface::Cylinder { cylinder, height } => (cylinder, Across::Span(0.0, *height), true),
        };
        Some(RoundGrid {
            surface,
            across,
            inward,
        })
    }
}

/// A round surface as `Surface::mesh_of` grids it: u once around its axis (period 2π), v
/// across.
#[derive(Clone, Copy)]
pub struct RoundGrid<'a> {
    /// The surface's point and normal functions.
    pub surface: &'a dyn ParametricSurface,
    across: Across,
    inward: bool,
}

impl RoundGrid<'_> {
    /// The parameter rectangle gridded: its lowest and highest (u, v).
    pub fn span(&self) -> [DVec2; 2] {
        let (from, to) = match self.across {
            Across::Around(period) => (0.0, period),
            Across::Span(from, to) => (from, to),
        };
        [DVec2::new(0.0, from), DVec2::new(std::f64::consts::TAU, to)]
    }
}

/// How a round surface's v runs: around a closed curve of this period, or over a span.
#[derive(Clone, Copy)]
enum Across {
    Around(f64),
    Span(f64, f64),
}

/// A surface whose u runs once around its axis (period 2π) as a grid of `quads` quads, its
/// outward normals at the vertices; triangles that collapse (an ellipsoid's poles) are left
/// out. `inward` says that f_u × f_v points into the surface: the triangles are then wound the
/// other way, so that their geometric normals point out as the vertex normals do.
fn grid_mesh(
    surface: &dyn ParametricSurface,
    quads: [u32; 2],
    v: Across,
    inward: bool,
) -> TriangleMesh {
    let [nu, nv] = quads;
    let rows = match v {
        Across::Around(_) => nv,
        Across::Span(..) => nv + 1,
    };
    let uv = |i: u32, j: u32| {
        let u = i as f64 / nu as f64 * std::f64::consts::TAU;
        match v {
            Across::Around(period) => DVec2::new(u, j as f64 / nv as f64 * period),
            Across::Span(from, to) => DVec2::new(u, from + (to - from) * j as f64 / nv as f64),
        }
    };
    let mut mesh = empty_mesh();
    let normals = mesh.normals.get_or_insert_with(Vec::new);
    for i in 0..nu {
        for j in 0..rows {
            mesh.positions.push(surface.point(uv(i, j)).as_vec3());
            normals.push(surface.outward_normal(uv(i, j)).as_vec3());
        }
    }
    let index = |i: u32, j: u32| (i % nu) * rows + j % rows;
    for i in 0..nu {
        for j in 0..nv {
            push_quad(&mut mesh, index, (i, j), inward);
        }
    }
    mesh
}

/// The grid quad (i, j) to (i + 1, j + 1) of `mesh`'s vertices (`index` numbers them) as two
/// triangles, wound the other way where `reversed`, leaving out a triangle that collapses (at
/// a pole or a degenerate edge).
fn push_quad(
    mesh: &mut TriangleMesh,
    index: impl Fn(u32, u32) -> u32,
    (i, j): (u32, u32),
    reversed: bool,
) {
    let [a, b, c, d] = [
        index(i, j),
        index(i + 1, j),
        index(i + 1, j + 1),
        index(i, j + 1),
    ];
    let pair = match reversed {
        true => [[a, c, b], [a, d, c]],
        false => [[a, b, c], [a, c, d]],
    };
    for t in pair {
        let [p, q, r] = t.map(|k| mesh.positions[k as usize]);
        if (q - p).cross(r - p) != glam::Vec3::ZERO {
            mesh.triangles.push(t);
        }
    }
}

/// Every patch as a grid of `quads` x `quads` quads, the patch's normals at the vertices;
/// triangles that collapse at a patch's degenerate edge (the teapot's poles) are left out.
pub fn patches_mesh(patches: &[BezierPatch], quads: u32) -> TriangleMesh {
    patches_mesh_cut(patches, &vec![[quads; 2]; patches.len()])
}

/// Every patch as a grid of its own `grids[k]` = [along u, along v] quads (as
/// [`patches_mesh`]); neighbours meet without cracks where the edges they share are cut alike
/// ([`alike_sides`]).
pub fn patches_mesh_cut(patches: &[BezierPatch], grids: &[[u32; 2]]) -> TriangleMesh {
    assert_eq!(patches.len(), grids.len(), "a grid for every patch");
    let mut mesh = empty_mesh();
    for (patch, &[nu, nv]) in patches.iter().zip(grids) {
        let first = mesh.positions.len() as u32;
        for i in 0..=nu {
            for j in 0..=nv {
                let uv = DVec2::new(i as f64 / nu as f64, j as f64 / nv as f64);
                mesh.positions.push(patch.point(uv).as_vec3());
                let normals = mesh.normals.get_or_insert_with(Vec::new);
                normals.push(patch_normal(patch, uv).as_vec3());
            }
        }
        let index = |i: u32, j: u32| first + i * (nv + 1) + j;
        for i in 0..nu {
            for j in 0..nv {
                push_quad(&mut mesh, index, (i, j), false);
            }
        }
    }
    mesh
}

/// Each patch's grid from its own (`own[k]`: [along u, along v] quads), each direction raised to
/// the finest of the directions it must match ([`alike_sides`]): grids with which
/// [`patches_mesh_cut`]'s patches meet without cracks.
pub fn grids_cut_alike(patches: &[BezierPatch], own: &[[u32; 2]]) -> Vec<[u32; 2]> {
    let classes = alike_sides(patches);
    let mut finest = std::collections::HashMap::new();
    for (class, grid) in classes.iter().zip(own) {
        for (&class, &quads) in class.iter().zip(grid) {
            let n = finest.entry(class).or_insert(0);
            *n = quads.max(*n);
        }
    }
    classes.iter().map(|c| c.map(|c| finest[&c])).collect()
}

/// Which directions of the patches must be cut into as many pieces: per patch, the class of
/// its u direction and of its v direction, two directions sharing a class where a chain of
/// shared edges links them (an edge of one patch whose four control points are another's, in
/// the same or the reverse order; its pieces run along u on one side, along the other's
/// direction there). Edges collapsed to a point (the teapot's poles) link nothing: no crack can
/// open along them.
pub fn alike_sides(patches: &[BezierPatch]) -> Vec<[usize; 2]> {
    // The edges at u = 0 and u = 1 run along v (direction 1), those at v = 0 and 1 along u.
    let edges = |p: &BezierPatch| {
        let along_v = |i: usize| p.points[i];
        let along_u = |j: usize| p.points.map(|row| row[j]);
        [
            (along_v(0), 1),
            (along_v(3), 1),
            (along_u(0), 0),
            (along_u(3), 0),
        ]
    };
    let mut parent: Vec<usize> = (0..2 * patches.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    // − 0.0 + 0.0 is 0.0: a coordinate of −0 in one patch and 0 in its neighbour is one point.
    let key = |points: [DVec3; 4]| points.map(|p| (p + DVec3::ZERO).to_array().map(f64::to_bits));
    let mut seen = std::collections::HashMap::new();
    for (k, patch) in patches.iter().enumerate() {
        for (points, direction) in edges(patch) {
            if points.iter().all(|&p| p == points[0]) {
                continue;
            }
            let mut reversed = points;
            reversed.reverse();
            let side = 2 * k + direction;
            let other = seen.get(&key(points)).or_else(|| seen.get(&key(reversed)));
            match other.copied() {
                Some(other) => {
                    let (a, b) = (root(&mut parent, side), root(&mut parent, other));
                    parent[a] = b;
                }
                None => {
                    seen.insert(key(points), side);
                }
            }
        }
    }
    (0..patches.len())
        .map(|k| [root(&mut parent, 2 * k), root(&mut parent, 2 * k + 1)])
        .collect()
}

/// A patch's unit normal f_u × f_v at `uv`; where that vanishes (a degenerate edge), the
/// normal a little inside the patch.
pub fn patch_normal(patch: &BezierPatch, uv: DVec2) -> DVec3 {
    let n = patch.outward_normal(uv);
    if n != DVec3::ZERO {
        return n;
    }
    patch.outward_normal(uv.clamp(DVec2::splat(1e-3), DVec2::splat(1.0 - 1e-3)))
}

fn empty_mesh() -> TriangleMesh {
    TriangleMesh {
        positions: Vec::new(),
        normals: Some(Vec::new()),
        texcoords: None,
        triangles: Vec::new(),
        dropped_degenerate: 0,
        materials: Vec::new(),
        face_materials: Vec::new(),
        notes: Vec::new(),
        missing_libraries: Vec::new(),
    }
}

/// Reads a file of bicubic Bézier patches in Newell's format (the teapot's): the patch count,
/// one line of 16 comma-separated 1-based control-point indices per patch (row by row: index
/// 4i + j + 1 of the line is P_ij), the point count, then one `x,y,z` line per point. Errors
/// name the file and line.
pub fn load_bezier_patches(path: &Path) -> Result<Vec<BezierPatch>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read patch file: {e}", path.display()))?;
    parse_bezier_patches(&text).map_err(|(line, e)| format!("{}:{line}: {e}", path.display()))
}

/// `load_bezier_patches` on the file's text; errors carry their 1-based line.
fn parse_bezier_patches(text: &str) -> Result<Vec<BezierPatch>, (usize, String)> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let last = text.lines().count().max(1);
    let mut next = |what: &str| lines.next().ok_or((last, format!("ends before {what}")));
    let count = |(line, l): (usize, &str), what: &str| {
        l.parse::<usize>()
            .ok()
            .filter(|&n| (1..=MAX_PATCH_POINTS).contains(&n))
            .ok_or((
                line,
                format!("expected the {what} (1 to {MAX_PATCH_POINTS}), got `{l}`"),
            ))
    };
    let numbers = |(line, l): (usize, &str), n: usize| -> Result<Vec<f64>, (usize, String)> {
        let values: Vec<f64> = l
            .split(',')
            .map(|v| v.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or((
                line,
                format!("expected {n} comma-separated numbers, got `{l}`"),
            ))?;
        if values.len() != n {
            return Err((line, format!("expected {n} numbers, got {}", values.len())));
        }
        Ok(values)
    };
    let patch_count = count(next("the patch count")?, "patch count")?;
    let mut indices = Vec::with_capacity(patch_count);
    for _ in 0..patch_count {
        let (line, l) = next("a patch's control-point indices")?;
        indices.push((line, numbers((line, l), 16)?));
    }
    let point_count = count(next("the control-point count")?, "control-point count")?;
    let mut points = Vec::with_capacity(point_count);
    for _ in 0..point_count {
        let (line, l) = next("a control point")?;
        let p = numbers((line, l), 3)?;
        points.push(DVec3::new(p[0], p[1], p[2]));
    }
    indices
        .into_iter()
        .map(|(line, row)| {
            let mut patch = BezierPatch {
                points: [[DVec3::ZERO; 4]; 4],
            };
            for (k, &index) in row.iter().enumerate() {
                if index.fract() != 0.0 || index < 1.0 || index > point_count as f64 {
                    return Err((
                        line,
                        format!("control-point index {index} is not one of 1..={point_count}"),
                    ));
                }
                patch.points[k / 4][k % 4] = points[index as usize - 1];
            }
            Ok(patch)
        })
        .collect()
}

/// Turns every patch whose normal f_u × f_v points into the surface the patches close (the
/// teapot's) the other way round, by reversing its u order, so that all face out as the
/// preview's test of a reflection seen from outside expects. Inward or outward is told by
/// parity: a ray leaving the patch's centre on its normal's side crosses the other patches an
/// odd number of times when it starts inward. Five rays (tilted 21° from the normal) vote, so that one grazing a seam or leaving through an opening (the teapot has no bottom)
/// does not decide alone.
pub fn orient_outward(patches: &mut [BezierPatch]) {
    let mesh = patches_mesh(patches, ORIENTATION_QUADS);
    let triangles: Vec<[DVec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|k| mesh.positions[k as usize].as_dvec3()))
        .collect();
    let scale = triangles
        .iter()
        .flatten()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    for patch in patches {
        let centre = DVec2::splat(0.5);
        let (p, n) = (patch.point(centre), patch_normal(patch, centre));
        let (a, b) = n.any_orthonormal_pair();
        // Tilted at an odd angle and azimuths, so that no ray runs exactly through a vertex or
        // an edge of the grids (where a crossing would count twice).
        let inward_votes = (0..5)
            .map(|k| {
                let azimuth = 0.3 + k as f64 * std::f64::consts::TAU / 5.0;
                let side = a * azimuth.cos() + b * azimuth.sin();
                (n * TILT.cos() + side * TILT.sin()).normalize()
            })
            .filter(|&d| {
                let origin = p + d * 1e-4 * scale.max(1e-30);
                triangles.iter().filter(|t| crosses(origin, d, t)).count() % 2 == 1
            })
            .count();
        if inward_votes >= 3 {
            patch.points.reverse();
        }
    }
}

/// How far `orient_outward`'s rays lean from the normal (radians).
const TILT: f64 = 0.37;

/// Quads per patch side of the mesh `orient_outward` casts its rays against.
const ORIENTATION_QUADS: u32 = 8;

/// Whether the ray origin + t d, t > 0, crosses triangle `t` (Möller–Trumbore, f64).
fn crosses(origin: DVec3, d: DVec3, [a, b, c]: &[DVec3; 3]) -> bool {
    let (e1, e2) = (*b - *a, *c - *a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return false;
    }
    let s = origin - *a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fine mesh of a round surface: a torus's lies within (R + r)(1 − cos(π/256)) ≈
    /// 7.5e-5 (R + r) of it along u and r(1 − cos(π/128)) ≈ 3.0e-4 r along v.
    const FINE: [u32; 2] = [256, 128];

    /// A one-patch file: the flat unit square z = 0, control points on a 4 x 4 grid.
    const FLAT_PATCH: &str = "1\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n16\n\
        0,0,0\n0,1,0\n0,2,0\n0,3,0\n1,0,0\n1,1,0\n1,2,0\n1,3,0\n\
        2,0,0\n2,1,0\n2,2,0\n2,3,0\n3,0,0\n3,1,0\n3,2,0\n3,3,0\n";

    #[test]
    fn a_patch_file_reads_row_by_row() {
        let patches = parse_bezier_patches(FLAT_PATCH).unwrap();
        assert_eq!(patches.len(), 1);
        let p = patches[0];
        assert_eq!(p.points[1][2], DVec3::new(1.0, 2.0, 0.0));
        // A bilinear grid: the patch is the plane itself, f(u, v) = 3 (u, v, 0).
        let uv = DVec2::new(0.3, 0.8);
        assert!((p.point(uv) - DVec3::new(0.9, 2.4, 0.0)).length() < 1e-12);
        assert!((patch_normal(&p, uv) - DVec3::Z).length() < 1e-12);
    }

    /// Newell's teapot cut with every patch's own grid, each direction then as fine as the ones
    /// it must match: wherever two patches share an edge, their mesh vertices along it are the
    /// same points (no crack), though the patches' grids differ.
    #[test]
    fn patches_cut_alike_along_shared_edges_meet_without_cracks() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/teapot.bpt");
        let mut patches = load_bezier_patches(&path).unwrap();
        orient_outward(&mut patches);
        let own: Vec<[u32; 2]> = (0..patches.len() as u32)
            .map(|k| [2 + k % 5, 3 + k % 3])
            .collect();
        let grids = grids_cut_alike(&patches, &own);
        let distinct: std::collections::HashSet<_> = grids.iter().collect();
        assert!(distinct.len() > 2, "{grids:?}");
        let mesh = patches_mesh_cut(&patches, &grids);
        // Each patch's mesh vertices along each of its edges, as bits.
        let mut first = 0;
        let mut sides = Vec::new();
        for (patch, &[nu, nv]) in patches.iter().zip(&grids) {
            let at = |i: u32, j: u32| mesh.positions[(first + i * (nv + 1) + j) as usize];
            let line = |points: Vec<glam::Vec3>| {
                let mut bits: Vec<[u32; 3]> = points
                    .iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect();
                bits.sort();
                bits
            };
            let column = |i| line((0..=nv).map(|j| at(i, j)).collect());
            let row = |j| line((0..=nu).map(|i| at(i, j)).collect());
            let edges = [
                (patch.points[0], column(0)),
                (patch.points[3], column(nu)),
                (patch.points.map(|r| r[0]), row(0)),
                (patch.points.map(|r| r[3]), row(nv)),
            ];
            sides.extend(edges);
            first += (nu + 1) * (nv + 1);
        }
        let mut shared = 0;
        for (a, (control_a, vertices_a)) in sides.iter().enumerate() {
            for (control_b, vertices_b) in &sides[a + 1..] {
                let mut reversed = *control_b;
                reversed.reverse();
                let collapsed = control_a.iter().all(|&p| p == control_a[0]);
                if collapsed || (control_a != control_b && *control_a != reversed) {
                    continue;
                }
                shared += 1;
                assert_eq!(
                    vertices_a, vertices_b,
                    "an edge shared by two patches cracks"
                );
            }
        }
        assert!(shared > 30, "{shared} shared edges");
    }

    #[test]
    fn a_bad_patch_file_names_its_line() {
        let cases = [
            (
                FLAT_PATCH.replacen("1,2,3,4,", "1,2,3,", 1),
                2,
                "expected 16 numbers",
            ),
            (
                FLAT_PATCH.replacen(",16\n16", ",17\n16", 1),
                2,
                "is not one of 1..=16",
            ),
            (
                FLAT_PATCH.replacen("1,1,0", "1,x,0", 1),
                9,
                "comma-separated numbers",
            ),
            (
                FLAT_PATCH.replacen("\n16\n", "\n-3\n", 1),
                3,
                "control-point count",
            ),
            (
                FLAT_PATCH[..FLAT_PATCH.len() - 7].to_string(),
                18,
                "ends before a control point",
            ),
        ];
        for (text, line, says) in cases {
            let (at, message) = parse_bezier_patches(&text).unwrap_err();
            assert_eq!(at, line, "{message}");
            assert!(message.contains(says), "{message}");
        }
    }

    /// A closed box of six flat patches, half of them wound inward, all turn out.
    #[test]
    fn patches_closing_a_box_are_turned_outward() {
        let flat = parse_bezier_patches(FLAT_PATCH).unwrap()[0];
        // The square [0, 3]² at z = 0 (facing +z), moved onto each face of the cube [0, 3]³.
        let face = |map: &dyn Fn(DVec3) -> DVec3| BezierPatch {
            points: flat.points.map(|row| row.map(map)),
        };
        // Three faces wound inward (normals into the cube), three outward.
        let mut patches = vec![
            face(&|p| p),
            face(&|p| DVec3::new(p.y, p.x, 3.0)),
            face(&|p| DVec3::new(p.z, p.x, p.y)),
            face(&|p| DVec3::new(3.0, p.y, p.x)),
            face(&|p| DVec3::new(p.y, p.z, p.x)),
            face(&|p| DVec3::new(p.x, 3.0, p.y)),
        ];
        orient_outward(&mut patches);
        let centre = DVec3::splat(1.5);
        for (k, patch) in patches.iter().enumerate() {
            let uv = DVec2::splat(0.5);
            let out = patch.point(uv) - centre;
            assert!(patch_normal(patch, uv).dot(out) > 0.0, "face {k} faces in");
        }
    }

    #[test]
    fn the_torus_mesh_lies_on_the_torus_within_its_sagitta() {
        let torus = Torus::new(DVec3::new(0.2, 0.5, -0.1), 0.6, 0.2);
        let mesh = Surface::Torus(torus).mesh_of(FINE, PATCH_QUADS);
        let [nu, nv] = FINE;
        assert_eq!(mesh.triangles.len() as u32, 2 * nu * nv);
        // |distance to the tube circle − r| is the distance to the torus.
        let off_surface = |p: DVec3| {
            let d = p - torus.center;
            let radial = DVec3::new(d.x, 0.0, d.z);
            let tube = radial.normalize() * torus.major;
            ((d - tube).length() - torus.minor).abs()
        };
        let sagitta = (torus.major + torus.minor)
            * (1.0 - (std::f64::consts::PI / nu as f64).cos())
            + torus.minor * (1.0 - (std::f64::consts::PI / nv as f64).cos());
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            for p in [a, b, c] {
                assert!(off_surface(p) < 1e-6, "vertex {p} off the torus");
            }
            let centroid = (a + b + c) / 3.0;
            assert!(
                off_surface(centroid) <= sagitta,
                "{} against {sagitta}",
                off_surface(centroid)
            );
            // Wound so that the geometric normal agrees with the vertex normals (outward).
            let n = (b - a).cross(c - a);
            let shading = mesh.normals.as_ref().unwrap()[t[0] as usize].as_dvec3();
            assert!(n.dot(shading) > 0.0);
        }
    }

    /// An implicit function of a surface, zero on it, with its gradient.
    type Implicit<'a> = dyn Fn(DVec3) -> (f64, DVec3) + 'a;

    /// The ellipsoid's and the cylinder's meshes: vertices on the surface, normals the
    /// surface's (the gradient of the implicit function), triangles facing out, none collapsed
    /// at the ellipsoid's poles, and the cylinder spanning its height.
    #[test]
    fn the_ellipsoid_and_cylinder_meshes_lie_on_their_surfaces() {
        let center = DVec3::new(0.2, 0.5, -0.1);
        let radii = DVec3::new(0.8, 0.45, 0.5);
        let ellipsoid = Surface::Ellipsoid(Ellipsoid::new(center, radii));
        let (radius, height) = (0.45, 1.2);
        let cylinder = Surface::Cylinder {
            cylinder: Cylinder::new(center, radius),
            height,
        };
        // Each surface's implicit function, zero on it, and its gradient.
        let on_ellipsoid = |p: DVec3| {
            let q = (p - center) / radii;
            (q.length_squared() - 1.0, q / radii)
        };
        let on_cylinder = |p: DVec3| {
            let q = p - center;
            let flat = DVec3::new(q.x, 0.0, q.z);
            assert!((-1e-6..=height + 1e-6).contains(&q.y), "{p} off the height");
            (flat.length() / radius - 1.0, flat)
        };
        let implicit: [(&Surface, &Implicit<'_>); 2] =
            [(&ellipsoid, &on_ellipsoid), (&cylinder, &on_cylinder)];
        for (surface, implicit) in implicit {
            let mesh = surface.mesh_of(FINE, PATCH_QUADS);
            let normals = mesh.normals.as_ref().unwrap();
            for (p, n) in mesh.positions.iter().zip(normals) {
                let (value, gradient) = implicit(p.as_dvec3());
                assert!(
                    value.abs() < 1e-6,
                    "{surface:?}: {p} off the surface by {value}"
                );
                let expected = gradient.normalize();
                assert!(
                    (n.as_dvec3() - expected).length() < 1e-5,
                    "{surface:?}: normal at {p}"
                );
            }
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|k| mesh.positions[k as usize].as_dvec3());
                let n = (b - a).cross(c - a);
                assert!(n.length() > 0.0, "{surface:?}: a collapsed triangle");
                let outward = normals[t[0] as usize].as_dvec3() + normals[t[1] as usize].as_dvec3();
                assert!(n.dot(outward) > 0.0, "{surface:?}: a triangle facing in");
            }
        }
        let [nu, nv] = FINE;
        // Two triangles a quad, but one at each pole of the ellipsoid.
        assert_eq!(
            ellipsoid.mesh_of(FINE, PATCH_QUADS).triangles.len() as u32,
            2 * nu * nv - 2 * nu
        );
        assert_eq!(
            cylinder.mesh_of(FINE, PATCH_QUADS).triangles.len() as u32,
            2 * nu * nv
        );
    }
}
