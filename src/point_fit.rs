//! The fits of RTW over the point-light bases (each side of the IPSM paraboloid, each
//! focused face of the cube map) and of the tiled cube map.

use alloc::vec::Vec;

use arrayvec::ArrayVec;
use glam::DVec3;
use shadowmap_frustum::math::sqrt;
use shadowmap_frustum::{LightDirection, ShadowMapping, ShadowSample};
use shadowmap_paraboloid::{
    CubeMap, CubeOptions, CubeOrientation, FaceSizes, IpsmOptions, IpsmPlan, ParaboloidMap, Side,
    TileOptions, TiledCube,
};
use shadowmap_rtw::{
    AxisNeed, BasePoint, EyeSample, ImportanceMap, WarpMaps, oracle_needs, oracle_needs_of,
};

use crate::fit::{FitError, FitInput, front_lit, is_front_lit, layer_side};
use crate::rtw_strength::{LitSplit, build_measured_by, warped_error};
use crate::sample_error::{MAX_SAMPLES, Samples, Unlit, percentile_of, sample_error};
use crate::shadow::Fitted;
use crate::technique::RtwPlan;

mod face_budget;
use face_budget::{FaceBudgetNeeds, face_densities};

/// The eye samples, which RTW requires.
fn eye_samples<'a>(
    input: &FitInput<'a>,
    technique: &'static str,
) -> Result<&'a [EyeSample], FitError> {
    input.eye_samples.ok_or(FitError::MissingInput {
        technique,
        input: "eye_samples",
    })
}

/// RTW over the IPSM paraboloid: per side, importance from the eye samples that
/// side stores ([`accumulate_side`]), then that side's tables at the strength of
/// least error measured on the front-lit samples it stores ([`front_lit`]; with
/// `build_measured_by`, as RTW over a directional light's uniform fit): where
/// backward analysis misjudges a room's walls, the full warp can lose to the
/// paraboloid it warps (a lamp beside the eye in a room: 1.16 times the DPSM's
/// error), and the strength 0 is that paraboloid. The samples the light reaches
/// from behind are dark whatever the map holds, and the quality report leaves them
/// out; counted in the measure (on the plane facing the bisector of the eye and
/// light directions), the surfaces turned away from a lamp in a room decided the
/// strength, and the full warp they chose measured 1.48 times the DPSM's error on
/// the lit ones (`compare --seed 59 --sweep 64`, random_indoor_room_023). The
/// importance is accumulated twice, from the front-lit samples and from all of
/// them, and the measure chooses between the two as between the strengths: neither
/// wins everywhere (at seed 59 of the sweep, random_indoor_room_023, the lit
/// samples' warp measured 0.59 times the other's error; at seed 54,
/// random_indoor_room_035, all samples' warp 0.78 times the lit ones').
///
/// The paraboloid warped is the plan's own map and, where the IPSM techniques keep
/// a dual alternative instead ([`fit_ipsm`]), that one too; the warp whose front-lit
/// samples' 95th percentile of `m` is smaller is kept. Neither base wins everywhere:
/// over wooded terrain the plan's own map started 1.09 times coarser than the DPSM
/// and no strength made that up, while in a city block the warp of the plan's own
/// map ended 2.8 times finer than any warp of the dual map.
pub(crate) fn fit_point_rtw(
    ipsm: &IpsmOptions,
    plan: &RtwPlan,
    input: &FitInput<'_>,
) -> Result<Fitted, FitError> {
    let own = IpsmPlan::new(input.light, input.camera, input.depth_bounds, ipsm)?;
    let samples = eye_samples(input, "point_rtw")?;
    let light = LightDirection::Position(own.map.position);
    let (lit, unlit): (Vec<EyeSample>, Vec<EyeSample>) =
        samples.iter().partition(|s| is_front_lit(s, light));
    let warped_own = warp_paraboloid(own, plan, input, &lit, &unlit)?;
    let kept = finest_ipsm(own, ipsm, input);
    let Some(ppr) = input.pixels_per_radian.filter(|_| kept.map != own.map) else {
        return Ok(warped_own);
    };
    let warped_kept = warp_paraboloid(kept, plan, input, &lit, &unlit)?;
    let error = |fitted: &Fitted| match fitted {
        Fitted::PointRtw { plan, front, back } => {
            let mapping = WarpedParaboloid {
                map: &plan.map,
                front,
                back: back.as_ref(),
            };
            front_lit_error(&mapping, &plan.map, input, samples, ppr)
        }
        _ => f64::INFINITY,
    };
    Ok(if error(&warped_kept) < error(&warped_own) {
        warped_kept
    } else {
        warped_own
    })
}

