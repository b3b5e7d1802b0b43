//! `shadowmap`: every serious shadow-map parameterization as small GPU-free crates,
//! and one vocabulary to switch between them by value.
//!
//! This umbrella crate re-exports the member crates, one feature each:
//!
//! | feature | crate | what |
//! |---|---|---|
//! | `frustum` | [`frustum`] | cameras, frustum slices, cascade splits and fits |
//! | `warp` | `warp` | focus region, LiSPSM, XPSM, TSM |
//! | `paraboloid` | `paraboloid` | dual-paraboloid maps, IPSM |
//! | `rtw` | `rtw` | rectilinear texture warping |
//!
//! With all four (the default), it adds the face an engine uses: a [`Technique`]
//! value, one [`fit`] that takes the same [`FitInput`] (camera, light, scene bounds,
//! texel budget, plus the optional inputs some techniques read) for every technique,
//! and the fitted [`Shadow`], which owns the math crate's own result ([`Fitted`]),
//! says which technique was fitted (`auto`'s choice), its layers and layer side, and
//! is a [`ShadowMapping`](frustum::ShadowMapping) (world point to shadow `uv`, depth
//! and layer).
//!
//! # Example
//!
//! Switch technique by a setting; everything else stays the same:
//!
//! ```
//! # #[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))] {
//! use shadowmap::frustum::glam::{DVec3, Vec3};
//! use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds, ShadowMapping};
//! use shadowmap::{FitInput, Technique, fit};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(1.0, 16.0 / 9.0, 0.5, 200.0),
//! )
//! .unwrap();
//! let light = Light::Directional { direction: Vec3::new(0.3, -1.0, 0.2) };
//! let scene = SceneBounds::whole(Aabb::new(Vec3::new(-100.0, 0.0, -220.0), Vec3::new(100.0, 20.0, 10.0)));
//! let input = FitInput::new(&camera, &light, scene, 2048 * 2048);
//!
//! for technique in [
//!     Technique::UniformFocused(Default::default()),
//!     Technique::Lispsm(Default::default()),
//!     Technique::StableCascades(Default::default()),
//!     Technique::Auto(Default::default()),
//! ] {
//!     let shadow = fit(&technique, &input)?;
//!     assert!(shadow.texels() <= 2048 * 2048);
//!     // A visible ground point lands inside the map.
//!     let s = shadow.map_point(DVec3::new(1.0, 0.0, -30.0)).unwrap();
//!     assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
//!     assert!(s.layer < shadow.layers());
//! }
//! // RTW needs the eye's samples: a typed error says so.
//! let rtw = fit(&Technique::Rtw(Default::default()), &input);
//! assert!(matches!(rtw, Err(shadowmap::FitError::MissingInput { input: "eye_samples", .. })));
//! # }
//! # Ok::<(), shadowmap::FitError>(())
//! ```
//!
//! # Techniques
//!
//! The budget is split evenly over the layers: `k` layers of side
//! `floor(sqrt(budget / k))` (cube faces sized by need share it as tiles of one
//! atlas instead). Optional inputs: **S** eye samples, **D** depth bounds (the
//! camera's range without them), **P** pixels per radian; bold = required.
//!
//! | [`Technique`] | light | layers | reads | paper |
//! |---|---|---|---|---|
//! | `UniformFocused` | directional | 1 | | focused orthographic fit |
//! | `StableCascades`, `TightCascades` | directional | 1..=8 | D | Zhang et al., *Parallel-split shadow maps* (practical splits); Lauritzen et al., *Sample distribution shadow maps* (tight fit to the depth bounds) |
//! | `Lispsm` | directional | 1 | | Wimmer, Scherzer and Purgathofer, *Light space perspective shadow maps* |
//! | `Xpsm` | directional | 1 | | Gusev, *Extended perspective shadow maps* |
//! | `Tsm` | directional | 1 | | Martin and Tan, *Anti-aliasing and continuity with trapezoidal shadow maps* |
//! | `WarpedCascades` | directional | 1..=8 | D | PSSM with LiSPSM per cascade |
//! | `Auto` | directional | as chosen | D, S and P | lowest error among [`auto_candidates`]: measured on the eye samples (S and P), else predicted |
//! | `Rtw` | directional | 1 | **S** | Rosen, *Rectilinear texture warping for fast adaptive shadow mapping* |
//! | `RtwOracle` | directional | 1 | **S**, **P** | RTW fed the exact required density (a limit, not a technique) |
//! | `SpotFit` | spot | 1 | | perspective fit to frustum ∩ receivers |
//! | `SpotWarp` | spot | 1 | D | LiSPSM (Wimmer et al.) or TSM (Martin and Tan) in the spot light's post-projective space, the strength kept where the error predicted on the receivers' box is within 10% of the best weaker warp's or the fit's |
//! | `Dpsm` | point | 2 | | Brabec, Annen and Seidel, *Shadow mapping for hemispherical and omnidirectional light sources* |
//! | `Ipsm` | point | 1 or 2 | D, S and P | Vanek, Navrátil, Herout and Zemčík, *High-quality shadows with improved paraboloid mapping*; `ConeFit::Exact` uses the exact minimal enclosing cone; with S and P, the plan is measured on the samples against its dual alternatives (its own seam, a DPSM's axis) and the finest kept |
//! | `CubeMaps` | point | 1..=6 | D, S and P | cube shadow maps, the engines' point-light baseline: the faces that see visible receivers, each focused on them (`CubeOptions::focused`); `FaceSizes::ByNeed` sizes the faces by the density they need (measured on S with P, else predicted on the receivers' box) |
//! | `SpotRtw` | spot | 1 | **S** | Rosen's RTW over the spot fit (a perspective base) |
//! | `PointRtw` | point | 1 or 2 | **S**, D | Rosen's RTW over each side of the IPSM paraboloid |
//! | `CubeRtw` | point | 1..=6 | **S**, **P**, D | Rosen's RTW over each focused cube face, from the oracle's per-axis needs of the samples (true normals where lit from the front), each face narrowed to its samples and sized per axis by the error its warp leaves |
//! | `TiledCube` | point | one per tile | **S**, **P**, D | Arvo, *Tiled shadow maps*, over the focused cube faces: each face narrowed to its samples and cut into `TileOptions::grid`² cells, each cell as many texels as its front-lit samples need, but for the 5% of them that cost the most texels (given up greedily, kept at half the common need at least), uniform neighbours merged into one tile (a quadtree), all tiles in one atlas; the samples' layer is their tile |
//!
//! Cascade count: for each count `k` up to [`CascadePlan::max_cascades`] (preferring
//! power-of-two sides), practical splits of the depth bounds are fitted to
//! slice ∩ receivers on `side(k)` texels (tight, or stable with the maps the state
//! holds and the margins of newly sized ones), and the count of least predicted error
//! (`shadowmap_frustum::predict_errors` within the depth bounds) wins, more than one
//! cascade only where predicted at most 0.9 times the error of one: open ground gets
//! several cascades, a small room one map of the whole budget. One cascade fits in
//! the uniform fit's light frame, so it is never worse than the uniform fit; more
//! fit in the frame lined up with the image.
//!
//! Across frames, [`fit_with_state`] threads a caller-held [`FitState`]: `auto`'s
//! choice, the cascade counts (kept unless another is clearly better) and each stable
//! cascade's map extents and orientation, fitted to slice ∩ receivers turned by up
//! to [`STABLE_TURN`](frustum::STABLE_TURN) (or grown by
//! [`STABLE_HEADROOM`](frustum::STABLE_HEADROOM) where that is more; with the
//! eye's samples, the headroom alone where the map with the turn would measure
//! more than [`STABLE_MAX_OVER_TIGHT`](frustum::STABLE_MAX_OVER_TIGHT) times the
//! tight box) and kept
//! while they still cover the footprint and are at most
//! [`STABLE_SHRINK_RATIO`](frustum::STABLE_SHRINK_RATIO) times too big, so the
//! maps move by whole texels and shadow edges do not shimmer.
//! The stable cascades also split a held depth range
//! ([`CascadeState::hold_depth_range`](frustum::CascadeState::hold_depth_range)):
//! the depth bounds jump when a receiver enters or leaves the view and creep as the
//! camera walks, and splits that followed them would re-size the maps.
//!
//! `auto` fits every candidate and keeps the lowest 95th-percentile error: measured
//! on the eye samples when the frame has them (and the image's focal length), as the
//! IPSM fit measures its maps, else predicted (`shadowmap_frustum::predict_errors`,
//! from camera, light and bounds alone: no rendering; the receivers' box cannot say
//! which surfaces a view really meets, and over the quality report's random sweep
//! the prediction picked a candidate more than 1.15 times the best in 7% of the
//! views, the samples in none). [`fit`] chooses on one frame; [`fit_with_selector`] with a
//! caller-held [`TechniqueSelector`](frustum::TechniqueSelector) keeps the choice
//! until another candidate is better by its margin, so the technique does not flicker.
//!
//! # Errors and allocation
//!
//! [`fit`] never panics: [`FitError`] says which input is wrong or missing, or wraps
//! the math crate's own error. Every fit is allocation-free except RTW (its
//! importance map and warp tables), the RTW oracle and RTW over the spot fit, the
//! paraboloid and the cube's faces, and the tiled cube maps (the tiles); measuring on eye samples uses at most 4096 of
//! them, on the stack.
#![cfg_attr(not(feature = "std"), no_std)]

