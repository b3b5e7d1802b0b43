//! The headless renderer: a scene from a camera, shadowed by one technique, into an
//! RGBA8 image (and a PNG) plus a per-pixel shadow mask for tests.
//!
//! Each frame renders the technique's depth pass (casters subdivided for the
//! paraboloid and RTW passes), the moments and blur passes for VSM, then the scene
//! pass, whose fragment shader is `render_scene.wgsl` with the technique's
//! `lookup_*.wgsl` and the filter's `filter_*.wgsl` composed in
//! ([`compose_scene_shader`]). The mask is the plain nearest-texel depth test
//! (`shadowmap_eval`'s `DepthMap::is_lit`), whatever the filter.
//!
//! The renderer is for tests, reports and examples: it uploads the geometry every
//! frame and waits for the GPU. An engine would keep the [`ShadowDepthPass`] and the
//! lookup shaders and drop the rest.
//!
//! ```no_run
//! use glam::Vec3;
//! use shadowmap_frustum::{Aabb, Camera, Projection};
//! use shadowmap_warp::{SceneBounds, UniformOptions, uniform_focused};
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowTechnique};
//!
//! let ctx = GpuContext::new_headless()?;
//! let ground = [[Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 0.0, -10.0), Vec3::new(0.0, 0.0, 10.0)]];
//! let camera = Camera::look_at(Vec3::new(0.0, 5.0, 15.0), Vec3::ZERO, Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 50.0)).unwrap();
//! let scene = SceneBounds::whole(Aabb::new(Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 1.0, 10.0)));
//! let light = uniform_focused(&camera, Vec3::new(0.3, -1.0, 0.2), &scene, &UniformOptions::default()).unwrap();
//! let mut renderer = HeadlessRenderer::new();
//! let frame = renderer.render(&ctx, &ground, &camera, &ShadowTechnique::Matrix(&light), &RenderOptions::default())?;
//! frame.image.save_png("shadow.png")?;
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use std::collections::HashMap;
use std::num::NonZeroU64;
use std::path::Path;

use glam::Vec3;
use shadowmap_frustum::{CascadeSet, LightDirection, ShadowTransform};
use shadowmap_paraboloid::{ParaboloidMap, Side, SubdivisionOptions, subdivide_triangles};
use shadowmap_rtw::RtwShadow;
use shadowmap_warp::XpsmShadow;
use wgpu::util::DeviceExt;

use crate::depth::{
    DepthBias, DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, RtwSubdivision,
    ShadowDepthPass, read_texture, subdivide_for_rtw, table_buffer,
};
use crate::uniforms::{FrameRaw, RtwShadowRaw, ToRaw, cascade_layers, paraboloid_layers};
use crate::{BackendError, GpuContext, shaders};

