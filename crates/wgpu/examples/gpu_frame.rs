//! One frame of the city block at 1920x1080 with a 2048² shadow budget per technique,
//! timed per pass: the CPU time of each step (`fit`: the technique's fit; every GPU
//! pass: recording it, uploads queued) and the GPU time of each pass from timestamp
//! queries (`GpuProfiler`). Without the timestamp features it says so and prints CPU
//! times only.
//!
//! ```text
//! cargo run --release -p shadowmap-wgpu --example gpu_frame [-- --json] [-- --frames N]
//! ```
//!
//! Every technique is fitted by value through `shadowmap::fit` with the same inputs
//! (RTW's CPU tables from the eye samples of a G-buffer traced at an eighth of the
//! image size; the cascades' depth bounds from the same samples) and drawn by the
//! headless renderer, which keeps its passes and the scene's casters across frames:
//! the paraboloid and RTW casters are refined on the GPU every frame (`refine`),
//! then the depth pass (`depth`) and the scene pass (`scene`). The row `rtw_gpu` is
//! RTW with its whole analysis on the GPU: the eye G-buffer rendered at a quarter of
//! the image size (`gbuffer`), importance splat and collapse (`importance`), blur and
//! tables (`tables`), then refinement, depth and scene; its `fit` is the uniform base
//! alone. Each figure is the median over `frames` frames (default 5) after one
//! warm-up frame.
//!
//! The figures the backend is judged by are printed last:
//!
//! ```text
//! rtw analysis     importance + tables GPU ms                 (target <= 0.1 ms)
//! rtw frame        importance + tables + refine + depth GPU ms
//!                  over uniform's depth GPU ms                (target <= 2)
//! ipsm / dpsm      IPSM's refine + depth (one paraboloid when single)
//!                  over DPSM's refine + depth (two)           (target <= 0.6)
//! ```
//!
//! On a software adapter (llvmpipe) the GPU times measure CPU rasterization, not a
//! GPU; the adapter line says which one ran.

use std::fmt::Write as _;
use std::io::Write as _;
use std::time::Instant;

use glam::Vec3;
use shadowmap::frustum::{Camera, Light, Projection, ShadowTransform};
use shadowmap::{FitInput, LightKind, RtwPlan, Technique, fit};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::GBuffer;
use shadowmap_eval::scene::Scene;
use shadowmap_eval::technique::eye_samples;
use shadowmap_wgpu::depth::MeshBuffers;
use shadowmap_wgpu::gbuffer::RtwGBufferPass;
use shadowmap_wgpu::profile::{GpuProfiler, PassTime};
use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowFilter, ShadowTechnique};
use shadowmap_wgpu::rtw::GpuRtw;
use shadowmap_wgpu::shadow::with_technique;
use shadowmap_wgpu::{BackendError, GpuContext};

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;
const BUDGET: u32 = 2048;
/// Vertical field of view of the camera, radians.
const FOV_Y: f32 = 60.0 * core::f32::consts::PI / 180.0;

type Error = Box<dyn std::error::Error>;

/// The measured figures of one technique: every pass's median CPU and GPU time.
struct Row {
    name: &'static str,
    resolution: u32,
    layers: u32,
    wall_ms: f64,
    passes: Vec<PassTime>,
}

impl Row {
    fn gpu(&self, label: &str) -> Option<f64> {
        self.passes
            .iter()
            .find(|p| p.label == label)
            .and_then(|p| p.gpu_ms)
    }

