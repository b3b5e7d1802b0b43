//! WGSL composition: WGSL has no includes, so a few shaders carry placeholder regions
//! between `// @compose NAME begin` and `// @compose NAME end` markers, replaced at
//! pipeline creation by the source that owns the function.
//!
//! - The scene shader (`render_scene.wgsl`) takes a lookup (`lookup_*.wgsl`) and a
//!   filter (`filter_*.wgsl`): [`compose_scene_shader`].
//! - RTW's depth pass (`depth_rtw.wgsl`), lookup (`lookup_rtw.wgsl`), the caster
//!   refinement (`refine.wgsl`) and the
//!   paraboloid depth pass and lookup (warped by RTW over a paraboloid side) take the
//!   one warp-table sampler of `rtw_sample.wgsl` ([`with_rtw_sample`]), which has the
//!   semantics of `shadowmap_rtw::sample_table`.
//! - The paraboloid depth pass, lookup and the refinement take the one paraboloid
//!   projection of `paraboloid_side.wgsl` (`ParaboloidMap::project`).
//!
//! [`expand`] fills every region a source has.
//!
//! Each placeholder is a stub with the real function's signature, so every file
//! validates on its own as well as composed.

use crate::{BackendError, shaders};

/// Replaces the region between `// @compose {name} begin` and `// @compose {name}
/// end` (markers included) by `with`.
///
/// # Errors
/// [`BackendError::InvalidInput`] if a marker is missing.
pub fn replace_region(source: &str, name: &str, with: &str) -> Result<String, BackendError> {
    let begin = format!("// @compose {name} begin");
    let end = format!("// @compose {name} end");
    let missing = || BackendError::InvalidInput("compose marker missing");
    let a = source.find(&begin).ok_or_else(missing)?;
    let b = source[a..]
        .find(&end)
        .map(|i| a + i + end.len())
        .ok_or_else(missing)?;
    Ok(format!("{}{}{}", &source[..a], with, &source[b..]))
}

/// `host` with its `rtw_sample` placeholder replaced by the sampler of
/// `rtw_sample.wgsl` (without that file's stand-in `rtw_tables` binding: the host
/// declares the tables in its own bind group).
///
/// # Errors
/// [`BackendError::InvalidInput`] if a marker is missing.
pub fn with_rtw_sample(host: &str) -> Result<String, BackendError> {
    let sampler = replace_region(shaders::RTW_SAMPLE, "rtw_tables", "")?;
    replace_region(host, "rtw_sample", &sampler)
}

/// RTW's depth pass with the table sampler composed in.
///
/// # Errors
/// As [`expand`].
pub fn depth_rtw() -> Result<String, BackendError> {
    expand(shaders::DEPTH_RTW)
}

/// The paraboloid depth pass with the projection and the table sampler composed in.
///
/// # Errors
/// As [`expand`].
pub fn depth_paraboloid() -> Result<String, BackendError> {
    expand(shaders::DEPTH_PARABOLOID)
}

/// The caster refinement with the table sampler and the paraboloid projection
/// composed in.
///
/// # Errors
/// As [`expand`].
pub fn refine() -> Result<String, BackendError> {
    expand(shaders::REFINE)
}

/// RTW's lookup with the table sampler composed in.
///
/// # Errors
/// As [`expand`].
pub fn lookup_rtw() -> Result<String, BackendError> {
    expand(shaders::LOOKUP_RTW)
}

/// The paraboloid lookup with the projection and the table sampler composed in.
///
/// # Errors
/// As [`expand`].
pub fn lookup_paraboloid() -> Result<String, BackendError> {
    expand(shaders::LOOKUP_PARABOLOID)
}

/// Replaces the `@compose lookup` and `@compose filter` regions of
/// `render_scene.wgsl` by a lookup and a filter source.
///
/// # Errors
/// [`BackendError::InvalidInput`] if a marker is missing.
pub fn compose_scene_shader(lookup: &str, filter: &str) -> Result<String, BackendError> {
    let s = replace_region(shaders::RENDER_SCENE, "lookup", lookup)?;
    replace_region(&s, "filter", filter)
}

macro_rules! combos {
    ($(($lookup:ident, $filter:ident)),* $(,)?) => {
        [$((
            concat!("render_scene+", stringify!($lookup), "+", stringify!($filter)),
            shaders::$lookup,
            shaders::$filter,
        )),*]
    };
}

