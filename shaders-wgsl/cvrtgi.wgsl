// CVRTGI (Cosin Ayerbe & Patow 2022, seed 003; docs/cvrtgi.md): clustered voxels with VPLs as the lit
// surface. Entry points, each over a range of items (crates/core/src/gi/cvrtgi.rs bounds the dispatches):
// - visibility (§4.3): per exposed voxel face, the clusters its rays see (BVH rays);
// - escape: per VPL, the fractions of its light stopped at its surface and sent into the scene
//   (not in the paper);
// - gather (§4.4): per face, the irradiance from the lit clusters it sees (times each cluster's
//   conservation scale, not in the paper);
// - filter_faces (§4.4): one pass of the Gaussian filter over same-direction faces;
// - lookup (§4.5): per pixel, ρ/π times its voxel face's filtered irradiance.
// CPU twin: crates/core/src/method/cvrtgi/twin.rs (same names).
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/rng.wgsl
#import common/sampling.wgsl
#import common/vpl.wgsl

// CvParams, declared in Rust (crates/core/src/method/cvrtgi/mod.rs: its fields' meaning).
#import rust/CvParams

@group(1) @binding(1) var<uniform> params: CvParams;
// Occupied voxels sorted by key, two vec4 each: (mean surface position, cluster bits), (normal, key
// bits).
@group(1) @binding(2) var<storage, read> voxels: array<vec4<f32>>;
// [0, 6V): face index of (voxel, dir) or INVALID; [6V, 6V + faces): 6 voxel + dir of each face.
@group(1) @binding(3) var<storage, read> faces: array<u32>;
// Cluster lights (5 vec4: pos | first lit, nrm | lit count, flux | conservation scale, box min, box
// max), then the lit voxels' lights (3 vec4, a Vpl) from 5 × num_clusters on. `escape`: the VPLs
// (3 vec4 each).
@group(1) @binding(4) var<storage, read> cv_lights: array<vec4<f32>>;
// Per face `rays` cluster ids, the seen ones first, INVALID after.
@group(1) @binding(5) var<storage, read_write> vis: array<u32>;
@group(1) @binding(6) var<storage, read> irr_in: array<vec4<f32>>;
// gather / filter: per face irradiance; lookup: per pixel indirect light.
@group(1) @binding(7) var<storage, read_write> out: array<vec4<f32>>;
@group(1) @binding(8) var<storage, read> gbuffer: array<ShadingPoint>;
// gather (gather_mode 1): per face `rays` slots beside `vis`, the flux each cluster of its list
// sends to the face before its conservation scale (`slot_flux`).
@group(1) @binding(9) var<storage, read_write> vis_w: array<f32>;

fn face_axis(dir: u32) -> vec3<f32> {
    var v = vec3<f32>(0.0);
    v[dir / 2u] = select(-1.0, 1.0, dir % 2u == 0u);
    return v;
}

fn dominant_face(n: vec3<f32>) -> u32 {
    let a = abs(n);
    var axis = 2u;
    if a.x >= a.y && a.x >= a.z {
        axis = 0u;
    } else if a.y >= a.z {
        axis = 1u;
    }
    return 2u * axis + select(0u, 1u, n[axis] < 0.0);
}

fn voxel_coord(p: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(floor((p - params.origin.xyz) / params.origin.w));
}

fn voxel_key(c: vec3<i32>) -> u32 {
    let d = vec3<i32>(params.dims.xyz);
    if any(c < vec3<i32>(0)) || any(c >= d) {
        return INVALID;
    }
    return u32(c.x) + params.dims.x * (u32(c.y) + params.dims.y * u32(c.z));
}

fn coord_of_key(k: u32) -> vec3<i32> {
    let d = params.dims;
    return vec3<i32>(vec3<u32>(k % d.x, k / d.x % d.y, k / (d.x * d.y)));
}

