//! The preview's triangles on the device: the main pass's meshes, drawn indexed ([`MainMesh`]),
//! and the sharing of vertices that indexing and the Fermat solves rest on.

use wgpu::util::DeviceExt;

use crate::preview::PreviewVertex;

/// Triangles of the main pass, drawn indexed.
pub(crate) struct MainMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    pub(crate) index_count: u32,
}

impl MainMesh {
    /// `triangles` in a vertex and an index buffer; `None` for none (wgpu refuses an empty
    /// slice: a scene without shapes draws the background only).
    pub(crate) fn new(device: &wgpu::Device, triangles: &[PreviewVertex]) -> Option<MainMesh> {
        if triangles.is_empty() {
            return None;
        }
        let (distinct, indices) = indexed(triangles);
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        Some(MainMesh {
            vertices: buffer(
                "preview vertices",
                bytemuck::cast_slice(&distinct),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer(
                "preview indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX,
            ),
            index_count: indices.len() as u32,
        })
    }

    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// The distinct positions of `vertices` and, per vertex, the index of its position: a vertex
/// shared by the triangles around it (n² pieces of a subdivided triangle share most of theirs),
/// or by faces of other normals or materials, is solved once. Positions are equal when their
/// bits are.
pub(crate) fn shared_positions(vertices: &[PreviewVertex]) -> (Vec<glam::Vec3>, Vec<u32>) {
    let (distinct, solve_of) = distinct_by(vertices, |v| v.position.map(f32::to_bits));
    let positions = distinct
        .iter()
        .map(|v| glam::Vec3::from(v.position))
        .collect();
    (positions, solve_of)
}

/// `triangles`' distinct vertices and, per corner, the index of its vertex: the main pass and
/// the reflection pass draw them indexed, so a corner shared by several triangles (six around a tessellated
/// sphere's or patch's vertex) is shaded once (lavapipe: the teapot's 4,066 triangles 1.55 →
/// 0.73 ms a frame, `BENCHMARKS.md`). Vertices are equal when their bits are.
pub(crate) fn indexed(triangles: &[PreviewVertex]) -> (Vec<PreviewVertex>, Vec<u32>) {
    distinct_by(triangles, |v| bytemuck::cast::<PreviewVertex, [u32; 8]>(*v))
}

/// The first of each class of `items` with equal keys, in order, and per item the index of its
/// class.
fn distinct_by<T: Copy, K: std::hash::Hash + Eq>(
    items: &[T],
    key: impl Fn(&T) -> K,
) -> (Vec<T>, Vec<u32>) {
    let mut index = std::collections::HashMap::new();
    let mut distinct = Vec::new();
    let indices = items
        .iter()
        .map(|item| {
            *index.entry(key(item)).or_insert_with(|| {
                distinct.push(*item);
                distinct.len() as u32 - 1
            })
        })
        .collect();
    (distinct, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Indexing loses no corner: the indices give back the triangle list, vertex for vertex,
    /// and each distinct vertex is stored once.
    #[test]
    fn indexing_gives_back_every_corner() {
        let corner = |x: f32, material| PreviewVertex {
            position: [x, 0.0, 1.0],
            material,
            normal: [0.0, 0.0, 1.0],
            reflector: 0,
        };
        // Two triangles sharing an edge; the fourth corner differs from the first only by its
        // material, which keeps it apart.
        let triangles = [
            corner(0.0, 0),
            corner(1.0, 0),
            corner(2.0, 0),
            corner(2.0, 0),
            corner(1.0, 0),
            corner(0.0, 1),
        ];
        let (distinct, indices) = indexed(&triangles);
        assert_eq!(distinct.len(), 4);
        assert_eq!(indices, [0, 1, 2, 2, 1, 3]);
        let rebuilt: Vec<PreviewVertex> = indices.iter().map(|&i| distinct[i as usize]).collect();
        assert_eq!(rebuilt, triangles);
        let (positions, solve_of) = shared_positions(&triangles);
        assert_eq!(positions.len(), 3);
        assert_eq!(solve_of, [0, 1, 2, 2, 1, 0]);
    }
}
