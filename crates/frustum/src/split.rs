use arrayvec::ArrayVec;

use crate::camera::MIN_RELATIVE_DEPTH_RANGE;
use crate::{FrustumError, math};

/// Most cascades any builder of this crate produces.
pub const MAX_CASCADES: usize = 8;

/// How the view depth range is divided among cascades (PSSM, Zhang et al. 2006).
///
/// With `n` = near, `f` = far, `m` cascades and `i` in `0..=m`:
///
/// ```text
/// uniform       C_i = n + (f - n) * i / m
/// logarithmic   C_i = n * (f / n)^(i / m)
/// practical     C_i = lambda * C_i_log + (1 - lambda) * C_i_uniform
/// ```
///
/// The PSSM thesis in the seeds prints the logarithmic scheme as `n + (f/n)^(i/m)`,
/// which does not start at `n`; the form above is the one of Zhang et al. and of
/// Lloyd's logarithmic analysis.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SplitScheme {
    /// Equal depth ranges.
    Uniform,
    /// Equal depth ratios: optimal for the perspective aliasing of a flat view.
    Logarithmic,
    /// Blend of the two, `lambda` in `[0, 1]` (0 = uniform, 1 = logarithmic).
    Practical {
        /// Blend weight of the logarithmic scheme.
        lambda: f32,
    },
    /// The interior split depths, strictly increasing inside `(near, far)`; the
    /// cascade count is their number plus one.
    Custom(ArrayVec<f32, { MAX_CASCADES - 1 }>),
}

/// Split depths of a cascade set, with an optional blend band.
///
/// Cascade `i` covers view depths `[split(i) - band(i - 1), split(i + 1)]`: each
/// cascade after the first reaches back over the blend band of its predecessor, and
/// inside that band a renderer blends the two with [`CascadeSplits::select`].
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CascadeSplits {
    depths: ArrayVec<f32, { MAX_CASCADES + 1 }>,
    overlap: f32,
}

/// The cascade for a view depth and the weight of the next cascade in the blend band.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CascadeBlend {
    /// Index of the cascade to sample.
    pub index: usize,
    /// Weight of cascade `index + 1`, in `[0, 1]`: 0 outside the blend band.
    pub next_weight: f32,
}

impl CascadeSplits {
    /// Splits `[near, far]` into `count` cascades.
    ///
    /// The first depth equals `near` and the last equals `far` exactly; the depths are
    /// strictly increasing.
    ///
    /// # Errors
    /// [`FrustumError::InvalidCascadeCount`] for `count` zero, above
    /// [`MAX_CASCADES`], or not matching a custom list;
    /// [`FrustumError::NonFinite`]; [`FrustumError::InvalidDepthRange`] for
    /// `near <= 0`, `far <= near`, or a range too thin for `count` distinct `f32`
    /// depths; [`FrustumError::InvalidSplitParameter`] for lambda outside `[0, 1]`;
    /// [`FrustumError::InvalidCustomSplits`].
    pub fn new(
        scheme: &SplitScheme,
        count: usize,
        near: f32,
        far: f32,
    ) -> Result<Self, FrustumError> {
        if count == 0 || count > MAX_CASCADES {
            return Err(FrustumError::InvalidCascadeCount);
        }
        if !(near.is_finite() && far.is_finite()) {
            return Err(FrustumError::NonFinite);
        }
        let range_err = FrustumError::InvalidDepthRange { near, far };
        let (n, f) = (f64::from(near), f64::from(far));
        if n <= 0.0 || f <= n || (f - n) < MIN_RELATIVE_DEPTH_RANGE * f {
            return Err(range_err);
        }
        let mut depths = ArrayVec::new();
        depths.push(near);
        let m = count as f64;
        match scheme {
            SplitScheme::Custom(interior) => {
                if interior.len() + 1 != count {
                    return Err(FrustumError::InvalidCascadeCount);
                }
                for d in interior {
                    if !d.is_finite() {
                        return Err(FrustumError::NonFinite);
                    }
                    depths.push(*d);
                }
            }
            _ => {
                let lambda = match scheme {
                    SplitScheme::Uniform => 0.0,
                    SplitScheme::Logarithmic => 1.0,
                    SplitScheme::Practical { lambda } => {
                        if !(0.0..=1.0).contains(lambda) {
                            return Err(FrustumError::InvalidSplitParameter);
                        }
                        f64::from(*lambda)
                    }
                    SplitScheme::Custom(_) => unreachable!("handled above"),
                };
                for i in 1..count {
                    let t = i as f64 / m;
                    let uniform = n + (f - n) * t;
                    let log = n * math::powf(f / n, t);
                    depths.push((lambda * log + (1.0 - lambda) * uniform) as f32);
                }
            }
        }
        depths.push(far);
        if depths.windows(2).any(|w| w[1] <= w[0]) {
            return Err(match scheme {
                SplitScheme::Custom(_) => FrustumError::InvalidCustomSplits,
                _ => range_err,
            });
        }
        Ok(Self {
            depths,
            overlap: 0.0,
        })
    }