// The occupied voxel at `c` (binary search over the sorted keys, the paper's hashed coordinates of
// Fig. 4), or INVALID.
fn find_voxel(c: vec3<i32>) -> u32 {
    let key = voxel_key(c);
    if key == INVALID {
        return INVALID;
    }
    var lo = 0u;
    var hi = params.dims.w;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        let k = bitcast<u32>(voxels[2u * mid + 1u].w);
        if k == key {
            return mid;
        }
        if k < key {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return INVALID;
}

// Twin of Voxels::at_surface: p, then p ± d s/2 (d into the surface).
fn voxel_at_surface(p: vec3<f32>, d: vec3<f32>) -> u32 {
    let h = 0.5 * params.origin.w;
    var v = find_voxel(voxel_coord(p));
    if v == INVALID {
        v = find_voxel(voxel_coord(p + d * h));
    }
    if v == INVALID {
        v = find_voxel(voxel_coord(p - d * h));
    }
    return v;
}

fn face_voxel_dir(f: u32) -> u32 {
    return faces[6u * params.dims.w + f];
}

fn radical_inverse(k: u32) -> f32 {
    return f32(reverseBits(k) >> 8u) * (1.0 / 16777216.0);
}

// Twin of method::cvrtgi::twin::face_ray: Hammersley over the hemisphere, turned by a per-face angle.
fn face_ray(f: u32, dir: u32, k: u32, rays: u32) -> vec3<f32> {
    let cos_t = (f32(k) + 0.5) / f32(rays);
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let turn = f32(pcg_hash(f) >> 8u) * (1.0 / 16777216.0);
    let phi = 2.0 * PI * fract(radical_inverse(k) + turn);
    let a = dir / 2u;
    var t = vec3<f32>(0.0);
    t[(a + 1u) % 3u] = 1.0;
    var b = vec3<f32>(0.0);
    b[(a + 2u) % 3u] = 1.0;
    return t * (sin_t * cos(phi)) + b * (sin_t * sin(phi)) + face_axis(dir) * cos_t;
}

fn face_origin(vd: u32) -> vec3<f32> {
    let c = coord_of_key(bitcast<u32>(voxels[2u * (vd / 6u) + 1u].w));
    let s = params.origin.w;
    let p = params.origin.xyz + (vec3<f32>(c) + 0.5) * s + face_axis(vd % 6u) * (0.5 * s);
    return offset_origin(p, face_axis(vd % 6u));
}

// §4.3: the clusters face f sees (BVH rays instead of the paper's Bresenham walk), each kept once
// (the paper's atomic OR; here one invocation walks all the face's rays). Twin: visible_clusters.
@compute @workgroup_size(64)
fn visibility(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let f = chunk_item(gid, nwg);
    if f == INVALID || f >= params.num_faces {
        return;
    }
    let vd = face_voxel_dir(f);
    let o = face_origin(vd);
    let base = f * params.rays;
    var seen = 0u;
    for (var k = 0u; k < params.rays; k++) {
        let d = face_ray(f, vd % 6u, k, params.rays);
        let hit = trace_closest(Ray(o, d, 0.0, INF));
        if hit.slot == INVALID {
            continue;
        }
        let v = voxel_at_surface(o + d * hit.t, d);
        if v == INVALID {
            continue;
        }
        let c = bitcast<u32>(voxels[2u * v].w);
        if c == INVALID {
            continue;
        }
        var dup = false;
        for (var j = 0u; j < seen; j++) {
            dup = dup || vis[base + j] == c;
        }
        if !dup {
            vis[base + seen] = c;
            seen += 1u;
        }
    }
    for (var j = seen; j < params.rays; j++) {
        vis[base + j] = INVALID;
    }
}

// Twin of method::cvrtgi::twin::escape_ray: ray k of n about the VPL's normal, cosine-distributed
// (Hammersley), turned by a per-VPL angle.
fn escape_ray(i: u32, n: vec3<f32>, k: u32, rays: u32) -> vec3<f32> {
    let turn = f32(pcg_hash(i ^ 0x9e3779b9u) >> 8u) * (1.0 / 16777216.0);
    return cosine_hemisphere(n, (f32(k) + 0.5) / f32(rays), fract(radical_inverse(k) + turn));
}

// Where VPL i's light goes, from `escape_rays` cosine-distributed rays: x the fraction that gets
// farther than `escape_reach` (a tenth of a voxel) or meets nothing, y the fraction that meets a
// surface beyond it (the light the VPL sends into the scene; the rest leaves it). Light stopped
// closer (a VPL in a gap far thinner than a voxel, between an emitter and the ceiling it nearly
// touches) lights nothing the voxels can tell from the VPL's own surface, yet its voxel may be seen
// from the room. Not in the paper (docs/cvrtgi.md). Twin: escape_fractions.
@compute @workgroup_size(64)
fn escape(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID || i >= params.num_vpls {
        return;
    }
    let p = cv_lights[3u * i].xyz;
    let n = cv_lights[3u * i + 1u].xyz;
    let o = offset_origin(p, n);
    var kept = 0u;
    var sent = 0u;
    for (var k = 0u; k < params.escape_rays; k++) {
        let hit = trace_closest(Ray(o, escape_ray(i, n, k, params.escape_rays), 0.0, INF));
        if hit.slot == INVALID {
            kept += 1u;
        } else if hit.t >= params.escape_reach {
            kept += 1u;
            sent += 1u;
        }
    }
    let r = f32(max(params.escape_rays, 1u));
    out[i] = vec4<f32>(f32(kept) / r, f32(sent) / r, 0.0, 0.0);
}

// §4.4's differential-area form factor: irradiance at x (normal n) from `light`, Eq. (5)'s term of
// seed 000 without ρ/π (albedo π), so ρ/π E is Eq. (5)'s radiance. Twin: face_irradiance.
fn face_irradiance(x: vec3<f32>, n: vec3<f32>, light: Vpl) -> vec3<f32> {
    return eq5_vpl_radiance(x, n, vec3<f32>(PI), light, params.d_min2);
}

fn load_light(i: u32) -> Vpl {
    return Vpl(cv_lights[i], cv_lights[i + 1u], cv_lights[i + 2u]);
}

// The flux (luminance r + g + b) a face of axis n in a voxel of normal nv takes at irradiance e:
// e times the face's area projected on the voxel's surface, s² |n · nv| (the faces of a staircase
// of voxels along a slanted surface add up to the surface's area, not more). Not in the paper.
// Twin: slot_flux.
fn slot_flux(nv: vec3<f32>, n: vec3<f32>, e: vec3<f32>) -> f32 {
    let s = params.origin.w;
    return s * s * abs(dot(nv, n)) * (e.x + e.y + e.z);
}

// §4.4: face f gathers the lit clusters of its cached list; with gather_mode 1 (not in the paper)
// each times its conservation scale, the flux each sends to the face kept in `vis_w`. Twin:
// gather_face (with cluster_irradiance and slot_flux).
@compute @workgroup_size(64)
fn gather(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let f = chunk_item(gid, nwg);
    if f == INVALID || f >= params.num_faces {
        return;
    }
    let vd = face_voxel_dir(f);
    let x = voxels[2u * (vd / 6u)].xyz;
    let n = face_axis(vd % 6u);
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < params.rays; k++) {
        let c = vis[f * params.rays + k];
        if c == INVALID {
            break;
        }
        let count = bitcast<u32>(cv_lights[5u * c + 1u].w);
        if count == 0u {
            continue;
        }
        let lo = cv_lights[5u * c + 3u].xyz;
        let hi = cv_lights[5u * c + 4u].xyz;
        var ec = vec3<f32>(0.0);
        if length(max(max(lo - x, x - hi), vec3<f32>(0.0))) < params.near {
            let first = bitcast<u32>(cv_lights[5u * c].w);
            for (var j = 0u; j < count; j++) {
                ec += face_irradiance(x, n, load_light(5u * params.num_clusters + 3u * (first + j)));
            }
        } else {
            ec = face_irradiance(x, n, load_light(5u * c));
        }
        if params.gather_mode == 1u {
            vis_w[f * params.rays + k] = slot_flux(voxels[2u * (vd / 6u) + 1u].xyz, n, ec);
            ec *= cv_lights[5u * c + 2u].w;
        }
        e += ec;
    }
    out[f] = vec4<f32>(e, 0.0);
}

