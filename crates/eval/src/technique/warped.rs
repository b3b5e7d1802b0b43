//! The depth pass of RTW over a paraboloid side or a cube face: the base's
//! projection, then its texture coordinates through the base's warp tables
//! (vertices only, as the GPU does), depth and clip distance unchanged.

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};
use shadowmap::rtw::{RtwSubdivision, WarpMaps, forward_warp_f64, subdivide_for_rtw_clipped};

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

/// A perspective face's projection divided by `w` (so that the warp acts on its
/// texture coordinates): `(x / w, y / w, z / w, 1)`, `None` at or behind the light's
/// plane (the casters are cut to the face's frustum first, see [`face_pieces`]).
pub(super) struct DividedProjector {
    pub(super) clip_from_world: DMat4,
    pub(super) reversed_z: bool,
}

impl DepthProjector for DividedProjector {
    fn layers(&self) -> u32 {
        1
    }
    fn reversed_z(&self) -> bool {
        self.reversed_z
    }
    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex> {
        let c = self.clip_from_world * world.extend(1.0);
        let ndc = c.truncate() / c.w;
        (layer == 0 && c.w > 0.0 && ndc.is_finite()).then(|| ClipVertex::unclipped(ndc.extend(1.0)))
    }
}

/// The casters of one warped perspective face (`clip_from_world`, its near plane
/// at face depth `near`, tables `warps`, `side` texels): cut to the window's
/// frustum (near plane and the four sides, where the depth pass clips them anyway)
/// and subdivided by the RTW rule, with enough pieces an edge to cross the window.
pub(super) fn face_pieces(
    clip_from_world: DMat4,
    near: f32,
    warps: &WarpMaps,
    side: u32,
    triangles: &[[Vec3; 3]],
    out: &mut Vec<[Vec3; 3]>,
) {
    let m = clip_from_world;
    let clip = move |p: Vec3| m * p.as_dvec3().extend(1.0);
    let uv = |p: Vec3| {
        let c = clip(p);
        (c.w > 0.0).then(|| DVec2::new(0.5 + 0.5 * c.x / c.w, 0.5 - 0.5 * c.y / c.w))
    };
    let near = f64::from(near);
    let planes: [&dyn Fn(Vec3) -> f64; 5] = [
        &|p| clip(p).w - near,
        &|p| clip(p).w + clip(p).x,
        &|p| clip(p).w - clip(p).x,
        &|p| clip(p).w + clip(p).y,
        &|p| clip(p).w - clip(p).y,
    ];
    let cells = warps.x_table().len().max(warps.y_table().len());
    let rule = RtwSubdivision::default()
        .with_resolution(side)
        .with_segments_for_extent(1.0, cells);
    subdivide_for_rtw_clipped(uv, &planes, warps, triangles, &rule, out);
}
