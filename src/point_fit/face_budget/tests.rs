use super::*;
use crate::point_fit::cell_densities;

/// A xorshift stream of numbers in `[0, 1)`.
fn uniform(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The least total of `texels(face, k)` over every way of giving up at most 3
/// samples (5% of 60) among `faces` faces, by brute force.
fn least_giving_up_three(faces: usize, texels: impl Fn(usize, usize) -> f64) -> f64 {
    let mut least = f64::INFINITY;
    for code in 0..4usize.pow(faces as u32) {
        let ks: Vec<usize> = (0..faces)
            .map(|f| code / 4usize.pow(f as u32) % 4)
            .collect();
        if ks.iter().sum::<usize>() <= 3 {
            least = least.min((0..faces).map(|f| texels(f, ks[f])).sum());
        }
    }
    least
}

/// A face's needs (of `needs`, by `value`) in decreasing order.
fn of_face<T>(needs: &[(usize, T)], face: usize, value: impl Fn(&T) -> f64) -> Vec<f64> {
    let mut d: Vec<f64> = needs
        .iter()
        .filter(|n| n.0 == face)
        .map(|n| value(&n.1))
        .collect();
    d.sort_by(|x, y| y.total_cmp(x));
    d
}

/// Texels of densities (the sum of their squares).
fn texels(densities: &[f64]) -> f64 {
    densities.iter().map(|d| d * d).sum()
}

/// The faces' densities are the least texels that serve all but 5% of the
/// samples: equal to a brute force over how many each face gives up, on random
/// needs; and where a face's largest needs are many and alike (no single sample
/// given up saves anything), fewer than the greedy choice of the largest saving.
#[test]
fn face_densities_are_the_least_texels_that_serve_the_percentile() {
    let mut next = uniform(0x9e37_79b9_7f4a_7c15);
    for _ in 0..40 {
        let faces = 1 + (next() * 4.0) as usize;
        let needs: Vec<(usize, f64)> = (0..60)
            .map(|_| {
                (
                    (next() * faces as f64) as usize,
                    1.0 + 100.0 * next() * next(),
                )
            })
            .collect();
        let found = face_densities(&mut needs.clone(), faces);
        let mut all: Vec<f64> = needs.iter().map(|n| n.1).collect();
        let common = common_need(&mut all);
        let least = least_giving_up_three(faces, |f, k| {
            let d = of_face(&needs, f, |x| *x);
            density_after(|i| d.get(i).copied(), k, common).powi(2)
        });
        assert!(
            (texels(&found) - least).abs() <= 1e-9 * least,
            "{found:?}: {least}"
        );
    }
    // Face 0: ten samples needing 100 and ninety needing 50; face 1: a hundred
    // needing 90 down to 80.5. Ten may be given up: all of face 0's top saves
    // 100² - 50² where the greedy choice gives up face 1's top for 0.1 steps.
    let mut needs: Vec<(usize, f64)> = (0..10).map(|_| (0, 100.0)).collect();
    needs.extend((0..90).map(|_| (0, 50.0)));
    needs.extend((0..100).map(|i| (1, 90.0 - 0.1 * f64::from(i))));
    let exact = face_densities(&mut needs.clone(), 2);
    assert_eq!(exact.as_slice(), &[50.0, 90.0]);
    let greedy = cell_densities(&mut needs, 2);
    assert!(texels(&greedy) > 1.3 * texels(&exact), "{greedy:?}");
}

/// The faces' shapes are the least texels that serve all but 5% of the samples
/// along both axes: equal to a brute force over every face's shape and how many
/// samples it gives up, on random needs whose axes are drawn apart (a face's
/// samples needing much along `u`, or along `v`, or both).
#[test]
fn face_shapes_are_the_least_texels_that_serve_the_percentile() {
    let mut next = uniform(0x2545_f491_4f6c_dd1d);
    let shapes: Vec<f64> = (-SHAPE_STEPS..=SHAPE_STEPS)
        .map(|s| powf(2.0, f64::from(s) / 4.0))
        .collect();
    for _ in 0..30 {
        let faces = 1 + (next() * 3.0) as usize;
        let needs: Vec<(usize, [f64; 2])> = (0..60)
            .map(|_| {
                let face = (next() * faces as f64) as usize;
                let (a, b) = (1.0 + 50.0 * next() * next(), 1.0 + 50.0 * next() * next());
                (face, if next() < 0.5 { [a, b] } else { [10.0 * a, b] })
            })
            .collect();
        let found = face_shapes(&mut needs.clone(), faces);
        let mut all: Vec<f64> = needs.iter().map(|n| n.1[0].max(n.1[1])).collect();
        let common = common_need(&mut all);
        // Every face's best shape for each count it gives up.
        let least = least_giving_up_three(faces, |f, k| {
            shapes
                .iter()
                .map(|&a| {
                    let d = of_face(&needs, f, |n| (n[0] / sqrt(a)).max(n[1] * sqrt(a)));
                    density_after(|i| d.get(i).copied(), k, common).powi(2)
                })
                .fold(f64::INFINITY, f64::min)
        });
        let area: f64 = found.iter().flatten().map(|s| s[0] * s[1]).sum();
        assert!((area - least).abs() <= 1e-9 * least, "{found:?}: {least}");
        // Every sample but 5% is served at its need along both axes (the given up
        // ones at least at half of it).
        let served = needs
            .iter()
            .filter(|n| {
                found[n.0]
                    .is_some_and(|s| n.1[0] <= s[0] * (1.0 + 1e-9) && n.1[1] <= s[1] * (1.0 + 1e-9))
            })
            .count();
        assert!(served >= 57, "{served} of 60 served");
    }
}

/// A face wider than high where its samples need much along `u` only, and the
/// other way round; a face without samples has no shape (the cube's floor sizes
/// it).
#[test]
fn face_shapes_follow_the_axis_the_samples_need() {
    let mut needs: Vec<(usize, [f64; 2])> =
        (0..40).map(|i| (0, [40.0 + f64::from(i), 5.0])).collect();
    needs.extend((0..40).map(|i| (2, [5.0, 40.0 + f64::from(i)])));
    let found = face_shapes(&mut needs, 3);
    let [wide, none, tall] = [found[0], found[1], found[2]];
    let (wide, tall) = (wide.unwrap(), tall.unwrap());
    assert!(
        wide[0] > 4.0 * wide[1] && tall[1] > 4.0 * tall[0],
        "{wide:?} {tall:?}"
    );
    assert_eq!(none, None);
}
