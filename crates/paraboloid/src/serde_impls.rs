//! `Deserialize` for the options, each payload checked as the builders check it, so
//! a bad one gives an error instead of an invalid value; missing fields take their
//! defaults.
//!
//! The private `*Def` types mirror the public ones field for field (serde's `remote`
//! derive builds the public type from them); the compiler checks that they match.

use glam::Vec3;
use serde::Deserialize;

use crate::{ConeFit, IpsmOptions, SubdivisionOptions};

#[derive(Deserialize)]
#[serde(remote = "IpsmOptions", default = "IpsmOptions::default")]
struct IpsmOptionsDef {
    fit: ConeFit,
    near: f32,
    margin: f32,
    max_single_half_angle: f32,
    up_hint: Vec3,
    reversed_z: bool,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked as [`IpsmPlan::new`](crate::IpsmPlan::new) checks it.
    IpsmOptions,
    IpsmOptionsDef,
    |options| options.validate()
);

#[derive(Deserialize)]
#[serde(remote = "SubdivisionOptions", default = "SubdivisionOptions::default")]
struct SubdivisionOptionsDef {
    resolution: u32,
    tolerance_texels: f32,
    max_segments: u32,
}

shadowmap_frustum::__deserialize_checked!(
    /// Checked as [`subdivide_triangle`](crate::subdivide_triangle) checks it.
    SubdivisionOptions,
    SubdivisionOptionsDef,
    |options| options.validate()
);
