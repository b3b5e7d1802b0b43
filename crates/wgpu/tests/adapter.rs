//! The adapter opens, or the test skips with a notice (fails under SHADOWMAP_REQUIRE_GPU=1).

#[test]
fn adapter_opens_and_reports_its_name() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("adapter_opens_and_reports_its_name")
    else {
        return;
    };
    let name = ctx.describe();
    eprintln!("adapter: {name}");
    assert!(!name.is_empty());
    let limits = ctx.device.limits();
    assert!(limits.max_texture_dimension_2d >= 2048);
}
