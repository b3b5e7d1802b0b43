//! An engine's frame loop in small: the eye's G-buffer gives the visible samples, every
//! technique is chosen by value (`shadowmap::Technique`) and fitted by the one
//! `shadowmap::fit`, and the fitted `Shadow` goes to the backend
//! (`HeadlessRenderer::render_shadow`) with no per-technique code.
//!
//! Renders the city block with every technique (RTW over the lamp's cube faces and
//! paraboloid included) and writes one PNG per technique to
//! `rendered/` of the report directory, and beside it the technique's
//! misclassification against exact stencil shadow volumes at the render resolution:
//! `<technique>_misclassified.png` (red falsely lit, blue falsely shadowed) and one
//! row per technique in `misclassification.csv` (`--out`, default `target/shadowmap-report`
//! relative to the working directory, as for `compare`). The `index.html` that
//! `compare` writes shows them; `compare` keeps `rendered/` when it replaces the
//! report.
//!
//! ```text
//! cargo run -p shadowmap-wgpu --example render_scene -- [--out DIR]
//! ```

use std::path::PathBuf;

use glam::Vec3;
use shadowmap::frustum::{Camera, Light, Projection};
use shadowmap::{FitInput, LightKind, Technique, fit};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::GBuffer;
use shadowmap_eval::scene::Scene;
use shadowmap_eval::technique::eye_samples;
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowFilter, ShadowMask};
use shadowmap_wgpu::volume::{VolumeMethod, VolumeRenderer, VolumeScene, misclassification};

/// Image size, and the G-buffer's (a quarter in each direction: enough samples for
/// RTW's importance and the cascades' depth bounds).
const WIDTH: u32 = 960;
const HEIGHT: u32 = 540;
/// Texels per technique, all layers together.
const BUDGET: u64 = 2048 * 2048;

const USAGE: &str = "usage: render_scene [--out DIR]

Renders the city block with every shadow-map technique into DIR/rendered/<technique>.png
(default DIR: target/shadowmap-report, the report directory of compare, whose index.html
shows them).";

/// The report directory: `--out DIR`, or `compare`'s default; `None` for `--help`.
fn out_dir() -> Result<Option<PathBuf>, String> {
    let mut args = std::env::args().skip(1);
    let mut out = PathBuf::from("target/shadowmap-report");
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--out" => out = args.next().ok_or("--out needs a directory")?.into(),
            "-h" | "--help" => return Ok(None),
            other => return Err(format!("unknown argument {other:?}\n\n{USAGE}")),
        }
    }
    Ok(Some(out))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = match out_dir() {
        Ok(Some(out)) => out.join("rendered"),
        Ok(None) => {
            #[allow(clippy::print_stdout)] // Asked-for help goes to stdout.
            {
                println!("{USAGE}");
            }
            return Ok(());
        }
        Err(message) => {
            eprintln!("{message}");
            std::process::exit(2);
        }
    };
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let ctx = GpuContext::new_headless()?;
    eprintln!("adapter: {}", ctx.describe());
    let scene = Scene::city_block(1);
    let triangles: Vec<[Vec3; 3]> = scene.mesh.triangles_f32();
    let scene_bounds = scene.scene_bounds().ok_or("empty scene")?;
    let camera = Camera::look_at(
        Vec3::new(-20.0, 25.0, 110.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        Projection::perspective(55f32.to_radians(), 16.0 / 9.0, 1.0, 400.0),
    )?;
    let gbuffer = GBuffer::trace(&Bvh::build(&scene.mesh)?, &camera, WIDTH / 4, HEIGHT / 4)?;
    let samples = eye_samples(&gbuffer, &camera);
    let sun = Light::Directional {
        direction: Vec3::new(0.5, -0.8, -0.4),
    };
    let lamp = Light::Point {
        position: Vec3::new(5.0, 40.0, 10.0),
        range: 600.0,
    };
    let options = RenderOptions::default()
        .with_size(WIDTH, HEIGHT)
        .with_filter(ShadowFilter::Pcf {
            taps: 3,
            radius: 1.0,
        });
    let pixels_per_radian = HEIGHT as f32 / 2.0 / (55f32.to_radians() / 2.0).tan();

    // The exact shadows of each light (z-fail: right wherever the camera is).
    let mut volumes = VolumeScene::new(&triangles)?;
    if let Some(open) = volumes.first_open_edge() {
        eprintln!(
            "{} open triangles receive but cast no volume ({open})",
            volumes.open_triangles()
        );
    }
    let mut volume_renderer = VolumeRenderer::new();
    let mut exact = |light: &Light| -> Result<ShadowMask, Box<dyn std::error::Error>> {
        Ok(volume_renderer.render_mask(
            &ctx,
            &mut volumes,
            &camera,
            light,
            (WIDTH, HEIGHT),
            VolumeMethod::ZFail,
        )?)
    };
    let (sun_exact, lamp_exact) = (exact(&sun)?, exact(&lamp)?);
    let mut csv =
        String::from("technique,compared_pixels,false_lit,false_shadowed,misclassification\n");

    let mut renderer = HeadlessRenderer::new();
    // Every technique of the umbrella crate, and RTW over the lamp's cube faces and
    // over its IPSM paraboloid (the scene has no spot light).
    let point_rtw = [
        Technique::CubeRtw {
            cube: Default::default(),
            rtw: Default::default(),
        },
        Technique::PointRtw {
            ipsm: Default::default(),
            rtw: Default::default(),
        },
    ];
    for technique in Technique::all_default().into_iter().chain(point_rtw) {
        let (light, truth) = match technique.light_kind() {
            LightKind::Directional => (&sun, &sun_exact),
            LightKind::Point => (&lamp, &lamp_exact),
            _ => continue,
        };
        let input = FitInput::new(&camera, light, scene_bounds, BUDGET)
            .with_eye_samples(&samples)
            .with_pixels_per_radian(pixels_per_radian);
        let shadow = fit(&technique, &input)?;
        let frame = renderer.render_shadow(&ctx, &triangles, &camera, &shadow, &options)?;
        let path = dir.join(format!("{}.png", technique.name()));
        frame.image.save_png(&path)?;
        let (miss, diff) = misclassification(&frame.mask, truth);
        diff.save_png(dir.join(format!("{}_misclassified.png", technique.name())))?;
        csv.push_str(&format!(
            "{},{},{},{},{:.6}\n",
            technique.name(),
            miss.compared,
            miss.false_lit,
            miss.false_shadowed,
            miss.rate()
        ));
        eprintln!(
            "wrote {} ({} layer(s) of {}²; {:.3}% misclassified)",
            path.display(),
            shadow.layers(),
            shadow.layer_side(),
            100.0 * miss.rate()
        );
    }
    let csv_path = dir.join("misclassification.csv");
    std::fs::write(&csv_path, csv).map_err(|e| format!("{}: {e}", csv_path.display()))?;
    eprintln!("wrote {}", csv_path.display());
    // The same stable cascades, filtered with variance shadow maps.
    let input = FitInput::new(&camera, &sun, scene_bounds, BUDGET).with_eye_samples(&samples);
    let cascades = fit(&Technique::StableCascades(Default::default()), &input)?;
    let vsm = options.with_filter(ShadowFilter::Vsm { blur_radius: 3 });
    let frame = renderer.render_shadow(&ctx, &triangles, &camera, &cascades, &vsm)?;
    let path = dir.join("cascades_vsm.png");
    frame.image.save_png(&path)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
