//! Every per-frame builder timed in one run, beside our transcription of Bevy's
//! per-frame directional cascade math (`benches/support/bevy_like.rs`, shared with
//! `cascades_vs_bevy`): uniform focused, stable and tight 4-cascade fits, LiSPSM,
//! XPSM, TSM, four warped cascades, the spot fit and its LiSPSM and TSM warps, the
//! IPSM plan with the paper's and the exact cone, RTW warp tables from a 1-D
//! importance, and camera validation; the
//! cascade fits and the four single-frustum warps also from a camera validated once
//! per frame (`ValidCamera`), and the focus body alone with each warp fitted from a
//! body built once (`FocusBody`: what a frame pays per technique once the body and
//! its probe points, cast by the first warp fitted from it, are shared), LiSPSM from
//! a body built in the call (`lispsm_valid`: a frame with one warped light), the IPSM
//! plan from the validated camera (`ipsm_plan_exact_cone_valid`), the body and
//! its four fits under a sun 2° above the horizon (`focus_body_valid_all_4_low_sun`:
//! the warps then choose on the probe's perspective set), and the
//! 4-cascade fits refitted in place into a set kept across calls
//! (`CascadeSet::refit_valid`), and the held stable fit (`CascadeSet::fit_with_state`,
//! maps fitted to slice ∩ receivers with their sizes kept in a state across calls).
//! Besides criterion's figures it prints one table: each
//! builder's time per call (the fastest of many short batches, see
//! `support/timing.rs`) and its ratio to Bevy's 4 cascades. `BUILDERS_ONLY` runs one
//! builder for instruction counting (see `only`).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Quat, Vec3};
use shadowmap::frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, CascadeState, DepthBounds,
    Light, Projection, SceneBounds, SplitScheme, ValidCamera, fit_spot,
};
use shadowmap::paraboloid::{ConeFit, IpsmOptions, IpsmPlan};
use shadowmap::rtw::{ImportanceMap, WarpMaps, WarpOptions};
use shadowmap::warp::{
    FocusBody, LispsmOptions, SpotWarpKind, SpotWarpOptions, TsmOptions, UniformOptions,
    XpsmOptions, lispsm, spot_warp, tsm, uniform_focused, warped_cascades, xpsm,
};
use std::hint::black_box;
use std::time::Duration;

#[allow(dead_code)] // Only the cascades bench reads every output field and constant.
#[path = "support/bevy_like.rs"]
mod bevy_like;
#[path = "support/timing.rs"]
mod timing;

/// Everything the builders read: Bevy's default camera and cascade configuration, a
/// ground plane with a block of casters, a spot and a point light.
struct Frame {
    camera: Camera,
    light: Vec3,
    /// A sun 2° above the horizon: no face of the receivers' box is lit enough to
    /// trust, so the warps choose on the probe's perspective set.
    low_sun: Vec3,
    light_rotation: Quat,
    far_bounds: [f32; bevy_like::CASCADES],
    splits: CascadeSplits,
    stable: CascadeOptions,
    tight: CascadeOptions,
    scene: SceneBounds,
    spot: Light,
    point: Light,
    bounds: DepthBounds,
    importance: ImportanceMap,
    valid: ValidCamera,
    /// The focus body of `valid`, built once (the per-frame share of every warp).
    body: FocusBody,
}

