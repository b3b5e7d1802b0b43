//! Regressions from the quality report's random sweep: cameras and lights where a
//! warp's formula strength (LiSPSM's `n_opt`, TSM's 80% rule, XPSM's `coef`) made
//! the warp several times worse than the uniform fit. Each case is measured by the
//! error prediction of `shadowmap-frustum` ([`predict_error`]: the 95th percentile
//! of the aliasing error over a grid of view rays stopped at the receivers' box),
//! which knows nothing of how the warps choose their strength.

use glam::Vec3;
use shadowmap_frustum::{
    Aabb, Camera, PredictOptions, Projection, SceneBounds, ShadowTransform, predict_error,
};
use shadowmap_warp::{
    LispsmOptions, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm, uniform_focused, xpsm,
};

struct Case {
    what: &'static str,
    eye: Vec3,
    forward: Vec3,
    near: f32,
    far: f32,
    light: Vec3,
    scene: Aabb,
}

/// The 2 km ground and buildings up to 58 m of the city block.
const CITY: Aabb = Aabb {
    min: Vec3::new(-1000.0, 0.0, -1000.0),
    max: Vec3::new(1000.0, 58.41394, 1000.0),
};
/// The fence's 2 km ground with a 4 m wall.
const FENCE: Aabb = Aabb {
    min: Vec3::new(-1000.0, 0.0, -1000.0),
    max: Vec3::new(1000.0, 4.0, 1000.0),
};
/// A 10 x 3 x 8 m room seen from inside.
const ROOM: Aabb = Aabb {
    min: Vec3::new(-5.0, 0.0, -4.0),
    max: Vec3::new(5.0, 3.0, 4.0),
};

const CASES: [Case; 6] = [
    Case {
        what: "camera 33 m up in a 2 km scene, light 14 degrees off the view (XPSM 61x, LiSPSM 11x)",
        eye: Vec3::new(7.1513143, 32.667534, 934.70056),
        forward: Vec3::new(-0.8813029, -0.40513027, 0.24325855),
        near: 0.18427484,
        far: 3394.8364,
        light: Vec3::new(-0.9661583, -0.24457778, 0.08197478),
        scene: CITY,
    },
    Case {
        what: "camera 1.2 m up looking level along a 2 km ground (LiSPSM 5x, XPSM 9x)",
        eye: Vec3::new(-74.982475, 1.1910285, -871.7527),
        forward: Vec3::new(-0.99882996, -0.04625124, -0.01412604),
        near: 0.3279298,
        far: 3394.116,
        light: Vec3::new(-0.8124699, -0.2792389, 0.5117795),
        scene: FENCE,
    },
    Case {
        what: "camera 1.3 m up looking 45 degrees down (XPSM's miner's-lamp fit widened by the far caster corners)",
        eye: Vec3::new(644.9004, 1.3365512, -240.44812),
        forward: Vec3::new(-0.69805026, -0.71478295, 0.042558398),
        near: 0.4142555,
        far: 3394.116,
        light: Vec3::new(-0.08454703, -0.24263023, -0.9664276),
        scene: FENCE,
    },
    Case {
        what: "inside a room looking at a wall, light from above (TSM 12x)",
        eye: Vec3::new(-1.6149194, 1.3561271, -0.4394221),
        forward: Vec3::new(-0.8113596, 0.014456095, -0.5843686),
        near: 0.12194261,
        far: 15.783536,
        light: Vec3::new(-0.2814301, -0.9395009, -0.19528198),
        scene: ROOM,
    },
    Case {
        what: "inside a room looking down at the floor and a wall the light grazes (LiSPSM 5x, XPSM 7x)",
        eye: Vec3::new(1.6396676, 1.4681845, 2.5766923),
        forward: Vec3::new(-0.8419597, -0.52553725, -0.12212473),
        near: 0.11838343,
        far: 15.783536,
        light: Vec3::new(-0.11083921, -0.99353665, 0.024487047),
        scene: ROOM,
    },
    Case {
        what: "inside a room facing a wall lit from behind the camera, the floor lit at 3.4 degrees (XPSM 1.61x, LiSPSM 1.55x)",
        eye: Vec3::new(-2.4356012, 1.538165, 1.5955052),
        forward: Vec3::new(0.49721867, 0.076921076, 0.86420876),
        near: 0.18294066,
        far: 15.783536,
        light: Vec3::new(0.5886504, -0.057770487, 0.80632085),
        scene: ROOM,
    },
];

fn p95(camera: &Camera, scene: &Aabb, t: &ShadowTransform) -> f64 {
    predict_error(camera, scene, t, 2048, &PredictOptions::default())
        .unwrap()
        .expect("the rays meet the receivers")
        .percentile
}

#[test]
fn warps_are_never_predicted_worse_than_uniform_on_the_sweep_failures() {
    for c in &CASES {
        let camera = Camera::look_to(
            c.eye,
            c.forward,
            Vec3::Y,
            Projection::perspective(60f32.to_radians(), 16.0 / 9.0, c.near, c.far),
        )
        .unwrap();
        let scene = SceneBounds::whole(c.scene);
        let uniform =
            uniform_focused(&camera, c.light, &scene, &UniformOptions::default()).unwrap();
        let base = p95(&camera, &c.scene, &uniform);
        let warps = [
            (
                "lispsm",
                lispsm(&camera, c.light, &scene, &LispsmOptions::default())
                    .unwrap()
                    .transform,
            ),
            (
                "tsm",
                tsm(&camera, c.light, &scene, &TsmOptions::default())
                    .unwrap()
                    .transform,
            ),
            (
                "xpsm",
                xpsm(&camera, c.light, &scene, &XpsmOptions::default())
                    .unwrap()
                    .transform,
            ),
        ];
        for (name, t) in warps {
            let m = p95(&camera, &c.scene, &t);
            assert!(
                m <= 1.1 * base,
                "{name}, {}: predicted p95 {m:.3} vs uniform {base:.3}",
                c.what
            );
        }
    }
}
