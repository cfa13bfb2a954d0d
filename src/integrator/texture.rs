//! Texture lookups: where a hit lies in its primitive's texture coordinates, and the colour
//! a texture has there. Twin: `wgsl/texture.wgsl`.
//!
//! Texels are sRGB-encoded RGBA8 (`layout::GpuTexture`); a lookup decodes the four texels
//! around the point to linear values first and then blends them bilinearly, as a GPU's sRGB
//! texture formats do (filtering encoded values would darken every edge). Coordinates follow
//! glTF: (0, 0) is the image's top-left corner, v grows downwards. Equations:
//! `docs/textures.md`.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::accel::intersect::Hit;
use crate::layout::*;

/// The texture coordinates of `hit` on `prim` (whose outward normal at the hit is `outward`):
/// a triangle's interpolated from its vertices' (`uvs`, at its `normals` index), a
/// parallelogram's along its edges (v from the far edge, so an image stands upright on a
/// quad whose second edge points up), a sphere's longitude and colatitude. Other primitives
/// have none (validation keeps textures off them): (0, 0).
pub fn texture_coordinates(
    prim: &GpuPrimitive,
    hit: Hit,
    outward: Vec3,
    uvs: &[GpuTexCoords],
) -> Vec2 {
    match prim.kind {
        PRIM_TRIANGLE => {
            let Some(t) = uvs.get(prim.normals as usize) else {
                return Vec2::ZERO;
            };
            let b0 = 1.0 - hit.b1 - hit.b2;
            b0 * Vec2::new(t.uv[0], t.uv[1])
                + hit.b1 * Vec2::new(t.uv[2], t.uv[3])
                + hit.b2 * Vec2::new(t.uv[4], t.uv[5])
        }
        PRIM_QUAD => Vec2::new(hit.b1, 1.0 - hit.b2),
        PRIM_SPHERE => sphere_coordinates(outward),
        _ => Vec2::ZERO,
    }
}

