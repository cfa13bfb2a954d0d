//! Writes an [`Image`] by extension: PNG (tone-mapped, sRGB-encoded, 8 bits), OpenEXR or PFM
//! (linear floats).
//!
//! The target is checked before a render starts ([`OutputTarget::prepare`]), so a path that
//! cannot take the image costs no render time. The image is then written atomically
//! ([`OutputTarget::write`]): encoded in memory, written to a temporary file beside the target,
//! synced, and renamed over the target. A failed or killed write leaves the previous image
//! whole; when two renders write one path, the last rename wins and the file is never a mix.
//!
//! A rename replaces a file whatever its mode, so the check before the render also refuses an
//! existing file that is write-protected, as `cp` would, unless the command is forced
//! ([`Protected::Replace`], `--force`).

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::io::{Cursor, ErrorKind, Write};
use std::path::{Path, PathBuf};

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::named::named_enum;
use crate::render::{Image, RenderOutput};

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

/// An output file's format, from its extension (`.png`, `.exr`, `.pfm`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// sRGB 8-bit after exposure and tone mapping; non-finite pixels become [`NON_FINITE_PNG`].
    Png,
    /// Linear 32-bit floats; non-finite values are kept as they are.
    Exr,
    /// Portable Float Map: linear 32-bit floats, little-endian, bottom row first (pbrt and
    /// Mitsuba read and write it); non-finite values are kept.
    Pfm,
}

impl ImageFormat {
    /// Whether the format stores linear radiance as floats (exposure and tone mapping do not
    /// apply to it).
    pub fn is_linear(self) -> bool {
        !matches!(self, ImageFormat::Png)
    }
}

named_enum! {
    /// How linear radiance becomes a displayable value in [0, 1] for an 8-bit image, after the
    /// exposure scale `2^EV`.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum ToneMap {
        /// Values above 1 clip to white.
        #[default]
        Clamp = "clamp",
        /// x / (1 + x) per channel (Reinhard et al. 2002, the simple global operator).
        Reinhard = "reinhard",
        /// Narkowicz's fit of the ACES filmic curve:
        /// (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14).
        Aces = "aces",
        /// AgX (Sobotka; Blender's default view since 4.0), as three.js has it: in Rec.2020, an
        /// inset matrix, log2 encoding over [-12.47, 4.03] stops, a sigmoid, the outset matrix;
        /// bright saturated colours go towards white rather than clip to a hue.
        Agx = "agx",
    }
}

/// AgX's matrices as three.js has them (after Filament, after Blender; working in Rec.2020),
/// column-major: linear sRGB to Rec.2020, the inset, the outset, and Rec.2020 back to sRGB.
/// Each maps grey to grey (its rows sum to 1).
const SRGB_TO_REC2020: [f32; 9] = [
    0.6274, 0.0691, 0.0164, 0.3293, 0.9195, 0.0880, 0.0433, 0.0113, 0.8956,
];
const AGX_INSET: [f32; 9] = [
    0.856_627_15,
    0.137_318_97,
    0.111_898_21,
    0.095_121_24,
    0.761_242,
    0.076_799_42,
    0.048_251_6,
    0.101_439_04,
    0.811_302_37,
];
const AGX_OUTSET: [f32; 9] = [
    1.127_100_6,
    -0.141_329_76,
    -0.141_329_76,
    -0.110_606_64,
    1.157_823_7,
    -0.110_606_64,
    -0.016_493_94,
    -0.016_493_94,
    1.251_936_4,
];
const REC2020_TO_SRGB: [f32; 9] = [
    1.6605, -0.1246, -0.0182, -0.5876, 1.1329, -0.1006, -0.0728, -0.0083, 1.1187,
];
/// The stops AgX's log encoding spans, relative to 0.18.
const AGX_MIN_EV: f32 = -12.473_93;
const AGX_MAX_EV: f32 = 4.026_069;

