//! One frame of the city block at 1920x1080 with a 2048² shadow budget per
//! technique: the CPU time to fit the technique (`fit ms`), the wall time of one
//! `HeadlessRenderer::render_profiled` call (`wall ms`: upload, caster subdivision,
//! encoding, submit, waiting for the GPU and reading the image and mask back; the
//! headless renderer is a test tool, not an engine's frame), and the GPU time of
//! each pass from timestamp queries (`GpuProfiler`). Without the timestamp features
//! it says so and prints CPU times only.
//!
//! ```text
//! cargo run --release -p shadowmap-wgpu --example gpu_frame [-- --json] [-- --frames N]
//! ```
//!
//! Each technique renders `frames` times (default 5) after one warm-up frame and
//! reports the median of each figure. The RTW row uses warp tables built on the CPU
//! from a fixed importance (its G-buffer analysis passes are not part of this
//! frame); the cascade budget is split into four 1024² layers, the dual paraboloid's
//! into two 1448² sides (the same texel count, as near as a power of two allows
//! for the cascades).

use std::fmt::Write as _;
use std::io::Write as _;
use std::time::Instant;

use glam::{DVec3, Vec2, Vec3};
use shadowmap_eval::scene::Scene;
use shadowmap_frustum::{
    Camera, CascadeOptions, CascadeSet, CascadeSplits, Projection, ShadowTransform, SplitScheme,
};
use shadowmap_paraboloid::{MapOptions, ParaboloidMap};
use shadowmap_rtw::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};
use shadowmap_warp::{
    LispsmOptions, SceneBounds, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::profile::{GpuProfiler, PassTime};
use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowFilter, ShadowTechnique};

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;
const BUDGET: u32 = 2048;

/// The measured figures of one technique.
struct Row {
    name: &'static str,
    resolution: u32,
    fit_ms: f64,
    wall_ms: f64,
    passes: Vec<PassTime>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The per-pass medians over the frames (scopes in the order of the first frame).
fn median_passes(frames: &[Vec<PassTime>]) -> Vec<PassTime> {
    let Some(first) = frames.first() else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .map(|(i, p)| PassTime {
            label: p.label.clone(),
            gpu_ms: median(
                frames
                    .iter()
                    .filter_map(|f| f.get(i))
                    .map(|q| q.gpu_ms)
                    .collect(),
            ),
        })
        .collect()
}

/// What every technique's frame shares.
struct Frame<'a> {
    ctx: &'a GpuContext,
    triangles: &'a [[Vec3; 3]],
    camera: &'a Camera,
    frames: usize,
}

impl Frame<'_> {
    /// Renders one warm-up frame and `frames` measured ones.
    fn measure(
        &self,
        renderer: &mut HeadlessRenderer,
        profiler: &mut GpuProfiler,
        (name, resolution, fit_ms): (&'static str, u32, f64),
        technique: &ShadowTechnique<'_>,
    ) -> Result<Row, Box<dyn std::error::Error>> {
        let options = RenderOptions::default()
            .with_size(WIDTH, HEIGHT)
            .with_shadow_resolution(resolution)
            .with_filter(ShadowFilter::Hardware2x2);
        let mut cpu = Vec::new();
        let mut gpu = Vec::new();
        for i in 0..=self.frames {
            let t = Instant::now();
            renderer.render_profiled(
                self.ctx,
                self.triangles,
                self.camera,
                technique,
                &options,
                profiler,
            )?;
            let wall = ms_since(t);
            let passes = profiler.read(self.ctx)?;
            if i > 0 {
                cpu.push(wall);
                gpu.push(passes);
            }
        }
        Ok(Row {
            name,
            resolution,
            fit_ms,
            wall_ms: median(cpu),
            passes: median_passes(&gpu),
        })
    }
}

/// The RTW tables: importance falling off with distance from the camera, splatted
/// along the streets in the base map.
fn rtw_warps(base: &ShadowTransform) -> Result<WarpMaps, Box<dyn std::error::Error>> {
    let mut importance = ImportanceMap::new(256, 256)?;
    for k in 0..96 {
        let z = -110.0 + 2.5 * k as f32;
        for x in [-50.0f32, -25.0, 0.0, 25.0, 50.0] {
            if let Some(s) = base.project(Vec3::new(x, 0.0, z)) {
                let _ = importance.splat(s.uv.as_vec2(), 1.0 / (1.0 + (120.0 - z) / 25.0));
            }
        }
    }
    let _ = importance.splat(Vec2::splat(0.5), 0.05);
    let mut warps = WarpMaps::new(256, 256)?;
    warps.build(&importance, &WarpOptions::default().with_blur_radius(4))?;
    Ok(warps)
}

fn table(adapter: &str, profiler: &GpuProfiler, rows: &[Row]) -> Result<String, std::fmt::Error> {
    let mut out = String::new();
    writeln!(out, "adapter: {adapter}")?;
    if let Some(why) = profiler.unsupported() {
        writeln!(out, "GPU times: not available ({why}); CPU times only")?;
    }
    writeln!(
        out,
        "{:<16} {:>6} {:>9} {:>11} {:>10} {:>10} {:>10}",
        "technique", "res", "fit ms", "wall ms", "depth ms", "vsm ms", "scene ms"
    )?;
    for r in rows {
        let pass = |label: &str| {
            r.passes
                .iter()
                .find(|p| p.label == label)
                .map_or("-".to_owned(), |p| format!("{:.3}", p.gpu_ms))
        };
        writeln!(
            out,
            "{:<16} {:>6} {:>9.3} {:>11.3} {:>10} {:>10} {:>10}",
            r.name,
            r.resolution,
            r.fit_ms,
            r.wall_ms,
            pass("depth"),
            pass("vsm"),
            pass("scene")
        )?;
    }
    Ok(out)
}

