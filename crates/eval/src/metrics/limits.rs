//! The limits printed beside the report's tables: Lloyd et al.'s frustum samples and
//! separable storage factor, and the logarithmic parameterization they are compared
//! with.

use glam::{DVec2, DVec3};
use shadowmap_frustum::{Camera, Light, Projection, ShadowMapping, ShadowSample};

use super::{
    ScreenGeometry, SurfacePoint, bisector_normal, separable_storage_factor, texel_footprint,
};

/// Points sampling the whole view frustum with the perspective-only normal (the
/// bisector of the eye and light directions): `nx x ny` pixel positions (cell
/// centres) times `nz` view depths spaced geometrically from near to far (both
/// included). With `nx = ny = 1` the points lie on the view direction (the ray
/// through the image centre): the point set of Lloyd et al.'s analysis.
#[must_use]
pub fn frustum_samples(
    screen: &ScreenGeometry,
    camera: &Camera,
    light: &Light,
    nx: u32,
    ny: u32,
    nz: u32,
) -> Vec<SurfacePoint> {
    let Ok((near, far)) = camera.depth_range() else {
        return Vec::new();
    };
    let (near, far) = (f64::from(near), f64::from(far));
    let forward = camera.forward().as_dvec3();
    let mut out = Vec::new();
    for k in 0..nz {
        let t = if nz > 1 {
            f64::from(k) / f64::from(nz - 1)
        } else {
            0.0
        };
        let depth = near * (far / near).powf(t);
        for j in 0..ny {
            for i in 0..nx {
                let px = DVec2::new(
                    (f64::from(i) + 0.5) / f64::from(nx) * f64::from(screen.width),
                    (f64::from(j) + 0.5) / f64::from(ny) * f64::from(screen.height),
                );
                let Some((o, d)) = screen.ray(px) else {
                    continue;
                };
                let eye = camera.eye().as_dvec3();
                let along = d.dot(forward);
                if along <= 0.0 {
                    continue;
                }
                // The point at this view depth on the pixel's ray.
                let t_ray = (depth - (o - eye).dot(forward)) / along;
                let p = o + d * t_ray;
                if let Some(normal) = bisector_normal(d, light, p) {
                    out.push(SurfacePoint {
                        position: p,
                        normal,
                    });
                }
            }
        }
    }
    out
}

/// Lloyd et al.'s measurement: the separable storage factor of the perspective-only
/// error over `samples` (from [`frustum_samples`]), with all `screen` pixels as the
/// pixel count. Each layer (cascade) is scaled on its own, so the factors of the
/// layers add up:
///
/// ```text
/// S_sep = sum over layers l of (texels_l / pixels) * max_l(m_u) * max_l(m_v)
/// ```
///
/// (the maxima over the samples stored in layer `l`). `None` if no sample is
/// covered.
#[must_use]
pub fn frustum_storage_factor(
    mapping: &dyn ShadowMapping,
    layer_sizes: &[(u32, u32)],
    screen: &ScreenGeometry,
    samples: &[SurfacePoint],
) -> Option<f64> {
    // Per layer: (max m_u, max m_v), zero while no sample landed there.
    let mut maxima = vec![(0.0f64, 0.0f64); layer_sizes.len()];
    let mut any = false;
    for s in samples {
        let Some(fp) = texel_footprint(mapping, layer_sizes, screen, s) else {
            continue;
        };
        let (mu, mv) = fp.axis_errors();
        if let Some(m) = maxima.get_mut(fp.layer as usize) {
            if mu.is_finite() && mv.is_finite() {
                m.0 = m.0.max(mu);
                m.1 = m.1.max(mv);
                any = true;
            }
        }
    }
    any.then(|| {
        layer_sizes
            .iter()
            .zip(&maxima)
            .map(|(size, (mu, mv))| {
                let texels = u64::from(size.0) * u64::from(size.1);
                separable_storage_factor(texels, screen.pixel_count(), *mu, *mv)
            })
            .sum()
    })
}

/// The ideal separable parameterization of Lloyd et al. for a light perpendicular to
/// the view direction (the logarithmic bound): `u` follows the eye's perspective
/// across the view, `v` is logarithmic in view depth.
///
/// ```text
/// z = (p - eye) . t     s = (p - eye) . b      t = view direction, b = t x light
/// u = 1/2 + s / (2 z tan(fovX / 2))             v = ln(z / n) / ln(f / n)
/// ```
///
/// A reference mapping for the metric code, not a technique: it has no depth pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogParameterization {
    eye: DVec3,
    along: DVec3,
    across: DVec3,
    tan_half_x: f64,
    near: f64,
    far: f64,
}

impl LogParameterization {
    /// The parameterization for a perspective `camera` and a directional light
    /// travelling along `light_direction` (perpendicular to the view for the bound
    /// to hold). `None` for other cameras or a light parallel to the view.
    #[must_use]
    pub fn new(camera: &Camera, light_direction: DVec3) -> Option<Self> {
        let Projection::Perspective {
            fov_y,
            aspect,
            near,
            far,
        } = camera.projection
        else {
            return None;
        };
        let l = light_direction.try_normalize()?;
        let f = camera.forward().as_dvec3();
        let along = (f - l * f.dot(l)).try_normalize()?;
        let across = along.cross(l).try_normalize()?;
        Some(Self {
            eye: camera.eye().as_dvec3(),
            along,
            across,
            tan_half_x: (f64::from(fov_y) * 0.5).tan() * f64::from(aspect),
            near: f64::from(near),
            far: f64::from(far),
        })
    }
}

impl ShadowMapping for LogParameterization {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let d = world - self.eye;
        let z = d.dot(self.along);
        if !(z > 0.0) {
            return None;
        }
        let s = d.dot(self.across);
        let uv = DVec2::new(
            0.5 + s / (2.0 * z * self.tan_half_x),
            (z / self.near).ln() / (self.far / self.near).ln(),
        );
        uv.is_finite().then_some(ShadowSample {
            uv,
            depth: 0.5,
            layer: 0,
        })
    }
}