/// Every source the backend composes at run time: each lookup with each filter,
/// named `render_scene+LOOKUP+FILTER` (lookups with their shared functions), then
/// the depth passes and the refinement with theirs (`depth_rtw+`, `depth_paraboloid+`,
/// `refine+`); each with the composition's own result, so a failing one is reported
/// by name rather than dropped (the naga test validates them all).
#[must_use]
pub fn composed_shaders() -> Vec<(&'static str, Result<String, BackendError>)> {
    let all = combos![
        (LOOKUP_MATRIX, FILTER_HARD),
        (LOOKUP_MATRIX, FILTER_HARDWARE),
        (LOOKUP_MATRIX, FILTER_PCF),
        (LOOKUP_MATRIX, FILTER_POISSON),
        (LOOKUP_MATRIX, FILTER_VSM),
        (LOOKUP_CASCADES, FILTER_HARD),
        (LOOKUP_CASCADES, FILTER_HARDWARE),
        (LOOKUP_CASCADES, FILTER_PCF),
        (LOOKUP_CASCADES, FILTER_POISSON),
        (LOOKUP_CASCADES, FILTER_VSM),
        (LOOKUP_PARABOLOID, FILTER_HARD),
        (LOOKUP_PARABOLOID, FILTER_HARDWARE),
        (LOOKUP_PARABOLOID, FILTER_PCF),
        (LOOKUP_PARABOLOID, FILTER_POISSON),
        (LOOKUP_PARABOLOID, FILTER_VSM),
        (LOOKUP_RTW, FILTER_HARD),
        (LOOKUP_RTW, FILTER_HARDWARE),
        (LOOKUP_RTW, FILTER_PCF),
        (LOOKUP_RTW, FILTER_POISSON),
        (LOOKUP_RTW, FILTER_VSM),
        (LOOKUP_TILES, FILTER_HARD),
        (LOOKUP_TILES, FILTER_HARDWARE),
        (LOOKUP_TILES, FILTER_PCF),
        (LOOKUP_TILES, FILTER_POISSON),
        (LOOKUP_TILES, FILTER_VSM),
    ];
    let mut out: Vec<_> = all
        .iter()
        .map(|(name, l, f)| (*name, expand(l).and_then(|l| compose_scene_shader(&l, f))))
        .collect();
    out.push(("depth_rtw+rtw_sample", depth_rtw()));
    out.push((
        "depth_paraboloid+paraboloid_side+rtw_sample",
        depth_paraboloid(),
    ));
    out.push(("refine+rtw_sample+paraboloid_side", refine()));
    out
}

/// `source` with every shared function it asks for composed in: the RTW table
/// sampler (`@compose rtw_sample`) and the paraboloid projection (`@compose
/// paraboloid_side`); unchanged when it has no placeholder.
///
/// # Errors
/// As [`with_rtw_sample`].
pub fn expand(source: &str) -> Result<String, BackendError> {
    let mut out = source.to_owned();
    if out.contains("// @compose rtw_sample begin") {
        out = with_rtw_sample(&out)?;
    }
    if out.contains("// @compose paraboloid_side begin") {
        out = replace_region(&out, "paraboloid_side", shaders::PARABOLOID_SIDE)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_marker_is_an_error() {
        assert!(replace_region("fn a() {}", "x", "").is_err());
        let begin_only = "// @compose x begin\nfn a() {}";
        assert!(replace_region(begin_only, "x", "").is_err());
        let ok = "a\n// @compose x begin\nstub\n// @compose x end\nb";
        assert_eq!(replace_region(ok, "x", "real").unwrap(), "a\nreal\nb");
    }

    #[test]
    fn rtw_hosts_get_the_real_sampler_once() {
        for source in [
            depth_rtw().unwrap(),
            lookup_rtw().unwrap(),
            refine().unwrap(),
            depth_paraboloid().unwrap(),
            lookup_paraboloid().unwrap(),
        ] {
            assert_eq!(source.matches("fn rtw_sample(").count(), 1);
            assert!(source.contains("rtw_tables[offset + i]"));
            assert!(!source.contains("// @compose"));
            assert_eq!(source.matches("var<storage, read> rtw_tables").count(), 1);
        }
    }

    #[test]
    fn paraboloid_hosts_get_the_real_projection_once() {
        for source in [
            depth_paraboloid().unwrap(),
            lookup_paraboloid().unwrap(),
            refine().unwrap(),
        ] {
            assert_eq!(source.matches("fn paraboloid_side(").count(), 1);
            assert!(source.contains("(x * x + d.y * d.y) / (1.0 - s)"));
            assert!(!source.contains("// @compose"));
        }
    }
}
