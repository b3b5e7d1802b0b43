//! [`Technique`]: every shadow-map parameterization as a value, with its options.

use glam::Vec3;
use shadowmap_frustum::Light;
use shadowmap_paraboloid::{ConeFit, CubeOptions, IpsmOptions, MapOptions, TileOptions};
use shadowmap_rtw::{ImportanceOptions, WarpOptions};
use shadowmap_warp::{
    LispsmOptions, SpotWarpKind, SpotWarpOptions, TsmOptions, UniformOptions, XpsmOptions,
};

/// A shadow technique with its options, chosen by value and fitted by
/// [`fit`](crate::fit). Which light each one is for, and which optional
/// [`FitInput`](crate::FitInput) fields it reads, is in the crate docs' table.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Technique {
    /// Orthographic fit of frustum ∩ receivers, near plane pulled back to the casters
    /// (`shadowmap_warp::uniform_focused`). Directional light.
    UniformFocused(UniformOptions),
    /// Parallel-split shadow maps (Zhang et al.), stable fit: each map fitted to
    /// slice ∩ receivers with a small margin (a turn of the camera by
    /// `STABLE_TURN` about `+Y`, 3% growth), its extents and orientation held across
    /// frames with hysteresis ([`fit_with_state`](crate::fit_with_state)), as are
    /// the splits (of a depth range held around the depth bounds), texel
    /// snapping: shadow edges do not shimmer, and the map costs the margin over the
    /// tight fit, not the whole slice's bounding sphere (which cost 1.26x here).
    /// Frame as [`Technique::TightCascades`]; the count is the one of least
    /// predicted error of the stable maps themselves, margins included (over a
    /// small footprint one newly sized map can pay more for its margins than four
    /// maps of a quarter of the texels each). Directional light.
    StableCascades(CascadePlan),
    /// Parallel-split shadow maps, tight fit to slice ∩ receivers over the depth
    /// bounds (SDSM-style). The count is the one of least predicted error, more than
    /// one only where predicted clearly better than one; one cascade fits in the
    /// uniform fit's light frame, so it is the uniform fit narrowed to the depth
    /// bounds and never worse than it; more fit in the frame lined up with the image
    /// (see the crate docs). Directional light.
    TightCascades(CascadePlan),
    /// Light space perspective shadow maps (Wimmer, Scherzer and Purgathofer).
    /// Directional light.
    Lispsm(LispsmOptions),
    /// Extended perspective shadow maps (Gusev). Directional light.
    Xpsm(XpsmOptions),
    /// Trapezoidal shadow maps (Martin and Tan). Directional light.
    Tsm(TsmOptions),
    /// Parallel splits with a LiSPSM warp per cascade, over the depth bounds; the
    /// count is chosen from their own predicted error (one warped map over a short
    /// range can beat four), or measured on the eye samples when the frame has
    /// them. With samples the warps then back off as the single warps do: the
    /// cascades are also fitted at half their warp ratio and at none, and the
    /// finest on the samples is kept (one warped map over a room at seed 44 of the
    /// sweeps measured 1.19 times the uniform fit at full strength). Directional
    /// light.
    WarpedCascades {
        /// Split count and placement.
        plan: CascadePlan,
        /// The per-cascade warp (its `eta` is the strength of every cascade).
        lispsm: LispsmOptions,
    },
    /// The candidate of [`auto_candidates`](crate::auto_candidates) (uniform,
    /// LiSPSM, TSM, XPSM and the three cascaded techniques with this plan) with the
    /// lowest 95th-percentile aliasing error: measured on the eye samples when the
    /// frame has them and the image's focal length (the quality report's measure on
    /// at most [`AUTO_MAX_SAMPLES`](crate::AUTO_MAX_SAMPLES) front-lit samples,
    /// the candidates still close within that subset's noise again on at most
    /// [`AUTO_CONFIRM_SAMPLES`](crate::AUTO_CONFIRM_SAMPLES)),
    /// otherwise predicted from the camera, light and bounds alone
    /// (`shadowmap_frustum::predict_errors`: the receivers' box within the depth
    /// bounds, no rendering), with hysteresis across frames through a caller-held
    /// selector ([`fit_with_selector`](crate::fit_with_selector)): candidates within
    /// the selector's margin of the current one do not take over, so the choice does
    /// not flip every frame. The uniform fit is a candidate, so `auto` is never
    /// measured (or predicted) worse than it. Directional light.
    Auto(CascadePlan),
    /// Rectilinear texture warping (Rosen) over the uniform fit, importance from the
    /// eye's samples (backward analysis) that the light reaches: a sample on a
    /// surface turned away from the light is dark whatever the map holds and gets
    /// no texels (near the eye it would otherwise claim the densest rows of the
    /// warp). The warp's strength (the importance raised to `t` in `[0, 1]`, `t = 0`
    /// the uniform fit) is the one of least 95th-percentile aliasing error measured
    /// on those samples, so it is never worse than its base where the importance
    /// model is off. Directional light.
    Rtw(RtwPlan),
    /// RTW fed the exact perspective-only density each axis requires: the limit RTW
    /// approaches. Directional light.
    RtwOracle(RtwPlan),
    /// Perspective fit of a spot light to frustum ∩ receivers, clamped to its cone.
    SpotFit {
        /// Reversed-Z depth.
        reversed_z: bool,
    },
    /// LiSPSM or TSM in the spot light's post-projective space
    /// (`shadowmap_warp::spot_warp`): the spot fit followed by a perspective warp of
    /// its device plane along the view's centre line. Spot light.
    SpotWarp(SpotWarpOptions),
    /// Dual paraboloid shadow map (Brabec et al.), not view-dependent. Point light.
    Dpsm(DpsmOptions),
    /// Improved paraboloid shadow maps (Vanek et al.): truncated frustum, cone fit,
    /// rotation, cut, single or dual; `fit` picks the paper's averaged cone or the
    /// exact minimal cone. Point light.
    Ipsm(IpsmOptions),
    /// Cube shadow maps: six 90-degree perspective faces around the light, the faces
    /// that miss the visible receivers skipped, each kept face focused on them (or,
    /// with `focused` off, the full face over the light's range). Point light.
    CubeMaps(CubeOptions),
    /// Rectilinear texture warping (Rosen) over the spot fit: the spot's perspective
    /// projection is the base, importance from the eye's samples (backward analysis,
    /// scaled by the base's texel footprint, which grows with the light depth). Spot
    /// light.
    SpotRtw(RtwPlan),
    /// Rectilinear texture warping (Rosen) over the IPSM paraboloid (Vanek et al.):
    /// each side's `uv` is the base, importance from the eye's samples scaled by the
    /// paraboloid's footprint, one pair of warp tables per side. Point light.
    PointRtw {
        /// The paraboloid plan (cone fit, cut, single or dual).
        ipsm: IpsmOptions,
        /// The warp.
        rtw: RtwPlan,
    },
    /// Rectilinear texture warping (Rosen) over each focused face of the cube map:
    /// each kept face's `uv` is a base, importance from the eye samples it stores,
    /// one pair of warp tables per face, and the faces share the budget (an atlas)
    /// in proportion to the error their warps leave. Point light.
    CubeRtw {
        /// The cube's faces and focusing (its budget and face sizes are set by the
        /// fit).
        cube: CubeOptions,
        /// The warp.
        rtw: RtwPlan,
    },
    /// Tiled cube maps (Arvo's tiled shadow maps over the focused faces): each kept
    /// face narrowed to the eye samples it stores and cut into a grid of tiles, each
    /// tile's resolution from the needs of the samples in it, all tiles in one atlas
    /// of the budget. Point light.
    TiledCube {
        /// The cube's faces and focusing (its budget and face sizes are set by the
        /// fit).
        cube: CubeOptions,
        /// The grid and the tiles' guard border.
        tiles: TileOptions,
    },
}

