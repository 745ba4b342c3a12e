// The direct light at rest, refined (crates/core/src/gi/refine.rs): the frame's emission + direct light becomes
// the running mean of its estimates, each new one blended in with weight 1 / n (n = the estimates so
// far, this one included), in place on the GPU. The CPU twin is the mean the viewer's split path
// takes in f64 (app::worker::Accumulation).
#import common/chunk.wgsl

struct RefineParams {
    // x: n, the estimates the mean holds after this one.
    n: vec4<u32>,
}

@group(1) @binding(1) var<uniform> params: RefineParams;
// The new estimate, a vec4 a pixel.
@group(1) @binding(2) var<storage, read> estimate: array<vec4<f32>>;
// In: the mean of the n − 1 estimates before; out: the mean of n.
@group(1) @binding(3) var<storage, read_write> mean: array<vec4<f32>>;

@compute @workgroup_size(64)
fn refine(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == 0xffffffffu {
        return;
    }
    let m = mean[i];
    let x = estimate[i];
    mean[i] = vec4<f32>(m.xyz + (x.xyz - m.xyz) / f32(params.n.x), m.w);
}
