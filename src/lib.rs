//! `shadowmap`: every serious shadow-map parameterization as small GPU-free crates.
//!
//! This umbrella crate re-exports the member crates, one feature each:
//!
//! | feature | crate | what |
//! |---|---|---|
//! | `frustum` | [`frustum`] | cameras, frustum slices, cascade splits and fits |
//! | `warp` | `warp` | focus region, LiSPSM, XPSM, TSM |
//! | `paraboloid` | `paraboloid` | dual-paraboloid maps, IPSM |
//! | `rtw` | `rtw` | rectilinear texture warping |
#![cfg_attr(not(feature = "std"), no_std)]

#[cfg(feature = "frustum")]
pub use shadowmap_frustum as frustum;
#[cfg(feature = "paraboloid")]
pub use shadowmap_paraboloid as paraboloid;
#[cfg(feature = "rtw")]
pub use shadowmap_rtw as rtw;
#[cfg(feature = "warp")]
pub use shadowmap_warp as warp;
