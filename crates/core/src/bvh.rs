//! BVH: built on the CPU with `obvhs` (BVH2, PLOC + reinsertion + leaf collapse), flattened into a
//! 32-byte node layout the WGSL traversal reads (`shaders-wgsl/common/bvh.wgsl`) as two 16-byte texels
//! of a texture (triangles: three texels), which is what makes it fast on lavapipe (`docs/bvh.md`).
//!
//! Triangles are reordered into BVH leaf order ("slots") so a leaf's `first_index..first_index+count`
//! indexes the triangle arrays directly, on the CPU and the GPU alike. `slot_to_triangle` maps back to
//! `Scene::triangles`. Why BVH2 rather than CWBVH is measured and argued in `docs/bvh.md`.

use glam::{Vec2, Vec3A};
use obvhs::{
    BvhBuildParams,
    bvh2::{Bvh2, builder::build_bvh2_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle as OTri,
};

use crate::scene::Scene;

/// Width in texels of the BVH data textures on the GPU (`gi::scene_gpu`): texel i is at
/// (i % W, i / W) (`texel_xy` in bvh.wgsl).
pub const TEXEL_ROW: u32 = 4096;
/// The most texels one data texture holds under WebGPU's default 8192-row limit.
pub const MAX_TEXELS: usize = TEXEL_ROW as usize * 8192;

/// The most triangles the data textures hold: 4 texels a triangle in the shading texture and in the
/// node texture (2 texels a node, fewer than 2 nodes a triangle).
pub const MAX_TRIANGLES: usize = MAX_TEXELS / 4;

/// A scene whose GPU data do not fit the device: one line naming the limit (exit 2 in the CLI).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct TooBig(pub String);

/// Deeper trees are refused at build time (the layout is built recursively).
pub const MAX_GPU_DEPTH: usize = 256;

/// A BVH node as the shader reads it (preorder with skip links, see `SceneBvh::gpu_nodes`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuNode {
    pub min: [f32; 3],
    /// 0 for inner nodes; for leaves the number of triangles, with `ALPHA_LEAF` set when one of them
    /// is alpha-tested (the shader then tests that leaf in a loop of its own).
    pub prim_count: u32,
    pub max: [f32; 3],
    /// Inner: the skip link (node after this subtree; = node count past the end). Leaf: first slot.
    pub index: u32,
}

/// The bit of `GpuNode::prim_count` that marks a leaf holding an alpha-tested triangle.
pub const ALPHA_LEAF: u32 = 0x8000_0000;

/// A triangle's vertices as the shader reads them; `v0[3]` is 1 for an alpha-tested triangle, else 0
/// (the per-triangle flag of the alpha test, read where a ray finds a candidate hit).
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
    /// The alpha test of the CPU traversal; `None` when no triangle is alpha-tested.
    pub alpha: Option<AlphaMask>,
}

/// What the CPU traversal needs to alpha-test (twin of `alpha_passes` in
/// `shaders-wgsl/common/alpha.wgsl`): a hit on a flagged triangle whose alpha (base colour factor ×
/// interpolated vertex alpha × bilinear texture alpha) is below its material's cutoff is no hit.
pub struct AlphaMask {
    /// Per slot: index into `tris`, or `u32::MAX` for a triangle that is not tested.
    slot: Vec<u32>,
    tris: Vec<MaskTri>,
    /// The alpha channels of the textures that tested triangles read.
    textures: Vec<AlphaTexture>,
}

struct MaskTri {
    uv: [Vec2; 3],
    vertex_alpha: [f32; 3],
    factor: f32,
    texture: Option<u32>,
    cutoff: f32,
}

struct AlphaTexture {
    width: u32,
    height: u32,
    alpha: Vec<u8>,
}

impl AlphaTexture {
    /// Twin of `sample_alpha` (bilinear, repeat, alpha stored linear).
    fn sample(&self, uv: Vec2) -> f32 {
        let (w, h) = (self.width as i32, self.height as i32);
        let f = (uv - uv.floor()) * Vec2::new(w as f32, h as f32) - 0.5;
        let i = f.floor();
        let t = f - i;
        let (x, y) = (i.x as i32, i.y as i32);
        let at = |x: i32, y: i32| {
            self.alpha[(y.rem_euclid(h) * w + x.rem_euclid(w)) as usize] as f32 / 255.0
        };
        let lerp = |a: f32, b: f32, s: f32| a + (b - a) * s;
        lerp(
            lerp(at(x, y), at(x + 1, y), t.x),
            lerp(at(x, y + 1), at(x + 1, y + 1), t.x),
            t.y,
        )
    }
}

