//! Triangle meshes from OBJ and PLY files (`.gz` read transparently), as real tools write them.
//!
//! OBJ goes through `tobj` (quads and n-gons fan-triangulated, negative indices, several objects
//! and groups, with or without normals); PLY through `ply-rs-bw` (ASCII and binary of either byte
//! order; properties other than positions, normals and faces are ignored).

use std::io::{BufRead, BufReader};
use std::path::Path;

use glam::{Mat3, Vec3};
use ply_rs_bw::ply::Property;

/// An indexed triangle mesh in scene space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, when the file has them and the shape asks for smooth shading.
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    /// Zero-area triangles dropped on load (they can never be hit).
    pub dropped_degenerate: usize,
}

/// Reads a mesh; the error is a sentence ready to follow the file name.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open mesh file: {e}"))?;
    let name = path.to_string_lossy().to_ascii_lowercase();
    let inner_name = name.strip_suffix(".gz").unwrap_or(&name);
    let mut reader: Box<dyn BufRead> = if name.ends_with(".gz") {
        Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(file)))
    } else {
        Box::new(BufReader::new(file))
    };
    let mesh = if inner_name.ends_with(".obj") {
        read_obj(&mut reader)?
    } else if inner_name.ends_with(".ply") {
        read_ply(&mut reader)?
    } else {
        return Err("unknown mesh format (expected .obj, .ply, .obj.gz or .ply.gz)".into());
    };
    check_mesh(mesh)
}

fn read_obj(reader: &mut dyn BufRead) -> Result<TriangleMesh, String> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    // Materials are chambre's own, so `mtllib` files are not read.
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(reader), &options, |_| {
        Ok(Default::default())
    })
    .map_err(|e| format!("malformed OBJ: {e}"))?;
    let mut mesh = TriangleMesh::default();
    let all_have_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let mut normals = Vec::new();
    for model in &models {
        let base = mesh.positions.len() as u32;
        let m = &model.mesh;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if all_have_normals {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if all_have_normals && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

fn read_ply(reader: &mut dyn BufRead) -> Result<TriangleMesh, String> {
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read PLY: {e}"))?;
    let ply = parser
        .read_ply(&mut bytes.as_slice())
        .map_err(|e| format!("malformed PLY: {e}"))?;
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or("PLY has no `vertex` element")?;
    let scalar = |e: &ply_rs_bw::ply::DefaultElement, key: &str| -> Option<f32> {
        match e.get(key)? {
            Property::Float(v) => Some(*v),
            Property::Double(v) => Some(*v as f32),
            Property::Int(v) => Some(*v as f32),
            Property::UInt(v) => Some(*v as f32),
            Property::Short(v) => Some(*v as f32),
            Property::UShort(v) => Some(*v as f32),
            Property::Char(v) => Some(*v as f32),
            Property::UChar(v) => Some(*v as f32),
            _ => None,
        }
    };
    let mut mesh = TriangleMesh::default();
    let mut normals = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        let p = ["x", "y", "z"].map(|k| scalar(v, k));
        let [Some(x), Some(y), Some(z)] = p else {
            return Err(format!("PLY vertex {i} lacks x, y or z"));
        };
        mesh.positions.push(Vec3::new(x, y, z));
        if let [Some(nx), Some(ny), Some(nz)] = ["nx", "ny", "nz"].map(|k| scalar(v, k)) {
            normals.push(Vec3::new(nx, ny, nz));
        }
    }
    if normals.len() == mesh.positions.len() && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    let faces = ply
        .payload
        .get("face")
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (f, face) in faces.iter().enumerate() {
        let indices: Vec<i64> = match face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
        {
            Some(Property::ListInt(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUInt(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListShort(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUShort(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListChar(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUChar(l)) => l.iter().map(|&i| i as i64).collect(),
            _ => return Err(format!("PLY face {f} has no integer vertex_indices list")),
        };
        let count = mesh.positions.len() as i64;
        if let Some(bad) = indices.iter().find(|&&i| i < 0 || i >= count) {
            return Err(format!(
                "PLY face {f} has vertex index {bad}, out of range (0..{count})"
            ));
        }
        // Fan-triangulate polygons, as tobj does for OBJ.
        for k in 1..indices.len().saturating_sub(1) {
            mesh.triangles
                .push([indices[0] as u32, indices[k] as u32, indices[k + 1] as u32]);
        }
    }
    Ok(mesh)
}

/// Rejects meshes that cannot be rendered and drops triangles that can never be hit.
fn check_mesh(mut mesh: TriangleMesh) -> Result<TriangleMesh, String> {
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a non-finite coordinate"));
    }
    let count = mesh.positions.len() as u32;
    if let Some(t) = mesh
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i >= count))
    {
        return Err(format!(
            "triangle {t} has a vertex index out of range ({} vertices)",
            count
        ));
    }
    let before = mesh.triangles.len();
    let positions = &mesh.positions;
    mesh.triangles.retain(|t| {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        (b - a).cross(c - a) != Vec3::ZERO
    });
    mesh.dropped_degenerate = before - mesh.triangles.len();
    if mesh.triangles.is_empty() {
        return Err(if before == 0 {
            "mesh has no faces".into()
        } else {
            format!("all {before} triangles of the mesh have zero area")
        });
    }
    Ok(mesh)
}

/// Applies scale, then rotation about x, then y, then z (degrees), then translation.
pub fn transform_mesh(mesh: &mut TriangleMesh, scale: Vec3, rotate_deg: Vec3, translate: Vec3) {
    let rotation = Mat3::from_rotation_z(rotate_deg.z.to_radians())
        * Mat3::from_rotation_y(rotate_deg.y.to_radians())
        * Mat3::from_rotation_x(rotate_deg.x.to_radians());
    let linear = rotation * Mat3::from_diagonal(scale);
    for p in &mut mesh.positions {
        *p = linear * *p + translate;
    }
    if let Some(normals) = &mut mesh.normals {
        // Normals transform by the inverse transpose: rotation * scale^-1.
        let normal_matrix = rotation * Mat3::from_diagonal(scale.recip());
        for n in normals.iter_mut() {
            *n = (normal_matrix * *n).normalize_or_zero();
        }
    }
}
