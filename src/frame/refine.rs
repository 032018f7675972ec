//! Refinement in image space: which texels of a frame's field are integrated exactly and which are predicted
//! from coarser ones, the plan both twins follow (`shaders/refine.wgsl` on the GPU, `reference::refine` in f64).
//!
//! The field texture is built in levels, coarse to fine. Level `L` (`Levels::coarsest`), the texels on a grid
//! of stride `2^L`, is integrated exactly. Each finer level `l` adds the texels of stride `s = 2^l` that lie
//! between the nodes of stride `2s`: each is first predicted from those nodes by cubic interpolation
//! (Catmull-Rom's weights at the midpoint, `-1 9 9 -1` / 16, shifted to one side near the borders), then
//! integrated exactly where
//! - the level is the first below the coarsest (nothing is known of the detail yet), or
//! - a node of stride `2s` within `3s` of it, introduced at level `l + 1`, showed a **detail** (its exact value
//!   minus its prediction, the largest over B and the tint) above the refinement's tolerance, or
//! - it is **forced** (`forced_mask`): on the texture's border, where no cubic stencil fits, or where an edge of
//!   the clips (an object's silhouette, a crease, where a ray starts or stops crossing a translucent object: the
//!   clips of the exit field) lies within `3s` of it, since the field is not smooth across one whatever the
//!   prediction says.
//!
//! Down to single texels at cores: the work follows the picture's detail, not its area. The refinement's
//! tolerance is `SHARE` of the scene's (`Refine::of`): a texel kept as predicted lies within it of the texel
//! integrated exactly (tests/refine.rs holds every shipped scene to that, on both twins).

/// The share of the scene's tolerance the refinement may spend: its detail threshold.
pub const SHARE: f64 = 0.125;

/// How a frame's field is integrated: every texel exactly, or refined in image space within a tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refine {
    /// Every texel integrated exactly (the reference, and jittered scenes, whose frames are averaged).
    EveryTexel,
    /// Texels predicted where the detail stays within this (absolute, on B and the tint), integrated elsewhere.
    Within(f64),
    /// The viewer's moving frames: from a coarsest grid of about `side` texels a side, whose own detail decides
    /// the first level too (`Levels::coarse`), texels predicted where the detail stays within `threshold`.
    Coarse { threshold: f64, side: u32 },
}

impl Refine {
    /// The refinement a scene's integration asks for: `SHARE` of its tolerance; every texel where the samples
    /// are jittered (the noise is averaged over frames, not predicted).
    pub fn of(integration: &crate::integrate::Integration) -> Self {
        if integration.jitter.is_some() {
            Refine::EveryTexel
        } else {
            Refine::Within(SHARE * integration.tolerance)
        }
    }

    /// The detail threshold, where refining.
    pub fn tolerance(self) -> Option<f64> {
        match self {
            Refine::EveryTexel => None,
            Refine::Within(t) | Refine::Coarse { threshold: t, .. } => Some(t),
        }
    }

    /// The levels of a `resolution`-square texture refined so; `None` where every texel is integrated (or the
    /// texture is too small to have a level below its coarsest).
    pub fn levels(self, resolution: u32) -> Option<Levels> {
        let levels = match self {
            Refine::EveryTexel => return None,
            Refine::Within(_) => Levels::of(resolution),
            Refine::Coarse { side, .. } => Levels::coarse(resolution, side),
        };
        (levels.coarsest > 0).then_some(levels)
    }
}

/// The levels of a `resolution` x `resolution` texture: the coarsest grid's stride is about a 32nd of the side,
/// at most 16 texels (a source's core finer than that could fall between two nodes of the first detail test).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Levels {
    pub resolution: u32,
    /// L: the coarsest level, of stride `2^L`.
    pub coarsest: u32,
    /// Whether the coarsest level's own detail (each of its texels predicted from the grid of stride `2^(L+1)`)
    /// decides the level below it, rather than that level being integrated whole: fewer texels, a coarser first
    /// test (the viewer's moving frames).
    pub measured_top: bool,
}

