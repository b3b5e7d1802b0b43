//! How a cube map's kept faces share the texel budget, and where each face lies in
//! the atlas that stores them.
//!
//! Equal sides give every kept face `floor(sqrt(budget / k))` texels per side, one
//! texture-array layer each (the atlas is then a column of equal tiles). Sides by need
//! give each face a side in proportion to the texel density it needs, so that the
//! predicted aliasing error is the same on every face:
//!
//! ```text
//! m_f = need_f / side_f          need_f: the 95th percentile of m over the face's
//!                                  rays for a face of one texel per side
//! side_f = k * max(need_f, MIN_SIDE_RATIO * max_g need_g)
//! ```
//!
//! with `k` the largest scale whose atlas fits the budget
//! ([`CubeMap::set_sizes_by_need_with_floor`] takes another floor than
//! [`MIN_SIDE_RATIO`], for needs measured on the surfaces the eye sees). The needs
//! come from
//! `shadowmap_frustum::predict_errors`: view rays stopped on the receivers' box, each
//! face measured as a mapping of its own (its window only). The faces are packed into
//! shelves (highest first, at the shelf width that gives the smallest atlas), and the
//! budget pays for the whole atlas, gaps included: a gap costs every face texels.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, DVec4, Mat4, Vec2};
use shadowmap_frustum::{
    Aabb, Camera, PredictOptions, PredictedError, ShadowMapping, ShadowSample, math, predict_errors,
};

use crate::cube::{CubeFace, CubeMap, CubeOptions};

/// How [`CubeMap::fit`](crate::CubeMap::fit) shares the texel budget between the
/// kept faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FaceSizes {
    /// Every kept face the same side, `floor(sqrt(budget / faces))`: one
    /// texture-array layer per face, what engines render.
    #[default]
    Equal,
    /// Sides in proportion to the texel density each face needs, predicted from
    /// the camera and the receivers' box (see the crate docs, "Cube maps"), packed
    /// into an atlas. Where the light is among the visible receivers every face is
    /// kept, and the faces toward the eye need several times the texels of the
    /// others.
    ByNeed,
}

/// No face's side below this fraction of the largest face's: caps what a face loses
/// when its need is misjudged (by the receivers' box, say).
pub const MIN_SIDE_RATIO: f64 = 0.25;

/// No face's map narrower along one axis than this fraction of the other.
pub const MIN_ASPECT: f64 = 0.125;

/// Smallest side of a face, in texels (as the umbrella's layers).
const MIN_SIDE: u32 = 4;

/// Largest atlas side, in texels.
const MAX_SIDE: u32 = shadowmap_frustum::MAX_RESOLUTION;

/// Rays of the need prediction (columns, rows).
const NEED_GRID: (u32, u32) = (24, 14);

/// One kept face as a mapping of its own: its window only, any layer number.
struct FaceWindow<'a> {
    face: &'a CubeFace,
    position: DVec3,
}

impl ShadowMapping for FaceWindow<'_> {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        self.face.sample(world - self.position, false, 0)
    }
}

/// The texel density each face needs: the 95th percentile of the predicted `m` on
/// its rays for a face of one texel per side; `None` where no ray meets the face's
/// window (or the prediction fails).
pub(crate) fn predicted_needs(
    faces: &[CubeFace],
    position: DVec3,
    camera: &Camera,
    receivers: &Aabb,
) -> ArrayVec<Option<f64>, 6> {
    let windows: ArrayVec<FaceWindow<'_>, 6> = faces
        .iter()
        .take(6)
        .map(|face| FaceWindow { face, position })
        .collect();
    let candidates: ArrayVec<(&dyn ShadowMapping, u32), 6> = windows
        .iter()
        .map(|w| (w as &dyn ShadowMapping, 1))
        .collect();
    let mut out = [None::<PredictedError>; 6];
    let options = PredictOptions::new().with_grid(NEED_GRID.0, NEED_GRID.1);
    let n = candidates.len();
    let ok = predict_errors(camera, receivers, &candidates, &options, &mut out[..n]).is_ok();
    out[..n]
        .iter()
        .map(|p| {
            p.filter(|_| ok)
                .map(|p| p.percentile)
                .filter(|m| m.is_finite() && *m > 0.0)
        })
        .collect()
}

