//! Quality evaluation for shadow-map parameterizations.
//!
//! Everything here runs on the CPU in `f64`: scenes built in code or imported from
//! OBJ / glTF ([`scene`], [`import`]), a BVH ray caster for exact visibility
//! ([`bvh`], [`mask`]), a reference rasterizer that renders a technique's shadow
//! depth map the way a GPU does ([`raster`]), the evaluation configurations
//! ([`config`]: scene, light, scripted camera path), the techniques at an equal
//! texel budget ([`technique`]), the aliasing metrics ([`metrics`]) and
//! the `compare` report that puts every technique side by side ([`report`]).
//!
//! ```text
//! cargo run --release -p shadowmap-eval --bin compare    # report in target/shadowmap-report
//! cargo run --release -p shadowmap-eval --bin compare -- --quick --mesh my.obj
//! cargo run --release -p shadowmap-eval --bin compare -- --sweep 64   # + robustness sweep
//! ```
//!
//! # Example
//!
//! Measure LiSPSM and the uniform fit on the overhead configuration:
//!
//! ```
//! use shadowmap_eval::bvh::Bvh;
//! use shadowmap_eval::config::{ConfigOptions, standard_configurations};
//! use shadowmap_eval::mask::GBuffer;
//! use shadowmap_eval::metrics::{ScreenGeometry, SurfacePoint, aliasing_stats};
//! use shadowmap_eval::technique::{
//!     FrameContext, Technique, TechniqueKind, TechniqueOptions, eye_samples,
//! };
//!
//! let configs = standard_configurations(&ConfigOptions::default().with_path_frames(1))?;
//! let config = configs.iter().find(|c| c.name == "overhead").unwrap();
//! let camera = config.camera();
//! let (w, h) = (48, 27);
//! let bvh = Bvh::build(&config.scene.mesh)?;
//! let gbuffer = GBuffer::trace(&bvh, camera, w, h)?;
//! let samples = eye_samples(&gbuffer, camera);
//! let screen = ScreenGeometry::new(camera, w, h)?;
//! let surfaces: Vec<Option<SurfacePoint>> = gbuffer
//!     .surfaces
//!     .iter()
//!     .map(|s| s.map(|s| SurfacePoint { position: s.position, normal: s.normal }))
//!     .collect();
//! let frame = FrameContext {
//!     camera,
//!     light: &config.light,
//!     scene: config.scene.scene_bounds().unwrap(),
//!     eye_samples: &samples,
//!     pixels_per_radian: screen.pixels_per_radian().unwrap() as f32,
//! };
//! let options = TechniqueOptions::default().with_texel_budget(256 * 256);
//! let median_m = |kind| {
//!     let t = Technique::build(kind, &frame, &options).unwrap();
//!     let (stats, _) = aliasing_stats(&t, &t.layer_sizes(), &screen, &config.light, &surfaces);
//!     stats.m.unwrap().median
//! };
//! // Perspective warping spends the texels where the eye needs them.
//! assert!(median_m(TechniqueKind::Lispsm) < median_m(TechniqueKind::UniformFocused));
//! # Ok::<(), shadowmap_eval::EvalError>(())
//! ```
//!
//! # Conventions
//!
//! | what | convention |
//! |---|---|
//! | precision | everything in `f64` (`DVec3`, `DMat4`); cameras and lights are the `f32` types of `shadowmap-frustum` |
//! | world | right-handed, `y` up, metres |
//! | images | row-major, row 0 at the top; pixel `(i, j)` has its centre at `(i + 0.5, j + 0.5)`, `y` down |
//! | shadow maps | `uv` with `v` down (WebGPU); texel coordinates `uv * resolution` of the sample's layer; depth maps layer-major |
//! | Jacobian | `J = d texel / d pixel` through the tangent plane of the visible surface; `m = 1 / s_min(J)` |
//! | budget | every technique gets the same number of texels over all its layers (default `1024²`) |
//! | not covered | a visible point a technique does not map reads as lit, as in a shader |
//! | errors | [`EvalError`]; a technique that cannot handle a configuration is reported as "n/a (reason)", never a panic |

// --- geometry: scenes, import, BVH, reference rasterizer (owned by one author) ---
pub mod bvh;
pub mod error;
pub mod import;
pub mod mask;
pub mod raster;
pub mod scene;
pub use error::EvalError;

// --- evaluation: configurations, techniques, metrics, report (owned by another) ---
pub mod config;
pub mod metrics;
pub mod report;
pub mod technique;
pub use metrics::{AliasingStats, ScreenGeometry, Summary, SurfacePoint, TexelFootprint};
pub use report::{Options as ReportOptions, Report};
pub use technique::{Technique, TechniqueKind, TechniqueOptions};
