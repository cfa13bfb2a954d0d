//! Mesh files as tools and scanners write them: OBJ with quads, negative indices and several
//! objects; PLY in ASCII and binary of both byte orders with extra properties; gzip-compressed.
//! Every encoding of the same pyramid must load to the same triangles.

use std::io::Write;
use std::path::PathBuf;

use chambre::scene::mesh_file::load_mesh;

/// Square pyramid: base (0..4) as one quad, apex 4, four sides.
const POSITIONS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 0.0, 1.0],
    [0.0, 0.0, 1.0],
    [0.5, 1.0, 0.5],
];
const QUAD: [u32; 4] = [0, 1, 2, 3];
const SIDES: [[u32; 3]; 4] = [[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-meshes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn obj_text() -> String {
    let mut text = String::from("# two objects, a quad, negative indices\no base\n");
    for p in POSITIONS {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    text += "f 1 2 3 4\no sides\n";
    // Relative indices count back from the last vertex (-1 is the apex).
    for side in SIDES {
        let rel = side.map(|i| i as i64 - 5);
        text += &format!("f {} {} {}\n", rel[0], rel[1], rel[2]);
    }
    text
}

fn ply_header(format: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment written by a scanner\nelement vertex 5\n\
         property float x\nproperty float y\nproperty float z\nproperty float confidence\n\
         property uchar intensity\nelement face 5\nproperty list uchar int vertex_indices\n\
         property uchar flags\nend_header\n"
    )
}

fn ply_ascii() -> Vec<u8> {
    let mut text = ply_header("ascii");
    for p in POSITIONS {
        text += &format!("{} {} {} 0.9 200\n", p[0], p[1], p[2]);
    }
    text += &format!("4 {} {} {} {} 7\n", QUAD[0], QUAD[1], QUAD[2], QUAD[3]);
    for s in SIDES {
        text += &format!("3 {} {} {} 7\n", s[0], s[1], s[2]);
    }
    text.into_bytes()
}

fn ply_binary(big_endian: bool) -> Vec<u8> {
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = ply_header(format).into_bytes();
    let f32b = |v: f32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let i32b = |v: i32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for p in POSITIONS {
        for c in p {
            out.extend(f32b(c));
        }
        out.extend(f32b(0.9));
        out.push(200);
    }
    let mut face = |indices: &[u32]| {
        out.push(indices.len() as u8);
        for &i in indices {
            out.extend(i32b(i as i32));
        }
        out.push(7);
    };
    face(&QUAD);
    for s in SIDES {
        face(&s);
    }
    out
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// Total area and triangle count: invariant to triangulation order and vertex numbering.
fn signature(path: &std::path::Path) -> (usize, f32) {
    let mesh = load_mesh(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let area = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    (mesh.triangles.len(), area)
}

#[test]
fn every_encoding_of_the_pyramid_loads_the_same_triangles() {
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("pyramid.obj", obj_text().into_bytes()),
        ("pyramid.obj.gz", gzip(obj_text().as_bytes())),
        ("pyramid_ascii.ply", ply_ascii()),
        ("pyramid_le.ply", ply_binary(false)),
        ("pyramid_be.ply", ply_binary(true)),
        ("pyramid_be.ply.gz", gzip(&ply_binary(true))),
    ];
    // Base 1 plus four sides of height sqrt(1.25) * base 1 / 2 each.
    let expected_area = 1.0 + 4.0 * 0.5 * 1.25f32.sqrt();
    for (name, bytes) in files {
        let path = scratch(name);
        std::fs::write(&path, bytes).unwrap();
        let (triangles, area) = signature(&path);
        assert_eq!(triangles, 6, "{name}");
        assert!((area - expected_area).abs() < 1e-5, "{name}: area {area}");
    }
}

#[test]
fn a_corrupt_gzip_or_truncated_binary_ply_is_an_error_not_a_panic() {
    let mut truncated = ply_binary(true);
    truncated.truncate(truncated.len() - 10);
    let path = scratch("truncated.ply");
    std::fs::write(&path, truncated).unwrap();
    assert!(load_mesh(&path).is_err());
    let path = scratch("corrupt.obj.gz");
    std::fs::write(&path, b"\x1f\x8b\x08\x00not really gzip").unwrap();
    assert!(load_mesh(&path).is_err());
}

/// The error of loading `path`, which must name the file.
fn load_error(path: &std::path::Path) -> String {
    let err = load_mesh(path).expect_err("an error");
    assert!(err.contains(&path.display().to_string()), "{err}");
    err
}

#[test]
fn a_mesh_that_never_ends_is_an_error_not_an_abort() {
    for name in ["zero.obj", "zero.ply"] {
        let path = scratch(name);
        let _ = std::fs::remove_file(&path);
        std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
        let err = load_error(&path);
        assert!(err.contains("line 1 is longer than 1048576 bytes"), "{err}");
    }
}

#[test]
fn an_endless_obj_line_is_cut_off() {
    let mut text = b"v 0 0 0\nv 1 0 0\n# ".to_vec();
    text.resize(text.len() + (3 << 20), b'x');
    let path = scratch("long_line.obj");
    std::fs::write(&path, &text).unwrap();
    let err = load_error(&path);
    assert!(err.contains("line 3 is longer than 1048576 bytes"), "{err}");
    // The same line compressed: the limit applies to the decompressed text.
    let path = scratch("long_line.obj.gz");
    std::fs::write(&path, gzip(&text)).unwrap();
    let err = load_error(&path);
    assert!(err.contains("line 3 is longer"), "{err}");
}

#[test]
fn a_ply_header_claiming_more_elements_than_its_bytes_is_refused() {
    for format in ["ascii", "binary_little_endian"] {
        let header = ply_header(format).replace("element vertex 5", "element vertex 4000000000");
        let mut bytes = header.into_bytes();
        bytes.extend([0u8; 64]);
        let path = scratch(&format!("claims_{format}.ply"));
        std::fs::write(&path, &bytes).unwrap();
        let err = load_error(&path);
        assert!(
            err.contains("declares 4000000000 `vertex` elements") && err.contains("only 64 bytes"),
            "{err}"
        );
        // Compressed, the size is unknown until read: the read limit bounds it instead.
        let path = scratch(&format!("claims_{format}.ply.gz"));
        std::fs::write(&path, gzip(&bytes)).unwrap();
        let err = load_error(&path);
        assert!(
            err.contains("declares 4000000000 `vertex` elements"),
            "{err}"
        );
    }
}

/// A UV sphere of `rings` x `segments` quads (split in triangles), radius 1 at the origin.
fn uv_sphere(rings: u32, segments: u32) -> chambre::scene::TriangleMesh {
    use glam::Vec3;
    let mut positions = vec![Vec3::Y, -Vec3::Y];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    let ring = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s + 1), ring(1, s)]);
        triangles.push([1, ring(rings - 1, s), ring(rings - 1, s + 1)]);
        for r in 1..rings - 1 {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s),
                ring(r + 1, s + 1),
            );
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    chambre::scene::TriangleMesh {
        positions,
        normals: None,
        triangles,
        ..Default::default()
    }
}

