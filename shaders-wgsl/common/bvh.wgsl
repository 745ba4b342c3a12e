// Software BVH2 traversal (stackless, skip links) with a conservative ray-box test (Ize 2013) and the
// watertight ray-triangle test (Woop, Benthin, Wald 2013); crates/core/src/bvh.rs has the CPU twin of both and
// tests/traversal.rs checks GPU, twin and obvhs' own CPU traversal agree.
//
// Nodes and triangles are read with textureLoad from 16-byte texels, not from storage buffers: on
// lavapipe a storage-buffer load with a per-lane address is a scalar loop over the SIMD lanes with a
// branch per lane and per component, while a texel fetch is one vector gather. That alone made the
// traversal 3x faster (docs/bvh.md).
#import common/scene.wgsl
#import common/alpha.wgsl

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
}

struct Hit {
    t: f32,
    slot: u32,
    // Barycentrics: p = (1 - u - v) v0 + u v1 + v v2.
    u: f32,
    v: f32,
}

fn safe_inverse(x: f32) -> f32 {
    let eps = 1.1920929e-7;
    if abs(x) <= eps {
        return select(-1.0, 1.0, x >= 0.0) / eps;
    }
    return 1.0 / x;
}

// Entry distance of the ray into the box, or INF when it misses. The exit distance is scaled by
// 1 + 2 gamma(3) (Ize 2013, "Robust BVH ray traversal"): the rounding of the slab distances can no
// longer make a ray that touches a box (a triangle's edge lies on its box) miss it.
fn aabb_entry(bmin: vec3<f32>, bmax: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>) -> f32 {
    let t1 = (bmin - origin) * inv_dir;
    let t2 = (bmax - origin) * inv_dir;
    let lo = min(t1, t2);
    let hi = max(t1, t2);
    let tn = max(lo.x, max(lo.y, lo.z));
    let tf = min(hi.x, min(hi.y, hi.z)) * BOX_EXIT_SCALE;
    if tf >= tn && tf >= 0.0 {
        return tn;
    }
    return INF;
}

fn load_node(i: u32) -> BvhNode {
    let a = textureLoad(bvh_texels, texel_xy(2u * i), 0);
    let b = textureLoad(bvh_texels, texel_xy(2u * i + 1u), 0);
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

// 1 + 2 gamma(3), gamma(n) = n u / (1 - n u), u = 2^-24 (Ize 2013; crates/core/src/bvh.rs has the same constant).
const BOX_EXIT_SCALE: f32 = 1.0000004;

// Per-ray constants of the watertight ray-triangle test (Woop, Benthin and Wald 2013): the axis `k.z`
// where the direction is largest becomes z, `k.x` and `k.y` the other two (swapped when the ray runs
// towards -z, which keeps the triangles' winding), and the shear `s` that maps the ray onto +z.
struct RayShear {
    k: vec3<u32>,
    s: vec3<f32>,
}

fn ray_shear(dir: vec3<f32>) -> RayShear {
    let a = abs(dir);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if dir[kz] < 0.0 {
        let t = kx;
        kx = ky;
        ky = t;
    }
    let dz = dir[kz];
    return RayShear(vec3<u32>(kx, ky, kz), vec3<f32>(dir[kx] / dz, dir[ky] / dz, 1.0 / dz));
}

// A vertex relative to the ray origin in the ray's sheared frame: (x, y) on the ray's image plane,
// z still to be scaled by s.z.
fn shear_vertex(p: vec3<f32>, ray: Ray, sh: RayShear) -> vec3<f32> {
    let a = p - ray.origin;
    let z = a[sh.k.z];
    return vec3<f32>(a[sh.k.x] - sh.s.x * z, a[sh.k.y] - sh.s.y * z, z);
}

// The 2D edge function p.x q.y - p.y q.x of the edge (p, q), evaluated with the two end points in a
// fixed order (the lexicographically smaller first) and negated when swapped. The triangles that
// share an edge thus get bit-exact opposite values even where the compiler fuses the multiply-add
// (FMA), so a ray through the edge is inside at least one of them.
fn edge_fn(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let swap = q.x < p.x || (q.x == p.x && q.y < p.y);
    let a = select(p, q, swap);
    let b = select(q, p, swap);
    let e = a.x * b.y - a.y * b.x;
    return select(e, -e, swap);
}

// Watertight ray-triangle test (Woop, Benthin and Wald 2013). Returns (t, u, v) with barycentrics
// p = (1 - u - v) v0 + u v1 + v v2; t = INF on a miss or outside [tmin, tmax]. A ray through an edge
// or a vertex (edge function 0, also -0.0) hits; a ray in the triangle's plane (det 0) misses.
fn intersect_tri(slot: u32, ray: Ray, sh: RayShear) -> vec3<f32> {
    let a = shear_vertex(textureLoad(tri_texels, texel_xy(3u * slot), 0).xyz, ray, sh);
    let b = shear_vertex(textureLoad(tri_texels, texel_xy(3u * slot + 1u), 0).xyz, ray, sh);
    let c = shear_vertex(textureLoad(tri_texels, texel_xy(3u * slot + 2u), 0).xyz, ray, sh);
    let u = edge_fn(c.xy, b.xy);
    let v = edge_fn(a.xy, c.xy);
    let w = edge_fn(b.xy, a.xy);
    let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    if !outside && det != 0.0 {
        let t = (u * a.z + v * b.z + w * c.z) * sh.s.z / det;
        if t >= ray.tmin && t <= ray.tmax {
            return vec3<f32>(t, v / det, w / det);
        }
    }
    return vec3<f32>(INF, 0.0, 0.0);
}

// The while-while form (Aila and Laine 2009) of the stackless preorder walk: first walk inner nodes
// until the ray stands at an entered leaf (this function), then test the leaf (the callers). SIMD
// lanes that reach a leaf wait for the others, so leaves are tested by more lanes at once.
// From node `i`, follow the preorder (a missed inner node is skipped with its link) to the next leaf
// whose box the ray enters before `tmax`: true with `i` and `leaf` set to it, false when the walk ends.
fn walk_to_leaf(i: ptr<function, u32>, leaf: ptr<function, BvhNode>, origin: vec3<f32>, inv_dir: vec3<f32>, tmax: f32) -> bool {
    while *i < scene.num_nodes {
        let node = load_node(*i);
        let entered = aabb_entry(node.min, node.max, origin, inv_dir) < tmax;
        if node.prim_count > 0u {
            if entered {
                *leaf = node;
                return true;
            }
            *i += 1u;
        } else {
            *i = select(node.index, *i + 1u, entered);
        }
    }
    return false;
}

// The BVH walk of `trace_closest` and `trace_any`: the closest hit along the ray, or with
// `any_hit` the first hit found; hit.slot == INVALID on a miss.
fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    var ray = ray_in;
    ray.tmax = min(ray.tmax, INF);
    var hit = Hit(INF, INVALID, 0.0, 0.0);
    let inv_dir = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    let sh = ray_shear(ray.dir);
    var i = 0u;
    var node: BvhNode;
    while walk_to_leaf(&i, &node, ray.origin, inv_dir, ray.tmax) {
        let count = node.prim_count & ~ALPHA_LEAF;
        if HAS_ALPHA_TEST && (node.prim_count & ALPHA_LEAF) != 0u {
            for (var k = node.index; k < node.index + count; k++) {
                let r = intersect_tri(k, ray, sh);
                if r.x < ray.tmax && alpha_passes(k, r.y, r.z) {
                    ray.tmax = r.x;
                    hit = Hit(r.x, k, r.y, r.z);
                    if any_hit {
                        return hit;
                    }
                }
            }
        } else {
            for (var k = node.index; k < node.index + count; k++) {
                let r = intersect_tri(k, ray, sh);
                if r.x < ray.tmax {
                    ray.tmax = r.x;
                    hit = Hit(r.x, k, r.y, r.z);
                    if any_hit {
                        return hit;
                    }
                }
            }
        }
        i += 1u;
    }
    return hit;
}

