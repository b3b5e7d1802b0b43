use glam::{Vec3, Vec4};

use super::*;
use crate::CubeOptions;

/// The cube tests' street under a lamp (five faces kept).
fn street_cube(reversed_z: bool) -> CubeMap {
    let (camera, light, scene) = crate::cube::tests::street();
    let options = CubeOptions::default().with_reversed_z(reversed_z);
    CubeMap::fit(&light, &camera, None, &scene, &options).unwrap()
}

/// Densities of a face's cells: `f(layer, row, col)`.
fn densities(cube: &CubeMap, grid: u32, f: impl Fn(u32, u32, u32) -> f64) -> Vec<f64> {
    let mut out = Vec::new();
    for layer in 0..cube.layers() {
        for row in 0..grid {
            for col in 0..grid {
                out.push(f(layer, row, col));
            }
        }
    }
    out
}

/// The tiles' squares are inside the atlas and apart, the atlas within the budget,
/// and every cell's table entry names a tile of its face holding it.
fn check_layout(t: &TiledCube, budget: u64) {
    assert!(t.texels() <= budget, "{:?} over {budget}", t.atlas);
    let rect = |i: usize| {
        let (o, s) = t.tile_viewport(i).unwrap();
        [o[0], o[1], o[0] + s, o[1] + s]
    };
    for i in 0..t.tiles.len() {
        let a = rect(i);
        assert!(
            a[2] <= t.atlas[0] && a[3] <= t.atlas[1],
            "{a:?} {:?}",
            t.atlas
        );
        for j in i + 1..t.tiles.len() {
            let b = rect(j);
            let apart = a[2] <= b[0] || b[2] <= a[0] || a[3] <= b[1] || b[3] <= a[1];
            assert!(apart, "{i} {a:?} {j} {b:?}");
        }
    }
    let g = t.grid;
    assert_eq!(t.table.len(), t.cube.faces.len() * (g * g) as usize);
    for (i, &entry) in t.table.iter().enumerate() {
        let (layer, row, col) = (i as u32 / (g * g), i as u32 % (g * g) / g, i as u32 % g);
        let tile = t.tiles[entry as usize];
        assert_eq!(tile.layer, layer);
        assert!((tile.cell[0]..tile.cell[0] + tile.span).contains(&col));
        assert!((tile.cell[1]..tile.cell[1] + tile.span).contains(&row));
    }
}

/// A denser cell gets a larger tile, in proportion (up to rounding), and the
/// tiles fill most of the budget.
#[test]
fn tiles_follow_the_densities_within_the_budget() {
    let cube = street_cube(false);
    let grid = 8;
    let budget = 512 * 512;
    // One cell per face four times as dense as its neighbours, which vary enough
    // that nothing merges.
    let d = densities(&cube, grid, |_, row, col| {
        if (row, col) == (3, 5) {
            4000.0
        } else {
            1000.0 * (1.0 + 0.3 * f64::from((row * 3 + col) % 4))
        }
    });
    let options = TileOptions::default().with_grid(grid);
    let t = TiledCube::new(cube, &options, &d, budget).unwrap();
    check_layout(&t, budget);
    assert!(t.texels() > budget * 7 / 10, "{}", t.texels());
    let side = |row: u32, col: u32| {
        let i = t.tile_index(
            0,
            DVec2::new(f64::from(col) + 0.5, f64::from(row) + 0.5) / 8.0,
        );
        t.tiles[i.unwrap()].side
    };
    let ratio = f64::from(side(3, 5)) / f64::from(side(0, 0));
    assert!((ratio - 4.0).abs() < 0.2, "{ratio}");
}

/// Equal densities merge into one tile per face (one border, not 64); empty faces
/// too; a lone dense cell keeps its own tile among merged neighbours.
#[test]
fn uniform_cells_merge_into_one_tile() {
    let cube = street_cube(false);
    let faces = cube.faces.len();
    let options = TileOptions::default().with_grid(8);
    let d = densities(&cube, 8, |layer, _, _| if layer == 0 { 0.0 } else { 500.0 });
    let t = TiledCube::new(cube.clone(), &options, &d, 512 * 512).unwrap();
    check_layout(&t, 512 * 512);
    assert_eq!(t.tiles.len(), faces);
    assert!(t.tiles.iter().all(|x| x.span == 8 && x.cell == [0, 0]));
    // Face 0 (no need) holds the smallest tile.
    assert_eq!(t.tiles.iter().find(|x| x.layer == 0).unwrap().side, 1);
    let d = densities(
        &cube,
        8,
        |_, row, col| if (row, col) == (7, 0) { 5e4 } else { 500.0 },
    );
    let t = TiledCube::new(cube, &options, &d, 512 * 512).unwrap();
    check_layout(&t, 512 * 512);
    let lone = t.tile_index(1, DVec2::new(0.01, 0.99)).unwrap();
    assert_eq!(t.tiles[lone].span, 1);
    assert!(t.tiles.len() < faces * 64 / 4, "{}", t.tiles.len());
}

