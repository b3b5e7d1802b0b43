//! A fitted [`Shadow`] of the umbrella crate (`shadowmap::fit`) handed to the
//! backend: the one match from its result to the renderer's [`ShadowTechnique`].
//!
//! ```no_run
//! use glam::Vec3;
//! use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds};
//! use shadowmap::{FitInput, Technique, fit};
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions};
//!
//! let ctx = GpuContext::new_headless()?;
//! let ground = [[Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 0.0, -10.0), Vec3::new(0.0, 0.0, 10.0)]];
//! let camera = Camera::look_at(Vec3::new(0.0, 5.0, 15.0), Vec3::ZERO, Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 50.0)).unwrap();
//! let scene = SceneBounds::whole(Aabb::new(Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 1.0, 10.0)));
//! let sun = Light::Directional { direction: Vec3::new(0.3, -1.0, 0.2) };
//! let shadow = fit(&Technique::Lispsm(Default::default()), &FitInput::new(&camera, &sun, scene, 1024 * 1024))
//!     .expect("fit");
//! let frame = HeadlessRenderer::new().render_shadow(&ctx, &ground, &camera, &shadow, &RenderOptions::default())?;
//! frame.image.save_png("shadow.png")?;
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use glam::Vec3;
use shadowmap::{Fitted, Shadow};
use shadowmap_frustum::Camera;

use crate::render::{HeadlessRenderer, RenderOptions, RenderedFrame, ShadowTechnique};
use crate::{BackendError, GpuContext};

impl HeadlessRenderer {
    /// Renders `triangles` from `camera` with a fitted [`Shadow`]: its result picks
    /// the depth pass and lookup ([`with_technique`]) and its layer side replaces
    /// `options.shadow_resolution`, so the maps have the texels the fit budgeted.
    ///
    /// # Errors
    /// As [`HeadlessRenderer::render`]; [`BackendError::InvalidInput`] for a result
    /// the backend has no pass for.
    pub fn render_shadow(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
        camera: &Camera,
        shadow: &Shadow,
        options: &RenderOptions,
    ) -> Result<RenderedFrame, BackendError> {
        let options = options.with_shadow_resolution(shadow.layer_side());
        with_technique(shadow, |technique| {
            self.render(ctx, triangles, camera, technique, &options)
        })?
    }
}

/// Calls `f` with the renderer's [`ShadowTechnique`] for a fitted shadow: the one
/// match from the umbrella crate's results to the backend's passes (RTW's borrowed
/// view of its tables lives for the call). RTW runs over whatever base it was fitted
/// on: the uniform fit (orthographic), the spot fit (perspective), the kept faces of
/// a cube map (`cube_rtw`) or the sides of the IPSM paraboloid (`point_rtw`).
///
/// # Errors
/// [`BackendError::InvalidInput`] for a result the backend has no pass for (a
/// `Fitted` variant added after this backend).
pub fn with_technique<R>(
    shadow: &Shadow,
    f: impl FnOnce(&ShadowTechnique<'_>) -> R,
) -> Result<R, BackendError> {
    let rtw = shadow.rtw();
    let technique = match (shadow.fitted(), &rtw) {
        (_, Some(rtw)) => ShadowTechnique::Rtw(rtw),
        (Fitted::Uniform(t), _) => ShadowTechnique::Matrix(t),
        (Fitted::Lispsm(s), _) => ShadowTechnique::Matrix(&s.transform),
        (Fitted::Tsm(s), _) => ShadowTechnique::Matrix(&s.transform),
        (Fitted::Spot(s), _) => ShadowTechnique::Matrix(&s.transform),
        (Fitted::SpotWarp(s), _) => ShadowTechnique::Matrix(&s.transform),
        (Fitted::Xpsm(x), _) => ShadowTechnique::Xpsm(x),
        (Fitted::Cascades(set), _) => ShadowTechnique::Cascades(set),
        (Fitted::Dpsm(map), _) => ShadowTechnique::Paraboloid(map),
        (Fitted::Ipsm(plan), _) => ShadowTechnique::Paraboloid(&plan.map),
        (Fitted::PointRtw { plan, front, back }, _) => ShadowTechnique::ParaboloidRtw {
            map: &plan.map,
            front,
            back: back.as_ref(),
        },
        (Fitted::WarpedCascades { cascades, .. }, _) => ShadowTechnique::WarpedCascades(cascades),
        (Fitted::Cube(cube), _) => ShadowTechnique::Cube(cube),
        (Fitted::CubeRtw { cube, warps }, _) => ShadowTechnique::CubeRtw { cube, warps },
        (Fitted::TiledCube(tiled), _) => ShadowTechnique::TiledCube(tiled),
        _ => return Err(UNSUPPORTED),
    };
    Ok(f(&technique))
}

const UNSUPPORTED: BackendError =
    BackendError::InvalidInput("the backend has no pass for this technique");