/// The technique whose shadow the renderer draws.
#[derive(Clone, Copy, Debug)]
pub enum ShadowTechnique<'a> {
    /// Uniform, LiSPSM, TSM, spot (one matrix).
    Matrix(&'a ShadowTransform),
    /// XPSM, with its warped-space Z bias.
    Xpsm(&'a XpsmShadow),
    /// Cascaded shadow maps, one layer per cascade, selected by view depth with the
    /// blend band.
    Cascades(&'a CascadeSet),
    /// Cascaded shadow maps selected by projection with this margin in texels.
    CascadesByProjection(&'a CascadeSet, f32),
    /// A paraboloid map (DPSM or cut IPSM map).
    Paraboloid(&'a ParaboloidMap),
    /// Rectilinear texture warping.
    Rtw(&'a RtwShadow<'a>),
}

impl ShadowTechnique<'_> {
    fn lookup(&self) -> Lookup {
        match self {
            Self::Matrix(_) | Self::Xpsm(_) => Lookup::Matrix,
            Self::Cascades(_) | Self::CascadesByProjection(..) => Lookup::Cascades,
            Self::Paraboloid(_) => Lookup::Paraboloid,
            Self::Rtw(_) => Lookup::Rtw,
        }
    }

    fn light(&self) -> LightDirection {
        match self {
            Self::Matrix(t) => t.light,
            Self::Xpsm(x) => x.transform.light,
            Self::Cascades(s) | Self::CascadesByProjection(s, _) => s
                .cascades
                .first()
                .map_or(LightDirection::Directional(Vec3::NEG_Y), |c| {
                    c.transform.light
                }),
            Self::Paraboloid(m) => LightDirection::Position(m.position),
            Self::Rtw(r) => r.base.light,
        }
    }

    fn reversed_z(&self) -> bool {
        match self {
            Self::Matrix(t) => t.reversed_z,
            Self::Xpsm(x) => x.transform.reversed_z,
            Self::Cascades(s) | Self::CascadesByProjection(s, _) => {
                s.cascades.first().is_some_and(|c| c.transform.reversed_z)
            }
            Self::Paraboloid(m) => m.reversed_z,
            Self::Rtw(r) => r.base.reversed_z,
        }
    }

    /// The lookup's uniform block, as bytes.
    fn lookup_bytes(&self) -> Vec<u8> {
        match self {
            Self::Matrix(t) => bytemuck::bytes_of(&t.to_raw()).to_vec(),
            Self::Xpsm(x) => bytemuck::bytes_of(&x.to_raw()).to_vec(),
            Self::Cascades(s) => bytemuck::bytes_of(&s.to_raw()).to_vec(),
            Self::CascadesByProjection(s, margin) => bytemuck::bytes_of(
                &s.to_raw()
                    .with_selection_by_projection(*margin, s.resolution),
            )
            .to_vec(),
            Self::Paraboloid(m) => bytemuck::bytes_of(&ToRaw::to_raw(*m)).to_vec(),
            Self::Rtw(r) => bytemuck::bytes_of(&r.to_raw()).to_vec(),
        }
    }
}

/// Which lookup shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Lookup {
    Matrix,
    Cascades,
    Paraboloid,
    Rtw,
}

impl Lookup {
    fn source(self) -> &'static str {
        match self {
            Self::Matrix => shaders::LOOKUP_MATRIX,
            Self::Cascades => shaders::LOOKUP_CASCADES,
            Self::Paraboloid => shaders::LOOKUP_PARABOLOID,
            Self::Rtw => shaders::LOOKUP_RTW,
        }
    }
}

/// How the rendered image filters the shadow (the mask never filters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowFilter {
    /// One nearest texel.
    Hard,
    /// The hardware 2×2 compare (bilinear PCF).
    Hardware2x2,
    /// `taps × taps` hardware compares (1 to 9) across `radius` texels.
    Pcf {
        /// Taps per side.
        taps: u32,
        /// Half-width of the kernel in texels.
        radius: f32,
    },
    /// 16 hardware compares on a Poisson disk of `radius` texels.
    Poisson {
        /// Disk radius in texels.
        radius: f32,
    },
    /// Variance shadow maps with a separable Gaussian blur of `blur_radius` texels.
    Vsm {
        /// Blur radius in texels, up to 32.
        blur_radius: u32,
    },
}

impl ShadowFilter {
    fn key(self) -> u8 {
        match self {
            Self::Hard => 0,
            Self::Hardware2x2 => 1,
            Self::Pcf { .. } => 2,
            Self::Poisson { .. } => 3,
            Self::Vsm { .. } => 4,
        }
    }

    fn source(self) -> &'static str {
        match self {
            Self::Hard => shaders::FILTER_HARD,
            Self::Hardware2x2 => shaders::FILTER_HARDWARE,
            Self::Pcf { .. } => shaders::FILTER_PCF,
            Self::Poisson { .. } => shaders::FILTER_POISSON,
            Self::Vsm { .. } => shaders::FILTER_VSM,
        }
    }

    /// (radius in texels, taps).
    fn params(self) -> (f32, f32) {
        match self {
            Self::Hard | Self::Hardware2x2 => (0.0, 1.0),
            Self::Pcf { taps, radius } => (radius, taps.clamp(1, 9) as f32),
            Self::Poisson { radius } => (radius, 16.0),
            Self::Vsm { blur_radius } => (0.0, blur_radius.min(32) as f32),
        }
    }
}

