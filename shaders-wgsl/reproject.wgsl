// The last frame as displayed, shown from the current camera while the next one renders, on the GPU
// (app::reproject_gpu; the shared display path, where nothing is read back). Forward splatting with
// a depth test, as the Render Cache of Walter et al. 1999 reduced to one frame:
// 1. `clear`: every new pixel's depth and source are "none".
// 2. `splat_depth`: each old pixel's shading point is projected into the new view and its depth
//    along the new view kept by an atomic min over a footprint as large as its projected size
//    (1 to 3 pixels across); pixels that saw nothing splat as directions, behind every surface.
// 3. `splat_source`: the old pixels whose depth won keep their index, the least one on a tie (an
//    atomic min again: the result does not depend on the order the GPU runs them in).
// 4. `resolve`: each new pixel takes its source's displayed colour; a pixel no splat reached takes
//    the mean of the reached ones in the 7 × 7 around it, else black.
// Its CPU twin is `cpu::reproject`.
#import common/gbuffer.wgsl
#import common/camera.wgsl

struct ReprojectParams {
    // The old frame's camera and the new one (render units, the old frame's size).
    old: CameraParams,
    new_cam: CameraParams,
}

@group(0) @binding(0) var<uniform> params: ReprojectParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<ShadingPoint>;
// Per new pixel: the winning depth (f32 bits; 0xffffffff none) and the winning old pixel.
@group(0) @binding(2) var<storage, read_write> depth: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> source: array<atomic<u32>>;
@group(0) @binding(4) var old_image: texture_2d<f32>;
@group(0) @binding(5) var out_image: texture_storage_2d<rgba8unorm, write>;

const NONE: u32 = 0xffffffffu;
// The depth a direction (sky) splats with: behind every surface, ahead of "none".
const SKY_DEPTH: u32 = 0x7f7fffffu;

fn width() -> u32 {
    return params.old.size.x;
}

fn height() -> u32 {
    return params.old.size.y;
}

fn axis(v: vec4<f32>) -> vec3<f32> {
    return v.xyz;
}

// Where direction `d` from the new eye lands (pixels) and its depth along the new view; z <= 0 behind
// the eye (`CameraParams::project`, near 1e-6).
fn project_new(d: vec3<f32>) -> vec3<f32> {
    let c = params.new_cam;
    let z = dot(d, axis(c.forward));
    if !(z > 1e-6 * length(d)) {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    let r = axis(c.right);
    let u = axis(c.up);
    let sx = dot(d, r) / (z * dot(r, r));
    let sy = dot(d, u) / (z * dot(u, u));
    return vec3<f32>((sx + 1.0) * 0.5 * f32(width()), (1.0 - sy) * 0.5 * f32(height()), z);
}

// The old pixel i's ray direction (`CameraParams::ray` through its centre).
fn old_ray(i: u32) -> vec3<f32> {
    let x = f32(i % width()) + 0.5;
    let y = f32(i / width()) + 0.5;
    let sx = 2.0 * x / f32(width()) - 1.0;
    let sy = 1.0 - 2.0 * y / f32(height());
    return axis(params.old.forward) + sx * axis(params.old.right) + sy * axis(params.old.up);
}

// Old pixel i's splat: its centre in the new image, the depth key, and the footprint's half width
// (0: none); `found` false when it lands behind the new eye.
struct Splat {
    centre: vec2<f32>,
    key: u32,
    half: i32,
    found: bool,
}

fn splat_of(i: u32) -> Splat {
    let sp = gbuffer[i];
    var s: Splat;
    s.found = false;
    if sp.pos.w > 0.0 {
        let d = sp.pos.xyz - axis(params.new_cam.eye);
        let p = project_new(d);
        if p.z <= 0.0 {
            return s;
        }
        // The pixel's projected size: its depth along the old view over that along the new.
        let old_z = dot(sp.pos.xyz - axis(params.old.eye), axis(params.old.forward));
        let grow = clamp(old_z / p.z, 1.0, 3.0);
        s.centre = p.xy;
        s.key = min(bitcast<u32>(p.z), SKY_DEPTH - 1u);
        s.half = i32(ceil(grow * 0.5 - 0.5));
        s.found = true;
    } else {
        let p = project_new(old_ray(i));
        if p.z <= 0.0 {
            return s;
        }
        s.centre = p.xy;
        s.key = SKY_DEPTH;
        s.half = 0;
        s.found = true;
    }
    return s;
}

// The new pixel at offset (dx, dy) from the splat's centre pixel, or NONE outside the image.
fn target_of(s: Splat, dx: i32, dy: i32) -> u32 {
    let x = i32(floor(s.centre.x)) + dx;
    let y = i32(floor(s.centre.y)) + dy;
    if x < 0 || y < 0 || x >= i32(width()) || y >= i32(height()) {
        return NONE;
    }
    return u32(y) * width() + u32(x);
}

fn pixel(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) g: vec3<u32>) {
    let i = pixel(id, g);
    if i < width() * height() {
        atomicStore(&depth[i], NONE);
        atomicStore(&source[i], NONE);
    }
}

// Old pixel i's splat over its footprint: the depth test (an atomic min of its key), or, once every
// depth is in (`winners`), its index where its key won (the least index on a tie).
fn splat(i: u32, winners: bool) {
    if i >= width() * height() {
        return;
    }
    let s = splat_of(i);
    if !s.found {
        return;
    }
    for (var dy = -s.half; dy <= s.half; dy++) {
        for (var dx = -s.half; dx <= s.half; dx++) {
            let t = target_of(s, dx, dy);
            if t == NONE {
                continue;
            }
            if !winners {
                atomicMin(&depth[t], s.key);
            } else if atomicLoad(&depth[t]) == s.key {
                atomicMin(&source[t], i);
            }
        }
    }
}

@compute @workgroup_size(64)
fn splat_depth(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) g: vec3<u32>) {
    splat(pixel(id, g), false);
}

@compute @workgroup_size(64)
fn splat_source(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) g: vec3<u32>) {
    splat(pixel(id, g), true);
}

fn colour_of(src: u32) -> vec4<f32> {
    return textureLoad(old_image, vec2<i32>(i32(src % width()), i32(src / width())), 0);
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= width() || id.y >= height() {
        return;
    }
    let t = id.y * width() + id.x;
    let src = atomicLoad(&source[t]);
    var c = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    if src != NONE {
        c = colour_of(src);
    } else {
        // A hole: the mean of the reached pixels around it (8-bit values, summed exactly).
        var sum = vec3<f32>(0.0);
        var n = 0.0;
        for (var dy = -3; dy <= 3; dy++) {
            for (var dx = -3; dx <= 3; dx++) {
                let x = i32(id.x) + dx;
                let y = i32(id.y) + dy;
                if x >= 0 && y >= 0 && x < i32(width()) && y < i32(height()) {
                    let q = atomicLoad(&source[u32(y) * width() + u32(x)]);
                    if q != NONE {
                        sum += round(colour_of(q).xyz * 255.0);
                        n += 1.0;
                    }
                }
            }
        }
        if n > 0.0 {
            c = vec4<f32>(floor(sum / n + 0.5) / 255.0, 1.0);
        }
    }
    textureStore(out_image, vec2<i32>(id.xy), vec4<f32>(c.xyz, 1.0));
}
