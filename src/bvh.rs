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

/// A closest hit: distance and the *scene* triangle index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
}

impl SceneBvh {
    pub fn build(scene: &Scene) -> anyhow::Result<SceneBvh> {
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
        // In the traversal's data textures a triangle takes 3 texels and each of the < 2n nodes 2.
        if 4 * tris.len() > crate::gi::scene_gpu::MAX_TEXELS {
            anyhow::bail!(
                "{} triangles exceed the GPU traversal's texture capacity",
                tris.len()
            );
        }
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

    /// The ray-triangle test of the CPU traversals: obvhs' test, then the alpha test on flagged
    /// triangles with the shader's barycentrics (`cpu::shading::barycentrics`).
    fn hit_distance(&self, r: &Ray, slot: usize) -> f32 {
        let t = self.tris[slot].intersect(r);
        match &self.alpha {
            Some(a) if t < f32::INFINITY && a.tested(slot) => {
                let (b1, b2) = crate::cpu::shading::barycentrics(
                    &self.tris[slot],
                    r.origin.into(),
                    r.direction.into(),
                );
                if a.passes(slot, b1, b2) {
                    t
                } else {
                    f32::INFINITY
                }
            }
            _ => t,
        }
    }

    /// obvhs' own CPU closest-hit traversal (the reference the shader is tested against), with the
    /// alpha test.
    pub fn closest(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, i| self.hit_distance(r, i))
        {
            Some(Hit {
                t: hit.t,
                triangle: self.slot_to_triangle[hit.primitive_id as usize],
            })
        } else {
            None
        }
    }

    /// obvhs' own CPU any-hit query: is anything hit in `[tmin, tmax]`? With the alpha test.
    pub fn occluded(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> bool {
        let ray = Ray::new(origin, dir, tmin, tmax);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, i| self.hit_distance(r, i))
    }
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