/// Knobs of [`HeadlessRenderer::render`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Image width in pixels. Default 320.
    pub width: u32,
    /// Image height in pixels. Default 240.
    pub height: u32,
    /// Shadow-map texels per side. Default 1024.
    pub shadow_resolution: u32,
    /// Depth-pass and lookup biases; `None` (the default): the technique's
    /// [`ShadowBias::default_for`] with this filter.
    pub bias: Option<ShadowBias>,
    /// The image's filter. Default [`ShadowFilter::Hardware2x2`].
    pub filter: ShadowFilter,
    /// Paraboloid caster subdivision (its resolution is replaced by
    /// `shadow_resolution`).
    pub subdivision: SubdivisionOptions,
    /// How casters are subdivided for RTW ([`subdivide_for_rtw`]; its resolution is
    /// replaced by `shadow_resolution`). Default [`RtwSubdivision::default`]: pieces
    /// of at most 2 table cells whose straight warped image misses the warp by at
    /// most a quarter texel, at most 32 per original edge.
    pub rtw_subdivision: RtwSubdivision,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 320,
            height: 240,
            shadow_resolution: 1024,
            bias: None,
            filter: ShadowFilter::Hardware2x2,
            subdivision: SubdivisionOptions::default(),
            rtw_subdivision: RtwSubdivision::default(),
        }
    }
}

impl RenderOptions {
    /// With this image size.
    #[must_use]
    pub const fn with_size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }
    /// With this shadow-map resolution.
    #[must_use]
    pub const fn with_shadow_resolution(mut self, resolution: u32) -> Self {
        self.shadow_resolution = resolution;
        self
    }
    /// With these biases instead of the technique's defaults.
    #[must_use]
    pub const fn with_bias(mut self, bias: ShadowBias) -> Self {
        self.bias = Some(bias);
        self
    }
    /// With this RTW caster subdivision.
    #[must_use]
    pub const fn with_rtw_subdivision(mut self, subdivision: RtwSubdivision) -> Self {
        self.rtw_subdivision = subdivision;
        self
    }
    /// With this filter.
    #[must_use]
    pub const fn with_filter(mut self, filter: ShadowFilter) -> Self {
        self.filter = filter;
        self
    }
}

/// The biases against shadow acne: a rasterizer bias in the depth pass and a lookup
/// bias in the scene pass.
///
/// Acne comes from a surface's depth varying across a shadow-map texel: a receiver
/// compared with a texel whose stored depth was taken up to half a texel (hard) or
/// a filter radius (PCF) away sees itself as occluded. The slope-scaled rasterizer
/// bias grows with that variation per texel, so it removes acne at every surface
/// angle and in every warp (LiSPSM/TSM/XPSM perspective, RTW compression) without
/// a large constant; the small constant and lookup biases absorb rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowBias {
    /// Depth-pass rasterizer bias for standard depth: positive pushes stored depth
    /// away from the light. The renderer negates all three fields for reversed-Z.
    pub raster: DepthBias,
    /// Lookup bias in stored-depth units, toward the light (as
    /// `shadowmap_eval`'s `DepthMap::is_lit`).
    pub depth: f32,
    /// Lookup bias in world units: XPSM's warped Z bias; ignored by the others.
    pub world: f32,
}

impl ShadowBias {
    /// No bias at all.
    pub const NONE: Self = Self::new(
        DepthBias {
            constant: 0,
            slope_scale: 0.0,
            clamp: 0.0,
        },
        0.0,
        0.0,
    );

    /// The three biases.
    #[must_use]
    pub const fn new(raster: DepthBias, depth: f32, world: f32) -> Self {
        Self {
            raster,
            depth,
            world,
        }
    }

