//! `Deserialize` for the options and the importance map, each payload checked as the
//! crate's own constructors and builders check it, so a bad one gives an error
//! instead of an invalid value; missing option fields take their defaults. (The warp
//! maps' impl lives beside their private tables, in the `warp` module.)
//!
//! The private `*Def` types mirror the public ones field for field (serde's `remote`
//! derive builds the public type from them); the compiler checks that they match.

use alloc::vec::Vec;

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::{ImportanceMap, ImportanceOptions, WarpOptions};

#[derive(Deserialize)]
#[serde(remote = "ImportanceOptions", default = "ImportanceOptions::default")]
struct ImportanceOptionsDef {
    reference_distance: f32,
    min_distance: f32,
    distance_exponent: f32,
    orientation_weight: f32,
    edge_weight: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked with [`ImportanceOptions::validate`].
    ImportanceOptions,
    ImportanceOptionsDef,
    |options| options.validate()
);

#[derive(Deserialize)]
#[serde(remote = "WarpOptions", default = "WarpOptions::default")]
struct WarpOptionsDef {
    blur_radius: u32,
    floor: f32,
    temporal: f32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked with [`WarpOptions::validate`].
    WarpOptions,
    WarpOptionsDef,
    |options| options.validate()
);

/// The serialized form of an [`ImportanceMap`]: its size and its cells, row-major.
#[derive(Deserialize)]
struct ImportanceMapData {
    width: u32,
    height: u32,
    cells: Vec<f32>,
}

/// Built with [`ImportanceMap::new`] and [`ImportanceMap::copy_from_slice`]: the size
/// within bounds, one cell per texel, every cell finite and non-negative.
impl<'de> Deserialize<'de> for ImportanceMap {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let data = ImportanceMapData::deserialize(deserializer)?;
        let mut map = ImportanceMap::new(data.width, data.height).map_err(D::Error::custom)?;
        map.copy_from_slice(&data.cells).map_err(D::Error::custom)?;
        Ok(map)
    }
}
