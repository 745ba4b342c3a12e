// Alg. 1 line 5: the uniform grid over the centroids that the nearest-centroid search reads: the
// shared centre grid (common/grid.wgsl: the bounds, count, prefix sum and scatter passes) over
// `centroids`, and the grid setup with Alg. 1's per-iteration bookkeeping.
#import common/kmeans.wgsl

// What common/grid.wgsl reads of the centres: the centroids; nothing once Alg. 1's loop has ended.
fn grid_centres() -> u32 {
    return params.k;
}

fn grid_centre_pos(k: u32) -> vec4<f32> {
    return centroids[k].pos;
}

fn grid_centre_nrm(k: u32) -> vec4<f32> {
    return centroids[k].nrm;
}

fn grid_live() -> bool {
    return !stopped();
}

// Step 2 (one invocation): the grid from the centroids' bounds (`grid_build`, without wang's guard
// for centres along a line), and the iteration's bookkeeping.
@compute @workgroup_size(1)
fn grid_setup() {
    if stopped() {
        return;
    }
    // Whether the iteration that follows changes any assignment (assign_sampled) or re-seeds a
    // cluster (update), and whether it finds an orphan.
    atomicStore(&bounds[6], 0u);
    atomicStore(&bounds[8], 0u);
    // Grid builds so far: the iteration's number (1 in the first) for the re-seeding draw.
    let iteration = atomicAdd(&bounds[7], 1u) + 1u;
    // The empty cluster this iteration's update will name (the previous update's stays readable).
    atomicStore(&bounds[9u + (iteration & 1u)], 0u);
    grid_build(params.k, params.lo.xyz, params.ext, false);
}
