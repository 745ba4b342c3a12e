// Software BVH2 traversal: the same stack traversal and Moller-Trumbore test as obvhs' CPU code
// (src/bvh.rs tests both against each other).
#import common/scene.wgsl

const STACK_SIZE: u32 = 64u;

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

// Returns (t, u, v); t = INF on a miss or outside [tmin, tmax].
fn intersect_tri(slot: u32, ray: Ray) -> vec3<f32> {
    let tri = tris[slot];
    let v0 = tri.v0.xyz;
    let e1 = v0 - tri.v1.xyz;
    let e2 = tri.v2.xyz - v0;
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

// Closest hit along the ray; hit.slot == INVALID on a miss.
fn trace_closest(ray_in: Ray) -> Hit {
    var ray = ray_in;
    // Misses report INF (the largest finite float): an infinite tmax must not count them as hits.
    ray.tmax = min(ray.tmax, INF);
    var hit = Hit(INF, INVALID, 0.0, 0.0);
    if scene.num_nodes == 0u {
        return hit;
    }
    let inv_dir = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    var stack: array<u32, STACK_SIZE>;
    var sp = 0u;
    let root = bvh_nodes[0];
    if aabb_entry(root.min, root.max, ray.origin, inv_dir) >= ray.tmax {
        return hit;
    }
    if root.prim_count > 0u {
        for (var i = root.first_index; i < root.first_index + root.prim_count; i++) {
            let r = intersect_tri(i, ray);
            if r.x < ray.tmax {
                ray.tmax = r.x;
                hit = Hit(r.x, i, r.y, r.z);
            }
        }
        return hit;
    }
    var current = root.first_index;
    loop {
        var left = bvh_nodes[current];
        var right = bvh_nodes[current + 1u];
        var tl = aabb_entry(left.min, left.max, ray.origin, inv_dir);
        var tr = aabb_entry(right.min, right.max, ray.origin, inv_dir);
        if tl > tr {
            let tn = left;
            left = right;
            right = tn;
            let tt = tl;
            tl = tr;
            tr = tt;
        }
        var go_left = tl < ray.tmax;
        if go_left && left.prim_count > 0u {
            for (var i = left.first_index; i < left.first_index + left.prim_count; i++) {
                let r = intersect_tri(i, ray);
                if r.x < ray.tmax {
                    ray.tmax = r.x;
                    hit = Hit(r.x, i, r.y, r.z);
                }
            }
            go_left = false;
        }
        var go_right = tr < ray.tmax;
        if go_right && right.prim_count > 0u {
            for (var i = right.first_index; i < right.first_index + right.prim_count; i++) {
                let r = intersect_tri(i, ray);
                if r.x < ray.tmax {
                    ray.tmax = r.x;
                    hit = Hit(r.x, i, r.y, r.z);
                }
            }
            go_right = false;
        }
        if go_left && go_right {
            current = left.first_index;
            if sp < STACK_SIZE {
                stack[sp] = right.first_index;
                sp += 1u;
            }
        } else if go_left {
            current = left.first_index;
        } else if go_right {
            current = right.first_index;
        } else {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            current = stack[sp];
        }
    }
    return hit;
}

// Any hit in [tmin, tmax]: true when the segment is blocked.
fn trace_any(ray_in: Ray) -> bool {
    var ray = ray_in;
    ray.tmax = min(ray.tmax, INF);
    if scene.num_nodes == 0u {
        return false;
    }
    let inv_dir = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    var stack: array<u32, STACK_SIZE>;
    var sp = 0u;
    let root = bvh_nodes[0];
    if aabb_entry(root.min, root.max, ray.origin, inv_dir) >= ray.tmax {
        return false;
    }
    if root.prim_count > 0u {
        for (var i = root.first_index; i < root.first_index + root.prim_count; i++) {
            if intersect_tri(i, ray).x < ray.tmax {
                return true;
            }
        }
        return false;
    }
    var current = root.first_index;
    loop {
        let left = bvh_nodes[current];
        let right = bvh_nodes[current + 1u];
        var go_left = aabb_entry(left.min, left.max, ray.origin, inv_dir) < ray.tmax;
        var go_right = aabb_entry(right.min, right.max, ray.origin, inv_dir) < ray.tmax;
        if go_left && left.prim_count > 0u {
            for (var i = left.first_index; i < left.first_index + left.prim_count; i++) {
                if intersect_tri(i, ray).x < ray.tmax {
                    return true;
                }
            }
            go_left = false;
        }
        if go_right && right.prim_count > 0u {
            for (var i = right.first_index; i < right.first_index + right.prim_count; i++) {
                if intersect_tri(i, ray).x < ray.tmax {
                    return true;
                }
            }
            go_right = false;
        }
        if go_left && go_right {
            current = left.first_index;
            if sp < STACK_SIZE {
                stack[sp] = right.first_index;
                sp += 1u;
            }
        } else if go_left {
            current = left.first_index;
        } else if go_right {
            current = right.first_index;
        } else {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            current = stack[sp];
        }
    }
    return false;
}
