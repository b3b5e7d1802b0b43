//! Generators and checks for RTW over the IPSM paraboloid and over the cube map's
//! faces, and for tiled cube maps (fitted by the umbrella crate's `fit`; the fuzz targets and the property
//! tests pass the fitted mapping in).

use arbitrary::Unstructured;
use glam::DVec2;
use shadowmap_frustum::ShadowMapping;
use shadowmap_paraboloid::{CubeMap, ParaboloidMap, TiledCube};
use shadowmap_rtw::EyeSample;

use crate::cube::{CubeInput, cube_input, near_floor, visible_points};
use crate::paraboloid::{PlanInput, plan_input};
use crate::rtw::frustum_samples;
use crate::{GenResult, log_uniform, unit_vec3};

/// Input of [`check_point_rtw`]: an IPSM plan input and eye samples in its camera's
/// frustum.
#[derive(Clone, Debug)]
pub struct PointRtwCase {
    /// Light (point or spot: the fit refuses a spot), camera, depth bounds, options.
    pub plan: PlanInput,
    /// What the eye sees.
    pub samples: Vec<EyeSample>,
}

/// A valid plan input (the light inside, next to or far from the truncated
/// frustum) with up to 64 samples in the camera's frustum.
pub fn point_rtw_case(u: &mut Unstructured<'_>) -> GenResult<PointRtwCase> {
    let plan = plan_input(u)?;
    let count = u.int_in_range(0usize..=64)?;
    let samples = frustum_samples(u, &plan.camera, count)?;
    Ok(PointRtwCase { plan, samples })
}

/// RTW over the paraboloid `map` (`rtw`, the fitted technique) on a case: every
/// sample the paraboloid stores (inside the cut) is mapped by RTW into the same
/// layer's `[0, 1]²` with the paraboloid's depth (coverage; finite). Returns how many
/// samples were checked.
pub fn check_point_rtw(
    case: &PointRtwCase,
    map: &ParaboloidMap,
    rtw: &impl ShadowMapping,
) -> usize {
    let inside = |uv: DVec2| uv.cmpge(DVec2::ZERO).all() && uv.cmple(DVec2::ONE).all();
    let mut checked = 0;
    for s in &case.samples {
        let p = s.position.as_dvec3();
        let Some(b) = map.map_point(p).filter(|b| inside(b.uv)) else {
            continue;
        };
        let r = rtw
            .map_point(p)
            .expect("stored by the paraboloid, mapped by RTW");
        assert!(r.uv.is_finite() && inside(r.uv), "{:?} left the map", r.uv);
        assert_eq!(
            (r.layer, r.depth),
            (b.layer, b.depth),
            "layer or depth changed"
        );
        checked += 1;
    }
    checked
}

/// Input of [`check_cube_samples`]: a cube input (the light inside the view, next to
/// a corner, far away, inside a caster's bounds, ...) and eye samples on its visible
/// receivers, each with its own normal or none.
#[derive(Clone, Debug)]
pub struct CubeSamplesCase {
    /// Light, camera, depth bounds, scene and options.
    pub cube: CubeInput,
    /// What the eye sees: points of the visible receivers.
    pub samples: Vec<EyeSample>,
    /// The image's focal length in pixels.
    pub pixels_per_radian: f32,
}

/// A valid cube input with samples at the visible receivers' points (see
/// [`visible_points`]).
pub fn cube_samples_case(u: &mut Unstructured<'_>) -> GenResult<CubeSamplesCase> {
    let cube = cube_input(u)?;
    let eye = cube.camera.eye();
    let mut samples = Vec::new();
    for p in visible_points(&cube) {
        let normal = if u.arbitrary()? {
            unit_vec3(u)?
        } else {
            glam::Vec3::ZERO
        };
        samples.push(EyeSample {
            position: p,
            normal,
            eye_distance: p.distance(eye),
        });
    }
    let pixels_per_radian = log_uniform(u, 1.0, 4000.0)?;
    Ok(CubeSamplesCase {
        cube,
        samples,
        pixels_per_radian,
    })
}