    /// The renderer's default for a technique and filter, chosen so the example
    /// scene shows no acne:
    ///
    /// ```text
    /// reach       = how far (texels) the filter compares from the sample:
    ///               hard 0.5, hardware 2x2 1, PCF / Poisson radius + 1, VSM 0.5
    /// slope_scale = reach * k,  k = 1.5 (matrix techniques, cascades, XPSM),
    ///                           k = 2   (paraboloid, RTW: their casters are
    ///                                    piecewise-linear approximations)
    /// constant    = 256 (about 1.5e-5 at depth 0.5, in units of 2^(e - 23))
    /// clamp       = 0.01 (nearly edge-on casters, RTW's compressed slivers)
    /// depth       = 1e-4 lookup bias (f32 rounding of the lookup)
    /// world       = 0.05 world units (XPSM only)
    /// ```
    #[must_use]
    pub fn default_for(technique: &ShadowTechnique<'_>, filter: ShadowFilter) -> Self {
        let reach = match filter {
            ShadowFilter::Hard | ShadowFilter::Vsm { .. } => 0.5,
            ShadowFilter::Hardware2x2 => 1.0,
            ShadowFilter::Pcf { radius, .. } | ShadowFilter::Poisson { radius } => {
                radius.clamp(0.0, 64.0) + 1.0
            }
        };
        let k = match technique {
            ShadowTechnique::Paraboloid(_) | ShadowTechnique::Rtw(_) => 2.0,
            _ => 1.5,
        };
        let world = if matches!(technique, ShadowTechnique::Xpsm(_)) {
            0.05
        } else {
            0.0
        };
        Self::new(
            DepthBias {
                constant: 256,
                slope_scale: reach * k,
                clamp: 0.01,
            },
            1e-4,
            world,
        )
    }

    /// The rasterizer bias for a depth direction.
    fn raster_for(&self, reversed_z: bool) -> DepthBias {
        let b = self.raster;
        if reversed_z {
            DepthBias {
                constant: b.constant.saturating_neg(),
                slope_scale: -b.slope_scale,
                clamp: -b.clamp,
            }
        } else {
            b
        }
    }

    fn is_finite(&self) -> bool {
        self.raster.slope_scale.is_finite()
            && self.raster.clamp.is_finite()
            && self.depth.is_finite()
            && self.world.is_finite()
    }
}

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

/// What [`HeadlessRenderer::render`] returns.
#[derive(Clone, Debug)]
pub struct RenderedFrame {
    /// The shaded image.
    pub image: Image,
    /// The per-pixel shadow test.
    pub mask: ShadowMask,
}

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Uint;
const MOMENTS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Replaces the `@compose lookup` and `@compose filter` regions of
/// `render_scene.wgsl` by a lookup and a filter source.
///
/// # Errors
/// [`BackendError::InvalidInput`] if a marker is missing.
pub fn compose_scene_shader(lookup: &str, filter: &str) -> Result<String, BackendError> {
    let s = replace_region(shaders::RENDER_SCENE, "lookup", lookup)?;
    replace_region(&s, "filter", filter)
}

fn replace_region(source: &str, name: &str, with: &str) -> Result<String, BackendError> {
    let begin = format!("// @compose {name} begin");
    let end = format!("// @compose {name} end");
    let missing = BackendError::InvalidInput("compose marker missing");
    let a = source.find(&begin).ok_or(missing)?;
    let b = source[a..]
        .find(&end)
        .map(|i| a + i + end.len())
        .ok_or(BackendError::InvalidInput("compose marker missing"))?;
    Ok(format!("{}{}{}", &source[..a], with, &source[b..]))
}

macro_rules! combos {
    ($(($lookup:ident, $filter:ident)),* $(,)?) => {
        [$((
            concat!("render_scene+", stringify!($lookup), "+", stringify!($filter)),
            shaders::$lookup,
            shaders::$filter,
        )),*]
    };
}