/// A mesh without normals asked to render smooth gets angle-weighted vertex normals: on a
/// sphere (no edge sharper than the crease) they point along the radius.
#[test]
fn computed_normals_of_a_sphere_are_radial() {
    let mut mesh = uv_sphere(24, 48);
    let vertices = mesh.positions.len();
    chambre::scene::mesh::compute_vertex_normals(&mut mesh, 30.0);
    assert_eq!(
        mesh.positions.len(),
        vertices,
        "no vertex is split on a smooth surface"
    );
    let normals = mesh.normals.as_ref().unwrap();
    let worst = mesh
        .positions
        .iter()
        .zip(normals)
        .map(|(p, n)| p.normalize().angle_between(*n).to_degrees())
        .fold(0.0f32, f32::max);
    assert!(
        worst < 0.5,
        "worst normal is {worst} degrees off the radius"
    );
}

/// A cube keeps its edges: with a 30 degree crease every corner takes its own face's normal
/// (each vertex split in three); with 180 degrees the corners average their faces.
#[test]
fn a_crease_angle_keeps_sharp_edges_sharp() {
    use glam::Vec3;
    let cube = || {
        let positions: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32))
            .collect();
        // Two triangles per face, outward winding.
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        chambre::scene::TriangleMesh {
            positions,
            normals: None,
            triangles,
            ..Default::default()
        }
    };
    let mut sharp = cube();
    chambre::scene::mesh::compute_vertex_normals(&mut sharp, 30.0);
    assert_eq!(sharp.positions.len(), 24);
    let normals = sharp.normals.as_ref().unwrap();
    for t in &sharp.triangles {
        let [a, b, c] = t.map(|i| sharp.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        for &i in t {
            assert!((normals[i as usize] - face).length() < 1e-6);
        }
    }
    let mut soft = cube();
    chambre::scene::mesh::compute_vertex_normals(&mut soft, 180.0);
    assert_eq!(soft.positions.len(), 8);
    for (p, n) in soft.positions.iter().zip(soft.normals.as_ref().unwrap()) {
        // Each corner of the cube averages three face normals (angles of 90, 90 and 2 x 45
        // degrees), so it points away from the centre on every axis.
        let outward = (*p - Vec3::splat(0.5)).signum();
        assert!(
            n.x * outward.x > 0.3 && n.y * outward.y > 0.3 && n.z * outward.z > 0.3,
            "{n}"
        );
    }
}

/// A PLY of triangle strips (a `tristrips` element, -1 restarting a strip) loads like faces:
/// a 2 x 1 grid of quads as one strip, and as two strips joined by a restart, both give four
/// triangles of the same winding covering the grid's area.
#[test]
fn ply_triangle_strips_load_like_faces() {
    for (name, strip) in [
        ("strip.ply", vec![0, 3, 1, 4, 2, 5]),
        ("restart.ply", vec![0, 3, 1, 4, -1, 1, 4, 2, 5]),
    ] {
        let mut text = String::from("ply\nformat ascii 1.0\nelement vertex 6\n");
        text += "property float x\nproperty float y\nproperty float z\n";
        text += "element tristrips 1\nproperty list int int vertex_indices\nend_header\n";
        for (x, y) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)] {
            text += &format!("{x} {y} 0\n");
        }
        text += &format!(
            "{} {}\n",
            strip.len(),
            strip
                .iter()
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
        let path = scratch(name);
        std::fs::write(&path, text).unwrap();
        let mesh = load_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.triangles.len(), 4, "{name}");
        let mut area = 0.0;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.z < 0.0, "{name}: {t:?} is wound the other way");
            area += 0.5 * n.length();
        }
        assert!((area - 2.0).abs() < 1e-6, "{name}: area {area}");
    }
}
