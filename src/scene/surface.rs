//! Smooth parametric surfaces a scene declares (`type = "torus"`), rendered by the ray tracers
//! as a fine mesh with the surface's own normals at its vertices, and kept whole for the raster
//! preview, which reflects in them by Fermat's principle (`crate::fermat`).

use glam::DVec2;

use super::TriangleMesh;
use crate::fermat::{Reflector, Torus};

/// Quads around a torus's axis (u) and around its tube (v): the mesh lies within
/// (R + r)(1 − cos(π/256)) ≈ 7.5e-5 (R + r) of the torus along u and r(1 − cos(π/128)) ≈
/// 3.0e-4 r along v, and shades with the torus's normals interpolated across each triangle.
pub const TORUS_QUADS: [u32; 2] = [256, 128];

/// A scene's parametric surface and the shape that renders it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvedSurface {
    /// Its index in `Scene::shapes`: a `Shape::Mesh` of its tessellation.
    pub shape: usize,
    /// The surface.
    pub surface: Torus,
}

/// The torus as a closed mesh of `TORUS_QUADS` quads (two triangles each), the torus's outward
/// normals at the vertices.
pub fn torus_mesh(torus: &Torus) -> TriangleMesh {
    torus_mesh_of(torus, TORUS_QUADS)
}

/// The torus, periodic in u and v over [0, 2π)², as a closed grid of `quads` quads around its
/// axis and its tube.
pub fn torus_mesh_of(surface: &Torus, quads: [u32; 2]) -> TriangleMesh {
    let [nu, nv] = quads;
    let uv = |i: u32, j: u32| {
        DVec2::new(i as f64 / nu as f64, j as f64 / nv as f64) * std::f64::consts::TAU
    };
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    let mut normals = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            positions.push(surface.point(uv(i, j)).as_vec3());
            normals.push(surface.outward_normal(uv(i, j)).as_vec3());
        }
    }
    let index = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut triangles = Vec::with_capacity(2 * (nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let [a, b, c, d] = [
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            ];
            // f_u × f_v points into a torus: wound the other way, the geometric normal
            // points out as the vertex normals do.
            triangles.push([a, c, b]);
            triangles.push([a, d, c]);
        }
    }
    TriangleMesh {
        positions,
        normals: Some(normals),
        triangles,
        dropped_degenerate: 0,
        materials: Vec::new(),
        face_materials: Vec::new(),
        notes: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_torus_mesh_lies_on_the_torus_within_its_sagitta() {
        let torus = Torus {
            center: DVec3::new(0.2, 0.5, -0.1),
            major: 0.6,
            minor: 0.2,
        };
        let mesh = torus_mesh(&torus);
        let [nu, nv] = TORUS_QUADS;
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
}
