//! Per-frame builders of the warped spot and point techniques, timed in one run beside
//! the fits they refine: RTW over the spot fit (backward importance of a G-buffer's
//! worth of eye samples into a 256² map, warp tables, both reused across frames) and
//! the whole `shadowmap::fit` of it (which allocates its map and tables) against the
//! spot fit, again with a quarter of the samples turned away from the spot (two
//! importance maps measured); RTW over the IPSM paraboloid through `shadowmap::fit`
//! against the IPSM plan. Besides criterion's figures it prints each one's time per
//! call (the fastest of many short batches, see `support/timing.rs`) and its ratio to
//! its base fit.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds, fit_spot};
use shadowmap::paraboloid::{ConeFit, IpsmOptions, IpsmPlan};
use shadowmap::rtw::{EyeSample, ImportanceMap, ImportanceOptions, WarpMaps, WarpOptions};
use shadowmap::{FitInput, RtwPlan, Technique, fit};
use std::hint::black_box;

#[path = "support/timing.rs"]
mod timing;

/// Side of the importance map and warp tables (the default [`RtwPlan`]).
const SIDE: u32 = 256;
/// Eye samples per frame: a 320 x 180 G-buffer.
const SAMPLES: usize = 320 * 180;

/// A street-level camera, a spot ahead aimed back at it (dueling frusta), a ground
/// with a block of casters, and the ground points the camera sees.
struct Frame {
    camera: Camera,
    spot: Light,
    point: Light,
    scene: SceneBounds,
    samples: Vec<EyeSample>,
}

fn frame() -> Frame {
    let eye = Vec3::new(0.0, 1.8, 0.0);
    let camera = Camera::look_to(
        eye,
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 300.0),
    )
    .unwrap();
    let spot = Light::Spot {
        position: Vec3::new(0.0, 12.0, -60.0),
        direction: Vec3::new(0.0, -0.4, 1.0).normalize(),
        half_angle: 0.9,
        range: 200.0,
    };
    let ground = Aabb::new(
        Vec3::new(-200.0, -1.0, -200.0),
        Vec3::new(200.0, 0.0, 200.0),
    );
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(
            Vec3::new(-20.0, 0.0, -80.0),
            Vec3::new(20.0, 30.0, -20.0),
        )),
    );
    // Ground points on a grid of view directions, as a G-buffer would hold them.
    let samples = (0..SAMPLES)
        .filter_map(|i| {
            let (x, y) = ((i % 320) as f32 / 320.0, (i / 320) as f32 / 180.0);
            let dir = Vec3::new((x - 0.5) * 1.7, -0.02 - 0.5 * y, -1.0).normalize();
            let t = -eye.y / dir.y;
            let position = eye + dir * t;
            (t < 290.0).then_some(EyeSample {
                position,
                normal: Vec3::Y,
                eye_distance: t,
            })
        })
        .collect();
    Frame {
        camera,
        spot,
        point: Light::Point {
            position: Vec3::new(0.0, 12.0, -60.0),
            range: 200.0,
        },
        scene,
        samples,
    }
}

#[allow(clippy::print_stdout)] // The table is this bench's output.
fn spot(c: &mut Criterion) {
    let f = frame();
    let frustum = f.camera.frustum().unwrap();
    let spot_fit = || fit_spot(&f.spot, &frustum, Some(&f.scene), false).unwrap();
    let mut map = ImportanceMap::new(SIDE, SIDE).unwrap();
    let mut warps = WarpMaps::new(SIDE, SIDE).unwrap();
    let (importance, warp) = (ImportanceOptions::default(), WarpOptions::default());
    let mut spot_rtw = || {
        let base = spot_fit().transform;
        map.clear();
        map.accumulate_backward(&base, &f.samples, None, &importance)
            .unwrap();
        warps.build(&map, &warp).unwrap();
        warps.x_table()[SIDE as usize / 2]
    };
    let input = FitInput::new(&f.camera, &f.spot, f.scene, 1 << 20).with_eye_samples(&f.samples);
    let technique = Technique::SpotRtw(RtwPlan::default());
    let umbrella = || fit(&technique, &input).unwrap();
    // The same G-buffer with every fourth sample on a surface turned away from the
    // spot (facing the camera, the spot behind it): RTW then also accumulates every
    // sample's importance and measures both maps' strengths.
    let partly_lit: Vec<EyeSample> = f
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| EyeSample {
            normal: if i % 4 == 0 { Vec3::Z } else { s.normal },
            ..*s
        })
        .collect();
    let partly_lit_input =
        FitInput::new(&f.camera, &f.spot, f.scene, 1 << 20).with_eye_samples(&partly_lit);
    let umbrella_partly_lit = || fit(&technique, &partly_lit_input).unwrap();

    let bounds = shadowmap::depth_bounds_of(&f.camera, &f.samples);
    let ipsm = IpsmOptions::default().with_fit(ConeFit::Exact);
    let ipsm_plan = || IpsmPlan::new(&f.point, &f.camera, bounds, &ipsm).unwrap();
    let point_input = FitInput::new(&f.camera, &f.point, f.scene, 1 << 20)
        .with_eye_samples(&f.samples)
        .with_depth_bounds(bounds);
    let point_technique = Technique::PointRtw {
        ipsm,
        rtw: RtwPlan::default(),
    };
    let point_rtw = || fit(&point_technique, &point_input).unwrap();

    let spot_ns = timing::min_ns(spot_fit);
    let ipsm_ns = timing::min_ns(ipsm_plan);
    let rows = [
        ("spot fit", spot_ns, spot_ns, "spot fit"),
        (
            "spot RTW (reused map and tables)",
            timing::min_ns(&mut spot_rtw),
            spot_ns,
            "spot fit",
        ),
        (
            "spot RTW through shadowmap::fit",
            timing::min_ns(umbrella),
            spot_ns,
            "spot fit",
        ),
        (
            "the same, a quarter of samples unlit",
            timing::min_ns(umbrella_partly_lit),
            spot_ns,
            "spot fit",
        ),
        ("IPSM plan (exact cone)", ipsm_ns, ipsm_ns, "IPSM plan"),
        (
            "point RTW through shadowmap::fit",
            timing::min_ns(point_rtw),
            ipsm_ns,
            "IPSM plan",
        ),
    ];
    println!(
        "\nspot and point builders, {} eye samples, {SIDE}² importance:",
        f.samples.len()
    );
    for (name, ns, base, base_name) in rows {
        println!(
            "  {name:<36} {:>10.2} us  {:>8.1}x {base_name}",
            ns / 1e3,
            ns / base
        );
    }

    let mut g = c.benchmark_group("spot");
    g.bench_function("spot_fit", |b| b.iter(|| black_box(spot_fit())));
    g.bench_function("spot_rtw", |b| b.iter(|| black_box(spot_rtw())));
    g.bench_function("spot_rtw_fit", |b| b.iter(|| black_box(umbrella())));
    g.bench_function("spot_rtw_fit_partly_lit", |b| {
        b.iter(|| black_box(umbrella_partly_lit()));
    });
    g.bench_function("ipsm_plan", |b| b.iter(|| black_box(ipsm_plan())));
    g.bench_function("point_rtw_fit", |b| b.iter(|| black_box(point_rtw())));
    g.finish();
}

criterion_group!(benches, spot);
criterion_main!(benches);