// One pass of §4.4's Gaussian filter over same-direction faces. Twin: filter_face.
@compute @workgroup_size(64)
fn filter_faces(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let f = chunk_item(gid, nwg);
    if f == INVALID || f >= params.num_faces {
        return;
    }
    let vd = face_voxel_dir(f);
    let dir = vd % 6u;
    let c = coord_of_key(bitcast<u32>(voxels[2u * (vd / 6u) + 1u].w));
    let r = i32(params.radius);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var dz = -r; dz <= r; dz++) {
        for (var dy = -r; dy <= r; dy++) {
            for (var dx = -r; dx <= r; dx++) {
                let d = vec3<i32>(dx, dy, dz);
                let u = find_voxel(c + d);
                if u == INVALID {
                    continue;
                }
                let g = faces[6u * u + dir];
                if g == INVALID {
                    continue;
                }
                let e = irr_in[g].xyz;
                if g != f && max(e.x, max(e.y, e.z)) <= 0.0 {
                    continue;
                }
                let w = exp(-f32(dot(d, d)) * params.inv_two_sigma2);
                sum += w * e;
                wsum += w;
            }
        }
    }
    if wsum > 0.0 {
        out[f] = vec4<f32>(sum / wsum, 0.0);
    } else {
        out[f] = irr_in[f];
    }
}