/// The [`NEED_PERCENTILE`] of `m` over the front-lit samples (those the quality
/// report measures) of `mapping`, a paraboloid mapping over `map` whose layers each
/// get the budget's side for its layer count; infinite where it covers none.
pub(crate) fn front_lit_error(
    mapping: &dyn ShadowMapping,
    map: &ParaboloidMap,
    input: &FitInput<'_>,
    samples: &[EyeSample],
    pixels_per_radian: f32,
) -> f64 {
    let side = f64::from(layer_side(input.texel_budget, map.layers()));
    let measured = Samples {
        unlit: Unlit::Skipped,
        ..Samples::new(input.camera, pixels_per_radian, samples)
    };
    let light = LightDirection::Position(map.position);
    sample_error(mapping, side, &measured, light, NEED_PERCENTILE).unwrap_or(f64::INFINITY)
}

/// RTW's tables over each side of `ipsm`'s map (see [`fit_point_rtw`]), from the
/// importance of the `lit` samples or of all of them (`unlit` the others),
/// measured on the `lit` ones.
fn warp_paraboloid(
    ipsm: IpsmPlan,
    plan: &RtwPlan,
    input: &FitInput<'_>,
    lit: &[EyeSample],
    unlit: &[EyeSample],
) -> Result<Fitted, FitError> {
    let map = ipsm.map;
    let n = plan.importance_side;
    let side_warps = |side: Side| -> Result<WarpMaps, FitError> {
        let mut warps = WarpMaps::new(n, n)?;
        let light = LightDirection::Position(map.position);
        build_measured_by(
            n,
            LitSplit { lit, unlit },
            |from, importance| accumulate_side(&map, side, from, plan, importance),
            &plan.warp,
            &mut warps,
            |warps| {
                let mapping = WarpedSide {
                    map: &map,
                    side,
                    warps,
                };
                warped_error(&mapping, lit, input.camera, light)
            },
        )?;
        Ok(warps)
    };
    let front = side_warps(Side::Front)?;
    let back = if map.layers() == 2 {
        Some(side_warps(Side::Back)?)
    } else {
        None
    };
    Ok(Fitted::PointRtw {
        plan: ipsm,
        front,
        back,
    })
}

/// Raises the cells of `importance` (over `side` of `map`, in its `uv`) to the
/// backward-analysis importance of `samples`, scaled by the paraboloid's footprint
/// there (world extent of a unit of `uv` across the ray:
/// `distance / sqrt(uv² per steradian)`); each cell keeps the largest.
fn accumulate_side(
    map: &ParaboloidMap,
    side: Side,
    samples: &[EyeSample],
    plan: &RtwPlan,
    importance: &mut ImportanceMap,
) -> Result<(), FitError> {
    let project = |p: DVec3| {
        let s = map.map_point(p).filter(|s| s.layer == side.layer())?;
        let world = p.as_vec3();
        let per_sr = f64::from(map.texels_per_steradian(world, 1)?);
        let toward_light = map.position.as_dvec3() - p;
        Some(BasePoint {
            uv: s.uv,
            footprint: toward_light.length() / sqrt(per_sr),
            toward_light,
        })
    };
    importance.accumulate_backward_with(project, samples, None, &plan.importance)?;
    Ok(())
}

/// Both sides of a paraboloid map, each warped by its tables: RTW over the
/// paraboloid as a mapping (the fitted technique's lookup, and what
/// [`fit_point_rtw`] measures a base's warp on).
pub(crate) struct WarpedParaboloid<'a> {
    pub(crate) map: &'a ParaboloidMap,
    pub(crate) front: &'a WarpMaps,
    pub(crate) back: Option<&'a WarpMaps>,
}

impl ShadowMapping for WarpedParaboloid<'_> {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let s = self.map.map_point(world)?;
        let warps = if s.layer == 0 { self.front } else { self.back? };
        warps.warp_sample(s)
    }
}

