//! The f64 twin of `shaders/refine.wgsl`: a field texture refined in image space (`frame::refine`), the same
//! levels and decisions as the GPU's, each level's exact texels integrated on every core.

use rayon::prelude::*;

use crate::frame::refine::{Levels, forced_mask, is_forced, predict, window};

/// A texture refined: each texel's B and tint, and how many were integrated exactly.
pub struct Refined {
    pub values: Vec<[f64; 4]>,
    pub integrated: usize,
}

/// The `levels.resolution`-square texture whose texel `(x, y)` is `exact(x, y)` (B, then the tint), integrated
/// exactly where the refinement decides (`frame::refine`: the detail above `tolerance`, or `forced`, a
/// `forced_mask`), else predicted from the level above.
pub fn refine(
    levels: &Levels,
    tolerance: f64,
    forced: &[u32],
    exact: impl Fn(u32, u32) -> [f64; 4] + Sync,
) -> Refined {
    let w = levels.resolution as usize;
    let mut values = vec![[0.0; 4]; w * w];
    let mut detail = vec![0.0f64; w * w];
    let mut integrated = 0;
    for l in (0..=levels.coarsest).rev() {
        let texels: Vec<(u32, u32)> = levels.texels(l).collect();
        let at = |x: u32, y: u32| y as usize * w + x as usize;
        let mut listed = Vec::new();
        let mut predicted = Vec::new();
        for &(x, y) in &texels {
            if l == levels.coarsest {
                listed.push((x, y));
                continue;
            }
            let p = predict((x, y), l, w as u32, |x, y| values[at(x, y)]);
            let refined = (l + 1 == levels.coarsest && !levels.measured_top)
                || is_forced(forced, at(x, y))
                || window(levels, (x, y), l).any(|(nx, ny)| detail[at(nx, ny)] > tolerance);
            match p {
                Some(p) if !refined => predicted.push((at(x, y), p)),
                _ => listed.push((x, y)),
            }
        }
        for (i, p) in predicted {
            values[i] = p;
        }
        let exact: Vec<[f64; 4]> = listed.par_iter().map(|&(x, y)| exact(x, y)).collect();
        integrated += listed.len();
        // The detail of the texels integrated: how far the prediction from the level above was off.
        for (&(x, y), v) in listed.iter().zip(&exact) {
            values[at(x, y)] = *v;
        }
        if l > 0 && (l < levels.coarsest || levels.measured_top) {
            for &(x, y) in &listed {
                if let Some(p) = predict((x, y), l, w as u32, |x, y| values[at(x, y)]) {
                    let v = values[at(x, y)];
                    detail[at(x, y)] = (0..4).map(|c| (v[c] - p[c]).abs()).fold(0.0, f64::max);
                }
            }
        }
    }
    Refined { values, integrated }
}

/// `refine` over `levels` with the texels' `clips` (row-major, or none without objects) forcing the texels
/// near their edges.
pub fn refine_clipped(
    levels: &Levels,
    tolerance: f64,
    clips: Option<&[f32]>,
    exact: impl Fn(u32, u32) -> [f64; 4] + Sync,
) -> Refined {
    let forced = forced_mask(levels, clips);
    refine(levels, tolerance, &forced, exact)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth glow is predicted almost everywhere; a narrow one is integrated near its core; both within the
    /// tolerance of the function itself everywhere.
    #[test]
    fn refining_a_known_picture_stays_within_the_tolerance() {
        for (width, w) in [(40.0, 256u32), (3.0, 256), (1.5, 200)] {
            let f = move |x: u32, y: u32| {
                let (dx, dy) = (x as f64 - 101.3, y as f64 - 77.8);
                let b = 1.0 / (1.0 + (dx * dx + dy * dy) / (width * width));
                [b, 0.3 * b, -0.1 * b, 0.0]
            };
            let tolerance = 2.5e-5;
            let r = refine_clipped(&Levels::of(w), tolerance, None, f);
            let mut worst = 0.0f64;
            for y in 0..w {
                for x in 0..w {
                    let v = r.values[(y * w + x) as usize];
                    let e = f(x, y);
                    worst = (0..4).map(|c| (v[c] - e[c]).abs()).fold(worst, f64::max);
                }
            }
            let share = r.integrated as f64 / (w * w) as f64;
            assert!(
                worst <= tolerance,
                "width {width}: {worst:e} off, {share:.3} integrated"
            );
            assert!(share < 0.6, "width {width}: {share:.3} integrated");
        }
    }

    /// The moving frames' levels: a coarser start whose own detail decides the first level, at a looser
    /// threshold: fewer texels (3564 against 6306 here), still within a few times the threshold.
    #[test]
    fn a_coarse_start_measures_its_own_detail() {
        let w = 256u32;
        let f = |x: u32, y: u32| {
            let (dx, dy) = (x as f64 - 101.3, y as f64 - 77.8);
            let b = 1.0 / (1.0 + (dx * dx + dy * dy) / 64.0);
            [b, 0.0, 0.0, 0.0]
        };
        let levels = Levels::coarse(w, 16);
        assert_eq!((levels.coarsest, levels.measured_top), (4, true));
        let threshold = 1e-3;
        let r = refine_clipped(&levels, threshold, None, f);
        let worst = (0..w * w)
            .map(|k| (r.values[k as usize][0] - f(k % w, k / w)[0]).abs())
            .fold(0.0, f64::max);
        let share = r.integrated as f64 / (w * w) as f64;
        let whole = refine_clipped(&Levels::of(w), threshold, None, f).integrated;
        assert!(worst <= 4.0 * threshold, "{worst:e} off");
        assert!(
            4 * r.integrated < 3 * whole,
            "{} texels against {whole}",
            r.integrated
        );
        assert!(share < 0.1, "{share:.3} integrated");
    }
}
