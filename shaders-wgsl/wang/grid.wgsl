// The grid over the centres that the assignment searches: common/grid.wgsl's (as colom's k-means,
// kmeans/grid.wgsl), over `centres`, built after every update.
#import wang/common.wgsl

// What common/grid.wgsl reads of the centres (two vec4 a cluster: position with w = 1 while it has
// members, normal); the grid passes always run.
fn grid_centres() -> u32 {
    return params.k;
}

fn grid_centre_pos(k: u32) -> vec4<f32> {
    return centres[2u * k];
}

fn grid_centre_nrm(k: u32) -> vec4<f32> {
    return centres[2u * k + 1u];
}

fn grid_live() -> bool {
    return true;
}

// The grid from the centres' bounds (one invocation), with the guard for centres along a line
// (`grid_build`).
@compute @workgroup_size(1)
fn grid_setup() {
    grid_build(params.k, params.lo.xyz, params.ext, true);
}