    /// The summed GPU time of `labels`; `None` if one is missing.
    fn gpu_sum(&self, labels: &[&str]) -> Option<f64> {
        labels.iter().map(|l| self.gpu(l)).sum()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The per-pass medians over the frames (scopes in the order of the first frame),
/// after the fit's CPU time.
fn median_passes(fit_ms: f64, frames: &[Vec<PassTime>]) -> Vec<PassTime> {
    let mut out = vec![PassTime {
        label: "fit".to_owned(),
        cpu_ms: fit_ms,
        gpu_ms: None,
    }];
    let Some(first) = frames.first() else {
        return out;
    };
    out.extend(first.iter().enumerate().map(|(i, p)| {
        let of = |f: &Vec<PassTime>| f.get(i).cloned();
        let all: Vec<PassTime> = frames.iter().filter_map(of).collect();
        let gpu: Vec<f64> = all.iter().filter_map(|q| q.gpu_ms).collect();
        PassTime {
            label: p.label.clone(),
            cpu_ms: median(all.iter().map(|q| q.cpu_ms).collect()),
            gpu_ms: (!gpu.is_empty()).then(|| median(gpu)),
        }
    }));
    out
}

/// RTW's GPU analysis: the G-buffer pass and the table build, kept across frames.
struct Analysis {
    mesh: MeshBuffers,
    gbuffer: RtwGBufferPass,
    rtw: GpuRtw,
}

/// What every technique's frame shares.
struct Frame<'a> {
    ctx: &'a GpuContext,
    triangles: &'a [[Vec3; 3]],
    camera: &'a Camera,
    frames: usize,
}

impl Frame<'_> {
    fn options(resolution: u32) -> RenderOptions {
        RenderOptions::default()
            .with_size(WIDTH, HEIGHT)
            .with_shadow_resolution(resolution)
            .with_filter(ShadowFilter::Hardware2x2)
    }

    /// Renders one warm-up frame and `frames` measured ones; `before` records the
    /// passes that precede the renderer's (RTW's analysis) into their own submission.
    fn measure(
        &self,
        renderer: &mut HeadlessRenderer,
        profiler: &mut GpuProfiler,
        (name, resolution, layers, fit_ms): (&'static str, u32, u32, f64),
        technique: &ShadowTechnique<'_>,
        mut before: impl FnMut(&mut GpuProfiler) -> Result<(), BackendError>,
    ) -> Result<Row, Error> {
        let options = Self::options(resolution);
        let mut walls = Vec::new();
        let mut frames = Vec::new();
        for i in 0..=self.frames {
            let t = Instant::now();
            before(profiler)?;
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
                walls.push(wall);
                frames.push(passes);
            }
        }
        Ok(Row {
            name,
            resolution,
            layers,
            wall_ms: median(walls),
            passes: median_passes(fit_ms, &frames),
        })
    }

    /// RTW with its analysis on the GPU over the uniform fit `base`.
    fn measure_rtw_gpu(
        &self,
        renderer: &mut HeadlessRenderer,
        profiler: &mut GpuProfiler,
        (base, fit_ms): (&ShadowTransform, f64),
        analysis: &mut Analysis,
    ) -> Result<Row, Error> {
        let ctx = self.ctx;
        let camera = self.camera;
        let Analysis { mesh, gbuffer, rtw } = analysis;
        let rtw = &*rtw;
        let technique = ShadowTechnique::RtwGpu { base, rtw };
        let before = |profiler: &mut GpuProfiler| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            profiler.scope(&mut encoder, "gbuffer", |e| {
                gbuffer.encode(ctx, e, mesh, camera)
            })?;
            let g = gbuffer.gbuffer();
            profiler.scope(&mut encoder, "importance", |e| {
                rtw.encode_importance(ctx, e, &g, base)
            })?;
            profiler.scope(&mut encoder, "tables", |e| rtw.encode_tables(e));
            ctx.queue.submit([encoder.finish()]);
            Ok(())
        };
        let figures = ("rtw_gpu", BUDGET, 1, fit_ms);
        self.measure(renderer, profiler, figures, &technique, before)
    }
}

fn cell(ms: Option<f64>) -> String {
    ms.map_or("-".to_owned(), |ms| format!("{ms:.3}"))
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    Some(a? / b?).filter(|r| r.is_finite())
}