/// One side of a paraboloid map warped by `warps`: what [`fit_point_rtw`] measures
/// each strength of a side's warp on (the samples the other side stores are not
/// covered, so not counted).
struct WarpedSide<'a> {
    map: &'a ParaboloidMap,
    side: Side,
    warps: &'a WarpMaps,
}

impl ShadowMapping for WarpedSide<'_> {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let s = self.map.map_point(world)?;
        (s.layer == self.side.layer()).then(|| self.warps.warp_sample(s))?
    }
}

/// IPSM. With the eye samples and pixels per radian, the plan's map is measured on
/// the front-lit ones ([`sample_error`], as the quality report measures: a surface
/// the light reaches from behind is dark whatever the map holds, and measured on
/// the bisector's plane it chose the paper's cone over a DPSM-like dual map 1.17
/// times finer on the lit terrain) against its dual alternatives, the dual map of the plan's
/// own seam and the dual map of a DPSM's fixed axis (`-up_hint`), each at the
/// budget's side for its layer count, and the finest is kept: the plan's own
/// decision rests on the frustum's corners, which can favour a seam or a cut that
/// the visible surfaces do not.
pub(crate) fn fit_ipsm(options: &IpsmOptions, input: &FitInput<'_>) -> Result<IpsmPlan, FitError> {
    let plan = IpsmPlan::new(input.light, input.camera, input.depth_bounds, options)?;
    Ok(finest_ipsm(plan, options, input))
}

/// Of `plan` and its dual alternatives, the finest on the front-lit eye samples
/// (see [`fit_ipsm`]); `plan` without samples or pixels per radian.
fn finest_ipsm(plan: IpsmPlan, options: &IpsmOptions, input: &FitInput<'_>) -> IpsmPlan {
    let (Some(samples), Some(ppr)) = (input.eye_samples, input.pixels_per_radian) else {
        return plan;
    };
    let error = |p: &IpsmPlan| front_lit_error(&p.map, &p.map, input, samples, ppr);
    let mut best = (error(&plan), plan);
    for axis in [None, Some(-options.up_hint)] {
        if let Ok(alternative) = plan.with_dual(axis, options) {
            let e = error(&alternative);
            if e < best.0 {
                best = (e, alternative);
            }
        }
    }
    best.1
}

/// Cube maps. With [`FaceSizes::ByNeed`] and the eye samples and pixels per radian,
/// the faces' sides follow the density the samples they store need (the oracle's
/// isotropic requirement, [`oracle_needs`], of the samples the light reaches from
/// the front, which are the ones measured: the error `m` of a face of one texel per
/// side) instead of the prediction on the receivers' box, which misjudges a face
/// when the box is far from the surfaces (a terrain's box reaches the sky). The
/// sides are the least texels that serve all but `1 - NEED_PERCENTILE` of the
/// samples over all faces ([`face_densities`], found exactly over the faces): the 95th
/// percentile over the view, not each face's own. Equal errors per face would let
/// a face that a few pixels see at a grazing angle (a wall beside a lamp) take
/// most of the budget from the faces most pixels see.
///
/// With [`CubeOrientation::Predicted`] the world-axis, the turned and the
/// corner-up cube ([`CubeOrientation::CornerUp`]) are fitted and sized this way and
/// the one whose samples' 95th percentile of `m` is least is kept: the prediction
/// on the receivers' box misjudges some rooms (it turned a cube that then measured
/// 2.2 times the world-axis cube's error), the samples do not. Without the cube
/// stood on a corner, a lamp low among the receivers lost to DPSM (its level faces
/// cut the lamp's horizon through their centres: 1.12 and 1.16 times DPSM over
/// terrain and a city block at seeds 108 and 114 of `compare --sweep 64`, 0.86 and
/// 0.91 times with it).
pub(crate) fn fit_cube(options: &CubeOptions, input: &FitInput<'_>) -> Result<CubeMap, FitError> {
    let (FaceSizes::ByNeed, Some(samples), Some(ppr)) =
        (options.sizes, input.eye_samples, input.pixels_per_radian)
    else {
        return fit_faces(options, input);
    };
    let orientations: &[CubeOrientation] = match options.orientation {
        CubeOrientation::Predicted => &[
            CubeOrientation::WorldAxes,
            CubeOrientation::TowardReceivers,
            CubeOrientation::CornerUp,
        ],
        ref o => core::slice::from_ref(o),
    };
    let mut best: Option<(f64, CubeMap)> = None;
    for o in orientations {
        // Fitted at equal sides, sized by the samples; by the box's prediction only
        // where no sample gives a need.
        let oriented = options.with_orientation(*o);
        let mut cube = fit_faces(&oriented.with_sizes(FaceSizes::Equal), input)?;
        if best
            .as_ref()
            .is_some_and(|(_, b)| b.orientation() == cube.orientation())
        {
            continue;
        }
        let error = match size_by_samples(&mut cube, input, samples, ppr)? {
            Some(error) => error,
            None => {
                cube = fit_faces(&oriented, input)?;
                f64::INFINITY
            }
        };
        if best.as_ref().is_none_or(|(e, _)| error < *e) {
            best = Some((error, cube));
        }
    }
    match best {
        Some((_, cube)) => Ok(cube),
        None => fit_faces(options, input),
    }
}

