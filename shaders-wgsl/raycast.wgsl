// Batch ray queries for the traversal tests and the throughput benchmark (crates/core/src/gi/raycast.rs).
#import common/bvh.wgsl
#import common/chunk.wgsl

struct RayIn {
    // xyz origin, w tmin
    o: vec4<f32>,
    // xyz direction, w tmax
    d: vec4<f32>,
}

// mode 0: closest hit -> (t bits, slot, u bits, v bits); mode 1: any hit -> (occluded, 0, 0, 0).
struct RaycastParams {
    mode: u32,
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: RaycastParams;
@group(1) @binding(2) var<storage, read> rays_in: array<RayIn>;
@group(1) @binding(3) var<storage, read_write> hits_out: array<vec4<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let r = rays_in[i];
    let ray = Ray(r.o.xyz, r.d.xyz, r.o.w, r.d.w);
    if params.mode == 0u {
        let h = trace_closest(ray);
        hits_out[i] = vec4<u32>(bitcast<u32>(h.t), h.slot, bitcast<u32>(h.u), bitcast<u32>(h.v));
    } else {
        hits_out[i] = vec4<u32>(select(0u, 1u, trace_any(ray)), 0u, 0u, 0u);
    }
}
