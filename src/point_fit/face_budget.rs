//! How the faces of a cube map share a texel budget among the eye samples they
//! store: the least texels that serve all but `1 - NEED_PERCENTILE` of the samples
//! at their need, found exactly over the faces (a dynamic program over the faces
//! and the number of samples each gives up).

use alloc::vec::Vec;

use arrayvec::ArrayVec;
use shadowmap_frustum::math::{powf, sqrt};
use shadowmap_paraboloid::{CubeMap, MIN_SIDE_RATIO};
use shadowmap_rtw::{AxisNeed, WarpMaps};

use super::{GIVEN_UP_FLOOR, MEASURED_MIN_SIDE_RATIO, NEED_PERCENTILE};
use crate::sample_error::{MAX_SAMPLES, percentile_rank};

/// Most samples the faces give up together: their share of [`MAX_SAMPLES`].
const MAX_FACE_DROPS: usize = MAX_SAMPLES / 20;

/// Width over height of the face shapes [`face_shapes`] tries: `2^(i/4)` from an
/// eighth to eight, the range of shapes the cube's packing keeps
/// ([`shadowmap_paraboloid::MIN_ASPECT`]).
const SHAPE_STEPS: i32 = 12;

/// How many of `len` samples may be given up.
fn drops_of(len: usize) -> usize {
    (((1.0 - NEED_PERCENTILE) * len as f64) as usize).min(MAX_FACE_DROPS)
}

/// The [`NEED_PERCENTILE`] of `values` (reordered), 0 when empty.
fn common_need(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let rank = percentile_rank(values.len(), NEED_PERCENTILE);
    *values.select_nth_unstable_by(rank, f64::total_cmp).1
}

/// A face's density with its `k` largest needs given up, from `need(i)`, its
/// `i`-th largest need (at least up to its `k + 1` largest; `None` past its last):
/// the next need, but a given up sample still gets [`GIVEN_UP_FLOOR`] of its need,
/// or of the `common` need if that is less. 0 without samples.
fn density_after(need: impl Fn(usize) -> Option<f64>, k: usize, common: f64) -> f64 {
    need(0).map_or(0.0, |top| {
        let floor = GIVEN_UP_FLOOR * top.min(common);
        need(k).unwrap_or(0.0).max(floor)
    })
}

/// How many samples each face gives up so that the faces' texels,
/// `texels(face, k)` with `k` given up, are least in total, giving up at most
/// `drops` (at most [`MAX_FACE_DROPS`]) and at most `len(face)` of a face's.
fn least_texels_drops(
    faces: usize,
    drops: usize,
    len: impl Fn(usize) -> usize,
    texels: impl Fn(usize, usize) -> f64,
) -> ArrayVec<usize, 6> {
    let drops = drops.min(MAX_FACE_DROPS);
    // least[j]: the least texels of the faces so far giving up at most `j`
    // samples; given[f][j]: how many of them face `f` gives up there.
    let mut least = [0.0f64; MAX_FACE_DROPS + 1];
    let mut given = [[0u16; MAX_FACE_DROPS + 1]; 6];
    for (face, choice) in given.iter_mut().enumerate().take(faces.min(6)) {
        let mut next = [f64::INFINITY; MAX_FACE_DROPS + 1];
        for j in 0..=drops {
            for k in 0..=j.min(len(face)) {
                let total = least[j - k] + texels(face, k);
                if total < next[j] {
                    next[j] = total;
                    choice[j] = u16::try_from(k).unwrap_or(u16::MAX);
                }
            }
        }
        least = next;
    }
    let mut left = drops;
    let mut out: ArrayVec<usize, 6> = (0..faces.min(6)).map(|_| 0).collect();
    for (choice, k) in given.iter().zip(out.iter_mut()).rev() {
        *k = usize::from(choice[left]);
        left -= (*k).min(left);
    }
    out
}

