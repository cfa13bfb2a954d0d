//! Triangle meshes from OBJ and PLY files (`.gz` read transparently), as real tools write them.
//!
//! OBJ goes through `tobj` (quads and n-gons fan-triangulated, negative indices, several objects
//! and groups, with or without normals); PLY through `ply-rs-bw` (ASCII and binary of either byte
//! order; faces and triangle strips; other properties are ignored).

use std::cell::{Cell, RefCell};
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use std::sync::Arc;

use glam::{DQuat, DVec3, Mat3, Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, Encoding, Header, Property, PropertyType, ScalarType};

use super::texture::{Texture, TextureCache, Wrap, resolve_file};

/// Most bytes read from one mesh file, after decompression: a file that never ends (a device,
/// a gzip bomb) stops here with an error instead of exhausting memory.
pub const MAX_MESH_BYTES: u64 = 2 << 30;
/// Longest text line of an OBJ file, a PLY header or an ASCII PLY body: the parsers grow one
/// string per line, so an endless line must be cut off before it exhausts memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// An indexed triangle mesh in scene space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions (scene units).
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, when the file has them and the shape asks for smooth shading.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates (glTF's convention: v = 0 at the image's top), when the
    /// file gives every vertex some.
    pub texcoords: Option<Vec<Vec2>>,
    /// Vertex indices of each triangle, into `positions` (and `normals`).
    pub triangles: Vec<[u32; 3]>,
    /// Zero-area triangles dropped on load (they can never be hit).
    pub dropped_degenerate: usize,
    /// The materials of the OBJ's `.mtl` files, as the file gives them.
    pub materials: Vec<MeshMaterial>,
    /// Per triangle, its index in `materials`, or `NO_MATERIAL`; empty when the file names no
    /// material.
    pub face_materials: Vec<u32>,
    /// What reading left out that a user should know (a glTF's textures), one sentence each.
    pub notes: Vec<String>,
    /// The OBJ's `mtllib` files that could not be read: an error where the scene needs the
    /// file's materials, a warning where it gives the mesh its own.
    pub missing_libraries: Vec<MissingLibrary>,
}

/// An OBJ `mtllib` file that could not be read (Blender and pbrt go on without it, as chambre
/// does when the scene gives the mesh a material).
#[derive(Clone, Debug, PartialEq)]
pub struct MissingLibrary {
    /// The OBJ file.
    pub obj: PathBuf,
    /// The OBJ's line that names it (1-based).
    pub line: usize,
    /// Where it was looked for: beside the OBJ.
    pub path: PathBuf,
    /// Why it could not be read.
    pub reason: String,
}

impl std::fmt::Display for MissingLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}: mtllib {}: {}",
            self.obj.display(),
            self.line,
            self.path.display(),
            self.reason
        )
    }
}

/// A triangle whose file gives it no material.
pub const NO_MATERIAL: u32 = u32::MAX;

/// A material of an OBJ `.mtl` file, mapped to chambre's models (see `docs/scene-format.md`):
/// `Kd` is the diffuse reflectance, `Ks` and `Ns` a Blinn-Phong lobe, `illum` 3 or 5 a mirror
/// of reflectance `Ks` (1 where `Ks` is absent), `Ke` an emitter, `illum` 4, 6 or 7 (refraction)
/// glass of index `Ni` under the path tracer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshMaterial {
    /// Its `newmtl` name.
    pub name: String,
    /// Diffuse reflectance: `Kd`, clamped to [0, 1].
    pub diffuse: Vec3,
    /// Specular reflectance of the Blinn-Phong lobe: `Ks`, clamped to [0, 1]; zero for a mirror.
    pub specular: Vec3,
    /// Exponent of the lobe: `Ns`, clamped to [0, 1e4].
    pub shininess: f32,
    /// Mirror reflectance (`illum` 3 or 5): `Ks`, or 1 where absent; zero otherwise.
    pub mirror: Vec3,
    /// `Ke`: emitted radiance, as the library gives it (validated with the scene); non-zero
    /// makes every triangle of it an area light.
    pub emission: Vec3,
    /// `illum` 4, 6 or 7 (a refracting material): its index of refraction, `Ni` (1.5 where
    /// absent), clamped to [0.1, 10]; the path tracer renders it as a smooth dielectric.
    pub ior: Option<f32>,
    /// `map_Kd`: a texture whose colour multiplies `diffuse`, as the MTL format defines it.
    pub diffuse_texture: Option<Arc<Texture>>,
    /// A rough conductor's perceptual roughness (a glTF metal's `roughnessFactor`): its lobe,
    /// of reflectance `specular`, is GGX's instead of Blinn-Phong's.
    pub conductor_roughness: Option<f32>,
}