    /// These splits with the first cascade starting at view depth `near` and the
    /// last ending at `far`, the splits between them unchanged: how the stable
    /// cascades cover a held range's margins
    /// ([`CascadeState::hold_depth_range`](crate::CascadeState::hold_depth_range))
    /// without moving a split.
    ///
    /// ```
    /// use shadowmap_frustum::{CascadeSplits, SplitScheme};
    /// let splits = CascadeSplits::new(&SplitScheme::Logarithmic, 2, 10.0, 1000.0)?;
    /// assert_eq!(splits.depths(), &[10.0, 100.0, 1000.0]);
    /// let wider = splits.clone().with_ends(8.0, 1250.0)?;
    /// assert_eq!(wider.depths(), &[8.0, 100.0, 1250.0]);
    /// // An end past an interior split is refused.
    /// assert!(splits.with_ends(200.0, 1000.0).is_err());
    /// # Ok::<(), shadowmap_frustum::FrustumError>(())
    /// ```
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`]; [`FrustumError::InvalidDepthRange`] for
    /// `near <= 0` or ends that are not strictly outside the interior splits.
    pub fn with_ends(mut self, near: f32, far: f32) -> Result<Self, FrustumError> {
        if !(near.is_finite() && far.is_finite()) {
            return Err(FrustumError::NonFinite);
        }
        let last = self.depths.len() - 1;
        let inner_lo = if last > 1 { self.depths[1] } else { far };
        let inner_hi = if last > 1 {
            self.depths[last - 1]
        } else {
            near
        };
        if near <= 0.0 || near >= inner_lo || far <= inner_hi || far <= near {
            return Err(FrustumError::InvalidDepthRange { near, far });
        }
        self.depths[0] = near;
        self.depths[last] = far;
        Ok(self)
    }

    /// These splits with a blend band: the last `overlap` fraction (in `[0, 1)`) of each
    /// cascade's own range is blended with the next cascade.
    ///
    /// # Errors
    /// [`FrustumError::InvalidSplitParameter`] for an overlap outside `[0, 1)`.
    pub fn with_overlap(mut self, overlap: f32) -> Result<Self, FrustumError> {
        if !(0.0..1.0).contains(&overlap) {
            return Err(FrustumError::InvalidSplitParameter);
        }
        self.overlap = overlap;
        Ok(self)
    }

    /// Number of cascades.
    #[must_use]
    pub fn count(&self) -> usize {
        self.depths.len() - 1
    }

    /// The `count + 1` split depths, from near to far.
    #[must_use]
    pub fn depths(&self) -> &[f32] {
        &self.depths
    }

    /// The blend-band fraction.
    #[must_use]
    pub fn overlap(&self) -> f32 {
        self.overlap
    }

    /// Width of the blend band at the far end of cascade `i` (zero for the last).
    #[must_use]
    pub fn band_width(&self, i: usize) -> f32 {
        if i + 1 >= self.count() {
            0.0
        } else {
            (self.depths[i + 1] - self.depths[i]) * self.overlap
        }
    }

    /// The view-depth range cascade `i` must cover, including the blend band it
    /// shares with its predecessor. `None` for an index out of range.
    #[must_use]
    pub fn cascade_range(&self, i: usize) -> Option<(f32, f32)> {
        if i >= self.count() {
            return None;
        }
        let start = if i == 0 {
            self.depths[0]
        } else {
            self.depths[i] - self.band_width(i - 1)
        };
        Some((start, self.depths[i + 1]))
    }

    /// The cascade for a view depth, by depth comparison, and the blend weight toward
    /// the next cascade (a smooth ramp across the band). Depths before `near` select
    /// cascade 0; `None` beyond `far` or for NaN.
    #[must_use]
    pub fn select(&self, view_depth: f32) -> Option<CascadeBlend> {
        if view_depth.is_nan() || view_depth > *self.depths.last()? {
            return None;
        }
        let index = self.depths[1..]
            .iter()
            .position(|d| view_depth <= *d)
            .unwrap_or(self.count() - 1);
        Some(CascadeBlend {
            index,
            next_weight: self.blend_weight(index, view_depth),
        })
    }

    /// Weight of cascade `i + 1` at `view_depth` while in cascade `i`: 0 before the
    /// band, rising linearly to 1 at the split.
    #[must_use]
    pub fn blend_weight(&self, i: usize, view_depth: f32) -> f32 {
        let band = self.band_width(i);
        if band <= 0.0 {
            return 0.0;
        }
        let end = self.depths[i + 1];
        ((view_depth - (end - band)) / band).clamp(0.0, 1.0)
    }
}
