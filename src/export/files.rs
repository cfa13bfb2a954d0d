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

/// Most texels of a map resampled for Mitsuba's `envmap` (12 MiB as 32-bit RGB).
pub const ENVMAP_MAX_TEXELS: u64 = 1 << 20;

/// Most samples per texel side of a map resampled for Mitsuba's `envmap`.
pub const ENVMAP_MAX_FACTOR: u32 = 32;

/// chambre's map (`width` x `height` texels, piecewise constant: texel (i, j) covers
/// u in [i / W, (i + 1) / W), v in [j / H, (j + 1) / H)) as a bitmap for Mitsuba's `envmap`,
/// which interpolates bilinearly between pixel centres at u = (x + 1/2) / W' and
/// v = y / (H' - 1) (rows on the poles). Each texel becomes `factor` x `factor` samples of
/// itself, plus one last row on the -y pole: W' = k W, H' = k H + 1. Column x holds texel
/// x / k, so two neighbouring columns differ only where they straddle a texel edge; row y
/// holds texel min(y / k, H - 1), so rows y and y + 1 differ only in the interval just above
/// an edge. Mitsuba's radiance is chambre's except on strips of width 1 / W' beside each
/// texel edge (a fraction 1 / k of the longitudes and (H - 1) / (k H) of the colatitudes),
/// where it is a blend of the two texels. Returns (W', H', texels row by row from the top).
pub fn envmap_resampled(
    width: u32,
    height: u32,
    texels: &[[f32; 3]],
    factor: u32,
) -> (u32, u32, Vec<[f32; 3]>) {
    let (w, h) = (width * factor, height * factor + 1);
    let mut out = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        let row = (y / factor).min(height - 1);
        for x in 0..w {
            out.push(texels[(row * width + x / factor) as usize]);
        }
    }
    (w, h, out)
}

/// The samples per texel side for a `width` x `height` map: the most, up to
/// `ENVMAP_MAX_FACTOR`, that keep the bitmap within `ENVMAP_MAX_TEXELS` (at least 1).
pub fn envmap_factor(width: u32, height: u32) -> u32 {
    let fits =
        |k: u32| (width as u64 * k as u64) * (height as u64 * k as u64 + 1) <= ENVMAP_MAX_TEXELS;
    (1..=ENVMAP_MAX_FACTOR)
        .rev()
        .find(|&k| fits(k))
        .unwrap_or(1)
}

/// A 32-bit float RGB OpenEXR of `width` x `height` texels, rows from the top.
pub fn exr_rgb(width: u32, height: u32, texels: &[[f32; 3]]) -> Result<Vec<u8>, String> {
    let flat: Vec<f32> = texels.iter().flatten().copied().collect();
    let image = image::Rgb32FImage::from_raw(width, height, flat)
        .ok_or_else(|| "texel count does not match the size".to_string())?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb32F(image)
        .write_to(&mut bytes, image::ImageFormat::OpenExr)
        .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}
