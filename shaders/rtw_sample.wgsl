// techniques: rtw
// The RTW warp-table sampler, shared by depth_rtw.wgsl and lookup_rtw.wgsl: the
// renderer composes it into their `@compose rtw_sample` regions (see
// `compose::with_rtw_sample`). S(u) of the table at `offset` with `n` texels, with the
// exact texel-centre linear, clamp-to-edge semantics of `shadowmap_rtw::sample_table`
// (texel `i` holds the offset at `(i + 0.5) / n`), so the CPU and the GPU agree to
// the last bit (up to fused multiply-adds).
//
// The host declares `rtw_tables` (the u table, then the v table) in its own bind
// group; the stand-in below lets this file validate on its own and is dropped when
// composed.

// @compose rtw_tables begin
@group(0) @binding(1) var<storage, read> rtw_tables: array<f32>;
// @compose rtw_tables end

fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    if n == 0u {
        return 0.0;
    }
    let x = u * f32(n) - 0.5;
    if !(x > 0.0) {
        return rtw_tables[offset];
    }
    if x >= f32(n - 1u) {
        return rtw_tables[offset + n - 1u];
    }
    let i = u32(x);
    let f = x - f32(i);
    let a = rtw_tables[offset + i];
    let b = rtw_tables[offset + min(i + 1u, n - 1u)];
    return a + f * (b - a);
}
