//! Input generators shared by the `shadowmap` fuzz targets and property tests.
//!
//! Every generator reads an [`arbitrary::Unstructured`] byte stream, so libFuzzer and
//! proptest drive exactly the same code: a fuzz target calls a generator on its
//! input bytes, and [`strategy`] turns the same generator into a proptest
//! [`Strategy`] over random byte vectors.
//!
//! Generators come in two flavours:
//! - `*_raw`: anything, including NaN, infinities, zero vectors, inverted ranges —
//!   for checking that builders return typed errors and never panic or emit NaN;
//! - the plain ones: valid input biased toward the degenerate edges (tiny and huge
//!   magnitudes, nearly parallel directions, near == far within a few ULPs of
//!   validity) — for checking properties.

use arbitrary::Unstructured;
use glam::{Mat4, Vec3};
use proptest::prelude::*;
use shadowmap_frustum::{Aabb, Camera, Projection, SplitScheme, projection};

pub use arbitrary;

#[cfg(feature = "paraboloid")]
pub mod cube;
pub mod frustum;
#[cfg(feature = "paraboloid")]
pub mod paraboloid;
#[cfg(all(feature = "paraboloid", feature = "rtw"))]
pub mod point_rtw;
#[cfg(feature = "rtw")]
pub mod rtw;
#[cfg(feature = "serde")]
pub mod serde_check;
#[cfg(feature = "warp")]
pub mod spot_warp;
#[cfg(feature = "warp")]
pub mod warp;

/// The configuration every property test uses: 1,000 cases from a fixed seed, so a
/// CI run is reproducible and a failure replays exactly. The fuzz targets explore the
/// same generators without a seed. `PROPTEST_CASES=<n>` in the environment runs
/// `n` cases instead (the same seed: the first 1,000 are CI's), for a longer search,
/// with rejected inputs allowed in proportion (a quarter of `n`, at least
/// proptest's 1,024).
pub fn proptest_config() -> ProptestConfig {
    let cases: u32 = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(1000);
    ProptestConfig {
        cases,
        max_global_rejects: (cases / 4).max(1024),
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x05AD_03A9),
        ..ProptestConfig::default()
    }
}

/// Runs `test`, named `name`, as the one test of a binary built without libtest's
/// harness (`harness = false`), printing libtest's lines for it so that a count of
/// the lines over every test binary includes it; a failure panics, exiting with an
/// error as libtest would. The no-allocation tests run this way, alone on the main
/// thread: their counting allocator counts every thread, and libtest's main thread
/// records the test it has just started (a map entry, a timeout entry) while the
/// test's thread runs, which a loaded machine lets fall inside the measured region.
#[allow(clippy::print_stdout)] // libtest's lines.
pub fn run_alone(name: &str, test: impl FnOnce()) {
    println!("\nrunning 1 test");
    test();
    println!("test {name} ... ok\n");
    println!("test result: ok. 1 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out\n");
}

/// Result of a generator.
pub type GenResult<T> = arbitrary::Result<T>;

/// `len` pseudo-random bytes from an xorshift stream (`state`, advanced): the input
/// of a generator in tests that count how often it reaches a case.
pub fn xorshift_bytes(state: &mut u64, len: usize) -> Vec<u8> {
    (0..len)
        .map(|_| {
            *state ^= *state << 13;
            *state ^= *state >> 7;
            *state ^= *state << 17;
            (*state >> 24) as u8
        })
        .collect()
}

/// Measured depth bounds inside `[near, far]` half of the time, `None` otherwise.
pub fn depth_bounds_in(
    u: &mut Unstructured<'_>,
    near: f32,
    far: f32,
) -> GenResult<Option<shadowmap_frustum::DepthBounds>> {
    Ok(if u.arbitrary()? {
        let a = in_range(u, near, far)?;
        let b = in_range(u, near, far)?;
        Some(shadowmap_frustum::DepthBounds {
            min: a.min(b),
            max: a.max(b),
        })
    } else {
        None
    })
}

