//! Prints a real 4-cascade plan for a default camera and sun: split depths, texel
//! sizes in world units, depth ranges and matrices. README's main command until the
//! `compare` report exists.
//!
//! ```text
//! cargo run --release --example cascade_plan
//! ```
#![allow(clippy::print_stdout)]

use glam::Vec3;
use shadowmap::frustum::{
    Aabb, Camera, CascadeOptions, CascadeSet, CascadeSplits, FrustumError, Projection, SceneBounds,
    SplitScheme,
};

fn main() -> Result<(), FrustumError> {
    let camera = Camera::look_to(
        Vec3::new(0.0, 1.8, 0.0),
        Vec3::new(0.0, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 500.0),
    )?;
    let sun = Vec3::new(-0.4, -1.0, -0.6);
    let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 500.0)?
        .with_overlap(0.1)?;
    let scene = SceneBounds {
        receivers: Aabb::new(
            Vec3::new(-600.0, -1.0, -600.0),
            Vec3::new(600.0, 0.0, 600.0),
        ),
        casters: Aabb::new(
            Vec3::new(-600.0, -1.0, -600.0),
            Vec3::new(600.0, 120.0, 600.0),
        ),
    };
    let options = CascadeOptions::default()
        .with_resolution(2048)
        .with_reversed_z(true)
        .with_scene(Some(scene));
    let set = CascadeSet::fit(&camera, sun, &splits, &options)?;

    println!("shadowmap cascade plan");
    println!(
        "  camera: eye {} looking {}, fovY 60 deg, 16:9, near 0.1, far 500",
        camera.eye(),
        camera.forward()
    );
    println!("  light:  directional, travelling {}", sun.normalize());
    println!(
        "  splits: practical, lambda 0.5, 10% blend band: {:?}",
        splits.depths()
    );
    println!(
        "  fit:    stable (rotation-invariant size, whole-texel motion), 2048^2, reversed-Z\n"
    );
    println!(
        "{:>3} {:>20} {:>14} {:>24} {:>24}",
        "#", "view depth", "texel (world)", "light depth (near, far)", "caster depth"
    );
    for (i, c) in set.cascades.iter().enumerate() {
        let casters = c
            .caster_depth
            .map_or_else(|| "-".to_owned(), |(a, b)| format!("({a:.1}, {b:.1})"));
        println!(
            "{i:>3} {:>20} {:>14.5} {:>24} {:>24}",
            format!("{:.2} .. {:.2}", c.view_depth.0, c.view_depth.1),
            c.texel_world_size,
            format!("({:.1}, {:.1})", c.light_depth.0, c.light_depth.1),
            casters,
        );
    }
    for (i, c) in set.cascades.iter().enumerate() {
        println!("\ncascade {i} clip_from_world (columns):");
        for col in c.transform.clip_from_world.to_cols_array_2d() {
            println!(
                "  [{:>12.6} {:>12.6} {:>12.6} {:>12.6}]",
                col[0], col[1], col[2], col[3]
            );
        }
    }
    Ok(())
}
