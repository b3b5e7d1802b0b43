//! Renders the city block with every technique and writes one PNG per technique to
//! `rendered/` of the report directory (`--out`, default `target/shadowmap-report`
//! relative to the working directory, as for `compare`). The `index.html` that
//! `compare` writes shows them; `compare` keeps `rendered/` when it replaces the
//! report.
//!
//! ```text
//! cargo run -p shadowmap-wgpu --example render_scene -- [--out DIR]
//! ```

use std::path::PathBuf;

use glam::{Vec2, Vec3};
use shadowmap_eval::scene::Scene;
use shadowmap_frustum::{
    Camera, CascadeOptions, CascadeSet, CascadeSplits, Projection, SplitScheme,
};
use shadowmap_paraboloid::{MapOptions, ParaboloidMap};
use shadowmap_rtw::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};
use shadowmap_warp::{
    LispsmOptions, SceneBounds, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, xpsm,
};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowFilter, ShadowTechnique};

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
    let triangles: Vec<[Vec3; 3]> = scene
        .mesh
        .triangles()
        .map(|t| t.map(glam::DVec3::as_vec3))
        .collect();
    let bounds = scene.bounds().ok_or("empty scene")?;
    let focus = SceneBounds::whole(bounds);
    let camera = Camera::look_at(
        Vec3::new(-20.0, 25.0, 110.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        Projection::perspective(55f32.to_radians(), 16.0 / 9.0, 1.0, 400.0),
    )?;
    let light = Vec3::new(0.5, -0.8, -0.4);
    let options = RenderOptions::default()
        .with_size(960, 540)
        .with_shadow_resolution(2048)
        .with_filter(ShadowFilter::Pcf {
            taps: 3,
            radius: 1.0,
        });

    let uniform = uniform_focused(&camera, light, &focus, &UniformOptions::default())?;
    let l = lispsm(&camera, light, &focus, &LispsmOptions::default())?;
    let x = xpsm(&camera, light, &focus, &XpsmOptions::default())?;
    let t = tsm(&camera, light, &focus, &TsmOptions::default())?;
    let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.7 }, 4, 1.0, 400.0)?
        .with_overlap(0.1)?;
    let set = CascadeSet::fit(
        &camera,
        light,
        &splits,
        &CascadeOptions::default()
            .with_resolution(2048)
            .with_scene(scene.scene_bounds()),
    )?;
    let map = ParaboloidMap::dual(
        Vec3::new(5.0, 40.0, 10.0),
        Vec3::NEG_Y,
        0.5,
        600.0,
        &MapOptions::default(),
    )?;
    // RTW importance: the ground near the camera matters most.
    let mut importance = ImportanceMap::new(128, 128)?;
    for k in 0..64 {
        let z = -100.0 + 3.2 * k as f32;
        for x in [-40.0f32, 0.0, 40.0] {
            if let Some(s) = uniform.project(Vec3::new(x, 0.0, z)) {
                let weight = 1.0 / (1.0 + (110.0 - z).max(1.0) / 20.0);
                let _ = importance.splat(s.uv.as_vec2(), weight);
            }
        }
    }
    let _ = importance.splat(Vec2::splat(0.5), 0.1);
    let mut warps = WarpMaps::new(128, 128)?;
    warps.build(&importance, &WarpOptions::default().with_blur_radius(4))?;
    let rtw = RtwShadow {
        base: uniform,
        warps: &warps,
    };

    let mut renderer = HeadlessRenderer::new();
    let jobs: [(&str, ShadowTechnique<'_>, RenderOptions); 8] = [
        ("uniform", ShadowTechnique::Matrix(&uniform), options),
        ("cascades", ShadowTechnique::Cascades(&set), options),
        ("lispsm", ShadowTechnique::Matrix(&l.transform), options),
        ("xpsm", ShadowTechnique::Xpsm(&x), options),
        ("tsm", ShadowTechnique::Matrix(&t.transform), options),
        ("paraboloid", ShadowTechnique::Paraboloid(&map), options),
        ("rtw", ShadowTechnique::Rtw(&rtw), options),
        (
            "cascades_vsm",
            ShadowTechnique::Cascades(&set),
            options.with_filter(ShadowFilter::Vsm { blur_radius: 3 }),
        ),
    ];
    for (name, technique, opts) in jobs {
        let frame = renderer.render(&ctx, &triangles, &camera, &technique, &opts)?;
        let path = dir.join(format!("{name}.png"));
        frame.image.save_png(&path)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
