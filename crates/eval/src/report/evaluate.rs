//! One configuration evaluated: the traced frames, the ray-traced truth, and per
//! technique the aliasing, misclassification and temporal measures.

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use shadowmap::FitState;
use shadowmap_frustum::{Camera, SceneBounds, ShadowMapping};

use crate::EvalError;
use crate::bvh::Bvh;
use crate::config::Configuration;
use crate::mask::{GBuffer, ShadowMask};
use crate::metrics::{
    self, ScreenGeometry, SurfacePoint, aliasing_stats, flip_rate, misclassification, phase_jitter,
};
use crate::raster::{DepthMap, RasterOptions};
use crate::technique::{FrameContext, Technique, TechniqueKind, TechniqueOptions, eye_samples};

use super::image::{heatmap_image, mask_image, write_png};
use super::plots::{DepthPlot, DepthProfile, depth_plot_svg};
use super::runner::write_file;
use super::{ConfigSummary, Row, RowMetrics, Settings};

/// Depth bias of the reference depth pass: slope-scaled, so that a receiver's
/// depth at its exact position never lies behind the stored depth of its own texel
/// (half a texel in each axis is at most one texel of slope).
const SLOPE_BIAS: f64 = 1.5;
/// Constant part of the depth pass bias, in units of the smallest resolvable depth.
const CONSTANT_BIAS: f64 = 16.0;
/// Lookup bias in depth units (toward the light).
const LOOKUP_BIAS: f64 = 1e-5;

/// What one configuration produced.
pub(super) struct ConfigOutput {
    pub(super) summary: ConfigSummary,
    pub(super) rows: Vec<Row>,
    pub(super) files: Vec<PathBuf>,
}

/// One frame of a configuration, traced once and shared by the techniques.
struct Frame {
    camera: Camera,
    gbuffer: GBuffer,
    samples: Vec<shadowmap_rtw::EyeSample>,
    screen: ScreenGeometry,
}

/// What every technique of a configuration is measured against: the traced frames,
/// the ray-traced mask of frame 0 and the fixed world points of the temporal measures.
struct Reference {
    frames: Vec<Frame>,
    /// The ray-traced mask restricted to front-lit pixels.
    truth_front_lit: Vec<Option<bool>>,
    surfaces: Vec<Option<SurfacePoint>>,
    fixed: Vec<DVec3>,
    scene_bounds: SceneBounds,
}

/// One technique's measures and the per-pixel data of its pictures.
struct Measured {
    metrics: RowMetrics,
    m: Vec<Option<f64>>,
    lit: Vec<Option<bool>>,
}

/// The fixed parameters of every technique's depth pass and fit.
struct Setup {
    technique: TechniqueOptions,
    raster: RasterOptions,
}

/// Evaluates every technique of `config`'s light and writes its pictures into
/// `pictures` (none when `None`).
///
/// A technique that cannot be built or rasterized gives an "n/a" row; a picture that
/// cannot be written is an error.
pub(super) fn evaluate_config(
    config: &Configuration,
    bvh: &Bvh,
    settings: &Settings,
    pictures: Option<&Path>,
    bar: &indicatif::ProgressBar,
) -> Result<ConfigOutput, EvalError> {
    let reference = Reference::trace(config, bvh, settings)?;
    let summary = summarize(config, &reference);
    let setup = Setup {
        technique: TechniqueOptions::default()
            .with_texel_budget(settings.texel_budget)
            .with_rtw_importance_side(settings.rtw_side),
        raster: RasterOptions::default().with_depth_bias(CONSTANT_BIAS, SLOPE_BIAS),
    };
    let mut rows = Vec::new();
    let mut files = Vec::new();
    let mut profiles = Vec::new();
    for kind in TechniqueKind::for_light(&config.light) {
        bar.set_message(format!("{}: {}", config.name, kind.name()));
        let outcome = match measure(kind, config, &reference, &setup) {
            Ok(measured) => {
                if let Some(out) = pictures.filter(|_| !kind.is_reference()) {
                    let base = format!("{}_{}", config.name, kind.name());
                    files.extend(write_pictures(out, &base, &reference, &measured, settings)?);
                    profiles.push(depth_profile(kind, &reference, &measured.m));
                }
                Ok(measured.metrics)
            }
            Err(EvalError::Technique { reason, .. }) => Err(reason),
            Err(other) => Err(other.to_string()),
        };
        rows.push(Row {
            config: config.name.clone(),
            technique: kind,
            outcome,
        });
        bar.inc(1);
    }
    if let Some(out) = pictures {
        files.push(write_depth_plot(out, &summary, &profiles, settings)?);
    }
    Ok(ConfigOutput {
        summary,
        rows,
        files,
    })
}