// Closest hit along the ray; hit.slot == INVALID on a miss.
fn trace_closest(ray: Ray) -> Hit {
    return trace(ray, false);
}

// Any hit in [tmin, tmax]: true when the segment is blocked.
fn trace_any(ray: Ray) -> bool {
    return trace(ray, true).slot != INVALID;
}

// vpl_visible's shadow ray from p (offset along its normal n) to q (offset along its normal qn),
// ending short of q's offset point; tmax < 0 where the two offset points coincide.
fn shadow_ray(p: vec3<f32>, n: vec3<f32>, q: vec3<f32>, qn: vec3<f32>) -> Ray {
    let o = offset_origin(p, n);
    let t = offset_origin(q, qn);
    let d = t - o;
    let dist = length(d);
    if !(dist > 0.0) {
        return Ray(o, vec3<f32>(0.0, 0.0, 1.0), 0.0, -1.0);
    }
    return Ray(o, d / dist, 0.0, dist * (1.0 - 1e-4));
}

// V(p, q) of Eq. (5), the shadow ray between two surface points: the segment from p (offset along
// its normal n) to q (offset along its normal qn) is free. CPU twin: `CpuScene::vpl_visible`.
fn vpl_visible(p: vec3<f32>, n: vec3<f32>, q: vec3<f32>, qn: vec3<f32>) -> bool {
    let ray = shadow_ray(p, n, q, qn);
    if ray.tmax < 0.0 {
        return false;
    }
    return !trace_any(ray);
}

// Whether triangle `slot` blocks vpl_visible's ray from p to q, as trace_any counts a hit (the same
// test, alpha included): then V(p, q) = 0 without a walk. False says nothing: another triangle may
// block the ray. The ray of coinciding ends is blocked, as vpl_visible has it.
fn shadow_ray_blocked_by(slot: u32, p: vec3<f32>, n: vec3<f32>, q: vec3<f32>, qn: vec3<f32>) -> bool {
    let ray = shadow_ray(p, n, q, qn);
    if ray.tmax < 0.0 {
        return true;
    }
    let r = intersect_tri(slot, ray, ray_shear(ray.dir));
    return r.x < ray.tmax && alpha_passes(slot, r.y, r.z);
}
