//! Focus regions and perspective shadow-map warps for directional lights: uniform
//! focused, LiSPSM, XPSM, TSM and warped cascades.
//!
//! Every technique returns the same output, a [`ShadowTransform`] of
//! `shadowmap-frustum` (wrapped with technique-specific extras): the depth-pass
//! matrix `clip_from_world` (WebGPU clip space), the lookup matrix `uv_from_world`
//! (texture `v` down, divide by `w`), the conversion of a world-space depth bias into
//! the technique's depth ([`ShadowTransform::depth_bias`], exact through the warp)
//! and the world size of a texel at a point ([`ShadowTransform::texel_world_size`],
//! from the Jacobian of the mapping) for normal-offset bias.
//!
//! - [`uniform_focused`]: orthographic fit of frustum ∩ receivers in light space, near
//!   plane pulled back to the casters. The baseline.
//! - [`lispsm`]: light space perspective shadow maps (Wimmer, Scherzer and
//!   Purgathofer, *Light Space Perspective Shadow Maps*, EGSR 2004) with the strength
//!   parameter `eta` of Lloyd, Tuft, Yoon and Manocha (*Warping and Partitioning for
//!   Low Error Shadow Maps*, EGSR 2006) and a fade to uniform as the light turns
//!   parallel to the view.
//! - [`xpsm`]: extended perspective shadow maps (Gusev, *Extended Perspective Shadow
//!   Maps*, 2007), all 18 steps, with the warped-space Z bias.
//! - [`tsm`]: trapezoidal shadow maps (Martin and Tan, *Anti-aliasing and Continuity
//!   with Trapezoidal Shadow Maps*, EGSR 2004) with the 80% focus rule.
//! - [`warped_cascades`]: LiSPSM (or uniform) per parallel split (PSSM + LiSPSM) with a
//!   strength per cascade.
//! - [`spot_warp`]: LiSPSM and TSM for a spot light, in its post-projective space
//!   (after the spot fit of `shadowmap-frustum`, where its rays are parallel): a
//!   homography of the fit's device plane along the view's centre line (see the
//!   [`spot_warp`] docs).
//!
//! # Example
//!
//! ```
//! use glam::Vec3;
//! use shadowmap_frustum::{Aabb, Camera, Projection};
//! use shadowmap_warp::{SceneBounds, LispsmOptions, UniformOptions, lispsm, uniform_focused};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.5, 100.0),
//! )?;
//! let scene = SceneBounds::whole(Aabb::new(Vec3::new(-100.0, 0.0, -120.0), Vec3::new(100.0, 20.0, 10.0)));
//! let light = Vec3::new(0.3, -1.0, -0.2);
//!
//! let uniform = uniform_focused(&camera, light, &scene, &UniformOptions::default())?;
//! let warped = lispsm(&camera, light, &scene, &LispsmOptions::default().with_eta(0.0))?;
//!
//! // A visible ground point lands inside both maps...
//! let p = Vec3::new(1.0, 0.0, -10.0);
//! for t in [uniform, warped.transform] {
//!     let s = t.project(p).unwrap();
//!     assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
//!     assert!((0.0..=1.0).contains(&s.depth));
//! }
//! // ...and LiSPSM spends more texels on it than the uniform fit.
//! let size_u = uniform.texel_world_size(p, 2048).unwrap();
//! let size_l = warped.transform.texel_world_size(p, 2048).unwrap();
//! assert!(size_l < size_u);
//! # Ok::<(), shadowmap_warp::WarpError>(())
//! ```
//!
//! # Conventions
//!
//! | what | convention |
//! |---|---|
//! | handedness | right-handed world, y up; cameras look down `-Z` |
//! | light frame | rotation only; the light looks down `-Z`; `+Y` is the warp axis ([`light_frame`]) |
//! | clip space | WebGPU: x, y in `[-1, 1]`, depth in `[0, 1]` (reversed-Z an option) |
//! | texture space | `uv_from_world = UV_FROM_CLIP * clip_from_world`, `v` down, divide by `w` |
//! | light direction | the direction the light travels (from the light into the scene) |
//! | precision | public API in `f32`; every fit is computed in `f64` and converted |
//!
//! The warp of LiSPSM in the light frame, with `s = 1/n` (`n` the distance from the
//! projection centre to the near face of the body along the warp axis):
//!
//! ```text
//! (x, y, z)  ->  (x - x_c, y - y_0, z - z_c) / (1 + s (y - y_0))
//! s = 0                                  uniform (eta = -1)
//! n_opt = (z_n + sqrt(z_n z_f)) / sin γ   LiSPSM (eta = 0), γ = angle(view, light)
//! n_psm = z_n / sin γ                     PSM-like (eta = 1)
//! ln(1 + s d) interpolated linearly in eta on [-1, 0] and on [0, 1]
//! ```
//!
//! then an orthographic fit of the warped body. Texel density along the warp axis
//! falls from the near to the far face of the body by `(1 + s d)²`, across it by
//! `(1 + s d)`; for the overhead light (`γ = 90°`) at `eta = 0`, `1 + s d = sqrt(f/n)`.
//!
//! # Bad input and fallbacks
//!
//! Every builder returns a [`WarpError`]: an invalid camera ([`WarpError::Frustum`]),
//! a non-finite or zero light direction, inverted receiver or caster boxes, receivers
//! that miss the view frustum, options out of range, or (for absurd magnitudes) a
//! result that would not be a finite invertible `f32` matrix. Documented fallbacks,
//! none of which is an error:
//!
//! - light parallel to the view direction: the warp fades smoothly to the uniform
//!   fit over a [`ParallelFade`] band (LiSPSM's and TSM's `fade` option; XPSM's
//!   miner's-lamp case below
//!   [`XpsmOptions::miner_lamp_threshold`]), and the light frame stays continuous
//!   (see below); the warp axis never points away from the viewer while a warp has
//!   strength. Measured in this crate's tests (a level camera 2 m above a ground
//!   box, one 30 m up looking down 14°): over a sweep of the light from the view
//!   direction to its opposite in 0.01° steps, in the plane of the view and up
//!   vectors, with the light at least 2° above the ground, no texel size at a fixed
//!   near or far ground point changes by more than 2% per step, and no warp's
//!   largest texel-to-pixel ratio over the view exceeds 1.1 times the uniform fit's.
//!   Not covered: a light grazing the ground (within 2°), where TSM's texel sizes
//!   change by up to 3% per 0.01° (continuously), and a light from below the
//!   ground, where XPSM can exceed the uniform fit's largest error by 12%: no
//!   surface in view is lit there, so nothing shows a shadow, and the prediction has
//!   nothing to choose the strength by (the warps keep their formula's; fading them
//!   to the uniform fit instead must happen over the 3° band in which the ground
//!   turns lit, which made TSM's texels change by 12% per 0.01°, and spreading it
//!   wider cost the 7° sun of the report's grazing configuration half its gain).
//!   The two light directions where the light frame has no axis (1° from the view
//!   axis and its opposite, see [`light_frame`]): no frame field on the sphere of
//!   directions is free of zeros, so near them the matrices turn fast about the
//!   light; the fits' boxes there are widened toward the footprint's diameter on
//!   both sides, which fits it in any orientation, so texel sizes stay continuous
//!   (under 0.4% per 1e-4 rad of light passing them at any distance; every warp has
//!   faded to the uniform fit there, and the box is at most `sqrt 2` larger within
//!   about a degree of them);
//! - a warp that would not pay (its formula's strength predicted worse than, or
//!   about as good as, the uniform fit over the focus body: a camera inside a
//!   large scene, looking down, a wall the light grazes): LiSPSM, TSM and XPSM
//!   (automatic length) scale their warp ratio to the fraction of least predicted
//!   perspective aliasing error (Lloyd et al.), continuously down to the uniform
//!   fit, so that no warp is predicted worse than the uniform fit anywhere (see
//!   [`lispsm`]). The prediction stands on the receivers' box, not on the surfaces
//!   the eye sees; a renderer that has those (a G-buffer) can measure the fit on
//!   them and back off with the options' `strength_scale` (the share of the chosen
//!   warp ratio to keep; `shadowmap::fit` tries 1, 1/2 and 0 on the eye's samples
//!   and keeps the finest);
//! - focus region thinner across the light than `f32` resolves at
//!   [`MAX_MAP_SIDE`] texels (a point receiver, a tiny scene far from the origin, a
//!   flat box seen edge-on): the uniform fit widened to [`MIN_RELATIVE_EXTENT`] times
//!   the receivers' largest coordinate, reached continuously;
//! - camera inside the caster volume (casters behind the viewer): uniform, LiSPSM and
//!   TSM only keep the casters that can shadow visible receivers (caster box ∩ the
//!   receivers' prism along the light); XPSM clips its projection vector against the
//!   back-projection singularity;
//! - warps too strong for `f32` matrices: clamped by [`MAX_WARP_RATIO`] (also
//!   relative to the scene's distance from the world origin);
//! - a cascade slice that misses the receivers: `shadow: None` in
//!   [`warped_cascades`].
//!
//! The light's depth range runs from the highest caster that can shadow a visible
//! receiver to the farthest visible receiver. Receivers outside the visible region
//! (and, for XPSM, outside the casters' footprint) may fall outside the map: sample
//! outside `[0, 1]²` as lit.
//!
//! No light frame can vary continuously with the light over the whole sphere (the
//! hairy-ball theorem). [`light_frame`] puts its two singular directions where no
//! warp has strength: the light exactly 1 degree from the view direction (or its
//! opposite), on the side opposite the camera's up vector. Wherever a warp is
//! active its axis agrees with the view direction made perpendicular to the light,
//! so no warp ever turns texels away from the viewer. Near the singular directions,
//! and only there, the (uniform) fit turns fast about the light axis. Within about
//! 10 degrees of the view axis the frame turns about the light axis faster than the
//! light moves (up to about `1 / sin 3° ≈ 19` times at 3 degrees), and a strong
//! warp's texels follow it: a light turning by 1e-4 rad there can change a texel's
//! size by a few percent, continuously.
//!
//! # Features
//!
//! `std` (default) or `libm` provides float math; without `std` the crate is
//! `no_std`. No builder allocates on the heap.
//!
//! Optional data features, all `no_std` compatible: `serde` (`Serialize` and
//! `Deserialize` on the options and results; options deserialize through the
//! builders' checks, and an unbounded value such as the default
//! [`LispsmOptions::far_hint`] is written as none), `mint` and `bytemuck` (glam's and
//! `shadowmap-frustum`'s).

