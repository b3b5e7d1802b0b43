//! Continuity and quality of every warp as the light turns through the whole range
//! of angles to the view, the near-parallel bands included.

use glam::Vec3;
use shadowmap_frustum::{Aabb, Camera, CascadeSplits, Projection, ShadowTransform, SplitScheme};
use shadowmap_warp::{
    FocusScene, LispsmOptions, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};

const RES: u32 = 2048;
const FOV: f32 = 1.0;
const HEIGHT_PX: f32 = 1080.0;
const NAMES: [&str; 5] = ["uniform", "lispsm", "tsm", "xpsm", "warped_cascades"];

struct Rig {
    camera: Camera,
    scene: FocusScene,
    /// A near and a far ground point in view.
    fixed: [Vec3; 2],
    /// Ground points spread over the view frustum.
    grid: Vec<Vec3>,
}

fn rig(height: f32, slope: f32) -> Rig {
    let eye = Vec3::new(0.0, height, 0.0);
    let forward = Vec3::new(0.0, slope, -1.0).normalize();
    let camera = Camera::look_to(
        eye,
        forward,
        Vec3::Y,
        Projection::perspective(FOV, 16.0 / 9.0, 0.5, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-800.0, -1.0, -800.0), Vec3::new(800.0, 0.0, 50.0));
    let casters = ground.union(&Aabb::new(
        Vec3::new(-800.0, 0.0, -800.0),
        Vec3::new(800.0, 12.0, 50.0),
    ));
    // Ground points along view rays through the lower half of the image.
    let ground_hit = |sx: f32, sy: f32| -> Option<Vec3> {
        let t = (FOV * 0.5).tan();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let dir = (forward + right * (sx * t * 16.0 / 9.0) + up * (sy * t)).normalize();
        let d = -eye.y / dir.y;
        let p = eye + dir * d;
        (dir.y < 0.0 && (p - eye).dot(forward) < 290.0 && (p - eye).dot(forward) > 0.6).then_some(p)
    };
    let mut grid = Vec::new();
    for i in 0..8 {
        for sx in [-0.9f32, 0.0, 0.9] {
            let sy = -0.98 + 0.95 * (i as f32 / 7.0);
            if let Some(p) = ground_hit(sx, sy) {
                grid.push(p);
            }
        }
    }
    let depth = |p: &Vec3| (*p - eye).dot(forward);
    let near = ground_hit(0.0, -0.95).unwrap();
    let far = *grid
        .iter()
        .max_by(|a, b| depth(a).total_cmp(&depth(b)))
        .unwrap();
    Rig {
        camera,
        scene: FocusScene::new(ground, casters),
        fixed: [near, far],
        grid,
    }
}

fn build(r: &Rig, light: Vec3) -> [ShadowTransform; 4] {
    let (c, s) = (&r.camera, &r.scene);
    [
        uniform_focused(c, light, s, &UniformOptions::default()).unwrap(),
        lispsm(c, light, s, &LispsmOptions::default())
            .unwrap()
            .transform,
        tsm(c, light, s, &TsmOptions::default()).unwrap().transform,
        xpsm(c, light, s, &XpsmOptions::default())
            .unwrap()
            .transform,
    ]
}

/// Texel size at the near and the far point, each in the warped cascade that holds
/// its view depth.
fn cascade_sizes(r: &Rig, light: Vec3) -> [f32; 2] {
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.7 }, 4, 0.5, 300.0).unwrap();
    let c = warped_cascades(
        &r.camera,
        light,
        &r.scene,
        &splits,
        &[0.0; 4],
        &LispsmOptions::default(),
    )
    .unwrap();
    r.fixed.map(|p| {
        let d = (p - r.camera.eye()).dot(r.camera.forward());
        let k = c.cascades.iter().position(|k| d <= k.far).unwrap();
        c.cascades[k]
            .shadow
            .unwrap()
            .transform
            .texel_world_size(p, RES)
            .unwrap()
    })
}

/// Texel footprint over pixel footprint (orientation-free, so the parameterization
/// alone: the perspective-only error of a surface facing the bisector).
fn error(r: &Rig, t: &ShadowTransform, p: Vec3) -> f32 {
    let texel = t.texel_world_size(p, RES).unwrap();
    let dist = (p - r.camera.eye()).length();
    let pixel = 2.0 * dist * (FOV * 0.5).tan() / HEIGHT_PX;
    texel / pixel
}

/// The light turns from the view direction (0°) to its opposite (180°) in the plane
/// of the view and up vectors, on the downward side (light from behind and above the
/// viewer at small angles, a low sun ahead near 180°), in 0.01° steps.
fn light_at(r: &Rig, deg: f64) -> Vec3 {
    let f = r.camera.forward().as_dvec3();
    let down = f.cross(glam::DVec3::Y).cross(f).normalize() * -1.0;
    let down = if down.y > 0.0 { -down } else { down };
    let a = deg.to_radians();
    (f * a.cos() + down * a.sin()).as_vec3()
}

#[test]
fn light_sweep_is_continuous_and_never_worse_than_uniform() {
    let steps = 18_000;
    // A level camera (a low sun ahead near 180°) and one looking down.
    for (height, slope) in [(2.0f32, 0.0f32), (30.0, -0.25)] {
        let r = rig(height, slope);
        assert!(r.grid.len() >= 12);
        let mut prev: Option<[[f32; 2]; 5]> = None;
        for i in 0..=steps {
            let deg = 180.0 * f64::from(i) / f64::from(steps);
            let light = light_at(&r, deg);
            if light.y > -(2f32.to_radians().sin()) {
                // Light grazing the ground or from below it: no receiver is lit.
                prev = None;
                continue;
            }
            let ts = build(&r, light);
            let mut sizes = [[0f32; 2]; 5];
            for k in 0..4 {
                sizes[k] = r.fixed.map(|p| ts[k].texel_world_size(p, RES).unwrap());
            }
            sizes[4] = cascade_sizes(&r, light);
            if let Some(pr) = prev {
                for k in 0..5 {
                    for j in 0..2 {
                        let ratio = sizes[k][j] / pr[k][j];
                        if (ratio - 1.0).abs() > 0.02 {
                            eprintln!("STEP {} {deg:.2} {height} {j} {ratio}", NAMES[k]);
                        }
                        assert!(
                            (ratio - 1.0).abs() <= 0.02,
                            "{} at {deg:.2}°, height {height}: texel size at {:?} changed by {ratio}",
                            NAMES[k],
                            r.fixed[j]
                        );
                    }
                }
            }
            prev = Some(sizes);
            // The quality bar, every 0.1°.
            if i % 10 == 0 {
                let worst =
                    ts.map(|t| r.grid.iter().map(|p| error(&r, &t, *p)).fold(0.0, f32::max));
                for k in 1..4 {
                    assert!(
                        worst[k] <= 1.1 * worst[0],
                        "{} at {deg:.2}°, height {height}: max error {} vs uniform {}",
                        NAMES[k],
                        worst[k],
                        worst[0]
                    );
                }
            }
        }
    }
}
