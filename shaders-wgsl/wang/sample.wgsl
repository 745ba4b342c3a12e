// The sample points (§3.2: "in each cluster, we pick the shading point with the smallest error"):
// the least error per cluster (an atomic min of its bits, non-negative floats ordering as their bits),
// then the lowest pixel with it; each cluster's sample point written as wang.wgsl and the gather read
// it.
#import wang/common.wgsl

@compute @workgroup_size(64)
fn sample_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j == 0u {
        atomicStore(&bounds[USED], 0u);
    }
    if j >= params.k {
        return;
    }
    atomicStore(&sums[WORDS * j + 13u], 0xffffffffu);
    atomicStore(&sums[WORDS * j + 14u], INVALID);
}

// The pixel of invocation gid when it has a cluster, else INVALID.
fn labelled_pixel(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    let m = chunk_item(gid, nwg);
    if m >= params.pixels || labels[m] == INVALID {
        return INVALID;
    }
    return m;
}

@compute @workgroup_size(64)
fn sample_dist(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = labelled_pixel(gid, nwg);
    if m == INVALID {
        return;
    }
    let l = labels[m];
    let sp = gbuffer[m];
    let bits = bitcast<u32>(eq2_error(sp.pos.xyz, sp.nrm.xyz, centres[2u * l].xyz, centres[2u * l + 1u].xyz));
    labels[params.pixels + m] = bits;
    if bits < atomicLoad(&sums[WORDS * l + 13u]) {
        atomicMin(&sums[WORDS * l + 13u], bits);
    }
}

@compute @workgroup_size(64)
fn sample_pick(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = labelled_pixel(gid, nwg);
    if m == INVALID {
        return;
    }
    let l = labels[m];
    if labels[params.pixels + m] == atomicLoad(&sums[WORDS * l + 13u]) {
        atomicMin(&sums[WORDS * l + 14u], m);
    }
}

// Each cluster's sample point as wang.wgsl reads it and as a shading point of albedo 1 (all zero for
// an empty cluster); counts the clusters with one.
@compute @workgroup_size(64)
fn sample_store(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let m = atomicLoad(&sums[WORDS * j + 14u]);
    var p = vec4<f32>(0.0);
    var n = vec4<f32>(0.0);
    var albedo = vec4<f32>(0.0);
    if m != INVALID {
        let sp = gbuffer[m];
        p = vec4<f32>(sp.pos.xyz, 1.0);
        n = vec4<f32>(sp.nrm.xyz, 0.0);
        albedo = vec4<f32>(1.0, 1.0, 1.0, 0.0);
        atomicAdd(&bounds[USED], 1u);
    }
    samples[2u * j] = p;
    samples[2u * j + 1u] = n;
    sample_gbuffer[4u * j] = p;
    sample_gbuffer[4u * j + 1u] = n;
    sample_gbuffer[4u * j + 2u] = albedo;
    sample_gbuffer[4u * j + 3u] = vec4<f32>(0.0);
}
