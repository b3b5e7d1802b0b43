//! `Deserialize` for [`WarpMaps`]: the payload's densities must be ones a build can
//! produce, and its tables must be exactly the ones [`build_table`] makes from them,
//! so a deserialized value is indistinguishable from a built one.

use alloc::vec::Vec;

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use super::{MIN_FLOOR, WarpMaps, build_table};
use crate::RtwError;
use crate::importance::check_value;

/// The serialized form of [`WarpMaps`] (every field but the build scratch buffer).
#[derive(Deserialize)]
struct WarpMapsData {
    x: Vec<f32>,
    y: Vec<f32>,
    col_max: Vec<f32>,
    row_max: Vec<f32>,
    density_x: Vec<f32>,
    density_y: Vec<f32>,
    has_history: bool,
    fallback: [bool; 2],
}

impl<'de> Deserialize<'de> for WarpMaps {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let data = WarpMapsData::deserialize(deserializer)?;
        let maps = from_data(&data).map_err(D::Error::custom)?;
        if maps.x != data.x || maps.y != data.y {
            return Err(D::Error::custom(
                "warp tables do not match the densities they are built from",
            ));
        }
        Ok(maps)
    }
}

/// Warp maps of the payload's size with its collapsed maxima and densities, and the
/// tables rebuilt from those densities.
fn from_data(data: &WarpMapsData) -> Result<WarpMaps, RtwError> {
    let side = |len: usize| u32::try_from(len).map_err(|_| RtwError::MapTooLarge);
    let mut maps = WarpMaps::new(side(data.x.len())?, side(data.y.len())?)?;
    for (src, dst) in [
        (&data.col_max, &mut maps.col_max),
        (&data.row_max, &mut maps.row_max),
        (&data.density_x, &mut maps.density_x),
        (&data.density_y, &mut maps.density_y),
    ] {
        if src.len() != dst.len() {
            return Err(RtwError::SizeMismatch {
                expected: dst.len(),
                got: src.len(),
            });
        }
        src.iter().try_for_each(|&v| check_value(v))?;
        dst.copy_from_slice(src);
    }
    // A build floors every density at `MIN_FLOOR` or more and caps it at 1.
    let density_ok = |d: &[f32]| d.iter().all(|v| (MIN_FLOOR..=1.0).contains(v));
    if !(density_ok(&maps.density_x) && density_ok(&maps.density_y)) {
        return Err(RtwError::InvalidOption);
    }
    build_table(&maps.density_x, &mut maps.x);
    build_table(&maps.density_y, &mut maps.y);
    maps.has_history = data.has_history;
    maps.fallback = data.fallback;
    Ok(maps)
}