/// A face map's width and height in texels.
pub(crate) type Size = [u32; 2];

/// Square maps of `count` faces sharing `budget` texels equally.
pub(crate) fn equal_sizes(count: usize, budget: u64) -> ArrayVec<Size, 6> {
    let per = budget / count.max(1) as u64;
    let side = (math::sqrt(per as f64) as u32).clamp(MIN_SIDE, MAX_SIDE);
    (0..count.min(6)).map(|_| [side, side]).collect()
}

/// Sizes in proportion to `needs` (per face the density needed along `u` and `v`;
/// a face without a need gets the smallest one allowed), at the largest scale whose
/// atlas fits `budget` (at least [`MIN_SIDE`] per axis).
///
/// A face's larger need is at least `min_side_ratio` (clamped to `[0, 1]`) times
/// the largest of all faces, and its smaller one at least [`MIN_ASPECT`] times its
/// larger one.
pub(crate) fn sizes_by_need(
    needs: &[Option<[f64; 2]>],
    budget: u64,
    min_side_ratio: f64,
) -> ArrayVec<Size, 6> {
    let valid = |n: &[f64; 2]| n.iter().all(|x| x.is_finite() && *x > 0.0);
    let top = needs
        .iter()
        .flatten()
        .filter(|n| valid(n))
        .map(|n| n[0].max(n[1]))
        .fold(0.0, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return equal_sizes(needs.len(), budget);
    }
    let floor = top * min_side_ratio.clamp(0.0, 1.0);
    let weights: ArrayVec<[f64; 2], 6> = needs
        .iter()
        .take(6)
        .map(|n| {
            let n = n.filter(valid).unwrap_or([floor, floor]);
            let m = n[0].max(n[1]);
            let larger = m.max(floor);
            n.map(|x| (x * larger / m).max(larger * MIN_ASPECT) / top)
        })
        .collect();
    let sizes_at = |k: f64| -> ArrayVec<Size, 6> {
        weights
            .iter()
            .map(|w| w.map(|x| ((k * x) as u32).clamp(MIN_SIDE, MAX_SIDE)))
            .collect()
    };
    let fits = |k: f64| pack(&sizes_at(k)).1.is_some_and(|a| area(a) <= budget);
    // The scale without gaps is an upper bound; bisect below it.
    let total: f64 = weights.iter().map(|w| w[0] * w[1]).sum();
    let (mut lo, mut hi) = (0.0, math::sqrt(budget as f64 / total) + 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    grown_into_gaps(sizes_at(lo), &weights, budget)
}

/// Most single-texel steps [`grown_into_gaps`] takes.
const GROWTH_STEPS: usize = 32;

/// `sizes` (scaled together from `weights` to the largest scale that fits) grown
/// one texel at a time into what the packing leaves: the axis of the largest
/// error (weight over side) of the face of the largest grows while the atlas stays
/// within `budget`, for at most [`GROWTH_STEPS`] steps. Four squares of needs 599, 463, 385 and 345 packed
/// into 135 x 120 texels leave 16% of it empty; grown, the face of the largest
/// need takes part of that.
fn grown_into_gaps(
    mut sizes: ArrayVec<Size, 6>,
    weights: &[[f64; 2]],
    budget: u64,
) -> ArrayVec<Size, 6> {
    let error = |size: Size, w: &[f64; 2], axis: usize| w[axis] / f64::from(size[axis].max(1));
    let mut stuck = [false; 6];
    for _ in 0..GROWTH_STEPS {
        let mut worst: Option<(f64, usize)> = None;
        for (f, (size, w)) in sizes.iter().zip(weights).enumerate() {
            let e = error(*size, w, 0).max(error(*size, w, 1));
            if !stuck[f] && worst.is_none_or(|(largest, _)| e > largest) {
                worst = Some((e, f));
            }
        }
        let Some((e, f)) = worst else { break };
        // Every axis at the face's error grows: both sides of a square of equal
        // needs (one side alone would not lower its error).
        let mut grown = sizes.clone();
        for axis in 0..2 {
            if error(sizes[f], &weights[f], axis) >= e * (1.0 - 1e-9) {
                grown[f][axis] = (grown[f][axis] + 1).min(MAX_SIDE);
            }
        }
        if pack(&grown).1.is_some_and(|a| area(a) <= budget) {
            sizes = grown;
        } else {
            stuck[f] = true;
        }
    }
    sizes
}

/// Texels of an atlas.
pub(crate) fn area(atlas: [u32; 2]) -> u64 {
    u64::from(atlas[0]) * u64::from(atlas[1])
}

/// Packing of the face maps, the highest first (ties: the wider, then face order):
/// on shelves, each as high as its first map, or on a skyline
/// ([`pack_skyline`]), at the width and by the packing whose atlas is the smallest
/// (ties: the narrowest, so equal squares make a column; then the shelves). The maps'
/// offsets in face order and the atlas size; `None` when the atlas would exceed the
/// largest texture side.
///
/// Every width is tried that matters: in a fixed order the shelves change only
/// where the width reaches the summed width of a run of consecutive maps, so the
/// smallest width of each packing is such a sum (at least the widest map), and
/// trying every such sum finds the smallest shelf atlas of any width (the skyline
/// is tried at the same widths). Two widths only
/// (the widest map, a square of the maps' area) leave gaps: maps of sides 84, 44,
/// 44, 31, 21, 21 make an atlas 84 wide with a 40-texel gap beside one of the 44s
/// (16,212 texels), where 88 packs both 44s on one shelf (13,992).
pub(crate) fn pack(sizes: &[Size]) -> (ArrayVec<[u32; 2], 6>, Option<[u32; 2]>) {
    let sizes = sizes.get(..6).unwrap_or(sizes);
    let order = shelf_order(sizes);
    let widest = sizes.iter().map(|s| s[0]).max().unwrap_or(0);
    // The sums of the runs of consecutive maps past the widest (21 at most).
    let mut widths: ArrayVec<u32, 22> = ArrayVec::new();
    widths.push(widest);
    for start in 0..order.len() {
        let mut width = 0u64;
        for &i in &order[start..] {
            width += u64::from(sizes[i][0]);
            if let Ok(w) = u32::try_from(width) {
                if w > widest && w <= MAX_SIDE {
                    let _ = widths.try_push(w);
                }
            }
        }
    }
    widths
        .iter()
        .flat_map(|&w| [pack_width(sizes, &order, w), pack_skyline(sizes, &order, w)])
        .min_by_key(|p| p.1.map_or((u64::MAX, u32::MAX), |a| (area(a), a[0])))
        .unwrap_or_else(|| pack_width(sizes, &order, widest))
}

/// Skyline packing of the maps in `order` into an atlas `width` texels wide: each
/// map at the lowest place on the outline of those before it (the leftmost of the
/// lowest), at the start of one of the outline's segments. Where a shelf is as high
/// as its first map and leaves a gap under the lower maps beside it, the skyline
/// puts a later map into that gap: maps of sides 75, 58, 48 and 43 pack into 133 x
/// 118 texels, where the best shelves take 133 x 123.
fn pack_skyline(
    sizes: &[Size],
    order: &[usize],
    width: u32,
) -> (ArrayVec<[u32; 2], 6>, Option<[u32; 2]>) {
    let width = u64::from(width);
    let mut offsets: ArrayVec<[u32; 2], 6> = (0..order.len()).map(|_| [0, 0]).collect();
    // The outline: segments (start, top) by increasing start, covering [0, width).
    let mut outline: ArrayVec<(u64, u64), 16> = ArrayVec::new();
    outline.push((0, 0));
    for &i in order {
        let [w, h] = sizes[i].map(u64::from);
        let mut lowest: Option<(u64, u64)> = None;
        for (k, &(x, _)) in outline.iter().enumerate() {
            if x + w > width {
                break;
            }
            let y = outline[k..]
                .iter()
                .take_while(|segment| segment.0 < x + w)
                .map(|segment| segment.1)
                .max()
                .unwrap_or(0);
            if lowest.is_none_or(|best| (y, x) < best) {
                lowest = Some((y, x));
            }
        }
        let Some((y, x)) = lowest else {
            return (offsets, None);
        };
        if let (Some(at), Ok(ox), Ok(oy)) = (offsets.get_mut(i), u32::try_from(x), u32::try_from(y))
        {
            *at = [ox, oy];
        }
        outline = raised(&outline, width, (x, x + w), y + h);
    }
    let height = outline.iter().map(|segment| segment.1).max().unwrap_or(0);
    let fits = height <= u64::from(MAX_SIDE) && width <= u64::from(MAX_SIDE);
    let atlas = fits.then_some([width as u32, height as u32]);
    (offsets, atlas)
}

/// The skyline `outline` (segments `(start, top)` over `[0, width)`) with `span`
/// raised to `top`.
fn raised(
    outline: &[(u64, u64)],
    width: u64,
    span: (u64, u64),
    top: u64,
) -> ArrayVec<(u64, u64), 16> {
    let mut next: ArrayVec<(u64, u64), 16> = ArrayVec::new();
    let mut placed = false;
    for (k, &(start, old)) in outline.iter().enumerate() {
        let end = outline.get(k + 1).map_or(width, |segment| segment.0);
        if end <= span.0 || start >= span.1 {
            if start >= span.1 && !placed {
                let _ = next.try_push((span.0, top));
                placed = true;
            }
            let _ = next.try_push((start, old));
            continue;
        }
        if start < span.0 {
            let _ = next.try_push((start, old));
        }
        if !placed {
            let _ = next.try_push((span.0, top));
            placed = true;
        }
        if end > span.1 {
            let _ = next.try_push((span.1, old));
        }
    }
    if !placed {
        let _ = next.try_push((span.0, top));
    }
    next
}

/// The order of the shelves: the highest map first (ties: the wider, then face
/// order).
fn shelf_order(sizes: &[Size]) -> ArrayVec<usize, 6> {
    let mut order: ArrayVec<usize, 6> = (0..sizes.len().min(6)).collect();
    order.sort_by(|a, b| {
        let (sa, sb) = (sizes[*a], sizes[*b]);
        sb[1].cmp(&sa[1]).then(sb[0].cmp(&sa[0])).then(a.cmp(b))
    });
    order
}

/// [`pack`] into shelves of width `width` (at least the widest map), the maps in
/// `order`.
fn pack_width(
    sizes: &[Size],
    order: &[usize],
    width: u32,
) -> (ArrayVec<[u32; 2], 6>, Option<[u32; 2]>) {
    let mut offsets: ArrayVec<[u32; 2], 6> = (0..order.len()).map(|_| [0, 0]).collect();
    let height = shelves(
        order,
        |i| sizes[i].map(u64::from),
        u64::from(width),
        |i, at| offsets[i] = at,
    );
    let fits = height <= u64::from(MAX_SIDE) && width <= MAX_SIDE;
    let atlas = fits.then_some([width, height as u32]);
    (offsets, atlas)
}

/// Shelf packing, the one the cube's faces and the tiled cube's tiles share: the
/// rectangles in `order` (highest first) left to right on shelves `width` texels
/// wide, a new shelf when the next does not fit, each shelf as high as its first;
/// `place(index, top-left corner)` for each. Returns the shelves' height.
pub(crate) fn shelves(
    order: &[usize],
    size: impl Fn(usize) -> [u64; 2],
    width: u64,
    mut place: impl FnMut(usize, [u32; 2]),
) -> u64 {
    let (mut x, mut y, mut shelf) = (0u64, 0u64, 0u64);
    for &i in order {
        let [w, h] = size(i);
        if x + w > width {
            y += shelf;
            (x, shelf) = (0, 0);
        }
        place(i, [x as u32, y.min(u64::from(u32::MAX)) as u32]);
        x += w;
        shelf = shelf.max(h);
    }
    y + shelf
}

impl CubeMap {
    /// Gives each kept face its size ([`CubeOptions::sizes`]) and its place in the
    /// atlas, with the needs predicted from the camera and the receivers' box (for
    /// [`FaceSizes::ByNeed`], and for every sizing when `predict` is set); returns
    /// the predicted error of the sized map: the largest of the faces' 95th
    /// percentiles of `m` ([`predicted_needs`] over the face's side), `None` without
    /// a prediction.
    pub(crate) fn share_budget(
        &mut self,
        camera: &Camera,
        receivers: &Aabb,
        options: &CubeOptions,
        predict: bool,
    ) -> Option<f64> {
        let budget = options.texel_budget;
        let needs = (predict || options.sizes == FaceSizes::ByNeed)
            .then(|| predicted_needs(&self.faces, self.position.as_dvec3(), camera, receivers));
        let sizes = match (&needs, options.sizes) {
            (Some(needs), FaceSizes::ByNeed) => {
                let needs: ArrayVec<Option<[f64; 2]>, 6> =
                    needs.iter().map(|n| n.map(|n| [n, n])).collect();
                sizes_by_need(&needs, budget, MIN_SIDE_RATIO)
            }
            _ => equal_sizes(self.faces.len(), budget),
        };
        self.set_sizes(&sizes);
        let needs = needs?;
        self.faces
            .iter()
            .zip(&needs)
            .map(|(f, n)| n.map(|n| n / f64::from(f.size[0].max(f.size[1]).max(1))))
            .try_fold(0.0_f64, |worst, m| m.map(|m| worst.max(m)))
    }

    /// Shares `budget` texels between the faces in proportion to `needs` (in face
    /// order: the texel density each face needs along its `u` and `v`, in any unit
    /// common to all; `None` for a face without an estimate) as
    /// [`FaceSizes::ByNeed`] does, and packs the atlas. For a renderer with a better
    /// estimate of the needs than the receivers' box (RTW's importance, say).
    pub fn set_sizes_by_need(&mut self, needs: &[Option<[f64; 2]>], budget: u64) {
        self.set_sizes_by_need_with_floor(needs, budget, MIN_SIDE_RATIO);
    }

    /// As [`set_sizes_by_need`](Self::set_sizes_by_need), with no face's side below
    /// `min_side_ratio` (clamped to `[0, 1]`) times the largest face's instead of
    /// [`MIN_SIDE_RATIO`]. That floor insures a face against a misjudged need;
    /// needs measured on the surfaces the eye sees can take a lower one, so that a
    /// face few pixels see does not keep a sixteenth of the largest face's texels.
    ///
    /// ```
    /// use glam::Vec3;
    /// use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds};
    /// use shadowmap_paraboloid::{CubeMap, CubeOptions, MIN_SIDE_RATIO};
    ///
    /// // A lamp in the middle of a room seen from one corner: every face is kept.
    /// let camera = Camera::look_to(
    ///     Vec3::new(-4.0, 1.5, 4.0),
    ///     Vec3::new(1.0, -0.2, -1.0),
    ///     Vec3::Y,
    ///     Projection::perspective(70f32.to_radians(), 1.5, 0.1, 30.0),
    /// )?;
    /// let light = Light::Point { position: Vec3::new(0.0, 1.5, 0.0), range: 20.0 };
    /// let room = Aabb::new(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 3.0, 5.0));
    /// let mut cube = CubeMap::fit(&light, &camera, None, &SceneBounds::new(room, room), &CubeOptions::default())?;
    /// // One face needs twenty times the others' density.
    /// let mut needs = vec![Some([1.0, 1.0]); cube.faces.len()];
    /// needs[0] = Some([20.0, 20.0]);
    /// cube.set_sizes_by_need(&needs, 1 << 16);
    /// let floored = cube.faces[1].size[0];
    /// assert!(floored as f64 >= 0.9 * MIN_SIDE_RATIO * cube.faces[0].size[0] as f64);
    /// cube.set_sizes_by_need_with_floor(&needs, 1 << 16, 0.0);
    /// assert!(cube.faces[1].size[0] < floored && cube.texels() <= 1 << 16);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn set_sizes_by_need_with_floor(
        &mut self,
        needs: &[Option<[f64; 2]>],
        budget: u64,
        min_side_ratio: f64,
    ) {
        let sizes = sizes_by_need(needs, budget, min_side_ratio);
        self.set_sizes(&sizes);
    }

    /// Sets the faces' map sizes (width, height; in face order, a missing one keeps
    /// its size) and packs them into the atlas: shelves of maps, the highest first.
    /// A packing past the largest texture side falls back to equal squares of the
    /// same total area.
    pub fn set_sizes(&mut self, sizes: &[[u32; 2]]) {
        for (f, s) in self.faces.iter_mut().zip(sizes) {
            f.size = s.map(|x| x.max(1));
        }
        let current: ArrayVec<Size, 6> = self.faces.iter().map(|f| f.size).collect();
        let (offsets, atlas) = match pack(&current) {
            (offsets, Some(atlas)) => (offsets, atlas),
            (_, None) => {
                let total: u64 = current.iter().map(|s| crate::cube_sizes::area(*s)).sum();
                let equal = equal_sizes(current.len(), total);
                for (f, s) in self.faces.iter_mut().zip(&equal) {
                    f.size = *s;
                }
                let (offsets, atlas) = pack(&equal);
                (offsets, atlas.unwrap_or([0, 0]))
            }
        };
        for (f, o) in self.faces.iter_mut().zip(offsets) {
            f.offset = o;
        }
        self.atlas = atlas;
    }

    /// Texels of the atlas (what the map costs, gaps between faces included).
    #[must_use]
    pub fn texels(&self) -> u64 {
        crate::cube_sizes::area(self.atlas)
    }

    /// The largest side of a kept face, in texels (0 without faces): the layer side
    /// of a texture array that stores each face in a corner of its layer
    /// ([`CubeFace::clip_from_world_in_layer`]).
    #[must_use]
    pub fn largest_side(&self) -> u32 {
        self.faces
            .iter()
            .map(|f| f.size[0].max(f.size[1]))
            .max()
            .unwrap_or(0)
    }

    /// Whether every kept face has the same square size: the faces can be the
    /// layers of a texture array (the atlas is a column of them).
    #[must_use]
    pub fn has_equal_faces(&self) -> bool {
        self.faces.iter().all(|f| f.size[0] == f.size[1])
            && self.faces.windows(2).all(|w| w[0].size == w[1].size)
    }

    /// A sample of [`ShadowMapping::map_point`] (a face's `uv`, its layer) in the
    /// atlas's texture coordinates, layer 0; `None` for a layer past the last face.
    ///
    /// ```text
    /// uv_atlas = (offset + uv * size) / atlas
    /// ```
    #[must_use]
    pub fn atlas_sample(&self, sample: ShadowSample) -> Option<ShadowSample> {
        let f = self.faces.get(sample.layer as usize)?;
        let pair = |p: [u32; 2]| DVec2::new(f64::from(p[0]), f64::from(p[1]));
        let uv = (pair(f.offset) + sample.uv * pair(f.size)) / pair(self.atlas);
        uv.is_finite().then_some(ShadowSample {
            uv,
            layer: 0,
            ..sample
        })
    }
}