fn json(adapter: &str, profiler: &GpuProfiler, rows: &[Row]) -> String {
    let esc = |s: &str| s.replace('\\', "\\\\").replace('"', "\\\"");
    let rows: Vec<String> = rows
        .iter()
        .map(|r| {
            let passes: Vec<String> = r
                .passes
                .iter()
                .map(|p| format!("{{\"pass\":\"{}\",\"gpu_ms\":{:.6}}}", esc(&p.label), p.gpu_ms))
                .collect();
            format!(
                "{{\"technique\":\"{}\",\"resolution\":{},\"fit_cpu_ms\":{:.6},\"render_wall_ms\":{:.6},\"passes\":[{}]}}",
                r.name,
                r.resolution,
                r.fit_ms,
                r.wall_ms,
                passes.join(",")
            )
        })
        .collect();
    let gpu = profiler
        .unsupported()
        .map_or("null".to_owned(), |w| format!("\"{}\"", esc(w)));
    format!(
        "{{\"adapter\":\"{}\",\"width\":{WIDTH},\"height\":{HEIGHT},\"budget\":{BUDGET},\"gpu_timing_unavailable\":{gpu},\"rows\":[{}]}}",
        esc(adapter),
        rows.join(",")
    )
}

/// Fits and measures every technique, in the order of the table.
fn measure_all(
    frame: &Frame<'_>,
    profiler: &mut GpuProfiler,
    focus: &SceneBounds,
    scene: &Scene,
) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let camera = frame.camera;
    let light = Vec3::new(0.45, -0.8, -0.35);
    let mut renderer = HeadlessRenderer::new();
    let mut rows = Vec::new();
    let mut run = |name, resolution, fit: Instant, t: &ShadowTechnique<'_>| {
        let fit_ms = ms_since(fit);
        frame.measure(&mut renderer, profiler, (name, resolution, fit_ms), t)
    };

    let t = Instant::now();
    let uniform = uniform_focused(camera, light, focus, &UniformOptions::default())?;
    rows.push(run(
        "uniform",
        BUDGET,
        t,
        &ShadowTechnique::Matrix(&uniform),
    )?);
    let t = Instant::now();
    let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.7 }, 4, 1.0, 500.0)?
        .with_overlap(0.1)?;
    let options = CascadeOptions::default()
        .with_resolution(BUDGET / 2)
        .with_scene(scene.scene_bounds());
    let set = CascadeSet::fit(camera, light, &splits, &options)?;
    rows.push(run(
        "cascades_4",
        BUDGET / 2,
        t,
        &ShadowTechnique::Cascades(&set),
    )?);
    let t = Instant::now();
    let l = lispsm(camera, light, focus, &LispsmOptions::default())?;
    rows.push(run(
        "lispsm",
        BUDGET,
        t,
        &ShadowTechnique::Matrix(&l.transform),
    )?);
    let t = Instant::now();
    let x = xpsm(camera, light, focus, &XpsmOptions::default())?;
    rows.push(run("xpsm", BUDGET, t, &ShadowTechnique::Xpsm(&x))?);
    let t = Instant::now();
    let tr = tsm(camera, light, focus, &TsmOptions::default())?;
    rows.push(run(
        "tsm",
        BUDGET,
        t,
        &ShadowTechnique::Matrix(&tr.transform),
    )?);
    let t = Instant::now();
    let w = warped_cascades(
        camera,
        light,
        focus,
        &splits,
        &[0.0; 4],
        &LispsmOptions::default(),
    )?;
    rows.push(run(
        "warped_cascades_4",
        BUDGET / 2,
        t,
        &ShadowTechnique::WarpedCascades(&w),
    )?);
    let t = Instant::now();
    let warps = rtw_warps(&uniform)?;
    let rtw = RtwShadow {
        base: uniform,
        warps: &warps,
    };
    rows.push(run(
        "rtw_cpu_tables",
        BUDGET,
        t,
        &ShadowTechnique::Rtw(&rtw),
    )?);
    let t = Instant::now();
    let map = ParaboloidMap::dual(
        Vec3::new(5.0, 45.0, 10.0),
        Vec3::NEG_Y,
        0.5,
        600.0,
        &MapOptions::default(),
    )?;
    rows.push(run("dpsm", 1448, t, &ShadowTechnique::Paraboloid(&map))?);

    Ok(rows)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let as_json = args.iter().any(|a| a == "--json");
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .map_or(Ok(5), |n| n.parse::<usize>())?
        .max(1);
    let ctx = GpuContext::new_headless_with_features(GpuProfiler::FEATURES)?;
    let mut profiler = GpuProfiler::new(&ctx, 8);
    let scene = Scene::city_block(1);
    let triangles: Vec<[Vec3; 3]> = scene
        .mesh
        .triangles()
        .map(|t| t.map(DVec3::as_vec3))
        .collect();
    let focus = SceneBounds::whole(scene.bounds().ok_or("empty scene")?);
    let camera = Camera::look_at(
        Vec3::new(10.0, 18.0, 120.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), WIDTH as f32 / HEIGHT as f32, 1.0, 500.0),
    )?;
    let frame = Frame {
        ctx: &ctx,
        triangles: &triangles,
        camera: &camera,
        frames,
    };
    let rows = measure_all(&frame, &mut profiler, &focus, &scene)?;
    let out = if as_json {
        json(&ctx.describe(), &profiler, &rows)
    } else {
        table(&ctx.describe(), &profiler, &rows)?
    };
    std::io::stdout().write_all(format!("{out}\n").as_bytes())?;
    Ok(())
}
