//! Writes an [`Image`]: PNG (sRGB-encoded, clamped) or OpenEXR (linear floats), by extension.
//!
//! The target is checked before a render starts ([`OutputTarget::prepare`]), so a path that
//! cannot take the image costs no render time. The image is then written atomically
//! ([`OutputTarget::write`]): encoded in memory, written to a temporary file beside the target,
//! synced, and renamed over the target. A failed or killed write leaves the previous image
//! whole; when two renders write one path, the last rename wins and the file is never a mix.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::io::{Cursor, ErrorKind, Write};
use std::path::{Path, PathBuf};

use image::codecs::openexr::OpenExrEncoder;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::render::Image;

/// What a PNG shows for a pixel that is not a finite number: magenta stands out in any render
/// and, unlike black or white, is not what a dark or saturated pixel would look like.
pub const NON_FINITE_PNG: [u8; 3] = [255, 0, 255];

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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// sRGB 8-bit; non-finite pixels become [`NON_FINITE_PNG`].
    Png,
    /// Linear 32-bit floats; non-finite values are kept as they are.
    Exr,
}

/// A checked place to write the image: a new path or an existing regular file, with a known
/// format, in a directory where files can be created.
#[derive(Debug)]
pub struct OutputTarget {
    /// As the user gave it, for messages.
    path: PathBuf,
    /// The file actually replaced: `path`, or what it links to, so a symbolic link survives.
    file: PathBuf,
    format: ImageFormat,
}

impl OutputTarget {
    /// Checks everything that can be checked before rendering: the extension, that the target
    /// is a regular file or does not exist yet, and that its directory accepts a new file.
    /// Devices and FIFOs (`/dev/full`, a named pipe) are refused: they cannot be replaced
    /// atomically, and renaming over a device node would remove it.
    pub fn prepare(path: &Path) -> Result<OutputTarget> {
        let fail = |message: String| Error::Output {
            path: path.to_path_buf(),
            message,
        };
        let format = format_of(path).map_err(fail)?;
        let file = resolve_target(path).map_err(fail)?;
        check_directory(directory_of(&file)).map_err(fail)?;
        Ok(OutputTarget {
            path: path.to_path_buf(),
            file,
            format,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn format(&self) -> ImageFormat {
        self.format
    }

    /// Encodes `image` and replaces the target with it atomically; every failure is an error
    /// and leaves the target as it was.
    pub fn write(&self, image: &Image) -> Result<()> {
        let fail = |message: String| Error::Output {
            path: self.path.clone(),
            message,
        };
        let bytes = encode(image, self.format).map_err(fail)?;
        replace_atomically(&self.file, &bytes).map_err(fail)
    }
}

fn format_of(path: &Path) -> std::result::Result<ImageFormat, String> {
    let extension = path
        .extension()
        .and_then(OsStr::to_str)
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("png") => Ok(ImageFormat::Png),
        Some("exr") => Ok(ImageFormat::Exr),
        Some(other) => Err(format!(
            "unknown image format `.{other}` (use .png or .exr)"
        )),
        None => Err("no file extension to choose the format (use .png or .exr)".into()),
    }
}

/// The regular file to replace: `path` itself when it does not exist yet, else what it is or
/// links to, which must be a regular file.
fn resolve_target(path: &Path) -> std::result::Result<PathBuf, String> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => {
            std::fs::canonicalize(path).map_err(|e| format!("resolving the path: {e}"))
        }
        Ok(meta) => Err(format!(
            "not a regular file ({}); chambre only replaces regular files, atomically",
            if meta.is_dir() {
                "a directory"
            } else {
                "a device, FIFO or socket"
            }
        )),
        // A missing directory on the way is reported, with its name, by the directory check.
        Err(e) if matches!(e.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) => {
            Ok(path.to_path_buf())
        }
        Err(e) => Err(e.to_string()),
    }
}

fn directory_of(file: &Path) -> &Path {
    match file.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// The directory must exist and accept a new file: creating (and removing) the temporary file
/// the write will use is the one test that permissions, read-only mounts and quotas all answer.
fn check_directory(dir: &Path) -> std::result::Result<(), String> {
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => return Err(format!("{} is not a directory", dir.display())),
        Err(e) if e.kind() == ErrorKind::NotFound => {
            return Err(format!("directory {} does not exist", dir.display()));
        }
        Err(e) => return Err(format!("directory {}: {e}", dir.display())),
    }
    TempFile::create(dir)
        .map(drop)
        .map_err(|e| format!("cannot create a file in {}: {e}", dir.display()))
}

fn encode(image: &Image, format: ImageFormat) -> std::result::Result<Vec<u8>, String> {
    let (w, h) = (image.width, image.height);
    let mut bytes = Vec::new();
    let encoded = match format {
        ImageFormat::Png => PngEncoder::new(&mut bytes).write_image(
            &png_pixels(image),
            w,
            h,
            ExtendedColorType::Rgb8,
        ),
        ImageFormat::Exr => OpenExrEncoder::new(Cursor::new(&mut bytes)).write_image(
            bytemuck::cast_slice(&image.pixels),
            w,
            h,
            ExtendedColorType::Rgb32F,
        ),
    };
    encoded.map_err(|e| format!("encoding: {e}"))?;
    Ok(bytes)
}

/// sRGB bytes of every pixel, a row per task: on a 16384^2 image the conversion, not the
/// compression, is what keeps an interrupted render waiting.
fn png_pixels(image: &Image) -> Vec<u8> {
    let width = image.width as usize;
    let mut bytes = vec![0u8; image.pixels.len() * 3];
    bytes
        .par_chunks_mut(3 * width)
        .zip(image.pixels.par_chunks(width))
        .for_each(|(out, row)| {
            for (rgb, p) in out.chunks_exact_mut(3).zip(row) {
                let encoded = if p.is_finite() {
                    [srgb_encode(p.x), srgb_encode(p.y), srgb_encode(p.z)]
                } else {
                    NON_FINITE_PNG
                };
                rgb.copy_from_slice(&encoded);
            }
        });
    bytes
}

/// Writes `bytes` to a temporary file beside `file`, syncs it, renames it over `file`, and
/// syncs the directory so the rename itself survives a crash.
fn replace_atomically(file: &Path, bytes: &[u8]) -> std::result::Result<(), String> {
    let dir = directory_of(file);
    let mut temp = TempFile::create(dir)
        .map_err(|e| format!("creating a temporary file in {}: {e}", dir.display()))?;
    temp.file
        .write_all(bytes)
        .and_then(|()| temp.file.sync_all())
        .map_err(|e| format!("writing {}: {e}", temp.path.display()))?;
    std::fs::rename(&temp.path, file)
        .map_err(|e| format!("renaming {} into place: {e}", temp.path.display()))?;
    temp.renamed = true;
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(|e| format!("written, but syncing directory {}: {e}", dir.display()))
}

/// A new, hidden file in the target's directory, removed when dropped unless it was renamed
/// into place: no error path leaves a stray temporary file.
struct TempFile {
    path: PathBuf,
    file: File,
    renamed: bool,
}

impl TempFile {
    fn create(dir: &Path) -> std::io::Result<TempFile> {
        let pid = std::process::id();
        // A killed run can leave a file with our pid; `create_new` never opens someone else's.
        for attempt in 0..64 {
            let path = dir.join(format!(".chambre-{pid}-{attempt}.tmp"));
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => {
                    return Ok(TempFile {
                        path,
                        file,
                        renamed: false,
                    });
                }
                Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(std::io::Error::new(
            ErrorKind::AlreadyExists,
            "64 temporary file names are taken",
        ))
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.renamed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}