impl Levels {
    pub fn of(resolution: u32) -> Self {
        let mut coarsest = 0;
        while coarsest < 4 && (2u64 << coarsest) * 32 <= resolution as u64 {
            coarsest += 1;
        }
        Self {
            resolution,
            coarsest,
            measured_top: false,
        }
    }

    /// The levels of the viewer's moving frames: a coarsest grid of about `side` texels a side (its stride the
    /// largest power of two within `resolution / side`), its own detail measured.
    pub fn coarse(resolution: u32, side: u32) -> Self {
        let stride = (resolution / side.max(1)).max(1);
        Self {
            resolution,
            coarsest: 31 - stride.leading_zeros(),
            measured_top: true,
        }
    }

    /// The level texel `(x, y)` is introduced at: the coarsest where both are multiples of its stride.
    pub fn level_of(&self, x: u32, y: u32) -> u32 {
        (x | y).trailing_zeros().min(self.coarsest)
    }

    /// The texels of level `l`, row by row.
    pub fn texels(&self, l: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        let s = 1usize << l;
        let w = self.resolution;
        (0..w)
            .step_by(s)
            .flat_map(move |y| (0..w).step_by(s).map(move |x| (x, y)))
            .filter(move |&(x, y)| self.level_of(x, y) == l)
    }
}

/// Where a texel lies along one axis of the grid of stride `2s` it is predicted from: on a node, or between two,
/// with the four nodes of its cubic stencil and their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis {
    On(u32),
    Between([u32; 4], [f64; 4]),
}

/// Catmull-Rom at the midpoint of the middle nodes, and the cubic through four nodes shifted one to the right
/// (left border) or to the left (right border), at the same point.
pub const CENTERED: [f64; 4] = [-1.0 / 16.0, 9.0 / 16.0, 9.0 / 16.0, -1.0 / 16.0];
pub const SHIFTED_RIGHT: [f64; 4] = [5.0 / 16.0, 15.0 / 16.0, -5.0 / 16.0, 1.0 / 16.0];
pub const SHIFTED_LEFT: [f64; 4] = [1.0 / 16.0, -5.0 / 16.0, 15.0 / 16.0, 5.0 / 16.0];

/// Coordinate `x` of a texel of level `l` (stride `s = 2^l`) on a side of `w` texels: on a node of stride `2s`,
/// or between two with its stencil; `None` where no stencil of four nodes fits inside the texture.
pub fn axis(x: u32, s: u32, w: u32) -> Option<Axis> {
    if x % (2 * s) == 0 {
        return Some(Axis::On(x));
    }
    let (x, s, last) = (x as i64, s as i64, w as i64 - 1);
    if x + s > last {
        return None;
    }
    let nodes = |first: i64| std::array::from_fn(|k| (first + 2 * s * k as i64) as u32);
    if x - 3 * s >= 0 && x + 3 * s <= last {
        Some(Axis::Between(nodes(x - 3 * s), CENTERED))
    } else if x - s >= 0 && x + 5 * s <= last {
        Some(Axis::Between(nodes(x - s), SHIFTED_RIGHT))
    } else if x - 5 * s >= 0 {
        Some(Axis::Between(nodes(x - 5 * s), SHIFTED_LEFT))
    } else {
        None
    }
}

/// The prediction of texel `(x, y)` of level `l` from the nodes of stride `2s` (`value` reads a node), or `None`
/// where no stencil fits.
pub fn predict<const N: usize>(
    (x, y): (u32, u32),
    l: u32,
    w: u32,
    value: impl Fn(u32, u32) -> [f64; N],
) -> Option<[f64; N]> {
    let s = 1 << l;
    let expand = |a: Axis| match a {
        Axis::On(x) => ([x; 4], [1.0, 0.0, 0.0, 0.0]),
        Axis::Between(n, w) => (n, w),
    };
    let (xs, wx) = expand(axis(x, s, w)?);
    let (ys, wy) = expand(axis(y, s, w)?);
    let mut sum = [0.0; N];
    for b in 0..4 {
        if wy[b] == 0.0 {
            continue;
        }
        for a in 0..4 {
            if wx[a] == 0.0 {
                continue;
            }
            let v = value(xs[a], ys[b]);
            (0..N).for_each(|c| sum[c] += wx[a] * wy[b] * v[c]);
        }
    }
    Some(sum)
}