/// AgX of a linear Rec.709 colour: display-linear values in [0, 1].
fn agx(rgb: glam::Vec3) -> glam::Vec3 {
    let matrix = glam::Mat3::from_cols_array;
    let inset = matrix(&AGX_INSET) * matrix(&SRGB_TO_REC2020) * rgb;
    let inset = inset.max(glam::Vec3::splat(1e-10));
    let encoded = inset.to_array().map(|v| {
        let x = (v.log2().clamp(AGX_MIN_EV, AGX_MAX_EV) - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV);
        // The sigmoid, as the minimal form's 6th-order polynomial fit.
        let (x2, x4) = (x * x, x * x * x * x);
        15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
            - 0.00232
    });
    let outset = matrix(&AGX_OUTSET) * glam::Vec3::from(encoded);
    // The curve's output is display-encoded for a 2.2 power display: back to linear.
    let linear = outset.max(glam::Vec3::ZERO).powf(2.2);
    (matrix(&REC2020_TO_SRGB) * linear).clamp(glam::Vec3::ZERO, glam::Vec3::ONE)
}

impl ToneMap {
    /// The display value in [0, 1] of linear value `x` (after exposure), for the maps that
    /// work per channel; AgX mixes channels (`apply_rgb`) and takes a grey here.
    pub fn apply(self, x: f32) -> f32 {
        let x = x.max(0.0);
        match self {
            ToneMap::Clamp => x.min(1.0),
            ToneMap::Reinhard => x / (1.0 + x),
            ToneMap::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
            ToneMap::Agx => agx(glam::Vec3::splat(x)).x,
        }
    }

    /// The display-linear colour in [0, 1]^3 of linear colour `rgb` (after exposure).
    pub fn apply_rgb(self, rgb: glam::Vec3) -> glam::Vec3 {
        match self {
            ToneMap::Agx => agx(rgb),
            _ => glam::Vec3::new(self.apply(rgb.x), self.apply(rgb.y), self.apply(rgb.z)),
        }
    }
}

/// What turns linear radiance into an 8-bit image: the exposure in stops and the tone map.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Display {
    /// Exposure in stops (EV): linear values are scaled by `2^exposure_ev` first.
    pub exposure_ev: f32,
    /// Applied to each scaled channel before sRGB encoding.
    pub tone_map: ToneMap,
}

/// What becomes of an existing output file that is write-protected: one with no write
/// permission bit at all (`chmod a-w`), or that the user running chambre may not write. Root
/// may write any file, so the mode bits alone decide for root, as `rm` asks before removing a
/// write-protected file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Protected {
    /// Refuse before any work is done, naming the file and `--force`.
    #[default]
    Refuse,
    /// Replace it like any other (`--force`).
    Replace,
}

impl Protected {
    /// [`Protected::Replace`] when a command's `--force` is given.
    pub fn replaced_if(force: bool) -> Protected {
        match force {
            true => Protected::Replace,
            false => Protected::Refuse,
        }
    }
}

/// Whether paths `a` and `b` name one file, existing or not: their directories resolved (links,
/// `..`), their names compared. Two outputs of one command at one path would overwrite each
/// other, an output at an input's path its input.
pub fn same_path(a: &Path, b: &Path) -> bool {
    let resolve = |path: &Path| {
        let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let file = std::fs::canonicalize(&absolute).ok();
        let in_directory = || {
            let (dir, name) = (absolute.parent()?, absolute.file_name()?);
            Some(std::fs::canonicalize(dir).ok()?.join(name))
        };
        file.or_else(in_directory).unwrap_or(absolute.clone())
    };
    resolve(a) == resolve(b)
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
    display: Display,
}

impl OutputTarget {
    /// Checks everything that can be checked before rendering: the extension, that the target
    /// is a regular file or does not exist yet, and that its directory accepts a new file.
    /// Devices and FIFOs (`/dev/full`, a named pipe) are refused: they cannot be replaced
    /// atomically, and renaming over a device node would remove it. So is a write-protected
    /// file ([`Protected`]; [`OutputTarget::prepare_with`] can replace it).
    pub fn prepare(path: &Path) -> Result<OutputTarget> {
        Self::prepare_with(path, Protected::Refuse)
    }

