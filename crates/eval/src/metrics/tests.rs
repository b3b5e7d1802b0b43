use super::*;

#[test]
fn singular_values_of_diagonal_and_rotation() {
    let (s1, s2) = singular_values(&DMat2::from_cols(
        DVec2::new(3.0, 0.0),
        DVec2::new(0.0, -0.5),
    ));
    assert!((s1 - 3.0).abs() < 1e-12 && (s2 - 0.5).abs() < 1e-12);
    let r = DMat2::from_angle(0.7) * 2.0;
    let (s1, s2) = singular_values(&r);
    assert!((s1 - 2.0).abs() < 1e-12 && (s2 - 2.0).abs() < 1e-12);
}

#[test]
fn summary_uses_nearest_rank() {
    let v: Vec<f64> = (1..=100).map(f64::from).collect();
    let s = Summary::of(&v).unwrap();
    assert_eq!((s.median, s.p95, s.max, s.count), (50.0, 95.0, 100.0, 100));
    assert!((s.mean - 50.5).abs() < 1e-12);
    assert_eq!(Summary::of(&[f64::NAN]), None);
}

#[test]
fn phase_jitter_and_flips() {
    let a = vec![Some((DVec2::new(0.1, 0.2), 0)), None];
    let b = vec![Some((DVec2::new(3.1, 0.95), 0)), None];
    // Whole texels in x, -0.25 in y after wrapping.
    assert!((phase_jitter(&[a, b]).unwrap() - 0.25).abs() < 1e-12);
    let lit = vec![
        vec![Some(true), Some(false)],
        vec![Some(false), Some(false)],
    ];
    assert_eq!(flip_rate(&lit), Some(0.5));
    assert_eq!(
        misclassification(&[None, Some(false)], &[Some(true), Some(true)]),
        Some(0.5)
    );
}
