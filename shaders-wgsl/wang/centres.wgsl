// The centres: the first ones at the seeds, then §3.2's update (the members' mean position and
// normal) after each assignment; each written centre grows the grid's bounds (common/grid.wgsl).
#import wang/common.wgsl

fn seed_count() -> u32 {
    return atomicLoad(&tree[2u]);
}

// Every pixel starts without a cluster (the assignment adds a pixel to its cluster's sums when its
// label changes).
@compute @workgroup_size(64)
fn init_labels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == 0u {
        for (var a = 0u; a < 3u; a++) {
            atomicStore(&bounds[a], 0xffffffffu);
            atomicStore(&bounds[3u + a], 0u);
        }
    }
    if m < params.pixels {
        labels[m] = INVALID;
    }
}

// The first centres: the seeds' shading points (clusters past the seeds, where the image has fewer
// valid grid pixels than K, stay empty); the sums start at zero.
@compute @workgroup_size(64)
fn seed_centres(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    var c = vec4<f32>(0.0);
    var nrm = vec4<f32>(0.0);
    if j < seed_count() {
        let sp = gbuffer[atomicLoad(&tree[params.seeds_base + j])];
        c = vec4<f32>(sp.pos.xyz, 1.0);
        nrm = vec4<f32>(sp.nrm.xyz, 0.0);
    }
    centres[2u * j] = c;
    centres[2u * j + 1u] = nrm;
    for (var w = 0u; w < WORDS; w++) {
        atomicStore(&sums[WORDS * j + w], 0u);
    }
    add_to_bounds(c);
}

fn mean64(i: u32, count: u32) -> f32 {
    let lo = atomicLoad(&sums[i]);
    let hi = atomicLoad(&sums[i + 1u]);
    return (f32(hi) * 4294967296.0 + f32(lo)) / f32(count);
}

// §3.2: "we recompute the cluster center by averaging the position and normal of all cluster
// members": mean position, normalised mean normal (kept when the normals cancel); a cluster without
// members keeps its place but leaves the grid (w = 0).
@compute @workgroup_size(64)
fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let base = WORDS * j;
    let count = atomicLoad(&sums[base + 12u]);
    var c = centres[2u * j];
    if count > 0u {
        let rel = vec3<f32>(mean64(base, count), mean64(base + 2u, count), mean64(base + 4u, count)) / POS_SCALE;
        let nrm = vec3<f32>(mean64(base + 6u, count), mean64(base + 8u, count), mean64(base + 10u, count)) / NRM_SCALE - 1.0;
        c = vec4<f32>(params.lo.xyz + rel * params.ext.xyz, 1.0);
        let l = length(nrm);
        if l > 1e-6 {
            centres[2u * j + 1u] = vec4<f32>(nrm / l, 0.0);
        }
    } else {
        c.w = 0.0;
    }
    centres[2u * j] = c;
    add_to_bounds(c);
}