    /// [`OutputTarget::prepare`], with a write-protected file refused or replaced as
    /// `protected` says.
    pub fn prepare_with(path: &Path, protected: Protected) -> Result<OutputTarget> {
        let fail = |message: String| Error::Output {
            path: path.to_path_buf(),
            message,
        };
        let format = format_of(path).map_err(fail)?;
        let file = resolve_target(path).map_err(fail)?;
        check_protection(&file, protected).map_err(fail)?;
        check_directory(directory_of(&file)).map_err(fail)?;
        Ok(OutputTarget {
            path: path.to_path_buf(),
            file,
            format,
            display: Display::default(),
        })
    }

    /// The path as the user gave it (a symbolic link is not resolved).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The format the extension names.
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
        let bytes = encode(image, self.format, self.display).map_err(fail)?;
        replace_atomically(&self.file, &bytes).map_err(fail)
    }

    /// Like [`OutputTarget::write`], with `channels` (name, one value a pixel) beside the
    /// image's R, G and B in the same file; EXR only (an error for another format).
    pub fn write_with_channels(
        &self,
        image: &Image,
        channels: &[(String, Vec<f32>)],
    ) -> Result<()> {
        let fail = |message: String| Error::Output {
            path: self.path.clone(),
            message,
        };
        if channels.is_empty() {
            return self.write(image);
        }
        if self.format != ImageFormat::Exr {
            return Err(fail("extra channels (AOVs) need an .exr image".into()));
        }
        let bytes = exr_bytes(image, channels).map_err(fail)?;
        replace_atomically(&self.file, &bytes).map_err(fail)
    }

    /// How an 8-bit format shows the linear image (ignored by the float formats).
    pub fn with_display(mut self, display: Display) -> Self {
        self.display = display;
        self
    }

    /// Checks, before a render, that `path` (e.g. a JSON sidecar) can be written as the image
    /// can: a regular file that is not write-protected or a new name, in a directory that
    /// accepts a new file.
    pub fn prepare_beside(path: &Path) -> Result<()> {
        Self::prepare_beside_with(path, Protected::Refuse)
    }

    /// [`OutputTarget::prepare_beside`], with a write-protected file refused or replaced as
    /// `protected` says.
    pub fn prepare_beside_with(path: &Path, protected: Protected) -> Result<()> {
        let fail = |message: String| Error::Output {
            path: path.to_path_buf(),
            message,
        };
        let file = resolve_target(path).map_err(fail)?;
        check_protection(&file, protected).map_err(fail)?;
        check_directory(directory_of(&file)).map_err(fail)
    }

    /// Writes `bytes` (e.g. a JSON sidecar) to `path` atomically, like the image.
    pub fn write_beside(path: &Path, bytes: &[u8]) -> Result<()> {
        let file = resolve_target(path).map_err(|message| Error::Output {
            path: path.to_path_buf(),
            message,
        })?;
        replace_atomically(&file, bytes).map_err(|message| Error::Output {
            path: path.to_path_buf(),
            message,
        })
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
        Some("pfm") => Ok(ImageFormat::Pfm),
        Some(other) => Err(format!(
            "unknown image format `.{other}` (use .png, .exr or .pfm)"
        )),
        None => Err("no file extension to choose the format (use .png, .exr or .pfm)".into()),
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

/// Refuses an existing `file` that is write-protected, unless `protected` lets it be replaced.
fn check_protection(file: &Path, protected: Protected) -> std::result::Result<(), String> {
    if protected == Protected::Replace {
        return Ok(());
    }
    let Ok(meta) = std::fs::metadata(file) else {
        return Ok(());
    };
    if meta.permissions().readonly() || !writable_by_this_user(file) {
        return Err(format!(
            "the file is write-protected{}; it is replaced only with --force",
            mode_text(&meta)
        ));
    }
    Ok(())
}

/// Whether the user running chambre may write `file`, as the system answers (for root, always,
/// which is why the mode bits are read too).
#[cfg(unix)]
fn writable_by_this_user(file: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(name) = std::ffi::CString::new(file.as_os_str().as_bytes()) else {
        return true;
    };
    // SAFETY: `name` is a NUL-terminated path that outlives the call.
    unsafe { libc::faccessat(libc::AT_FDCWD, name.as_ptr(), libc::W_OK, libc::AT_EACCESS) == 0 }
}

/// Elsewhere the read-only attribute (`Permissions::readonly`) is the whole answer.
#[cfg(not(unix))]
fn writable_by_this_user(_file: &Path) -> bool {
    true
}

/// ` (mode -r--r--r--)`, as `ls -l` shows it, where the system has modes.
fn mode_text(meta: &std::fs::Metadata) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = meta.permissions().mode();
        let bits: String = (0..9)
            .map(|i| match (mode >> (8 - i)) & 1 {
                0 => '-',
                _ => ['r', 'w', 'x'][i % 3],
            })
            .collect();
        format!(" (mode -{bits})")
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        " (read-only)".to_string()
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

fn encode(
    image: &Image,
    format: ImageFormat,
    display: Display,
) -> std::result::Result<Vec<u8>, String> {
    let (w, h) = (image.width, image.height);
    let mut bytes = Vec::new();
    let encoded = match format {
        ImageFormat::Png => PngEncoder::new(&mut bytes).write_image(
            &png_pixels(image, display),
            w,
            h,
            ExtendedColorType::Rgb8,
        ),
        ImageFormat::Pfm => return Ok(pfm_bytes(image)),
        ImageFormat::Exr => return exr_bytes(image, &[]),
    };
    encoded.map_err(|e| format!("encoding: {e}"))?;
    Ok(bytes)
}

named_enum! {
    /// An arbitrary output variable an EXR can carry beside the image (`chambre render --aov`).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Aov {
        /// `depth.Z`: distance along the camera ray to the first hit (0 where nothing is hit).
        Depth = "depth",
        /// `normal.X`, `.Y`, `.Z`: the first hit's shading normal, world space, facing the camera.
        Normal = "normal",
        /// `albedo.R`, `.G`, `.B`: the first hit's diffuse plus mirror reflectance.
        Albedo = "albedo",
        /// `samples.Y`: the samples the pixel received (adaptive sampling, a stopped render).
        Samples = "samples",
    }
}