/// Sizes the faces of `cube` by the needs of the eye samples they store (see
/// [`fit_cube`]); returns the [`NEED_PERCENTILE`] of the samples' `m` on the sized
/// faces, `None` (sizes unchanged) without a need.
fn size_by_samples(
    cube: &mut CubeMap,
    input: &FitInput<'_>,
    samples: &[EyeSample],
    pixels_per_radian: f32,
) -> Result<Option<f64>, FitError> {
    // At most `MAX_SAMPLES` of them (every `stride`-th), the front-lit ones (the
    // others are dark whatever the map holds), each measured on the face that
    // stores it, found once; no allocation per frame.
    let stride = samples.len().div_ceil(MAX_SAMPLES).max(1);
    let light = LightDirection::Position(cube.position);
    let no_face = u8::MAX;
    let faces: ArrayVec<u8, MAX_SAMPLES> = samples
        .iter()
        .step_by(stride)
        .take(MAX_SAMPLES)
        .map(|s| {
            let face = is_front_lit(s, light)
                .then(|| cube.map_point(s.position.as_dvec3()))
                .flatten();
            face.and_then(|x| u8::try_from(x.layer).ok())
                .unwrap_or(no_face)
        })
        .collect();
    let mut needs: ArrayVec<(usize, f64), MAX_SAMPLES> = ArrayVec::new();
    for layer in 0..cube.layers() {
        let Some(base) = cube.transform(layer) else {
            continue;
        };
        let stored = faces
            .iter()
            .enumerate()
            .filter(|(_, face)| u32::from(**face) == layer)
            .filter_map(|(k, _)| Some((k * stride, samples.get(k * stride)?)));
        oracle_needs_of(&base, input.camera, pixels_per_radian, stored, |_, need| {
            if need.isotropic.is_finite() && need.isotropic > 0.0 {
                let _ = needs.try_push((layer as usize, need.isotropic));
            }
        })?;
    }
    let densities = face_densities(&mut needs, cube.faces.len());
    let by_need: ArrayVec<Option<[f64; 2]>, 6> = densities
        .iter()
        .map(|&d| (d > 0.0).then_some([d, d]))
        .collect();
    if by_need.iter().all(Option::is_none) {
        return Ok(None);
    }
    cube.set_sizes_by_need_with_floor(&by_need, input.texel_budget, MEASURED_MIN_SIDE_RATIO);
    let mut errors: ArrayVec<f64, MAX_SAMPLES> = needs
        .iter()
        .filter_map(|&(layer, need)| {
            let side = cube.faces.get(layer)?.size.into_iter().min()?;
            Some(need / f64::from(side.max(1)))
        })
        .collect();
    Ok(percentile(&mut errors))
}

/// The smallest side of a face sized by measured needs ([`fit_cube`]), as a
/// fraction of the largest face's. The needs come from the surfaces the eye sees
/// (a regular subset of them), so a face is misjudged only where few pixels see it;
/// the box prediction's floor ([`shadowmap_paraboloid::MIN_SIDE_RATIO`], a quarter)
/// would keep 6% of the budget on three faces that such a few pixels see over wooded
/// terrain (1.11 times the DPSM's error there, 1.08 times at this floor).
const MEASURED_MIN_SIDE_RATIO: f64 = 1.0 / 16.0;