/// Every source the backend composes at run time, named
/// `render_scene+LOOKUP+FILTER`: each lookup with each filter (for the naga test),
/// with the composition's own result, so a failing one is reported by name rather
/// than dropped.
#[must_use]
pub fn composed_shaders() -> Vec<(&'static str, Result<String, BackendError>)> {
    let all = combos![
        (LOOKUP_MATRIX, FILTER_HARD),
        (LOOKUP_MATRIX, FILTER_HARDWARE),
        (LOOKUP_MATRIX, FILTER_PCF),
        (LOOKUP_MATRIX, FILTER_POISSON),
        (LOOKUP_MATRIX, FILTER_VSM),
        (LOOKUP_CASCADES, FILTER_HARD),
        (LOOKUP_CASCADES, FILTER_HARDWARE),
        (LOOKUP_CASCADES, FILTER_PCF),
        (LOOKUP_CASCADES, FILTER_POISSON),
        (LOOKUP_CASCADES, FILTER_VSM),
        (LOOKUP_PARABOLOID, FILTER_HARD),
        (LOOKUP_PARABOLOID, FILTER_HARDWARE),
        (LOOKUP_PARABOLOID, FILTER_PCF),
        (LOOKUP_PARABOLOID, FILTER_POISSON),
        (LOOKUP_PARABOLOID, FILTER_VSM),
        (LOOKUP_RTW, FILTER_HARD),
        (LOOKUP_RTW, FILTER_HARDWARE),
        (LOOKUP_RTW, FILTER_PCF),
        (LOOKUP_RTW, FILTER_POISSON),
        (LOOKUP_RTW, FILTER_VSM),
    ];
    all.iter()
        .map(|(name, l, f)| (*name, compose_scene_shader(l, f)))
        .collect()
}

/// The scene pipeline of one (lookup, filter, camera depth direction).
#[derive(Debug)]
struct ScenePipeline {
    pipeline: wgpu::RenderPipeline,
    frame_layout: wgpu::BindGroupLayout,
    lookup_layout: wgpu::BindGroupLayout,
    maps_layout: wgpu::BindGroupLayout,
}

/// The VSM moments and blur pipelines.
#[derive(Debug)]
struct VsmPipelines {
    moments: wgpu::RenderPipeline,
    blur: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// Renders scenes headlessly; caches its pipelines across frames.
#[derive(Debug, Default)]
pub struct HeadlessRenderer {
    scene: HashMap<(Lookup, u8, bool), ScenePipeline>,
    vsm: Option<VsmPipelines>,
}

impl HeadlessRenderer {
    /// An empty renderer (pipelines are created on first use).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Renders `triangles` (every triangle casts and receives) from `camera` with the
    /// shadow of `technique`, waits for the GPU and reads the image and the mask back.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for an empty or non-finite scene, a zero or too
    /// large image or map, an invalid camera, or caster subdivision failing;
    /// [`BackendError::Wgpu`] for any wgpu error; [`BackendError::Readback`].
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
        camera: &shadowmap_frustum::Camera,
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
    ) -> Result<RenderedFrame, BackendError> {
        let limit = ctx.device.limits().max_texture_dimension_2d;
        if options.width == 0
            || options.height == 0
            || options.width > limit
            || options.height > limit
        {
            return Err(BackendError::InvalidInput("image size out of range"));
        }
        if !options.bias.is_none_or(|b| b.is_finite()) {
            return Err(BackendError::InvalidInput("non-finite bias"));
        }
        let clip_from_world = camera
            .clip_from_world()
            .map_err(|_| BackendError::InvalidInput("invalid camera"))?;
        let view_from_world = camera
            .view_from_world()
            .map_err(|_| BackendError::InvalidInput("invalid camera"))?;
        ctx.scoped(|ctx| {
            self.render_scoped(
                ctx,
                triangles,
                camera,
                technique,
                options,
                (clip_from_world, view_from_world),
            )
        })
    }

