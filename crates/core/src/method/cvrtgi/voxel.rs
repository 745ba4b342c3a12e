//! The CPU steps of CVRTGI (Cosin Ayerbe & Patow 2022, seed 003; `method::cvrtgi`, docs/cvrtgi.md):
//! the scene's voxelisation (§4.1) with each occupied voxel's mean normal and albedo, the paper's
//! heuristic normal (§4.2, Fig. 7) where the mean normal cancels out, the exposed faces, and the
//! SLIC-style voxel clustering (§4.2, Eq. (1), Alg. 1). The paper runs these on the GPU once per
//! static scene; here they run once per scene and settings on the CPU (the result is resident).

use std::collections::HashMap;

use glam::{IVec3, Vec3};

use crate::scene::Scene;

/// A uniform grid over the scene bounds: `res` voxels of side `size` along the longest axis, the
/// bounds centred in the grid (a point on the bounds' faces lies half a voxel inside it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: Vec3,
    pub size: f32,
    pub dims: [u32; 3],
}

impl Grid {
    pub fn new(lo: Vec3, hi: Vec3, res: u32) -> Grid {
        let ext = (hi - lo).max(Vec3::ZERO);
        let size = (ext.max_element() / res.max(1) as f32).max(1e-30);
        let dims = [0, 1, 2].map(|a| (ext[a] / size).floor() as u32 + 1);
        let span = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * size;
        Grid {
            origin: lo - 0.5 * (span - ext),
            size,
            dims,
        }
    }

    /// The voxel coordinates of point `p` (possibly outside the grid).
    pub fn coord(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) / self.size).floor().as_ivec3()
    }

    /// The linear key x + X (y + Y z) of `c`, `None` outside the grid.
    pub fn key(&self, c: IVec3) -> Option<u32> {
        let d = self.dims;
        if c.cmplt(IVec3::ZERO).any()
            || c.x >= d[0] as i32
            || c.y >= d[1] as i32
            || c.z >= d[2] as i32
        {
            return None;
        }
        Some(c.x as u32 + d[0] * (c.y as u32 + d[1] * c.z as u32))
    }

    pub fn coord_of_key(&self, k: u32) -> IVec3 {
        let d = self.dims;
        IVec3::new(
            (k % d[0]) as i32,
            (k / d[0] % d[1]) as i32,
            (k / (d[0] * d[1])) as i32,
        )
    }

    pub fn centre(&self, c: IVec3) -> Vec3 {
        self.origin + (c.as_vec3() + 0.5) * self.size
    }
}

/// The direction of face `dir` (0..6: +x, -x, +y, -y, +z, -z).
pub fn face_axis(dir: u32) -> Vec3 {
    let mut v = Vec3::ZERO;
    v[(dir / 2) as usize] = if dir.is_multiple_of(2) { 1.0 } else { -1.0 };
    v
}

/// The face most similar to `n` (its dominant axis with its sign), as §4.5 picks it.
pub fn dominant_face(n: Vec3) -> u32 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + (n[axis as usize] < 0.0) as u32
}

/// A voxel fragment: position, normal, albedo, area.
pub type Fragment = (Vec3, Vec3, Vec3, f32);

/// Per voxel key the area-weighted sums of its fragments (position, normal, albedo) and their area.
#[derive(Default)]
struct Accumulator(HashMap<u32, (Vec3, Vec3, Vec3, f32)>);

impl Accumulator {
    fn add(&mut self, grid: &Grid, (p, n, a, w): Fragment) {
        if let Some(k) = grid.key(grid.coord(p)) {
            let e = self
                .0
                .entry(k)
                .or_insert((Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0));
            e.0 += p * w;
            e.1 += n * w;
            e.2 += a * w;
            e.3 += w;
        }
    }
}

/// An occupied voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Voxel {
    pub key: u32,
    /// Area-weighted mean of its fragments' positions (where its surface is).
    pub pos: Vec3,
    /// Mean normal (area-weighted fragment normals), or the heuristic normal where they cancel.
    pub normal: Vec3,
    pub albedo: Vec3,
    /// Total fragment area.
    pub area: f32,
    /// Bit `dir` set when the neighbour across face `dir` is empty (or outside the grid).
    pub exposed: u32,
    /// Its cluster (`u32::MAX`: none).
    pub cluster: u32,
}

/// The occupied voxels sorted by key (the paper's compacted buffers, Fig. 4).
#[derive(Clone, Debug)]
pub struct Voxels {
    pub grid: Grid,
    pub voxels: Vec<Voxel>,
    index: HashMap<u32, u32>,
}

impl Voxels {
    pub fn find(&self, c: IVec3) -> Option<u32> {
        self.grid.key(c).and_then(|k| self.index.get(&k).copied())
    }

    /// The occupied voxel at surface point `p`, trying `p`, then `p + d h` and `p - d h` (h = half a
    /// voxel; `d` points into the surface): a point on a voxel boundary may fall on either side.
    pub fn at_surface(&self, p: Vec3, d: Vec3) -> Option<u32> {
        let h = 0.5 * self.grid.size;
        [p, p + d * h, p - d * h]
            .into_iter()
            .find_map(|q| self.find(self.grid.coord(q)))
    }

