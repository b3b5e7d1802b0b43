//! What a frame returns: the shaded image (and its PNG), the per-pixel shadow mask,
//! and the render targets they are read back from.

use std::path::Path;

use crate::{BackendError, GpuContext};

/// An RGBA8 image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// Writes the image as a PNG, creating the parent directories.
    ///
    /// # Errors
    /// [`BackendError::Io`] when the file cannot be written.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), BackendError> {
        let path = path.as_ref();
        let io = |e: &dyn std::fmt::Display| BackendError::Io(format!("{}: {e}", path.display()));
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| io(&e))?;
        }
        let file = std::fs::File::create(path).map_err(|e| io(&e))?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| io(&e))?;
        writer.write_image_data(&self.rgba).map_err(|e| io(&e))?;
        writer.finish().map_err(|e| io(&e))
    }
}

/// One pixel of a [`ShadowMask`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaskValue {
    /// No geometry.
    Background,
    /// Visible surface, lit.
    Lit,
    /// Visible surface, shadowed.
    Shadowed,
    /// Visible surface the technique's map does not cover.
    Uncovered,
}

impl MaskValue {
    /// `Some(lit)` for a covered surface, `None` for background or not covered (the
    /// convention of `shadowmap_eval`'s masks).
    #[must_use]
    pub const fn lit(self) -> Option<bool> {
        match self {
            Self::Lit => Some(true),
            Self::Shadowed => Some(false),
            Self::Background | Self::Uncovered => None,
        }
    }
}

/// The per-pixel shadow test of a frame, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShadowMask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` values.
    pub values: Vec<MaskValue>,
}

impl ShadowMask {
    /// The value at pixel `(x, y)`, `None` out of range.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Option<MaskValue> {
        (x < self.width && y < self.height).then(|| self.values[(y * self.width + x) as usize])
    }
}

/// What [`HeadlessRenderer::render`](super::HeadlessRenderer::render) returns.
#[derive(Clone, Debug)]
pub struct RenderedFrame {
    /// The shaded image.
    pub image: Image,
    /// The per-pixel shadow test.
    pub mask: ShadowMask,
}

pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub(super) const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Uint;

/// The scene pass's attachments: colour, mask, and the camera's depth.
pub(super) struct SceneTargets {
    pub(super) color: wgpu::Texture,
    pub(super) mask: wgpu::Texture,
    pub(super) depth: wgpu::Texture,
}

impl SceneTargets {
    pub(super) fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let target = |format, label| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            crate::context::texture_2d(device, label, (width, height), format, usage)
        };
        Self {
            color: target(COLOR_FORMAT, "shadowmap color"),
            mask: target(MASK_FORMAT, "shadowmap mask"),
            depth: target(crate::depth::DEPTH_FORMAT, "shadowmap camera depth"),
        }
    }

    /// Reads the image and the mask back (waits for the GPU).
    pub(super) fn read(&self, ctx: &GpuContext) -> Result<RenderedFrame, BackendError> {
        let (width, height) = (self.color.width(), self.color.height());
        let rgba = ctx.read_texture(&self.color, wgpu::TextureAspect::All)?;
        let values = ctx
            .read_texture(&self.mask, wgpu::TextureAspect::All)?
            .iter()
            .map(|v| match v {
                1 => MaskValue::Lit,
                2 => MaskValue::Shadowed,
                3 => MaskValue::Uncovered,
                _ => MaskValue::Background,
            })
            .collect();
        Ok(RenderedFrame {
            image: Image {
                width,
                height,
                rgba,
            },
            mask: ShadowMask {
                width,
                height,
                values,
            },
        })
    }
}