#[cfg(feature = "frustum")]
pub use shadowmap_frustum as frustum;
#[cfg(feature = "paraboloid")]
pub use shadowmap_paraboloid as paraboloid;
#[cfg(feature = "rtw")]
pub use shadowmap_rtw as rtw;
#[cfg(feature = "warp")]
pub use shadowmap_warp as warp;

#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
extern crate alloc;

#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod auto;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod cascaded;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod fit;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod held_orientation;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod point_fit;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod rtw_strength;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod sample_error;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod shadow;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod technique;
#[cfg(all(test, feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod test_views;
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
mod warp_fit;

#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
pub use auto::{
    AUTO_CANDIDATE_COUNT, AUTO_CONFIRM_CANDIDATES, AUTO_CONFIRM_SAMPLES, AUTO_MAX_SAMPLES,
    auto_candidates,
};
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
pub use fit::{
    FitError, FitInput, FitState, depth_bounds_of, fit, fit_with_selector, fit_with_state,
    layer_side,
};
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
pub use shadow::{Fitted, Shadow};
#[cfg(all(feature = "warp", feature = "paraboloid", feature = "rtw"))]
pub use technique::{CascadePlan, DpsmOptions, LightKind, RtwPlan, Technique};

/// The README's examples, compiled and run as doctests so they cannot rot.
#[cfg(all(doctest, feature = "warp", feature = "paraboloid", feature = "rtw"))]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
