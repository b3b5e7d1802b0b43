//! Visible surfaces and shadow masks: one primary ray per pixel finds what the camera
//! sees ([`GBuffer`]); the shadow test of a technique's depth map
//! ([`ShadowMask::from_map`]) or a shadow ray toward the light
//! ([`ShadowMask::ray_traced`], the ground truth) then classifies each visible point.
//!
//! Pixel `(x, y)` (row 0 at the top) looks through its centre:
//!
//! ```text
//! ndc = ((x + 1/2) / W * 2 - 1,  1 - (y + 1/2) / H * 2)
//! ray from world_from_clip * (ndc, z_near) through world_from_clip * (ndc, 1/2)
//! t up to the camera's far view depth (the shadow distance for infinite projections)
//! ```
//!
//! # Example
//!
//! ```
//! use glam::{DVec3, Vec3};
//! use shadowmap_eval::bvh::Bvh;
//! use shadowmap_eval::mask::{GBuffer, ShadowMask};
//! use shadowmap_eval::scene::Mesh;
//! use shadowmap_frustum::{Camera, Light, Projection};
//!
//! let mut mesh = Mesh::new();
//! mesh.push_quad([
//!     DVec3::new(-50.0, 0.0, -50.0),
//!     DVec3::new(-50.0, 0.0, 50.0),
//!     DVec3::new(50.0, 0.0, 50.0),
//!     DVec3::new(50.0, 0.0, -50.0),
//! ]);
//! mesh.push_box(DVec3::new(-1.0, 0.0, -1.0), DVec3::new(1.0, 2.0, 1.0));
//! let bvh = Bvh::build(&mesh)?;
//! let camera = Camera::look_at(
//!     Vec3::new(0.0, 10.0, 10.0),
//!     Vec3::ZERO,
//!     Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 100.0),
//! )
//! .unwrap();
//! let gbuffer = GBuffer::trace(&bvh, &camera, 32, 32)?;
//! let light = Light::Directional { direction: Vec3::new(0.3, -1.0, 0.2) };
//! let truth = ShadowMask::ray_traced(&gbuffer, &bvh, &light)?;
//! assert!(truth.count(Some(false)) > 0 && truth.count(Some(true)) > 0);
//! # Ok::<(), shadowmap_eval::EvalError>(())
//! ```

use glam::{DMat4, DVec3, DVec4};
use shadowmap_frustum::{Camera, Light, ShadowMapping};

use crate::EvalError;
use crate::bvh::Bvh;
use crate::raster::DepthMap;

/// Largest image side the mask functions accept.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The surface seen through one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// World position of the visible point.
    pub position: DVec3,
    /// Unit geometric normal, facing the camera.
    pub normal: DVec3,
    /// Unit direction of the primary ray (from the camera toward the point).
    pub view_dir: DVec3,
    /// Distance from the ray's start on the near plane to the point.
    pub distance: f64,
    /// Index of the mesh triangle seen.
    pub triangle: usize,
}

/// What the camera sees, pixel by pixel (row-major, row 0 at the top).
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The visible surface of each pixel, `None` for background.
    pub surfaces: Vec<Option<Surface>>,
}

/// A pixel's primary ray: start on the near plane, unit direction, and the largest
/// `t` inside the camera's depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRay {
    /// Start on the near plane.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
    /// Largest distance along `dir` inside the depth range.
    pub t_max: f64,
}

/// Unprojects pixel centres of one camera and image size.
#[derive(Clone, Copy, Debug)]
struct PixelRays {
    world_from_clip: DMat4,
    near_z: f64,
    eye: DVec3,
    forward: DVec3,
    far_depth: f64,
    width: u32,
    height: u32,
}

impl PixelRays {
    fn new(camera: &Camera, width: u32, height: u32) -> Result<Self, EvalError> {
        check_size(width, height)?;
        let view = |e: shadowmap_frustum::FrustumError| EvalError::InvalidView {
            message: e.to_string(),
        };
        let clip_from_view = camera.clip_from_view().map_err(view)?.as_dmat4();
        let view_from_world = camera.view_from_world().map_err(view)?.as_dmat4();
        let world_from_clip = (clip_from_view * view_from_world).inverse();
        let (_, far) = camera.depth_range().map_err(view)?;
        if !world_from_clip.is_finite() {
            return Err(EvalError::InvalidView {
                message: "singular camera matrix".into(),
            });
        }
        Ok(Self {
            world_from_clip,
            near_z: if camera.reversed_z { 1.0 } else { 0.0 },
            eye: camera.eye().as_dvec3(),
            forward: camera.forward().as_dvec3(),
            far_depth: f64::from(far),
            width,
            height,
        })
    }

