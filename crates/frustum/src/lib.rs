//! Cameras, frustum slices, cascade splits and cascade fitting for shadow maps.
//!
//! This crate is the shared vocabulary of `shadowmap`: [`Aabb`], [`Plane`],
//! [`Sphere`], [`Camera`] with its [`Projection`], [`Light`], [`Frustum`] and
//! [`ConvexBody`]; the output type of matrix techniques, [`ShadowTransform`]; and the
//! one trait every technique implements, [`ShadowMapping`]. On top of it, it fits
//! parallel-split (cascaded) shadow maps for directional lights:
//!
//! - split schemes ([`SplitScheme`]): uniform, logarithmic, practical (lambda) and
//!   custom, with a blend band between cascades ([`CascadeSplits`]);
//! - fits ([`CascadeFit`]): tight, scene-dependent (slice ∩ receivers, near plane
//!   pulled back to the casters) and stable (rotation-invariant size, whole-texel
//!   motion);
//! - depth bounds from a min/max depth reduction ([`CascadeSplits::from_depth_bounds`],
//!   the "sample distribution" of SDSM and the truncated frustum of IPSM);
//! - cascade selection by view depth and by projection;
//! - a perspective fit for spot lights ([`fit_spot`]).
//!
//! The algorithms follow Zhang et al., *Parallel-Split Shadow Maps* (2006) and the PSSM
//! thesis of Ferko (*Shadow Mapping for Large Virtual Environments*, Comenius University, 2010).
//!
//! # Example
//!
//! ```
//! use glam::Vec3;
//! use shadowmap_frustum::{Camera, CascadeOptions, CascadeSet, CascadeSplits, Projection, SplitScheme};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 200.0),
//! )?;
//! let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 200.0)?
//!     .with_overlap(0.1)?;
//! let set = CascadeSet::fit(&camera, Vec3::new(-1.0, -2.0, -0.5), &splits, &CascadeOptions::default())?;
//! assert_eq!(set.cascades.len(), 4);
//!
//! // A point in view lands inside its cascade's map.
//! let p = Vec3::new(1.0, 0.0, -30.0);
//! let blend = set.select_by_depth(p).unwrap();
//! let sample = set.cascades[blend.index].transform.project(p).unwrap();
//! assert!((0.0..=1.0).contains(&sample.uv.x) && (0.0..=1.0).contains(&sample.depth));
//! # Ok::<(), shadowmap_frustum::FrustumError>(())
//! ```
//!
//! # Conventions
//!
//! | what | convention |
//! |---|---|
//! | handedness | right-handed world, y up |
//! | view space | looks down `-Z`; view depth = `-z_view` |
//! | light space | looks down `-Z` along the light; light distance = `-z_light` |
//! | clip space | WebGPU: x, y in `[-1, 1]`, depth in `[0, 1]` |
//! | reversed-Z | an option of every builder: depth 1 at the near plane |
//! | texture space | `u = x/2 + 1/2`, `v = 1/2 - y/2` (`v` down), see [`UV_FROM_CLIP`] |
//! | matrix names | destination-from-source: `clip_from_world`, `uv_from_world` |
//! | precision | public API in `f32`; builders compute in `f64` and convert |
//! | frustum corners | near then far; each bottom-left, bottom-right, top-right, top-left |
//! | frustum planes | inward normals: left, right, bottom, top, near, far |
//!
//! # Bad input
//!
//! Every builder returns a [`FrustumError`] for input it cannot honour, and documents
//! which; none panics or returns a NaN or singular matrix. Documented fallbacks:
//! a light parallel to the up hint uses another axis to orient the light frame
//! ([`directional_light_from_world`]); a cascade whose slice misses the receivers is
//! fitted to the whole slice ([`Cascade::receivers_missed`]).
//!
//! # Features
//!
//! `std` (default) or `libm`: one of them provides float math; with `libm` and without
//! `std` the crate is `no_std`. No builder allocates on the heap.
//!
//! Optional data features, all `no_std` compatible: `serde` (`Serialize` and
//! `Deserialize` on the options and result types; [`Camera`], [`Light`],
//! [`PredictOptions`] and [`CascadeSplits`] deserialize through their validation, so a
//! bad payload is an error, never an invalid value), `mint` (conversions of [`Aabb`],
//! [`Plane`] and [`Sphere`], plus glam's), `bytemuck` (`Pod` on the `#[repr(C)]` types
//! [`Aabb`], [`Plane`], [`Sphere`] and [`DepthBounds`], plus glam's).

#![cfg_attr(not(feature = "std"), no_std)]

mod body;
mod bounding_sphere;
mod camera;
mod cascade;
mod cascade_fit;
mod cascade_state;
mod clip;
mod depth_bounds;
mod error;
mod frustum;
mod geometry;
mod light;
mod light_prism;
mod mapping;
pub mod math;
mod min_area;
mod predict;
pub mod projection;
mod rays;
mod scene_bounds;
mod selector;
mod split;
mod spot;
mod spot_rounding;
mod valid;

#[cfg(feature = "mint")]
mod mint_impls;
#[cfg(feature = "serde")]
mod serde_impls;

pub use body::{ConvexBody, MAX_BODY_VERTICES};
pub use camera::{Camera, Projection};
pub use cascade::{Cascade, CascadeFit, CascadeMeasure, CascadeOptions, CascadeSet};
pub use cascade_fit::fit_cascade;
pub use cascade_state::{
    CascadeState, HeldDepthRange, MAX_HELD_CANDIDATES, STABLE_DEPTH_MARGIN, STABLE_HEADROOM,
    STABLE_MAX_OVER_TIGHT, STABLE_SHRINK_RATIO, STABLE_TURN,
};
pub use clip::MAX_FRUSTUM_AABB_VERTICES;
pub use depth_bounds::DepthBounds;
pub use error::FrustumError;
pub use frustum::Frustum;
pub use geometry::{Aabb, Plane, Sphere};
pub use light::{Light, directional_light_from_world};
pub use light_prism::LightPrism;
pub use mapping::{
    LightDirection, ShadowMapping, ShadowSample, ShadowTransform, UV_FROM_CLIP, is_invertible,
    is_invertible_at, projective_uv_differentials, uv_differentials_by_points,
};
pub use predict::{
    FRONT_LIT_MIN_COS, MAX_PREDICT_CANDIDATES, MAX_PREDICT_RAYS, PredictOptions, PredictedError,
    predict_error, predict_errors,
};
pub use scene_bounds::{MAX_RESOLUTION, SceneBounds};
pub use selector::TechniqueSelector;
pub use split::{CascadeBlend, CascadeSplits, MAX_CASCADES, SplitScheme};
pub use spot::{SpotShadow, fit_spot};
pub use spot_rounding::{SPOT_ROUNDING_BUDGET, SpotRounding};
pub use valid::ValidCamera;

pub use glam;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
