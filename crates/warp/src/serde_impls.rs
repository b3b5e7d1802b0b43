//! `Deserialize` for the options, each payload checked as the builders check it, so
//! a bad one gives an error instead of an invalid value; missing fields take their
//! defaults.
//!
//! The private `*Def` types mirror the public ones field for field (serde's `remote`
//! derive builds the public type from them); the compiler checks that they match.

use serde::{Deserialize, Deserializer, Serializer};

use crate::{LispsmOptions, ParallelFade, TsmOptions, WarpError, XpsmOptions};

/// An `f32` that is `+inf` when unbounded (JSON has no infinity): serialized as
/// `None` when infinite, and `None` reads back as `+inf`.
pub(crate) mod infinite_as_none {
    use super::{Deserialize, Deserializer, Serializer};

    pub(crate) fn serialize<S: Serializer>(value: &f32, serializer: S) -> Result<S::Ok, S::Error> {
        if *value == f32::INFINITY {
            serializer.serialize_none()
        } else {
            serializer.serialize_some(value)
        }
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f32, D::Error> {
        Ok(Option::<f32>::deserialize(deserializer)?.unwrap_or(f32::INFINITY))
    }
}

#[derive(Deserialize)]
#[serde(remote = "ParallelFade", default = "ParallelFade::default")]
struct ParallelFadeDef {
    start_deg: f32,
    end_deg: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked with [`ParallelFade::is_valid`] ([`WarpError::InvalidOption`] otherwise).
    ParallelFade,
    ParallelFadeDef,
    |fade| if fade.is_valid() { Ok(()) } else { Err(WarpError::InvalidOption) }
);

#[derive(Deserialize)]
#[serde(remote = "LispsmOptions", default = "LispsmOptions::default")]
struct LispsmOptionsDef {
    reversed_z: bool,
    eta: f32,
    near_hint: f32,
    #[serde(with = "infinite_as_none")]
    far_hint: f32,
    fade: ParallelFade,
    strength_scale: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked as [`crate::lispsm`] checks it.
    LispsmOptions,
    LispsmOptionsDef,
    |options| options.check()
);

#[derive(Deserialize)]
#[serde(remote = "TsmOptions", default = "TsmOptions::default")]
struct TsmOptionsDef {
    reversed_z: bool,
    focus: f32,
    fade: ParallelFade,
    strength_scale: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked as [`crate::tsm`] checks it.
    TsmOptions,
    TsmOptionsDef,
    |options| options.check()
);

#[derive(Deserialize)]
#[serde(remote = "XpsmOptions", default = "XpsmOptions::default")]
struct XpsmOptionsDef {
    reversed_z: bool,
    epsilon_w: f32,
    coef: Option<f32>,
    miner_lamp_threshold: f32,
    strength_scale: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked as [`crate::xpsm`] checks it.
    XpsmOptions,
    XpsmOptionsDef,
    |options| options.validate()
);