// Twin of nearest_face: the exposed face of the voxel at p whose axis is nearest n.
fn nearest_face(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let u = voxel_at_surface(p, -n);
    if u == INVALID {
        return vec3<f32>(0.0);
    }
    var best = 0.0;
    var bf = INVALID;
    for (var dir = 0u; dir < 6u; dir++) {
        let f = faces[6u * u + dir];
        let c = dot(face_axis(dir), n);
        if f != INVALID && c > best {
            best = c;
            bf = f;
        }
    }
    if bf == INVALID {
        return vec3<f32>(0.0);
    }
    return irr_in[bf].xyz;
}

// §4.5: ρ/π times the irradiance of the pixel's face, trilinear over the 8 voxel centres around it.
// Twin: lookup_pixel.
@compute @workgroup_size(64)
fn lookup(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID {
        return;
    }
    let sp = gbuffer[m];
    if sp.pos.w <= 0.0 {
        out[m] = vec4<f32>(0.0);
        return;
    }
    let dir = dominant_face(sp.nrm.xyz);
    let q = (sp.pos.xyz - params.origin.xyz) / params.origin.w - 0.5;
    let b = floor(q);
    let t = q - b;
    let base = vec3<i32>(b);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let wv = select(vec3<f32>(1.0) - t, t, o == vec3<u32>(1u));
        let w = wv.x * wv.y * wv.z;
        let u = find_voxel(base + vec3<i32>(o));
        if u == INVALID {
            continue;
        }
        let f = faces[6u * u + dir];
        if f != INVALID {
            sum += w * irr_in[f].xyz;
            wsum += w;
        }
    }
    var e = vec3<f32>(0.0);
    if wsum > 0.0 {
        e = sum / wsum;
    } else {
        e = nearest_face(sp.pos.xyz, sp.nrm.xyz);
    }
    out[m] = vec4<f32>(sp.albedo.xyz / PI * e, 0.0);
}