/// Writes the heatmap and the masks of one technique; their names, relative to `out`.
fn write_pictures(
    out: &Path,
    base: &str,
    reference: &Reference,
    measured: &Measured,
    settings: &Settings,
) -> Result<[PathBuf; 2], EvalError> {
    let (w, h) = (settings.width, settings.height);
    let first = &reference.frames[0];
    let heat = PathBuf::from(format!("heatmap_{base}.png"));
    write_png(
        &out.join(&heat),
        &heatmap_image(w, h, &first.gbuffer, &measured.m),
    )?;
    let masks = PathBuf::from(format!("mask_{base}.png"));
    write_png(
        &out.join(&masks),
        &mask_image(w, h, &measured.lit, &reference.truth_front_lit),
    )?;
    Ok([heat, masks])
}

/// The p95 of `m` per view-depth slice of frame 0 (see [`DepthProfile`]).
fn depth_profile(kind: TechniqueKind, reference: &Reference, m: &[Option<f64>]) -> DepthProfile {
    let camera = &reference.frames[0].camera;
    let (eye, forward) = (camera.eye().as_dvec3(), camera.forward().as_dvec3());
    let (near, far) = camera
        .depth_range()
        .map_or((f64::NAN, f64::NAN), |(n, f)| (f64::from(n), f64::from(f)));
    let samples = reference
        .surfaces
        .iter()
        .zip(m)
        .filter_map(|(s, m)| Some(((s.as_ref()?.position - eye).dot(forward), (*m)?)));
    DepthProfile::new(kind, near, far, samples)
}

/// Writes `aliasing_<config>.svg`, the aliasing error against view depth of every
/// technique with the pixel-matched and logarithmic limits; its name.
fn write_depth_plot(
    out: &Path,
    summary: &ConfigSummary,
    profiles: &[DepthProfile],
    settings: &Settings,
) -> Result<PathBuf, EvalError> {
    let name = PathBuf::from(format!("aliasing_{}.svg", summary.name));
    let log_limit = summary
        .log_bound
        .map(|b| (b * summary.visible_pixels as f64 / settings.texel_budget as f64).sqrt())
        .filter(|l| l.is_finite() && *l > 0.0);
    let svg = depth_plot_svg(&DepthPlot {
        config: &summary.name,
        profiles,
        log_limit,
    })
    .map_err(|e| EvalError::Write {
        path: out.join(&name),
        source: std::io::Error::other(e),
    })?;
    write_file(&out.join(&name), &svg)?;
    Ok(name)
}

impl Reference {
    fn trace(config: &Configuration, bvh: &Bvh, settings: &Settings) -> Result<Self, EvalError> {
        let (w, h) = (settings.width, settings.height);
        let frames: Vec<Frame> = config
            .path
            .iter()
            .map(|camera| {
                let gbuffer = GBuffer::trace(bvh, camera, w, h)?;
                let samples = eye_samples(&gbuffer, camera);
                let screen = ScreenGeometry::new(camera, w, h)?;
                Ok(Frame {
                    camera: *camera,
                    gbuffer,
                    samples,
                    screen,
                })
            })
            .collect::<Result<_, EvalError>>()?;
        let first = frames.first().ok_or_else(|| EvalError::InvalidView {
            message: format!("{}: camera path without frames", config.name),
        })?;
        let truth = ShadowMask::ray_traced(&first.gbuffer, bvh, &config.light)?;
        let surfaces: Vec<Option<SurfacePoint>> = first
            .gbuffer
            .surfaces
            .iter()
            .map(|s| {
                s.as_ref().map(|s| SurfacePoint {
                    position: s.position,
                    normal: s.normal,
                })
            })
            .collect();
        // Misclassification counts front-lit pixels only: elsewhere shading darkens the
        // surface whatever the map says (see metrics::FRONT_LIT_MIN_COS).
        let truth_front_lit: Vec<Option<bool>> = truth
            .lit
            .iter()
            .zip(&surfaces)
            .map(|(t, s)| t.filter(|_| s.is_some_and(|s| metrics::is_front_lit(&config.light, &s))))
            .collect();
        let fixed = fixed_points(config, settings, &surfaces);
        let scene_bounds = config
            .scene
            .scene_bounds()
            .ok_or_else(|| EvalError::InvalidMesh {
                message: format!("{}: scene has no bounds", config.scene.name),
            })?;
        Ok(Self {
            frames,
            truth_front_lit,
            surfaces,
            fixed,
            scene_bounds,
        })
    }

    fn context<'a>(&'a self, frame: &'a Frame, config: &'a Configuration) -> FrameContext<'a> {
        FrameContext {
            camera: &frame.camera,
            light: &config.light,
            scene: self.scene_bounds,
            eye_samples: &frame.samples,
            pixels_per_radian: frame.screen.pixels_per_radian().unwrap_or(1.0) as f32,
        }
    }
}

/// Fixed world points for the temporal measures: a regular subset of the front-lit
/// points of frame 0 (on surfaces parallel to the light the shadow test is a coin
/// toss that shading hides).
fn fixed_points(
    config: &Configuration,
    settings: &Settings,
    surfaces: &[Option<SurfacePoint>],
) -> Vec<DVec3> {
    let (w, h) = (settings.width, settings.height);
    let stride = settings.temporal_stride.max(1) as usize;
    (0..h)
        .step_by(stride)
        .flat_map(|y| (0..w).step_by(stride).map(move |x| (x, y)))
        .filter_map(|(x, y)| surfaces[(y * w + x) as usize])
        .filter(|s| metrics::is_front_lit(&config.light, s))
        .map(|s| s.position)
        .collect()
}