    fn ray(&self, x: u32, y: u32) -> Option<PixelRay> {
        let nx = (f64::from(x) + 0.5) / f64::from(self.width) * 2.0 - 1.0;
        let ny = 1.0 - (f64::from(y) + 0.5) / f64::from(self.height) * 2.0;
        let unproject = |z: f64| {
            let h = self.world_from_clip * DVec4::new(nx, ny, z, 1.0);
            (h.w != 0.0).then(|| h.truncate() / h.w)
        };
        let origin = unproject(self.near_z)?;
        let dir = (unproject(0.5)? - origin).try_normalize()?;
        let along = dir.dot(self.forward);
        let start_depth = (origin - self.eye).dot(self.forward);
        let t_max = if along > 0.0 {
            (self.far_depth - start_depth) / along
        } else {
            f64::INFINITY
        };
        (origin.is_finite() && t_max > 0.0).then_some(PixelRay { origin, dir, t_max })
    }
}

fn check_size(width: u32, height: u32) -> Result<(), EvalError> {
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(EvalError::InvalidRasterSize {
            width,
            height,
            layers: 1,
        });
    }
    Ok(())
}

impl GBuffer {
    /// Casts one primary ray per pixel centre.
    ///
    /// # Errors
    /// [`EvalError::InvalidRasterSize`] for a zero size or one past
    /// [`MAX_IMAGE_SIDE`]; [`EvalError::InvalidView`] for a camera that fails
    /// [`Camera::validate`].
    pub fn trace(bvh: &Bvh, camera: &Camera, width: u32, height: u32) -> Result<Self, EvalError> {
        let rays = PixelRays::new(camera, width, height)?;
        let mut surfaces = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                surfaces.push(rays.ray(x, y).and_then(|r| {
                    bvh.intersect(r.origin, r.dir, 0.0, r.t_max)
                        .map(|hit| Surface {
                            position: hit.position,
                            normal: hit.normal,
                            view_dir: r.dir,
                            distance: hit.t,
                            triangle: hit.triangle,
                        })
                }));
            }
        }
        Ok(Self {
            width,
            height,
            surfaces,
        })
    }

    /// The primary ray of pixel `(x, y)` for a camera, as [`GBuffer::trace`] casts it;
    /// `None` for a pixel outside the image or a degenerate ray.
    ///
    /// # Errors
    /// As [`GBuffer::trace`].
    pub fn pixel_ray(
        camera: &Camera,
        width: u32,
        height: u32,
        x: u32,
        y: u32,
    ) -> Result<Option<PixelRay>, EvalError> {
        let rays = PixelRays::new(camera, width, height)?;
        Ok((x < width && y < height).then(|| rays.ray(x, y)).flatten())
    }

    /// The surface at pixel `(x, y)`, `None` for background or outside the image.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Option<&Surface> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.surfaces[y as usize * self.width as usize + x as usize].as_ref()
    }

    /// Number of pixels that see a surface.
    #[must_use]
    pub fn visible_count(&self) -> usize {
        self.surfaces.iter().filter(|s| s.is_some()).count()
    }
}

/// Per-pixel shadow classification (row-major, row 0 at the top): `Some(true)` lit,
/// `Some(false)` in shadow, `None` for background or a point the map does not cover.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShadowMask {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Classification of each pixel.
    pub lit: Vec<Option<bool>>,
}

/// How two masks differ over the pixels both classify.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaskComparison {
    /// Pixels classified by both masks.
    pub compared: usize,
    /// Pixels lit in the mask, shadowed in the truth.
    pub false_lit: usize,
    /// Pixels shadowed in the mask, lit in the truth.
    pub false_shadowed: usize,
}

impl MaskComparison {
    /// Misclassified pixels.
    #[must_use]
    pub const fn misclassified(&self) -> usize {
        self.false_lit + self.false_shadowed
    }