/// The nodes whose detail decides texel `(x, y)` of level `l`: those of stride `2s` within `3s` of it on both
/// axes that were introduced at level `l + 1` (the older ones' detail was measured at a coarser scale).
pub fn window(
    levels: &Levels,
    (x, y): (u32, u32),
    l: u32,
) -> impl Iterator<Item = (u32, u32)> + '_ {
    let s = 1i64 << l;
    let w = levels.resolution as i64;
    let near = move |c: u32| {
        let c = c as i64;
        let first = if c % (2 * s) == 0 {
            c - 2 * s
        } else {
            c - 3 * s
        };
        (0..4)
            .map(move |k| first + 2 * s * k)
            .filter(move |&n| n >= 0 && n < w && (n - c).abs() <= 3 * s)
    };
    near(y)
        .flat_map(move |ny| near(x).map(move |nx| (nx as u32, ny as u32)))
        .filter(move |&(nx, ny)| levels.level_of(nx, ny) == l + 1)
}

/// How far a texel's clip may bend from the line through its neighbours' before the clips have an edge there.
const CLIP_BEND: f64 = 1e-3;

/// The texels of `levels` that are integrated whatever the prediction says, one bit a texel (bit `i % 32` of
/// word `i / 32`, `i = y w + x`): those on the border, those where no cubic stencil fits, and, given the
/// texels' `clips` (the share of each ray before a surface, row-major), those within `3s` of an edge of the
/// clips: where a ray starts or stops being hidden or cut short by a surface (an object's silhouette, the
/// outline of a translucent object in its exit field), or where the clip bends (a crease, one surface in front
/// of another). The coarsest level's texels are integrated anyway and have no bit.
pub fn forced_mask(levels: &Levels, clips: Option<&[f32]>) -> Vec<u32> {
    let w = levels.resolution as usize;
    let mut mask = vec![0u32; (w * w).div_ceil(32)];
    if levels.coarsest == 0 {
        return mask;
    }
    // A summed-area table of the clips' edges, for the count within a box.
    let edges = clips.map(|c| {
        let edge = clip_edges(c, w);
        let mut sum = vec![0u32; (w + 1) * (w + 1)];
        for y in 0..w {
            for x in 0..w {
                sum[(y + 1) * (w + 1) + x + 1] =
                    edge[y * w + x] as u32 + sum[y * (w + 1) + x + 1] + sum[(y + 1) * (w + 1) + x]
                        - sum[y * (w + 1) + x];
            }
        }
        sum
    });
    let last = w as u32 - 1;
    for y in 0..w as u32 {
        for x in 0..w as u32 {
            let l = levels.level_of(x, y);
            if l == levels.coarsest {
                continue;
            }
            let s = 1u32 << l;
            let mut forced = x == 0 || y == 0 || x == last || y == last;
            forced |= axis(x, s, w as u32).is_none() || axis(y, s, w as u32).is_none();
            if let (false, Some(sum)) = (forced, &edges) {
                let lo = |c: u32| c.saturating_sub(3 * s) as usize;
                let hi = |c: u32| (c + 3 * s).min(last) as usize + 1;
                let (x0, x1, y0, y1) = (lo(x), hi(x), lo(y), hi(y));
                let row = w + 1;
                let count = sum[y1 * row + x1] + sum[y0 * row + x0]
                    - sum[y0 * row + x1]
                    - sum[y1 * row + x0];
                forced = count > 0;
            }
            if forced {
                let i = y as usize * w + x as usize;
                mask[i / 32] |= 1 << (i % 32);
            }
        }
    }
    mask
}

/// Whether bit `i` of a `forced_mask` is set.
pub fn is_forced(mask: &[u32], i: usize) -> bool {
    mask[i / 32] >> (i % 32) & 1 != 0
}

