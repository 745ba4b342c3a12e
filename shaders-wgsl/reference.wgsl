// The unclustered reference (Eq. 5): every shading point gathers every VPL with its own shadow ray
// (or, as wang's and colom's gather, every VPL-cluster light: eq5_cluster_radiance).
// Runs as bounded dispatches over pixel ranges x VPL ranges, accumulating into `indirect`.
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/pixel.wgsl
#import common/gbuffer.wgsl
#import common/vpl.wgsl

struct RefParams {
    d_min2: f32,
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: RefParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read> vpls: array<Vpl>;
@group(1) @binding(4) var<storage, read_write> indirect: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = surface_item(gid, nwg);
    if i != INVALID {
        indirect[i] += vec4<f32>(gather_all(gbuffer[i]), 0.0);
    }
}

// Eq. (5) at shading point `sp` over the chunk's VPL range: every VPL with its own shadow ray.
fn gather_all(sp: ShadingPoint) -> vec3<f32> {
    let p = sp.pos.xyz;
    let n = sp.nrm.xyz;
    var sum = vec3<f32>(0.0);
    for (var j = chunk.sub_offset; j < chunk.sub_offset + chunk.sub_count; j++) {
        let v = vpls[j];
        let c = eq5_cluster_radiance(p, n, sp.albedo.xyz, v, params.d_min2);
        if any(c > vec3<f32>(0.0)) && vpl_visible(p, n, v.pos.xyz, v.nrm.xyz) {
            sum += c;
        }
    }
    return sum;
}
