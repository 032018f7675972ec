//! The optical thickness between every pair of surface voxels, `tau(k, l) = integral of sigma_t` along the
//! straight segment from voxel k's point to voxel l's, through the voxels: each voxel the segment crosses adds
//! its extinction times the length of the segment inside it (Amanatides and Woo's traversal, exact for the
//! voxelised medium). Symmetric, so only its upper triangle is kept, in f32.

use glam::DVec3;
use rayon::prelude::*;

use super::voxels::Voxels;

/// `tau` between every pair of an object's surface voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Surface voxels.
    pub n: usize,
    /// Row k holds `tau(k, l)` for l from k to n - 1.
    pub tau: Vec<f32>,
}

impl Table {
    /// The table of `voxels`, on every core.
    pub fn of(voxels: &Voxels) -> Table {
        let n = voxels.surface.len();
        let rows: Vec<Vec<f32>> = (0..n)
            .into_par_iter()
            .map(|k| {
                let from = voxels.surface[k].position;
                (k..n)
                    .map(|l| match l == k {
                        true => 0.0,
                        false => thickness(voxels, from, voxels.surface[l].position) as f32,
                    })
                    .collect()
            })
            .collect();
        Table {
            n,
            tau: rows.concat(),
        }
    }

    /// `tau(k, l)`.
    pub fn get(&self, k: usize, l: usize) -> f32 {
        let (k, l) = if k <= l { (k, l) } else { (l, k) };
        self.tau[row_start(self.n, k) + (l - k)]
    }

    /// The table's bytes.
    pub fn bytes(&self) -> u64 {
        (self.tau.len() * 4) as u64
    }
}

/// Where row k of an `n`-voxel table starts: the rows before it hold n, n - 1, ..., n - k + 1 entries.
pub fn row_start(n: usize, k: usize) -> usize {
    k * n - k * k.saturating_sub(1) / 2
}

/// The optical thickness of the segment `from -> to` through the voxels' extinction.
pub fn thickness(voxels: &Voxels, from: DVec3, to: DVec3) -> f64 {
    let d = to - from;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let side = voxels.side;
    let dims = voxels.dims;
    // In voxel units, from the grid's corner.
    let a = (from - voxels.origin) / side;
    let dir = d / side;
    let mut cell: [i64; 3] = std::array::from_fn(|i| a[i].floor() as i64);
    let mut step = [0i64; 3];
    let mut next = [f64::INFINITY; 3];
    let mut delta = [f64::INFINITY; 3];
    for i in 0..3 {
        if dir[i] > 0.0 {
            step[i] = 1;
            next[i] = ((cell[i] + 1) as f64 - a[i]) / dir[i];
            delta[i] = 1.0 / dir[i];
        } else if dir[i] < 0.0 {
            step[i] = -1;
            next[i] = (cell[i] as f64 - a[i]) / dir[i];
            delta[i] = -1.0 / dir[i];
        }
    }
    let mut t = 0.0;
    let mut tau = 0.0;
    loop {
        let t_next = next[0].min(next[1]).min(next[2]).min(1.0);
        let inside = (0..3).all(|i| cell[i] >= 0 && (cell[i] as usize) < dims[i]);
        if inside {
            let v = cell[0] as usize + dims[0] * (cell[1] as usize + dims[1] * cell[2] as usize);
            tau += voxels.extinction[v] as f64 * (t_next - t);
        }
        if t_next >= 1.0 {
            break;
        }
        t = t_next;
        let axis = if next[0] <= next[1] && next[0] <= next[2] {
            0
        } else if next[1] <= next[2] {
            1
        } else {
            2
        };
        cell[axis] += step[axis];
        next[axis] += delta[axis];
    }
    tau * length
}