/// The edges of a `w` x `w` grid of clips: a texel whose ray is hidden, cut short or free unlike a neighbour's
/// (4-connected), or whose clip bends away from the line through its two neighbours on either axis.
fn clip_edges(clips: &[f32], w: usize) -> Vec<bool> {
    let class = |c: f32| match c {
        c if c <= 0.0 => 0,
        c if c < 1.0 => 1,
        _ => 2,
    };
    let at = |x: usize, y: usize| clips[y * w + x];
    let mut edge = vec![false; w * w];
    for y in 0..w {
        for x in 0..w {
            let c = at(x, y);
            let mut e = false;
            for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                if nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < w {
                    e |= class(at(nx as usize, ny as usize)) != class(c);
                }
            }
            if !e && class(c) == 1 {
                let bend =
                    |a: f32, b: f32| (a as f64 - 2.0 * c as f64 + b as f64).abs() > CLIP_BEND;
                if x > 0 && x + 1 < w {
                    e |= bend(at(x - 1, y), at(x + 1, y));
                }
                if y > 0 && y + 1 < w {
                    e |= bend(at(x, y - 1), at(x, y + 1));
                }
            }
            edge[y * w + x] = e;
        }
    }
    edge
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_texel_has_one_level_and_the_levels_cover_the_texture() {
        for w in [1, 7, 64, 100, 256, 257, 1024] {
            let levels = Levels::of(w);
            let count: usize = (0..=levels.coarsest)
                .map(|l| levels.texels(l).count())
                .sum();
            assert_eq!(count, (w * w) as usize, "W = {w}");
        }
        assert_eq!(Levels::of(256).coarsest, 3);
        assert_eq!(Levels::of(1024).coarsest, 4);
        assert_eq!(Levels::of(32).coarsest, 0);
    }

    /// The stencils reproduce a cubic exactly (the order the refinement's error estimate counts on), centered
    /// and shifted alike.
    #[test]
    fn the_stencils_are_exact_on_cubics() {
        let cubic = |x: f64| 0.3 - 1.7 * x + 0.02 * x * x - 0.0009 * x * x * x;
        let w = 40;
        for s in [1, 2, 4] {
            for x in (s..w).step_by(2 * s as usize) {
                match axis(x, s, w) {
                    Some(Axis::Between(nodes, weights)) => {
                        let p: f64 = (0..4).map(|k| weights[k] * cubic(nodes[k] as f64)).sum();
                        assert!((p - cubic(x as f64)).abs() < 1e-9, "x {x} s {s}");
                    }
                    Some(Axis::On(_)) => panic!("x {x} is not on the grid of stride {}", 2 * s),
                    None => assert!(x + s > w - 1 || (x < 5 * s && x + 5 * s > w - 1)),
                }
            }
        }
    }

    #[test]
    fn the_window_holds_the_nodes_of_the_level_above_within_three_strides() {
        let levels = Levels::of(256);
        // A center texel of level 0: 12 of its 16 neighbours of stride 2 are of level 1.
        let n: Vec<_> = window(&levels, (13, 13), 0).collect();
        assert_eq!(n.len(), 12);
        assert!(
            n.iter()
                .all(|&(x, y)| x.abs_diff(13) <= 3 && y.abs_diff(13) <= 3)
        );
    }

    #[test]
    fn an_edge_of_the_clips_forces_the_texels_near_it() {
        let levels = Levels::of(64);
        let w = 64usize;
        // A disc of objects: hidden inside radius 10 around (32, 32).
        let clips: Vec<f32> = (0..w * w)
            .map(|i| {
                let (x, y) = ((i % w) as f64 - 32.0, (i / w) as f64 - 32.0);
                if x.hypot(y) < 10.0 { 0.0 } else { 1.0 }
            })
            .collect();
        let free = forced_mask(&levels, None);
        let mask = forced_mask(&levels, Some(&clips));
        // On the silhouette, forced; far from it, as without objects.
        assert!(is_forced(&mask, 32 * w + 43) && !is_forced(&free, 32 * w + 43));
        assert!(!is_forced(&mask, 5 * w + 5) && !is_forced(&mask, 32 * w + 33));
        // The border always.
        assert!(is_forced(&free, 5) && is_forced(&free, 63 * w + 7));
    }
}
