//! CPU twins of `visibility.wgsl` (step 5) and `shade.wgsl` (step 6, Eq. 6 with Eq. 8 / 9).

use glam::Vec3;

use super::kmeans::RepPoint;
use super::shading::CpuScene;
use super::vpl::eq5_cluster_light;
use crate::gi::primary::ShadingPoint;
use crate::gi::vpl_trace::Vpl;
use crate::settings::ClusterLight;

/// The visibility bit matrix: row k (SP cluster with representative point `reps[k]`, or none), bit c
/// set when light c's representative is visible from it (with `facing`, only when they also face
/// each other). Returns (bits, words per row).
pub fn visibility_bits(
    cpu: &CpuScene,
    reps: &[RepPoint],
    lights: &[Vpl],
    facing: bool,
) -> (Vec<u32>, usize) {
    let words = lights.len().div_ceil(32).max(1);
    let mut bits = vec![0u32; reps.len() * words];
    for (k, rep) in reps.iter().enumerate() {
        if !rep.valid {
            continue;
        }
        for (c, l) in lights.iter().enumerate() {
            let d = Vec3::new(l.pos[0], l.pos[1], l.pos[2]) - rep.pos;
            let ln = Vec3::new(l.nrm[0], l.nrm[1], l.nrm[2]);
            if facing && (rep.nrm.dot(d) <= 0.0 || ln.dot(d) >= 0.0) {
                continue;
            }
            if cpu.vpl_visible(rep.pos, rep.nrm, l) {
                bits[k * words + c / 32] |= 1 << (c % 32);
            }
        }
    }
    (bits, words)
}

/// The visibility bit matrix a pixel's slots read (`visibility_bits`): rows of `words` words.
#[derive(Clone, Copy)]
pub struct Bits<'a> {
    pub bits: &'a [u32],
    pub words: usize,
}

impl Bits<'_> {
    /// V(p_f, p_c) of SP cluster `row` and light `c`.
    pub fn visible(&self, row: u32, c: usize) -> bool {
        self.bits[row as usize * self.words + c / 32] & (1 << (c % 32)) != 0
    }
}

/// A pixel's F slots: its SP clusters (`u32::MAX` unused) and their Eq. (10) weights, used as they
/// are (`weighted`, Eq. 9) or replaced by Eq. (8)'s uniform weights.
#[derive(Clone, Copy)]
pub struct Slots<'a> {
    pub assign: &'a [u32],
    pub weights: &'a [f32],
    pub weighted: bool,
}

/// Eq. (8) as weights: 1/F' for each of the F' used slots, 0 for the others (twin of
/// `eq8_mean_weights` in shade.wgsl).
pub fn eq8_mean_weights(assign: &[u32]) -> Vec<f32> {
    let nf = assign.iter().filter(|&&k| k != u32::MAX).count();
    assign
        .iter()
        .map(|&k| if k != u32::MAX { 1.0 / nf as f32 } else { 0.0 })
        .collect()
}

/// Eq. (9): Ṽ(p, p_c) = Σ_f w_f V(p_f, p_c), summed over the slots in order (twin of
/// `eq9_weighted_visibility` in shade.wgsl; with `eq8_mean_weights` it is Eq. 8).
pub fn eq9_weighted_visibility(w: &[f32], visible: impl Fn(usize) -> bool) -> f32 {
    w.iter()
        .enumerate()
        .filter(|&(f, _)| visible(f))
        .map(|(_, &w)| w)
        .sum()
}

/// The lights of a 32-light word that every slot sees as it sees light `b` (its visibility pattern
/// over the slots), as a mask; `rw[f]` is slot f's word (0 for an unused slot). Twin of
/// `same_visibility` in shade.wgsl, whose pattern table gives each light of a pattern the Ṽ of its
/// first light.
pub fn same_visibility(rw: &[u32], b: u32) -> u32 {
    rw.iter().fold(u32::MAX, |same, &r| {
        same & if (r >> b) & 1 != 0 { r } else { !r }
    })
}

/// The boxes of a tile's shading points' positions and normals (twin of `tile_cull`'s bounds in
/// shade.wgsl, which shades 8 × 8 tiles, `method::colom::shade::TILE`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    pub nlo: Vec3,
    pub nhi: Vec3,
}