fn frame() -> Frame {
    use bevy_like::{CASCADES, MAP_SIZE, MAX_DISTANCE, MIN_DISTANCE, OVERLAP};
    let camera = Camera::look_to(
        Vec3::new(10.0, 1.8, 3.0),
        Vec3::new(0.3, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(core::f32::consts::FRAC_PI_4, 16.0 / 9.0, 0.1, 1000.0),
    )
    .unwrap();
    let light = Vec3::new(-0.4, -1.0, -0.6).normalize();
    let far_bounds = bevy_like::far_bounds();
    let interior = SplitScheme::Custom(far_bounds[..CASCADES - 1].iter().copied().collect());
    let splits = CascadeSplits::new(&interior, CASCADES, MIN_DISTANCE, MAX_DISTANCE)
        .unwrap()
        .with_overlap(OVERLAP)
        .unwrap();
    let stable = CascadeOptions::default().with_resolution(MAP_SIZE as u32);
    let ground = Aabb::new(
        Vec3::new(-600.0, -1.0, -600.0),
        Vec3::new(600.0, 0.0, 600.0),
    );
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(80.0))),
    );
    // A 1-D importance: one row of 1024 cells with a peak.
    let mut importance = ImportanceMap::new(1024, 1).unwrap();
    let row: Vec<f32> = (0..1024)
        .map(|i| {
            let x = i as f32 / 1024.0 - 0.3;
            0.05 + (-x * x * 400.0).exp()
        })
        .collect();
    importance.copy_from_slice(&row).unwrap();
    Frame {
        camera,
        light,
        low_sun: {
            let (sin, cos) = 2.0f32.to_radians().sin_cos();
            (Vec3::new(-0.4, 0.0, -0.6).normalize() * cos - Vec3::Y * sin).normalize()
        },
        light_rotation: Quat::from_rotation_arc(Vec3::NEG_Z, light),
        far_bounds,
        splits,
        stable,
        tight: stable.with_fit(CascadeFit::Tight),
        scene,
        spot: Light::Spot {
            position: Vec3::new(30.0, 25.0, -20.0),
            direction: Vec3::new(-0.5, -1.0, 0.2),
            half_angle: 0.6,
            range: 200.0,
        },
        point: Light::Point {
            position: Vec3::new(60.0, 20.0, -40.0),
            range: 2000.0,
        },
        bounds: DepthBounds {
            min: 0.5,
            max: 80.0,
        },
        importance,
        valid: ValidCamera::new(&camera).unwrap(),
        body: FocusBody::new(&camera, light, &scene).unwrap(),
    }
}

/// What the builders that refit in place write into, kept across calls as a renderer
/// keeps them across frames.
struct Outputs {
    /// RTW warp tables.
    warps: WarpMaps,
    /// One light's cascades.
    set: CascadeSet,
    /// The stable maps held across frames.
    held: CascadeState,
}

/// The builders, by name.
const NAMES: [&str; 29] = [
    "bevy_cascades_4",
    "uniform_focused",
    "stable_cascades_4",
    "tight_cascades_4",
    "lispsm",
    "xpsm",
    "tsm",
    "warped_cascades_4",
    "spot_fit",
    "ipsm_plan_paper_cone",
    "ipsm_plan_exact_cone",
    "rtw_tables_1d_1024",
    "camera_validate",
    "stable_cascades_4_valid",
    "tight_cascades_4_valid",
    "focus_body_valid_all_4",
    "focus_body_valid",
    "uniform_from_body",
    "lispsm_from_body",
    "xpsm_from_body",
    "tsm_from_body",
    "stable_cascades_4_refit",
    "tight_cascades_4_refit",
    "stable_cascades_4_held",
    "lispsm_valid",
    "ipsm_plan_exact_cone_valid",
    "focus_body_valid_all_4_low_sun",
    "spot_warp_lispsm",
    "spot_warp_tsm",
];

/// Keeps a builder's result where it was returned (the output is not moved out of
/// the `Result`, so no builder, nor the reference, is charged for a copy of it).
#[inline(always)]
fn keep<T, E: core::fmt::Debug>(result: &Result<T, E>) {
    black_box(result.as_ref().expect("builder failed"));
}

/// `fit` applied to the focus body of `f`'s validated camera and `light`, built in
/// the call, in a stack frame of its own: a body with its probe points is tens of
/// kilobytes, and held in [`run`]'s frame it would be charged to every builder.
#[inline(never)]
fn with_new_body(f: &Frame, light: Vec3, fit: impl FnOnce(&FocusBody)) {
    let body = FocusBody::new_valid(black_box(&f.valid), light, &f.scene);
    fit(body.as_ref().expect("builder failed"));
}