impl CubeFace {
    /// The face's texels as a fraction of a square texture-array layer of
    /// `layer_side` texels per side (`size / layer_side`, at most 1 per axis): a
    /// backend that stores faces of different sizes as layers of the largest face's
    /// side draws each face into the layer's top-left corner of this extent and
    /// scales the face's `uv` by it when it reads the layer.
    #[must_use]
    pub fn uv_scale_in_layer(&self, layer_side: u32) -> Vec2 {
        let side = f64::from(layer_side.max(1));
        let scale = |texels: u32| (f64::from(texels) / side).clamp(f64::MIN_POSITIVE, 1.0);
        DVec2::new(scale(self.size[0]), scale(self.size[1])).as_vec2()
    }

    /// [`CubeFace::clip_from_world`] followed by the map of the face's window onto
    /// the top-left corner of a layer of `layer_side` texels
    /// ([`CubeFace::uv_scale_in_layer`]), so each face keeps its own texel density
    /// in a texture array of one side:
    ///
    /// ```text
    /// s = size / layer_side
    /// ndc'.x = s.x ndc.x + s.x - 1       uv'.x = s.x uv.x
    /// ndc'.y = s.y ndc.y + 1 - s.y       uv'.y = s.y uv.y
    /// ```
    ///
    /// Geometry beyond the window lands in the rest of the layer, where the face's
    /// own projection continues: a filter that reaches past the window's edge reads
    /// depths of the same projection, not of another face.
    #[must_use]
    pub fn clip_from_world_in_layer(&self, layer_side: u32) -> Mat4 {
        let s = self.uv_scale_in_layer(layer_side).as_dvec2();
        let corner_from_clip = DMat4::from_cols(
            DVec4::new(s.x, 0.0, 0.0, 0.0),
            DVec4::new(0.0, s.y, 0.0, 0.0),
            DVec4::Z,
            DVec4::new(s.x - 1.0, 1.0 - s.y, 0.0, 1.0),
        );
        (corner_from_clip * self.clip_from_world.as_dmat4()).as_mat4()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_sizes_make_a_column() {
        let sizes = equal_sizes(6, 1024 * 1024);
        assert_eq!(sizes.as_slice(), &[[418, 418]; 6]);
        let (offsets, atlas) = pack(&sizes);
        assert_eq!(atlas, Some([418, 6 * 418]));
        for (i, o) in offsets.iter().enumerate() {
            assert_eq!(*o, [0, 418 * i as u32]);
        }
    }

    /// Maps do not overlap and lie in the atlas.
    fn check_packing(sizes: &[Size]) {
        let (offsets, atlas) = pack(sizes);
        check_apart(sizes, &offsets, atlas.unwrap());
    }

    /// Every map of `sizes` at `offsets` lies inside `atlas`, apart from the others.
    fn check_apart(sizes: &[Size], offsets: &[[u32; 2]], atlas: [u32; 2]) {
        for (i, (a, sa)) in offsets.iter().zip(sizes).enumerate() {
            assert!(
                a[0] + sa[0] <= atlas[0] && a[1] + sa[1] <= atlas[1],
                "{sizes:?}"
            );
            for (b, sb) in offsets.iter().zip(sizes).skip(i + 1) {
                let apart = a[0] + sa[0] <= b[0]
                    || b[0] + sb[0] <= a[0]
                    || a[1] + sa[1] <= b[1]
                    || b[1] + sb[1] <= a[1];
                assert!(apart, "{sizes:?}: {offsets:?}");
            }
        }
    }

    #[test]
    fn shelves_hold_every_map_apart() {
        for sizes in [
            vec![[300, 300], [100, 100], [100, 100], [100, 100], [100, 100]],
            vec![[10, 10], [200, 50], [7, 90], [199, 199], [64, 64], [64, 8]],
            vec![[5, 5]],
            vec![[90, 30], [90, 90], [30, 30], [30, 90], [30, 30], [30, 30]],
        ] {
            check_packing(&sizes);
        }
    }

    /// The atlas is the smallest of any shelf width: a face beside the largest
    /// one's shelf, or two on one shelf, rather than a gap on every shelf of an
    /// atlas as wide as the largest face (the sides of the faces of a seed-5 sweep
    /// terrain: 84 wide, 16,212 texels; 88 wide, 13,992).
    /// Face sizes of mixed shapes the packing tests share.
    const MIXED: [&[Size]; 3] = [
        &[[83, 83], [20, 20], [20, 20], [20, 20], [26, 26], [65, 65]],
        &[[10, 10], [200, 50], [7, 90], [199, 199], [64, 64], [64, 8]],
        &[[90, 30], [90, 90], [30, 30], [30, 90], [30, 30], [30, 30]],
    ];

    #[test]
    fn the_atlas_is_the_smallest_of_any_shelf_width() {
        let terrain = [[31, 31], [84, 84], [21, 21], [21, 21], [44, 44], [44, 44]];
        let (_, atlas) = pack(&terrain);
        assert_eq!(atlas, Some([88, 159]));
        check_packing(&terrain);
        for sizes in [&terrain[..], &[[5, 5]]].into_iter().chain(MIXED) {
            let best = area(pack(sizes).1.unwrap());
            let order = shelf_order(sizes);
            let widest = sizes.iter().map(|s| s[0]).max().unwrap();
            let sum: u32 = sizes.iter().map(|s| s[0]).sum();
            for width in widest..=sum {
                let texels = area(pack_width(sizes, &order, width).1.unwrap());
                assert!(best <= texels, "{sizes:?}: {best} > {texels} at {width}");
            }
        }
    }

    /// The skyline fills the gap a shelf leaves under its lower maps, and holds
    /// every map apart inside the atlas.
    #[test]
    fn the_skyline_fills_the_gaps_of_the_shelves() {
        let city = [[75, 75], [58, 58], [4, 4], [4, 4], [43, 43], [48, 48]];
        let order = shelf_order(&city);
        let shelves = (75..=232)
            .filter_map(|w| pack_width(&city, &order, w).1)
            .map(area)
            .min()
            .unwrap();
        assert_eq!(shelves, 133 * 123);
        let (_, atlas) = pack(&city);
        assert!(area(atlas.unwrap()) <= 133 * 118, "{atlas:?}");
        check_packing(&city);
        for sizes in [&city[..]].into_iter().chain(MIXED) {
            let order = shelf_order(sizes);
            for width in [200, 250, 300, 400] {
                if let (offsets, Some(atlas)) = pack_skyline(sizes, &order, width) {
                    check_apart(sizes, &offsets, atlas);
                }
            }
        }
    }

    #[test]
    fn sizes_follow_the_needs_within_the_budget() {
        let budget = 1024 * 1024;
        let needs = [
            Some([3.0, 3.0]),
            Some([1.0, 1.0]),
            Some([2.0, 1.0]),
            None,
            Some([1.0, 1.0]),
            Some([0.01, 0.01]),
        ];
        let sizes = sizes_by_need(&needs, budget, MIN_SIDE_RATIO);
        let (_, atlas) = pack(&sizes);
        let texels = area(atlas.unwrap());
        assert!(texels <= budget && texels > budget * 8 / 10, "{texels}");
        // Three times the need, three times the side (up to rounding); twice the
        // need along u, twice the width; the face without a need and the one below
        // the floor get at least the floor (and what the packing leaves, grown
        // into: less than the faces with a need).
        assert!((f64::from(sizes[0][0]) / f64::from(sizes[1][0]) - 3.0).abs() < 0.05);
        assert!((f64::from(sizes[2][0]) / f64::from(sizes[2][1]) - 2.0).abs() < 0.05);
        let floor = (f64::from(sizes[0][0]) * MIN_SIDE_RATIO) as u32;
        for small in [sizes[3][0], sizes[5][1]] {
            assert!(small + 1 >= floor && small < sizes[1][0], "{sizes:?}");
        }
        check_packing(&sizes);
        // An extreme aspect is limited.
        let thin = sizes_by_need(&[Some([1.0, 1e-4])], budget, MIN_SIDE_RATIO);
        assert!((f64::from(thin[0][1]) / f64::from(thin[0][0]) - MIN_ASPECT).abs() < 0.01);
        // Equal needs: equal squares, as `equal_sizes` (up to the last texel).
        let same = sizes_by_need(&[Some([2.0, 2.0]); 6], budget, MIN_SIDE_RATIO);
        assert!(
            same.iter().flatten().all(|s| s.abs_diff(418) <= 1),
            "{same:?}"
        );
        // No need at all: equal sizes.
        assert_eq!(
            sizes_by_need(&[None, None], budget, MIN_SIDE_RATIO),
            equal_sizes(2, budget)
        );
    }
}