    /// Misclassified fraction of the compared pixels (0 when none were compared).
    #[must_use]
    pub fn rate(&self) -> f64 {
        if self.compared == 0 {
            0.0
        } else {
            self.misclassified() as f64 / self.compared as f64
        }
    }
}

impl ShadowMask {
    /// Classifies each visible point with a technique's depth map: `mapping` gives
    /// its sample, [`DepthMap::is_lit`] with `bias` (depth units, toward the light)
    /// the answer.
    #[must_use]
    pub fn from_map(
        gbuffer: &GBuffer,
        mapping: &dyn ShadowMapping,
        map: &DepthMap,
        bias: f64,
    ) -> Self {
        Self::classify(gbuffer, |s| {
            mapping
                .map_point(s.position)
                .and_then(|sample| map.is_lit(&sample, bias))
        })
    }

    /// Ground truth: a shadow ray from each visible point toward the light (along
    /// `-direction` for a directional light, to the position for point and spot
    /// lights), starting a small distance off the surface along its camera-facing
    /// normal. This is visibility only: the spot cone and the range do not darken.
    ///
    /// # Errors
    /// [`EvalError::InvalidView`] for a light that fails [`Light::validate`].
    pub fn ray_traced(gbuffer: &GBuffer, bvh: &Bvh, light: &Light) -> Result<Self, EvalError> {
        light.validate().map_err(|e| EvalError::InvalidView {
            message: e.to_string(),
        })?;
        let light = *light;
        Ok(Self::classify(gbuffer, |s| {
            let offset = 1e-5 * (1.0 + s.position.abs().max_element());
            let origin = s.position + s.normal * offset;
            let (dir, t_max) = match light {
                Light::Directional { direction } => {
                    (-direction.as_dvec3().normalize(), f64::INFINITY)
                }
                Light::Spot { position, .. } | Light::Point { position, .. } => {
                    let to = position.as_dvec3() - origin;
                    let len = to.length();
                    if !(len > offset) {
                        return Some(true);
                    }
                    (to / len, len - offset)
                }
            };
            Some(!bvh.occluded(origin, dir, 0.0, t_max))
        }))
    }

    fn classify(gbuffer: &GBuffer, mut test: impl FnMut(&Surface) -> Option<bool>) -> Self {
        Self {
            width: gbuffer.width,
            height: gbuffer.height,
            lit: gbuffer
                .surfaces
                .iter()
                .map(|s| s.as_ref().and_then(&mut test))
                .collect(),
        }
    }

    /// The classification of pixel `(x, y)`, `None` outside the image too.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Option<bool> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.lit[y as usize * self.width as usize + x as usize]
    }

    /// Number of pixels with this classification.
    #[must_use]
    pub fn count(&self, value: Option<bool>) -> usize {
        self.lit.iter().filter(|&&l| l == value).count()
    }

    /// Compares with a reference (`truth`) over the pixels both classify; masks of
    /// different sizes compare nothing.
    #[must_use]
    pub fn compare(&self, truth: &Self) -> MaskComparison {
        let mut c = MaskComparison::default();
        if (self.width, self.height) != (truth.width, truth.height) {
            return c;
        }
        for (a, b) in self.lit.iter().zip(&truth.lit) {
            if let (Some(a), Some(b)) = (a, b) {
                c.compared += 1;
                match (a, b) {
                    (true, false) => c.false_lit += 1,
                    (false, true) => c.false_shadowed += 1,
                    _ => {}
                }
            }
        }
        c
    }
}

/// [`GBuffer::trace`] then [`ShadowMask::from_map`].
///
/// # Errors
/// As [`GBuffer::trace`].
pub fn shadow_mask(
    scene_bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    mapping: &dyn ShadowMapping,
    map: &DepthMap,
    bias: f64,
) -> Result<ShadowMask, EvalError> {
    let gbuffer = GBuffer::trace(scene_bvh, camera, width, height)?;
    Ok(ShadowMask::from_map(&gbuffer, mapping, map, bias))
}

/// [`GBuffer::trace`] then [`ShadowMask::ray_traced`].
///
/// # Errors
/// As [`GBuffer::trace`] and [`ShadowMask::ray_traced`].
pub fn ray_traced_mask(
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
    light: &Light,
) -> Result<ShadowMask, EvalError> {
    let gbuffer = GBuffer::trace(bvh, camera, width, height)?;
    ShadowMask::ray_traced(&gbuffer, bvh, light)
}