    /// Builds the set from fragments (position, normal, albedo, area), as voxelisation does.
    pub fn from_fragments(grid: Grid, frags: &[Fragment]) -> Voxels {
        let mut acc = Accumulator::default();
        for &f in frags {
            acc.add(&grid, f);
        }
        Voxels::from_accumulated(grid, acc)
    }

    fn from_accumulated(grid: Grid, acc: Accumulator) -> Voxels {
        let acc = acc.0;
        let mut keys: Vec<u32> = acc.keys().copied().collect();
        keys.sort_unstable();
        let voxels = keys
            .iter()
            .map(|&k| {
                let (p, n, a, w) = acc[&k];
                let w = w.max(1e-30);
                Voxel {
                    key: k,
                    pos: p / w,
                    normal: n / w,
                    albedo: a / w,
                    area: w,
                    exposed: 0,
                    cluster: u32::MAX,
                }
            })
            .collect();
        let index = keys
            .iter()
            .enumerate()
            .map(|(i, &k)| (k, i as u32))
            .collect();
        let mut v = Voxels {
            grid,
            voxels,
            index,
        };
        v.finish_normals_and_faces();
        v
    }

    /// Normalises the mean normals (the heuristic normal where the fragments' normals cancel:
    /// |mean| < 0.1) and marks the exposed faces.
    fn finish_normals_and_faces(&mut self) {
        let normals: Vec<Vec3> = (0..self.voxels.len())
            .map(|i| {
                let n = self.voxels[i].normal;
                if n.length() >= 0.1 {
                    n.normalize()
                } else {
                    self.heuristic_normal(i, n)
                }
            })
            .collect();
        let exposed: Vec<u32> = self
            .voxels
            .iter()
            .map(|v| {
                let c = self.grid.coord_of_key(v.key);
                (0..6)
                    .filter(|&dir| self.find(c + face_axis(dir).as_ivec3()).is_none())
                    .fold(0, |m, dir| m | 1 << dir)
            })
            .collect();
        for ((v, n), e) in self.voxels.iter_mut().zip(normals).zip(exposed) {
            v.normal = n;
            v.exposed = e;
        }
    }

    /// §4.2's heuristic normal (Fig. 7): of the six axis directions, the one whose 3×3 slab of
    /// neighbours next to the voxel has the fewest occupied voxels; a tie goes to the direction nearer
    /// the fragments' normals (`mean`, their area-weighted sum; the paper breaks ties between the
    /// two directions of an axis so), then to the first in the order +x, -x, +y, -y, +z, -z.
    pub fn heuristic_normal(&self, i: usize, mean: Vec3) -> Vec3 {
        let c = self.grid.coord_of_key(self.voxels[i].key);
        let mut best = (u32::MAX, f32::MAX, 0u32);
        for dir in 0..6 {
            let axis = (dir / 2) as usize;
            let s = if dir % 2 == 0 { 1 } else { -1 };
            let mut occupied = 0;
            for a in -1..=1 {
                for b in -1..=1 {
                    let mut d = IVec3::ZERO;
                    d[axis] = s;
                    d[(axis + 1) % 3] = a;
                    d[(axis + 2) % 3] = b;
                    occupied += self.find(c + d).is_some() as u32;
                }
            }
            // The accumulated angle to the fragments' normals, as -cos (smaller is nearer).
            let angle = -mean.dot(face_axis(dir));
            if (occupied, angle) < (best.0, best.1) {
                best = (occupied, angle, dir);
            }
        }
        face_axis(best.2)
    }
}

/// §4.1: voxelises the triangles of `scene` into a grid of `res` voxels along its longest axis.
/// Fragments are points on each triangle on a barycentric lattice spaced at most a third of a voxel
/// (the paper rasterises from the three axes; this samples the same surface), each carrying the
/// triangle's interpolated shading normal, its albedo (base colour × vertex colour; textures are
/// not sampled) and an equal share of its area.
pub fn voxelise(scene: &Scene, res: u32) -> Voxels {
    let (lo, hi) = scene.bounds();
    let grid = Grid::new(lo, hi, res);
    let h = grid.size / 3.0;
    let mut acc = Accumulator::default();
    for t in &scene.triangles {
        let m = &scene.materials[t.material as usize];
        let longest = (t.p[1] - t.p[0])
            .length()
            .max((t.p[2] - t.p[1]).length())
            .max((t.p[0] - t.p[2]).length());
        let steps = ((longest / h).ceil() as u32).clamp(1, 4096);
        let count = (steps + 1) * (steps + 2) / 2;
        let w = t.area() / count as f32;
        for i in 0..=steps {
            for j in 0..=steps - i {
                let (b1, b2) = (i as f32 / steps as f32, j as f32 / steps as f32);
                let b0 = 1.0 - b1 - b2;
                let p = b0 * t.p[0] + b1 * t.p[1] + b2 * t.p[2];
                let n = b0 * t.n[0] + b1 * t.n[1] + b2 * t.n[2];
                let n = if n.length() > 1e-12 {
                    n.normalize()
                } else {
                    t.geometric_normal()
                };
                let col = (b0 * t.color[0] + b1 * t.color[1] + b2 * t.color[2]).truncate();
                let a = (m.base_color.truncate() * col).clamp(Vec3::ZERO, Vec3::ONE);
                acc.add(&grid, (p, n, a, w));
            }
        }
    }
    Voxels::from_accumulated(grid, acc)
}

