//! Rectilinear texture warping (RTW): importance maps to 1-D warp maps, with a CPU
//! forward and inverse warp that reproduce the shader's texture sampling exactly.
//!
//! RTW (Paul Rosen, *Rectilinear Texture Warping for Fast Adaptive Shadow Mapping*,
//! I3D 2012; see also Grøn and Sørensen's report on rectilinear texture warping) renders one
//! ordinary shadow map whose texels are redistributed along `u` and `v` by two 1-D
//! warps, so that regions that matter to the eye get more texels:
//!
//! 1. **Importance map** ([`ImportanceMap`]): a `W x H` grid over a base light
//!    projection (a [`ShadowTransform`](shadowmap_frustum::ShadowTransform), for
//!    example the tight uniform fit of
//!    [`fit_cascade`](shadowmap_frustum::fit_cascade)). Filled by *backward analysis*
//!    (eye samples, [`ImportanceMap::accumulate_backward`]), *forward analysis* (the
//!    previous shadow map's depths, [`ImportanceMap::accumulate_forward`]), or the
//!    *oracle* (the exact texel density each eye sample requires,
//!    [`ImportanceMap::accumulate_oracle`]). Cells keep the maximum.
//! 2. **Collapse** to two 1-D maps (maximum of each column, of each row) in one
//!    streaming pass, **blur** (Gaussian, configurable radius), **normalize** to a
//!    maximum of 1, **temporal smoothing** with the previous frame, **floor**
//!    ([`WarpOptions`]).
//! 3. **Warp tables** ([`WarpMaps`]) from Rosen's equation, sampled by the shader
//!    with linear filtering; [`forward_warp`] / [`inverse_warp`] on the CPU.
//! 4. **The technique** ([`RtwShadow`]): the base projection, then each texture axis
//!    warped by its table; it implements
//!    [`ShadowMapping`](shadowmap_frustum::ShadowMapping) like every other technique.
//!
//! Per-frame work does not allocate: an [`ImportanceMap`] and its [`WarpMaps`] are
//! created once, then each frame is `clear()`, `accumulate_*()`, `build()`. Building
//! reads the 2-D map once (column and row maxima in the same pass); everything after
//! that is 1-D.
//!
//! # Example
//!
//! ```
//! use glam::Vec2;
//! use shadowmap_rtw::{ImportanceMap, WarpMaps, WarpOptions, forward_warp, inverse_warp};
//!
//! // Created once; reused every frame without allocating.
//! let mut map = ImportanceMap::new(64, 32)?;
//! let mut warps = WarpMaps::new(64, 32)?;
//!
//! // Per frame: clear, accumulate (here by hand), build.
//! map.clear();
//! map.splat(Vec2::new(0.2, 0.7), 10.0)?;
//! map.splat(Vec2::new(0.8, 0.1), 1.0)?;
//! warps.build(&map, &WarpOptions::default().with_blur_radius(3))?;
//!
//! // The region around u = 0.2 got more texels: its warped extent grew.
//! let x = warps.x_table();
//! assert_eq!(x.len(), 64);
//! let extent = |a: f32, b: f32| forward_warp(x, b) - forward_warp(x, a);
//! assert!(extent(0.15, 0.25) > 3.0 * 0.1);
//! // Ends are fixed, and the inverse undoes the forward warp.
//! assert_eq!((forward_warp(x, 0.0), forward_warp(x, 1.0)), (0.0, 1.0));
//! assert!((inverse_warp(x, forward_warp(x, 0.3)) - 0.3).abs() < 1e-5);
//! # Ok::<(), shadowmap_rtw::RtwError>(())
//! ```
//!
//! # Conventions
//!
//! | what | convention |
//! |---|---|
//! | base texture space | `uv` of the base projection: `u` right, `v` down, `[0, 1]²` (see `shadowmap-frustum`) |
//! | importance map | row-major, cell `(x, y)` covers `[x/W, (x+1)/W) x [y/H, (y+1)/H)` |
//! | collapse | `x` table from the maximum of each column, `y` table from each row's maximum |
//! | warp tables | `R32Float`, `W` texels for `u`, `H` for `v`; stored value = offset `u' - u` |
//! | warped coordinate | `u' = u + S_x(u)`, `v' = v + S_y(v)`, `S` = texture sample (below) |
//! | precision | tables `f32`; cumulative sums in `f64`; forward warp in `f32` like the GPU |
//! | depth | from the base projection, unwarped |
//!
//! # Sampling semantics
//!
//! A table `T` of `N` texels is a 1-D texture sampled with `textureSampleLevel`, a
//! linear (min and mag) sampler and clamp-to-edge addressing. Texel `i` holds the value
//! at coordinate `c_i = (i + 0.5) / N`; between centres the value is linear; outside
//! `[c_0, c_{N-1}]` it is the edge texel:
//!
//! ```text
//! x = u * N - 0.5
//! S(u) = T[0]                              if x <= 0
//!      = T[N-1]                            if x >= N - 1
//!      = T[i] + f * (T[i+1] - T[i])        otherwise, i = floor(x), f = x - i
//! u'   = u + S(u)
//! ```
//!
//! [`sample_table`] and [`forward_warp`] compute exactly this in `f32`. A WGSL shader
//! that filters by hand (two `textureLoad`s and the formula above) agrees bit for bit
//! unless the compiler fuses the multiply-add (then within 1 ulp). Hardware linear
//! filtering quantizes the weight `f` (8 fractional bits on common GPUs), which moves
//! `u'` by at most `2^-9 |T[i+1] - T[i]|`, that is `2^-9 |slope - 1|` texels.
//!
//! **The ends.** Clamp-to-edge makes `S` constant on `[0, c_0]` and `[c_{N-1}, 1]`,
//! so the builder stores `T[0] = T[N-1] = 0`: there `u' = u` (slope 1), hence
//! `u'(0) = 0` and `u'(1) = 1`. The warp is the identity outside `[0, 1]` too.
//!
//! **The table** (Rosen's equation, discretized for those semantics): with the final
//! density `d_k` (collapsed, blurred, normalized, smoothed, floored), the knots
//! `W_i = u'(c_i)` are the normalized cumulative density over the segments between
//! centres, and the stored value is that minus the uniform position:
//!
//! ```text
//! a_k = (d_k + d_{k+1}) / 2                          k = 0 .. N-2   (f64)
//! W_i = c_0 + (N-1)/N * sum_{k<i} a_k / sum_k a_k     W_0 = c_0, W_{N-1} = c_{N-1}
//! T[i] = f32(W_i - c_i)
//! ```
//!
//! so on `[c_k, c_{k+1}]` the slope `du'/du` (the local texel density) is
//! proportional to `a_k`, and the knots `c_i + T[i]` are non-decreasing after rounding
//! to `f32` (where the warp is nearly flat, consecutive knots are closer than an ulp of
//! their offset; the builder then moves a stored value by an ulp or two).
//! [`inverse_warp`] inverts the same piecewise-linear function (binary search over the
//! knots, one interpolation), so `inverse(forward(u)) = u` up to rounding. Constant
//! density gives `T = 0` exactly.
//!
//! # Bad input
//!
//! Every fallible function returns an [`RtwError`] and says which: [`RtwError::EmptyMap`]
//! for a zero-sized map, [`RtwError::MapTooLarge`], [`RtwError::NonFinite`] for NaN or
//! infinite samples, values or transforms, [`RtwError::NegativeImportance`],
//! [`RtwError::SizeMismatch`] / [`RtwError::ShapeMismatch`] for buffers that do not
//! match, [`RtwError::InvalidOption`]. Zero total importance is not an error: that
//! axis falls back to the identity warp. On error nothing is modified. Nothing panics,
//! nothing returns NaN (a NaN coordinate given to the warp functions maps to 0).
//!
//! # Features
//!
//! `std` (default) or `libm` for float math; without `std` the crate is `no_std` and
//! needs `alloc` (the importance map and warp buffers live on the heap, allocated once).
//!
//! Optional data features, `no_std` compatible: `serde` (`Serialize` and
//! `Deserialize` on the options, samples and maps; an [`ImportanceMap`] or
//! [`WarpMaps`] payload is validated, and warp tables must be the ones built from the
//! payload's densities), `mint` (glam's and `shadowmap-frustum`'s conversions) and
//! `bytemuck` (`Pod` on the `#[repr(C)]` [`EyeSample`], plus glam's).

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod error;
mod importance;
#[cfg(feature = "serde")]
mod serde_impls;
mod subdivide;
mod table;
mod warp;

pub use error::RtwError;
pub use importance::{
    AccumulateStats, AxisNeed, BasePoint, EyeSample, ImportanceMap, ImportanceOptions,
    MAX_MAP_CELLS, MAX_MAP_SIDE, OracleAxis, PixelSteps, oracle_needs, oracle_needs_of,
    oracle_needs_where,
};
pub use subdivide::{
    ClipPlane, MAX_CLIP_PLANES, RtwSplitRule, RtwSubdivision, subdivide_for_rtw,
    subdivide_for_rtw_clipped, subdivide_for_rtw_with,
};
pub use table::{
    forward_warp, forward_warp_f64, inverse_warp, inverse_warp_f64, sample_table, sample_table_f64,
};
pub use warp::{MAX_BLUR_RADIUS, MIN_FLOOR, RtwShadow, WarpMaps, WarpOptions, gaussian_weights};

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
