//! Depth maps whose layers differ in size: the faces of a cube map, each at its own
//! resolution.

use super::DepthMap;
use crate::EvalError;

impl DepthMap {
    /// One map of the layers of `maps`, in order, each keeping its own size (the
    /// faces of a cube map, say): `width` and `height` are the largest, a layer's
    /// own size is [`DepthMap::layer_size`].
    ///
    /// # Errors
    /// [`EvalError::InvalidRasterSize`] for no map, or maps of both depth
    /// conventions.
    pub fn from_layers(maps: Vec<Self>) -> Result<Self, EvalError> {
        let first = maps.first().ok_or(EvalError::InvalidRasterSize {
            width: 0,
            height: 0,
            layers: 0,
        })?;
        let reversed_z = first.reversed_z;
        let mut sizes = Vec::new();
        for m in &maps {
            if m.reversed_z != reversed_z {
                return Err(EvalError::InvalidRasterSize {
                    width: m.width,
                    height: m.height,
                    layers: m.layers,
                });
            }
            sizes.extend((0..m.layers).map(|l| m.layer_size(l)));
        }
        Ok(Self {
            width: sizes.iter().map(|s| s.0).max().unwrap_or(0),
            height: sizes.iter().map(|s| s.1).max().unwrap_or(0),
            layers: u32::try_from(sizes.len()).unwrap_or(u32::MAX),
            reversed_z,
            depth: maps.into_iter().flat_map(|m| m.depth).collect(),
            sizes: Some(sizes),
        })
    }

    /// The size `(width, height)` of a layer (`(0, 0)` past the last).
    #[must_use]
    pub fn layer_size(&self, layer: u32) -> (u32, u32) {
        match &self.sizes {
            Some(sizes) => sizes.get(layer as usize).copied().unwrap_or((0, 0)),
            None if layer < self.layers => (self.width, self.height),
            None => (0, 0),
        }
    }

    /// Where a layer starts in [`DepthMap::depth`].
    pub(super) fn layer_offset(&self, layer: u32) -> usize {
        match &self.sizes {
            Some(sizes) => sizes
                .iter()
                .take(layer as usize)
                .map(|(w, h)| *w as usize * *h as usize)
                .sum(),
            None => layer as usize * self.height as usize * self.width as usize,
        }
    }
}