/// A cube map fitted to a case's samples (`cube`, the fitted map; `mapping`, the
/// technique's lookup: the cube itself or RTW over its faces) covers every sample
/// beyond the near floor and within the light's range: the cube stores it in a kept
/// face, and `mapping` maps it into the same layer, inside `[0, 1]²` (up to
/// rounding), at the cube's depth. The faces' sizes are positive and their atlas
/// within `budget` (unless at its smallest, four texels a side). Returns how many
/// samples were checked.
///
/// # Errors
/// A description of the violated clause.
pub fn check_cube_samples(
    case: &CubeSamplesCase,
    cube: &CubeMap,
    mapping: &impl ShadowMapping,
    budget: u64,
) -> Result<usize, String> {
    let shadowmap_frustum::Light::Point { position, range } = case.cube.light else {
        return Err("a cube for a non-point light".into());
    };
    let smallest = cube.faces.iter().all(|f| f.size == [4, 4]);
    if cube.faces.iter().any(|f| f.size.contains(&0)) || (cube.texels() > budget && !smallest) {
        return Err(format!(
            "sizes {:?} in {:?} over {budget}",
            cube.faces, cube.atlas
        ));
    }
    let floor = near_floor(&case.cube, position, range);
    let mut checked = 0;
    for s in &case.samples {
        let p = s.position.as_dvec3();
        let q = p - position.as_dvec3();
        let scale = f64::from(
            s.position
                .abs()
                .max_element()
                .max(position.abs().max_element()),
        );
        // f32 rounding of the sample and of the fitted windows.
        let along_faces = cube.orientation().as_dquat().inverse() * q;
        if along_faces.abs().max_element() <= 1.01 * floor + 1e-3 * scale
            || q.length() >= 0.99 * f64::from(range)
        {
            continue;
        }
        let Some(c) = cube.map_point(p) else {
            return Err(format!("sample {} in no face", s.position));
        };
        let Some(m) = mapping.map_point(p) else {
            return Err(format!(
                "sample {} stored by the cube, not by the technique",
                s.position
            ));
        };
        if !(m.uv.is_finite() && inside_unit_square(m.uv))
            || m.layer != c.layer
            || m.depth != c.depth
        {
            return Err(format!(
                "sample {}: cube {c:?}, technique {m:?}",
                s.position
            ));
        }
        checked += 1;
    }
    Ok(checked)
}

/// A tiled cube map fitted to a case's samples (`tiled`; `mapping`, the fitted
/// technique's lookup) covers every sample its cube covers (the clauses of
/// [`check_cube_samples`] on the cube's windows): `mapping` maps it into the tile of
/// its face and cell, inside the tile's `[0, 1]²`, at the cube's depth; the tile's
/// place in the atlas lies within the tile's square and the atlas; the tiles' squares
/// are disjoint and inside an atlas of at most `budget` texels. Returns how many
/// samples were checked.
///
/// # Errors
/// A description of the violated clause.
pub fn check_tiled_samples(
    case: &CubeSamplesCase,
    tiled: &TiledCube,
    mapping: &impl ShadowMapping,
    budget: u64,
) -> Result<usize, String> {
    if tiled.texels() > budget || tiled.atlas.contains(&0) {
        return Err(format!("atlas {:?} over {budget}", tiled.atlas));
    }
    check_tiles_apart(tiled)?;
    check_table(tiled)?;
    let mut checked = 0;
    for s in &case.samples {
        let p = s.position.as_dvec3();
        let Some(c) = tiled.cube.map_point(p) else {
            continue;
        };
        let index = tiled
            .tile_index(c.layer, c.uv)
            .ok_or("a face without tiles")?;
        let m = mapping
            .map_point(p)
            .ok_or_else(|| format!("sample {} stored by the cube, not by the tiles", s.position))?;
        if m.layer as usize != index
            || !(m.uv.is_finite() && inside_unit_square(m.uv))
            || m.depth != c.depth
        {
            return Err(format!("sample {}: cube {c:?}, tiles {m:?}", s.position));
        }
        let a = tiled.atlas_sample(m).ok_or("no atlas sample")?;
        let (offset, side) = tiled.tile_viewport(index).ok_or("no viewport")?;
        let atlas = DVec2::new(f64::from(tiled.atlas[0]), f64::from(tiled.atlas[1]));
        let texel = a.uv * atlas;
        let lo = DVec2::new(f64::from(offset[0]), f64::from(offset[1]));
        let hi = lo + f64::from(side);
        if !(texel.cmpge(lo - UV_TOLERANCE).all() && texel.cmple(hi + UV_TOLERANCE).all()) {
            return Err(format!("texel {texel} outside its tile {lo}..{hi}"));
        }
        checked += 1;
    }
    Ok(checked)
}