/// Eq. (1): whether voxel normal `n1` may join a cluster of normal `n0`: the angle between them
/// is below `max_deg` (the paper's 35°).
pub fn eq1_within_angle(n0: Vec3, n1: Vec3, max_deg: f32) -> bool {
    let c = n0.dot(n1) / (n0.length() * n1.length()).max(1e-30);
    c.clamp(-1.0, 1.0).acos().to_degrees() < max_deg
}

/// A voxel cluster after Alg. 1 (line 15's cluster info).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cluster {
    /// Mean position of its voxels.
    pub centre: Vec3,
    /// Mean normal of its voxels (its "main direction").
    pub normal: Vec3,
    /// Mean reflectance of its voxels.
    pub albedo: Vec3,
    /// World-space box of its voxels.
    pub min: Vec3,
    pub max: Vec3,
    pub voxels: u32,
}

/// The SLIC knobs of Alg. 1.
#[derive(Clone, Copy, Debug)]
pub struct SlicSettings {
    /// Seed spacing S in voxels; each cluster searches the (2S+1)³ voxels around its centre.
    pub step: u32,
    pub iterations: u32,
    /// Eq. (1)'s angle in degrees.
    pub angle: f32,
}

/// A voxel's distance to a cluster as the assignment minimises it: Eq. (1) gates and SLIC's
/// spatial term orders. Within the angle, the distance between centres in units of S (< √3 in the
/// search window); beyond it (or for a cluster without a normal yet), 2 + that, so the cluster
/// takes the voxel only if no cluster within the angle reaches it: "a cluster will always add a
/// voxel tested for the first time, even if the angle ... is larger than 35°" (§4.2).
pub fn slic_distance(cluster: (Vec3, Vec3), voxel: (Vec3, Vec3), step: f32, angle: f32) -> f32 {
    let spatial = (voxel.0 - cluster.0).length() / step;
    let gated = cluster.1 == Vec3::ZERO || !eq1_within_angle(cluster.1, voxel.1, angle);
    spatial + if gated { 2.0 } else { 0.0 }
}