/// A proptest strategy running `generate` on random bytes.
///
/// Inputs the generator rejects (it ran out of bytes in a way it cannot recover
/// from) are filtered out.
pub fn strategy<T, F>(generate: F) -> BoxedStrategy<T>
where
    T: core::fmt::Debug + 'static,
    F: Fn(&mut Unstructured<'_>) -> GenResult<T> + Clone + 'static,
{
    proptest::collection::vec(any::<u8>(), 32..512)
        .prop_filter_map("generator rejected input", move |bytes| {
            generate(&mut Unstructured::new(&bytes)).ok()
        })
        .boxed()
}

/// Uniform `f32` in `[lo, hi]`.
pub fn in_range(u: &mut Unstructured<'_>, lo: f32, hi: f32) -> GenResult<f32> {
    let t = f64::from(u.int_in_range(0u32..=u32::MAX)?) / f64::from(u32::MAX);
    Ok((f64::from(lo) + (f64::from(hi) - f64::from(lo)) * t) as f32)
}

/// Log-uniform positive `f32` in `[lo, hi]` (`0 < lo < hi`).
pub fn log_uniform(u: &mut Unstructured<'_>, lo: f32, hi: f32) -> GenResult<f32> {
    let t = in_range(u, 0.0, 1.0)?;
    let (a, b) = (f64::from(lo).ln(), f64::from(hi).ln());
    Ok(((a + (b - a) * f64::from(t)).exp() as f32).clamp(lo, hi))
}

/// Any `f32`: special values, raw bit patterns (NaN, infinities, subnormals) and
/// ordinary magnitudes.
pub fn any_f32(u: &mut Unstructured<'_>) -> GenResult<f32> {
    const SPECIAL: [f32; 12] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        f32::MIN_POSITIVE,
        f32::EPSILON,
        f32::MAX,
        f32::MIN,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e-38,
    ];
    Ok(match u.int_in_range(0u8..=3)? {
        0 => SPECIAL[usize::from(u.int_in_range(0u8..=11)?)],
        1 => f32::from_bits(u.arbitrary()?),
        2 => in_range(u, -10.0, 10.0)?,
        _ => {
            let m = log_uniform(u, 1e-6, 1e6)?;
            if u.arbitrary()? { -m } else { m }
        }
    })
}

/// Any `Vec3` (components from [`any_f32`]).
pub fn any_vec3(u: &mut Unstructured<'_>) -> GenResult<Vec3> {
    Ok(Vec3::new(any_f32(u)?, any_f32(u)?, any_f32(u)?))
}

/// A unit vector, biased toward the axes and toward tiny deviations from them.
pub fn unit_vec3(u: &mut Unstructured<'_>) -> GenResult<Vec3> {
    const AXES: [Vec3; 6] = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    let v = match u.int_in_range(0u8..=3)? {
        0 => AXES[usize::from(u.int_in_range(0u8..=5)?)],
        1 => {
            let axis = AXES[usize::from(u.int_in_range(0u8..=5)?)];
            near_parallel(u, axis)?
        }
        _ => {
            // Uniform on the sphere.
            let z = in_range(u, -1.0, 1.0)?;
            let phi = in_range(u, 0.0, core::f32::consts::TAU)?;
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        }
    };
    Ok(v.try_normalize().unwrap_or(Vec3::Y))
}

/// A unit vector within a tiny angle (1e-7 to 1e-1 rad, log-uniform) of `base`,
/// sometimes exactly `base` or its opposite.
pub fn near_parallel(u: &mut Unstructured<'_>, base: Vec3) -> GenResult<Vec3> {
    let base = base.try_normalize().unwrap_or(Vec3::Y);
    let sign = if u.arbitrary()? { 1.0 } else { -1.0 };
    if u.int_in_range(0u8..=4)? == 0 {
        return Ok(base * sign);
    }
    let angle = log_uniform(u, 1e-7, 1e-1)?;
    let (a, b) = base.any_orthonormal_pair();
    let phi = in_range(u, 0.0, core::f32::consts::TAU)?;
    let perp = a * phi.cos() + b * phi.sin();
    Ok((base * angle.cos() + perp * angle.sin()).normalize() * sign)
}

/// A position with magnitude up to `scale`, sometimes exactly zero or tiny.
pub fn position(u: &mut Unstructured<'_>, scale: f32) -> GenResult<Vec3> {
    Ok(match u.int_in_range(0u8..=5)? {
        0 => Vec3::ZERO,
        1 => unit_vec3(u)? * log_uniform(u, 1e-6, 1e-2)?,
        _ => Vec3::new(
            in_range(u, -scale, scale)?,
            in_range(u, -scale, scale)?,
            in_range(u, -scale, scale)?,
        ),
    })
}

/// A valid `(near, far)` pair: `near` from 1e-3 to 10, `far / near` from barely above
/// the thinnest accepted range (about 1 + 1e-4) to 1e5.
pub fn depth_range(u: &mut Unstructured<'_>) -> GenResult<(f32, f32)> {
    let near = log_uniform(u, 1e-3, 10.0)?;
    let ratio = match u.int_in_range(0u8..=3)? {
        0 => 1.0 + log_uniform(u, 1e-4, 1e-2)?,
        _ => log_uniform(u, 1.01, 1e5)?,
    };
    Ok((near, near * ratio))
}

