//! A mesh file of any format chambre reads, chosen by its extension: OBJ and PLY (`.gz` read
//! transparently, `mesh`) and glTF (`gltf`, its meshes merged into one).

use std::io::{BufRead, Read};
use std::path::Path;

use super::gltf::read_gltf;
use super::mesh::{
    GuardedReader, MAX_LINE_BYTES, MAX_MESH_BYTES, TriangleMesh, check_mesh, non_finite_vertex,
    read_obj, read_ply,
};

/// Reads a mesh; the error is a sentence that starts with the file's path.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, String> {
    read_mesh(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn read_mesh(path: &Path) -> Result<TriangleMesh, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open mesh file: {e}"))?;
    let name = path.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".gltf") || name.ends_with(".glb") {
        // `read_gltf` bounds the file's size, as a mesh or as a scene.
        let scene = read_gltf(path)?;
        let mut mesh = scene.mesh;
        mesh.notes = scene.notes;
        return check_mesh(mesh);
    }
    let compressed = name.ends_with(".gz");
    let inner_name = name.strip_suffix(".gz").unwrap_or(&name);
    // Only an uncompressed regular file tells its size; otherwise the read limit bounds it.
    let available = match file.metadata() {
        Ok(m) if m.is_file() && !compressed => m.len().min(MAX_MESH_BYTES),
        _ => MAX_MESH_BYTES,
    };
    let source: Box<dyn Read> = if compressed {
        Box::new(flate2::read::MultiGzDecoder::new(file))
    } else {
        Box::new(file)
    };
    let mut reader = GuardedReader::new(source, MAX_MESH_BYTES, MAX_LINE_BYTES);
    let mesh = if inner_name.ends_with(".obj") {
        let mesh = read_obj(&mut reader, path)?;
        if non_finite_vertex(&mesh).is_some()
            && let Some((line, text)) = non_finite_obj_line(path, compressed)
        {
            return Err(format!(
                "line {line}: `{text}`: a number that is not finite (NaN, infinity, or beyond \
                 the 32-bit float range)"
            ));
        }
        mesh
    } else if inner_name.ends_with(".ply") {
        read_ply(&mut reader, available)?
    } else {
        return Err(
            "unknown mesh format (expected .obj, .ply, .obj.gz, .ply.gz, .gltf or .glb)".into(),
        );
    };
    check_mesh(mesh)
}

/// The first `v`, `vt` or `vn` line of OBJ `path` with a number that is not finite (NaN,
/// infinity, or beyond the 32-bit float range), with its number: tobj keeps no lines, so the
/// file is read again once `check_mesh` has refused what tobj made of it.
fn non_finite_obj_line(path: &Path, compressed: bool) -> Option<(usize, String)> {
    let file = std::fs::File::open(path).ok()?;
    let source: Box<dyn Read> = match compressed {
        true => Box::new(flate2::read::MultiGzDecoder::new(file)),
        false => Box::new(file),
    };
    let reader = GuardedReader::new(source, MAX_MESH_BYTES, MAX_LINE_BYTES);
    let not_finite = |word: &str| word.parse::<f32>().is_ok_and(|v| !v.is_finite());
    reader
        .lines()
        .map_while(|line| line.ok())
        .enumerate()
        .find(|(_, line)| {
            let mut words = line.split_whitespace();
            matches!(words.next(), Some("v" | "vt" | "vn")) && words.any(not_finite)
        })
        .map(|(i, line)| (i + 1, line.trim().to_string()))
}