/// A sphere's (u, v) at outward normal `n`: u the longitude from +x turning towards -z
/// (anticlockwise seen from above, y up) over 2π, v the angle from the +y pole over π.
pub fn sphere_coordinates(n: Vec3) -> Vec2 {
    let longitude = (-n.z).atan2(n.x);
    let u = longitude / (2.0 * PI);
    Vec2::new(u - u.floor(), n.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The linear value of an sRGB-encoded channel `c` in [0, 1] (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear RGB of a packed RGBA8 sRGB texel (red in the low byte).
pub fn decode_texel(texel: u32) -> Vec3 {
    let channel = |shift: u32| srgb_to_linear(((texel >> shift) & 0xff) as f32 / 255.0);
    Vec3::new(channel(0), channel(8), channel(16))
}

/// Coordinate `x` (in texture units, 1 = one copy of the texture) brought into the range the
/// wrap mode reads, so that texel indices stay small whatever the coordinate: [0, 1) for
/// repeat, [0, 2) for mirror (a copy and its mirror image), [0, 1] for clamp.
pub fn wrap_coordinate(x: f32, mode: u32) -> f32 {
    match mode {
        WRAP_CLAMP => x.clamp(0.0, 1.0),
        WRAP_MIRROR => x - 2.0 * (0.5 * x).floor(),
        _ => x - x.floor(),
    }
}

/// Texel index `i` (possibly one beyond either edge of `size` texels) as the wrap mode reads it.
pub fn wrap_index(i: i32, size: i32, mode: u32) -> u32 {
    let wrapped = match mode {
        WRAP_CLAMP => i.clamp(0, size - 1),
        WRAP_MIRROR => {
            let m = i.rem_euclid(2 * size);
            if m >= size { 2 * size - 1 - m } else { m }
        }
        _ => i.rem_euclid(size),
    };
    wrapped as u32
}

/// The linear RGB of `texture` at `uv`, filtered bilinearly between texel centres.
pub fn texture_lookup(texture: &GpuTexture, texels: &[u32], uv: Vec2) -> Vec3 {
    let (width, height) = (texture.width as i32, texture.height as i32);
    let x = wrap_coordinate(uv.x, texture.wrap & 0xff) * width as f32 - 0.5;
    let y = wrap_coordinate(uv.y, texture.wrap >> 8) * height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let columns = [x0 as i32, x0 as i32 + 1].map(|i| wrap_index(i, width, texture.wrap & 0xff));
    let rows = [y0 as i32, y0 as i32 + 1].map(|j| wrap_index(j, height, texture.wrap >> 8));
    let at = |c: u32, r: u32| {
        let index = texture.offset + r * texture.width + c;
        decode_texel(texels.get(index as usize).copied().unwrap_or(0))
    };
    let top = at(columns[0], rows[0]) * (1.0 - fx) + at(columns[1], rows[0]) * fx;
    let bottom = at(columns[0], rows[1]) * (1.0 - fx) + at(columns[1], rows[1]) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texture of `texels` (width `width`) at offset 0 with `wrap` on both axes.
    fn texture(width: u32, height: u32, wrap: u32) -> GpuTexture {
        GpuTexture {
            offset: 0,
            width,
            height,
            wrap: wrap | wrap << 8,
        }
    }

    fn gray(level: u8) -> u32 {
        let l = level as u32;
        l | l << 8 | l << 16 | 0xff << 24
    }

    #[test]
    fn srgb_decoding_meets_the_standard_at_its_ends_and_joint() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // The two pieces meet at 0.04045 to within the standard's rounding of its constants.
        let below = 0.04045 / 12.92;
        let above = ((0.04045f32 + 0.055) / 1.055).powf(2.4);
        assert!((below - above).abs() < 1e-7, "{below} {above}");
        // Mid-grey 188/255 is 0.5 linear to 1%.
        assert!((srgb_to_linear(188.0 / 255.0) - 0.5).abs() < 5e-3);
    }

    #[test]
    fn a_texel_centre_reads_that_texel_exactly() {
        let texels = [gray(0), gray(255), gray(188), gray(50)];
        let t = texture(2, 2, WRAP_CLAMP);
        for (k, &texel) in texels.iter().enumerate() {
            let uv = Vec2::new((k % 2) as f32 * 0.5 + 0.25, (k / 2) as f32 * 0.5 + 0.25);
            assert_eq!(texture_lookup(&t, &texels, uv), decode_texel(texel), "{uv}");
        }
    }

    #[test]
    fn halfway_between_texels_is_the_mean_of_their_linear_values() {
        let texels = [gray(0), gray(255)];
        let t = texture(2, 1, WRAP_CLAMP);
        let mid = texture_lookup(&t, &texels, Vec2::new(0.5, 0.5));
        assert!((mid - Vec3::splat(0.5)).abs().max_element() < 1e-6, "{mid}");
    }

    #[test]
    fn wrap_modes_read_the_texels_gltf_names() {
        // Repeat: the left edge blends with the right texel; clamp: it stays the edge's.
        let texels = [gray(255), gray(0)];
        let edge = Vec2::new(0.0, 0.5);
        let repeat = texture_lookup(&texture(2, 1, WRAP_REPEAT), &texels, edge);
        let clamp = texture_lookup(&texture(2, 1, WRAP_CLAMP), &texels, edge);
        let mirror = texture_lookup(&texture(2, 1, WRAP_MIRROR), &texels, edge);
        assert!((repeat.x - 0.5).abs() < 1e-6, "{repeat}");
        assert_eq!(clamp, Vec3::ONE);
        assert_eq!(mirror, Vec3::ONE);
        // Mirrored copies alternate: at u = 1.25 the mirror reads u = 0.75's texel's twin (0.25).
        let at =
            |u: f32, mode: u32| texture_lookup(&texture(2, 1, mode), &texels, Vec2::new(u, 0.5));
        assert_eq!(at(1.25, WRAP_MIRROR), at(0.75, WRAP_MIRROR));
        assert_eq!(at(1.25, WRAP_REPEAT), at(0.25, WRAP_REPEAT));
        assert_eq!(at(-0.75, WRAP_REPEAT), at(0.25, WRAP_REPEAT));
    }

    #[test]
    fn extreme_coordinates_stay_finite_and_in_range() {
        let texels = [gray(10), gray(20), gray(30), gray(40)];
        for mode in [WRAP_REPEAT, WRAP_CLAMP, WRAP_MIRROR] {
            for u in [
                -1e30,
                -3.5e9,
                -1.0,
                -1e-30,
                0.0,
                1e-30,
                1.0,
                7.3e7,
                1e30,
                f32::MAX,
            ] {
                let c = texture_lookup(&texture(2, 2, mode), &texels, Vec2::new(u, -u));
                let (lo, hi) = (decode_texel(gray(10)).x, decode_texel(gray(40)).x);
                assert!(
                    c.is_finite() && c.x >= lo - 1e-6 && c.x <= hi + 1e-6,
                    "{mode} {u}: {c}"
                );
            }
        }
    }

    #[test]
    fn sphere_coordinates_follow_longitude_and_colatitude() {
        let uv = |n: Vec3| sphere_coordinates(n.normalize());
        assert_eq!(uv(Vec3::X), Vec2::new(0.0, 0.5));
        assert!((uv(-Vec3::Z) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((uv(-Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert_eq!(uv(Vec3::Y).y, 0.0);
        assert!((uv(-Vec3::Y).y - 1.0).abs() < 1e-6);
    }
}