/// Margin of a face's window around its samples, as a fraction of their extent.
const SAMPLE_MARGIN: f64 = 0.01;

/// Narrows each face's window to the bounding rectangle of the samples it stores
/// (with [`SAMPLE_MARGIN`]): the warp's tables then spend their cells on what the
/// eye sees. A face without samples keeps its window.
fn narrow_to_samples(cube: &mut CubeMap, samples: &[EyeSample]) -> Result<(), FitError> {
    let mut boxes = [(glam::DVec2::INFINITY, glam::DVec2::NEG_INFINITY); 6];
    for s in samples {
        if let Some(x) = cube.map_point(s.position.as_dvec3()) {
            if let Some((lo, hi)) = boxes.get_mut(x.layer as usize) {
                *lo = lo.min(x.uv);
                *hi = hi.max(x.uv);
            }
        }
    }
    for (layer, (lo, hi)) in (0..cube.layers()).zip(boxes) {
        let margin = (hi - lo) * SAMPLE_MARGIN + 1e-6;
        cube.narrow_to_uv(layer, lo - margin, hi + margin)?;
    }
    Ok(())
}

/// The cube map of `options` fitted to the frame, over the input's texel budget.
fn fit_faces(options: &CubeOptions, input: &FitInput<'_>) -> Result<CubeMap, FitError> {
    let options = options.with_texel_budget(input.texel_budget);
    Ok(CubeMap::fit(
        input.light,
        input.camera,
        input.depth_bounds,
        &input.scene,
        &options,
    )?)
}

/// The samples each kept face of `cube` stores (its layer's entry), in their order:
/// each sample is mapped once, and each face's needs are then computed on its own
/// samples only.
fn samples_by_face(cube: &CubeMap, samples: &[EyeSample]) -> ArrayVec<Vec<EyeSample>, 6> {
    let mut by_face: ArrayVec<Vec<EyeSample>, 6> = (0..cube.layers()).map(|_| Vec::new()).collect();
    for s in samples {
        if let Some(face) = cube
            .map_point(s.position.as_dvec3())
            .and_then(|x| by_face.get_mut(x.layer as usize))
        {
            face.push(*s);
        }
    }
    by_face
}

/// The needs ([`oracle_needs`]) of the samples a cube's `layer` stores
/// ([`samples_by_face`]) for which `keep` holds, into `out` (cleared first).
fn stored_needs(
    cube: &CubeMap,
    layer: u32,
    camera: &shadowmap_frustum::Camera,
    pixels_per_radian: f32,
    stored: &[EyeSample],
    out: &mut Vec<AxisNeed>,
    mut keep: impl FnMut(usize, &AxisNeed) -> bool,
) -> Result<(), FitError> {
    out.clear();
    let Some(base) = cube.transform(layer) else {
        return Ok(());
    };
    oracle_needs(&base, camera, pixels_per_radian, stored, |i, need| {
        if keep(i, &need) {
            out.push(need);
        }
    })?;
    Ok(())
}

/// The [`NEED_PERCENTILE`] of `values` (reordered), `None` when empty or not
/// positive and finite.
fn percentile(values: &mut [f64]) -> Option<f64> {
    percentile_of(values, NEED_PERCENTILE)
}

/// The focused faces of equal sizes, each narrowed to the eye samples it stores
/// ([`narrow_to_samples`]), with the samples and the image's focal length that
/// `technique` requires.
fn narrowed_faces<'a>(
    options: &CubeOptions,
    input: &FitInput<'a>,
    technique: &'static str,
) -> Result<(CubeMap, &'a [EyeSample], f32), FitError> {
    let samples = eye_samples(input, technique)?;
    let pixels_per_radian = input.pixels_per_radian.ok_or(FitError::MissingInput {
        technique,
        input: "pixels_per_radian",
    })?;
    let mut cube = fit_faces(&options.with_sizes(FaceSizes::Equal), input)?;
    narrow_to_samples(&mut cube, samples)?;
    Ok((cube, samples, pixels_per_radian))
}

