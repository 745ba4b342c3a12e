//! BVH: built on the CPU with `obvhs` (BVH2, PLOC + reinsertion + leaf collapse), flattened into a
//! 32-byte node layout the WGSL traversal reads (`shaders-wgsl/common/bvh.wgsl`) as two 16-byte texels
//! of a texture (triangles: three texels), which is what makes it fast on lavapipe (`docs/bvh.md`).
//!
//! Triangles are reordered into BVH leaf order ("slots") so a leaf's `first_index..first_index+count`
//! indexes the triangle arrays directly, on the CPU and the GPU alike. `slot_to_triangle` maps back to
//! `Scene::triangles`. Why BVH2 rather than CWBVH is measured and argued in `docs/bvh.md`.

use glam::Vec3A;
use obvhs::{
    BvhBuildParams,
    bvh2::{Bvh2, builder::build_bvh2_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle as OTri,
};

use crate::scene::Scene;

/// Deeper trees are refused at build time (the layout is built recursively).
pub const MAX_GPU_DEPTH: usize = 256;

/// A BVH node as the shader reads it (preorder with skip links, see `SceneBvh::gpu_nodes`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuNode {
    pub min: [f32; 3],
    /// 0 for inner nodes; for leaves the number of triangles.
    pub prim_count: u32,
    pub max: [f32; 3],
    /// Inner: the skip link (node after this subtree; = node count past the end). Leaf: first slot.
    pub index: u32,
}

/// A triangle's vertices as the shader reads them (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTriangle {
    pub v0: [f32; 4],
    pub v1: [f32; 4],
    pub v2: [f32; 4],
}

pub struct SceneBvh {
    pub bvh: Bvh2,
    /// Triangles in slot (leaf) order.
    pub tris: Vec<OTri>,
    pub slot_to_triangle: Vec<u32>,
    pub depth: usize,
    pub build_ms: f64,
}

/// A closest hit: distance, the *scene* triangle index, its BVH slot and the barycentrics
/// `p = (1 − u − v) v0 + u v1 + v v2` (NaN from `closest_obvhs`, which does not report them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub slot: u32,
    pub u: f32,
    pub v: f32,
}

