//! The one error type of the library. The binary (`src/bin/chambre/`) alone turns it into a
//! message and an exit code.

use std::path::PathBuf;

/// Where in a scene file a problem was found: file, 1-based line and column, and the field path.
#[derive(Debug, Clone, PartialEq)]
pub struct Location {
    /// The scene file.
    pub file: PathBuf,
    /// 1-based line, or 0 when the value came from a `--set` override.
    pub line: usize,
    /// 1-based column (in bytes); 0 when `line` is.
    pub column: usize,
    /// Dotted field path, e.g. `shapes[2].radius`; empty for syntax errors.
    pub field: String,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            write!(f, "{} (set on the command line)", self.file.display())?;
        } else {
            write!(f, "{}:{}:{}", self.file.display(), self.line, self.column)?;
        }
        if !self.field.is_empty() {
            write!(f, ": field `{}`", self.field)?;
        }
        Ok(())
    }
}

/// Everything that can go wrong in the library, from scene files to the GPU.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene file (or a file it names) is malformed or physically meaningless.
    #[error("{location}: {message}")]
    Scene {
        /// Where in the scene file.
        location: Location,
        /// What is wrong, as a sentence.
        message: String,
    },

    /// A file could not be read or written. The cause is part of the message and deliberately
    /// not a `source` (a field of that name would become one): `main` prints an error with its
    /// chain of sources, which would print the cause twice.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system reported.
        cause: std::io::Error,
    },

    /// A file named on the command line, outside a scene, is unusable: a mesh for
    /// `chambre bench`, a shard manifest for `chambre merge`.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },

    /// A command-line override `--set key=value` is malformed.
    #[error("--set {key}: {message}")]
    Override {
        /// The override's key (the whole argument when it has no `=`).
        key: String,
        /// What is wrong with it.
        message: String,
    },

    /// No GPU adapter could be found (or the one found cannot run chambre's kernels).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),

    /// The GPU reported an error (validation, out of memory, device lost, timeout).
    #[error("GPU error: {0}")]
    Gpu(String),

    /// An array larger than one storage binding may hold on this adapter, refused before any
    /// work: what, how large, the limit, and what the user can do about it.
    #[error(
        "GPU error: {what} takes {:.1} MiB, more than this adapter's largest storage binding \
         (max_storage_buffer_binding_size = {:.1} MiB); {advice}",
        mib(*.bytes),
        mib(*.limit)
    )]
    BindingLimit {
        /// The array.
        what: String,
        /// Its size.
        bytes: u64,
        /// The adapter's `max_storage_buffer_binding_size`.
        limit: u64,
        /// What to do: the command's own remedy ([`Error::with_advice`]).
        advice: String,
    },

    /// Writing an output file failed: an image, a report, a plot or a composed scene.
    #[error("{path}: cannot write: {message}")]
    Output {
        /// The file.
        path: PathBuf,
        /// What the encoder or the file system reported.
        message: String,
    },

    /// A scene an exporter cannot write as it is: each part it refused, placed in the scene
    /// file (`file:line:column: field `...``) with the reason, one a line.
    #[error(
        "cannot export to {format} (--approximate writes the nearest it has and lists what it \
         changed):\n  {}",
        .refusals.join("\n  ")
    )]
    Unsupported {
        /// The format refused, e.g. "Mitsuba 3".
        format: String,
        /// The refused parts, each placed and explained.
        refusals: Vec<String>,
    },

    /// The render was stopped (Ctrl-C) before all samples were taken.
    #[error("render interrupted after {done} of {total} samples per pixel")]
    Interrupted {
        /// Samples per pixel finished (of the least-sampled pixel).
        done: u32,
        /// Samples per pixel asked for.
        total: u32,
    },
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

impl Error {
    /// A [`Error::BindingLimit`] refusal with `advice` in place of the renderer's (the raster
    /// preview, whose arrays grow with its subdivision, has no `--backend`); other errors as
    /// they are.
    pub fn with_advice(self, advice: &str) -> Self {
        match self {
            Error::BindingLimit {
                what, bytes, limit, ..
            } => Error::BindingLimit {
                what,
                bytes,
                limit,
                advice: advice.to_string(),
            },
            other => other,
        }
    }

    /// An [`Error::Io`] about `path`.
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            cause,
        }
    }
}

/// The library's `Result`, with [`Error`] by default.
pub type Result<T, E = Error> = std::result::Result<T, E>;