    fn render_scoped(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
        camera: &shadowmap_frustum::Camera,
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
        (clip_from_world, view_from_world): (glam::Mat4, glam::Mat4),
    ) -> Result<RenderedFrame, BackendError> {
        let device = &ctx.device;
        let resolution = options.shadow_resolution;
        let reversed = technique.reversed_z();
        let bias = options
            .bias
            .unwrap_or_else(|| ShadowBias::default_for(technique, options.filter));
        let raster_bias = bias.raster_for(reversed);
        let scene_mesh = MeshBuffers::from_triangles(ctx, triangles)?;

        // 1. The depth pass, casters subdivided where the projection is not linear.
        let mut encoder = device.create_command_encoder(&Default::default());
        let (depth_pass, layers, tables) = match technique {
            ShadowTechnique::Matrix(_)
            | ShadowTechnique::Xpsm(_)
            | ShadowTechnique::Cascades(_)
            | ShadowTechnique::CascadesByProjection(..) => {
                let blocks = match technique {
                    ShadowTechnique::Matrix(t) => vec![t.to_raw()],
                    ShadowTechnique::Xpsm(x) => vec![x.to_raw()],
                    ShadowTechnique::Cascades(s) | ShadowTechnique::CascadesByProjection(s, _) => {
                        cascade_layers(s)
                    }
                    _ => Vec::new(),
                };
                let layers = blocks.len() as u32;
                let desc = DepthPassDesc::new(DepthTechnique::Matrix, resolution)
                    .with_layers(layers)
                    .with_reversed_z(reversed)
                    .with_bias(raster_bias);
                let mut pass = ShadowDepthPass::new(ctx, &desc)?;
                pass.encode(
                    ctx,
                    &mut encoder,
                    &[&scene_mesh],
                    &DepthUniforms::Matrix(&blocks),
                )?;
                (pass, layers, None)
            }
            ShadowTechnique::Paraboloid(map) => {
                let sub = options.subdivision.with_resolution(resolution);
                let blocks = paraboloid_layers(map);
                let mut meshes = Vec::new();
                let mut out = Vec::new();
                for side in [Side::Front, Side::Back].into_iter().take(blocks.len()) {
                    subdivide_triangles(map, side, triangles, &sub, &mut out)
                        .map_err(|_| BackendError::InvalidInput("paraboloid subdivision failed"))?;
                    meshes.push(MeshBuffers::from_triangles(ctx, &out)?);
                }
                let refs: Vec<&MeshBuffers> = meshes.iter().collect();
                let layers = blocks.len() as u32;
                let desc = DepthPassDesc::new(DepthTechnique::Paraboloid, resolution)
                    .with_layers(layers)
                    .with_reversed_z(reversed)
                    .with_bias(raster_bias);
                let mut pass = ShadowDepthPass::new(ctx, &desc)?;
                pass.encode(
                    ctx,
                    &mut encoder,
                    &refs,
                    &DepthUniforms::Paraboloid(&blocks),
                )?;
                (pass, layers, None)
            }
            ShadowTechnique::Rtw(shadow) => {
                let mut out = Vec::new();
                let sub = options.rtw_subdivision.with_resolution(resolution);
                subdivide_for_rtw(shadow, triangles, &sub, &mut out);
                let mesh = MeshBuffers::from_triangles(ctx, &out)?;
                let tables = RtwShadowRaw::tables(shadow);
                let desc = DepthPassDesc::new(DepthTechnique::Rtw, resolution)
                    .with_reversed_z(reversed)
                    .with_bias(raster_bias);
                let mut pass = ShadowDepthPass::new(ctx, &desc)?;
                pass.encode(
                    ctx,
                    &mut encoder,
                    &[&mesh],
                    &DepthUniforms::Rtw {
                        raw: shadow.to_raw(),
                        tables: &tables,
                    },
                )?;
                (pass, 1, Some(tables))
            }
        };

        // 2. VSM moments and blur.
        let moments = self.encode_vsm(ctx, &mut encoder, &depth_pass, options, reversed)?;

        // 3. The scene pass.
        let lookup = technique.lookup();
        let key = (lookup, options.filter.key(), camera.reversed_z);
        let pipeline = match self.scene.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(v) => v.insert(create_scene_pipeline(
                device,
                lookup,
                options.filter,
                camera.reversed_z,
            )?),
        };
        let (radius, taps) = options.filter.params();
        let frame = FrameRaw {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            view_from_world: view_from_world.to_cols_array_2d(),
            light: FrameRaw::light_vector(technique.light()),
            bias: [
                bias.depth,
                bias.world,
                radius,
                f32::from(u8::from(reversed)),
            ],
            shadow_size: [resolution as f32, resolution as f32, layers as f32, taps],
            eye: camera.eye().extend(1.0).to_array(),
        };
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadowmap frame"),
            contents: bytemuck::bytes_of(&frame),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let lookup_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadowmap lookup"),
            contents: &technique.lookup_bytes(),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadowmap frame"),
            layout: &pipeline.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let table_buf = tables.as_ref().map(|t| {
            let b = table_buffer(device, (t.len() * 4) as u64);
            ctx.queue.write_buffer(&b, 0, bytemuck::cast_slice(t));
            b
        });
        let mut lookup_entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: lookup_buffer.as_entire_binding(),
        }];
        if let Some(b) = &table_buf {
            lookup_entries.push(wgpu::BindGroupEntry {
                binding: 1,
                resource: b.as_entire_binding(),
            });
        }
        let lookup_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadowmap lookup"),
            layout: &pipeline.lookup_layout,
            entries: &lookup_entries,
        });
        let compare = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadowmap compare"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(if reversed {
                wgpu::CompareFunction::GreaterEqual
            } else {
                wgpu::CompareFunction::LessEqual
            }),
            ..Default::default()
        });
        let moments_view = moments.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let maps_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadowmap maps"),
            layout: &pipeline.maps_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(depth_pass.array_view()),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&compare),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&moments_view),
                },
            ],
        });
        let size = wgpu::Extent3d {
            width: options.width,
            height: options.height,
            depth_or_array_layers: 1,
        };
        let target = |format, label| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let color = target(COLOR_FORMAT, "shadowmap color");
        let mask = target(MASK_FORMAT, "shadowmap mask");
        let depth = target(crate::depth::DEPTH_FORMAT, "shadowmap camera depth");
        let color_view = color.create_view(&Default::default());
        let mask_view = mask.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadowmap scene"),
                color_attachments: &[
                    Some(wgpu::RenderPassColorAttachment {
                        view: &color_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.55,
                                g: 0.7,
                                b: 0.9,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                    Some(wgpu::RenderPassColorAttachment {
                        view: &mask_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(if camera.reversed_z { 0.0 } else { 1.0 }),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, &frame_group, &[]);
            pass.set_bind_group(1, &lookup_group, &[]);
            pass.set_bind_group(2, &maps_group, &[]);
            pass.set_vertex_buffer(0, scene_mesh.vertices.slice(..));
            pass.set_index_buffer(scene_mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..scene_mesh.index_count, 0, 0..1);
        }
        ctx.queue.submit([encoder.finish()]);
        let rgba = read_texture(
            ctx,
            &color,
            wgpu::TextureAspect::All,
            options.width,
            options.height,
            1,
            4,
        )?;
        let raw_mask = read_texture(
            ctx,
            &mask,
            wgpu::TextureAspect::All,
            options.width,
            options.height,
            1,
            1,
        )?;
        let values = raw_mask
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
                width: options.width,
                height: options.height,
                rgba,
            },
            mask: ShadowMask {
                width: options.width,
                height: options.height,
                values,
            },
        })
    }

    /// The moments texture: blurred moments for VSM, else a 1×1 placeholder.
    fn encode_vsm(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        depth: &ShadowDepthPass,
        options: &RenderOptions,
        reversed: bool,
    ) -> Result<wgpu::Texture, BackendError> {
        let device = &ctx.device;
        let desc = depth.desc();
        let ShadowFilter::Vsm { blur_radius } = options.filter else {
            return Ok(moments_texture(device, 1, 1));
        };
        if self.vsm.is_none() {
            self.vsm = Some(create_vsm_pipelines(device));
        }
        let vsm = self.vsm.as_ref().ok_or(BackendError::InvalidInput("vsm"))?;
        let a = moments_texture(device, desc.resolution, desc.layers);
        let b = moments_texture(device, desc.resolution, desc.layers);
        let array = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let layer_view = |t: &wgpu::Texture, layer: u32| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let (a_all, b_all) = (array(&a), array(&b));
        for layer in 0..desc.layers {
            // moments -> a, blur x: a -> b, blur y: b -> a.
            let steps: [(
                &wgpu::RenderPipeline,
                &wgpu::TextureView,
                &wgpu::Texture,
                [i32; 2],
            ); 3] = [
                (&vsm.moments, &b_all, &a, [0, 0]),
                (&vsm.blur, &a_all, &b, [1, 0]),
                (&vsm.blur, &b_all, &a, [0, 1]),
            ];
            for (pipeline, input, output, direction) in steps {
                let params: [u32; 8] = [
                    layer,
                    blur_radius.min(32),
                    u32::from(reversed),
                    0,
                    direction[0] as u32,
                    direction[1] as u32,
                    0,
                    0,
                ];
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("shadowmap vsm params"),
                    contents: bytemuck::cast_slice(&params),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("shadowmap vsm"),
                    layout: &vsm.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(depth.array_view()),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(input),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: buffer.as_entire_binding(),
                        },
                    ],
                });
                let view = layer_view(output, layer);
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("shadowmap vsm"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.draw(0..3, 0..1);
            }
        }
        Ok(a)
    }
}

