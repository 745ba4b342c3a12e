//! CPU twins of `primary.wgsl` and `direct.wgsl` (with `common/surface.wgsl`, `common/lights.wgsl`,
//! `common/sampling.wgsl`): the same formulas, the same random numbers, obvhs for the rays.

use glam::{Vec2, Vec3};

use crate::bvh::SceneBvh;
use crate::gi::primary::{CameraParams, ShadingPoint};
use crate::gi::rng::{rng_next, rng_seed};
use crate::gi::scene_gpu::{GpuEmitter, SceneInfo};
use crate::scene::{LightKind, Scene, Texture};

/// Samples per random stream in the direct light (`RNG_BLOCK` in direct.wgsl).
const RNG_BLOCK: u32 = crate::gi::direct::SAMPLES_PER_DISPATCH;

/// Everything the twins need besides the scene and the BVH.
pub struct CpuScene<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a SceneBvh,
    pub info: SceneInfo,
    pub emitters: &'a [GpuEmitter],
}

fn srgb(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn fetch(t: &Texture, x: i32, y: i32) -> [f32; 4] {
    let (w, h) = (t.width as i32, t.height as i32);
    let xi = x.rem_euclid(w);
    let yi = y.rem_euclid(h);
    let c = t.rgba8[(yi * w + xi) as usize];
    [
        srgb(c[0] as f32 / 255.0),
        srgb(c[1] as f32 / 255.0),
        srgb(c[2] as f32 / 255.0),
        c[3] as f32 / 255.0,
    ]
}

/// Twin of `sample_texture` (bilinear, repeat, sRGB decode).
pub fn sample_texture(t: &Texture, uv: Vec2) -> Vec3 {
    let f = (uv - uv.floor()) * Vec2::new(t.width as f32, t.height as f32) - 0.5;
    let i = f.floor();
    let w = f - i;
    let (x, y) = (i.x as i32, i.y as i32);
    let a = fetch(t, x, y);
    let b = fetch(t, x + 1, y);
    let c = fetch(t, x, y + 1);
    let d = fetch(t, x + 1, y + 1);
    let lerp = |p: [f32; 4], q: [f32; 4], s: f32| {
        Vec3::new(p[0], p[1], p[2]).lerp(Vec3::new(q[0], q[1], q[2]), s)
    };
    lerp(a, b, w.x).lerp(lerp(c, d, w.x), w.y)
}

impl<'a> CpuScene<'a> {
    fn tri(&self, slot: u32) -> &crate::scene::Triangle {
        &self.scene.triangles[self.bvh.slot_to_triangle[slot as usize] as usize]
    }

    fn emission(&self, material: u32, uv: Vec2) -> Vec3 {
        let m = &self.scene.materials[material as usize];
        let mut e = m.emissive;
        if let Some(t) = m.emissive_texture {
            e *= sample_texture(&self.scene.textures[t as usize], uv);
        }
        e
    }

    /// Twin of `material_albedo`: factor × texture × vertex colour.
    fn albedo(&self, material: u32, uv: Vec2, color: Vec3) -> Vec3 {
        let m = &self.scene.materials[material as usize];
        let mut a = m.base_color.truncate();
        if let Some(t) = m.base_color_texture {
            a *= sample_texture(&self.scene.textures[t as usize], uv);
        }
        (a * color).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// Twin of `tri_vertex_color`.
    fn vertex_color(&self, slot: u32, b1: f32, b2: f32) -> Vec3 {
        let c = self.tri(slot).color;
        ((1.0 - b1 - b2) * c[0] + b1 * c[1] + b2 * c[2]).truncate()
    }

    fn shading_normal(&self, slot: u32, b1: f32, b2: f32) -> Vec3 {
        let t = self.tri(slot);
        let n = (1.0 - b1 - b2) * t.n[0] + b1 * t.n[1] + b2 * t.n[2];
        let l = n.length();
        if l > 1e-12 {
            n / l
        } else {
            self.geometric_normal(slot)
        }
    }

    fn geometric_normal(&self, slot: u32) -> Vec3 {
        let t = &self.bvh.tris[slot as usize];
        Vec3::from((t.v1 - t.v0).cross(t.v2 - t.v0).normalize())
    }

    fn point(&self, slot: u32, b1: f32, b2: f32) -> Vec3 {
        let t = &self.bvh.tris[slot as usize];
        Vec3::from((1.0 - b1 - b2) * t.v0 + b1 * t.v1 + b2 * t.v2)
    }

    fn uv(&self, slot: u32, b1: f32, b2: f32) -> Vec2 {
        let t = self.tri(slot);
        (1.0 - b1 - b2) * t.uv[0] + b1 * t.uv[1] + b2 * t.uv[2]
    }

    /// Twin of `primary.wgsl` for one pixel.
    pub fn primary(&self, cam: &CameraParams, pixel: u32) -> ShadingPoint {
        let w = cam.size[0];
        let [jx, jy] = cam.jitter();
        let x = (pixel % w) as f32 + 0.5 + jx;
        let y = (pixel / w) as f32 + 0.5 + jy;
        let dir = cam.ray(x, y).normalize();
        let eye = cam.eye_point();
        let none = ShadingPoint {
            valid: false,
            pos: Vec3::ZERO,
            normal: Vec3::Z,
            material: 0,
            albedo: Vec3::ZERO,
            emission: Vec3::ZERO,
        };
        let Some(hit) = self.bvh.closest(eye.into(), dir.into(), 0.0, f32::INFINITY) else {
            return none;
        };
        let (slot, b1, b2) = (hit.slot, hit.u, hit.v);
        let material = self.tri(slot).material;
        let uv = self.uv(slot, b1, b2);
        let mut ng = self.geometric_normal(slot);
        let mut n = self.shading_normal(slot, b1, b2);
        let front = n.dot(dir) < 0.0;
        let emission = if front {
            self.emission(material, uv)
        } else {
            Vec3::ZERO
        };
        if ng.dot(dir) > 0.0 {
            ng = -ng;
        }
        if n.dot(ng) < 0.0 {
            n = -n;
        }
        ShadingPoint {
            valid: true,
            pos: eye + hit.t * dir,
            normal: n,
            material,
            albedo: self.albedo(material, uv, self.vertex_color(slot, b1, b2)),
            emission,
        }
    }

    fn offset_origin(&self, p: Vec3, n: Vec3) -> Vec3 {
        p + n * (self.info.eps + 4e-6 * p.abs().max_element())
    }

    fn emitter_index(&self, u: f32) -> usize {
        let (mut lo, mut hi) = (0usize, self.emitters.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.emitters[mid].cdf <= u {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Twin of `direct.wgsl`: emission + direct light of one shading point (summed in one loop; the
    /// shader sums sub ranges of `SAMPLES_PER_DISPATCH` samples in turn, which rounds differently).
    pub fn direct(&self, sp: &ShadingPoint, pixel: u32, seed: u32, spp: u32) -> Vec3 {
        if !sp.valid {
            return Vec3::ZERO;
        }
        let (p, n) = (sp.pos, sp.normal);
        let mut sum = Vec3::ZERO;
        if !self.emitters.is_empty() {
            let mut rng = 0;
            let spp = spp.max(1);
            let mut area_sum = Vec3::ZERO;
            for s in 0..spp {
                // A fresh stream every RNG_BLOCK samples (direct.wgsl).
                if s % RNG_BLOCK == 0 {
                    rng = rng_seed(pixel, seed, 0x9e3779b9u32.wrapping_add(s / RNG_BLOCK));
                }
                let u0 = (s as f32 + rng_next(&mut rng)) / spp as f32;
                let (u1, u2) = (rng_next(&mut rng), rng_next(&mut rng));
                let e = self.emitters[self.emitter_index(u0.min(0.99999994))];
                let sq = u1.sqrt();
                let (b1, b2) = (1.0 - sq, u2 * sq);
                let lp = self.point(e.slot, b1, b2);
                let ln = self.shading_normal(e.slot, b1, b2);
                let le = self.emission(self.tri(e.slot).material, self.uv(e.slot, b1, b2));
                let pdf = (e.power / self.info.emit_power) / e.area;
                let d = lp - p;
                let d2 = d.dot(d);
                if d2 <= 0.0 {
                    continue;
                }
                let wi = d / d2.sqrt();
                let (cp, cl) = (n.dot(wi), ln.dot(-wi));
                if cp <= 0.0 || cl <= 0.0 || pdf <= 0.0 {
                    continue;
                }
                if self.visible(p, n, lp + ln * self.info.eps) {
                    area_sum += le * cp * cl / (d2 * pdf);
                }
            }
            sum += area_sum / spp as f32;
        }
        for l in &self.scene.lights {
            let c = l.color * l.intensity;
            let (wi, dist, e) = match l.kind {
                LightKind::Directional => (-l.direction, f32::INFINITY, c),
                _ => {
                    let d = l.position - p;
                    let d2 = d.dot(d).max(1e-30);
                    let dist = d2.sqrt();
                    let wi = d / dist;
                    let mut fall = 1.0;
                    if let LightKind::Spot {
                        inner_cone,
                        outer_cone,
                    } = l.kind
                    {
                        let cd = l.direction.dot(-wi);
                        let (co, ci) = (outer_cone.cos(), inner_cone.cos());
                        let t = ((cd - co) / (ci - co).max(1e-4)).clamp(0.0, 1.0);
                        fall = t * t;
                    }
                    (wi, dist, c * fall / d2)
                }
            };
            let cp = n.dot(wi);
            if cp <= 0.0 || e == Vec3::ZERO {
                continue;
            }
            let o = self.offset_origin(p, n);
            let tmax = if dist.is_finite() {
                dist * (1.0 - 1e-4)
            } else {
                f32::INFINITY
            };
            if !self.bvh.occluded(o.into(), wi.into(), 0.0, tmax) {
                sum += e * cp;
            }
        }
        sp.emission + sp.albedo / std::f32::consts::PI * sum
    }

    fn visible(&self, p: Vec3, n: Vec3, q: Vec3) -> bool {
        let o = self.offset_origin(p, n);
        let d = q - o;
        let dist = d.length();
        if dist <= 0.0 {
            return false;
        }
        !self.bvh.occluded(
            o.into(),
            (d / dist).into(),
            0.0,
            dist * (1.0 - 1e-4) - self.info.eps,
        )
    }
}

/// Twin of `common/sampling.wgsl`'s `onb`: the two tangents completing unit normal `n` to an
/// orthonormal basis (Duff et al. 2017; cosine rays, disc points).
pub fn onb(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = Vec3::new(b, s + n.y * n.y * a, -n.y);
    (t, bt)
}
