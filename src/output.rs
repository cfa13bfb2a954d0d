//! Writes an [`Image`]: PNG (sRGB-encoded, clamped) or OpenEXR (linear floats), by extension.

use std::path::Path;

use crate::error::{Error, Result};
use crate::render::Image;

/// The sRGB transfer function (IEC 61966-2-1) of a linear value clamped to [0, 1].
pub fn srgb_encode(linear: f32) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let encoded = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

pub fn write_image(image: &Image, path: &Path) -> Result<()> {
    let fail = |message: String| Error::Output {
        path: path.to_path_buf(),
        message,
    };
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let (w, h) = (image.width, image.height);
    match extension.as_str() {
        "png" => {
            let bytes: Vec<u8> = image
                .pixels
                .iter()
                .flat_map(|p| [srgb_encode(p.x), srgb_encode(p.y), srgb_encode(p.z)])
                .collect();
            image::RgbImage::from_raw(w, h, bytes)
                .ok_or_else(|| fail("image size mismatch".into()))?
                .save(path)
                .map_err(|e| fail(e.to_string()))
        }
        "exr" => {
            let floats: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
            image::Rgb32FImage::from_raw(w, h, floats)
                .ok_or_else(|| fail("image size mismatch".into()))?
                .save(path)
                .map_err(|e| fail(e.to_string()))
        }
        other => Err(fail(format!(
            "unknown image format `.{other}` (use .png or .exr)"
        ))),
    }
}
