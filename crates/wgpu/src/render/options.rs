//! The renderer's knobs: the image filter, the biases against acne, and
//! [`RenderOptions`].

use shadowmap_paraboloid::SubdivisionOptions;

use super::ShadowTechnique;
use crate::depth::{DepthBias, RtwSubdivision};
use crate::shaders;

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
    pub(super) fn key(self) -> u8 {
        match self {
            Self::Hard => 0,
            Self::Hardware2x2 => 1,
            Self::Pcf { .. } => 2,
            Self::Poisson { .. } => 3,
            Self::Vsm { .. } => 4,
        }
    }

    pub(super) fn source(self) -> &'static str {
        match self {
            Self::Hard => shaders::FILTER_HARD,
            Self::Hardware2x2 => shaders::FILTER_HARDWARE,
            Self::Pcf { .. } => shaders::FILTER_PCF,
            Self::Poisson { .. } => shaders::FILTER_POISSON,
            Self::Vsm { .. } => shaders::FILTER_VSM,
        }
    }

    /// (radius in texels, taps).
    pub(super) fn params(self) -> (f32, f32) {
        match self {
            Self::Hard | Self::Hardware2x2 => (0.0, 1.0),
            Self::Pcf { taps, radius } => (radius, taps.clamp(1, 9) as f32),
            Self::Poisson { radius } => (radius, 16.0),
            Self::Vsm { blur_radius } => (0.0, blur_radius.min(32) as f32),
        }
    }
}

/// Knobs of [`HeadlessRenderer::render`](super::HeadlessRenderer::render).
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
    /// How casters are subdivided for the paraboloid passes (on the GPU by
    /// [`crate::refine::GpuRefine`], the twin of
    /// `shadowmap_paraboloid::subdivide_triangles`; its resolution is replaced by
    /// `shadow_resolution`).
    pub subdivision: SubdivisionOptions,
    /// How casters are subdivided for RTW (on the GPU by [`crate::refine::GpuRefine`],
    /// the twin of [`crate::depth::subdivide_for_rtw`]; its resolution is
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
    /// constant    = 256 (about 1.5e-5 at depth 0.5, in units of 2^(e - 23));
    ///               16 for the perspective depth of cube faces and spot maps
    /// clamp       = 0.01 (nearly edge-on casters, RTW's compressed slivers)
    /// depth       = 1e-4 lookup bias (f32 rounding of the lookup); 2e-7 for cube
    ///               faces and spot maps, whose depth near 1 spans d² / near of
    ///               distance
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
            ShadowTechnique::Paraboloid(_)
            | ShadowTechnique::ParaboloidRtw { .. }
            | ShadowTechnique::Rtw(_)
            | ShadowTechnique::RtwGpu { .. } => 2.0,
            _ => 1.5,
        };
        let world = if matches!(technique, ShadowTechnique::Xpsm(_)) {
            0.05
        } else {
            0.0
        };
        // Cube faces and spot maps store perspective depth from a near plane close
        // to the light (a cube's down to 5 cm): there one unit of stored depth spans
        // `d² / near` of distance at distance `d` (1e-4 is 20 m at 100 m), so their
        // constant and lookup biases are a few steps of `f32` depth near 1.
        let (constant, depth) = if technique.perspective_depth() {
            (16, 2e-7)
        } else {
            (256, 1e-4)
        };
        Self::new(
            DepthBias {
                constant,
                slope_scale: reach * k,
                clamp: 0.01,
            },
            depth,
            world,
        )
    }

    /// The rasterizer bias for a depth direction.
    pub(super) fn raster_for(&self, reversed_z: bool) -> DepthBias {
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

    pub(super) fn is_finite(&self) -> bool {
        self.raster.slope_scale.is_finite()
            && self.raster.clamp.is_finite()
            && self.depth.is_finite()
            && self.world.is_finite()
    }
}
