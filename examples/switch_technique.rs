//! An engine's view of technique switching: a camera walks a path over a city-sized
//! ground plane; each frame the shadow technique is a setting (a `Technique` value)
//! that changes as the player flips through the options, and `auto` keeps its choice
//! across frames with a `TechniqueSelector`. Prints what was fitted, its layers and
//! the CPU time of the fit. GPU-free.
//!
//! ```text
//! cargo run --release --example switch_technique
//! ```
#![allow(clippy::print_stdout)]

use std::time::Instant;

use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds, TechniqueSelector};
use shadowmap::paraboloid::ConeFit;
use shadowmap::rtw::EyeSample;
use shadowmap::{FitError, FitInput, Technique, depth_bounds_of, fit_with_selector};

/// The frame's visible surfaces, as a G-buffer would give them: a grid of ground
/// points in front of the camera.
fn eye_samples(camera: &Camera) -> Vec<EyeSample> {
    let (eye, forward) = (camera.eye(), camera.forward());
    let right = forward.cross(Vec3::Y).normalize_or_zero();
    let mut out = Vec::new();
    for i in 1..=24 {
        for j in -8..=8 {
            let depth = 2.0 * (i as f32).powf(1.5);
            let p = eye + forward * depth + right * (j as f32 * 0.05 * depth);
            let p = Vec3::new(p.x, 0.0, p.z);
            out.push(EyeSample {
                position: p,
                normal: Vec3::Y,
                eye_distance: p.distance(eye),
            });
        }
    }
    out
}

fn main() -> Result<(), FitError> {
    let settings = [
        Technique::UniformFocused(Default::default()),
        Technique::StableCascades(Default::default()),
        Technique::Lispsm(Default::default()),
        Technique::Xpsm(Default::default()),
        Technique::Tsm(Default::default()),
        Technique::WarpedCascades {
            plan: Default::default(),
            lispsm: Default::default(),
        },
        Technique::Rtw(Default::default()),
        Technique::Auto(Default::default()),
        Technique::Auto(Default::default()),
        Technique::Auto(Default::default()),
    ];
    let ground = Aabb::new(Vec3::new(-500.0, 0.0, -500.0), Vec3::new(500.0, 1.0, 500.0));
    let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 60.0 * Vec3::Y));
    let sun = Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.6),
    };
    let mut selector = TechniqueSelector::new();
    println!("frame  setting          fitted           layers  side   fit time");
    for (frame, technique) in settings.iter().enumerate() {
        // The camera turns and climbs along its path.
        let t = frame as f32 / settings.len() as f32;
        let heading = t * core::f32::consts::PI;
        let camera = Camera::look_to(
            Vec3::new(40.0 * t, 1.8 + 30.0 * t * t, 0.0),
            Vec3::new(heading.sin(), -0.15 - 0.4 * t, -heading.cos()),
            Vec3::Y,
            Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 500.0),
        )?;
        let samples = eye_samples(&camera);
        let input = FitInput::new(&camera, &sun, scene, 2048 * 2048)
            .with_eye_samples(&samples)
            .with_depth_bounds(depth_bounds_of(&camera, &samples));
        let start = Instant::now();
        let shadow = fit_with_selector(technique, &input, &mut selector)?;
        let elapsed = start.elapsed();
        println!(
            "{frame:>5}  {:<15}  {:<15}  {:>6}  {:>4}  {:>7.1} us",
            technique.name(),
            shadow.technique().name(),
            shadow.layers(),
            shadow.layer_side(),
            elapsed.as_secs_f64() * 1e6,
        );
    }
    // A point light: the same call with another value.
    let lamp = Light::Point {
        position: Vec3::new(3.0, 4.0, -10.0),
        range: 40.0,
    };
    let camera = Camera::look_to(
        Vec3::new(0.0, 1.8, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 100.0),
    )?;
    let input = FitInput::new(&camera, &lamp, scene, 2048 * 2048);
    for technique in [
        Technique::Dpsm(Default::default()),
        Technique::Ipsm(Default::default()),
        Technique::Ipsm(shadowmap::paraboloid::IpsmOptions::default().with_fit(ConeFit::Paper)),
    ] {
        let start = Instant::now();
        let shadow = fit_with_selector(&technique, &input, &mut selector)?;
        println!(
            "point  {:<15}  {:<15}  {:>6}  {:>4}  {:>7.1} us",
            technique.name(),
            shadow.technique().name(),
            shadow.layers(),
            shadow.layer_side(),
            start.elapsed().as_secs_f64() * 1e6,
        );
    }
    Ok(())
}
