//! `Deserialize` for the types whose values are checked: each payload goes through the
//! type's own validation, so a bad one gives an error instead of an invalid value.
//!
//! The private `*Def` types mirror the public ones field for field (serde's `remote`
//! derive builds the public type from them); the compiler checks that they match.

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

/// Checked with [`Camera::validate`].
impl<'de> Deserialize<'de> for Camera {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let camera = CameraDef::deserialize(deserializer)?;
        camera.validate().map_err(D::Error::custom)?;
        Ok(camera)
    }
}

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

/// Checked with [`Light::validate`].
impl<'de> Deserialize<'de> for Light {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let light = LightDef::deserialize(deserializer)?;
        light.validate().map_err(D::Error::custom)?;
        Ok(light)
    }
}

#[derive(Deserialize)]
#[serde(remote = "PredictOptions", default = "PredictOptions::default")]
struct PredictOptionsDef {
    viewport_height: u32,
    grid_columns: u32,
    grid_rows: u32,
    percentile: f64,
}

/// Missing fields take their defaults; the result is checked as [`crate::predict_error`]
/// checks it.
impl<'de> Deserialize<'de> for PredictOptions {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let options = PredictOptionsDef::deserialize(deserializer)?;
        options.check().map_err(D::Error::custom)?;
        Ok(options)
    }
}

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
