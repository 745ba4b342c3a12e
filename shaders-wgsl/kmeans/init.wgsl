// Alg. 1 line 2: the initial centroids (stratified, or kept from the previous frame: temporal reuse).
#import common/kmeans.wgsl

// --- Alg. 1 line 2: initial centroids, stratified over the (sampled) data: centroid k takes the
// first valid sampled point of stratum k of the sampled sequence.
fn stratum_centroid(k: u32) -> Centroid {
    let s0 = u32(u64_mul_div(k, params.num_sampled, params.k));
    let s1 = max(u32(u64_mul_div(k + 1u, params.num_sampled, params.k)), s0 + 1u);
    var c: Centroid;
    c.pos = vec4<f32>(0.0);
    c.nrm = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    for (var s = s0; s < min(s1, params.num_sampled); s++) {
        let m = sample_index(s);
        let p = point_pos(m);
        if p.w > 0.0 {
            c.pos = vec4<f32>(p.xyz, 1.0);
            c.nrm = vec4<f32>(point_nrm(m), 0.0);
            break;
        }
    }
    return c;
}

fn set_initial(k: u32, c: Centroid) {
    if c.pos.w == 0.0 {
        name_empty(k, 0u);
    }
    centroids[k] = c;
    add_to_bounds(c.pos);
}

@compute @workgroup_size(64)
fn init_centroids(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    set_initial(k, stratum_centroid(k));
}

// Temporal warm start (not in the paper; its §5 names temporal coherence as future work): Alg. 1
// starts from the previous frame's clusters, whose centroids and representative points the host
// copied into `centroids` and `rep_points` [0, previous K). A previous cluster is kept where the new
// view still sees its representative (a real surface point, unlike the centroid, which may float
// between parallel surfaces of one cluster): warm_keeps. Its representative becomes a candidate for
// reuse (rep_store). Every other cluster starts from its stratum as in init_centroids. Counts the
// kept ones in bounds[11].
@compute @workgroup_size(64)
fn warm_centroids(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    if k < params.warm_size.z {
        let c = centroids[k];
        let r = rep_points[2u * k];
        let rn = rep_points[2u * k + 1u];
        let seen = params.warm_size.x == 0u || (r.w > 0.0 && warm_keeps(r.xyz, rn.xyz));
        if c.pos.w > 0.0 && seen {
            atomicAdd(&bounds[11], 1u);
            rep_points[2u * k + 1u] = vec4<f32>(rn.xyz, 1.0);
            set_initial(k, c);
            return;
        }
    }
    rep_points[2u * k + 1u].w = 0.0;
    set_initial(k, stratum_centroid(k));
}

// A surface point of the previous frame (position q, normal nq) is still seen by the new view when it
// projects into the image, the pixel there has a shading point whose normal agrees with nq by Eq. (7),
// and q lies on that point's tangent plane within eye.w times the point's eye distance (a point now
// hidden behind nearer geometry lies farther off).
fn warm_keeps(q: vec3<f32>, nq: vec3<f32>) -> bool {
    let w = params.warm_size.x;
    let h = params.warm_size.y;
    let v = q - params.warm_eye.xyz;
    let z = dot(v, params.warm_forward.xyz);
    if !(z > 0.0) {
        return false;
    }
    let r = params.warm_right.xyz;
    let u = params.warm_up.xyz;
    let sx = dot(v, r) / (z * dot(r, r));
    let sy = dot(v, u) / (z * dot(u, u));
    let x = (sx + 1.0) * 0.5 * f32(w);
    let y = (1.0 - sy) * 0.5 * f32(h);
    if !(x >= 0.0 && y >= 0.0 && x < f32(w) && y < f32(h)) {
        return false;
    }
    let m = min(u32(y), h - 1u) * w + min(u32(x), w - 1u);
    if m >= params.num_points {
        return false;
    }
    let p = point_pos(m);
    if p.w <= 0.0 {
        return false;
    }
    let n = point_nrm(m);
    if !eq7_normals_agree(n, nq) {
        return false;
    }
    let tol = params.warm_eye.w * length(p.xyz - params.warm_eye.xyz);
    return abs(dot(n, q - p.xyz)) <= tol;
}

// floor(a * b / c) without 32-bit overflow for a, b < 2^32 (a < c).
fn u64_mul_div(a: u32, b: u32, c: u32) -> f32 {
    return floor(f32(a) * (f32(b) / f32(c)));
}

// Before the first iteration: no sampled point has a cluster yet (its sums are all zero).
@compute @workgroup_size(64)
fn init_sampled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let s = chunk_item(gid, nwg);
    if s == INVALID || s >= params.num_sampled {
        return;
    }
    sample_assign[s] = INVALID;
}
