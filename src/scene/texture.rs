//! Image textures as scenes give them: a PNG or JPEG file (an OBJ material's `map_Kd`, a scene
//! material's `diffuse_texture`) or an image inside a glTF file, decoded to sRGB-encoded RGBA8
//! texels with the wrap mode of each axis. Lookups are the kernels' business
//! (`integrator::texture`, `wgsl/texture.wgsl`).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::layout::{WRAP_CLAMP, WRAP_MIRROR, WRAP_REPEAT};
use crate::named::named_enum;

/// Largest side of a texture (texels): the image reader's and GPU's common ground, and a bound
/// on memory (4 bytes a texel).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

named_enum! {
    /// How a texture continues beyond [0, 1] (glTF's sampler modes).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Wrap {
        /// The texture repeats (glTF's `REPEAT`, the default).
        #[default]
        Repeat = "repeat",
        /// The edge texels continue (`CLAMP_TO_EDGE`).
        Clamp = "clamp",
        /// The texture repeats, every other copy mirrored (`MIRRORED_REPEAT`).
        Mirror = "mirror",
    }
}

impl Wrap {
    /// Its `layout::WRAP_*` code.
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => WRAP_REPEAT,
            Wrap::Clamp => WRAP_CLAMP,
            Wrap::Mirror => WRAP_MIRROR,
        }
    }
}

/// A decoded texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (a file, or a glTF file's image), for messages and exports.
    pub source: PathBuf,
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// RGBA8 texels, sRGB-encoded, red in the low byte, rows from the image's top.
    pub texels: Vec<u32>,
    /// The wrap mode along u and along v.
    pub wrap: [Wrap; 2],
}

impl Texture {
    /// The texture in file `path` (PNG or JPEG), repeating along both axes. The error is a
    /// sentence without the path.
    pub fn read(path: &Path) -> Result<Texture, String> {
        let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
        Texture::decode(&bytes, path)
    }

    /// The texture encoded in `bytes` (PNG or JPEG), which came from `source`.
    pub fn decode(bytes: &[u8], source: &Path) -> Result<Texture, String> {
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let (width, height) = reader
            .into_dimensions()
            .map_err(|e| format!("not a readable PNG or JPEG image: {e}"))?;
        if width == 0 || height == 0 || width.max(height) > MAX_TEXTURE_SIDE {
            return Err(format!(
                "a texture of {width} x {height} texels: each side must be 1 to {MAX_TEXTURE_SIDE}"
            ));
        }
        if bytes.starts_with(&[0xFF, 0xD8]) && !jpeg_ends_its_image(bytes) {
            return Err(
                "a JPEG image cut short: no end-of-image marker after its last scan (the \
                 decoder would fill the missing rows with a flat colour)"
                    .into(),
            );
        }
        let image = image::load_from_memory(bytes)
            .map_err(|e| format!("not a readable PNG or JPEG image: {e}"))?
            .into_rgba8();
        let texels = image.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
        Ok(Texture {
            source: source.to_path_buf(),
            width,
            height,
            texels,
            wrap: [Wrap::Repeat; 2],
        })
    }
}

/// Whether a JPEG's last scan (its last start-of-scan marker, `FF DA`) is followed by an
/// end-of-image marker (`FF D9`). Neither can occur inside a scan's coded data, where an `FF`
/// byte is always followed by `00` or a restart marker; an EXIF thumbnail's own markers come
/// before the image's scans, and bytes a camera appends after the end are allowed.
fn jpeg_ends_its_image(bytes: &[u8]) -> bool {
    let last = |marker: u8| bytes.windows(2).rposition(|w| w == [0xFF, marker]);
    matches!((last(0xDA), last(0xD9)), (Some(scan), Some(end)) if end > scan)
}

/// Textures read once each, whatever number of materials name them.
#[derive(Debug, Default)]
pub struct TextureCache {
    read: Vec<Arc<Texture>>,
}

