//! Misclassification of a shadow map against the shadow volumes, per pixel.

use crate::render::{Image, MaskValue, ShadowMask};

/// How a shadow map's mask differs from the volumes' over the pixels both classify
/// (a pixel the map does not cover, or background in either, is not compared).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Misclassification {
    /// Pixels classified by both masks.
    pub compared: usize,
    /// Lit by the map, shadowed by the volumes.
    pub false_lit: usize,
    /// Shadowed by the map, lit by the volumes.
    pub false_shadowed: usize,
}

impl Misclassification {
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

/// Colours of the difference image.
const BACKGROUND: [u8; 4] = [0, 0, 0, 255];
const AGREE_LIT: [u8; 4] = [200, 200, 200, 255];
const AGREE_SHADOWED: [u8; 4] = [80, 80, 80, 255];
const FALSE_LIT: [u8; 4] = [230, 40, 40, 255];
const FALSE_SHADOWED: [u8; 4] = [40, 90, 230, 255];
const NOT_COMPARED: [u8; 4] = [120, 60, 120, 255];

/// Compares `map` (a technique's mask) with `volumes` (the truth) and draws the
/// differences: light grey lit in both, dark grey shadowed in both, red falsely lit,
/// blue falsely shadowed, purple a surface only one mask classifies, black
/// background. Masks of different sizes compare nothing (and draw all black).
#[must_use]
pub fn misclassification(map: &ShadowMask, volumes: &ShadowMask) -> (Misclassification, Image) {
    let (width, height) = (volumes.width, volumes.height);
    let mut counts = Misclassification::default();
    let mut rgba = Vec::with_capacity(volumes.values.len() * 4);
    let same_size = (map.width, map.height) == (width, height);
    for (i, truth) in volumes.values.iter().enumerate() {
        let test = if same_size {
            map.values[i]
        } else {
            MaskValue::Background
        };
        let color = match (test.lit(), truth.lit()) {
            (Some(a), Some(b)) => {
                counts.compared += 1;
                match (a, b) {
                    (true, true) => AGREE_LIT,
                    (false, false) => AGREE_SHADOWED,
                    (true, false) => {
                        counts.false_lit += 1;
                        FALSE_LIT
                    }
                    (false, true) => {
                        counts.false_shadowed += 1;
                        FALSE_SHADOWED
                    }
                }
            }
            (None, None) => BACKGROUND,
            _ if !same_size => BACKGROUND,
            _ => NOT_COMPARED,
        };
        rgba.extend_from_slice(&color);
    }
    (
        counts,
        Image {
            width,
            height,
            rgba,
        },
    )
}