/// Any `(near, far)` pair, often invalid: equal, a few ULPs apart, inverted, zero,
/// negative, non-finite.
pub fn depth_range_raw(u: &mut Unstructured<'_>) -> GenResult<(f32, f32)> {
    Ok(match u.int_in_range(0u8..=4)? {
        0 => {
            let n = any_f32(u)?;
            let ulps = u.int_in_range(0u32..=8)?;
            (n, f32::from_bits(n.to_bits().wrapping_add(ulps)))
        }
        1 => depth_range(u)?,
        2 => {
            let (n, f) = depth_range(u)?;
            (f, n)
        }
        _ => (any_f32(u)?, any_f32(u)?),
    })
}

/// A valid camera of any projection kind, biased toward extreme fields of view,
/// aspect ratios and depth ranges, with either depth convention.
pub fn camera(u: &mut Unstructured<'_>) -> GenResult<Camera> {
    let eye = position(u, 1e3)?;
    let forward = unit_vec3(u)?;
    // Up may be nearly parallel to forward, but not within the builder's rejection angle.
    let up = loop_free_up(u, forward)?;
    let fov_y = match u.int_in_range(0u8..=3)? {
        0 => log_uniform(u, 1e-3, 0.1)?,
        1 => in_range(u, 2.8, 3.1)?,
        _ => in_range(u, 0.3, 2.0)?,
    };
    let aspect = match u.int_in_range(0u8..=3)? {
        0 => log_uniform(u, 1e-2, 1e2)?,
        _ => in_range(u, 0.5, 2.5)?,
    };
    let (near, far) = depth_range(u)?;
    let reversed_z: bool = u.arbitrary()?;
    let projection = match u.int_in_range(0u8..=4)? {
        0 => Projection::InfinitePerspective {
            fov_y,
            aspect,
            near,
            shadow_distance: far,
        },
        1 => {
            let h = log_uniform(u, 1e-2, 1e3)?;
            Projection::Orthographic {
                left: -h * aspect,
                right: h * aspect * in_range(u, 0.2, 1.0)?,
                bottom: -h * in_range(u, 0.2, 1.0)?,
                top: h,
                near: near - in_range(u, 0.0, near)?,
                far,
            }
        }
        2 => {
            // An off-centre (jittered, VR-style) finite perspective as a raw matrix.
            let ty = (0.5 * f64::from(fov_y)).tan();
            let tx = ty * f64::from(aspect);
            let sx = f64::from(in_range(u, -0.5, 0.5)?) * tx;
            let sy = f64::from(in_range(u, -0.5, 0.5)?) * ty;
            let m = projection::perspective_off_center(
                -tx + sx,
                tx + sx,
                -ty + sy,
                ty + sy,
                f64::from(near),
                f64::from(far),
                reversed_z,
            );
            Projection::Custom {
                clip_from_view: m.as_mat4(),
                shadow_distance: far,
            }
        }
        _ => Projection::Perspective {
            fov_y,
            aspect,
            near,
            far,
        },
    };
    // Keep the eye within f32-representable distance of its frustum: no farther from
    // the origin than 1e4 times the frustum's smallest edge.
    let at_origin =
        Camera::look_to(Vec3::ZERO, forward, up, projection).map(|c| c.with_reversed_z(reversed_z));
    let Ok(camera) = at_origin.and_then(|c| c.frustum().map(|f| (c, f))) else {
        return Ok(fallback_camera(reversed_z));
    };
    let (camera, frustum) = camera;
    let edges = [(0, 1), (1, 2), (0, 4), (4, 5), (5, 6)];
    let smallest = edges
        .iter()
        .map(|(a, b)| frustum.corners[*a].distance(frustum.corners[*b]))
        .fold(f32::INFINITY, f32::min);
    let reach = (1e4 * smallest).min(1e3);
    let eye = if eye.length() > reach {
        eye.normalize_or_zero() * reach
    } else {
        eye
    };
    let moved = Camera {
        world_from_view: Mat4::from_translation(eye) * camera.world_from_view,
        ..camera
    };
    Ok(if moved.validate().is_ok() {
        moved
    } else {
        camera
    })
}