impl TileBounds {
    /// The bounds of the valid points of `sps`; `None` when none is valid.
    pub fn of<'a>(sps: impl IntoIterator<Item = &'a ShadingPoint>) -> Option<TileBounds> {
        sps.into_iter()
            .filter(|sp| sp.valid)
            .fold(None, |b: Option<TileBounds>, sp| {
                let b = b.unwrap_or(TileBounds {
                    lo: sp.pos,
                    hi: sp.pos,
                    nlo: sp.normal,
                    nhi: sp.normal,
                });
                Some(TileBounds {
                    lo: b.lo.min(sp.pos),
                    hi: b.hi.max(sp.pos),
                    nlo: b.nlo.min(sp.normal),
                    nhi: b.nhi.max(sp.normal),
                })
            })
    }
}

/// The tile of pixel `m` of an image `width` wide (tiles of `TILE` × `TILE`, row-major), as
/// `tile_bounds` lists them.
pub fn tile_of(m: usize, width: u32) -> usize {
    let tile = crate::method::colom::shade::TILE as usize;
    let (x, y) = (m % width as usize, m / width as usize);
    (y / tile) * (width as usize).div_ceil(tile) + x / tile
}

/// Each tile's bounds over the image's shading points `sps` (`width` × `height`, row-major).
pub fn tile_bounds(sps: &[ShadingPoint], width: u32, height: u32) -> Vec<Option<TileBounds>> {
    let tile = crate::method::colom::shade::TILE as usize;
    let tiles = (width as usize).div_ceil(tile) * (height as usize).div_ceil(tile);
    let mut members: Vec<Vec<&ShadingPoint>> = vec![Vec::new(); tiles];
    for (m, sp) in sps.iter().enumerate() {
        members[tile_of(m, width)].push(sp);
    }
    members.into_iter().map(TileBounds::of).collect()
}

/// Not in the paper: whether light `v` may add to Eq. (6) at a point of the tile `b` (twin of
/// `may_light_box` in shade.wgsl): false when, over the boxes, the largest cosine term at the
/// light, n_v · (p - x_v), or at the point, n · (x_v - p), is at most the slack (1e-5 of the
/// largest coordinate), each maximum a sum over the axes of the largest product at a corner.
pub fn may_light_box(b: &TileBounds, v: &Vpl) -> bool {
    let x = Vec3::new(v.pos[0], v.pos[1], v.pos[2]);
    let n = Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2]);
    let at_light = (n * (b.lo - x)).max(n * (b.hi - x));
    let (a, c) = (x - b.lo, x - b.hi);
    let at_point = (b.nlo * a).max(b.nlo * c).max((b.nhi * a).max(b.nhi * c));
    let scale = b.lo.abs().max(b.hi.abs()).max(x.abs());
    let slack = 1e-5 * scale.max_element();
    at_light.dot(Vec3::ONE) > slack && at_point.dot(Vec3::ONE) > slack
}

/// Not in the paper: the most a unit normal and its `oct_decode(oct_encode(n))` lie apart, in
/// radians (0.008°). Rounding the octahedral coordinates to multiples of 2^-14 moves the point by
/// at most 2^-15 √2 = 4.3e-5 in the plane, and the map from the plane to the sphere stretches
/// lengths up to about 3×: measured over 10^6 normals, at most 1.29e-4
/// (`oct_code_error_is_bounded`). A cosine moves by at most as much.
pub const OCT_ERROR: f32 = 1.4e-4;

/// Not in the paper: unit normal `n` as 32 bits, its octahedral coordinates (Cigolle et al. 2014)
/// each rounded to a multiple of 2^-14 as 16-bit integers, x low (twin of `oct_encode` in
/// shade.wgsl).
pub fn oct_encode(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let mut e = if l1 > 0.0 {
        glam::Vec2::new(n.x / l1, n.y / l1)
    } else {
        glam::Vec2::ZERO
    };
    if n.z < 0.0 {
        e = oct_wrap(e);
    }
    let q = (e.clamp(glam::Vec2::splat(-1.0), glam::Vec2::ONE) * 16384.0).map(f32::round_ties_even);
    (q.x as i32 as u32 & 0xffff) | ((q.y as i32 as u32) << 16)
}

/// The octahedral map's fold of the lower half (z < 0) over the upper one, either way (it is its
/// own inverse): (1 − |e.yx|) with the signs of `e`, +1 at ±0 (twin of `oct_wrap` in shade.wgsl).
fn oct_wrap(e: glam::Vec2) -> glam::Vec2 {
    let sign = |x: f32| if x >= 0.0 { 1.0 } else { -1.0 };
    glam::Vec2::new((1.0 - e.y.abs()) * sign(e.x), (1.0 - e.x.abs()) * sign(e.y))
}