/// Splits of the cascaded techniques: practical splits (Zhang et al.) of the eye's
/// depth bounds, the count chosen from their ratio (see the crate docs).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct CascadePlan {
    /// Most cascades. Default 4 (clamped to `1..=MAX_CASCADES`).
    pub max_cascades: usize,
    /// Practical split weight (0 uniform, 1 logarithmic). Default 0.5.
    pub split_lambda: f32,
    /// Blend band: the last `overlap` fraction (in `[0, 1)`) of each cascade's range is
    /// blended with the next cascade. Default 0 (no band).
    pub overlap: f32,
    /// Reversed-Z depth (1 at the light's near plane) of the stable and tight
    /// cascades; warped cascades take it from their LiSPSM options. Default `false`.
    pub reversed_z: bool,
}

impl Default for CascadePlan {
    fn default() -> Self {
        Self {
            max_cascades: 4,
            split_lambda: 0.5,
            overlap: 0.0,
            reversed_z: false,
        }
    }
}

impl CascadePlan {
    /// With at most this many cascades.
    #[must_use]
    pub const fn with_max_cascades(mut self, count: usize) -> Self {
        self.max_cascades = count;
        self
    }
    /// With this practical-split weight (1: logarithmic splits).
    #[must_use]
    pub const fn with_split_lambda(mut self, lambda: f32) -> Self {
        self.split_lambda = lambda;
        self
    }
    /// With this blend band (see [`overlap`](Self::overlap)).
    #[must_use]
    pub const fn with_overlap(mut self, overlap: f32) -> Self {
        self.overlap = overlap;
        self
    }
    /// With reversed-Z depth (see [`reversed_z`](Self::reversed_z)).
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }
}