/// Runs builder `which` once on `f` (`out` holds the outputs refitted in place: the
/// RTW tables and a cascade set).
fn run(f: &Frame, out: &mut Outputs, which: usize) {
    let warps = &mut out.warps;
    let cam = black_box(&f.camera);
    let light = black_box(f.light);
    match which {
        0 => {
            black_box(&bevy_like::cascades(
                black_box(f.light_rotation),
                black_box(f.camera.world_from_view),
                core::f32::consts::FRAC_PI_4,
                16.0 / 9.0,
                &f.far_bounds,
            ));
        }
        1 => {
            let o = UniformOptions::default();
            keep(&uniform_focused(cam, light, &f.scene, &o));
        }
        2 => {
            keep(&CascadeSet::fit(cam, light, &f.splits, &f.stable));
        }
        3 => {
            keep(&CascadeSet::fit(cam, light, &f.splits, &f.tight));
        }
        4 => {
            keep(&lispsm(cam, light, &f.scene, &LispsmOptions::default()));
        }
        5 => {
            keep(&xpsm(cam, light, &f.scene, &XpsmOptions::default()));
        }
        6 => {
            keep(&tsm(cam, light, &f.scene, &TsmOptions::default()));
        }
        7 => {
            let etas = [0.0, 0.0, -0.5, -1.0];
            let o = LispsmOptions::default();
            keep(&warped_cascades(cam, light, &f.scene, &f.splits, &etas, &o));
        }
        8 => {
            let frustum = cam.frustum().unwrap();
            keep(&fit_spot(
                black_box(&f.spot),
                &frustum,
                Some(&f.scene),
                false,
            ));
        }
        9 | 10 => {
            let fit = if which == 9 {
                ConeFit::Paper
            } else {
                ConeFit::Exact
            };
            let o = IpsmOptions::default().with_fit(fit);
            keep(&IpsmPlan::new(black_box(&f.point), cam, Some(f.bounds), &o));
        }
        11 => {
            warps
                .build(black_box(&f.importance), &WarpOptions::default())
                .unwrap();
            black_box(warps.x_table());
        }
        12 => {
            black_box(cam.validate().is_ok());
        }
        13 => {
            keep(&CascadeSet::fit_valid(
                &f.valid, light, &f.splits, &f.stable,
            ));
        }
        14 => {
            keep(&CascadeSet::fit_valid(&f.valid, light, &f.splits, &f.tight));
        }
        15 | 26 => {
            let light = if which == 15 { light } else { f.low_sun };
            with_new_body(f, light, |body| {
                keep(&body.uniform(&UniformOptions::default()));
                keep(&body.lispsm(&LispsmOptions::default()));
                keep(&body.xpsm(&XpsmOptions::default()));
                keep(&body.tsm(&TsmOptions::default()));
            });
        }
        16 => {
            with_new_body(f, light, |body| {
                black_box(body);
            });
        }
        17 => {
            keep(&black_box(&f.body).uniform(&UniformOptions::default()));
        }
        18 => {
            keep(&black_box(&f.body).lispsm(&LispsmOptions::default()));
        }
        19 => {
            keep(&black_box(&f.body).xpsm(&XpsmOptions::default()));
        }
        20 => {
            keep(&black_box(&f.body).tsm(&TsmOptions::default()));
        }
        21 | 22 => {
            let options = if which == 21 { &f.stable } else { &f.tight };
            let fitted = out.set.refit_valid(&f.valid, light, &f.splits, options);
            keep(&fitted);
            black_box(&out.set);
        }
        23 => {
            // The stable fit the umbrella and the report use: each map fitted to
            // slice ∩ receivers, its size and orientation held across calls.
            let options = f.stable.with_scene(Some(f.scene));
            let fitted =
                CascadeSet::fit_with_state(&f.valid, light, &f.splits, &options, &mut out.held);
            keep(&fitted);
        }
        24 => {
            // One warp a frame from a camera validated once: the body, its probe
            // and the fit (what an engine with one LiSPSM light pays).
            with_new_body(f, light, |body| {
                keep(&body.lispsm(&LispsmOptions::default()));
            });
        }
        25 => {
            let o = IpsmOptions::default().with_fit(ConeFit::Exact);
            keep(&IpsmPlan::new_valid(
                black_box(&f.point),
                black_box(&f.valid),
                Some(f.bounds),
                &o,
            ));
        }
        27 | 28 => {
            // The spot fit warped in its post-projective space: the fit, the
            // candidate strengths and their predicted errors.
            let kind = if which == 27 {
                SpotWarpKind::Lispsm
            } else {
                SpotWarpKind::Tsm
            };
            let o = SpotWarpOptions::default().with_kind(kind);
            keep(&spot_warp(
                black_box(&f.spot),
                cam,
                Some(f.bounds),
                &f.scene,
                &o,
            ));
        }
        _ => unreachable!("no builder {which}"),
    }
}