impl SceneBvh {
    pub fn build(scene: &Scene) -> anyhow::Result<SceneBvh> {
        // Checked before the build (a minute for millions of triangles): the traversal's data textures
        // hold 4 texels a triangle (nodes: 2 texels each, fewer than 2 a triangle).
        let max = crate::gi::scene_gpu::MAX_TRIANGLES;
        if scene.triangles.len() > max {
            return Err(crate::gi::scene_gpu::TooBig(format!(
                "{}: {} triangles, more than the {max} the GPU data textures hold",
                scene.name,
                scene.triangles.len()
            ))
            .into());
        }
        let t0 = std::time::Instant::now();
        let tris: Vec<OTri> = scene
            .triangles
            .iter()
            .map(|t| OTri {
                v0: t.p[0].into(),
                v1: t.p[1].into(),
                v2: t.p[2].into(),
            })
            .collect();
        let mut core = std::time::Duration::ZERO;
        let bvh = build_bvh2_from_tris(&tris, BvhBuildParams::medium_build(), &mut core);
        let slot_to_triangle = bvh.primitive_indices.clone();
        let tris: Vec<OTri> = slot_to_triangle.iter().map(|&i| tris[i as usize]).collect();
        let depth = depth_of(&bvh);
        if depth >= MAX_GPU_DEPTH {
            anyhow::bail!("BVH depth {depth} exceeds {MAX_GPU_DEPTH}");
        }
        Ok(SceneBvh {
            bvh,
            tris,
            slot_to_triangle,
            depth,
            build_ms: t0.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The tree in depth-first preorder with skip links (Smits 1998), the layout the shader traverses.
    /// An inner node's first child is the next node and `skip` is where traversal goes when the ray
    /// misses it; a leaf is always followed by the next node. Traversal needs no stack: on SIMD software
    /// drivers (lavapipe) a per-lane stack array turns every push and pop into a gather or scatter.
    /// Nodes per-octant ordered (8 preorders) measured no faster on lavapipe (docs/bvh.md).
    pub fn gpu_nodes(&self) -> Vec<GpuNode> {
        fn emit(nodes: &[obvhs::bvh2::node::Bvh2Node], i: usize, out: &mut Vec<GpuNode>) {
            let n = &nodes[i];
            let me = out.len();
            out.push(GpuNode {
                min: n.aabb.min.into(),
                prim_count: n.prim_count,
                max: n.aabb.max.into(),
                index: n.first_index,
            });
            if n.prim_count == 0 {
                emit(nodes, n.first_index as usize, out);
                emit(nodes, n.first_index as usize + 1, out);
                out[me].index = out.len() as u32;
            }
        }
        let mut out = Vec::with_capacity(self.bvh.nodes.len());
        if !self.bvh.nodes.is_empty() {
            emit(&self.bvh.nodes, 0, &mut out);
        }
        out
    }

    pub fn gpu_triangles(&self) -> Vec<GpuTriangle> {
        self.tris
            .iter()
            .map(|t| GpuTriangle {
                v0: t.v0.extend(0.0).into(),
                v1: t.v1.extend(0.0).into(),
                v2: t.v2.extend(0.0).into(),
            })
            .collect()
    }

    /// Closest hit in `[tmin, tmax]`: the CPU twin of `trace_closest` in `shaders-wgsl/common/bvh.wgsl`
    /// (the same conservative box test and watertight triangle test, on obvhs' tree with a stack).
    pub fn closest(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Option<Hit> {
        // The shader clamps tmax to its INF, f32::MAX.
        let mut best = None;
        let mut tmax = tmax.min(f32::MAX);
        self.walk(origin, dir, tmin, &mut tmax, |slot, t, (u, v)| {
            best = Some(Hit {
                t,
                triangle: self.slot_to_triangle[slot as usize],
                slot,
                u,
                v,
            });
            false
        });
        best
    }

    /// Is anything hit in `[tmin, tmax]`? The CPU twin of `trace_any`.
    pub fn occluded(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> bool {
        let mut blocked = false;
        let mut tmax = tmax.min(f32::MAX);
        self.walk(origin, dir, tmin, &mut tmax, |_, _, _| {
            blocked = true;
            true
        });
        blocked
    }

    /// Visits the leaves the ray enters before `tmax` and reports each triangle hit closer than
    /// `tmax` (which then shrinks to it); `on_hit(slot, t, (u, v))` returns true to stop.
    fn walk(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        tmin: f32,
        tmax: &mut f32,
        mut on_hit: impl FnMut(u32, f32, (f32, f32)) -> bool,
    ) {
        if self.bvh.nodes.is_empty() {
            return;
        }
        let inv_dir = Vec3A::new(
            safe_inverse(dir.x),
            safe_inverse(dir.y),
            safe_inverse(dir.z),
        );
        let sh = RayShear::new(dir);
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.bvh.nodes[i];
            if aabb_entry(n.aabb.min, n.aabb.max, origin, inv_dir) >= *tmax {
                continue;
            }
            if n.prim_count == 0 {
                stack.push(n.first_index as usize + 1);
                stack.push(n.first_index as usize);
                continue;
            }
            for k in n.first_index..n.first_index + n.prim_count {
                if let Some((t, u, v)) =
                    intersect_watertight(&self.tris[k as usize], origin, &sh, tmin, *tmax)
                    && t < *tmax
                {
                    *tmax = t;
                    if on_hit(k, t, (u, v)) {
                        return;
                    }
                }
            }
        }
    }

    /// obvhs' own CPU closest-hit traversal with its Möller–Trumbore test: an independent oracle
    /// for the tests, not watertight (a ray through a shared edge can miss both triangles).
    pub fn closest_obvhs(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, i| self.tris[i].intersect(r))
        {
            Some(Hit {
                t: hit.t,
                triangle: self.slot_to_triangle[hit.primitive_id as usize],
                slot: hit.primitive_id,
                u: f32::NAN,
                v: f32::NAN,
            })
        } else {
            None
        }
    }

    /// obvhs' own CPU any-hit query (the oracle counterpart of `occluded`).
    pub fn occluded_obvhs(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> bool {
        let ray = Ray::new(origin, dir, tmin, tmax);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, i| self.tris[i].intersect(r))
    }
}

/// `1 + 2 gamma(3)` with `gamma(n) = n u / (1 - n u)`, `u = 2^-24`: the factor on a box's exit distance
/// that makes the slab test conservative under rounding (Ize 2013, "Robust BVH ray traversal").
/// `BOX_EXIT_SCALE` in `bvh.wgsl`.
pub const BOX_EXIT_SCALE: f32 = 1.000_000_4;

/// `safe_inverse` of `bvh.wgsl` (−0.0 counts as positive there, as here).
pub fn safe_inverse(x: f32) -> f32 {
    let eps = f32::EPSILON;
    if x.abs() <= eps {
        (if x >= 0.0 { 1.0 } else { -1.0 }) / eps
    } else {
        1.0 / x
    }
}

/// `aabb_entry` of `bvh.wgsl`: the entry distance, or infinity when the ray misses the box.
pub fn aabb_entry(bmin: Vec3A, bmax: Vec3A, origin: Vec3A, inv_dir: Vec3A) -> f32 {
    let t1 = (bmin - origin) * inv_dir;
    let t2 = (bmax - origin) * inv_dir;
    let lo = t1.min(t2);
    let hi = t1.max(t2);
    // The same order of min/max as the shader (NaN-free inputs: both give the same value).
    let tn = lo.x.max(lo.y.max(lo.z));
    let tf = hi.x.min(hi.y.min(hi.z)) * BOX_EXIT_SCALE;
    if tf >= tn && tf >= 0.0 {
        tn
    } else {
        f32::INFINITY
    }
}

/// Per-ray constants of the watertight triangle test (`RayShear` in `bvh.wgsl`).
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub k: [usize; 3],
    pub s: [f32; 3],
}

impl RayShear {
    pub fn new(dir: Vec3A) -> RayShear {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = dir[kz];
        RayShear {
            k: [kx, ky, kz],
            s: [dir[kx] / dz, dir[ky] / dz, 1.0 / dz],
        }
    }

    fn vertex(&self, p: Vec3A, origin: Vec3A) -> [f32; 3] {
        let a = p - origin;
        let z = a[self.k[2]];
        [
            a[self.k[0]] - self.s[0] * z,
            a[self.k[1]] - self.s[1] * z,
            z,
        ]
    }
}

/// `edge_fn` of `bvh.wgsl`: `p.x q.y − p.y q.x` with the end points in a fixed order, so that the
/// two triangles sharing an edge get exactly opposite values.
fn edge_fn(p: [f32; 3], q: [f32; 3]) -> f32 {
    let swap = q[0] < p[0] || (q[0] == p[0] && q[1] < p[1]);
    let (a, b) = if swap { (q, p) } else { (p, q) };
    let e = a[0] * b[1] - a[1] * b[0];
    if swap { -e } else { e }
}

/// The watertight ray–triangle test (Woop, Benthin and Wald 2013), `intersect_tri` of `bvh.wgsl`:
/// `(t, u, v)` with `p = (1 − u − v) v0 + u v1 + v v2` when the ray hits in `[tmin, tmax]`. A ray
/// through an edge or a vertex hits (an edge function of 0 or −0.0 counts as inside).
pub fn intersect_watertight(
    tri: &OTri,
    origin: Vec3A,
    sh: &RayShear,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    let a = sh.vertex(tri.v0, origin);
    let b = sh.vertex(tri.v1, origin);
    let c = sh.vertex(tri.v2, origin);
    let u = edge_fn(c, b);
    let v = edge_fn(a, c);
    let w = edge_fn(b, a);
    let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    if outside || det == 0.0 {
        return None;
    }
    let t = (u * a[2] + v * b[2] + w * c[2]) * sh.s[2] / det;
    (t >= tmin && t <= tmax).then_some((t, v / det, w / det))
}

fn depth_of(bvh: &Bvh2) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut max = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        max = max.max(d);
        let n = &bvh.nodes[i];
        if n.prim_count == 0 {
            stack.push((n.first_index as usize, d + 1));
            stack.push((n.first_index as usize + 1, d + 1));
        }
    }
    max
}