/// The three figures of the backend's targets, with how they are made.
fn figures(rows: &[Row]) -> Vec<(&'static str, Option<f64>, &'static str)> {
    let row = |name: &str| rows.iter().find(|r| r.name == name);
    let analysis = row("rtw_gpu").and_then(|r| r.gpu_sum(&["importance", "tables"]));
    let rtw_frame =
        row("rtw_gpu").and_then(|r| r.gpu_sum(&["importance", "tables", "refine", "depth"]));
    let uniform_depth = row("uniform").and_then(|r| r.gpu("depth"));
    let paraboloid = |name: &str| row(name).and_then(|r| r.gpu_sum(&["refine", "depth"]));
    vec![
        (
            "rtw_analysis_gpu_ms",
            analysis,
            "RTW analysis (importance + tables) GPU ms, target <= 0.1",
        ),
        (
            "rtw_frame_over_uniform_depth",
            ratio(rtw_frame, uniform_depth),
            "RTW frame (importance + tables + refine + depth) / uniform depth, GPU, target <= 2",
        ),
        (
            "ipsm_over_dpsm",
            ratio(paraboloid("ipsm_exact"), paraboloid("dpsm")),
            "IPSM (exact cone; refine + depth) / DPSM (refine + depth, two sides), GPU, target <= 0.6",
        ),
    ]
}

fn table(adapter: &str, profiler: &GpuProfiler, rows: &[Row]) -> Result<String, std::fmt::Error> {
    let mut out = String::new();
    writeln!(out, "adapter: {adapter}")?;
    if let Some(why) = profiler.unsupported() {
        writeln!(out, "GPU times: not available ({why}); CPU times only")?;
    }
    writeln!(
        out,
        "{:<18} {:>5} {:>6} {:>9} {:<11} {:>9} {:>9}",
        "technique", "res", "layers", "wall ms", "pass", "CPU ms", "GPU ms"
    )?;
    for r in rows {
        for (i, p) in r.passes.iter().enumerate() {
            let head = if i == 0 {
                format!(
                    "{:<18} {:>5} {:>6} {:>9.3}",
                    r.name, r.resolution, r.layers, r.wall_ms
                )
            } else {
                format!("{:<18} {:>5} {:>6} {:>9}", "", "", "", "")
            };
            writeln!(
                out,
                "{head} {:<11} {:>9.3} {:>9}",
                p.label,
                p.cpu_ms,
                cell(p.gpu_ms)
            )?;
        }
    }
    let ipsm_layers = rows
        .iter()
        .find(|r| r.name == "ipsm_exact")
        .map(|r| r.layers);
    writeln!(out)?;
    for (_, value, what) in figures(rows) {
        writeln!(out, "{what}: {}", cell(value))?;
    }
    if let Some(layers) = ipsm_layers {
        writeln!(out, "IPSM (exact cone) rendered {layers} paraboloid(s)")?;
    }
    Ok(out)
}

fn json(adapter: &str, profiler: &GpuProfiler, rows: &[Row]) -> String {
    let esc = |s: &str| s.replace('\\', "\\\\").replace('"', "\\\"");
    let num = |v: Option<f64>| v.map_or("null".to_owned(), |v| format!("{v:.6}"));
    let rows_json: Vec<String> = rows
        .iter()
        .map(|r| {
            let passes: Vec<String> = r
                .passes
                .iter()
                .map(|p| {
                    format!(
                        "{{\"pass\":\"{}\",\"cpu_ms\":{:.6},\"gpu_ms\":{}}}",
                        esc(&p.label),
                        p.cpu_ms,
                        num(p.gpu_ms)
                    )
                })
                .collect();
            format!(
                "{{\"technique\":\"{}\",\"resolution\":{},\"layers\":{},\"render_wall_ms\":{:.6},\"passes\":[{}]}}",
                r.name,
                r.resolution,
                r.layers,
                r.wall_ms,
                passes.join(",")
            )
        })
        .collect();
    let figures: Vec<String> = figures(rows)
        .into_iter()
        .map(|(key, value, _)| format!("\"{key}\":{}", num(value)))
        .collect();
    let gpu = profiler
        .unsupported()
        .map_or("null".to_owned(), |w| format!("\"{}\"", esc(w)));
    format!(
        "{{\"adapter\":\"{}\",\"width\":{WIDTH},\"height\":{HEIGHT},\"budget\":{BUDGET},\"gpu_timing_unavailable\":{gpu},\"rows\":[{}],\"figures\":{{{}}}}}",
        esc(adapter),
        rows_json.join(","),
        figures.join(",")
    )
}