/// With `BUILDERS_ONLY=<name>` (and `BUILDERS_CALLS=<n>`, default 1), calls that one
/// builder `n` times and times nothing, for instruction counts
/// (`timing::only_request`).
fn only(f: &Frame, out: &mut Outputs) -> bool {
    let Some((name, calls)) = timing::only_request("BUILDERS_ONLY", "BUILDERS_CALLS") else {
        return false;
    };
    let which = NAMES
        .iter()
        .position(|n| *n == name)
        .unwrap_or_else(|| panic!("BUILDERS_ONLY: no builder {name}; one of {NAMES:?}"));
    for _ in 0..calls {
        run(f, out, which);
    }
    true
}

/// The table's rows named in `BUILDERS_TABLE` (comma-separated; Bevy's row is
/// always timed, as the ratios' reference), or every row. With a filter that
/// matches no criterion benchmark (`--bench builders/zzz`), the table of a few rows
/// takes seconds: alternating runs of two builds compare them on a noisy machine.
fn table_rows() -> Option<Vec<String>> {
    let rows = std::env::var("BUILDERS_TABLE").ok()?;
    Some(rows.split(',').map(|r| r.trim().to_owned()).collect())
}

#[allow(clippy::print_stdout)] // The table is this bench's output.
fn builders(c: &mut Criterion) {
    let f = frame();
    let mut out = Outputs {
        warps: WarpMaps::new(1024, 1).unwrap(),
        set: CascadeSet::fit_valid(&f.valid, f.light, &f.splits, &f.stable).unwrap(),
        held: CascadeState::new(),
    };
    if only(&f, &mut out) {
        return;
    }
    let mut g = c.benchmark_group("builders");
    g.warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(1));
    for (i, name) in NAMES.iter().enumerate() {
        g.bench_function(*name, |b| b.iter(|| run(&f, &mut out, i)));
    }
    g.finish();

    let bevy = timing::min_ns(|| run(&f, &mut out, 0));
    println!("builders, one run (time per call, fastest of 201 batches):");
    let rows = table_rows();
    for (i, name) in NAMES.iter().enumerate() {
        if !(i == 0
            || rows
                .as_ref()
                .is_none_or(|r| r.iter().any(|row| row == name)))
        {
            continue;
        }
        let t = if i == 0 {
            bevy
        } else {
            timing::min_ns(|| run(&f, &mut out, i))
        };
        println!(
            "  {name:<22} {:>9.3} us  {:>7.2}x bevy_cascades_4",
            t * 1e-3,
            t / bevy
        );
    }
}

criterion_group!(benches, builders);
criterion_main!(benches);
