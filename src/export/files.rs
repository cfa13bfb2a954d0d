//! The binary files an export writes beside its scene file: triangle meshes as PLY, tables as
//! PFM.

use glam::{Vec2, Vec3};

/// A binary little-endian PLY of triangles: positions, vertex normals and texture coordinates
/// (`u`, `v`) when given, and faces as lists of three `int` indices (what Mitsuba's, pbrt's and
/// Blender's readers take).
pub fn ply(
    comment: &str,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    texcoords: Option<&[Vec2]>,
    triangles: &[[u32; 3]],
) -> Vec<u8> {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment {}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n",
        comment.replace(['\n', '\r'], " "),
        positions.len()
    );
    if normals.is_some() {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if texcoords.is_some() {
        header += "property float u\nproperty float v\n";
    }
    header += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        triangles.len()
    );
    let floats_per_vertex = 3 + 3 * normals.is_some() as usize + 2 * texcoords.is_some() as usize;
    let mut bytes = Vec::with_capacity(
        header.len() + positions.len() * floats_per_vertex * 4 + triangles.len() * 13,
    );
    bytes.extend_from_slice(header.as_bytes());
    for (k, p) in positions.iter().enumerate() {
        let mut put = |v: Vec3| {
            for c in v.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        };
        put(*p);
        if let Some(n) = normals {
            put(n[k]);
        }
        if let Some(t) = texcoords {
            for c in t[k].to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for t in triangles {
        bytes.push(3);
        for i in t {
            bytes.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    bytes
}

/// A one-channel PFM (`Pf`) of `size` x `size` values given by `value(column, row)`, rows
/// from the bottom up as the format stores them.
pub fn pfm_gray(size: u32, value: impl Fn(u32, u32) -> f32) -> Vec<u8> {
    let header = format!("Pf\n{size} {size}\n-1\n");
    let mut bytes = Vec::with_capacity(header.len() + (size * size * 4) as usize);
    bytes.extend_from_slice(header.as_bytes());
    for row in (0..size).rev() {
        for column in 0..size {
            bytes.extend_from_slice(&value(column, row).to_le_bytes());
        }
    }
    bytes
}