/// Alg. 1: clusters the voxels and sets each voxel's `cluster`. Seeds on a uniform grid of spacing
/// S (Achanta et al.), each moved to the occupied voxel nearest its cell's centre and taking that
/// voxel's normal (a seed whose cell is empty is dropped); then `iterations` times: every voxel
/// starts at the largest distance (line 3), every cluster offers itself to the occupied voxels of
/// its (2S+1)³ window and a voxel keeps the cluster of least `slic_distance` (lines 4-12; ties to
/// the lower cluster index, so the result does not depend on the order), and the clusters move to
/// their voxels' mean position and mean normal (line 13). Last, clusters left without voxels are
/// dropped and the rest numbered in order (line 16's compaction) with their info (line 15). A
/// voxel no cluster window reached stays unassigned (`u32::MAX`), as in the paper.
pub fn slic(v: &mut Voxels, s: &SlicSettings) -> Vec<Cluster> {
    let step = s.step.max(1) as i32;
    let g = v.grid;
    let half = step / 2;
    // Seeds: one per grid cell holding an occupied voxel (line 1's mean normals are the voxels').
    let mut centres: Vec<(Vec3, Vec3)> = Vec::new();
    let cells = g.dims.map(|d| d.div_ceil(step as u32) as i32);
    for cz in 0..cells[2] {
        for cy in 0..cells[1] {
            for cx in 0..cells[0] {
                let mid = IVec3::new(cx, cy, cz) * step + half;
                let mut best: Option<(i32, u32)> = None;
                for dz in 0..step {
                    for dy in 0..step {
                        for dx in 0..step {
                            let c = IVec3::new(cx, cy, cz) * step + IVec3::new(dx, dy, dz);
                            if let Some(i) = v.find(c) {
                                let d = (c - mid).length_squared();
                                if best.is_none_or(|b| d < b.0) {
                                    best = Some((d, i));
                                }
                            }
                        }
                    }
                }
                if let Some((_, i)) = best {
                    let vx = &v.voxels[i as usize];
                    centres.push((g.coord_of_key(vx.key).as_vec3(), vx.normal));
                }
            }
        }
    }
    let n = v.voxels.len();
    let mut assign = vec![u32::MAX; n];
    for _ in 0..s.iterations.max(1) {
        let mut best = vec![f32::MAX; n];
        assign.fill(u32::MAX);
        for (k, &(c, cn)) in centres.iter().enumerate() {
            let base = c.round().as_ivec3();
            for dz in -step..=step {
                for dy in -step..=step {
                    for dx in -step..=step {
                        let cc = base + IVec3::new(dx, dy, dz);
                        let Some(i) = v.find(cc) else { continue };
                        let i = i as usize;
                        let d = slic_distance(
                            (c, cn),
                            (cc.as_vec3(), v.voxels[i].normal),
                            step as f32,
                            s.angle,
                        );
                        if d < best[i] {
                            best[i] = d;
                            assign[i] = k as u32;
                        }
                    }
                }
            }
        }
        // Line 13: new centres and mean normals.
        let mut sums = vec![(Vec3::ZERO, Vec3::ZERO, 0u32); centres.len()];
        for (i, &k) in assign.iter().enumerate() {
            if k != u32::MAX {
                let e = &mut sums[k as usize];
                e.0 += g.coord_of_key(v.voxels[i].key).as_vec3();
                e.1 += v.voxels[i].normal;
                e.2 += 1;
            }
        }
        for (c, &(p, nsum, count)) in centres.iter_mut().zip(&sums) {
            if count > 0 {
                c.0 = p / count as f32;
                c.1 = nsum.normalize_or(c.1);
            }
        }
    }
    // Lines 15-16: drop empty clusters, number the rest in order, their info.
    let mut renum = vec![u32::MAX; centres.len()];
    let mut out: Vec<Cluster> = Vec::new();
    let mut sums: Vec<(Vec3, Vec3, Vec3, u32)> = Vec::new();
    for (i, &k) in assign.iter().enumerate() {
        if k == u32::MAX {
            v.voxels[i].cluster = u32::MAX;
            continue;
        }
        if renum[k as usize] == u32::MAX {
            renum[k as usize] = out.len() as u32;
            out.push(Cluster {
                centre: Vec3::ZERO,
                normal: centres[k as usize].1,
                albedo: Vec3::ZERO,
                min: Vec3::splat(f32::MAX),
                max: Vec3::splat(f32::MIN),
                voxels: 0,
            });
            sums.push((Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0));
        }
        let j = renum[k as usize];
        v.voxels[i].cluster = j;
        let vx = v.voxels[i];
        let c = g.coord_of_key(vx.key);
        let e = &mut sums[j as usize];
        e.0 += g.centre(c);
        e.1 += vx.normal;
        e.2 += vx.albedo;
        e.3 += 1;
        let cl = &mut out[j as usize];
        cl.min = cl.min.min(g.origin + c.as_vec3() * g.size);
        cl.max = cl.max.max(g.origin + (c.as_vec3() + 1.0) * g.size);
    }
    for (cl, &(p, nsum, a, count)) in out.iter_mut().zip(&sums) {
        let k = count.max(1) as f32;
        cl.centre = p / k;
        cl.normal = nsum.normalize_or(cl.normal);
        cl.albedo = a / k;
        cl.voxels = count;
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Voxels of side 1 on a grid of `dims` from the origin, one fragment at the centre of each
    /// cell: (cell, normal, albedo, area).
    pub(crate) fn unit_voxels(dims: [u32; 3], cells: &[(IVec3, Vec3, Vec3, f32)]) -> Voxels {
        let grid = Grid {
            origin: Vec3::ZERO,
            size: 1.0,
            dims,
        };
        let frags: Vec<Fragment> = cells
            .iter()
            .map(|&(c, n, a, w)| (c.as_vec3() + 0.5, n, a, w))
            .collect();
        Voxels::from_fragments(grid, &frags)
    }

    /// Alg. 1 on `v` with Eq. (1)'s 35°: each voxel's cluster, and the clusters.
    fn slic_labels(v: &mut Voxels, step: u32, iterations: u32) -> (Vec<u32>, Vec<Cluster>) {
        let s = SlicSettings {
            step,
            iterations,
            angle: 35.0,
        };
        let clusters = slic(v, &s);
        (v.voxels.iter().map(|x| x.cluster).collect(), clusters)
    }

    /// A point on a voxel's face, on the empty side, is found half a voxel into the surface, both
    /// ways along `d` (cargo-mutants: the step back as `p - d / h` survived; on the unit grids of the
    /// other tests it is two voxels).
    #[test]
    fn at_surface_steps_half_a_voxel_into_the_surface() {
        let grid = Grid {
            origin: Vec3::ZERO,
            size: 0.25,
            dims: [4; 3],
        };
        // One voxel, (1, 1, 1): [0.25, 0.5]³.
        let frag = (Vec3::splat(0.375), Vec3::Y, Vec3::splat(0.5), 1.0);
        let v = Voxels::from_fragments(grid, &[frag]);
        assert_eq!(v.voxels.len(), 1);
        // On its top face (y = 0.5 lies in the empty voxel above), looking down into it.
        let top = Vec3::new(0.4, 0.5, 0.3);
        assert_eq!(v.find(grid.coord(top)), None);
        assert_eq!(v.at_surface(top, -Vec3::Y), Some(0));
        // The other way round too: `d` pointing away, the step back finds it.
        assert_eq!(v.at_surface(top, Vec3::Y), Some(0));
        // A point a voxel away from it finds nothing.
        assert_eq!(v.at_surface(Vec3::new(0.4, 0.8, 0.3), -Vec3::Y), None);
    }

    /// Alg. 1's seeds are the occupied voxels nearest their cells' centres: a row of 8 voxels, S = 4
    /// (cells x 0..3 and 4..7, centres x = 2 and 6), occupied at x = 0, 3, 5, 6, 7, all facing +y.
    /// The seeds are x = 3 and 6; one pass (iterations 1) gives each voxel the nearer: clusters
    /// {0, 3} and {5, 6, 7} (cargo-mutants: the centre as `step % 2`, seeds x = 0 and 5, clusters
    /// {0} and {3, 5, 6, 7}, and as `step * 2`, seeds x = 3 and 7, x = 5 at 2 from both and so to
    /// the lower index, clusters {0, 3, 5} and {6, 7}, survived).
    #[test]
    fn slic_seeds_at_the_voxels_nearest_the_cell_centres() {
        // On a unit grid and on one of side 0.5 (the same voxels, every length halved).
        for size in [1.0f32, 0.5] {
            let grid = Grid {
                origin: Vec3::ZERO,
                size,
                dims: [8, 1, 1],
            };
            let frags: Vec<Fragment> = [0.0, 3.0, 5.0, 6.0, 7.0]
                .map(|x| (Vec3::new(x + 0.5, 0.5, 0.5) * size, Vec3::Y, Vec3::ONE, 1.0))
                .to_vec();
            let mut v = Voxels::from_fragments(grid, &frags);
            let (of, clusters) = slic_labels(&mut v, 4, 1);
            assert_eq!(of, [0, 0, 1, 1, 1], "size {size}");
            assert_eq!(
                clusters.iter().map(|c| c.voxels).collect::<Vec<_>>(),
                [2, 3]
            );
            // Each cluster's box spans its voxels' whole cells: x 0..4 and 5..8, y and z 0..1,
            // times the size (cargo-mutants: the far corner as `c * size`, without the + 1, and
            // as `(c + 1) / size`, survived).
            let boxes: Vec<(Vec3, Vec3)> = clusters.iter().map(|c| (c.min, c.max)).collect();
            assert_eq!(
                boxes,
                [
                    (Vec3::ZERO, Vec3::new(4.0, 1.0, 1.0) * size),
                    (
                        Vec3::new(5.0, 0.0, 0.0) * size,
                        Vec3::new(8.0, 1.0, 1.0) * size
                    ),
                ],
                "size {size}"
            );
        }
    }

    /// A voxel's albedo and position are its fragments' area-weighted means: two fragments of areas
    /// 0.5 and 1.5 in one voxel, albedos 0.2 and 0.6, give 0.5, and the voxel's area is 2
    /// (cargo-mutants: the albedo sum as `a / w` survived fragments of area 1, and the mean's
    /// division by the area, `a / w` as `a * w` or `a % w`, areas summing to 1).
    #[test]
    fn voxel_means_are_weighted_by_fragment_area() {
        let grid = Grid {
            origin: Vec3::ZERO,
            size: 1.0,
            dims: [1; 3],
        };
        let frags = [
            (Vec3::splat(0.2), Vec3::Y, Vec3::splat(0.2), 0.5),
            (Vec3::splat(0.6), Vec3::Y, Vec3::splat(0.6), 1.5),
        ];
        let v = Voxels::from_fragments(grid, &frags);
        assert_eq!(v.voxels.len(), 1);
        let x = v.voxels[0];
        assert!(
            (x.albedo - Vec3::splat(0.5)).abs().max_element() < 1e-6,
            "{:?}",
            x.albedo
        );
        assert!(
            (x.pos - Vec3::splat(0.5)).abs().max_element() < 1e-6,
            "{:?}",
            x.pos
        );
        assert!((x.area - 2.0).abs() < 1e-6);
    }

    /// Voxelisation keeps the surface's area: the voxels of the built-in Cornell box at 12³ and 20³
    /// hold the triangles' total area between them (cargo-mutants: the samples' count as
    /// `(s + 1) * (s + 2) * 2`, each sample's area a quarter of its share, survived; the means
    /// are area-weighted, so only the absolute area tells).
    #[test]
    fn voxels_hold_the_surfaces_area() {
        let sc = crate::scene::load("builtin:cornell").unwrap();
        let total: f64 = sc.triangles.iter().map(|t| t.area() as f64).sum();
        for res in [12, 20] {
            let v = voxelise(&sc, res);
            let held: f64 = v.voxels.iter().map(|x| x.area as f64).sum();
            // Measured: within 2.3e-8 (f32 sums of the samples' shares).
            assert!(
                (held / total - 1.0).abs() < 1e-6,
                "{res}³: {held} of {total}"
            );
        }
    }

    /// Eq. (1) compares directions: normals of any length (a voxel's mean normal is shorter than 1
    /// where its fragments disagree) at 30° pass a 35° test and at 40° fail it (cargo-mutants: the
    /// cosine's division by the lengths as a product survived; unit normals hide it).
    #[test]
    fn eq1_compares_directions_whatever_the_lengths() {
        let at = |deg: f32, len: f32| {
            let r = deg.to_radians();
            Vec3::new(r.cos(), r.sin(), 0.0) * len
        };
        for len in [0.5, 1.0, 3.0] {
            assert!(eq1_within_angle(at(0.0, len), at(30.0, len), 35.0), "{len}");
            assert!(
                !eq1_within_angle(at(0.0, len), at(40.0, len), 35.0),
                "{len}"
            );
            assert!(eq1_within_angle(at(0.0, 1.0), at(30.0, len), 35.0), "{len}");
        }
        // "Below" the angle, strictly: perpendicular normals at 90° (acos(0) is 90° exactly in
        // f32) and equal ones at 0° do not join (cargo-mutants: `<` as `<=` survived).
        assert!(!eq1_within_angle(Vec3::X, Vec3::Y, 90.0));
        assert!(!eq1_within_angle(Vec3::Z, Vec3::Z, 0.0));
        assert!(eq1_within_angle(Vec3::Z, Vec3::Z, 1e-3));
    }

    /// A voxel's normal is its fragments' area-weighted mean normal, normalised: areas 0.25 (+y)
    /// and 0.75 (+x) give (3, 1, 0)/√10. Where they nearly cancel (|mean| < 0.1) the heuristic
    /// normal takes over, and in a voxel with no neighbour its six directions tie on occupancy, so
    /// the one nearer the fragments' mean wins: +x (area 0.5) against -x (0.45) gives +x, and the
    /// other way round -x (cargo-mutants: the normal sum `+=` as `-=` survived; every consumer of a
    /// voxel's normal but this tie takes |axis · n|).
    #[test]
    fn voxel_normals_are_the_fragments_mean_or_the_heuristic_nearest_it() {
        let at = IVec3::ONE;
        let v = unit_voxels(
            [3; 3],
            &[
                (at, Vec3::Y, Vec3::ONE, 0.25),
                (at, Vec3::X, Vec3::ONE, 0.75),
            ],
        );
        let want = Vec3::new(3.0, 1.0, 0.0) / 10f32.sqrt();
        let n = v.voxels[0].normal;
        assert!((n - want).abs().max_element() < 1e-6, "{n:?}");
        for (big, want) in [(Vec3::X, Vec3::X), (-Vec3::X, -Vec3::X)] {
            let v = unit_voxels(
                [3; 3],
                &[(at, big, Vec3::ONE, 0.5), (at, -big, Vec3::ONE, 0.45)],
            );
            assert_eq!(v.voxels[0].normal, want, "{big:?}");
        }
    }

    /// Voxels of side 1 in a 5³ grid at `cells`, each from one fragment at its centre of normal +y
    /// and area `area`.
    fn cells_of(cells: &[IVec3], area: f32) -> Voxels {
        let cells: Vec<_> = cells
            .iter()
            .map(|&c| (c, Vec3::Y, Vec3::ONE, area))
            .collect();
        unit_voxels([5; 3], &cells)
    }

    /// The heuristic normal (§4.2, Fig. 7) by hand: a voxel whose face neighbours are all occupied
    /// but the one below has an empty slab only under it, so its normal is -y whatever the mean.
    /// A voxel whose fragments' normals agree keeps their mean however small their area: a floor
    /// voxel under a wall, of fragments of area 0.05 facing +y, is +y (its heuristic normal would
    /// be -y) (cargo-mutants: the slab's side `s` flipped, and fixed to +1 or -1, survived the
    /// symmetric wall of `tests/cvrtgi.rs`).
    #[test]
    fn the_heuristic_normal_takes_the_emptiest_slab() {
        let c = IVec3::splat(2);
        let mut cells = vec![c];
        cells.extend([0, 1, 2, 4, 5].map(|d| c + face_axis(d).as_ivec3()));
        let v = cells_of(&cells, 1.0);
        let i = v.find(c).unwrap() as usize;
        for mean in [Vec3::ZERO, Vec3::Y * 0.05, Vec3::X * 0.05] {
            assert_eq!(v.heuristic_normal(i, mean), -Vec3::Y, "{mean:?}");
        }
        // The floor voxel (2, 1, 2) with four floor neighbours and the wall's voxel above it.
        let floor = IVec3::new(2, 1, 2);
        let mut cells = vec![floor, floor + IVec3::Y];
        cells.extend([0, 1, 4, 5].map(|d| floor + face_axis(d).as_ivec3()));
        let v = cells_of(&cells, 0.05);
        let i = v.find(floor).unwrap() as usize;
        assert_eq!(v.heuristic_normal(i, Vec3::ZERO), -Vec3::Y);
        assert_eq!(v.voxels[i].normal, Vec3::Y);
    }

    /// The heuristic normal against slabs counted another way (each occupied voxel q is in the slab
    /// of direction a when d = q - c has every component in -1..=1 and d · a = 1), with the same
    /// tie rules (fewest, then the largest mean · a, then the first), over 300 pseudo-random
    /// neighbourhoods (each of the 26 neighbours occupied with probability 1/2, some with every
    /// slab occupied) and means (cargo-mutants: the slab's in-plane axes `(axis + k) % 3` as `/`,
    /// `-` or `*`, and the count `+=` as `-=`, survived the symmetric wall of `tests/cvrtgi.rs`).
    #[test]
    fn the_heuristic_normal_counts_each_slab() {
        let c = IVec3::splat(2);
        let mut state = 0x9e37_79b9u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        let mut full = 0;
        for case in 0..300 {
            let mut cells = vec![c];
            for z in -1..=1 {
                for y in -1..=1 {
                    for x in -1..=1 {
                        let d = IVec3::new(x, y, z);
                        if d != IVec3::ZERO && next() % 2 == 0 {
                            cells.push(c + d);
                        }
                    }
                }
            }
            let mean = if case % 3 == 0 {
                Vec3::ZERO
            } else {
                let u = |r: u32| (r % 1000) as f32 / 1000.0 - 0.5;
                Vec3::new(u(next()), u(next()), u(next())) * 0.1
            };
            let count = |a: IVec3| {
                cells
                    .iter()
                    .filter(|&&q| {
                        let d = q - c;
                        d.abs().max_element() <= 1 && d.dot(a) == 1
                    })
                    .count() as u32
            };
            let mut want = (u32::MAX, f32::MIN, 0);
            for dir in 0..6 {
                let a = face_axis(dir);
                let (n, m) = (count(a.as_ivec3()), mean.dot(a));
                if n < want.0 || (n == want.0 && m > want.1) {
                    want = (n, m, dir);
                }
            }
            full += (want.0 > 0) as u32;
            let v = cells_of(&cells, 1.0);
            let i = v.find(c).unwrap() as usize;
            assert_eq!(
                v.heuristic_normal(i, mean),
                face_axis(want.2),
                "case {case}: {cells:?}, mean {mean:?}"
            );
        }
        // Some neighbourhoods have no empty slab (where the count's `-=` wraps and the fullest wins).
        assert!(full >= 10, "{full}");
    }

    /// Voxelisation interpolates each triangle's shading normals and vertex colours (§4.1): a
    /// triangle in the plane y = 0 (geometric normal -y) over a 7 × 1 × 7 grid, whose vertex normals
    /// are all (0.6, 0.8, 0), gives every voxel that normal. Its vertex colours (0.2, 0.4, 0.6),
    /// (0.8, 0.2, 0.4) and (0.5, 1, 0.1) times the base colour (0.5, 0.8, 1) average, over the
    /// voxels weighted by area, to the base colour times their mean (0.25, 0.4267, 0.3667): the
    /// barycentric lattice is symmetric in its three coordinates (cargo-mutants: each `+` and `*`
    /// of the normal's and the colour's interpolation, the shading normal's fallback test and the
    /// albedo product survived; the built-in scenes have flat normals and white vertex colours).
    #[test]
    fn voxelise_interpolates_shading_normals_and_vertex_colours() {
        use crate::scene::{Material, Scene, Triangle};
        use glam::{Vec2, Vec4};
        let tilted = Vec3::new(0.6, 0.8, 0.0);
        let colors = [
            Vec4::new(0.2, 0.4, 0.6, 1.0),
            Vec4::new(0.8, 0.2, 0.4, 1.0),
            Vec4::new(0.5, 1.0, 0.1, 1.0),
        ];
        let base = Vec3::new(0.5, 0.8, 1.0);
        let sc = Scene {
            triangles: vec![Triangle {
                p: [
                    Vec3::ZERO,
                    Vec3::new(4.0, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, 4.0),
                ],
                n: [tilted; 3],
                uv: [Vec2::ZERO; 3],
                color: colors,
                material: 0,
            }],
            materials: vec![Material {
                base_color: base.extend(1.0),
                ..Material::default()
            }],
            ..Default::default()
        };
        assert_eq!(sc.triangles[0].geometric_normal(), -Vec3::Y);
        let v = voxelise(&sc, 6);
        assert_eq!(v.grid.dims, [7, 1, 7]);
        assert!(v.voxels.len() >= 20, "{}", v.voxels.len());
        for x in &v.voxels {
            assert!(
                (x.normal - tilted).abs().max_element() < 1e-5,
                "{:?}",
                x.normal
            );
        }
        let area: f32 = v.voxels.iter().map(|x| x.area).sum();
        let mean = v.voxels.iter().map(|x| x.albedo * x.area).sum::<Vec3>() / area;
        let want = base * (colors[0] + colors[1] + colors[2]).truncate() / 3.0;
        assert!((area - 8.0).abs() < 1e-4, "{area}");
        assert!(
            (mean - want).abs().max_element() < 1e-5,
            "{mean:?} against {want:?}"
        );
    }

    /// A seed cell whose two voxels are equally near its centre seeds at the first in key order: on
    /// an 8 × 2 × 1 grid with S = 4 (cell centres (2, 2, 2) and (6, 2, 2)), voxels (1, 0, 0) and
    /// (3, 0, 0) tie in the first cell (9 from its centre) and it seeds at (1, 0, 0); the second
    /// seeds at (6, 0, 0) (8, against 9 for (4, 1, 0), which is scanned after it). One pass gives
    /// (4, 1, 0) to the seed at (6, 0, 0) (√5 against √10): clusters {(1, 0, 0), (3, 0, 0)} and
    /// {(6, 0, 0), (4, 1, 0)}. Seeded at (3, 0, 0), (4, 1, 0) would join it (√2) (cargo-mutants: the
    /// nearest test `d < best` as `<=`, which takes the later voxel of a tie, and as `==`, which
    /// keeps the first voxel scanned unless a later one ties it, survived).
    #[test]
    fn a_tied_seed_cell_seeds_at_its_first_voxel() {
        let cells = [[1, 0, 0], [3, 0, 0], [6, 0, 0], [4, 1, 0]]
            .map(|c| (IVec3::from(c), Vec3::Y, Vec3::ONE, 1.0));
        let mut v = unit_voxels([8, 2, 1], &cells);
        let keys: Vec<u32> = v.voxels.iter().map(|x| x.key).collect();
        assert_eq!(keys, [1, 3, 6, 12]);
        let (of, clusters) = slic_labels(&mut v, 4, 1);
        assert_eq!(of, [0, 0, 1, 1]);
        assert_eq!(clusters.len(), 2);
    }

    /// A cluster that no voxel joins in a pass keeps its centre and may take voxels again later
    /// (Alg. 1 line 13 moves only clusters that have voxels). Nine voxels on a 7 × 1 × 5 grid (S =
    /// 3, 6 passes; found by a search over 3000 random grids, 20 of which tell the two apart): the
    /// cluster seeded at (4, 0, 3) (normal (1, 1, 0)/√2) loses its voxels to its neighbours in
    /// passes 3 and 4 and takes (4, 0, 3) back in pass 5, so the result has 5 clusters. Moved to
    /// the mean of no voxels, 0/0, its centre is NaN, it never takes a voxel again, and 4 are left
    /// (cargo-mutants: `count > 0` as `>=` survived; no other test empties a cluster).
    #[test]
    fn an_emptied_cluster_keeps_its_centre_and_can_refill() {
        let diag = Vec3::new(1.0, 1.0, 0.0).normalize();
        let cells = [
            ([5, 0, 0], Vec3::X),
            ([6, 0, 1], Vec3::X),
            ([0, 0, 2], -Vec3::Y),
            ([2, 0, 2], -Vec3::Y),
            ([5, 0, 2], Vec3::Z),
            ([3, 0, 3], Vec3::X),
            ([4, 0, 3], diag),
            ([6, 0, 3], diag),
            ([5, 0, 4], -Vec3::Y),
        ];
        let mut v = unit_voxels(
            [7, 1, 5],
            &cells.map(|(c, n)| (IVec3::from(c), n, Vec3::ONE, 1.0)),
        );
        let (of, clusters) = slic_labels(&mut v, 3, 6);
        assert_eq!(of, [0, 0, 1, 1, 2, 0, 3, 3, 4]);
        assert_eq!(clusters.len(), 5);
    }

    /// Alg. 1 line 15's cluster info: each cluster's mean voxel centre (world space), mean albedo
    /// and voxel count. The row of `slic_seeds_at_the_voxels_nearest_the_cell_centres` (clusters
    /// {0, 3} and {5, 6, 7}) with albedos 0.1 and 0.3, then 0.2, 0.4 and 0.9: albedos 0.2 and 0.5,
    /// centres (2, 0.5, 0.5) and (6.5, 0.5, 0.5) (cargo-mutants: the albedo sum `+=` as `-=` or `*=`
    /// and its mean `a / k` as `a * k` or `a % k` survived; every other test's albedo is 1).
    #[test]
    fn slic_cluster_info_is_the_mean_of_its_voxels() {
        let cells = [(0, 0.1), (3, 0.3), (5, 0.2), (6, 0.4), (7, 0.9)]
            .map(|(x, a)| (IVec3::new(x, 0, 0), Vec3::Y, Vec3::splat(a), 1.0));
        let mut v = unit_voxels([8, 1, 1], &cells);
        let (_, clusters) = slic_labels(&mut v, 4, 1);
        let got: Vec<(Vec3, Vec3, u32)> = clusters
            .iter()
            .map(|c| (c.centre, c.albedo, c.voxels))
            .collect();
        let want = [
            (Vec3::new(2.0, 0.5, 0.5), Vec3::splat(0.2), 2),
            (Vec3::new(6.5, 0.5, 0.5), Vec3::splat(0.5), 3),
        ];
        assert_eq!(got.len(), 2);
        for ((c, a, n), (wc, wa, wn)) in got.iter().zip(want) {
            assert!((*c - wc).abs().max_element() < 1e-6, "{got:?}");
            assert!((*a - wa).abs().max_element() < 1e-6, "{got:?}");
            assert_eq!(*n, wn);
        }
    }
}