/// Knobs of RTW and the RTW oracle.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RtwPlan {
    /// Side of the importance map and of the warp tables. Default 256.
    pub importance_side: u32,
    /// Backward analysis (RTW only).
    pub importance: ImportanceOptions,
    /// Blur, floor and normalization of the warp.
    pub warp: WarpOptions,
}

impl Default for RtwPlan {
    fn default() -> Self {
        Self {
            importance_side: 256,
            importance: ImportanceOptions::default(),
            warp: WarpOptions::default(),
        }
    }
}

impl RtwPlan {
    /// With this importance-map side.
    #[must_use]
    pub const fn with_importance_side(mut self, side: u32) -> Self {
        self.importance_side = side;
        self
    }
    /// With these backward-analysis options.
    #[must_use]
    pub const fn with_importance(mut self, importance: ImportanceOptions) -> Self {
        self.importance = importance;
        self
    }
    /// With these warp options.
    #[must_use]
    pub const fn with_warp(mut self, warp: WarpOptions) -> Self {
        self.warp = warp;
        self
    }
}

/// Knobs of the dual paraboloid map.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct DpsmOptions {
    /// The front map's axis (world). Default `-Y` (down).
    pub axis: Vec3,
    /// Distance from the light mapped to depth 0; the far distance is the light's
    /// range. Default that of [`IpsmOptions`].
    pub near: f32,
    /// The map's other knobs.
    pub map: MapOptions,
}

impl Default for DpsmOptions {
    fn default() -> Self {
        Self {
            axis: Vec3::NEG_Y,
            near: IpsmOptions::default().near,
            map: MapOptions::default(),
        }
    }
}

impl DpsmOptions {
    /// With this front axis.
    #[must_use]
    pub const fn with_axis(mut self, axis: Vec3) -> Self {
        self.axis = axis;
        self
    }
    /// With this near distance.
    #[must_use]
    pub const fn with_near(mut self, near: f32) -> Self {
        self.near = near;
        self
    }
    /// With these map options.
    #[must_use]
    pub const fn with_map(mut self, map: MapOptions) -> Self {
        self.map = map;
        self
    }
}

/// Which kind of light a technique is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightKind {
    /// [`Light::Directional`].
    Directional,
    /// [`Light::Spot`].
    Spot,
    /// [`Light::Point`].
    Point,
}