/// The samples of `needs` (sorted by face) each face stores.
fn by_face<T>(needs: &[(usize, T)], faces: usize) -> ArrayVec<&[(usize, T)], 6> {
    (0..faces.min(6))
        .map(|f| {
            let start = needs.partition_point(|n| n.0 < f);
            let end = needs.partition_point(|n| n.0 <= f);
            needs.get(start..end).unwrap_or(&[])
        })
        .collect()
}

/// Each face's density (texels per unit of face `uv`) from the `(face, need)` of
/// every sample (reordered): the least texels (the sum of the squared densities)
/// that serve all but `1 - NEED_PERCENTILE` of the samples at their need, a face's
/// samples given up from its largest need down, each given up sample still served
/// at [`GIVEN_UP_FLOOR`]. With six faces the least is found exactly, not greedily:
/// a face whose largest needs are many and alike saves nothing until all of them
/// are given up, which a greedy choice of the largest saving never reaches (over
/// wooded terrain it gave up the samples of the face the most pixels see and left
/// the others' tops: 1.16 times the texels of equal per-face percentiles).
pub(super) fn face_densities(needs: &mut [(usize, f64)], faces: usize) -> ArrayVec<f64, 6> {
    // No allocation: the focused cube maps size their faces this way every frame.
    let common = if needs.is_empty() {
        0.0
    } else {
        let rank = percentile_rank(needs.len(), NEED_PERCENTILE);
        needs
            .select_nth_unstable_by(rank, |a, b| a.1.total_cmp(&b.1))
            .1
            .1
    };
    needs.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
    let faces_needs = by_face(needs, faces);
    let density = |f: usize, k: usize| {
        let face = faces_needs.get(f).copied().unwrap_or(&[]);
        density_after(|i| face.get(i).map(|n| n.1), k, common)
    };
    let given = least_texels_drops(
        faces_needs.len(),
        drops_of(needs.len()),
        |f| faces_needs[f].len(),
        |f, k| density(f, k).powi(2),
    );
    given
        .iter()
        .enumerate()
        .map(|(f, &k)| density(f, k))
        .collect()
}

/// One face's best shape for each number of samples given up: its texels, its
/// width over height and its density (texels per unit of face `uv`, the geometric
/// mean of its sides').
#[derive(Clone, Copy)]
struct Shape {
    texels: f64,
    aspect: f64,
    density: f64,
}

/// Each face's width and height in texels per unit of face `uv` from the
/// `(face, [u need, v need])` of every sample (reordered): as [`face_densities`],
/// the least texels that serve all but `1 - NEED_PERCENTILE` of the samples at
/// both their needs, each face's shape (width over height) chosen with them among
/// the shapes from an eighth to eight. A sample's need on a face of shape `a` and
/// unit area is the larger of `u / sqrt(a)` and `v sqrt(a)`. `None` for a face
/// without samples.
///
/// Shaping each face by the ratio of its `u` and `v` needs' percentiles instead
/// misjudges a face whose samples need much along one axis or the other but not
/// both: over a city block it made a face tall where its samples were served best
/// by a wide one, 1.8 times the error of the sizing before it (`compare --seed 52
/// --sweep 64`, random_city_block_044).
pub(super) fn face_shapes(
    needs: &mut [(usize, [f64; 2])],
    faces: usize,
) -> ArrayVec<Option<[f64; 2]>, 6> {
    let mut all: Vec<f64> = needs.iter().map(|n| n.1[0].max(n.1[1])).collect();
    let common = common_need(&mut all);
    needs.sort_unstable_by_key(|n| n.0);
    let drops = drops_of(needs.len());
    let faces_needs = by_face(needs, faces);
    let mut best = Vec::with_capacity(faces_needs.len());
    let mut descending: Vec<f64> = Vec::new();
    for face in &faces_needs {
        let mut shapes = [Shape {
            texels: f64::INFINITY,
            aspect: 1.0,
            density: 0.0,
        }; MAX_FACE_DROPS + 1];
        for step in -SHAPE_STEPS..=SHAPE_STEPS {
            let aspect = powf(2.0, f64::from(step) / 4.0);
            let root = sqrt(aspect);
            descending.clear();
            descending.extend(face.iter().map(|n| (n.1[0] / root).max(n.1[1] * root)));
            largest_first(&mut descending, drops + 1);
            for (k, shape) in shapes
                .iter_mut()
                .enumerate()
                .take(drops.min(face.len()) + 1)
            {
                let density = density_after(|i| descending.get(i).copied(), k, common);
                if density * density < shape.texels {
                    *shape = Shape {
                        texels: density * density,
                        aspect,
                        density,
                    };
                }
            }
        }
        best.push(shapes);
    }
    let given = least_texels_drops(
        faces_needs.len(),
        drops,
        |f| faces_needs[f].len(),
        |f, k| best[f][k].texels,
    );
    given
        .iter()
        .zip(&best)
        .map(|(&k, shapes)| {
            let s = shapes[k];
            (s.density > 0.0).then(|| [s.density * sqrt(s.aspect), s.density / sqrt(s.aspect)])
        })
        .collect()
}