/// Every cell of every kept face has an entry, and it names a tile of that face
/// whose cells hold it.
fn check_table(tiled: &TiledCube) -> Result<(), String> {
    let g = tiled.grid;
    let cells = tiled.cube.faces.len() * (g * g) as usize;
    if tiled.table.len() != cells {
        return Err(format!("{} entries for {cells} cells", tiled.table.len()));
    }
    for (i, &entry) in tiled.table.iter().enumerate() {
        let (layer, row, col) = ((i as u32) / (g * g), (i as u32 % (g * g)) / g, i as u32 % g);
        let t = tiled
            .tiles
            .get(entry as usize)
            .ok_or("entry past the tiles")?;
        let holds = (t.cell[0]..t.cell[0] + t.span).contains(&col)
            && (t.cell[1]..t.cell[1] + t.span).contains(&row);
        if t.layer != layer || !holds {
            return Err(format!("cell {layer}/{row}/{col} in tile {t:?}"));
        }
    }
    Ok(())
}

/// Rounding allowed past a map's edge, in `uv` (and in atlas texels).
const UV_TOLERANCE: f64 = 1e-4;

/// `uv` inside `[0, 1]²` up to [`UV_TOLERANCE`].
fn inside_unit_square(uv: DVec2) -> bool {
    uv.cmpge(DVec2::splat(-UV_TOLERANCE)).all() && uv.cmple(DVec2::splat(1.0 + UV_TOLERANCE)).all()
}

/// The tiles' squares (border included) lie inside the atlas and overlap nowhere.
fn check_tiles_apart(tiled: &TiledCube) -> Result<(), String> {
    let [w, h] = tiled.atlas.map(u64::from);
    let mut rects: Vec<[u64; 4]> = Vec::with_capacity(tiled.tiles.len());
    for i in 0..tiled.tiles.len() {
        let (o, side) = tiled.tile_viewport(i).ok_or("no viewport")?;
        let r = [
            u64::from(o[0]),
            u64::from(o[1]),
            u64::from(side),
            u64::from(side),
        ];
        if side == 0 || r[0] + r[2] > w || r[1] + r[3] > h {
            return Err(format!("tile {i} {r:?} outside the atlas {w}x{h}"));
        }
        rects.push(r);
    }
    // Sweep by rows: sort by top edge, compare with the tiles that start above
    // this one's bottom.
    let mut order: Vec<usize> = (0..rects.len()).collect();
    order.sort_by_key(|i| rects[*i][1]);
    for (k, &i) in order.iter().enumerate() {
        let a = rects[i];
        for &j in &order[k + 1..] {
            let b = rects[j];
            if b[1] >= a[1] + a[3] {
                break;
            }
            if a[0] < b[0] + b[2] && b[0] < a[0] + a[2] {
                return Err(format!("tiles {i} {a:?} and {j} {b:?} overlap"));
            }
        }
    }
    Ok(())
}
