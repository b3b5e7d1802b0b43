//! One focus body shared by several warps: each warp chooses its strength on the
//! probe points the first one cast, so every fit from a shared body, in any order,
//! at any strength scale and depth convention, must equal the fit of a body of its
//! own (the free function), bit for bit.

use proptest::prelude::*;
use shadowmap_testgen::strategy;
use shadowmap_testgen::warp::{WarpCase, warp_case};
use shadowmap_warp::{
    FocusBody, LispsmOptions, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, xpsm,
};

/// Every fit of `case` a shared body offers, as `Debug` text (the shadows' types
/// differ; their `Debug` prints every field, so equal text is equal output).
type Fits = [String; 4];

/// The fits in `order` (indices into uniform, LiSPSM, XPSM, TSM) from one body,
/// listed in the canonical order.
fn shared(case: &WarpCase, scale: f32, order: [usize; 4]) -> Option<Fits> {
    let body = FocusBody::new(&case.camera, case.light, &case.scene).ok()?;
    let z = case.reversed_z;
    let mut fits: Fits = Default::default();
    for i in order {
        fits[i] = match i {
            0 => format!(
                "{:?}",
                body.uniform(&UniformOptions::new().with_reversed_z(z))
            ),
            1 => format!("{:?}", body.lispsm(&lispsm_options(case, scale))),
            2 => format!("{:?}", body.xpsm(&xpsm_options(case, scale))),
            _ => format!("{:?}", body.tsm(&tsm_options(case, scale))),
        };
    }
    Some(fits)
}

/// The same fits, each from a body of its own.
fn alone(case: &WarpCase, scale: f32) -> Fits {
    let (c, l, s) = (&case.camera, case.light, &case.scene);
    let z = case.reversed_z;
    [
        format!(
            "{:?}",
            uniform_focused(c, l, s, &UniformOptions::new().with_reversed_z(z))
        ),
        format!("{:?}", lispsm(c, l, s, &lispsm_options(case, scale))),
        format!("{:?}", xpsm(c, l, s, &xpsm_options(case, scale))),
        format!("{:?}", tsm(c, l, s, &tsm_options(case, scale))),
    ]
}

fn lispsm_options(case: &WarpCase, scale: f32) -> LispsmOptions {
    LispsmOptions::new()
        .with_eta(case.eta)
        .with_reversed_z(case.reversed_z)
        .with_strength_scale(scale)
}

fn xpsm_options(case: &WarpCase, scale: f32) -> XpsmOptions {
    XpsmOptions::new()
        .with_reversed_z(case.reversed_z)
        .with_strength_scale(scale)
}

fn tsm_options(case: &WarpCase, scale: f32) -> TsmOptions {
    TsmOptions::new()
        .with_reversed_z(case.reversed_z)
        .with_strength_scale(scale)
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    #[test]
    fn a_shared_body_fits_as_a_body_of_its_own(case in strategy(warp_case)) {
        for scale in [1.0, 0.5] {
            let alone = alone(&case, scale);
            for order in [[0, 1, 2, 3], [3, 2, 1, 0], [2, 0, 3, 1]] {
                if let Some(shared) = shared(&case, scale, order) {
                    prop_assert_eq!(&shared, &alone, "order {:?}, scale {}", order, scale);
                }
            }
        }
    }
}

/// A body is `Send` (its probe cache is not shared between threads).
#[test]
fn a_body_moves_between_threads() {
    fn send<T: Send>() {}
    send::<FocusBody>();
}