impl MeshMaterial {
    /// The MTL material `m`, its texture (`map_Kd`, the file name after any options) read
    /// from `folder`, the library's, through `textures`.
    fn from_mtl(
        m: &tobj::Material,
        folder: &Path,
        textures: &mut TextureCache,
    ) -> Result<MeshMaterial, String> {
        let diffuse_texture = match m.diffuse_texture.as_deref() {
            Some(map) => {
                let name = map.split_whitespace().last().unwrap_or(map);
                let path = resolve_file(folder, name);
                let texture = textures.get(&path, [Wrap::Repeat; 2]).map_err(|e| {
                    format!("material {:?}: map_Kd {}: {e}", m.name, path.display())
                })?;
                Some(texture)
            }
            None => None,
        };
        Ok(MeshMaterial {
            diffuse_texture,
            ..MeshMaterial::from_mtl_factors(m)
        })
    }

    /// The MTL material `m`'s factors.
    fn from_mtl_factors(m: &tobj::Material) -> MeshMaterial {
        let rgb = |v: Option<[f32; 3]>| v.map_or(Vec3::ZERO, Vec3::from);
        let specular = rgb(m.specular);
        let mirror = matches!(m.illumination_model, Some(3 | 5));
        MeshMaterial {
            name: m.name.clone(),
            diffuse: rgb(m.diffuse).clamp(Vec3::ZERO, Vec3::ONE),
            specular: if mirror {
                Vec3::ZERO
            } else {
                specular.clamp(Vec3::ZERO, Vec3::ONE)
            },
            shininess: m.shininess.unwrap_or(0.0).clamp(0.0, 1.0e4),
            mirror: match (mirror, m.specular) {
                (true, Some(ks)) => Vec3::from(ks).clamp(Vec3::ZERO, Vec3::ONE),
                (true, None) => Vec3::ONE,
                (false, _) => Vec3::ZERO,
            },
            // Kept as written: the scene's validation refuses what no radiance can be.
            emission: rgb(m.emissive),
            ior: matches!(m.illumination_model, Some(4 | 6 | 7)).then(|| {
                let ior = m.optical_density.unwrap_or(DEFAULT_IOR);
                ior.clamp(*IOR_RANGE.start() as f32, *IOR_RANGE.end() as f32)
            }),
            diffuse_texture: None,
            conductor_roughness: None,
        }
    }
}

/// The index of refraction of a glass that names none (an MTL without `Ni`, a scene material
/// or glTF material without `ior`).
pub const DEFAULT_IOR: f32 = 1.5;
/// The indices of refraction chambre's glass takes, from every source.
pub const IOR_RANGE: std::ops::RangeInclusive<f64> = 0.1..=10.0;

/// A buffered reader with limits: at most `max_bytes` in all, and (while `line_limit` is set)
/// at most that many bytes without a line break. It counts the lines its reader has consumed,
/// so a parser's error can be placed, and keeps the reason of the first failure, because the
/// parsers replace a read error by a generic one (tobj: "read error").
pub(super) struct GuardedReader {
    inner: BufReader<Box<dyn Read>>,
    max_bytes: u64,
    line_limit: Option<usize>,
    consumed: u64,
    /// Where the reading stands, shared with whoever must place what it reads as it reads
    /// (an OBJ's `mtllib` lines, whose files the parser opens mid-read).
    position: Rc<Position>,
    failure: Option<String>,
}

/// Lines a reader has consumed.
#[derive(Debug, Default)]
struct Position {
    /// Line breaks consumed so far.
    lines: Cell<usize>,
    /// Bytes consumed since the last line break.
    line_length: Cell<usize>,
}

impl Position {
    /// 1-based number of the line being read (the last one consumed, if it has no break yet).
    fn current_line(&self) -> usize {
        if self.line_length.get() > 0 {
            self.lines.get() + 1
        } else {
            self.lines.get().max(1)
        }
    }
}

