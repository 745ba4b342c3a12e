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

    /// obvhs' own CPU closest-hit traversal (the reference the shader is tested against).
    pub fn closest(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, i| self.tris[i].intersect(r))
        {
            Some(Hit {
                t: hit.t,
                triangle: self.slot_to_triangle[hit.primitive_id as usize],
            })
        } else {
            None
        }
    }

    /// obvhs' own CPU any-hit query: is anything hit in `[tmin, tmax]`?
    pub fn occluded(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> bool {
        let ray = Ray::new(origin, dir, tmin, tmax);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, i| self.tris[i].intersect(r))
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