#![cfg_attr(not(feature = "std"), no_std)]

mod cascades;
mod error;
mod focus;
mod lispsm;
mod predict;
#[cfg(feature = "serde")]
mod serde_impls;
mod spot;
mod tsm;
mod uniform;
mod warped_mapping;
mod xpsm;

pub use cascades::{WarpedCascade, WarpedCascades, warped_cascades};
pub use error::WarpError;
pub use focus::{FocusBody, MAX_MAP_SIDE, MAX_WARP_RATIO, MIN_RELATIVE_EXTENT, ParallelFade};
pub use lispsm::{LispsmOptions, LispsmShadow, lispsm};
pub use shadowmap_frustum::SceneBounds;
pub use shadowmap_frustum::{ShadowTransform, glam};
pub use spot::{SpotWarpKind, SpotWarpOptions, SpotWarpShadow, spot_warp};
pub use tsm::{TsmOptions, TsmShadow, tsm};
pub use uniform::{UniformOptions, uniform_focused};
pub use warped_mapping::WarpedCascadesView;
pub use xpsm::{XpsmOptions, XpsmShadow, xpsm};

use glam::{Mat4, Vec3};
use shadowmap_frustum::Camera;

/// The light frame every technique of this crate uses (rotation only): the light
/// looks down `-Z` and `+Y` is the warp axis.
///
/// The warp axis is the camera's viewing direction made perpendicular to the light.
/// When the light is within 3 degrees of the viewing direction (where every warp has
/// faded to the uniform fit), a small multiple of the camera's up vector (made
/// perpendicular) is added, so the frame stays defined and continuous as the light
/// passes the viewing direction; the axis never points against the view direction
/// where a warp is active (see the crate docs on parallel light).
///
/// # Errors
/// [`WarpError::Frustum`], [`WarpError::NonFinite`], [`WarpError::ZeroDirection`].
pub fn light_frame(camera: &Camera, light_direction: Vec3) -> Result<Mat4, WarpError> {
    let view = focus::View::camera(camera)?;
    let light = focus::light_unit(light_direction)?;
    Ok(focus::frame(light, view.forward, view.up).0.as_mat4())
}

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
