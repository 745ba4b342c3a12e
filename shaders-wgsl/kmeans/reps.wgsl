// The clusters' representatives: the member nearest to each centroid, the point the visibility pass
// traces from.
#import common/kmeans.wgsl

// --- Representatives on real surfaces: the member (in any of its F slots) nearest to the centroid.
// Step 1 (before final_assign): clear. reps[2k] = smallest distance (float bits), reps[2k + 1] = member index.
@compute @workgroup_size(64)
fn rep_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    atomicStore(&reps[2u * k], 0xffffffffu);
    atomicStore(&reps[2u * k + 1u], 0xffffffffu);
}

// Step 2 is in final_assign. Step 3: the lowest-index member at that distance (the distance as
// final_assign stored it, not recomputed: a GPU may round one expression differently in two kernels).
@compute @workgroup_size(64)
fn rep_pick(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    for (var j = 0u; j < f; j++) {
        let k = assign[m * f + j];
        if k != INVALID && member_dists[m * f + j] == atomicLoad(&reps[2u * k]) {
            atomicMin(&reps[2u * k + 1u], m);
        }
    }
}

// Step 4: the representative as a point for the visibility pass. A cluster the warm start kept keeps
// its previous representative while that point is still one of it: its normal agrees with the
// centroid's by Eq. (7) and it lies within twice this frame's nearest member distance of the centroid
// (so it cannot drift away as the centroid moves); then its visibility stays the same from frame to
// frame. Otherwise the member rep_pick chose.
@compute @workgroup_size(64)
fn rep_store(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    let m = atomicLoad(&reps[2u * k + 1u]);
    if m == INVALID {
        rep_points[2u * k] = vec4<f32>(0.0);
        rep_points[2u * k + 1u] = vec4<f32>(0.0, 0.0, 1.0, 0.0);
        return;
    }
    let c = centroids[k];
    let r = rep_points[2u * k];
    let rn = rep_points[2u * k + 1u];
    if rn.w == 1.0 && r.w > 0.0 {
        let nearest = bitcast<f32>(atomicLoad(&reps[2u * k]));
        if eq7_dist(r.xyz, rn.xyz, c.pos.xyz, c.nrm.xyz) <= 2.0 * nearest {
            return;
        }
    }
    rep_points[2u * k] = vec4<f32>(point_pos(m).xyz, 1.0);
    rep_points[2u * k + 1u] = vec4<f32>(point_nrm(m), 0.0);
}

// The representatives' counts for the stats, kept on the GPU (bounds[15], [16]; read only when
// asked): clusters with a representative, and those below the previous K whose representative is the
// previous frame's (their visibility rows can be copied). A count a workgroup, then one atomic each.
var<workgroup> wg_reps: array<atomic<u32>, 2>;

@compute @workgroup_size(64)
fn rep_count(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let k = chunk_item(gid, nwg);
    if k != INVALID && k < params.k {
        if atomicLoad(&reps[2u * k + 1u]) != INVALID {
            atomicAdd(&wg_reps[0], 1u);
        }
        if k < params.warm_size.z && rep_points[2u * k].w > 0.0 && rep_points[2u * k + 1u].w == 1.0 {
            atomicAdd(&wg_reps[1], 1u);
        }
    }
    workgroupBarrier();
    if t == 0u {
        for (var i = 0u; i < 2u; i++) {
            let n = atomicLoad(&wg_reps[i]);
            if n > 0u {
                atomicAdd(&bounds[15u + i], n);
            }
        }
    }
}

// Optional step 5, Eq. (10) as the paper's text states it: w'_f = 1 / dist(p, p_f) with p_f the
// representative of cluster f (a real shading point) instead of its centroid (Alg. 2's W), and dist
// Eq. (7)'s metric: a representative whose normal fails n_t is at distance ∞, weight 0. Replaces the
// weights of final_assign, except for a point whose representatives all fail n_t, which keeps them
// (1/∞ over Σ 1/∞ has no value). The same exact case (distance 0 takes the whole weight). CPU twin:
// cpu::kmeans::rep_weights.
@compute @workgroup_size(64)
fn rep_weights(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    let p = point_pos(m).xyz;
    let n = point_nrm(m);
    var d: array<f32, MAX_F>;
    var zero = INVALID;
    var any_passes = false;
    for (var j = 0u; j < f; j++) {
        let k = assign[m * f + j];
        d[j] = -1.0;
        if k != INVALID {
            let r = atomicLoad(&reps[2u * k + 1u]);
            if r == INVALID || !eq7_normals_agree(n, point_nrm(r)) {
                continue;
            }
            d[j] = length(p - point_pos(r).xyz);
            any_passes = true;
            if d[j] <= ZERO_DIST && zero == INVALID {
                zero = j;
            }
        }
    }
    if !any_passes {
        return;
    }
    var w: array<f32, MAX_F>;
    eq10_weights(&d, f, zero, &w);
    for (var j = 0u; j < f; j++) {
        weights[m * f + j] = w[j];
    }
}
