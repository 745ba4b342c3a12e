// Software BVH2 traversal (stackless, skip links) with the same ray-box and Moller-Trumbore tests as
// obvhs' CPU code; tests/traversal.rs checks both agree.
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

// Entry distance of the ray into the box, or INF when it misses.
fn aabb_entry(bmin: vec3<f32>, bmax: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>) -> f32 {
    let t1 = (bmin - origin) * inv_dir;
    let t2 = (bmax - origin) * inv_dir;
    let lo = min(t1, t2);
    let hi = max(t1, t2);
    let tn = max(lo.x, max(lo.y, lo.z));
    let tf = min(hi.x, min(hi.y, hi.z));
    if tf >= tn && tf >= 0.0 {
        return tn;
    }
    return INF;
}

// Texel i of a data texture: TEXEL_ROW (4096) texels a row (src/gi/scene_gpu.rs).
fn texel_xy(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
}

fn load_node(i: u32) -> BvhNode {
    let a = textureLoad(bvh_texels, texel_xy(2u * i), 0);
    let b = textureLoad(bvh_texels, texel_xy(2u * i + 1u), 0);
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

// Returns (t, u, v); t = INF on a miss or outside [tmin, tmax].
fn intersect_tri(slot: u32, ray: Ray) -> vec3<f32> {
    let v0 = textureLoad(tri_texels, texel_xy(3u * slot), 0).xyz;
    let e1 = v0 - textureLoad(tri_texels, texel_xy(3u * slot + 1u), 0).xyz;
    let e2 = textureLoad(tri_texels, texel_xy(3u * slot + 2u), 0).xyz - v0;
    let n = cross(e1, e2);
    let c = v0 - ray.origin;
    let r = cross(ray.dir, c);
    let inv_det = 1.0 / dot(n, ray.dir);
    let u = dot(r, e2) * inv_det;
    let v = dot(r, e1) * inv_det;
    let w = 1.0 - u - v;
    let signs = (bitcast<u32>(u) | bitcast<u32>(v) | bitcast<u32>(w)) & 0x80000000u;
    if inv_det != 0.0 && signs == 0u && abs(inv_det) < INF {
        let t = dot(n, c) * inv_det;
        if t >= ray.tmin && t <= ray.tmax {
            return vec3<f32>(t, u, v);
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

// Closest hit along the ray; hit.slot == INVALID on a miss.
fn trace_closest(ray_in: Ray) -> Hit {
    var ray = ray_in;
    ray.tmax = min(ray.tmax, INF);
    var hit = Hit(INF, INVALID, 0.0, 0.0);
    let inv_dir = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    var i = 0u;
    var node: BvhNode;
    while walk_to_leaf(&i, &node, ray.origin, inv_dir, ray.tmax) {
        let count = node.prim_count & ~ALPHA_LEAF;
        if HAS_ALPHA_TEST && (node.prim_count & ALPHA_LEAF) != 0u {
            for (var k = node.index; k < node.index + count; k++) {
                let r = intersect_tri(k, ray);
                if r.x < ray.tmax && alpha_passes(k, r.y, r.z) {
                    ray.tmax = r.x;
                    hit = Hit(r.x, k, r.y, r.z);
                }
            }
        } else {
            for (var k = node.index; k < node.index + count; k++) {
                let r = intersect_tri(k, ray);
                if r.x < ray.tmax {
                    ray.tmax = r.x;
                    hit = Hit(r.x, k, r.y, r.z);
                }
            }
        }
        i += 1u;
    }
    return hit;
}

// Any hit in [tmin, tmax]: true when the segment is blocked.
fn trace_any(ray_in: Ray) -> bool {
    var ray = ray_in;
    ray.tmax = min(ray.tmax, INF);
    let inv_dir = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    var i = 0u;
    var node: BvhNode;
    while walk_to_leaf(&i, &node, ray.origin, inv_dir, ray.tmax) {
        let count = node.prim_count & ~ALPHA_LEAF;
        if HAS_ALPHA_TEST && (node.prim_count & ALPHA_LEAF) != 0u {
            for (var k = node.index; k < node.index + count; k++) {
                let r = intersect_tri(k, ray);
                if r.x < ray.tmax && alpha_passes(k, r.y, r.z) {
                    return true;
                }
            }
        } else {
            for (var k = node.index; k < node.index + count; k++) {
                if intersect_tri(k, ray).x < ray.tmax {
                    return true;
                }
            }
        }
        i += 1u;
    }
    return false;
}