impl Aov {
    /// Whether the render must sum first hits for it (`FlatScene::aovs`).
    pub fn needs_first_hits(self) -> bool {
        self != Aov::Samples
    }
}

/// The named channels of `which` from a render's output, in that order; an error if one needs
/// first hits the render did not sum (`FlatScene::aovs` unset).
pub fn aov_channels(
    output: &RenderOutput,
    which: &[Aov],
) -> std::result::Result<Vec<(String, Vec<f32>)>, String> {
    let mut channels = Vec::new();
    let vector = |name: &str, values: &[glam::Vec3], components: [&str; 3]| {
        components
            .iter()
            .enumerate()
            .map(|(c, suffix)| {
                let values = values.iter().map(|v| v[c]).collect();
                (format!("{name}.{suffix}"), values)
            })
            .collect::<Vec<_>>()
    };
    for aov in which {
        match (aov, &output.aovs) {
            (Aov::Samples, _) => channels.push((
                "samples.Y".to_string(),
                output.sample_counts.iter().map(|&n| n as f32).collect(),
            )),
            (Aov::Depth, Some(aovs)) => channels.push(("depth.Z".to_string(), aovs.depth.clone())),
            (Aov::Normal, Some(aovs)) => channels.extend(vector("normal", &aovs.normal, XYZ)),
            (Aov::Albedo, Some(aovs)) => channels.extend(vector("albedo", &aovs.albedo, RGB)),
            (aov, None) => {
                return Err(format!(
                    "the render summed no first hits for the {aov:?} AOV (set FlatScene::aovs)"
                ));
            }
        }
    }
    Ok(channels)
}

const XYZ: [&str; 3] = ["X", "Y", "Z"];
const RGB: [&str; 3] = ["R", "G", "B"];

