//! Property tests of the warp builder and the accumulation, driven by the shared
//! generators of `shadowmap_testgen::rtw` (the fuzz targets run the same checks).

use proptest::prelude::*;
use shadowmap_rtw::{
    ImportanceMap, WarpMaps, WarpOptions, forward_warp, forward_warp_f64, inverse_warp,
    inverse_warp_f64,
};
use shadowmap_testgen::rtw::{
    WarpCase, accumulate_case_raw, check_accumulate, check_spot_rtw, check_warp, spot_rtw_case_raw,
    warp_case, warp_case_raw,
};
use shadowmap_testgen::strategy;

fn build(case: &WarpCase, options: &WarpOptions) -> (ImportanceMap, WarpMaps) {
    let mut map = ImportanceMap::new(case.width, case.height).unwrap();
    map.copy_from_slice(&case.values).unwrap();
    let mut warps = WarpMaps::new(case.width, case.height).unwrap();
    warps.build(&map, options).unwrap();
    (map, warps)
}

/// Test points: every texel centre, every texel edge, and the ends.
fn points(n: usize) -> impl Iterator<Item = f64> {
    (0..=2 * n).map(move |k| k as f64 / (2 * n) as f64)
}

/// Independent reference of the documented blur: `exp(-k²/(2 sigma²))`,
/// `sigma = r/2`, normalized, clamp-to-edge.
fn reference_density(src: &[f32], radius: u32, floor: f32) -> Vec<f64> {
    let n = src.len() as i64;
    let r = i64::from(radius);
    let sigma = f64::from(radius) / 2.0;
    let weight = |k: i64| {
        if r == 0 {
            1.0
        } else {
            (-((k * k) as f64) / (2.0 * sigma * sigma)).exp()
        }
    };
    let total: f64 = (-r..=r).map(weight).sum();
    let blurred: Vec<f64> = (0..n)
        .map(|i| {
            (-r..=r)
                .map(|k| weight(k) * f64::from(src[(i + k).clamp(0, n - 1) as usize]))
                .sum::<f64>()
                / total
        })
        .collect();
    let max = blurred.iter().copied().fold(0.0, f64::max);
    blurred
        .iter()
        .map(|&b| {
            if max > 0.0 {
                (b / max).max(f64::from(floor))
            } else {
                1.0
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// The builder's contract on valid input: tables zero at the ends, knots
    /// non-decreasing, forward warp monotone and onto [0, 1], inverse exact,
    /// densities in [floor, 1], collapse = column / row maxima, identity fallback
    /// exactly for all-zero maps (over two frames, so temporal smoothing is covered).
    #[test]
    fn warps_are_monotone_and_onto(case in strategy(warp_case)) {
        check_warp(&case);
    }

    /// The same check on raw input (what the `rtw_warp` fuzz target runs): typed
    /// errors for zero sizes, wrong lengths, NaN / negative values, bad options.
    #[test]
    fn warp_builder_contract_on_raw_input(case in strategy(warp_case_raw)) {
        check_warp(&case);
    }

    /// Backward, oracle and forward analysis on raw input (what the `rtw_accumulate`
    /// fuzz target runs).
    #[test]
    fn accumulation_contract_on_raw_input(case in strategy(accumulate_case_raw)) {
        check_accumulate(&case);
    }

    /// RTW over the spot fit (a perspective base; what the `rtw_spot` fuzz target
    /// runs): the accumulation contract, coverage of the samples the spot fit maps,
    /// base depth kept, inverse and monotone warp.
    #[test]
    fn rtw_over_the_spot_fit_covers_what_the_spot_fit_covers(
        case in strategy(spot_rtw_case_raw)
    ) {
        check_spot_rtw(&case);
    }

    /// Constant importance (any magnitude, size, blur, floor, temporal weight, two
    /// frames) gives exactly the identity warp.
    #[test]
    fn constant_importance_gives_identity(
        case in strategy(warp_case),
        c in prop_oneof![Just(1.0f32), 1e-30f32..1e30f32],
    ) {
        let mut map = ImportanceMap::new(case.width, case.height).unwrap();
        let mut warps = WarpMaps::new(case.width, case.height).unwrap();
        map.copy_from_slice(&vec![c; case.values.len()]).unwrap();
        for _ in 0..2 {
            warps.build(&map, &case.options).unwrap();
            prop_assert!(warps.x_table().iter().chain(warps.y_table()).all(|&t| t == 0.0));
            for u in points(64) {
                let u = u as f32;
                prop_assert_eq!(forward_warp(warps.x_table(), u), u);
                prop_assert_eq!(inverse_warp(warps.y_table(), u), u);
            }
        }
    }

    /// inverse(forward(u)) = u: within 1e-5 in f32 (the GPU path) for floors of at
    /// least 0.05 (the f32 error is about 1e-7 / floor), within 1e-9 in f64 for
    /// floors of at least 1e-4.
    #[test]
    fn inverse_undoes_forward(
        case in strategy(warp_case),
        floor in prop_oneof![Just(0.05f32), 0.05f32..1.0],
        floor64 in prop_oneof![Just(1e-4f32), 1e-4f32..1.0],
        extra in proptest::collection::vec(0.0f32..=1.0, 16),
    ) {
        let (_, warps) = build(&case, &case.options.with_floor(floor).with_temporal(0.0));
        for table in [warps.x_table(), warps.y_table()] {
            for u in points(table.len()).map(|u| u as f32).chain(extra.iter().copied()) {
                let back = inverse_warp(table, forward_warp(table, u));
                prop_assert!((back - u).abs() <= 1e-5, "u {} back {} (n {})", u, back, table.len());
            }
        }
        let (_, warps) = build(&case, &case.options.with_floor(floor64).with_temporal(0.0));
        for table in [warps.x_table(), warps.y_table()] {
            for u in points(table.len()).chain(extra.iter().map(|&u| f64::from(u))) {
                let back = inverse_warp_f64(table, forward_warp_f64(table, u));
                prop_assert!((back - u).abs() <= 1e-9, "u {} back {}", u, back);
            }
        }
    }

    /// The local density (the warp's slope between texel centres) is proportional to
    /// the blurred, floored importance: slope on [c_k, c_{k+1}] =
    /// (d_k + d_{k+1})/2 * (N-1) / sum_j (d_j + d_{j+1})/2, with d recomputed here
    /// from the raw map by an independent blur; slope 1 in the outer half texels.
    #[test]
    fn density_follows_blurred_importance(case in strategy(warp_case)) {
        let options = case.options.with_temporal(0.0).with_floor(case.options.floor.max(1e-3));
        let (_, warps) = build(&case, &options);
        for (src, density, table) in [
            (warps.column_max(), warps.density_x(), warps.x_table()),
            (warps.row_max(), warps.density_y(), warps.y_table()),
        ] {
            let n = table.len();
            let d = reference_density(src, options.blur_radius, options.floor);
            for (got, want) in density.iter().zip(&d) {
                prop_assert!((f64::from(*got) - want).abs() <= 1e-6 * want.max(1e-3) + 1e-9,
                    "density {} vs reference {}", got, want);
            }
            if n < 2 {
                continue;
            }
            let nf = n as f64;
            let a: Vec<f64> = d.windows(2).map(|p| 0.5 * (p[0] + p[1])).collect();
            let total: f64 = a.iter().sum();
            let c = |i: usize| (i as f64 + 0.5) / nf;
            for (k, ak) in a.iter().enumerate() {
                let slope = (forward_warp_f64(table, c(k + 1)) - forward_warp_f64(table, c(k))) * nf;
                let want = ak * (nf - 1.0) / total;
                // f32 storage of the knots: each off by at most an ulp of 1.
                let tol = 2.5e-7 * nf + 1e-4 * want;
                prop_assert!((slope - want).abs() <= tol, "segment {} of {}: slope {} want {}", k, n, slope, want);
            }
            let h = 0.5 / nf;
            prop_assert!((forward_warp_f64(table, h) - h).abs() < 1e-15);
            prop_assert!((forward_warp_f64(table, 1.0 - h) - (1.0 - h)).abs() < 1e-15);
        }
    }
}

/// The spot-RTW generator is not vacuous: over fixed pseudo-random inputs, most
/// cases fit a spot and check samples inside its map.
#[test]
fn spot_rtw_cases_reach_the_coverage_check() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let (mut cases, mut checked) = (0, 0);
    for _ in 0..200 {
        let bytes: Vec<u8> = (0..512).map(|_| (next() >> 56) as u8).collect();
        let Ok(case) =
            spot_rtw_case_raw(&mut shadowmap_testgen::arbitrary::Unstructured::new(&bytes))
        else {
            continue;
        };
        let n = check_spot_rtw(&case);
        cases += usize::from(n > 0);
        checked += n;
    }
    assert!(
        cases >= 40 && checked >= 500,
        "{cases} cases, {checked} samples"
    );
}