/// RTW over the focused faces of a cube map: per kept face, each eye sample the face
/// stores asks for the texel density it needs along the face's `u` and `v` (the
/// oracle's exact requirement, [`oracle_needs`]: the screen-to-texture Jacobian
/// through its surface, with its own normal where it is lit from the front, the
/// bisector of the eye and light directions elsewhere, since shading darkens those
/// surfaces whatever the map holds); the column maxima of the `u` needs and the row
/// maxima of the `v` needs build the face's tables. The faces then share the budget
/// for the front-lit samples (the ones the quality report measures) at the needs
/// along `u` and `v` each keeps after its face's warp, in the sizes of three
/// candidates whose packed faces leave those samples the least error (the
/// [`NEED_PERCENTILE`] of the larger of `u / width` and `v / height`;
/// [`FaceBudgetNeeds`]): the least texels that serve that share of them over all
/// faces, each face's width over height chosen with them (as the focused cube
/// maps' faces share it, [`face_densities`]); each face's sides in
/// proportion to its front-lit samples' percentiles (equal error per face); and
/// the same over all its samples, the unlit ones on the bisector's plane, with the
/// floor of [`CubeMap::set_sizes_by_need`]. Where a face stores no front-lit
/// sample, the first two keep it at the floor of [`MEASURED_MIN_SIDE_RATIO`]. Sized
/// by the last alone, a face that held mostly walls turned away from a lamp took
/// as many texels as the lit ones: 1.35 times the DPSM's error, 3.0 times the
/// focused cube maps' (`compare --seed 59 --sweep 64`, random_indoor_room_023).
pub(crate) fn fit_cube_rtw(
    options: &CubeOptions,
    plan: &RtwPlan,
    input: &FitInput<'_>,
) -> Result<Fitted, FitError> {
    let (mut cube, samples, pixels_per_radian) = narrowed_faces(options, input, "cube_rtw")?;
    let light = LightDirection::Position(cube.position);
    let n = plan.importance_side;
    let (mut map_u, mut map_v) = (ImportanceMap::new(n, n)?, ImportanceMap::new(n, n)?);
    let mut warps = Vec::with_capacity(cube.faces.len());
    let mut face_needs: Vec<AxisNeed> = Vec::new();
    let mut lit: Vec<bool> = Vec::new();
    let lit_total = samples.iter().filter(|s| is_front_lit(s, light)).count();
    let mut budget_needs = FaceBudgetNeeds::new(lit_total);
    let by_face = samples_by_face(&cube, samples);
    for (layer, stored) in (0..cube.layers()).zip(&by_face) {
        map_u.clear();
        map_v.clear();
        lit.clear();
        stored_needs(
            &cube,
            layer,
            input.camera,
            pixels_per_radian,
            stored,
            &mut face_needs,
            |i, n| {
                let kept = map_u.splat_need(n.uv, n.u) && map_v.splat_need(n.uv, n.v);
                if kept {
                    lit.push(stored.get(i).is_some_and(|s| is_front_lit(s, light)));
                }
                kept
            },
        )?;
        let mut w = WarpMaps::new(n, n)?;
        w.build_separable(&map_u, &map_v, &plan.warp)?;
        budget_needs.add_face(layer as usize, &w, &face_needs, &lit);
        warps.push(w);
    }
    budget_needs.size(&mut cube, input.texel_budget);
    Ok(Fitted::CubeRtw { cube, warps })
}

