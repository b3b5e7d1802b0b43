//! What the renderer keeps across frames on the depth side: the depth passes (texture
//! and pipeline per description), the scene's casters on the GPU and their refinement.
//! A frame with the same scene and maps as the last records commands and writes
//! uniforms only, as an engine's frame would.

use glam::Vec3;

use crate::depth::{DepthPassDesc, MeshBuffers, ShadowDepthPass};
use crate::refine::{GpuRefine, RefineOptions};
use crate::{BackendError, GpuContext};

/// Depth passes kept at most (a 2048² layer is 16 MiB).
const MAX_PASSES: usize = 4;

/// The scene's casters as uploaded, with the refinement built over them.
#[derive(Debug)]
struct Casters {
    triangles: Vec<[Vec3; 3]>,
    mesh: MeshBuffers,
    refine: Option<GpuRefine>,
}

/// The depth side of the renderer's frames.
#[derive(Debug, Default)]
pub(super) struct DepthCache {
    /// Most recently used last.
    passes: Vec<ShadowDepthPass>,
    casters: Option<Casters>,
}

impl DepthCache {
    /// Uploads `triangles` unless they are the last frame's (compared by value).
    ///
    /// # Errors
    /// As [`MeshBuffers::from_triangles`].
    pub(super) fn use_scene(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
    ) -> Result<(), BackendError> {
        if self
            .casters
            .as_ref()
            .is_some_and(|c| c.triangles == triangles)
        {
            return Ok(());
        }
        self.casters = None;
        let mesh = MeshBuffers::from_triangles(ctx, triangles)?;
        self.casters = Some(Casters {
            triangles: triangles.to_vec(),
            mesh,
            refine: None,
        });
        Ok(())
    }

    /// The scene mesh of [`DepthCache::use_scene`].
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] before any scene.
    pub(super) fn mesh(&self) -> Result<&MeshBuffers, BackendError> {
        self.casters
            .as_ref()
            .map(|c| &c.mesh)
            .ok_or(BackendError::InvalidInput("no scene uploaded"))
    }

    /// The scene's caster triangles of [`DepthCache::use_scene`].
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] before any scene.
    pub(super) fn triangles(&self) -> Result<&[[Vec3; 3]], BackendError> {
        self.casters
            .as_ref()
            .map(|c| c.triangles.as_slice())
            .ok_or(BackendError::InvalidInput("no scene uploaded"))
    }

    /// The index of the depth pass of `desc`, created (and the least recently used
    /// one dropped) when it is not kept.
    ///
    /// # Errors
    /// As [`ShadowDepthPass::new`].
    pub(super) fn pass_index(
        &mut self,
        ctx: &GpuContext,
        desc: &DepthPassDesc,
    ) -> Result<usize, BackendError> {
        if let Some(i) = self.passes.iter().position(|p| p.desc() == desc) {
            let pass = self.passes.remove(i);
            self.passes.push(pass);
        } else {
            let pass = ShadowDepthPass::new(ctx, desc)?;
            if self.passes.len() >= MAX_PASSES {
                self.passes.remove(0);
            }
            self.passes.push(pass);
        }
        Ok(self.passes.len() - 1)
    }

    /// The pass at `index` (from [`DepthCache::pass_index`]).
    pub(super) fn pass(&self, index: usize) -> Option<&ShadowDepthPass> {
        self.passes.get(index)
    }

    /// The pass at `index`, the scene mesh and the scene's refinement with `options`
    /// (built when missing or built with other options), borrowed together.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a bad index or no scene; as
    /// [`GpuRefine::new`].
    pub(super) fn parts(
        &mut self,
        ctx: &GpuContext,
        index: usize,
        options: Option<&RefineOptions>,
    ) -> Result<(&mut ShadowDepthPass, &MeshBuffers, Option<&mut GpuRefine>), BackendError> {
        let casters = self
            .casters
            .as_mut()
            .ok_or(BackendError::InvalidInput("no scene uploaded"))?;
        let pass = self
            .passes
            .get_mut(index)
            .ok_or(BackendError::InvalidInput("no such depth pass"))?;
        let refine = match options {
            Some(options) => {
                if casters
                    .refine
                    .as_ref()
                    .is_none_or(|r| r.options() != options)
                {
                    casters.refine = None;
                    casters.refine = Some(GpuRefine::new(ctx, &casters.triangles, options)?);
                }
                casters.refine.as_mut()
            }
            None => None,
        };
        Ok((pass, &casters.mesh, refine))
    }
}
