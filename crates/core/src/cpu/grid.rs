//! CPU twin of `shaders-wgsl/common/grid.wgsl`: the uniform grid over cluster centres and its rings
//! of cells, one for the paper's k-means (Alg. 1, `cpu::kmeans`, searched with Eq. 7) and one for a
//! method module's own k-means (its twin, searched with its own metric). The kernels' ring search skips
//! cells that cannot change the result; the twins scan every cell of a ring, which gives the same
//! result.

use glam::Vec3;

pub use crate::gi::kmeans::MAX_DIM;

/// The grid: cell `(x, y, z)` of side `cell` spans `origin + (x, y, z) · cell` onwards, `dims` cells
/// an axis, each holding its centres' indices.
pub struct CentreGrid {
    origin: Vec3,
    cell: f32,
    dims: [u32; 3],
    cells: Vec<Vec<u32>>,
}

impl CentreGrid {
    /// The grid over the valid centres `(index, position)` of a clustering into `k` clusters
    /// (`grid_build`): over their bounds, or the frame (`lo`, `ext`, `ext[3]` its diagonal) when
    /// there are none; `along_line`: the guard for centres along a line (`centre_spacing`; a method module's
    /// k-means sets it).
    pub fn build(
        centres: impl Iterator<Item = (u32, Vec3)> + Clone,
        k: u32,
        lo: [f32; 4],
        ext: [f32; 4],
        along_line: bool,
    ) -> CentreGrid {
        let (origin, e) = centre_bounds(centres.clone().map(|(_, p)| p), lo, ext);
        let spacing = centre_spacing(e, k, along_line);
        let (cell, dims) = cell_side_and_dims(e, spacing, ext[3], MAX_DIM);
        let mut g = CentreGrid {
            origin,
            cell,
            dims,
            cells: vec![Vec::new(); (dims[0] * dims[1] * dims[2]) as usize],
        };
        for (k, pos) in centres {
            let i = g.index(g.coord(pos));
            g.cells[i].push(k);
        }
        g
    }

    /// Cells of the grid.
    pub fn cells(&self) -> usize {
        self.cells.len()
    }

    /// Cells an axis.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// The side of a cell.
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// The lowest corner of cell (0, 0, 0).
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The centres of cell `i` (x fastest, then y, then z), in the order given to `build`.
    pub fn members(&self, i: usize) -> &[u32] {
        &self.cells[i]
    }

    /// The cell of `p` (`cell_coord`: clamped to the grid).
    pub fn coord(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.origin) / self.cell).floor();
        [0, 1, 2].map(|a| c[a].clamp(0.0, self.dims[a] as f32 - 1.0) as i32)
    }

    fn index(&self, c: [i32; 3]) -> usize {
        ((c[2] as u32 * self.dims[1] + c[1] as u32) * self.dims[0] + c[0] as u32) as usize
    }

    /// The most rings around a cell: the most cells an axis.
    pub fn max_ring(&self) -> i32 {
        *self.dims.iter().max().unwrap() as i32
    }

    /// The centres in the cells at Chebyshev distance `ring` from cell `c` (ring 1: the 27 cells
    /// around it, `c` included), in `ring_cells`' order.
    pub fn ring(&self, c: [i32; 3], ring: i32) -> impl Iterator<Item = u32> + '_ {
        ring_cells(c, ring, self.dims.map(|d| d as i32))
            .flat_map(move |cell| self.cells[self.index(cell)].iter().copied())
    }
}