impl GuardedReader {
    pub(super) fn new(source: Box<dyn Read>, max_bytes: u64, line_limit: usize) -> Self {
        GuardedReader {
            inner: BufReader::new(source),
            max_bytes,
            line_limit: Some(line_limit),
            consumed: 0,
            position: Rc::default(),
            failure: None,
        }
    }

    /// 1-based number of the line being read (the last one consumed, if it has no break yet).
    fn current_line(&self) -> usize {
        self.position.current_line()
    }

    fn fail(&mut self, reason: String) -> std::io::Error {
        let error = std::io::Error::new(std::io::ErrorKind::InvalidData, reason.clone());
        self.failure.get_or_insert(reason);
        error
    }

    /// The reason of the reader's own failure if there was one, else the parser's `message`.
    fn explain(&self, message: String) -> String {
        self.failure.clone().unwrap_or(message)
    }

    /// Errors that must stop the read before more bytes are handed out.
    fn check_limits(&mut self, buffered: usize) -> std::io::Result<()> {
        if let Some(limit) = self.line_limit
            && self.position.line_length.get() > limit
        {
            let line = self.position.lines.get() + 1;
            return Err(self.fail(format!(
                "line {line} is longer than {limit} bytes without a line break"
            )));
        }
        if self.consumed >= self.max_bytes && buffered > 0 {
            return Err(self.fail(format!(
                "holds more than {} bytes (the limit on a mesh file, after decompression)",
                self.max_bytes
            )));
        }
        Ok(())
    }
}

