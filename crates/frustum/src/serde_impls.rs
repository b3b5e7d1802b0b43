//! `Deserialize` for the types whose values are checked: each payload goes through the
//! type's own validation, so a bad one gives an error instead of an invalid value.
//!
//! The private `*Def` types mirror the public ones field for field (serde's `remote`
//! derive builds the public type from them); the compiler checks that they match.

/// `Deserialize` for a type through its private serde `remote` mirror, then a check:
/// `__deserialize_checked!(Type, TypeDef, |value| value.validate())` reads a `Type` with
/// `TypeDef`'s derived code and turns an `Err` of the check (any `Display` error) into
/// the deserializer's error. Shared by the `serde` features of the `shadowmap` crates.
#[doc(hidden)]
#[macro_export]
macro_rules! __deserialize_checked {
    ($(#[$meta:meta])* $ty:ty, $def:ty, |$value:ident| $check:expr) => {
        $(#[$meta])*
        impl<'de> ::serde::Deserialize<'de> for $ty {
            fn deserialize<D: ::serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let $value = <$def>::deserialize(deserializer)?;
                $check
                    .map(|()| $value)
                    .map_err(<D::Error as ::serde::de::Error>::custom)
            }
        }
    };
}

use arrayvec::ArrayVec;
use glam::{Mat4, Vec3};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::{Camera, CascadeSplits, Light, MAX_CASCADES, PredictOptions, Projection, SplitScheme};

#[derive(Deserialize)]
#[serde(remote = "Camera")]
struct CameraDef {
    world_from_view: Mat4,
    projection: Projection,
    reversed_z: bool,
}

crate::__deserialize_checked!(
    /// Checked with [`Camera::validate`].
    Camera,
    CameraDef,
    |camera| camera.validate()
);

#[derive(Deserialize)]
#[serde(remote = "Light")]
enum LightDef {
    Directional {
        direction: Vec3,
    },
    Spot {
        position: Vec3,
        direction: Vec3,
        half_angle: f32,
        range: f32,
    },
    Point {
        position: Vec3,
        range: f32,
    },
}

crate::__deserialize_checked!(
    /// Checked with [`Light::validate`].
    Light,
    LightDef,
    |light| light.validate()
);

#[derive(Deserialize)]
#[serde(remote = "PredictOptions", default = "PredictOptions::default")]
struct PredictOptionsDef {
    viewport_height: u32,
    grid_columns: u32,
    grid_rows: u32,
    percentile: f64,
    light_direction: Option<Vec3>,
    light_position: Option<Vec3>,
    depth_range: Option<(f32, f32)>,
}

crate::__deserialize_checked!(
    /// Missing fields take their defaults; the result is checked as [`crate::predict_error`]
    /// checks it.
    PredictOptions,
    PredictOptionsDef,
    |options| options.check()
);

/// The serialized form of [`CascadeSplits`]: its depths and blend band.
#[derive(Deserialize)]
struct CascadeSplitsData {
    depths: ArrayVec<f32, { MAX_CASCADES + 1 }>,
    overlap: f32,
}

/// Rebuilt through [`CascadeSplits::new`] (the interior depths as a custom scheme)
/// and [`CascadeSplits::with_overlap`], so every invariant of the constructors holds.
impl<'de> Deserialize<'de> for CascadeSplits {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let data = CascadeSplitsData::deserialize(deserializer)?;
        let (&near, rest) = data
            .depths
            .split_first()
            .ok_or_else(|| D::Error::custom("cascade splits need at least two depths"))?;
        let (&far, interior) = rest
            .split_last()
            .ok_or_else(|| D::Error::custom("cascade splits need at least two depths"))?;
        let scheme = SplitScheme::Custom(interior.iter().copied().collect());
        CascadeSplits::new(&scheme, rest.len(), near, far)
            .and_then(|splits| splits.with_overlap(data.overlap))
            .map_err(D::Error::custom)
    }
}