impl TextureCache {
    /// The texture in file `path` with `wrap`, read on first use.
    pub fn get(&mut self, path: &Path, wrap: [Wrap; 2]) -> Result<Arc<Texture>, String> {
        if let Some(t) = self
            .read
            .iter()
            .find(|t| t.source == path && t.wrap == wrap)
        {
            return Ok(t.clone());
        }
        let texture = Arc::new(Texture {
            wrap,
            ..Texture::read(path)?
        });
        self.read.push(texture.clone());
        Ok(texture)
    }
}

/// The file `name` names in folder `folder`: the name as it is, or else the one file of the
/// folder whose name differs from it only in case, as a file written on a system that ignores
/// case expects (the Sponza's `.mtl` names `KAMEN.JPG` for `kamen.JPG`). The name as given
/// when neither exists.
pub fn resolve_file(folder: &Path, name: &str) -> PathBuf {
    let path = folder.join(name);
    if path.exists() {
        return path;
    }
    let (Some(parent), Some(file)) = (path.parent(), path.file_name()) else {
        return path;
    };
    let wanted = file.to_string_lossy().to_lowercase();
    let found = std::fs::read_dir(parent).ok().and_then(|entries| {
        entries
            .filter_map(|e| e.ok())
            .find(|e| e.file_name().to_string_lossy().to_lowercase() == wanted)
    });
    found.map_or(path, |e| e.path())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_png_decodes_to_its_texels_top_row_first() {
        let mut png = Vec::new();
        let image = image::RgbaImage::from_fn(2, 2, |x, y| {
            image::Rgba([x as u8 * 200, y as u8 * 100, 7, 255])
        });
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = Texture::decode(&png, Path::new("t.png")).unwrap();
        assert_eq!((t.width, t.height), (2, 2));
        assert_eq!(t.texels[1], u32::from_le_bytes([200, 0, 7, 255]));
        assert_eq!(t.texels[2], u32::from_le_bytes([0, 100, 7, 255]));
    }

    #[test]
    fn bytes_that_are_no_image_are_refused_with_a_reason() {
        let e = Texture::decode(b"not an image", Path::new("x.png")).unwrap_err();
        assert!(e.contains("image"), "{e}");
    }

    /// A JPEG cut anywhere inside its scan is refused; the whole file, and the file with
    /// bytes appended after its end, decode.
    #[test]
    fn a_jpeg_cut_short_is_refused() {
        let image =
            image::RgbImage::from_fn(32, 32, |x, y| image::Rgb([x as u8 * 8, y as u8 * 8, 90]));
        let mut jpeg = Vec::new();
        image
            .write_to(
                &mut std::io::Cursor::new(&mut jpeg),
                image::ImageFormat::Jpeg,
            )
            .unwrap();
        assert!(Texture::decode(&jpeg, Path::new("t.jpg")).is_ok());
        let mut trailed = jpeg.clone();
        trailed.extend_from_slice(b"a camera's trailer");
        assert!(Texture::decode(&trailed, Path::new("t.jpg")).is_ok());
        // Cuts inside the scan, which the decoder alone would accept.
        let scan = jpeg.windows(2).rposition(|w| w == [0xFF, 0xDA]).unwrap();
        for cut in [scan + 20, (scan + jpeg.len()) / 2, jpeg.len() - 2] {
            let e = Texture::decode(&jpeg[..cut], Path::new("t.jpg")).unwrap_err();
            assert!(e.contains("cut short"), "{cut}: {e}");
        }
    }

    #[test]
    fn a_name_in_the_wrong_case_finds_its_file() {
        let folder = std::env::temp_dir().join(format!("chambre-case-{}", std::process::id()));
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("kamen.JPG"), b"x").unwrap();
        assert_eq!(resolve_file(&folder, "KAMEN.JPG"), folder.join("kamen.JPG"));
        assert_eq!(
            resolve_file(&folder, "absent.png"),
            folder.join("absent.png")
        );
        std::fs::remove_dir_all(&folder).unwrap();
    }
}
