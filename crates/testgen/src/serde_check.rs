//! Checks for the `serde` features of the `shadowmap` crates: JSON round trips and
//! rejected payloads.

use core::fmt::{Debug, Display};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// `value` through JSON and back: equal. Panics with the JSON otherwise (also when
/// `value` holds a NaN or an infinity, which JSON cannot carry).
pub fn round_trip<T: Serialize + DeserializeOwned + PartialEq + Debug>(value: &T) {
    let json = serde_json::to_string(value).expect("serializes");
    let back: T = serde_json::from_str(&json)
        .unwrap_or_else(|e| panic!("{value:?} -> {json} does not read back: {e}"));
    assert_eq!(&back, value, "through {json}");
}

/// Deserializing `json` as `T` fails (a payload of the wrong shape).
pub fn rejects<T: DeserializeOwned + Debug>(json: &str) {
    let result = serde_json::from_str::<T>(json);
    assert!(result.is_err(), "{json} gave {result:?}");
}

/// Deserializing `json` as `T` fails with the message of the typed error `expected`
/// (a payload that the type's validation refuses).
pub fn rejects_with<T: DeserializeOwned + Debug>(json: &str, expected: impl Display) {
    match serde_json::from_str::<T>(json) {
        Ok(value) => panic!("{json} gave {value:?}"),
        Err(e) => assert!(
            e.to_string().contains(&expected.to_string()),
            "{json}: {e}, expected {expected}"
        ),
    }
}