/// One channel of an EXR: a component of the image's pixels, or a layer of its own.
#[derive(Clone, Copy)]
enum Samples<'a> {
    Component(&'a [glam::Vec3], usize),
    Layer(&'a [f32]),
}

/// An EXR of `image`'s R, G, B and `channels` (name, a value a pixel), 32-bit floats in 64x64
/// tiles compressed by RLE (the exr crate's default). The tiles are filled and compressed on
/// all cores and written in order, so the same image is the same bytes; the exr crate's own
/// writer fills them on one thread, which was two thirds of writing a 16384^2 image on two
/// cores (`docs/robustness.md`).
fn exr_bytes(
    image: &Image,
    channels: &[(String, Vec<f32>)],
) -> std::result::Result<Vec<u8>, String> {
    use exr::block::writer::ChunksWriter;
    use exr::block::{BlockIndex, UncompressedBlock};
    use exr::meta::header::Header;
    use exr::prelude::{ChannelDescription, LineOrder, SampleType, SmallVec, Text};
    let (width, height) = (image.width as usize, image.height as usize);
    let mut named: Vec<(&str, Samples)> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| (*name, Samples::Component(&image.pixels, c)))
        .collect();
    for (name, values) in channels {
        if values.len() != width * height {
            return Err(format!("channel {name} has {} values", values.len()));
        }
        named.push((name, Samples::Layer(values)));
    }
    // EXR lists channels sorted by name, and a tile's lines hold them in that order.
    named.sort_by(|a, b| a.0.cmp(b.0));
    let descriptions: SmallVec<[ChannelDescription; 5]> = named
        .iter()
        .map(|(name, _)| ChannelDescription::named(*name, SampleType::F32))
        .collect();
    let mut header = Header::new(Text::from("image"), (width, height), descriptions);
    header.own_attributes.layer_name = None;
    header.line_order = LineOrder::Increasing;
    let tile_bytes = |index: &BlockIndex| {
        let (x0, y0) = (index.pixel_position.x(), index.pixel_position.y());
        let (w, h) = (index.pixel_size.width(), index.pixel_size.height());
        let mut data = Vec::with_capacity(w * h * named.len() * 4);
        for y in y0..y0 + h {
            let row = y * width + x0..y * width + x0 + w;
            for (_, samples) in &named {
                match *samples {
                    Samples::Component(pixels, c) => {
                        for p in &pixels[row.clone()] {
                            data.extend_from_slice(&p[c].to_ne_bytes());
                        }
                    }
                    Samples::Layer(values) => {
                        for v in &values[row.clone()] {
                            data.extend_from_slice(&v.to_ne_bytes());
                        }
                    }
                }
            }
        }
        data
    };
    let mut bytes = Vec::new();
    let headers: SmallVec<[Header; 3]> = SmallVec::from_elem(header, 1);
    exr::block::write(Cursor::new(&mut bytes), headers, true, |meta, writer| {
        let order: Vec<(usize, BlockIndex)> =
            exr::block::enumerate_ordered_header_block_indices(&meta.headers).collect();
        // A few tiles a thread at a time: the compressed ones wait in memory for their turn.
        for part in order.chunks(8 * rayon::current_num_threads()) {
            let chunks: Vec<_> = part
                .par_iter()
                .map(|(_, index)| {
                    let block = UncompressedBlock {
                        index: *index,
                        data: tile_bytes(index),
                    };
                    block.compress_to_chunk(&meta.headers)
                })
                .collect();
            for ((i, _), chunk) in part.iter().zip(chunks) {
                writer.write_chunk(*i, chunk?)?;
            }
        }
        Ok(())
    })
    .map_err(|e| format!("encoding: {e}"))?;
    Ok(bytes)
}

