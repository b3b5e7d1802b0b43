//! The CPU reference of projective shadows: the occluder mask rasterized from the
//! light, and the receivers' lookup through homogeneous texture coordinates.
//!
//! The mask is `side x side` texels, row 0 at the top (`v` down). A texel is an
//! occluder texel when its centre lies inside (or on the edge of) the light-space
//! projection of an occluder triangle, whatever the triangle's winding. A receiver
//! point is shadowed when its mask coordinates (see [`ProjectiveShadow`]) fall in
//! an occluder texel:
//!
//! ```text
//! (s, t, _, q) = uv_from_world * (p, 1);   q <= 0: lit (behind the light)
//! texel = floor((s / q, t / q) * side);    outside the mask: lit
//! ```

use alloc::vec::Vec;

use glam::{DVec2, DVec4, Vec3};
use shadowmap_frustum::math::floor;

use crate::{ProjectiveShadow, VolumeError};

/// Largest mask side accepted.
pub const MAX_MASK_SIDE: u32 = 16384;

/// The occluder mask of a projective shadow.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OccluderMask {
    /// Texels per side.
    pub side: u32,
    /// `side * side` flags, row-major, row 0 at the top: `true` where an occluder is.
    pub occluded: Vec<bool>,
}

impl OccluderMask {
    /// Rasterizes the occluder triangles (`indices` into `positions`) with the
    /// shadow's `clip_from_world`. Triangles with a corner behind the light
    /// (`w <= 0`; not the case for occluders inside the bounds the shadow was
    /// framed for) are skipped.
    ///
    /// # Errors
    /// [`VolumeError::InvalidOccluders`] for a side of 0 or past
    /// [`MAX_MASK_SIDE`]; [`VolumeError::IndexOutOfRange`] for a bad index;
    /// [`VolumeError::NonFinite`] for a non-finite position.
    pub fn render(
        shadow: &ProjectiveShadow,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        side: u32,
    ) -> Result<Self, VolumeError> {
        if side == 0 || side > MAX_MASK_SIDE {
            return Err(VolumeError::InvalidOccluders);
        }
        if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
            return Err(VolumeError::NonFinite { vertex });
        }
        let n = positions.len();
        if let Some(triangle) = indices
            .iter()
            .position(|t| t.iter().any(|&k| k as usize >= n))
        {
            return Err(VolumeError::IndexOutOfRange { triangle });
        }
        let mut mask = Self {
            side,
            occluded: alloc::vec![false; side as usize * side as usize],
        };
        let m = shadow.clip_from_world.as_dmat4();
        let s = f64::from(side);
        for tri in indices {
            let clip = tri.map(|k| m * positions[k as usize].as_dvec3().extend(1.0));
            if clip.iter().any(|c: &DVec4| !(c.w > 0.0)) {
                continue;
            }
            let t =
                clip.map(|c| DVec2::new((c.x / c.w * 0.5 + 0.5) * s, (0.5 - c.y / c.w * 0.5) * s));
            mask.fill(t);
        }
        Ok(mask)
    }

    /// Marks the texels whose centres lie in the triangle `t` (texel units).
    fn fill(&mut self, t: [DVec2; 3]) {
        let edge = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
        let area = edge(t[0], t[1], t[2]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        let side = f64::from(self.side);
        let first = |v: f64| floor((v - 0.5).clamp(-1.0, side)) as i64 + 1;
        let last = |v: f64| floor((v - 0.5).clamp(-1.0, side)) as i64;
        let (x0, x1) = (first(lo.x).max(0), last(hi.x).min(i64::from(self.side) - 1));
        let (y0, y1) = (first(lo.y).max(0), last(hi.y).min(i64::from(self.side) - 1));
        let sign = if area > 0.0 { 1.0 } else { -1.0 };
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let inside = (0..3).all(|k| sign * edge(t[k], t[(k + 1) % 3], p) >= 0.0);
                if inside {
                    self.occluded[y as usize * self.side as usize + x as usize] = true;
                }
            }
        }
    }

    /// Is the world point `p` (a receiver) in an occluder's projective shadow?
    #[must_use]
    pub fn shadows(&self, shadow: &ProjectiveShadow, p: Vec3) -> bool {
        let Some(uv) = shadow.uv(p) else {
            return false;
        };
        let s = f64::from(self.side);
        let (x, y) = (floor(f64::from(uv.x) * s), floor(f64::from(uv.y) * s));
        if !(x >= 0.0 && y >= 0.0 && x < s && y < s) {
            return false;
        }
        self.occluded[y as usize * self.side as usize + x as usize]
    }
}
