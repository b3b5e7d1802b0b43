//! The report's pictures: heatmaps of the aliasing error, the three-panel shadow
//! masks, the colour legend, and their PNG encoding (see the parent module's docs
//! for the colour scale).

use std::path::Path;

use crate::EvalError;
use crate::mask::GBuffer;

/// An RGB image.
pub(super) struct Image {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

const BACKGROUND: [u8; 3] = [128, 128, 128];
const UNCOVERED: [u8; 3] = [48, 48, 48];
const ABOVE_SCALE: [u8; 3] = [220, 30, 30];

/// Viridis at 9 evenly spaced points (0, 1/8, ..., 1).
const VIRIDIS: [[u8; 3]; 9] = [
    [68, 1, 84],
    [71, 44, 122],
    [59, 81, 139],
    [44, 113, 142],
    [33, 144, 141],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

/// The heatmap colour of an aliasing error (see the module docs).
#[must_use]
pub fn heat_colour(m: f64) -> [u8; 3] {
    if m.is_nan() {
        return UNCOVERED;
    }
    if m > 10.0 {
        return ABOVE_SCALE;
    }
    let t = m.max(1.0).log10().clamp(0.0, 1.0) * 8.0;
    let i = (t.floor() as usize).min(7);
    let f = t - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    core::array::from_fn(|k| {
        (f64::from(a[k]) + (f64::from(b[k]) - f64::from(a[k])) * f).round() as u8
    })
}

pub(super) fn heatmap_image(w: u32, h: u32, gbuffer: &GBuffer, m: &[Option<f64>]) -> Image {
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for (s, e) in gbuffer.surfaces.iter().zip(m) {
        let c = match (s, e) {
            (None, _) => BACKGROUND,
            (Some(_), None) => UNCOVERED,
            (Some(_), Some(e)) => heat_colour(*e),
        };
        rgb.extend_from_slice(&c);
    }
    Image {
        width: w,
        height: h,
        rgb,
    }
}

/// Three panels: technique, ray-traced truth, differences (red: lit but should be in
/// shadow; blue: shadowed but should be lit), separated by 2-pixel white bars.
///
/// `truth` holds the measured pixels only (the misclassification's: visible and
/// front-lit); every other pixel is background grey in all three panels, so the
/// picture shows what the table counts. An uncovered measured pixel reads as lit,
/// as the table counts it.
pub(super) fn mask_image(
    w: u32,
    h: u32,
    technique: &[Option<bool>],
    truth: &[Option<bool>],
) -> Image {
    const LIT: [u8; 3] = [235, 225, 200];
    const SHADOW: [u8; 3] = [40, 50, 80];
    const GAP: u32 = 2;
    let width = 3 * w + 2 * GAP;
    let mut rgb = vec![255u8; width as usize * h as usize * 3];
    let class = |l: Option<bool>| match l {
        Some(true) => LIT,
        Some(false) => SHADOW,
        None => BACKGROUND,
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let (t, g) = (technique[i], truth[i]);
            let diff = match (g, t.unwrap_or(true)) {
                (None, _) => BACKGROUND,
                (Some(false), true) => [220, 40, 40],
                (Some(true), false) => [40, 90, 230],
                (Some(_), _) => [200, 200, 200],
            };
            // An uncovered visible pixel reads as lit, like the shader.
            let t_shown = if g.is_some() {
                class(Some(t.unwrap_or(true)))
            } else {
                BACKGROUND
            };
            for (panel, c) in [(0, t_shown), (1, class(g)), (2, diff)] {
                let px = panel * (w + GAP) + x;
                let k = (y * width + px) as usize * 3;
                rgb[k..k + 3].copy_from_slice(&c);
            }
        }
    }
    Image {
        width,
        height: h,
        rgb,
    }
}

pub(super) fn legend_image() -> Image {
    let (w, h) = (330u32, 20u32);
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for _ in 0..h {
        for x in 0..w {
            // 0..300: m from 1 to 10 (log); 300..330: above 10.
            let c = if x < 300 {
                heat_colour(10f64.powf(f64::from(x) / 299.0))
            } else {
                ABOVE_SCALE
            };
            rgb.extend_from_slice(&c);
        }
    }
    Image {
        width: w,
        height: h,
        rgb,
    }
}

/// Encodes `image` in memory, then writes the file in one call, so that every
/// failure (a full disk included) is reported rather than lost in a buffered
/// writer's drop.
pub(super) fn write_png(path: &Path, image: &Image) -> Result<(), EvalError> {
    let err = |source: std::io::Error| EvalError::Write {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, image.width, image.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder
            .write_header()
            .map_err(|e| err(std::io::Error::other(e)))?;
        writer
            .write_image_data(&image.rgb)
            .map_err(|e| err(std::io::Error::other(e)))?;
        writer.finish().map_err(|e| err(std::io::Error::other(e)))?;
    }
    std::fs::write(path, bytes).map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_shows_only_measured_pixels() {
        // Pixels: unmeasured (back-facing), wrongly shadowed, correctly lit,
        // uncovered but truly in shadow.
        let technique = [Some(false), Some(false), Some(true), None];
        let truth = [None, Some(true), Some(true), Some(false)];
        let image = mask_image(4, 1, &technique, &truth);
        let px = |panel: u32, x: u32| {
            let k = ((panel * (4 + 2) + x) * 3) as usize;
            [image.rgb[k], image.rgb[k + 1], image.rgb[k + 2]]
        };
        for panel in 0..3 {
            assert_eq!(px(panel, 0), BACKGROUND, "panel {panel}");
            assert_ne!(px(panel, 1), BACKGROUND, "panel {panel}");
        }
        assert_eq!(px(2, 1), [40, 90, 230], "shadowed but lit: blue");
        assert_eq!(px(2, 2), [200, 200, 200], "agreement");
        assert_eq!(px(2, 3), [220, 40, 40], "uncovered reads lit: red");
    }

    #[test]
    fn colour_scale_ends() {
        assert_eq!(heat_colour(0.5), VIRIDIS[0]);
        assert_eq!(heat_colour(1.0), VIRIDIS[0]);
        assert_eq!(heat_colour(10.0), VIRIDIS[8]);
        assert_eq!(heat_colour(10.5), ABOVE_SCALE);
        assert_eq!(heat_colour(f64::NAN), UNCOVERED);
        // Monotone in the green channel over the scale.
        let g: Vec<u8> = (0..=20)
            .map(|k| heat_colour(10f64.powf(f64::from(k) / 20.0))[1])
            .collect();
        assert!(g.windows(2).all(|w| w[0] <= w[1]));
    }
}