/// The depth pass of a tile (its cropped clip matrix, divided by `w`, into its
/// square of the atlas) puts a point where the lookup does, for both depth
/// conventions.
#[test]
fn tile_clip_agrees_with_the_lookup() {
    for reversed in [false, true] {
        let cube = street_cube(reversed);
        let grid = 16;
        let d = densities(&cube, grid, |layer, row, col| {
            100.0 + f64::from((layer * 7 + row * 5 + col * 3) % 11) * 90.0
        });
        let options = TileOptions::default().with_grid(grid);
        let t = TiledCube::new(cube, &options, &d, 1 << 20).unwrap();
        check_layout(&t, 1 << 20);
        let mut checked = 0;
        for x in [-40.0, -5.0, 0.0, 7.0, 30.0] {
            for z in [-200.0, -60.0, -31.0, -29.0, -10.0] {
                let p = Vec3::new(x, 0.5, z);
                let Some(s) = t.map_point(p.as_dvec3()) else {
                    continue;
                };
                let clip = t.tile_clip_from_world(s.layer as usize).unwrap();
                let c = clip * Vec4::new(p.x, p.y, p.z, 1.0);
                let ndc = c.truncate() / c.w;
                let uv = DVec2::new(0.5 + 0.5 * f64::from(ndc.x), 0.5 - 0.5 * f64::from(ndc.y));
                assert!(
                    (uv - s.uv).abs().max_element() < 1e-4,
                    "{p}: {uv} {:?}",
                    s.uv
                );
                assert!((f64::from(ndc.z) - s.depth).abs() < 1e-5, "{p}");
                assert!(s.uv.cmpge(DVec2::ZERO).all() && s.uv.cmple(DVec2::ONE).all());
                // In the atlas: inside the tile's square, past its border.
                let a = t.atlas_sample(s).unwrap();
                let (o, side) = t.tile_viewport(s.layer as usize).unwrap();
                let texel = a.uv * DVec2::new(f64::from(t.atlas[0]), f64::from(t.atlas[1]));
                let inner = f64::from(t.border);
                let lo = DVec2::new(f64::from(o[0]), f64::from(o[1])) + inner;
                let hi = lo + f64::from(side) - 2.0 * inner;
                assert!(texel.cmpge(lo - 1e-6).all() && texel.cmple(hi + 1e-6).all());
                checked += 1;
            }
        }
        assert!(checked >= 20, "{checked}");
    }
}

/// A budget too small for the grid takes a coarser one; below one small tile per
/// face it is an error, as are a grid that is not a power of two and a border past the limit.
#[test]
fn small_budgets_coarsen_the_grid_and_bad_options_are_errors() {
    let cube = street_cube(false);
    let faces = cube.faces.len() as u64;
    let d = densities(&cube, 16, |_, row, _| 100.0 * f64::from(row + 1));
    let options = TileOptions::default();
    // 16x16 cells of at least 5x5 texels need 5 * 256 * 25 per copy.
    let t = TiledCube::new(cube.clone(), &options, &d, faces * 256 * 25).unwrap();
    assert!(t.grid <= 8, "{}", t.grid);
    check_layout(&t, faces * 256 * 25);
    assert!(matches!(
        TiledCube::new(cube.clone(), &options, &d, faces * 25),
        Err(ParaboloidError::InvalidOptions)
    ));
    for bad in [
        options.with_grid(12),
        options.with_grid(0),
        options.with_grid(128),
        options.with_border(MAX_TILE_BORDER + 1),
    ] {
        assert_eq!(bad.validate(), Err(ParaboloidError::InvalidOptions));
    }
    // Missing and non-finite densities are no need.
    let t = TiledCube::new(cube, &options, &[f64::NAN, -1.0], 1 << 20).unwrap();
    assert!(t.tiles.iter().all(|x| x.side == 1));
}
