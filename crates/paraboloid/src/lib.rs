//! Dual-paraboloid shadow maps and improved paraboloid shadow maps (IPSM) with an exact
//! minimal light cone.
//!
//! Omnidirectional and hemispherical lights cost engines six cube faces. A paraboloid
//! map (Brabec, Annen and Seidel, *Shadow mapping for hemispherical and omnidirectional
//! light sources*, CGI 2002) stores a hemisphere in one texture; two of them back to
//! back (DPSM) store the whole sphere. IPSM (Vanek, Navrátil, Herout and Zemčík,
//! *High-Quality Shadows with Improved Paraboloid Mapping*, ISVC 2011)
//! turns the front paraboloid toward the visible part of the scene and cuts it to the
//! light cone that covers the truncated view frustum, so one map, with more texels
//! where they matter, often does the job.
//!
//! This crate provides:
//!
//! - [`ParaboloidMap`]: the forward map (world point to uv, depth and side), the inverse
//!   map, the texel density per steradian, the usable disc, and the shader's uniform
//!   block ([`ParaboloidUniform`], whose lookup mirrors [`ParaboloidMap::lookup`]);
//! - [`IpsmPlan`]: the paper's four steps (truncated frustum, light cone, rotation, cut)
//!   and the single-or-dual decision, with the paper's cone or the exact one
//!   ([`ConeFit`]);
//! - [`fit_paper_cone`] and [`fit_minimal_cone`]: the two cone fits on their own;
//! - [`edge_subdivisions`], [`subdivide_triangle`], [`subdivide_triangles`]: caster
//!   subdivision, because wgpu has no tessellation stage (its rule,
//!   [`SubdivisionOptions::split_rule`], is shared with the GPU refinement of
//!   `shadowmap-wgpu`);
//! - [`CubeMap`]: cube shadow maps, what engines ship for point lights and the
//!   baseline the paraboloid maps are measured against: the faces that see visible
//!   receivers, each focused on them (see [Cube maps](#cube-maps));
//! - [`TiledCube`]: cube maps whose faces are cut into tiles sized by need, in one
//!   atlas (see [Tiled cube maps](#tiled-cube-maps)).
//!
//! # Example
//!
//! ```
//! use glam::Vec3;
//! use shadowmap_frustum::{Camera, DepthBounds, Light, Projection, ShadowMapping};
//! use shadowmap_paraboloid::{ConeFit, IpsmOptions, IpsmPlan};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 200.0),
//! )?;
//! let light = Light::Point { position: Vec3::new(10.0, 30.0, -40.0), range: 300.0 };
//! // Min/max view depth measured from the depth buffer: the truncated frustum.
//! let bounds = DepthBounds { min: 2.0, max: 60.0 };
//!
//! let exact = IpsmPlan::new(&light, &camera, Some(bounds), &IpsmOptions::default())?;
//! let paper = IpsmPlan::new(
//!     &light,
//!     &camera,
//!     Some(bounds),
//!     &IpsmOptions::default().with_fit(ConeFit::Paper),
//! )?;
//! // The light is outside the truncated frustum: one cut paraboloid suffices.
//! assert!(exact.is_single());
//! // The exact cone is never wider than the paper's: more texels per steradian.
//! assert!(exact.zoom() <= paper.zoom());
//!
//! // Every border point of the truncated frustum lands in the map.
//! for p in exact.border_points {
//!     let s = exact.map_point(p.as_dvec3()).expect("covered");
//!     assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
//!     assert_eq!(s.layer, 0);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! | what | convention |
//! |---|---|
//! | light frame | [`ParaboloidMap::light_from_world`] is rigid: light at the origin, right-handed, the front paraboloid faces `-Z` (the cone axis), `Y` from [`MapOptions::up_hint`] |
//! | front paraboloid | layer 0, directions with `-z_light >= 0`; disc = `(x, y) / (1 - z)` of the unit direction |
//! | back paraboloid | layer 1, directions with `z_light > 0`; disc = `(-x, y) / (1 + z)` (mirrored, so it reads like a camera facing `+Z`) |
//! | cut (zoom) | `ndc = disc / zoom`, `zoom = tan(half_angle / 2)`, 1 for a DPSM |
//! | texture space | WebGPU: `u = ndc.x / 2 + 1/2`, `v = 1/2 - ndc.y / 2` (`v` down) |
//! | depth | `(|P - L| - near) / (far - near)` in `[0, 1]`, `1 -` that with reversed-Z |
//! | single map | only the front layer; a point whose uv leaves `[0, 1]²` is not covered |
//! | precision | public API in `f32`; every builder computes in `f64`; lookups rotate `P - position` (not the `f32` translation), so points near the light keep their direction |
//!
//! The forward map, for a world point `P` and the unit light-space direction `d`:
//!
//! ```text
//! q = light_from_world * P     d = q / |q|
//! front: disc = ( d.x, d.y) / (1 - d.z)        back: disc = (-d.x, d.y) / (1 + d.z)
//! uv = (1/2 + disc.x / (2 zoom), 1/2 - disc.y / (2 zoom))
//! depth = (|q| - near) / (far - near)
//! ```
//!
//! A direction at angle `theta` from the side's axis lands at disc radius
//! `tan(theta / 2)`: the hemisphere fills the unit disc, and a cone of half-angle `h`
//! fills the disc of radius `tan(h / 2)`, which the cut scales to the texture.
//!
//! # The exact minimal cone
//!
//! The paper's cone takes the normalized sum of the directions `D_j` toward the 8
//! border points as its axis and the largest angle as its half-angle; the paper says
//! itself that this is not optimal. The smallest cone containing unit directions has
//!
//! ```text
//! p* = argmin { |p| : p in conv(D_1 .. D_8) }     axis = p* / |p*|     cos(h) = |p*|
//! ```
//!
//! (the largest `min_j a . D_j` over unit `a` is the distance from the origin to the
//! hull). No cone under 90 degrees exists exactly when `p* = 0`, and since the hull
//! of the directions contains the origin exactly when the light lies in the hull of the
//! border points, the exact fit decides single versus dual exactly: one paraboloid
//! suffices whenever the light is outside the truncated frustum. The paper's fit, in
//! contrast, goes dual whenever its averaged cone reaches 90 degrees.
//!
//! # The dual fallback
//!
//! When one paraboloid cannot cover the truncated frustum (the light inside it, or a
//! cone of 90 degrees or more), the plan renders two, uncut. The paper turns the
//! front paraboloid toward the view and says the result then equals a DPSM. It does
//! not: a paraboloid's linear texel density at angle `theta` from its axis is
//! proportional to `1 / (1 + cos theta)`, so the axis is its sparsest direction and
//! the rim (the seam between the two maps) twice as dense. Facing the view puts the
//! view on the sparsest texels; measured with the `compare` report of
//! `shadowmap-eval` (1M texels, seed 1), that turned map had a p95 aliasing error
//! 1.55 times a DPSM facing straight down on `facing_point` (28.4 against 18.4) and
//! 1.12 times on `point_inside` (5.60 against 5.02).
//!
//! The plan instead chooses the dual axis that minimizes the largest predicted
//! texel-to-pixel ratio over 15 sample points of the truncated frustum (corners and
//! centres of its near, middle and far cross-sections), among the up hint's axis (a
//! fixed DPSM orientation) and every axis perpendicular to two sample directions:
//!
//! ```text
//! cost(a) = max_i (|v_i| + |a . v_i|) / s_i     v_i = P_i - L,  s_i = cross-section diagonal
//! ```
//!
//! `|v_i| (1 + |cos theta_i|)` is proportional to the world size of a texel at `P_i`
//! and `s_i` to that of a pixel, so the view's directions end up near the seam. On the
//! same report the dual fallback then beats the downward DPSM on every point
//! configuration instead of losing (`facing_point` 15.5, `point_inside` 4.56).
//!
//! The same cost also decides a cone under 90 degrees: a wide cut spends the single
//! map's texels at its sparse centre (a texel there spans `zoom (1 + cos theta)`
//! times a dual map's centre texel), while the dual map has `1 / sqrt 2` of its
//! side, so the plan goes dual ([`DualReason::DualFiner`]) when
//!
//! ```text
//! max_i zoom (|v_i| + a . v_i) / s_i / sqrt(2)  >  cost(dual axis)
//! ```
//!
//! ([`IpsmPlan::with_dual`] builds a plan's dual alternatives for a renderer that
//! measures them on its own samples, as `shadowmap::fit` does with eye samples.)
//!
//! # Measured gain
//!
//! Over 2000 random light and camera configurations (`examples/ipsm_table.rs`; the
//! camera perspective with fov 30 to 100 degrees, aspect 1 to 2.4, the truncated
//! frustum a random slice of `[0.1, 500]`, the light uniform in a 400-unit cube around
//! the camera), texel-area gain `(zoom_paper / zoom_exact)²` (how many more texels
//! per steradian the exact cone gives, 1 where both plans are dual):
//!
//! | configurations | count | mean gain | median gain | p95 gain |
//! |---|---|---|---|---|
//! | all | 2000 | 1.583 | 1.419 | 2.652 |
//! | exact fit single | 1898 | 1.614 | 1.450 | 2.667 |
//!
//! | outcome | fraction |
//! |---|---|
//! | dual with the paper's cone, single with the exact cone | 11.9% |
//! | single with both | 83.0% |
//! | dual with both (light inside the truncated frustum) | 5.1% |
//!
//! On average the exact cone gives about 1.6 times the texels per steradian of the
//! paper's cone, and in about one configuration in eight it saves the back
//! paraboloid's whole render pass (the paper's averaged cone reaches 90 degrees while
//! the light is outside the truncated frustum). The exact fit never turns a single
//! case dual (the example asserts it).
//!
//! Reproduce with `cargo run --release -p shadowmap-paraboloid --example ipsm_table`.
//!
//! # Cost
//!
//! `cargo bench --bench paraboloid` (workspace root) times one [`IpsmPlan::new`] call,
//! cycling through 64 fixed configurations (single and dual), with each fit and with
//! `Camera::validate` alone in the same run, and the two cone fits alone. In one run
//! on the shared 2-core development machine (heavily loaded, so read the ratios, not
//! the times): exact plan / paper plan 1.15, exact plan / `Camera::validate` 3.1,
//! exact cone fit / paper cone fit 4.8. The plan validates the camera once at its
//! door and then works on the validated slice.
//!
//! The exact fit scores the paper's axis, the 8 directions and the 28 pair midpoints,
//! then bounds each of the 56 triangle circumcentres by its norm and by its
//! barycentric weights (the minimum-norm point lies inside its support triangle), so
//! only a few triples are scored; the dual fallback's axis search stops scoring a
//! candidate as soon as it cannot win. The plan allocates nothing (a counting
//! allocator test, `tests/no_alloc.rs`, checks both fits, single and dual).
//!
//! # Bad input
//!
//! Every builder returns a [`ParaboloidError`] for input it cannot honour and says
//! which in its docs; none panics or returns a NaN. [`IpsmPlan::new`] has documented
//! fallbacks instead of errors where a renderer should keep rendering: a light inside
//! the truncated frustum, on one of its border points, at the centroid of the
//! directions (paper fit), or with a cone of 90 degrees or more gives a regular DPSM
//! whose seam passes through the view ([`IpsmPlan::dual_reason`] says why; see
//! [The dual fallback](#the-dual-fallback)).
//!
//! | input | result |
//! |---|---|
//! | NaN or infinite value | [`ParaboloidError::NonFinite`] (or [`ParaboloidError::Frustum`] from camera and light checks) |
//! | light on a border point | dual fallback ([`DualReason::LightOnFrustumPoint`]); [`fit_minimal_cone`] / [`fit_paper_cone`]: [`ParaboloidError::ZeroDirection`] for the zero direction |
//! | light at the centroid of the directions | paper plan: dual fallback ([`DualReason::DirectionsCancel`] or `LightInsideFrustum`); [`fit_paper_cone`]: [`ParaboloidError::DirectionsCancel`] |
//! | light inside the truncated frustum | dual fallback; [`fit_minimal_cone`]: [`ParaboloidError::NoConeUnder90`] |
//! | degenerate frustum | [`ParaboloidError::DegenerateFrustum`], or the camera's error |
//! | `near >= range`, `near <= 0` | [`ParaboloidError::InvalidDepthRange`] |
//! | depth bounds with `min > max` | [`ParaboloidError::InvalidDepthBounds`] |
//! | directional light | [`ParaboloidError::UnsupportedLight`] |
//!
//! # Cube maps
//!
//! [`CubeMap::fit`] renders up to six 90-degree perspective faces around the light
//! ([`CubeFaceId`]: along the world axes, or the cube turned about the world's `Y`
//! axis toward the visible receivers, [`CubeOrientation`]), one map per kept face, with
//! ordinary matrices (`clip_from_world`, WebGPU clip space, reversed-Z optional), so
//! no caster subdivision is needed. As IPSM focuses the paraboloid, it focuses each
//! face on the visible receivers `V = slice ∩ receivers ∩ range box` (the truncated
//! view frustum, the receiver box, the box of the light's range):
//!
//! ```text
//! window(face) = bounding rectangle of proj(V ∩ {d >= near}) ∩ [-1, 1]²
//! proj(a, b, d) = (a / d, b / d)      (face coordinates: right, up, forward)
//! near(face)    = clamp(min d over casters ∩ range box ∩ window frustum, near option, min d over V)
//! far(face)     = min(max d over V, range)
//! ```
//!
//! A face whose window is empty is skipped. [`CubeOptions::focused`] off keeps the
//! same faces at their full 90 degrees over `[near, range]`: the unfocused cube of
//! the engines that skip faces by culling (with [`CubeOrientation::WorldAxes`]).
//!
//! The cube's orientation is free (its faces cover every direction however it is
//! turned), and it decides how the visible receivers fall across the faces. With
//! world-axis faces, receivers that spread less than 90 degrees around a lamp can
//! still straddle two or three faces, each face then with its own minimum size and
//! place in the atlas; turned so that one side face looks at the receivers' centre,
//! they fall in that face (and the floor's), but a turned window only bounds the
//! edges of axis-aligned walls that world-axis windows fit exactly. Neither wins
//! everywhere: [`CubeOrientation::Predicted`] fits both and keeps the one with the
//! smaller predicted error; with [`FaceSizes::ByNeed`] and the eye's samples,
//! `shadowmap::fit` measures both on the samples instead (over 86 to 88 point-light
//! cases per seed at seeds 25 and 26 of `compare --sweep 64`: 5% lower p95 `m` on
//! average, at most 0.1% higher on any case), and a third beside them, the cube
//! stood on a corner ([`CubeOrientation::CornerUp`]), whose faces meet a low
//! lamp's horizon away from their centres.
//!
//! The faces share [`CubeOptions::texel_budget`] ([`CubeOptions::sizes`]):
//! [`FaceSizes::Equal`] gives each the same side (one texture-array layer each, what
//! engines and the `shadowmap-wgpu` pass render), so a face skipped gives the others
//! more texels and a focused window never has fewer texels per steradian than the
//! full face. With the light among the visible receivers every face is kept, and the
//! faces toward the eye need several times the texels of the others:
//! [`FaceSizes::ByNeed`] sizes each face by the density it needs (predicted on the
//! receivers' box, so that every face is predicted to reach the same error;
//! `shadowmap::fit` measures the needs on the eye's samples when it has them and
//! sizes the faces for the least texels that serve 95% of those samples over all
//! faces, see [`CubeMap::set_sizes_by_need_with_floor`]). The faces' maps are then tiles of one atlas ([`CubeMap::atlas`],
//! shelves of tiles, the largest first, at the shelf width that gives the smallest
//! atlas), and its whole area is what the map costs
//! ([`CubeMap::texels`]); [`CubeMap::atlas_sample`] turns a face's sample into atlas
//! coordinates.
//!
//! A point maps through the kept face whose window holds it, the major-axis face
//! first (see [`CubeFace::sample`] for the formula); the depth is the perspective
//! depth of the face, `far (d - near) / ((far - near) d)`.
//!
//! ```
//! use glam::{DVec3, Vec3};
//! use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds, ShadowMapping};
//! use shadowmap_paraboloid::{CubeMap, CubeOptions};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 200.0),
//! )?;
//! // A lamp 20 m ahead, 8 m up, over a ground slab.
//! let light = Light::Point { position: Vec3::new(0.0, 8.0, -20.0), range: 100.0 };
//! let ground = Aabb::new(Vec3::new(-100.0, -0.5, -200.0), Vec3::new(100.0, 0.0, 10.0));
//! let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 10.0 * Vec3::Y));
//!
//! let cube = CubeMap::fit(&light, &camera, None, &scene, &CubeOptions::default())?;
//! // Nothing visible lies above the lamp: its up face is skipped.
//! assert!(cube.layers() < 6);
//! // A visible ground point lands in a kept face, inside its window.
//! let s = cube.map_point(DVec3::new(3.0, 0.0, -30.0)).expect("covered");
//! assert!(s.layer < cube.layers());
//! assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
//! assert!((0.0..=1.0).contains(&s.depth));
//!
//! // The unfocused cube keeps the same faces, at their full size.
//! let full = CubeMap::fit(&light, &camera, None, &scene, &CubeOptions::default().with_focused(false))?;
//! assert_eq!(full.layers(), cube.layers());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Measured with the `compare` report of `shadowmap-eval` (seed 1, 1M texels, p95
//! aliasing error `m`; `cube`: focused, sized by the eye samples' needs; `equal`:
//! equal full faces, what engines render; RTW over the focused faces is the
//! umbrella's `CubeRtw`):
//!
//! | configuration | DPSM | IPSM exact | cube, by need | cube, equal full faces | RTW over the faces | tiled |
//! |---|---|---|---|---|---|---|
//! | `point_near` | 4.73 | 2.62 | 1.72 (5 faces) | 2.46 | 1.11 | 0.79 |
//! | `point_mid` | 28.9 | 13.2 | 7.22 (5 faces) | 18.6 | 1.48 | 1.90 |
//! | `point_far` | 115 | 55.7 | 25.6 (5 faces) | 97.2 | 2.12 | 3.40 |
//! | `point_inside` | 5.02 | 4.56 | 4.52 (6 faces) | 5.42 | 1.03 | 1.47 |
//! | `facing_point` | 18.4 | 15.5 | 10.3 (6 faces) | 23.7 | 1.57 | 1.97 |
//!
//! With the light among the visible receivers every face is kept, and six equal maps
//! of `1024² / 6` texels lose to a DPSM's two of `1024² / 2` (1.08 and 1.29 times its
//! `m`); sized by need, the faces toward the eye get the texels and the cube has
//! 0.22 to 0.56 times the DPSM's error, 0.90 times with the light inside the view. The focused fit costs about 0.1 ms with equal faces
//! (`cargo bench --bench paraboloid -- cube_fit`: about 8 times an exact IPSM plan on
//! the shared development machine); sizing by the prediction on the receivers' box
//! casts a grid of 24 x 14 view rays on top.
//!
//! # Tiled cube maps
//!
//! A face's texels all have one size, and a warp of the face (RTW) moves them only
//! by whole rows and columns, so the texels a row needs for its nearest receiver are
//! spent along the whole row. [`TiledCube`] (Arvo, *Tiled Shadow Maps*, CGI 2004;
//! current engines' virtual shadow maps choose each page's resolution the same way)
//! cuts each kept face into `grid x grid` cells ([`TileOptions`]), gives each cell
//! as many texels per unit of `uv` as the caller says it needs (the umbrella's
//! `TiledCube` technique: its eye samples' needs, but for the 5% of all samples
//! that would cost the most texels), groups
//! four neighbours into one tile where that costs no more texels (a quadtree: a
//! uniform region pays one guard border, not one per cell), keeps the grid (halving
//! from the one asked) whose tiles get the most texels, and packs the tiles into one
//! atlas of the budget. Each tile renders its
//! face's projection cropped to it ([`TiledCube::tile_clip_from_world`]) into its
//! square ([`TiledCube::tile_viewport`]); a point maps through its face, its cell
//! ([`TiledCube::table`]) and its tile, the tile being the sample's layer
//! ([`TiledCube::atlas_sample`] gives the atlas coordinates). Where the light is near
//! the eye (`point_near` above) the tiles need 0.42 times the focused cube's error;
//! where the need varies smoothly along rows and columns (a light far down the
//! street), RTW's warp of the whole face does better.
//!
//! ```
//! use glam::{DVec2, DVec3, Vec3};
//! use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds, ShadowMapping};
//! use shadowmap_paraboloid::{CubeMap, CubeOptions, TileOptions, TiledCube};
//!
//! let camera = Camera::look_to(
//!     Vec3::new(0.0, 2.0, 0.0),
//!     Vec3::NEG_Z,
//!     Vec3::Y,
//!     Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 200.0),
//! )?;
//! let light = Light::Point { position: Vec3::new(0.0, 8.0, -20.0), range: 100.0 };
//! let ground = Aabb::new(Vec3::new(-100.0, -0.5, -200.0), Vec3::new(100.0, 0.0, 10.0));
//! let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 10.0 * Vec3::Y));
//! let cube = CubeMap::fit(&light, &camera, None, &scene, &CubeOptions::default())?;
//!
//! // Each cell's need (texels per unit of face uv): here the upper half of every
//! // face four times the lower half's.
//! let options = TileOptions::default().with_grid(8);
//! let cells = (cube.layers() * 64) as usize;
//! let needs: Vec<f64> = (0..cells).map(|i| if i % 64 < 32 { 800.0 } else { 200.0 }).collect();
//! let tiled = TiledCube::new(cube, &options, &needs, 512 * 512)?;
//! assert!(tiled.texels() <= 512 * 512);
//! // Uniform halves merge into few tiles; the upper ones are four times as wide.
//! assert!(tiled.tiles.len() < cells);
//! let s = tiled.map_point(DVec3::new(3.0, 0.0, -30.0)).expect("covered");
//! let tile = tiled.tiles[s.layer as usize];
//! assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
//! let atlas = tiled.atlas_sample(s).unwrap();
//! assert!(atlas.uv.cmple(DVec2::ONE).all() && tile.side >= 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Errors ([`ParaboloidError`]): as the other builders for non-finite input, a bad
//! near option or depth range, and a directional light;
//! `ParaboloidError::Frustum(FrustumError::SliceOutsideScene)` when no visible
//! receiver is within the light's range (nothing to shadow); a zero texel budget is
//! `InvalidOptions`. The fit allocates nothing (fixed arrays of six faces; the
//! projected points of a face and the prediction's rays on the stack).
//!
//! # Features
//!
//! `std` (default) or `libm` provide float math; with `libm` and without `std` the
//! crate is `no_std` (it uses `alloc` only for [`subdivide_triangles`] and the tiles of
//! [`TiledCube`]). The plan
//! allocates nothing.
//!
//! Optional data features, `no_std` compatible: `serde` (`Serialize` and
//! `Deserialize` on the options and results; [`IpsmOptions`] and
//! [`SubdivisionOptions`] deserialize through the builders' checks) and `mint`
//! (glam's and `shadowmap-frustum`'s conversions), and `bytemuck` (`Pod` and
//! `Zeroable` on [`ParaboloidUniform`], so the lookup's block uploads as is).

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod cone;
mod cube;
mod cube_fit;
mod cube_sizes;
mod cube_tiles;
mod error;
mod map;
mod orient;
mod plan;
#[cfg(feature = "serde")]
mod serde_impls;
mod subdivide;

pub use cone::{Cone, ConeFit, MAX_CONE_DIRECTIONS, MIN_ZOOM, fit_minimal_cone, fit_paper_cone};
pub use cube::{CubeFace, CubeFaceId, CubeMap, CubeOptions, CubeOrientation};
pub use cube_sizes::{FaceSizes, MIN_ASPECT, MIN_SIDE_RATIO};
pub use cube_tiles::{CubeTile, MAX_TILE_BORDER, MAX_TILE_GRID, TileOptions, TiledCube};
pub use error::ParaboloidError;
pub use map::{MapOptions, ParaboloidMap, ParaboloidMode, ParaboloidUniform, Side, UsableDisc};
pub use plan::{DualReason, IpsmOptions, IpsmPlan};
pub use subdivide::{
    DEVIATION_SAMPLES, ParaboloidSplitRule, SubdivisionOptions, edge_subdivisions,
    subdivide_triangle, subdivide_triangles,
};

pub use shadowmap_frustum;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
