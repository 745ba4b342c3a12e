// Step 3 of the paper's frame: one primary ray per pixel centre -> a shading point (G-buffer).
#import common/bvh.wgsl
#import common/surface.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/camera.wgsl

@group(1) @binding(1) var<uniform> cam: CameraParams;
@group(1) @binding(2) var<storage, read_write> gbuffer: array<ShadingPoint>;

fn camera_ray(px: u32) -> Ray {
    let w = cam.size.x;
    let h = cam.size.y;
    let x = f32(px % w) + 0.5 + bitcast<f32>(cam.size.z);
    let y = f32(px / w) + 0.5 + bitcast<f32>(cam.size.w);
    let sx = 2.0 * x / f32(w) - 1.0;
    let sy = 1.0 - 2.0 * y / f32(h);
    let d = normalize(cam.forward.xyz + sx * cam.right.xyz + sy * cam.up.xyz);
    return Ray(cam.eye.xyz, d, 0.0, INF);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let ray = camera_ray(i);
    let hit = trace_closest(ray);
    var sp: ShadingPoint;
    if hit.slot == INVALID {
        sp.pos = vec4<f32>(0.0);
        sp.nrm = vec4<f32>(0.0, 0.0, 1.0, 0.0);
        sp.albedo = vec4<f32>(0.0);
        sp.emission = vec4<f32>(0.0);
    } else {
        let s = surface_at(hit.slot, hit.u, hit.v, ray.dir);
        // Position from the ray, not the barycentrics: it lies on the ray exactly.
        sp.pos = vec4<f32>(ray.origin + hit.t * ray.dir, 1.0);
        sp.nrm = vec4<f32>(s.n, bitcast<f32>(s.material));
        sp.albedo = vec4<f32>(s.albedo, 1.0);
        sp.emission = vec4<f32>(s.emission, 0.0);
    }
    gbuffer[i] = sp;
}
