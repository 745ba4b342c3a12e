// Temporal accumulation of the indirect light (`--temporal on`, crates/core/src/gi/accumulate.rs): each pixel's
// surface point is projected into the previous frame, that frame's accumulated indirect light is read
// there bilinearly from the taps that show the same surface (depth along the previous view and normal),
// and blended with this frame's: an exponential moving average over the frames that saw the point.
// CPU twin: crates/core/src/cpu/accumulate.rs.
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/camera.wgsl

struct AccumulateParams {
    // width, height (both frames); history: 1 when there is a previous frame, 0 for none; same_view:
    // 1 when the previous camera is this frame's (each pixel then reads its own history).
    size: vec4<u32>,
    // The previous frame's camera.
    prev: CameraParams,
    // x: alpha, the new frame's weight once the history is long (1 / frames of the average);
    // y: the depth tolerance (fraction of the depth); z: the normals' cosine tolerance.
    blend: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: AccumulateParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read> prev_gbuffer: array<ShadingPoint>;
@group(1) @binding(4) var<storage, read> prev_history: array<vec4<f32>>;
// In: this frame's indirect light; out: the accumulated light, w = the frames it averages.
@group(1) @binding(5) var<storage, read_write> indirect: array<vec4<f32>>;

// World point `q`'s image position (pixels, centres at + 0.5) and depth along the previous view;
// z <= 0 where it lies behind the eye (`CameraParams::project` with near = 1e-6).
fn project_prev(q: vec3<f32>) -> vec3<f32> {
    let d = q - params.prev.eye.xyz;
    let z = dot(d, params.prev.forward.xyz);
    if z <= 1e-6 * length(d) {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    let r = params.prev.right.xyz;
    let u = params.prev.up.xyz;
    let sx = dot(d, r) / (z * dot(r, r));
    let sy = dot(d, u) / (z * dot(u, u));
    return vec3<f32>((sx + 1.0) * 0.5 * f32(params.size.x), (1.0 - sy) * 0.5 * f32(params.size.y), z);
}

// History tap `j` shows the surface at depth `z` with normal `n`.
fn same_surface(j: u32, z: f32, n: vec3<f32>) -> bool {
    let q = prev_gbuffer[j];
    if q.pos.w <= 0.0 || dot(n, q.nrm.xyz) < params.blend.z {
        return false;
    }
    let pq = project_prev(q.pos.xyz);
    return pq.z > 0.0 && abs(pq.z - z) <= params.blend.y * z;
}

@compute @workgroup_size(64)
fn accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == 0xffffffffu {
        return;
    }
    let cur = indirect[i].xyz;
    let sp = gbuffer[i];
    if params.size.z == 0u || sp.pos.w <= 0.0 {
        indirect[i] = vec4<f32>(cur, 1.0);
        return;
    }
    let n = sp.nrm.xyz;
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    var sum = vec4<f32>(0.0);
    var wsum = 0.0;
    if params.size.w == 1u {
        // The same view: the pixel's own history, where it shows the same surface.
        let pq = project_prev(sp.pos.xyz);
        if pq.z > 0.0 && same_surface(i, pq.z, n) {
            sum = prev_history[i];
            wsum = 1.0;
        }
    } else {
        let pq = project_prev(sp.pos.xyz);
        if pq.z > 0.0 {
            let fx = pq.x - 0.5;
            let fy = pq.y - 0.5;
            let x0 = i32(floor(fx));
            let y0 = i32(floor(fy));
            let tx = fx - f32(x0);
            let ty = fy - f32(y0);
            for (var t = 0u; t < 4u; t++) {
                let dx = i32(t & 1u);
                let dy = i32(t >> 1u);
                let bx = select(1.0 - tx, tx, dx == 1);
                let by = select(1.0 - ty, ty, dy == 1);
                let wt = bx * by;
                let x = x0 + dx;
                let y = y0 + dy;
                if wt <= 0.0 || x < 0 || y < 0 || x >= w || y >= h {
                    continue;
                }
                let j = u32(y * w + x);
                if same_surface(j, pq.z, n) {
                    sum += wt * prev_history[j];
                    wsum += wt;
                }
            }
        }
    }
    if wsum <= 1e-6 {
        indirect[i] = vec4<f32>(cur, 1.0);
        return;
    }
    let history = sum / wsum;
    let alpha = history_alpha(history.w, params.blend.x);
    indirect[i] = vec4<f32>(mix(history.xyz, cur, alpha), min(history.w + 1.0, 1.0 / params.blend.x));
}

// The new frame's weight after `frames` frames of history: their plain mean while the history is
// short (1 / (frames + 1)), then `alpha` (an exponential moving average over about 1 / alpha frames).
fn history_alpha(frames: f32, alpha: f32) -> f32 {
    return max(1.0 / (frames + 1.0), alpha);
}