/// The unit normal of `oct_encode`'s code (twin of `oct_decode` in shade.wgsl): the octahedron's
/// point exactly, normalised.
pub fn oct_decode(code: u32) -> Vec3 {
    let e = glam::Vec2::new(
        ((code << 16) as i32 >> 16) as f32,
        (code as i32 >> 16) as f32,
    ) * (1.0 / 16384.0);
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    if n.z < 0.0 {
        let xy = oct_wrap(e);
        n = Vec3::new(xy.x, xy.y, n.z);
    }
    n * (1.0 / n.dot(n).sqrt())
}

/// Not in the paper: a cluster light's spread share s (in [0, 1]) and r² (≥ 0) as 32 bits, r²
/// rounded to 11 mantissa bits in the high 19 and s to a multiple of 2^-12 in the low 13 (twin of
/// `spread_encode` in shade.wgsl).
pub fn spread_encode(s: f32, r2: f32) -> u32 {
    let r = ((r2.max(0.0).to_bits() + 0x800) & 0x7fff_f000) << 1;
    r | (s.clamp(0.0, 1.0) * 4096.0).round_ties_even() as u32
}

/// (s, r²) of `spread_encode`'s code (twin of `spread_decode` in shade.wgsl).
pub fn spread_decode(code: u32) -> (f32, f32) {
    (
        (code & 0x1fff) as f32 * (1.0 / 4096.0),
        f32::from_bits((code >> 1) & 0x7fff_f000),
    )
}

/// Light `v` as the shade pass walks it (twin of `pack_lights` then `load_light` in shade.wgsl):
/// position and flux exact, the normal through `oct_encode`, the spread's (s, r²) through
/// `spread_encode`.
pub fn stored_light(v: &Vpl) -> Vpl {
    let n = oct_decode(oct_encode(Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2])));
    let (s, r2) = spread_decode(spread_encode(v.flux[3], v.nrm[3]));
    Vpl {
        pos: [v.pos[0], v.pos[1], v.pos[2], 1.0],
        nrm: [n.x, n.y, n.z, r2],
        flux: [v.flux[0], v.flux[1], v.flux[2], s],
    }
}

