//! The depth pass of RTW over a paraboloid side: the side's projection, then its
//! texture coordinates through the side's warp tables (vertices only, as the GPU
//! does), depth and clip distance unchanged.

use glam::{DVec3, DVec4};
use shadowmap::rtw::{WarpMaps, forward_warp_f64};

use crate::raster::{ClipVertex, DepthProjector};

/// `inner`'s vertices with `uv` warped by `warps` (`inner` maps to `w = 1`).
pub(super) struct WarpedProjector<'a, P> {
    pub(super) inner: P,
    pub(super) warps: &'a WarpMaps,
}

impl<P: DepthProjector> DepthProjector for WarpedProjector<'_, P> {
    fn layers(&self) -> u32 {
        self.inner.layers()
    }
    fn reversed_z(&self) -> bool {
        self.inner.reversed_z()
    }
    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex> {
        let v = self.inner.project_vertex(layer, world)?;
        let (u, t) = (0.5 + 0.5 * v.clip.x, 0.5 - 0.5 * v.clip.y);
        let u = forward_warp_f64(self.warps.x_table(), u);
        let t = forward_warp_f64(self.warps.y_table(), t);
        let clip = DVec4::new(2.0 * u - 1.0, 1.0 - 2.0 * t, v.clip.z, v.clip.w);
        clip.is_finite()
            .then_some(ClipVertex::new(clip, v.clip_distance))
    }
}