impl AlphaMask {
    fn build(scene: &Scene, slot_to_triangle: &[u32]) -> Option<AlphaMask> {
        let flags = scene.alpha_test_flags();
        if !flags.iter().any(|&f| f) {
            return None;
        }
        let mut texture_index = std::collections::HashMap::new();
        let mut textures = Vec::new();
        let mut tris = Vec::new();
        let slot = slot_to_triangle
            .iter()
            .map(|&ti| {
                if !flags[ti as usize] {
                    return u32::MAX;
                }
                let t = &scene.triangles[ti as usize];
                let m = &scene.materials[t.material as usize];
                let texture = m.base_color_texture.map(|k| {
                    *texture_index.entry(k).or_insert_with(|| {
                        let tex = &scene.textures[k as usize];
                        textures.push(AlphaTexture {
                            width: tex.width,
                            height: tex.height,
                            alpha: tex.rgba8.iter().map(|c| c[3]).collect(),
                        });
                        textures.len() as u32 - 1
                    })
                });
                tris.push(MaskTri {
                    uv: t.uv,
                    vertex_alpha: t.color.map(|c| c.w),
                    factor: m.base_color.w,
                    texture,
                    cutoff: m.alpha_cutoff.unwrap_or(0.0),
                });
                tris.len() as u32 - 1
            })
            .collect();
        Some(AlphaMask {
            slot,
            tris,
            textures,
        })
    }

    /// Whether `slot` is alpha-tested.
    pub fn tested(&self, slot: usize) -> bool {
        self.slot[slot] != u32::MAX
    }

    /// Whether a hit on `slot` at barycentrics (b1, b2) counts (always for untested triangles).
    pub fn passes(&self, slot: usize, b1: f32, b2: f32) -> bool {
        let Some(m) = self.tris.get(self.slot[slot] as usize) else {
            return true;
        };
        let b0 = 1.0 - b1 - b2;
        let va = b0 * m.vertex_alpha[0] + b1 * m.vertex_alpha[1] + b2 * m.vertex_alpha[2];
        let mut a = m.factor * va;
        if let Some(k) = m.texture {
            let uv = b0 * m.uv[0] + b1 * m.uv[1] + b2 * m.uv[2];
            a *= self.textures[k as usize].sample(uv);
        }
        a >= m.cutoff
    }
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
        let max = MAX_TRIANGLES;
        if scene.triangles.len() > max {
            return Err(TooBig(format!(
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
        let alpha = AlphaMask::build(scene, &slot_to_triangle);
        Ok(SceneBvh {
            bvh,
            tris,
            alpha,
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
        fn emit(
            nodes: &[obvhs::bvh2::node::Bvh2Node],
            alpha: Option<&AlphaMask>,
            i: usize,
            out: &mut Vec<GpuNode>,
        ) {
            let n = &nodes[i];
            let me = out.len();
            let slots = n.first_index as usize..(n.first_index + n.prim_count) as usize;
            let tested =
                n.prim_count > 0 && alpha.is_some_and(|a| slots.into_iter().any(|s| a.tested(s)));
            out.push(GpuNode {
                min: n.aabb.min.into(),
                prim_count: n.prim_count | if tested { ALPHA_LEAF } else { 0 },
                max: n.aabb.max.into(),
                index: n.first_index,
            });
            if n.prim_count == 0 {
                emit(nodes, alpha, n.first_index as usize, out);
                emit(nodes, alpha, n.first_index as usize + 1, out);
                out[me].index = out.len() as u32;
            }
        }
        let mut out = Vec::with_capacity(self.bvh.nodes.len());
        if !self.bvh.nodes.is_empty() {
            emit(&self.bvh.nodes, self.alpha.as_ref(), 0, &mut out);
        }
        out
    }

    pub fn gpu_triangles(&self) -> Vec<GpuTriangle> {
        self.tris
            .iter()
            .enumerate()
            .map(|(slot, t)| {
                let tested = self.alpha.as_ref().is_some_and(|a| a.tested(slot));
                GpuTriangle {
                    v0: t.v0.extend(if tested { 1.0 } else { 0.0 }).into(),
                    v1: t.v1.extend(0.0).into(),
                    v2: t.v2.extend(0.0).into(),
                }
            })
            .collect()
    }

    /// Whether any triangle is alpha-tested.
    pub fn has_alpha_test(&self) -> bool {
        self.alpha.is_some()
    }

    /// Closest hit in `[tmin, tmax]`: the CPU twin of `trace_closest` in `shaders-wgsl/common/bvh.wgsl`
    /// (the same conservative box test, watertight triangle test and alpha test, on obvhs' tree with
    /// a stack).
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
                    && self
                        .alpha
                        .as_ref()
                        .is_none_or(|a| a.passes(k as usize, u, v))
                {
                    *tmax = t;
                    if on_hit(k, t, (u, v)) {
                        return;
                    }
                }
            }
        }
    }

    /// obvhs' own CPU closest-hit traversal with its Möller–Trumbore test (no alpha test): an independent oracle
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