fn moments_texture(device: &wgpu::Device, resolution: u32, layers: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadowmap moments"),
        size: wgpu::Extent3d {
            width: resolution,
            height: resolution,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: MOMENTS_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

fn texture_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    size: usize,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(size as u64),
        },
        count: None,
    }
}

fn create_vsm_pipelines(device: &wgpu::Device) -> VsmPipelines {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap vsm"),
        entries: &[
            texture_entry(0, wgpu::TextureSampleType::Depth),
            texture_entry(1, wgpu::TextureSampleType::Float { filterable: false }),
            uniform_entry(2, wgpu::ShaderStages::FRAGMENT, 32),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap vsm"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap vsm"),
        source: wgpu::ShaderSource::Wgsl(shaders::FILTER_VSM_MOMENTS.into()),
    });
    let make = |entry: &str| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("shadowmap vsm"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[Some(MOMENTS_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    VsmPipelines {
        moments: make("fs_moments"),
        blur: make("fs_blur"),
        layout,
    }
}

fn create_scene_pipeline(
    device: &wgpu::Device,
    lookup: Lookup,
    filter: ShadowFilter,
    camera_reversed_z: bool,
) -> Result<ScenePipeline, BackendError> {
    let source = compose_scene_shader(lookup.source(), filter.source())?;
    let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap frame"),
        entries: &[uniform_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            size_of::<FrameRaw>(),
        )],
    });
    // The block size depends on the technique: no minimum.
    let mut lookup_entries = vec![uniform_entry(0, wgpu::ShaderStages::FRAGMENT, 0)];
    if lookup == Lookup::Rtw {
        lookup_entries.push(wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: NonZeroU64::new(4),
            },
            count: None,
        });
    }
    let lookup_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap lookup"),
        entries: &lookup_entries,
    });
    let maps_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap maps"),
        entries: &[
            texture_entry(0, wgpu::TextureSampleType::Depth),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            },
            texture_entry(2, wgpu::TextureSampleType::Float { filterable: false }),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap scene"),
        bind_group_layouts: &[
            Some(&frame_layout),
            Some(&lookup_layout),
            Some(&maps_layout),
        ],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap scene"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("shadowmap scene"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(MeshBuffers::layout())],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: crate::depth::DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(if camera_reversed_z {
                wgpu::CompareFunction::Greater
            } else {
                wgpu::CompareFunction::Less
            }),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(COLOR_FORMAT.into()), Some(MASK_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    Ok(ScenePipeline {
        pipeline,
        frame_layout,
        lookup_layout,
        maps_layout,
    })
}