/// What RTW over the cube faces sizes its faces by, face by face: the needs along
/// `u` and `v` each front-lit sample keeps after its face's warp (every
/// `stride`-th of them, at most [`MAX_SAMPLES`]), and each face's percentiles of
/// those needs over all its samples and over its front-lit samples kept.
pub(super) struct FaceBudgetNeeds {
    /// `(face, [u need, v need])` of the front-lit samples kept.
    lit: Vec<(usize, [f64; 2])>,
    lit_equal: ArrayVec<Option<[f64; 2]>, 6>,
    all_equal: ArrayVec<Option<[f64; 2]>, 6>,
    stride: usize,
    lit_seen: usize,
    /// Room for a face's needs and for their percentiles.
    face_left: Vec<([f64; 2], bool)>,
    scratch: Vec<f64>,
}

impl FaceBudgetNeeds {
    /// Room for the faces of a frame with `lit_total` front-lit samples.
    pub(super) fn new(lit_total: usize) -> Self {
        Self {
            lit: Vec::with_capacity(lit_total.min(MAX_SAMPLES)),
            lit_equal: ArrayVec::new(),
            all_equal: ArrayVec::new(),
            stride: lit_total.div_ceil(MAX_SAMPLES).max(1),
            lit_seen: 0,
            face_left: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Adds the next face (`face`, in order): its `warps` and its samples' `needs`,
    /// each front-lit where `lit` says so. At most six faces.
    pub(super) fn add_face(
        &mut self,
        face: usize,
        warps: &WarpMaps,
        needs: &[AxisNeed],
        lit: &[bool],
    ) {
        if self.all_equal.is_full() {
            return;
        }
        self.face_left.clear();
        self.face_left.extend(
            needs
                .iter()
                .zip(lit)
                .map(|(need, lit)| (left_after_warp(warps, need), *lit))
                .filter(|(x, _)| x.iter().all(|x| x.is_finite() && *x > 0.0)),
        );
        let all = axis_percentiles(&self.face_left.iter().map(|x| x.0), &mut self.scratch);
        self.all_equal.push(all);
        let start = self.lit.len();
        for (x, _) in self.face_left.iter().filter(|x| x.1) {
            if self.lit_seen % self.stride == 0 {
                self.lit.push((face, *x));
            }
            self.lit_seen += 1;
        }
        let kept = self.lit.get(start..).unwrap_or(&[]).iter().map(|x| x.1);
        let of_lit = axis_percentiles(&kept, &mut self.scratch);
        self.lit_equal.push(of_lit);
    }

    /// Sizes the faces of `cube` within `budget` ([`size_for_lit`]) by the least
    /// texels' shapes ([`face_shapes`]), by equal error per face over the front-lit
    /// samples (both floored at [`MEASURED_MIN_SIDE_RATIO`]), or by equal error per
    /// face over all samples (floored at [`MIN_SIDE_RATIO`]).
    pub(super) fn size(mut self, cube: &mut CubeMap, budget: u64) {
        let shaped = face_shapes(&mut self.lit, cube.faces.len());
        let candidates = [
            (&shaped[..], MEASURED_MIN_SIDE_RATIO),
            (&self.lit_equal[..], MEASURED_MIN_SIDE_RATIO),
            (&self.all_equal[..], MIN_SIDE_RATIO),
        ];
        size_for_lit(cube, &candidates, &self.lit, budget);
    }
}

/// A sample's needs along its face's `u` and `v` left after the warp's
/// magnification there: the error each axis keeps on a map of one texel per side.
fn left_after_warp(warps: &WarpMaps, need: &AxisNeed) -> [f64; 2] {
    let m = warps.magnification(need.uv);
    [need.u / m.x, need.v / m.y]
}

/// The [`NEED_PERCENTILE`]s of the needs along `u` and along `v` of `needs`,
/// with `scratch` for room; `None` without needs.
pub(super) fn axis_percentiles(
    needs: &(impl Iterator<Item = [f64; 2]> + Clone),
    scratch: &mut Vec<f64>,
) -> Option<[f64; 2]> {
    let mut axis = |i: usize| {
        scratch.clear();
        scratch.extend(needs.clone().map(|n| n[i]));
        (!scratch.is_empty()).then(|| common_need(scratch))
    };
    Some([axis(0)?, axis(1)?])
}

/// The [`NEED_PERCENTILE`] of the error the faces of `cube` leave the samples of
/// `needs` (`(face, [u need, v need])`): the larger of `u / width` and
/// `v / height`. `None` without samples.
fn predicted_error(cube: &CubeMap, needs: &[(usize, [f64; 2])]) -> Option<f64> {
    let mut errors: Vec<f64> = needs
        .iter()
        .filter_map(|(f, n)| {
            let size = cube.faces.get(*f)?.size.map(|s| f64::from(s.max(1)));
            Some((n[0] / size[0]).max(n[1] / size[1]))
        })
        .collect();
    (!errors.is_empty()).then(|| common_need(&mut errors))
}

/// Sizes the faces of `cube` within `budget` by the candidate needs (each with its
/// floor, [`CubeMap::set_sizes_by_need_with_floor`]) whose packed sizes leave the
/// samples of `needs` (`(face, [u need, v need])`) the least
/// [`predicted_error`]; the first candidate on ties and without samples. The
/// atlas packs the faces' shapes on shelves, and the least texels do not always
/// pack into the least error: a wide face beside tall ones left a third of the
/// atlas empty over a city block, 1.2 times the error of sizes for equal error
/// per face.
pub(super) fn size_for_lit(
    cube: &mut CubeMap,
    candidates: &[(&[Option<[f64; 2]>], f64)],
    needs: &[(usize, [f64; 2])],
    budget: u64,
) {
    let mut best: Option<(f64, CubeMap)> = None;
    for (face_needs, floor) in candidates {
        let mut sized = cube.clone();
        sized.set_sizes_by_need_with_floor(face_needs, budget, *floor);
        let error = predicted_error(&sized, needs).unwrap_or(f64::INFINITY);
        if best.as_ref().is_none_or(|(e, _)| error < *e) {
            best = Some((error, sized));
        }
    }
    if let Some((_, sized)) = best {
        *cube = sized;
    }
}

/// Puts the `count` largest of `values` first, in decreasing order (the rest
/// after them in any order).
fn largest_first(values: &mut [f64], count: usize) {
    let count = count.min(values.len());
    if count == 0 {
        return;
    }
    if count < values.len() {
        values.select_nth_unstable_by(count - 1, |a, b| b.total_cmp(a));
    }
    values[..count].sort_unstable_by(|a, b| b.total_cmp(a));
}

#[cfg(test)]
mod tests;