fn summarize(config: &Configuration, reference: &Reference) -> ConfigSummary {
    let (near, far) = config
        .camera()
        .depth_range()
        .map(|(n, f)| (f64::from(n), f64::from(f)))
        .unwrap_or((f64::NAN, f64::NAN));
    ConfigSummary {
        name: config.name.clone(),
        description: config.description.clone(),
        scene: config.scene.name.clone(),
        light_kind: config.light_kind(),
        depth_range: (near, far),
        log_bound: metrics::log_bound(config.camera()),
        visible_pixels: reference.frames[0].gbuffer.visible_count(),
    }
}

/// Frame 0's measures of one technique, then its temporal measures along the path.
fn measure(
    kind: TechniqueKind,
    config: &Configuration,
    reference: &Reference,
    setup: &Setup,
) -> Result<Measured, EvalError> {
    let first = &reference.frames[0];
    // One state through the path, as a renderer keeps it (auto's choice, the stable
    // cascades' sizes); frame 0 starts fresh.
    let mut state = FitState::default();
    let technique = Technique::build_with_state(
        kind,
        &reference.context(first, config),
        &setup.technique,
        &mut state,
    )?;
    let (aliasing, pixels) = aliasing_stats(
        &technique,
        &technique.layer_sizes(),
        &first.screen,
        &config.light,
        &reference.surfaces,
    );
    let map = technique.rasterize(&config.scene.mesh, &setup.raster)?;
    let mask = ShadowMask::from_map(&first.gbuffer, &technique, &map, LOOKUP_BIAS);
    let miss = misclassification(&mask.lit, &reference.truth_front_lit);
    let path = CameraRun {
        kind,
        config,
        reference,
        setup,
    };
    let (phase_jitter, flip_rate) = temporal(&path, &technique, &map, &mut state);
    Ok(Measured {
        metrics: RowMetrics {
            layers: texture_layers(&technique),
            layer_side: texture_side(&technique),
            texels: technique.texels(),
            aliasing,
            misclassification: miss,
            phase_jitter,
            flip_rate,
        },
        m: pixels.m,
        lit: mask.lit,
    })
}

/// Layers of the technique's texture: a tiled cube map's tiles share one atlas.
fn texture_layers(technique: &Technique) -> u32 {
    match technique.shadow().tiled_cube() {
        Some(_) => 1,
        None => technique.layers(),
    }
}

/// Side of the technique's (first) layer: a tiled cube map's atlas square.
fn texture_side(technique: &Technique) -> u32 {
    match technique.shadow().tiled_cube() {
        Some(_) => technique.shadow().layer_side(),
        None => technique.layer_sizes().first().map_or(0, |s| s.0),
    }
}

/// What [`temporal`] refits along a camera path.
struct CameraRun<'a> {
    kind: TechniqueKind,
    config: &'a Configuration,
    reference: &'a Reference,
    setup: &'a Setup,
}

/// Refits the technique to every frame of the path after frame 0, threading `state`
/// (left by frame 0's fit) from frame to frame as a renderer would, and follows the
/// fixed points: (phase jitter, flip rate), `None` when a frame cannot be fitted or
/// rasterized.
fn temporal(
    path: &CameraRun<'_>,
    technique: &Technique,
    map: &DepthMap,
    state: &mut FitState,
) -> (Option<f64>, Option<f64>) {
    let CameraRun {
        kind,
        config,
        reference,
        setup,
    } = *path;
    let fixed = &reference.fixed;
    let mut texels = vec![texels_of(technique, fixed)];
    let mut lit = vec![lit_of(technique, map, fixed)];
    for f in &reference.frames[1..] {
        let context = reference.context(f, config);
        let Ok(t) = Technique::build_with_state(kind, &context, &setup.technique, state) else {
            return (None, None);
        };
        let Ok(m) = t.rasterize(&config.scene.mesh, &setup.raster) else {
            return (None, None);
        };
        texels.push(texels_of(&t, fixed));
        lit.push(lit_of(&t, &m, fixed));
    }
    (phase_jitter(&texels), flip_rate(&lit))
}

fn texels_of(t: &Technique, points: &[DVec3]) -> Vec<Option<(DVec2, u32)>> {
    let sizes = t.layer_sizes();
    points
        .iter()
        .map(|&p| {
            let s = t.map_point(p)?;
            let (w, h) = *sizes.get(s.layer as usize)?;
            Some((s.uv * DVec2::new(f64::from(w), f64::from(h)), s.layer))
        })
        .collect()
}

fn lit_of(t: &Technique, map: &DepthMap, points: &[DVec3]) -> Vec<Option<bool>> {
    points
        .iter()
        .map(|&p| t.map_point(p).and_then(|s| map.is_lit(&s, LOOKUP_BIAS)))
        .collect()
}