/// Every technique of the umbrella crate, plus RTW over the spot fit, over the cube
/// faces and over the IPSM paraboloid, and the tiled cube maps.
fn techniques() -> Vec<Technique> {
    let mut all = Technique::all_default().to_vec();
    all.push(Technique::SpotRtw(RtwPlan::default()));
    all.push(Technique::CubeRtw {
        cube: Default::default(),
        rtw: RtwPlan::default(),
    });
    all.push(Technique::PointRtw {
        ipsm: Default::default(),
        rtw: RtwPlan::default(),
    });
    all.push(Technique::TiledCube {
        cube: Default::default(),
        tiles: Default::default(),
    });
    all
}

/// Fits every technique by value through `shadowmap::fit`, as an engine would, and
/// measures it (the fitted `Shadow` goes to the backend through its one match,
/// `with_technique`); then RTW with its analysis on the GPU.
fn measure_all(
    frame: &Frame<'_>,
    profiler: &mut GpuProfiler,
    scene: &Scene,
) -> Result<Vec<Row>, Error> {
    let camera = frame.camera;
    let bounds = scene.scene_bounds().ok_or("empty scene")?;
    let gbuffer = GBuffer::trace(&Bvh::build(&scene.mesh)?, camera, WIDTH / 8, HEIGHT / 8)?;
    let samples = eye_samples(&gbuffer, camera);
    let sun = Light::Directional {
        direction: Vec3::new(0.45, -0.8, -0.35),
    };
    // Behind and above the camera, outside the truncated frustum: IPSM fits one cut
    // paraboloid where DPSM renders two.
    let lamp = Light::Point {
        position: Vec3::new(-30.0, 80.0, 220.0),
        range: 600.0,
    };
    let spot = Light::Spot {
        position: Vec3::new(-40.0, 50.0, 60.0),
        direction: Vec3::new(0.5, -0.8, -0.6),
        half_angle: 0.7,
        range: 400.0,
    };
    let pixels_per_radian = HEIGHT as f32 / 2.0 / (FOV_Y / 2.0).tan();
    let budget = u64::from(BUDGET) * u64::from(BUDGET);
    let mut renderer = HeadlessRenderer::new();
    let mut rows = Vec::new();
    for technique in techniques() {
        let light = match technique.light_kind() {
            LightKind::Directional => &sun,
            LightKind::Point => &lamp,
            LightKind::Spot => &spot,
        };
        let input = FitInput::new(camera, light, bounds, budget)
            .with_eye_samples(&samples)
            .with_pixels_per_radian(pixels_per_radian);
        let t = Instant::now();
        let shadow = fit(&technique, &input)?;
        let fit_ms = ms_since(t);
        let figures = (
            technique.name(),
            shadow.layer_side(),
            shadow.layers(),
            fit_ms,
        );
        rows.push(with_technique(&shadow, |t| {
            frame.measure(&mut renderer, profiler, figures, t, |_| Ok(()))
        })??);
    }
    // RTW with the analysis on the GPU: the base is the uniform fit.
    let input = FitInput::new(camera, &sun, bounds, budget);
    let t = Instant::now();
    let uniform = fit(&Technique::UniformFocused(Default::default()), &input)?;
    let fit_ms = ms_since(t);
    let base = *uniform
        .transform()
        .ok_or("uniform fit without a transform")?;
    let plan = RtwPlan::default();
    let side = plan.importance_side;
    let mut analysis = Analysis {
        mesh: MeshBuffers::from_triangles(frame.ctx, frame.triangles)?,
        gbuffer: RtwGBufferPass::new(frame.ctx, WIDTH / 4, HEIGHT / 4, camera.reversed_z)?,
        rtw: GpuRtw::new(frame.ctx, side, side, &plan.warp, &plan.importance)?,
    };
    rows.push(frame.measure_rtw_gpu(&mut renderer, profiler, (&base, fit_ms), &mut analysis)?);
    Ok(rows)
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let as_json = args.iter().any(|a| a == "--json");
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .map_or(Ok(5), |n| n.parse::<usize>())?
        .max(1);
    let ctx = GpuContext::new_headless_with_features(GpuProfiler::FEATURES)?;
    let mut profiler = GpuProfiler::new(&ctx, 16);
    let scene = Scene::city_block(1);
    let triangles: Vec<[Vec3; 3]> = scene.mesh.triangles_f32();
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