/// Tiled cube maps: the focused faces narrowed to the samples they store (as for
/// [`fit_cube_rtw`]), each cut into `tiles.grid²` cells, each cell's tile as many
/// texels per unit of face `uv` as its samples' isotropic need ([`oracle_needs`]:
/// the largest extent of one unit of `uv` on the screen, in pixels, with the true
/// normal where the sample is lit from the front and the bisector elsewhere) asks,
/// but for the [`NEED_PERCENTILE`] share of all samples that costs the least
/// ([`cell_densities`]), all tiles scaled together to the budget.
pub(crate) fn fit_tiled_cube(
    options: &CubeOptions,
    tiles: &TileOptions,
    input: &FitInput<'_>,
) -> Result<Fitted, FitError> {
    tiles.validate()?;
    let (cube, samples, pixels_per_radian) = narrowed_faces(options, input, "cube_tiled")?;
    let grid = tiles.grid as usize;
    // The windows cover every sample; the texels go where the light reaches the
    // surface from the front (the others are dark whatever the map holds).
    let lit = front_lit(samples, LightDirection::Position(cube.position));
    let by_face = samples_by_face(&cube, &lit);
    // (cell, need) of every sample, then each cell's density.
    let mut needs: Vec<(usize, f64)> = Vec::with_capacity(samples.len());
    let mut face_needs: Vec<AxisNeed> = Vec::new();
    for (layer, stored) in (0..cube.layers()).zip(&by_face) {
        stored_needs(
            &cube,
            layer,
            input.camera,
            pixels_per_radian,
            stored,
            &mut face_needs,
            |_, n| n.isotropic.is_finite() && n.isotropic > 0.0,
        )?;
        let cell = |x: f64| ((x * grid as f64).max(0.0) as usize).min(grid - 1);
        let first = layer as usize * grid * grid;
        needs.extend(
            face_needs
                .iter()
                .map(|n| (first + cell(n.uv.y) * grid + cell(n.uv.x), n.isotropic)),
        );
    }
    let densities = cell_densities(&mut needs, cube.faces.len() * grid * grid);
    let tiled = TiledCube::new(cube, tiles, &densities, input.texel_budget)?;
    Ok(Fitted::TiledCube(tiled))
}

/// Each cell's density (texels per unit of face `uv`) from the `(cell, need)` of
/// every sample (reordered): the least texels that serve all but
/// `1 - NEED_PERCENTILE` of the samples at their need. Greedily, from every cell at
/// its largest need, the sample whose giving up saves the most texels (its cell
/// then needs its next sample's need) is given up, until that share is. A sample
/// given up still gets [`GIVEN_UP_FLOOR`] of its need, or of the samples'
/// [`NEED_PERCENTILE`] if that is less: the p95 is what is optimized, but no
/// region of the view is left at one texel.
fn cell_densities(needs: &mut [(usize, f64)], cells: usize) -> Vec<f64> {
    use alloc::collections::BinaryHeap;
    needs.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
    // Per cell: where its samples start and how many are given up.
    let mut start = alloc::vec![usize::MAX; cells];
    let mut end = alloc::vec![0usize; cells];
    for (i, n) in needs.iter().enumerate() {
        if let (Some(s), Some(e)) = (start.get_mut(n.0), end.get_mut(n.0)) {
            *s = (*s).min(i);
            *e = i + 1;
        }
    }
    let need_at = |i: usize, e: usize| if i < e { needs[i].1 } else { 0.0 };
    // The saving of giving up sample `i` of a cell ending at `e`; non-negative, so
    // its bits order as the value does.
    let saving = |i: usize, e: usize| {
        let (a, b) = (need_at(i, e), need_at(i + 1, e));
        (a * a - b * b).max(0.0).to_bits()
    };
    let mut heap: BinaryHeap<(u64, usize)> = (0..cells)
        .filter(|&c| start[c] < end[c])
        .map(|c| (saving(start[c], end[c]), c))
        .collect();
    let mut top = start.clone();
    let drops = ((1.0 - NEED_PERCENTILE) * needs.len() as f64) as usize;
    for _ in 0..drops {
        let Some((_, c)) = heap.pop() else { break };
        top[c] += 1;
        if top[c] < end[c] {
            heap.push((saving(top[c], end[c]), c));
        }
    }
    let mut all: Vec<f64> = needs.iter().map(|n| n.1).collect();
    let common = percentile(&mut all).unwrap_or(0.0);
    (0..cells)
        .map(|c| {
            if start[c] < end[c] {
                let floor = GIVEN_UP_FLOOR * need_at(start[c], end[c]).min(common);
                need_at(top[c], end[c]).max(floor)
            } else {
                0.0
            }
        })
        .collect()
}

/// Share of its need a sample given up by [`cell_densities`] still gets (at most
/// that share of the common need): twice the error of the others at worst.
const GIVEN_UP_FLOOR: f64 = 0.5;

/// Share of a face's samples whose need decides its size.
const NEED_PERCENTILE: f64 = 0.95;

#[cfg(test)]
mod tests;