impl LightKind {
    /// The kind of a light.
    #[must_use]
    pub const fn of(light: &Light) -> Self {
        match light {
            Light::Directional { .. } => Self::Directional,
            Light::Spot { .. } => Self::Spot,
            Light::Point { .. } => Self::Point,
        }
    }
}

impl Technique {
    /// Every technique with default options, in report order (RTW over the spot
    /// fit, the paraboloid and the cube's faces aside).
    #[must_use]
    pub fn all_default() -> [Self; 18] {
        let plan = CascadePlan::default();
        let rtw = RtwPlan::default();
        [
            Self::UniformFocused(UniformOptions::default()),
            Self::StableCascades(plan),
            Self::TightCascades(plan),
            Self::Lispsm(LispsmOptions::default()),
            Self::Xpsm(XpsmOptions::default()),
            Self::Tsm(TsmOptions::default()),
            Self::WarpedCascades {
                plan,
                lispsm: LispsmOptions::default(),
            },
            Self::Auto(plan),
            Self::Rtw(rtw),
            Self::RtwOracle(rtw),
            Self::SpotFit { reversed_z: false },
            Self::SpotWarp(SpotWarpOptions::default()),
            Self::SpotWarp(SpotWarpOptions::default().with_kind(SpotWarpKind::Tsm)),
            Self::Dpsm(DpsmOptions::default()),
            Self::Ipsm(IpsmOptions::default().with_fit(ConeFit::Paper)),
            Self::Ipsm(IpsmOptions::default().with_fit(ConeFit::Exact)),
            Self::CubeMaps(CubeOptions::default()),
            Self::CubeMaps(CubeOptions::default().with_focused(false)),
        ]
    }

    /// Short identifier for tables, logs and file names (`"uniform"`, `"lispsm"`,
    /// `"ipsm_exact"`, ...).
    #[must_use]
    pub const fn name(&self) -> &'static str {
        match self {
            Self::UniformFocused(_) => "uniform",
            Self::StableCascades(_) => "cascades",
            Self::TightCascades(_) => "tight_cascades",
            Self::Lispsm(_) => "lispsm",
            Self::Xpsm(_) => "xpsm",
            Self::Tsm(_) => "tsm",
            Self::WarpedCascades { .. } => "warped_cascades",
            Self::Auto(_) => "auto",
            Self::Rtw(_) => "rtw",
            Self::RtwOracle(_) => "rtw_oracle",
            Self::SpotFit { .. } => "spot",
            Self::SpotWarp(o) => match o.kind {
                SpotWarpKind::Lispsm => "spot_lispsm",
                SpotWarpKind::Tsm => "spot_tsm",
            },
            Self::Dpsm(_) => "dpsm",
            Self::Ipsm(o) => match o.fit {
                ConeFit::Paper => "ipsm_paper",
                ConeFit::Exact => "ipsm_exact",
            },
            Self::CubeMaps(o) => {
                if o.focused {
                    "cube"
                } else {
                    "cube_unfocused"
                }
            }
            Self::SpotRtw(_) => "spot_rtw",
            Self::PointRtw { .. } => "point_rtw",
            Self::CubeRtw { .. } => "cube_rtw",
            Self::TiledCube { .. } => "cube_tiled",
        }
    }

    /// The kind of light the technique is for.
    #[must_use]
    pub const fn light_kind(&self) -> LightKind {
        match self {
            Self::SpotFit { .. } | Self::SpotWarp(_) | Self::SpotRtw(_) => LightKind::Spot,
            Self::Dpsm(_)
            | Self::Ipsm(_)
            | Self::CubeMaps(_)
            | Self::PointRtw { .. }
            | Self::CubeRtw { .. }
            | Self::TiledCube { .. } => LightKind::Point,
            _ => LightKind::Directional,
        }
    }

    /// Whether the technique is meant for this light.
    #[must_use]
    pub const fn applies_to(&self, light: &Light) -> bool {
        matches!(
            (self.light_kind(), LightKind::of(light)),
            (LightKind::Directional, LightKind::Directional)
                | (LightKind::Spot, LightKind::Spot)
                | (LightKind::Point, LightKind::Point)
        )
    }
}
