//! Warped cascades as a [`ShadowMapping`]: the cascade is selected by view depth.
//!
//! A [`WarpedCascades`] fit records each cascade's view-depth range but not the camera,
//! so the mapping pairs the cascades with the camera's eye and viewing direction
//! ([`WarpedCascades::view`]). The view depth of a world point `p` is
//!
//! ```text
//! d = (p - eye) . forward
//! ```
//!
//! and the cascade is the first (nearest) whose `[near, far]` contains `d` (ranges
//! overlap by the blend band; the nearer, finer cascade wins). A cascade whose slice
//! missed the receivers (`shadow: None`) maps nothing: those points read as lit.

use glam::{DVec2, DVec3, Vec3};
use shadowmap_frustum::{Camera, ShadowMapping, ShadowSample};

use crate::WarpedCascades;

/// [`WarpedCascades`] seen from the camera they were fitted for: a [`ShadowMapping`]
/// whose layer is the cascade index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpedCascadesView<'a> {
    /// The fitted cascades.
    pub cascades: &'a WarpedCascades,
    /// The camera's eye (world).
    pub eye: Vec3,
    /// The camera's unit viewing direction (world).
    pub forward: Vec3,
}

impl WarpedCascades {
    /// Index of the cascade for a view depth: the first whose `[near, far]` contains
    /// it, `None` outside every cascade (or for a NaN depth).
    #[must_use]
    pub fn select_by_depth(&self, view_depth: f64) -> Option<usize> {
        self.cascades
            .iter()
            .position(|c| view_depth >= f64::from(c.near) && view_depth <= f64::from(c.far))
    }

    /// These cascades as a [`ShadowMapping`] for a camera at `eye` looking along the
    /// unit `forward`.
    #[must_use]
    pub const fn view(&self, eye: Vec3, forward: Vec3) -> WarpedCascadesView<'_> {
        WarpedCascadesView {
            cascades: self,
            eye,
            forward,
        }
    }

    /// These cascades as a [`ShadowMapping`] for `camera` (the camera they were
    /// fitted for).
    #[must_use]
    pub fn view_from(&self, camera: &Camera) -> WarpedCascadesView<'_> {
        self.view(camera.eye(), camera.forward())
    }
}

impl WarpedCascadesView<'_> {
    /// View depth of a world point, in `f64`.
    #[must_use]
    pub fn view_depth(&self, world: DVec3) -> f64 {
        (world - self.eye.as_dvec3()).dot(self.forward.as_dvec3())
    }
}

impl ShadowMapping for WarpedCascadesView<'_> {
    /// Selects by view depth ([`WarpedCascades::select_by_depth`]); the layer is the
    /// cascade index.
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let index = self.cascades.select_by_depth(self.view_depth(world))?;
        let shadow = self.cascades.cascades.get(index)?.shadow.as_ref()?;
        let mut sample = shadow.transform.map_point(world)?;
        sample.layer = u32::try_from(index).ok()?;
        Some(sample)
    }

    /// The derivative of the cascade that stores `centre` (selected by view depth),
    /// whichever cascades store the points `around` it, as `CascadeSet`'s.
    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        let index = self.cascades.select_by_depth(self.view_depth(centre))?;
        let shadow = self.cascades.cascades.get(index)?.shadow.as_ref()?;
        shadow.transform.uv_differentials(centre, around)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use shadowmap_frustum::{
        Aabb, Camera, CascadeSplits, Projection, SceneBounds, ShadowMapping, SplitScheme,
    };

    use crate::{LispsmOptions, warped_cascades};

    #[test]
    fn cascade_follows_view_depth() {
        let camera = Camera::look_to(
            Vec3::new(0.0, 5.0, 0.0),
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(1.0, 1.5, 1.0, 200.0),
        )
        .unwrap();
        let scene = SceneBounds::whole(Aabb::new(
            Vec3::new(-200.0, 0.0, -220.0),
            Vec3::new(200.0, 10.0, 10.0),
        ));
        let splits = CascadeSplits::new(&SplitScheme::Logarithmic, 3, 1.0, 200.0).unwrap();
        let w = warped_cascades(
            &camera,
            Vec3::new(0.3, -1.0, 0.2),
            &scene,
            &splits,
            &[0.0; 3],
            &LispsmOptions::default(),
        )
        .unwrap();
        let view = w.view_from(&camera);
        for (i, c) in w.cascades.iter().enumerate() {
            // A point near the view axis, inside the receivers, at the middle of the
            // cascade's own depth range (not in a blend band) maps into that cascade.
            let lo = if i == 0 {
                c.near
            } else {
                w.cascades[i - 1].far
            };
            let hi = w.cascades.get(i + 1).map_or(c.far, |n| n.near);
            let d = 0.5 * (lo + hi);
            let s = view
                .map_point(glam::DVec3::new(0.5, 4.0, -f64::from(d)))
                .unwrap();
            assert_eq!(s.layer as usize, i);
            assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
        }
        // The differentials from the derivative are those of each point mapped alone,
        // within a cascade and across the boundaries (where both refuse).
        for depth in [1.5, 10.0, 37.0, 90.0, 199.0] {
            for step in [0.01, 5.0] {
                let centre = glam::DVec3::new(0.5, 4.0, -depth);
                let around = [
                    glam::DVec3::X,
                    glam::DVec3::NEG_X,
                    glam::DVec3::Y,
                    glam::DVec3::NEG_Y,
                ]
                .map(|d| centre + d * step);
                let fast = view.uv_differentials(centre, &around);
                let slow = shadowmap_frustum::uv_differentials_by_points(&view, centre, &around);
                assert_eq!(fast.is_some(), slow.is_some(), "at {depth}, step {step}");
                // Central differences of a perspective map are its derivative to the
                // square of the step over the distance: compare at the small step.
                if let (Some(fast), Some(slow), true) = (fast, slow, step < 1.0) {
                    for (f, s) in fast.iter().zip(&slow) {
                        let tolerance = 1e-6 * s.length() + 1e-15;
                        assert!((*f - *s).length() <= tolerance, "{f} vs {s}");
                    }
                }
            }
        }
        // Behind the camera and beyond the last cascade: not mapped.
        assert!(view.map_point(glam::DVec3::new(0.0, 0.0, 5.0)).is_none());
        assert!(view.map_point(glam::DVec3::new(0.0, 0.0, -500.0)).is_none());
        assert_eq!(w.select_by_depth(f64::NAN), None);
    }
}
