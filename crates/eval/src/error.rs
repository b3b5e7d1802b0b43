//! The error type of the evaluation crate.

use std::fmt;
use std::path::PathBuf;

/// Everything that can go wrong in `shadowmap-eval`.
///
/// Geometry variants come first (import, meshes, rasterizer, ray casting); the
/// evaluation variants follow. `#[non_exhaustive]`: match with a wildcard arm.
#[derive(Debug)]
#[non_exhaustive]
pub enum EvalError {
    /// A mesh file could not be read (missing, unreadable).
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A mesh file was read but could not be parsed.
    Malformed {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        message: String,
    },
    /// A mesh file whose extension names no supported format (`.obj`, `.gltf`, `.glb`).
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// A mesh file that holds no triangle.
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// A mesh file that was read but cannot be evaluated (no area, a size no `f32`
    /// camera can frame).
    UnusableMesh {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A mesh with a non-finite position or an index past the end of its positions.
    InvalidMesh {
        /// What is wrong.
        message: String,
    },
    /// Raster or image dimensions that are zero, too large, or a subpixel precision
    /// outside `1..=16`.
    InvalidRasterSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// Requested layers.
        layers: u32,
    },
    /// A camera or light the ray caster cannot use (non-finite, singular).
    InvalidView {
        /// What is wrong.
        message: String,
    },
    // --- evaluation variants ---
    /// A technique cannot be built for a configuration (the math crate's typed error,
    /// or a light kind the technique does not handle); the report shows it as
    /// "n/a (reason)".
    Technique {
        /// The technique's name.
        technique: &'static str,
        /// Why, in words.
        reason: String,
    },
    /// An option of the report that cannot be honoured (zero worker threads).
    InvalidOption {
        /// What is wrong.
        message: String,
    },
    /// A report file could not be written.
    Write {
        /// The file or directory.
        path: PathBuf,
        /// What the operating system (or the encoder) said.
        source: std::io::Error,
    },
}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            Self::Malformed { path, message } => {
                write!(f, "malformed mesh file {}: {message}", path.display())
            }
            Self::UnsupportedFormat { path } => write!(
                f,
                "unsupported mesh format {} (expected .obj, .gltf or .glb)",
                path.display()
            ),
            Self::NoTriangles { path } => write!(f, "{} holds no triangle", path.display()),
            Self::InvalidMesh { message } => write!(f, "invalid mesh: {message}"),
            Self::UnusableMesh { path, message } => {
                write!(f, "cannot evaluate mesh {}: {message}", path.display())
            }
            Self::InvalidRasterSize {
                width,
                height,
                layers,
            } => write!(
                f,
                "invalid raster size {width}x{height}x{layers} (or subpixel bits outside 1..=16)"
            ),
            Self::InvalidView { message } => write!(f, "invalid view: {message}"),
            Self::InvalidOption { message } => write!(f, "invalid option: {message}"),
            Self::Technique { technique, reason } => write!(f, "{technique}: {reason}"),
            Self::Write { path, source } => write!(f, "cannot write {}: {source}", path.display()),
        }
    }
}

impl std::error::Error for EvalError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } | Self::Write { source, .. } => Some(source),
            _ => None,
        }
    }
}