impl Read for GuardedReader {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let buffered = self.fill_buf()?;
        let n = buffered.len().min(out.len());
        out[..n].copy_from_slice(&buffered[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for GuardedReader {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        let buffered = match self.inner.fill_buf() {
            Ok(b) => b.len(),
            Err(e) => return Err(self.fail(format!("cannot read: {e}"))),
        };
        self.check_limits(buffered)?;
        let allowed = (self.max_bytes - self.consumed).min(buffered as u64) as usize;
        Ok(&self.inner.buffer()[..allowed])
    }

    fn consume(&mut self, amount: usize) {
        let taken = &self.inner.buffer()[..amount];
        let position = &self.position;
        match taken.iter().rposition(|&b| b == b'\n') {
            Some(last) => {
                let breaks = taken.iter().filter(|&&b| b == b'\n').count();
                position.lines.set(position.lines.get() + breaks);
                position.line_length.set(amount - last - 1);
            }
            None => position
                .line_length
                .set(position.line_length.get() + amount),
        }
        self.consumed += amount as u64;
        self.inner.consume(amount);
    }
}

pub(super) fn read_obj(reader: &mut GuardedReader, obj: &Path) -> Result<TriangleMesh, String> {
    let directory = obj.parent().unwrap_or(Path::new("."));
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    // `mtllib` files are read beside the OBJ. One that cannot be read is noted with its line
    // (the parser calls this right after consuming it) and stands for no materials, so its
    // `usemtl` faces get none: whether that matters is the scene's to say.
    let position = reader.position.clone();
    let missing = RefCell::new(Vec::new());
    // Each library's folder, with its number of materials: their textures are named from there.
    let libraries = RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(reader, &options, |name| {
        let path = directory.join(name);
        let folder = path.parent().unwrap_or(directory).to_path_buf();
        let loaded = tobj::load_mtl(&path);
        if let Ok((materials, _)) = &loaded {
            libraries.borrow_mut().push((folder, materials.len()));
        }
        loaded.or_else(|e| {
            missing.borrow_mut().push(MissingLibrary {
                obj: obj.to_path_buf(),
                line: position.current_line(),
                reason: library_failure(&path, e),
                path,
            });
            Ok(Default::default())
        })
    })
    .map_err(|e| reader.explain(obj_error_message(e, reader.current_line())))?;
    // The loader above stands in for every library that fails, so tobj has no error to give.
    let materials = materials.unwrap_or_default();
    let folders = libraries
        .into_inner()
        .into_iter()
        .flat_map(|(folder, count)| std::iter::repeat_n(folder, count));
    let mut textures = TextureCache::default();
    let mut mesh = TriangleMesh {
        materials: materials
            .iter()
            .zip(folders.chain(std::iter::repeat(directory.to_path_buf())))
            .map(|(m, folder)| MeshMaterial::from_mtl(m, &folder, &mut textures))
            .collect::<Result<_, _>>()?,
        missing_libraries: missing.into_inner(),
        ..TriangleMesh::default()
    };
    let has_materials = models.iter().any(|m| m.mesh.material_id.is_some());
    let all_have_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let all_have_texcoords = models
        .iter()
        .all(|m| 3 * m.mesh.texcoords.len() == 2 * m.mesh.positions.len());
    let mut normals = Vec::new();
    let mut texcoords = Vec::new();
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
        // OBJ's v grows upwards from the image's bottom; glTF's, chambre's, from its top.
        if all_have_texcoords {
            texcoords.extend(
                m.texcoords
                    .chunks_exact(2)
                    .map(|t| Vec2::new(t[0], 1.0 - t[1])),
            );
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
        if has_materials {
            let id = m.material_id.map_or(NO_MATERIAL, |i| i as u32);
            mesh.face_materials.resize(mesh.triangles.len(), id);
        }
    }
    if all_have_normals && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    if all_have_texcoords && !texcoords.is_empty() {
        mesh.texcoords = Some(texcoords);
    }
    Ok(mesh)
}

/// Why `path`, an `mtllib` file, could not be read: tobj's error says only "open error" or
/// "read error", so the file is asked again for the system's reason.
fn library_failure(path: &Path, e: tobj::LoadError) -> String {
    match (e, std::fs::File::open(path)) {
        (tobj::LoadError::OpenFileFailed, Err(io)) => io.to_string(),
        (e, _) => match small_text(path).and_then(|t| first_failing_line(&t)) {
            Some((line, text)) => format!("malformed material library: line {line}: `{text}`: {e}"),
            None => format!("malformed material library: {e}"),
        },
    }
}

/// The text of `path` where it is a regular file of at most 16 MiB: the search for a
/// library's failing line reads it whole, many times over.
fn small_text(path: &Path) -> Option<String> {
    let meta = std::fs::metadata(path).ok()?;
    (meta.is_file() && meta.len() <= 16 << 20)
        .then(|| std::fs::read_to_string(path).ok())
        .flatten()
}

/// The line of MTL `text` tobj refuses, with its number: tobj names no line, so the shortest
/// run of first lines it refuses is searched for (a run it refuses is refused longer too).
/// None where the whole text reads (the library failed for another reason).
fn first_failing_line(text: &str) -> Option<(usize, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let fails = |count: usize| {
        let prefix = lines[..count].join("\n");
        tobj::load_mtl_buf(&mut prefix.as_bytes()).is_err()
    };
    if !fails(lines.len()) {
        return None;
    }
    // The fewest lines that fail: in (low, high], `high` failing.
    let (mut low, mut high) = (0, lines.len());
    while high - low > 1 {
        let middle = (low + high) / 2;
        match fails(middle) {
            true => high = middle,
            false => low = middle,
        }
    }
    Some((high, lines[high - 1].trim().to_string()))
}

/// tobj parses line by line, except that it resolves face indices when an object ends (at the
/// next `o` line or at the end of the file), so those errors name the object's last line.
fn obj_error_message(e: tobj::LoadError, line: usize) -> String {
    use tobj::LoadError::*;
    match e {
        // Read errors from the file itself are kept by the reader; what is left is std's check
        // that each line is UTF-8.
        ReadError => format!("malformed OBJ: line {line} is not UTF-8 text"),
        FaceVertexOutOfBounds
        | FaceTexCoordOutOfBounds
        | FaceNormalOutOfBounds
        | FaceColorOutOfBounds => {
            format!("malformed OBJ: {e} in a face of the object that ends at line {line}")
        }
        _ => format!("malformed OBJ at line {line}: {e}"),
    }
}

pub(super) fn read_ply(reader: &mut GuardedReader, available: u64) -> Result<TriangleMesh, String> {
    let parser = Parser::<DefaultElement>::new();
    let header = parser
        .read_header(&mut Reader::new(&mut *reader))
        .map_err(|e| reader.explain(format!("malformed PLY header: {e}")))?;
    check_element_counts(&header, available.saturating_sub(reader.consumed))?;
    if header.encoding != Encoding::Ascii {
        // Binary data has no lines: any run of bytes without 0x0a is legitimate.
        reader.line_limit = None;
    }
    let payload = parser
        .read_payload(&mut Reader::new(&mut *reader), &header)
        .map_err(|e| reader.explain(format!("malformed PLY: {e}")))?;
    let vertices = payload.get("vertex").ok_or("PLY has no `vertex` element")?;
    let scalar = |e: &DefaultElement, key: &str| -> Option<f32> {
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
    let count = mesh.positions.len() as i64;
    let faces = payload.get("face").map(Vec::as_slice).unwrap_or_default();
    for (f, face) in faces.iter().enumerate() {
        let indices = integer_list(face, &["vertex_indices", "vertex_index"])
            .ok_or_else(|| format!("PLY face {f} has no integer vertex_indices list"))?;
        check_indices(&indices, count, || format!("PLY face {f}"))?;
        // Fan-triangulate polygons, as tobj does for OBJ.
        for k in 1..indices.len().saturating_sub(1) {
            mesh.triangles
                .push([indices[0] as u32, indices[k] as u32, indices[k + 1] as u32]);
        }
    }
    // Triangle strips (scanners and some exporters write them): each new index makes a
    // triangle with the two before it, every other one reversed to keep the winding; -1
    // restarts the strip.
    let strips = payload
        .get("tristrips")
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (s, strip) in strips.iter().enumerate() {
        let indices = integer_list(strip, &["vertex_indices", "vertex_index"])
            .ok_or_else(|| format!("PLY tristrips {s} has no integer vertex_indices list"))?;
        let vertices: Vec<i64> = indices.iter().copied().filter(|&i| i != -1).collect();
        check_indices(&vertices, count, || format!("PLY tristrips {s}"))?;
        for run in indices.split(|&i| i == -1) {
            for k in 2..run.len() {
                let (a, b, c) = (run[k - 2] as u32, run[k - 1] as u32, run[k] as u32);
                mesh.triangles
                    .push(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
            }
        }
    }
    Ok(mesh)
}

/// The first of `keys` that is an integer list property of `element`, widened to i64.
fn integer_list(element: &DefaultElement, keys: &[&str]) -> Option<Vec<i64>> {
    let property = keys.iter().find_map(|k| element.get(*k))?;
    Some(match property {
        Property::ListInt(l) => l.iter().map(|&i| i as i64).collect(),
        Property::ListUInt(l) => l.iter().map(|&i| i as i64).collect(),
        Property::ListShort(l) => l.iter().map(|&i| i as i64).collect(),
        Property::ListUShort(l) => l.iter().map(|&i| i as i64).collect(),
        Property::ListChar(l) => l.iter().map(|&i| i as i64).collect(),
        Property::ListUChar(l) => l.iter().map(|&i| i as i64).collect(),
        _ => return None,
    })
}

/// Every index must name a vertex; `what` names the element for the message.
fn check_indices(indices: &[i64], count: i64, what: impl Fn() -> String) -> Result<(), String> {
    match indices.iter().find(|&&i| i < 0 || i >= count) {
        Some(bad) => Err(format!(
            "{} has vertex index {bad}, out of range (0..{count})",
            what()
        )),
        None => Ok(()),
    }
}

/// The header's element counts against the bytes that follow it, before the parser reads them:
/// a header claiming 4e9 vertices in a small file is refused at once, not after a long loop.
fn check_element_counts(header: &Header, available: u64) -> Result<(), String> {
    let mut needed = 0u64;
    for element in header.elements.values() {
        // Every element takes at least a byte (an element without properties is refused by
        // counting it as one), so a count can never outrun the data.
        let smallest = element
            .properties
            .values()
            .map(|p| smallest_encoding(&header.encoding, &p.data_type))
            .sum::<u64>()
            .max(1);
        needed = needed.saturating_add((element.count as u64).saturating_mul(smallest));
        if needed > available {
            return Err(format!(
                "PLY header declares {} `{}` elements, which need at least {needed} bytes, but \
                 only {available} bytes follow the header",
                element.count, element.name
            ));
        }
    }
    Ok(())
}

/// Fewest bytes one property can take: its binary size (a list: its length field alone), or in
/// ASCII one digit and one separator.
fn smallest_encoding(encoding: &Encoding, property: &PropertyType) -> u64 {
    if *encoding == Encoding::Ascii {
        return 2;
    }
    let scalar = match property {
        PropertyType::Scalar(t) | PropertyType::List(t, _) => t,
    };
    match scalar {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// What is wrong with the first position, texture coordinate or normal of `mesh` that is not
/// finite (NaN, infinity, or beyond the 32-bit float range), if any.
pub(super) fn non_finite_vertex(mesh: &TriangleMesh) -> Option<String> {
    fn first<T: Copy>(values: &[T], finite: impl Fn(&T) -> bool) -> Option<(usize, T)> {
        values
            .iter()
            .position(|v| !finite(v))
            .map(|i| (i, values[i]))
    }
    if let Some((i, p)) = first(&mesh.positions, |p| p.is_finite()) {
        return Some(format!(
            "vertex {i} has a non-finite coordinate ({}, {}, {}): NaN, infinity, or beyond \
             the 32-bit float range",
            p.x, p.y, p.z
        ));
    }
    let texcoords = mesh.texcoords.as_deref().unwrap_or_default();
    if let Some((i, t)) = first(texcoords, |t| t.is_finite()) {
        return Some(format!(
            "vertex {i} has a non-finite texture coordinate ({}, {})",
            t.x, t.y
        ));
    }
    let normals = mesh.normals.as_deref().unwrap_or_default();
    let (i, n) = first(normals, |n| n.is_finite())?;
    Some(format!(
        "vertex {i} has a non-finite normal ({}, {}, {})",
        n.x, n.y, n.z
    ))
}

/// Rejects meshes that cannot be rendered and drops triangles that can never be hit.
pub(super) fn check_mesh(mut mesh: TriangleMesh) -> Result<TriangleMesh, String> {
    if let Some(message) = non_finite_vertex(&mesh) {
        return Err(message);
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
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a) != Vec3::ZERO
        })
        .collect();
    let mut kept = keep.iter();
    mesh.triangles.retain(|_| *kept.next().unwrap_or(&false));
    if !mesh.face_materials.is_empty() {
        let mut kept = keep.iter();
        mesh.face_materials
            .retain(|_| *kept.next().unwrap_or(&false));
    }
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

/// Vertex normals for a mesh whose file has none: each triangle corner gets the average of the
/// normals of the triangles around its vertex that lie within `crease_deg` of its own triangle,
/// each weighted by its angle at the vertex (Thürmer and Wüthrich's angle weighting, which does
/// not depend on how the surface is triangulated). Edges sharper than the crease stay sharp:
/// corners of one vertex that end with different normals get their own copy of the vertex, so
/// the mesh stays indexed per vertex.
pub fn compute_vertex_normals(mesh: &mut TriangleMesh, crease_deg: f32) {
    let positions = &mesh.positions;
    let corners = |t: &[u32; 3]| t.map(|i| positions[i as usize]);
    let face_normals: Vec<Vec3> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = corners(t);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    // The angle of triangle `t` at its corner `k`.
    let corner_angle = |t: &[u32; 3], k: usize| {
        let p = corners(t);
        let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        e1.angle_between(e2)
    };
    let mut incident: Vec<Vec<(u32, f32)>> = vec![Vec::new(); positions.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            incident[t[k] as usize].push((f as u32, corner_angle(t, k)));
        }
    }
    let cos_crease = crease_deg.to_radians().cos();
    let mut new_positions = Vec::with_capacity(positions.len());
    let mut new_texcoords = Vec::new();
    let texcoords = mesh.texcoords.as_ref();
    let mut normals = Vec::with_capacity(positions.len());
    let mut index = std::collections::HashMap::new();
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    for (f, t) in mesh.triangles.iter().enumerate() {
        let own = face_normals[f];
        let corner_normal = |v: u32| {
            let sum: Vec3 = incident[v as usize]
                .iter()
                .filter(|(g, _)| face_normals[*g as usize].dot(own) >= cos_crease)
                .map(|&(g, angle)| angle * face_normals[g as usize])
                .sum();
            sum.try_normalize().unwrap_or(own)
        };
        triangles.push(t.map(|v| {
            let n = corner_normal(v);
            *index
                .entry((v, n.to_array().map(f32::to_bits)))
                .or_insert_with(|| {
                    new_positions.push(positions[v as usize]);
                    if let Some(t) = texcoords {
                        new_texcoords.push(t[v as usize]);
                    }
                    normals.push(n);
                    new_positions.len() as u32 - 1
                })
        }));
    }
    mesh.positions = new_positions;
    if mesh.texcoords.is_some() {
        mesh.texcoords = Some(new_texcoords);
    }
    mesh.normals = Some(normals);
    mesh.triangles = triangles;
}

/// Applies scale, then rotation about x, then y, then z (degrees), then translation.
pub fn transform_mesh(mesh: &mut TriangleMesh, scale: Vec3, rotate_deg: Vec3, translate: Vec3) {
    let rotation = rotation_of(rotate_deg);
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

/// The rotation of a shape's `rotate` (degrees about x, then y, then z).
pub fn rotation_of(rotate_deg: Vec3) -> Mat3 {
    Mat3::from_rotation_z(rotate_deg.z.to_radians())
        * Mat3::from_rotation_y(rotate_deg.y.to_radians())
        * Mat3::from_rotation_x(rotate_deg.x.to_radians())
}

/// The same rotation as [`rotation_of`], in double precision, as a quaternion: a torus's,
/// ellipsoid's or cylinder's `rotate` (its orientation about its centre).
pub fn orientation_of(rotate_deg: DVec3) -> DQuat {
    DQuat::from_rotation_z(rotate_deg.z.to_radians())
        * DQuat::from_rotation_y(rotate_deg.y.to_radians())
        * DQuat::from_rotation_x(rotate_deg.x.to_radians())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curved shape's `rotate` turns it as a mesh's turns the mesh.
    #[test]
    fn orientation_of_turns_as_rotation_of() {
        for rotate in [
            DVec3::new(90.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 90.0),
            DVec3::new(30.0, -45.0, 120.0),
        ] {
            for v in [DVec3::X, DVec3::Y, DVec3::new(0.3, -0.5, 0.8)] {
                let by_matrix = rotation_of(rotate.as_vec3()) * v.as_vec3();
                let by_quaternion = orientation_of(rotate) * v;
                assert!(
                    (by_quaternion.as_vec3() - by_matrix).length() < 1e-6,
                    "{rotate} turns {v} to {by_quaternion} and {by_matrix}"
                );
            }
        }
    }

    /// The 2 GiB limit scaled down: an endless stream of empty lines stops at `max_bytes`.
    #[test]
    fn the_byte_limit_stops_an_endless_stream() {
        let mut reader = GuardedReader::new(Box::new(std::io::repeat(b'\n')), 1000, 10);
        let mut sink = Vec::new();
        let err = reader.read_to_end(&mut sink).unwrap_err();
        assert_eq!(sink.len(), 1000);
        assert!(err.to_string().contains("more than 1000 bytes"), "{err}");
        assert_eq!(reader.explain("parser".into()), err.to_string());
    }

    #[test]
    fn lines_are_counted_and_limited() {
        let text = b"a\nbb\nccccccccccccccc".to_vec();
        let mut reader = GuardedReader::new(Box::new(std::io::Cursor::new(text)), 1000, 10);
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        reader.read_line(&mut line).unwrap();
        assert_eq!(reader.current_line(), 2);
        let err = reader.read_line(&mut line).unwrap_err();
        assert!(
            err.to_string().contains("line 3 is longer than 10 bytes"),
            "{err}"
        );
    }

    /// A normal that is not finite (a glTF's, a binary PLY's) is refused with its vertex, as a
    /// position is: it would shade its triangles NaN.
    #[test]
    fn a_non_finite_normal_is_refused() {
        let mesh = |n: Vec3| TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: Some(vec![Vec3::Z, n, Vec3::Z]),
            triangles: vec![[0, 1, 2]],
            ..TriangleMesh::default()
        };
        assert!(check_mesh(mesh(Vec3::Z)).is_ok());
        let err = check_mesh(mesh(Vec3::new(0.0, f32::NAN, 1.0))).unwrap_err();
        assert_eq!(err, "vertex 1 has a non-finite normal (0, NaN, 1)");
    }
}