/// Eq. (6) for one pixel: Σ_c I_c ρ G Ṽ(p, p_c) over the lights, each a point or spread as `light`
/// says (twin of `eq6_indirect` in shade.wgsl), each as the pass stores it (`stored_light`); with
/// `tile` (the pixel's tile's bounds), only the lights `may_light_box` keeps, as the shader's tile
/// cull does.
pub fn eq6_indirect(
    sp: &ShadingPoint,
    lights: &[Vpl],
    bits: &Bits,
    slots: &Slots,
    d_min2: f32,
    light: ClusterLight,
    tile: Option<&TileBounds>,
) -> Vec3 {
    if !sp.valid {
        return Vec3::ZERO;
    }
    let w = if slots.weighted {
        slots.weights.to_vec()
    } else {
        eq8_mean_weights(slots.assign)
    };
    let mut sum = Vec3::ZERO;
    for (c, l) in lights.iter().enumerate() {
        let l = &stored_light(l);
        if tile.is_some_and(|b| !may_light_box(b, l)) {
            continue;
        }
        let t = eq5_cluster_light(sp.pos, sp.normal, sp.albedo, l, d_min2, light);
        if t.max_element() <= 0.0 {
            continue;
        }
        let row = |f: usize| slots.assign[f];
        let v = eq9_weighted_visibility(&w, |f| row(f) != u32::MAX && bits.visible(row(f), c));
        sum += t * v;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: slot words 0b1101 (lights 0, 2, 3), 0b0111 (lights 0, 1, 2) and an unused slot
    /// (0). Lights 0 and 2: both slots (pattern 11-); light 1: slot 1 only (01-); light 3: slot 0
    /// only (10-); lights 4..31: none (00-).
    #[test]
    fn same_visibility_by_hand() {
        let rw = [0b1101, 0b0111, 0];
        assert_eq!(same_visibility(&rw, 0), 0b0101);
        assert_eq!(same_visibility(&rw, 2), 0b0101);
        assert_eq!(same_visibility(&rw, 1), 0b0010);
        assert_eq!(same_visibility(&rw, 3), 0b1000);
        assert_eq!(same_visibility(&rw, 4), !0b1111);
        // One slot: the lights it sees, or those it does not.
        assert_eq!(same_visibility(&[0xf0f0_0000], 20), 0xf0f0_0000);
        assert_eq!(same_visibility(&[0xf0f0_0000], 0), 0x0f0f_ffff);
    }

    /// Hand-worked: the axes' codes (octahedral coordinates (0, 0), (±1, 0), (0, ±1), and (1, 1)
    /// for −z, whose fold sends (0, 0) to the corner) and their exact decoding.
    #[test]
    fn oct_code_of_the_axes_by_hand() {
        let cases = [
            (Vec3::Z, 0u32),
            (Vec3::X, 0x4000),
            (Vec3::NEG_X, 0xc000),
            (Vec3::Y, 0x4000_0000),
            (Vec3::NEG_Y, 0xc000_0000),
            (Vec3::NEG_Z, 0x4000_4000),
        ];
        for (n, code) in cases {
            assert_eq!(oct_encode(n), code, "{n}");
            assert_eq!(oct_decode(code), n, "{code:#x}");
        }
    }

    /// A unit normal and its decoding lie at most `OCT_ERROR` apart (10^6 normals, uniform on the
    /// sphere from a fixed sequence), and the decoding is unit to 2 ulp.
    #[test]
    fn oct_code_error_is_bounded() {
        let mut next = crate::test_rng::unit_floats(0x2545_f491_4f6c_dd1d);
        let mut worst = 0f32;
        for _ in 0..1_000_000 {
            let (z, phi) = (2.0 * next() - 1.0, std::f32::consts::TAU * next());
            let r = (1.0 - z * z).max(0.0).sqrt();
            let n = Vec3::new(r * phi.cos(), r * phi.sin(), z).normalize();
            let m = oct_decode(oct_encode(n));
            assert!((m.length() - 1.0).abs() < 2.5e-7, "{n} -> {m}");
            let angle = 2.0 * ((n - m).length() / 2.0).asin();
            worst = worst.max(angle);
        }
        assert!(worst <= OCT_ERROR, "worst {worst} rad");
        assert!(
            worst > OCT_ERROR / 4.0,
            "worst {worst} rad: the bound is loose"
        );
    }

    /// Hand-worked: (s, r²) = (0.5, 0.25) and (1, 0) are exact; r² = 1 + 2^-12 + 2^-20 rounds up
    /// to 1 + 2^-11 (11 mantissa bits), s = 0.3 to 1229 / 4096; a code's fields do not overlap.
    #[test]
    fn spread_code_by_hand() {
        assert_eq!(spread_decode(spread_encode(0.5, 0.25)), (0.5, 0.25));
        assert_eq!(spread_decode(spread_encode(1.0, 0.0)), (1.0, 0.0));
        let r2 = 1.0 + 2f32.powi(-12) + 2f32.powi(-20);
        assert_eq!(
            spread_decode(spread_encode(0.3, r2)),
            (1229.0 / 4096.0, 1.0 + 2f32.powi(-11))
        );
        for r2 in [1e-30f32, 3.7e-3, 12.5, 7.1e12] {
            let (s, r) = spread_decode(spread_encode(1.0, r2));
            assert_eq!(s, 1.0);
            assert!(((r - r2) / r2).abs() <= 2f32.powi(-12), "{r2} -> {r}");
        }
    }

    fn light(pos: [f32; 3], nrm: [f32; 3]) -> Vpl {
        Vpl {
            pos: [pos[0], pos[1], pos[2], 0.0],
            nrm: [nrm[0], nrm[1], nrm[2], 0.0],
            flux: [1.0; 4],
        }
    }

    /// Hand-worked: a floor tile, x and z in [0, 2], y = 0, normals +y. A light above it facing
    /// down lights it; one above facing up (its cosine at the tile is negative), one below facing
    /// up (the tile's cosine is negative) and one in the floor's plane (both cosines 0) do not; a
    /// light on a wall, and a tile over a corner, as below.
    #[test]
    fn may_light_box_by_hand() {
        let floor = TileBounds {
            lo: Vec3::new(0.0, 0.0, 0.0),
            hi: Vec3::new(2.0, 0.0, 2.0),
            nlo: Vec3::Y,
            nhi: Vec3::Y,
        };
        assert!(may_light_box(
            &floor,
            &light([1.0, 1.0, 1.0], [0.0, -1.0, 0.0])
        ));
        assert!(!may_light_box(
            &floor,
            &light([1.0, 1.0, 1.0], [0.0, 1.0, 0.0])
        ));
        assert!(!may_light_box(
            &floor,
            &light([1.0, -1.0, 1.0], [0.0, 1.0, 0.0])
        ));
        assert!(!may_light_box(
            &floor,
            &light([5.0, 0.0, 1.0], [0.0, 1.0, 0.0])
        ));
        // A wall light at y = 0.5 facing -x: at the floor (y = 0) the point's cosine n · (x - p)
        // is 0.5 > 0 and the light's -x · (p - x) = 3 - p.x > 0: it lights the floor.
        assert!(may_light_box(
            &floor,
            &light([3.0, 0.5, 1.0], [-1.0, 0.0, 0.0])
        ));
        // The same light at y = 0 (in the floor's plane): the floor's cosine is 0.
        assert!(!may_light_box(
            &floor,
            &light([3.0, 0.0, 1.0], [-1.0, 0.0, 0.0])
        ));
        // Within the slack (1e-5 of the largest coordinate, 3 here): 1e-6 above the plane is in
        // it, 1e-3 above is not.
        assert!(!may_light_box(
            &floor,
            &light([3.0, 1e-6, 1.0], [-1.0, 0.0, 0.0])
        ));
        assert!(may_light_box(
            &floor,
            &light([3.0, 1e-3, 1.0], [-1.0, 0.0, 0.0])
        ));
        // A tile over a corner (floor and wall x = 0 facing +x, normals in the box [0, 1]^2 × 0):
        // a light below the floor level at x = 1 facing -x sees the wall's side: the point's
        // bound over the box is max(n.x) (1 - 0) + max(n.y (−1 − y)) = 1 + 0 > 0.
        let corner = TileBounds {
            lo: Vec3::new(0.0, 0.0, 0.0),
            hi: Vec3::new(2.0, 2.0, 2.0),
            nlo: Vec3::ZERO,
            nhi: Vec3::new(1.0, 1.0, 0.0),
        };
        assert!(may_light_box(
            &corner,
            &light([1.0, -1.0, 1.0], [0.0, 1.0, 0.0])
        ));
        // Behind the wall (x = -1) facing -x: the light's bound is -x · (p - x) ≤ -(0 + 1) < 0.
        assert!(!may_light_box(
            &corner,
            &light([-1.0, 1.0, 1.0], [-1.0, 0.0, 0.0])
        ));
    }

    /// Tiles of 8 × 8 pixels, row-major: in a 20 × 10 image (3 × 2 tiles) pixel (19, 9) is in
    /// tile 5, pixel (8, 7) in tile 1; the bounds skip invalid points, and a tile of none has none.
    #[test]
    fn tiles_by_hand() {
        assert_eq!(tile_of(9 * 20 + 19, 20), 5);
        assert_eq!(tile_of(7 * 20 + 8, 20), 1);
        assert_eq!(tile_of(0, 20), 0);
        let sp = |valid, x: f32| ShadingPoint {
            valid,
            pos: Vec3::new(x, 0.0, -x),
            normal: Vec3::new(0.0, 1.0, x),
            material: 0,
            albedo: Vec3::ONE,
            emission: Vec3::ZERO,
        };
        let b = TileBounds::of([&sp(true, 1.0), &sp(false, 9.0), &sp(true, -2.0)]).unwrap();
        assert_eq!(b.lo, Vec3::new(-2.0, 0.0, -1.0));
        assert_eq!(b.hi, Vec3::new(1.0, 0.0, 2.0));
        assert_eq!(b.nlo, Vec3::new(0.0, 1.0, -2.0));
        assert_eq!(b.nhi, Vec3::new(0.0, 1.0, 1.0));
        assert_eq!(TileBounds::of([&sp(false, 1.0)]), None);
        let sps: Vec<ShadingPoint> = (0..200).map(|m| sp(m != 199, m as f32)).collect();
        let tiles = tile_bounds(&sps, 20, 10);
        assert_eq!(tiles.len(), 6);
        // Tile 5: x 16..19, y 8..9: pixels 176..179 and 196..198 (199 invalid).
        assert_eq!(tiles[5].unwrap().lo.x, 176.0);
        assert_eq!(tiles[5].unwrap().hi.x, 198.0);
    }
}
