//! A mesh file of any format chambre reads, chosen by its extension: OBJ and PLY (`.gz` read
//! transparently, `mesh`) and glTF (`gltf`, its meshes merged into one).

use std::io::Read;
use std::path::Path;

use super::gltf::read_gltf;
use super::mesh::{
    GuardedReader, MAX_LINE_BYTES, MAX_MESH_BYTES, TriangleMesh, check_mesh, read_obj, read_ply,
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
        read_obj(&mut reader, path)?
    } else if inner_name.ends_with(".ply") {
        read_ply(&mut reader, available)?
    } else {
        return Err(
            "unknown mesh format (expected .obj, .ply, .obj.gz, .ply.gz, .gltf or .glb)".into(),
        );
    };
    check_mesh(mesh)
}