fn loop_free_up(u: &mut Unstructured<'_>, forward: Vec3) -> GenResult<Vec3> {
    let up = match u.int_in_range(0u8..=3)? {
        0 => Vec3::Y,
        1 => {
            // 1e-5 to 1e-1 rad away from forward: barely accepted.
            let angle = log_uniform(u, 1e-5, 1e-1)?;
            let (a, _) = forward.any_orthonormal_pair();
            forward * angle.cos() + a * angle.sin()
        }
        _ => unit_vec3(u)?,
    };
    Ok(if up.cross(forward).length() < 1e-5 {
        forward.any_orthonormal_vector()
    } else {
        up
    })
}

/// A camera that is always valid, used when a generated one is rejected.
fn fallback_camera(reversed_z: bool) -> Camera {
    Camera {
        world_from_view: Mat4::IDENTITY,
        projection: Projection::perspective(1.0, 1.5, 0.1, 100.0),
        reversed_z,
    }
}

/// Any camera, often invalid: NaN poses, zero directions, bad projections.
pub fn camera_raw(u: &mut Unstructured<'_>) -> GenResult<Camera> {
    let base = camera(u)?;
    Ok(match u.int_in_range(0u8..=5)? {
        0 => Camera {
            world_from_view: Mat4::from_cols_array(&core::array::from_fn(|_| {
                any_f32(u).unwrap_or(f32::NAN)
            })),
            ..base
        },
        1 => {
            let (near, far) = depth_range_raw(u)?;
            Camera {
                projection: Projection::Perspective {
                    fov_y: any_f32(u)?,
                    aspect: any_f32(u)?,
                    near,
                    far,
                },
                ..base
            }
        }
        2 => Camera {
            projection: Projection::Custom {
                clip_from_view: Mat4::from_cols_array(&core::array::from_fn(|_| {
                    any_f32(u).unwrap_or(0.0)
                })),
                shadow_distance: any_f32(u)?,
            },
            ..base
        },
        3 => {
            let (near, far) = depth_range_raw(u)?;
            Camera {
                projection: Projection::Orthographic {
                    left: any_f32(u)?,
                    right: any_f32(u)?,
                    bottom: any_f32(u)?,
                    top: any_f32(u)?,
                    near,
                    far,
                },
                ..base
            }
        }
        _ => base,
    })
}

/// A light direction, biased to lie nearly parallel to the camera's viewing
/// direction or up vector, or to a world axis.
pub fn light_direction(u: &mut Unstructured<'_>, camera: &Camera) -> GenResult<Vec3> {
    Ok(match u.int_in_range(0u8..=4)? {
        0 => near_parallel(u, camera.forward())?,
        1 => near_parallel(u, camera.world_from_view.y_axis.truncate())?,
        _ => unit_vec3(u)?,
    })
}

/// A valid box: sometimes flat on one axis or a point, sometimes huge or tiny.
pub fn aabb(u: &mut Unstructured<'_>, scale: f32) -> GenResult<Aabb> {
    let center = position(u, scale)?;
    let mut half = Vec3::new(
        log_uniform(u, 1e-3, scale.max(2e-3))?,
        log_uniform(u, 1e-3, scale.max(2e-3))?,
        log_uniform(u, 1e-3, scale.max(2e-3))?,
    );
    match u.int_in_range(0u8..=5)? {
        0 => half[usize::from(u.int_in_range(0u8..=2)?)] = 0.0,
        1 => half = Vec3::ZERO,
        _ => {}
    }
    Ok(Aabb::from_center_half_extents(center, half))
}

/// Any box, often inverted or non-finite.
pub fn aabb_raw(u: &mut Unstructured<'_>) -> GenResult<Aabb> {
    Ok(match u.int_in_range(0u8..=3)? {
        0 => Aabb::new(any_vec3(u)?, any_vec3(u)?),
        1 => {
            let b = aabb(u, 1e3)?;
            Aabb::new(b.max, b.min)
        }
        _ => aabb(u, 1e3)?,
    })
}

/// A split scheme, valid or not (lambda outside `[0, 1]`, unsorted custom splits).
pub fn split_scheme_raw(u: &mut Unstructured<'_>, count: usize) -> GenResult<SplitScheme> {
    Ok(match u.int_in_range(0u8..=4)? {
        0 => SplitScheme::Uniform,
        1 => SplitScheme::Logarithmic,
        2 => SplitScheme::Practical {
            lambda: any_f32(u)?,
        },
        3 => {
            let mut v = arrayvec::ArrayVec::new();
            for _ in 1..count.min(shadowmap_frustum::MAX_CASCADES) {
                v.push(any_f32(u)?);
            }
            SplitScheme::Custom(v)
        }
        _ => SplitScheme::Practical {
            lambda: in_range(u, 0.0, 1.0)?,
        },
    })
}

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