/// The bounds a search grid spans: the centres' (lowest corner, extent), or the frame `lo`, `ext`
/// given to the kernels when there is no centre.
pub fn centre_bounds(
    centres: impl Iterator<Item = Vec3>,
    lo: [f32; 4],
    ext: [f32; 4],
) -> (Vec3, Vec3) {
    let (mut a, mut b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for c in centres {
        a = a.min(c);
        b = b.max(c);
    }
    if a.x > b.x {
        a = Vec3::from_slice(&lo[..3]);
        b = a + Vec3::from_slice(&ext[..3]);
    }
    (a, (b - a).max(Vec3::ZERO))
}

/// The spacing of `k` centres spread over the surface of a box of extent `e`; with `along_line`, at
/// least their spacing along its longest edge (centres along a line have no area). The guard acts
/// only below 97 centres: above, 1.5 times it stays under `cell_side_and_dims`' floor of 1/64 of
/// that edge, which then sets the cell alike with or without it (tested).
pub fn centre_spacing(e: Vec3, k: u32, along_line: bool) -> f32 {
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    let spacing = (area / k.max(1) as f32).sqrt();
    if along_line {
        spacing.max(e.max_element() / k.max(1) as f32)
    } else {
        spacing
    }
}

/// The cells of a search grid of `dims` cells at Chebyshev distance `ring` from cell `c` (ring 1:
/// the 27 around it, `c` included), clipped to the grid, z then y then x ascending (the kernels'
/// order).
pub fn ring_cells(c: [i32; 3], ring: i32, dims: [i32; 3]) -> impl Iterator<Item = [i32; 3]> {
    let lo = [0, 1, 2].map(|a| (c[a] - ring).max(0));
    let hi = [0, 1, 2].map(|a| (c[a] + ring).min(dims[a] - 1));
    (lo[2]..=hi[2])
        .flat_map(move |z| {
            (lo[1]..=hi[1]).flat_map(move |y| (lo[0]..=hi[0]).map(move |x| [x, y, z]))
        })
        .filter(move |&[x, y, z]| {
            let cheb = (x - c[0]).abs().max((y - c[1]).abs()).max((z - c[2]).abs());
            ring <= 1 || cheb == ring
        })
}

/// A search grid's cell side and size over extent `e`: 1.5 centre spacings, but no finer than
/// `max_dim` cells along the longest side nor than 1e-7 of the scene diagonal `diag` (the
/// kernels' `grid_build`).
pub fn cell_side_and_dims(e: Vec3, spacing: f32, diag: f32, max_dim: u32) -> (f32, [u32; 3]) {
    let floor_cell = (e.max_element() / max_dim as f32).max(1e-7 * diag.max(1e-30));
    let cell = (1.5 * spacing).max(floor_cell);
    let dims = [e.x, e.y, e.z].map(|x| ((x / cell).ceil() as u32).clamp(1, max_dim));
    (cell, dims)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRAME_LO: [f32; 4] = [0.0; 4];
    const FRAME_EXT: [f32; 4] = [8.0, 8.0, 8.0, 13.856406];

    /// Four centres on the x axis from 0 to 3 (a line: no area). Without the guard the cell is the
    /// floor, 3 / 64, so 64 cells along x and the 27 around x = 1.5 hold no centre; with it the
    /// spacing is 3 / 4, the cell 1.125, 3 cells along x (ceil(3 / 1.125)), and x = 1.5 (cell 1,
    /// [1.125, 2.25)) sees all four.
    #[test]
    fn the_line_guard_by_hand() {
        let line = [0.0, 1.0, 2.0, 3.0].map(|x| Vec3::new(x, 0.0, 0.0));
        let centres = || line.iter().enumerate().map(|(i, &p)| (i as u32, p));
        let plain = CentreGrid::build(centres(), 4, FRAME_LO, FRAME_EXT, false);
        assert_eq!((plain.cell(), plain.dims()), (3.0 / 64.0, [64, 1, 1]));
        let c = plain.coord(Vec3::new(1.5, 0.0, 0.0));
        assert_eq!(c, [32, 0, 0]);
        assert_eq!(plain.ring(c, 1).count(), 0);
        let guarded = CentreGrid::build(centres(), 4, FRAME_LO, FRAME_EXT, true);
        assert_eq!((guarded.cell(), guarded.dims()), (1.125, [3, 1, 1]));
        let c = guarded.coord(Vec3::new(1.5, 0.0, 0.0));
        assert_eq!(c, [1, 0, 0]);
        let mut seen: Vec<u32> = guarded.ring(c, 1).collect();
        seen.sort();
        assert_eq!(seen, [0, 1, 2, 3]);
    }

    /// From 97 centres on, the guard leaves every grid as it is (the floor of 1/64 of the longest
    /// edge exceeds 1.5 / K of it): boxes of every shape, lines and points included.
    #[test]
    fn the_line_guard_acts_only_below_97_centres() {
        let mut seed = 7u32;
        let mut f = || {
            seed = seed.wrapping_mul(747796405).wrapping_add(2891336453);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        for case in 0..2000 {
            let k = 97 + (case % 40) * 13 + (case / 40) * 1000;
            let e = Vec3::new(f(), f(), f()).powf(1.0 + 6.0 * f()) * 10.0;
            let e = match case % 5 {
                0 => Vec3::new(e.x, 0.0, 0.0),
                1 => Vec3::new(e.x, e.y * 1e-6, 0.0),
                2 => Vec3::ZERO,
                _ => e,
            };
            let plain = cell_side_and_dims(e, centre_spacing(e, k, false), 17.3, MAX_DIM);
            let guarded = cell_side_and_dims(e, centre_spacing(e, k, true), 17.3, MAX_DIM);
            assert_eq!(plain, guarded, "K {k}, extent {e}");
        }
    }

    /// Ring 2 around the middle of a 5×5×5 grid is the 98 cells of its shell; ring 1 the 27 around.
    #[test]
    fn rings_are_shells() {
        assert_eq!(ring_cells([2, 2, 2], 1, [5, 5, 5]).count(), 27);
        assert_eq!(ring_cells([2, 2, 2], 2, [5, 5, 5]).count(), 125 - 27);
        assert_eq!(ring_cells([0, 0, 0], 1, [5, 5, 5]).count(), 8);
    }
}