/// A Portable Float Map: "PF", the size, a negative scale (little-endian), then RGB floats
/// with the bottom row first.
fn pfm_bytes(image: &Image) -> Vec<u8> {
    let width = image.width as usize;
    let mut bytes = format!("PF\n{} {}\n-1.0\n", image.width, image.height).into_bytes();
    for row in image.pixels.chunks(width).rev() {
        for p in row {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    bytes
}

/// The image of a colour Portable Float Map (`pfm_bytes`'s format, either byte order): an
/// error saying what is wrong otherwise.
pub fn read_pfm(bytes: &[u8]) -> std::result::Result<Image, String> {
    // The header is three whitespace-separated fields after "PF", then one whitespace byte.
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while at < bytes.len() && bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        if start == at {
            return Err("a PFM header is `PF`, the width, the height and the scale".into());
        }
        fields.push(String::from_utf8_lossy(&bytes[start..at]).into_owned());
    }
    if fields[0] != "PF" {
        return Err(format!("`{}`: not a colour PFM (`PF`)", fields[0]));
    }
    let size = |field: &str| field.parse::<u32>().ok().filter(|&v| v > 0);
    let (Some(width), Some(height)) = (size(&fields[1]), size(&fields[2])) else {
        return Err(format!("a PFM of {} x {} pixels", fields[1], fields[2]));
    };
    let scale: f32 = fields[3]
        .parse()
        .map_err(|_| format!("`{}`: not a PFM scale", fields[3]))?;
    let data = &bytes[(at + 1).min(bytes.len())..];
    let expected = width as usize * height as usize * 12;
    if data.len() != expected {
        return Err(format!(
            "{width} x {height} pixels need {expected} bytes of floats, the file has {}",
            data.len()
        ));
    }
    let float = |b: &[u8]| {
        let b: [u8; 4] = b.try_into().expect("chunks of four");
        match scale < 0.0 {
            true => f32::from_le_bytes(b),
            false => f32::from_be_bytes(b),
        }
    };
    let rows: Vec<Vec<glam::Vec3>> = data
        .chunks_exact(12 * width as usize)
        .map(|row| {
            row.chunks_exact(12)
                .map(|p| glam::Vec3::new(float(&p[0..4]), float(&p[4..8]), float(&p[8..12])))
                .collect()
        })
        .collect();
    Ok(Image {
        width,
        height,
        // The file's rows run bottom to top.
        pixels: rows.into_iter().rev().flatten().collect(),
    })
}

/// sRGB bytes of every pixel after exposure and tone mapping, a row per task: on a 16384^2
/// image the conversion, not the compression, is what keeps an interrupted render waiting.
fn png_pixels(image: &Image, display: Display) -> Vec<u8> {
    let scale = display.exposure_ev.exp2();
    let show = |p: glam::Vec3| {
        display
            .tone_map
            .apply_rgb(p * scale)
            .to_array()
            .map(srgb_encode)
    };
    let width = image.width as usize;
    let mut bytes = vec![0u8; image.pixels.len() * 3];
    bytes
        .par_chunks_mut(3 * width)
        .zip(image.pixels.par_chunks(width))
        .for_each(|(out, row)| {
            for (rgb, p) in out.chunks_exact_mut(3).zip(row) {
                let encoded = if p.is_finite() {
                    show(*p)
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
pub(crate) fn replace_atomically(file: &Path, bytes: &[u8]) -> std::result::Result<(), String> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_maps_take_their_defining_values() {
        assert_eq!(ToneMap::Clamp.apply(2.0), 1.0);
        assert_eq!(ToneMap::Clamp.apply(0.25), 0.25);
        assert_eq!(ToneMap::Reinhard.apply(1.0), 0.5);
        assert_eq!(ToneMap::Reinhard.apply(3.0), 0.75);
        assert_eq!(ToneMap::Aces.apply(0.0), 0.0);
        // Narkowicz's fit saturates at 1 near x = 11 and is monotonic below.
        assert_eq!(ToneMap::Aces.apply(100.0), 1.0);
        let samples: Vec<f32> = (0..200)
            .map(|i| ToneMap::Aces.apply(i as f32 * 0.05))
            .collect();
        assert!(samples.windows(2).all(|w| w[1] >= w[0]));
        for map in [ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces] {
            assert_eq!(map.apply(-1.0), 0.0, "{map:?}");
        }
    }

    #[test]
    fn agx_maps_black_to_black_grey_to_grey_and_bright_colours_towards_white() {
        use glam::Vec3;
        let agx = |rgb: Vec3| ToneMap::Agx.apply_rgb(rgb);
        assert!(agx(Vec3::ZERO).max_element() < 1e-3, "{}", agx(Vec3::ZERO));
        // Greys stay grey (the matrices' rows sum to the same), rise monotonically, and reach
        // white only far above 1.
        let greys: Vec<Vec3> = (0..=60)
            .map(|i| agx(Vec3::splat(2f32.powf(i as f32 / 4.0 - 10.0))))
            .collect();
        for g in &greys {
            assert!((g.x - g.y).abs() < 2e-3 && (g.y - g.z).abs() < 2e-3, "{g}");
        }
        assert!(greys.windows(2).all(|w| w[1].x >= w[0].x));
        // Middle grey 0.18 shows near the middle of the display range (sRGB about 0.5).
        let middle = srgb_encode(agx(Vec3::splat(0.18)).x);
        assert!((100..=150).contains(&middle), "{middle}");
        assert!(agx(Vec3::splat(1.0)).x < 0.95 && agx(Vec3::splat(1e3)).x > 0.95);
        // A bright pure red desaturates towards white instead of clipping at pure red.
        let red = agx(Vec3::new(50.0, 0.0, 0.0));
        assert!(red.x > 0.9 && red.y > 0.2 && red.z > 0.2, "{red}");
        // Never out of [0, 1].
        for rgb in [
            Vec3::new(1e6, 0.0, 0.0),
            Vec3::new(0.0, 1e-8, 3.0),
            Vec3::splat(-1.0),
        ] {
            let out = agx(rgb);
            assert!(
                out.min_element() >= 0.0 && out.max_element() <= 1.0,
                "{out}"
            );
        }
    }

    #[test]
    fn a_pfm_reads_back_as_written_and_a_bad_one_says_why() {
        let image = Image {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| glam::Vec3::splat(i as f32 * 0.5 - 1.0))
                .collect(),
        };
        let read = read_pfm(&pfm_bytes(&image)).unwrap();
        assert_eq!((read.width, read.height), (3, 2));
        assert_eq!(read.pixels, image.pixels);
        let bytes = pfm_bytes(&image);
        for (bad, why) in [
            (&bytes[..bytes.len() - 1], "bytes of floats"),
            (&b"Pf\n1 1\n-1.0\n"[..], "not a colour PFM"),
            (&b"PF\n0 1\n-1.0\n"[..], "0 x 1 pixels"),
            (&b"PF\n1"[..], "a PFM header"),
        ] {
            let e = read_pfm(bad).unwrap_err();
            assert!(e.contains(why), "{e}");
        }
    }

    #[test]
    fn a_pfm_holds_the_floats_bottom_row_first() {
        let image = Image {
            width: 2,
            height: 2,
            pixels: vec![
                glam::Vec3::new(1.0, 2.0, 3.0),
                glam::Vec3::new(4.0, 5.0, 6.0),
                glam::Vec3::new(7.0, 8.0, f32::INFINITY),
                glam::Vec3::new(-0.5, 0.0, 1e-30),
            ],
        };
        let bytes = pfm_bytes(&image);
        let header = b"PF\n2 2\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        let floats: Vec<f32> = bytes[header.len()..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(
            floats,
            [
                7.0,
                8.0,
                f32::INFINITY,
                -0.5,
                0.0,
                1e-30,
                1.0,
                2.0,
                3.0,
                4.0,
                5.0,
                6.0
            ]
        );
    }

    #[test]
    fn one_stop_of_exposure_doubles_the_radiance_shown() {
        let image = Image {
            width: 3,
            height: 1,
            pixels: vec![
                glam::Vec3::splat(0.05),
                glam::Vec3::splat(0.2),
                glam::Vec3::splat(0.9),
            ],
        };
        let doubled = Image {
            pixels: image.pixels.iter().map(|p| *p * 2.0).collect(),
            ..image.clone()
        };
        for tone_map in [ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces] {
            let display = |exposure_ev| Display {
                exposure_ev,
                tone_map,
            };
            assert_eq!(
                png_pixels(&image, display(1.0)),
                png_pixels(&doubled, display(0.0)),
                "{tone_map:?}"
            );
        }
    }
}
