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
//! Every technique is fitted by value through `shadowmap::fit` with the same inputs
//! (`fit ms` includes, for RTW, its importance and tables built on the CPU from the
//! eye samples of a G-buffer traced at an eighth of the image size; the GPU analysis
//! passes are not part of this frame), and renders `frames` times (default 5) after
//! one warm-up frame; the median of each figure is reported. Layers share the budget
//! as `fit` splits it (cascades by the depth range, the dual paraboloid into two
//! sides).

use std::fmt::Write as _;
use std::io::Write as _;
use std::time::Instant;

use glam::{DVec3, Vec3};
use shadowmap::frustum::{Camera, Light, Projection};
use shadowmap::{FitInput, LightKind, Technique, fit};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::GBuffer;
use shadowmap_eval::scene::Scene;
use shadowmap_eval::technique::eye_samples;
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::profile::{GpuProfiler, PassTime};
use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowFilter, ShadowTechnique};
use shadowmap_wgpu::shadow::with_technique;

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;
const BUDGET: u32 = 2048;
/// Vertical field of view of the camera, radians.
const FOV_Y: f32 = 60.0 * core::f32::consts::PI / 180.0;

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

/// Fits every technique by value through `shadowmap::fit`, as an engine would, and
/// measures it: the eye's samples (a G-buffer traced at an eighth of the image size)
/// feed RTW's importance and the cascades' depth bounds; the fitted `Shadow` goes to
/// the backend through its one match (`with_technique`).
fn measure_all(
    frame: &Frame<'_>,
    profiler: &mut GpuProfiler,
    scene: &Scene,
) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let camera = frame.camera;
    let bounds = scene.scene_bounds().ok_or("empty scene")?;
    let gbuffer = GBuffer::trace(&Bvh::build(&scene.mesh)?, camera, WIDTH / 8, HEIGHT / 8)?;
    let samples = eye_samples(&gbuffer, camera);
    let sun = Light::Directional {
        direction: Vec3::new(0.45, -0.8, -0.35),
    };
    let lamp = Light::Point {
        position: Vec3::new(5.0, 45.0, 10.0),
        range: 600.0,
    };
    let pixels_per_radian = HEIGHT as f32 / 2.0 / (FOV_Y / 2.0).tan();
    let budget = u64::from(BUDGET) * u64::from(BUDGET);
    let mut renderer = HeadlessRenderer::new();
    let mut rows = Vec::new();
    for technique in Technique::all_default() {
        let light = match technique.light_kind() {
            LightKind::Directional => &sun,
            LightKind::Point => &lamp,
            _ => continue,
        };
        let input = FitInput::new(camera, light, bounds, budget)
            .with_eye_samples(&samples)
            .with_pixels_per_radian(pixels_per_radian);
        let t = Instant::now();
        let shadow = fit(&technique, &input)?;
        let fit_ms = ms_since(t);
        let figures = (technique.name(), shadow.layer_side(), fit_ms);
        rows.push(with_technique(&shadow, |t| {
            frame.measure(&mut renderer, profiler, figures, t)
        })??);
    }
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
    let camera = Camera::look_at(
        Vec3::new(10.0, 18.0, 120.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::Y,
        Projection::perspective(FOV_Y, WIDTH as f32 / HEIGHT as f32, 1.0, 500.0),
    )?;
    let frame = Frame {
        ctx: &ctx,
        triangles: &triangles,
        camera: &camera,
        frames,
    };
    let rows = measure_all(&frame, &mut profiler, &scene)?;
    let out = if as_json {
        json(&ctx.describe(), &profiler, &rows)
    } else {
        table(&ctx.describe(), &profiler, &rows)?
    };
    std::io::stdout().write_all(format!("{out}\n").as_bytes())?;
    Ok(())
}
