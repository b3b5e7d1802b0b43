//! A thin wgpu backend for the shadowmap math crates: the shadow depth passes of
//! every technique, the WGSL lookups and filters, the GPU parts of SDSM and RTW
//! (compute), and a headless renderer for tests, reports and examples.
//!
//! The math crates compute everything per frame on the CPU (`shadowmap-frustum`,
//! `shadowmap-warp`, `shadowmap-paraboloid`, `shadowmap-rtw`); this crate packs
//! their results into uniform blocks ([`uniforms::ToRaw`]), evaluates per vertex or
//! per pixel only what must be evaluated there, and checks itself against the CPU
//! reference rasterizer of `shadowmap-eval`.
//!
//! | module | what |
//! |---|---|
//! | [`context`] | [`GpuContext`]: headless device, error scopes ([`GpuContext::scoped`]), readback ([`GpuContext::read_buffer`], [`GpuContext::read_texture`]), test gating |
//! | [`compose`] | WGSL composition: lookups and filters into the scene shader, the RTW table sampler into its depth pass and lookup |
//! | [`uniforms`] | `#[repr(C)]` blocks built by [`uniforms::ToRaw`] |
//! | [`depth`] | [`depth::ShadowDepthPass`]: matrix / paraboloid / RTW depth passes (RTW over an orthographic or perspective base or each kept cube face, paraboloid sides optionally warped) |
//! | [`render`] | [`render::HeadlessRenderer`]: scene pass with a lookup and a filter composed in, PNGs, shadow masks |
//! | [`shadow`] | [`render::HeadlessRenderer::render_shadow`]: a fitted `shadowmap::Shadow` to the renderer, the one match from fitted result to lookup and depth pass |
//! | [`profile`] | [`profile::GpuProfiler`]: GPU time per pass from timestamp queries |
//! | [`reduce`] | depth min/max reduction (SDSM, IPSM depth bounds) |
//! | [`rtw`] | [`rtw::GpuRtw`]: importance, blur, warp tables on the GPU |
//! | [`gbuffer`] | [`gbuffer::RtwGBufferPass`]: RTW's eye G-buffer rendered on the GPU |
//! | [`refine`] | [`refine::GpuRefine`]: caster refinement for RTW and the paraboloid maps as a compute pass writing indirect draws |
//! | [`volume`] | [`volume::VolumeRenderer`]: stencil shadow volumes (z-pass, z-fail with caps), the exact mask; [`volume::misclassification`] of any technique against it; [`volume::ProjectiveRenderer`]: projective shadows |
//! | [`shaders`] | every WGSL source, embedded |
//!
//! # Example
//!
//! A uniform shadow map of one triangle, rendered and read back:
//!
//! ```no_run
//! use glam::Vec3;
//! use shadowmap_frustum::{Aabb, Camera, Projection};
//! use shadowmap_warp::{SceneBounds, UniformOptions, uniform_focused};
//! use shadowmap_wgpu::depth::{DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass};
//! use shadowmap_wgpu::{GpuContext, uniforms::ToRaw};
//!
//! let ctx = GpuContext::new_headless()?;
//! let camera = Camera::look_at(Vec3::new(0.0, 5.0, 15.0), Vec3::ZERO, Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 50.0)).unwrap();
//! let scene = SceneBounds::whole(Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0)));
//! let light = uniform_focused(&camera, Vec3::new(0.3, -1.0, 0.2), &scene, &UniformOptions::default()).unwrap();
//!
//! let caster = MeshBuffers::from_triangles(&ctx, &[[Vec3::ZERO, Vec3::X, Vec3::Y]])?;
//! let mut pass = ShadowDepthPass::new(&ctx, &DepthPassDesc::new(DepthTechnique::Matrix, 1024))?;
//! let depth = ctx.scoped(|ctx| {
//!     let mut encoder = ctx.device.create_command_encoder(&Default::default());
//!     pass.encode(ctx, &mut encoder, &[&caster], &DepthUniforms::Matrix(&[light.to_raw()]))?;
//!     ctx.queue.submit([encoder.finish()]);
//!     pass.readback_depth(ctx)
//! })?;
//! assert_eq!(depth.len(), 1024 * 1024);
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```
//!
//! `examples/render_scene.rs` renders the city block with every technique into
//! `target/shadowmap-report/rendered/*.png`.
//!
//! # Conventions
//!
//! - **Spaces.** WebGPU clip space (`x, y` in `[-w, w]`, `z` in `[0, w]`), texture
//!   `uv` with `v` down (row 0 at the top), matrices named destination-from-source
//!   and uploaded column-major (`clip_from_world`), as in `shadowmap-frustum`.
//! - **Uniform layouts.** Every block is a whole number of 16-byte rows
//!   (`mat4x4<f32>` columns, `vec4` rows; scalars packed into `vec4`s), so
//!   `#[repr(C)]` and WGSL's uniform layout agree with no hidden padding;
//!   `tests/uniforms.rs` checks sizes and offsets against naga's layouter. The depth
//!   pass writes its map resolution into one spare lane (`ParaboloidLayerRaw::side.y`,
//!   `RtwShadowRaw::sizes.w`) for the subpixel snap below.
//! - **Bind groups.** Depth passes: group 0 = binding 0 the layer's block (one
//!   256-byte-aligned slot per layer, dynamic offset), binding 1 the warp tables
//!   (RTW and paraboloid passes). Scene pass: group 0 the frame (`FrameRaw`), group 1
//!   the lookup (binding 0 the technique's block, binding 1 the warp tables of the
//!   RTW and paraboloid lookups), group 2 the maps (binding 0 the
//!   `texture_depth_2d_array`, 1 the comparison sampler, 2 the VSM moments). Compute
//!   passes own group 0 (see [`reduce`] and [`rtw`]).
//! - **Depth maps.** `Depth32Float` 2-D arrays, one layer per cascade or paraboloid
//!   side. Standard depth clears to 1 and keeps `Less`; **reversed-Z** (the
//!   transform's `reversed_z`) clears to 0 and keeps `Greater`, the lookups flip
//!   their comparisons, and biases change sign.
//! - **Bias.** Two parts ([`render::ShadowBias`]): the depth pass's rasterizer bias
//!   ([`depth::DepthBias`], wgpu's `DepthBiasState`: `slope_scale * max(|dz/dx|,
//!   |dz/dy|) + constant * 2^(e - 23)`, clamped), positive away from the light for
//!   standard depth and negated for reversed-Z; and a lookup bias in stored-depth
//!   units toward the light (plus XPSM's world-units Z bias). The renderer's
//!   per-technique defaults ([`render::ShadowBias::default_for`]) scale the slope
//!   term with the filter's reach.
//! - **RTW tables.** One storage buffer of `f32`: the `u` table (`sizes.x` texels)
//!   then the `v` table (`sizes.y` texels), texel `i` holding the offset at
//!   `(i + 0.5) / N`, `T[0] = T[N-1] = 0`, sampled by hand with the texel-centre
//!   linear, clamp-to-edge semantics of `shadowmap_rtw::forward_warp`. Written by
//!   the CPU ([`uniforms::RtwShadowRaw::tables`]) or by [`rtw::GpuRtw`] (fed to the
//!   depth pass by [`rtw::GpuRtw::depth_uniforms`]). RTW over the sides of a
//!   paraboloid (`point_rtw`) keeps every side's tables in one buffer, each side's
//!   offsets in its block ([`uniforms::warped_paraboloid`]).
//! - **Caster refinement.** RTW warps and the paraboloid bends only vertices, so
//!   casters are subdivided: on the GPU every frame ([`refine::GpuRefine`], drawn by
//!   [`depth::ShadowDepthPass::encode_refined`]; the headless renderer's path) or on
//!   the CPU, the reference ([`depth::subdivide_for_rtw`],
//!   `shadowmap_paraboloid::subdivide_triangles`); each pair follows one split rule
//!   (`RtwSubdivision::split_rule`, `SubdivisionOptions::split_rule`). Casters the
//!   base cannot map (behind a perspective light) are dropped both ways.
//! - **Subpixel snap.** The paraboloid and RTW vertex shaders snap positions to the
//!   1/256-pixel grid of the rasterizer: their maps compress, so casters become
//!   slivers with depth slopes near 1 per texel, and rasterizers differ in whether
//!   the depth plane uses snapped positions (llvmpipe does not); snapping first
//!   makes every rasterizer store the same depths.
//! - **Errors.** Invalid input is [`BackendError::InvalidInput`]; GPU work that wgpu
//!   rejects is caught in error scopes ([`GpuContext::scoped`]) and returned as
//!   [`BackendError::Wgpu`], never a panic.
//!
//! # GPU tests
//!
//! The tests in `tests/gpu_*.rs` compare the GPU with the CPU references of
//! `shadowmap-eval` and `shadowmap-rtw`. Each opens its device with
//! [`context::test_context`]: without an adapter it prints a one-line notice and
//! passes (skips); with `SHADOWMAP_REQUIRE_GPU=1` a missing adapter fails the test,
//! so CI cannot skip silently. Mesa's llvmpipe (software Vulkan) is enough:
//!
//! ```text
//! SHADOWMAP_REQUIRE_GPU=1 cargo test -p shadowmap-wgpu
//! ```
//!
//! # Portability of the compute passes
//!
//! The RTW analysis failed on an NVIDIA H100 (identity tables for a 64x48 map with
//! importance near `f32::MAX`): the tables shader divided by a peak above 2^126,
//! outside the range where WGSL guarantees `x / y`; it now scales by exponent bits,
//! and the test that exposed it passes on an NVIDIA H200. The other suspects were audited ([`rtw`], "Memory, barriers, subgroups,
//! reduction order"): every workgroup variable is written before it is read (the
//! pipelines run without wgpu's zeroing, so the llvmpipe tests see what a driver
//! that leaves it uninitialized would give); the density history, read times a zero
//! weight on a first build (`0 * NaN` is NaN), is now read only when there is
//! history (a test fills it with NaN first); barriers are in uniform control flow;
//! no subgroup operation is used; the one floating-point sum is a fixed-order scan;
//! maps and G-buffers that are not multiples of the workgroups are tested. The
//! refinement ([`refine`]) uses no workgroup memory and meets other invocations only
//! in integer atomics.
//!
//! # GPU timings
//!
//! [`profile::GpuProfiler`] measures each scope's CPU recording time and, on a
//! device with `TIMESTAMP_QUERY`, its GPU time;
//! [`render::HeadlessRenderer::render_profiled`] records a frame's `refine`,
//! `depth`, `vsm` and `scene` passes with it. `cargo run --release -p shadowmap-wgpu
//! --example gpu_frame [-- --json]` renders the city block at 1920x1080 with a 2048²
//! budget for every technique (uniform, cascades, LiSPSM, XPSM, TSM, RTW with CPU
//! tables, `rtw_gpu` with its analysis on the GPU: G-buffer, importance, tables;
//! spot, DPSM, IPSM, cube maps, RTW over the spot fit, the cube faces and the
//! paraboloid),
//! prints CPU ms and GPU ms per pass (CPU times only, and says so, without the
//! timestamp features) and then the backend's three targets:
//!
//! ```text
//! RTW analysis: importance + tables, GPU ms                           <= 0.1 ms
//! RTW frame: importance + tables + refine + depth / uniform's depth   <= 2
//! IPSM (one cut paraboloid: refine + depth) / DPSM (two sides)        <= 0.6
//! ```
//!
//! Measured on an NVIDIA H200 (Vulkan, `gpu_frame --frames 5`, release build; every
//! GPU test of this crate passes there too), GPU ms per pass:
//!
//! ```text
//! uniform             depth 0.68   scene 2.01
//! cascades (4)        depth 0.95   scene 2.94
//! LiSPSM / XPSM / TSM depth 0.96 / 1.01 / 0.94
//! RTW (CPU tables)    refine 8.05  depth 1.85
//! rtw_gpu             gbuffer 0.38  importance 0.034  tables 0.012  refine 7.83  depth 1.61
//! DPSM (two sides)    refine 0.24  depth 0.60
//! IPSM, exact cone    refine 0.25  depth 0.67  (one paraboloid)
//! cube maps           depth 1.17
//! RTW over the cube faces   refine 79.8   depth 3.25
//! RTW over IPSM             refine 669    depth 2.22
//! tiled cube maps (214 tiles)  depth 1.53
//!
//! RTW analysis: importance + tables                   0.046 ms   (target <= 0.1: met)
//! RTW frame / uniform's depth                         14.0       (target <= 2: not met)
//! IPSM / DPSM                                         1.085      (target <= 0.6: not met)
//! ```
//!
//! The refinement is what RTW's frame costs on a GPU: one invocation per caster
//! walks all of that caster's pieces, so the few large casters (the ground, long
//! walls) that refine into tens of thousands of pieces keep a handful of invocations
//! busy while the rest of the GPU idles. llvmpipe exposes timestamps too, but they
//! time CPU rasterization and compute emulation: on it (shared 2-core machine) the
//! three figures read 5.9 ms, 54 and 0.80 (the refinement's compute alone takes 260
//! ms there).
//!
//! `cargo bench -p shadowmap-wgpu --bench frame` and `--bench compute` measure the
//! CPU side (uniform packing, command encoding, caster subdivision) and, where an
//! adapter opens, GPU round trips; on this machine the adapter is llvmpipe, so any
//! GPU-side figure is a software-adapter figure (CPU rasterization), not a GPU
//! timing. `--bench frame` on a shared 2-core machine (load average about 5),
//! release profile, adapter llvmpipe (LLVM 15, 256 bits); the `encode/*` and
//! `*_frame_cpu` rows are CPU time to record commands (the adapter only matters
//! through wgpu's validation):
//!
//! ```text
//! pack/uniform, pack/xpsm (to_raw)                 16 ns
//! pack/cascades_lookup_4                           39 ns
//! pack/cascades_layers_4                           60 ns
//! pack/paraboloid_layers                           47 ns
//! pack/rtw_256 (block + 512 table floats)          67 ns
//! encode/cascades_4_depth_passes                   25 us
//! encode/rtw_depth_pass_256_cell_tables            23 us
//!
//! same run (load average 4.7):
//! subdivide_rtw/city_block_256_cells_2048         108 ms  (CPU: 5264 -> 722 512 triangles)
//! rtw_frame_cpu/city_block_2048_tables_256_gpu_refine  64 us  (tables built,
//!     casters refined and the depth pass drawn indirectly on the GPU, 5264 ->
//!     696 144 triangles there; 1/1700 of the CPU subdivision it replaces)
//! subdivide_paraboloid/city_block_ipsm_2048       4.9 ms  (CPU: 5264 -> 41 735)
//! ipsm_frame_cpu/city_block_2048_fit_and_gpu_refine    62 us  (IPSM plan fitted,
//!     casters refined against the paraboloid on the GPU, 41 735 triangles there,
//!     depth pass drawn indirectly; 1/79 of the CPU subdivision alone)
//! ipsm_frame_cpu/dpsm_city_block_2048_gpu_refine       67 us  (two sides, 76 169)
//! ```

pub mod compose;
pub mod context;
pub use context::{BackendError, GpuContext};

// --- depth passes, uniforms, lookup, headless renderer (one author) ---
pub mod depth;
mod mesh;
pub mod profile;
pub mod render;
pub mod shadow;
pub mod tiles;
pub mod uniforms;

// --- compute passes: depth reduction, RTW pipeline (another author) ---
pub mod gbuffer;
pub mod reduce;
pub mod refine;
pub mod rtw;

// --- shadow volumes and projective shadows ---
pub mod volume;

/// The WGSL sources in `shaders/`, embedded so users need no file access.
pub mod shaders {
    // Each author adds `pub const NAME: &str = include_str!("../shaders/<file>.wgsl");`
    // for the files they own, with a one-line doc comment.

    // --- depth passes, lookups, filters, renderer (depth_*, lookup_*, filter_*, render_*) ---
    /// Depth pass of the matrix techniques (uniform, cascades, LiSPSM, XPSM, TSM).
    pub const DEPTH_MATRIX: &str = include_str!("../shaders/depth_matrix.wgsl");
    /// Depth pass of a paraboloid map (one side per layer, hemisphere clipped, warp
    /// tables optional); its shared functions are placeholders until composed
    /// ([`crate::compose::depth_paraboloid`]).
    pub const DEPTH_PARABOLOID: &str = include_str!("../shaders/depth_paraboloid.wgsl");
    /// The paraboloid projection, composed into the paraboloid depth pass, lookup and
    /// the caster refinement.
    pub const PARABOLOID_SIDE: &str = include_str!("../shaders/paraboloid_side.wgsl");
    /// Depth pass of RTW (base projection, then the warp tables per axis); its
    /// table sampler is a placeholder until composed ([`crate::compose::depth_rtw`]).
    pub const DEPTH_RTW: &str = include_str!("../shaders/depth_rtw.wgsl");
    /// Lookup of a matrix technique (uniform, LiSPSM, XPSM with its Z bias, TSM).
    pub const LOOKUP_MATRIX: &str = include_str!("../shaders/lookup_matrix.wgsl");
    /// Lookup of cascades: selection by view depth with the blend band, or by projection.
    pub const LOOKUP_CASCADES: &str = include_str!("../shaders/lookup_cascades.wgsl");
    /// Lookup of a paraboloid map (front/back side, cut, warp tables optional); its
    /// shared functions are placeholders until composed
    /// ([`crate::compose::lookup_paraboloid`]).
    pub const LOOKUP_PARABOLOID: &str = include_str!("../shaders/lookup_paraboloid.wgsl");
    /// Lookup of RTW over one base or each kept cube face (base projection, warp
    /// tables, the layer's corner); its table sampler is a
    /// placeholder until composed ([`crate::compose::lookup_rtw`]).
    pub const LOOKUP_RTW: &str = include_str!("../shaders/lookup_rtw.wgsl");
    /// Lookup of a tiled cube map: face, cell, tile, the tile's square of the atlas.
    pub const LOOKUP_TILES: &str = include_str!("../shaders/lookup_tiles.wgsl");
    /// The RTW warp-table sampler, composed into the RTW depth pass and lookup.
    pub const RTW_SAMPLE: &str = include_str!("../shaders/rtw_sample.wgsl");
    /// Filter: one nearest texel.
    pub const FILTER_HARD: &str = include_str!("../shaders/filter_hard.wgsl");
    /// Filter: the hardware 2x2 compare.
    pub const FILTER_HARDWARE: &str = include_str!("../shaders/filter_hardware.wgsl");
    /// Filter: N x N percentage-closer filtering.
    pub const FILTER_PCF: &str = include_str!("../shaders/filter_pcf.wgsl");
    /// Filter: Poisson-disk percentage-closer filtering.
    pub const FILTER_POISSON: &str = include_str!("../shaders/filter_poisson.wgsl");
    /// Filter: variance shadow maps (Chebyshev bound on blurred moments).
    pub const FILTER_VSM: &str = include_str!("../shaders/filter_vsm.wgsl");
    /// VSM moments pass and separable blur (full-screen fragment passes).
    pub const FILTER_VSM_MOMENTS: &str = include_str!("../shaders/filter_vsm_moments.wgsl");
    /// The headless renderer's scene pass (a lookup and a filter are composed in).
    pub const RENDER_SCENE: &str = include_str!("../shaders/render_scene.wgsl");

    // --- compute (reduce_*, rtw_*) ---
    /// Min/max reduction of a depth buffer (two entry points: tiles, then partials).
    pub const REDUCE_DEPTH: &str = include_str!("../shaders/reduce_depth.wgsl");
    /// RTW importance splat from an eye-space G-buffer and collapse to 1-D maxima.
    pub const RTW_IMPORTANCE: &str = include_str!("../shaders/rtw_importance.wgsl");
    /// RTW's eye-space G-buffer rendered from the camera (position, distance, normal).
    pub const RTW_GBUFFER: &str = include_str!("../shaders/rtw_gbuffer.wgsl");
    /// RTW per-axis blur, normalization, temporal smoothing, floor and warp table.
    pub const RTW_WARP: &str = include_str!("../shaders/rtw_warp.wgsl");
    /// Caster refinement (count, choose, emit) for RTW and paraboloid maps, writing
    /// indirect draws; its shared functions are placeholders until composed
    /// ([`crate::compose::refine`]).
    pub const REFINE: &str = include_str!("../shaders/refine.wgsl");

    // --- shadow volumes, projective shadows (volume_*, projective_*) ---
    /// Stencil shadow volumes: surfaces, two-sided stencil count, classification.
    pub const VOLUME_STENCIL: &str = include_str!("../shaders/volume_stencil.wgsl");
    /// Silhouette edges of a closed mesh for one light (compute, one edge per invocation).
    pub const VOLUME_SILHOUETTE: &str = include_str!("../shaders/volume_silhouette.wgsl");
    /// Projective shadows: occluder mask from the light, receivers' homogeneous lookup.
    pub const PROJECTIVE_SHADOW: &str = include_str!("../shaders/projective_shadow.wgsl");
}
