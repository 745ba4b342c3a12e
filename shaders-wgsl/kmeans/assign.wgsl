// Alg. 2: every point to its F nearest centroids with the weights of Eq. (10).
#import common/kmeans.wgsl
#import common/nearest.wgsl

// Eq. (10), generalised to w'_f = dist_f^-p (the paper's §6 asks for a faster fall-off under a
// parameter; p = 1 is Eq. 10, p = 0 Eq. 8's mean, large p tends to hard clustering). Computed as
// (d_min / d_f)^p / Σ (d_min / d_f)^p, ratios in (0, 1]: no overflow for any distance or p. Slots at
// or past `count` (and negative distances) get 0; a distance of 0 (`zero`) takes the whole weight.
// CPU twin: cpu::kmeans::eq10_weights.
// A distance at or below this counts as 0 (the point sits on the centroid): below it a GPU may flush
// the quotient d_min / d to 0 / 0.
const ZERO_DIST: f32 = 1e-30;

// x^p for x in (0, 1]: exact for p = 1 (Eq. 10) and p = 0, else exp2(p log2 x).
fn ratio_pow(x: f32, p: f32) -> f32 {
    if p == 1.0 {
        return x;
    }
    if p == 0.0 {
        return 1.0;
    }
    return exp2(p * log2(x));
}

// The weights go to `*w` (slots from F on untouched). Arrays go by pointer, never by value
// (docs/architecture.md, "WGSL for real GPUs"). Every loop runs over the pipeline's F slots (a
// constant) with the count as a guard, so the arrays stay in registers: a loop to the run-time count
// indexes them at run time, which put them in memory (on lavapipe a per-lane scatter; final_assign
// spent more time here than in its search).
fn eq10_weights(d: ptr<function, array<f32, MAX_F>>, count: u32, zero: u32, w: ptr<function, array<f32, MAX_F>>) {
    var d_min = 3.4e38;
    for (var j = 0u; j < F; j++) {
        (*w)[j] = 0.0;
        if j < count && (*d)[j] >= 0.0 {
            d_min = min(d_min, (*d)[j]);
        }
    }
    var wsum = 0.0;
    for (var j = 0u; j < F; j++) {
        if j < count && (*d)[j] >= 0.0 {
            if zero != INVALID {
                (*w)[j] = select(0.0, 1.0, j == zero);
            } else {
                (*w)[j] = ratio_pow(d_min / (*d)[j], params.weight_exponent);
            }
            wsum += (*w)[j];
        }
    }
    if zero == INVALID && wsum > 0.0 {
        for (var j = 0u; j < F; j++) {
            (*w)[j] /= wsum;
        }
    }
}

// The plane gate (off unless asked; not in the paper): slot j >= 2 keeps cluster k only when its
// centroid lies within the gate's angle of the point's tangent plane, seen from the point. Eq. (7)
// gates on normals alone, so a pixel's F nearest clusters include parallel surfaces above or below
// it (a chair seat over the floor), whose visibility differs. The first slot is always kept, and a
// centroid on the point (|d| = 0) passes. CPU twin: cpu::kmeans::plane_gate_keeps.
fn plane_gate_keeps(p: vec3<f32>, n: vec3<f32>, k: u32) -> bool {
    let d = centroids[k].pos.xyz - p;
    return abs(dot(n, d)) <= params.plane_gate * length(d);
}

// --- Alg. 2: every data point to its F nearest centroids with normalised inverse-distance weights
// (Eq. 10). A point on a centroid (distance 0) takes that cluster's whole weight.
@compute @workgroup_size(64)
fn final_assign(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    let p = point_pos(m);
    var b = empty_nearest();
    var n = vec3<f32>(0.0);
    if p.w > 0.0 {
        n = point_nrm(m);
        b = nearest(p.xyz, n, f);
    }
    var zero = INVALID;
    // A slot the plane gate drops gets distance -1: weight 0 (eq10_weights) and no
    // cluster below. (Off, the pipeline is built without the test: see PLANE_GATE.)
    var dists: array<f32, MAX_F>;
    for (var j = 0u; j < F; j++) {
        dists[j] = b.dist[j];
        if PLANE_GATE && j > 0u && j < b.count && !plane_gate_keeps(p.xyz, n, b.idx[j]) {
            dists[j] = -1.0;
        }
        if j < b.count && b.dist[j] <= ZERO_DIST && zero == INVALID {
            zero = j;
        }
    }
    var w: array<f32, MAX_F>;
    eq10_weights(&dists, b.count, zero, &w);
    for (var j = 0u; j < f; j++) {
        var k = INVALID;
        if j < b.count && dists[j] >= 0.0 {
            k = b.idx[j];
            // Representatives, step 2 (rep_min): the smallest member distance per cluster
            // (non-negative floats order like their bits).
            let bits = bitcast<u32>(b.dist[j]);
            // Only when it can lower the minimum: every member's atomic on its cluster's one word
            // (4.4M on 1000 words at 1024x720, F 6) serialised the pass on a GPU.
            if bits < atomicLoad(&reps[2u * k]) {
                atomicMin(&reps[2u * k], bits);
            }
            member_dists[m * f + j] = bits;
        }
        assign[m * f + j] = k;
        weights[m * f + j] = w[j];
    }
}
