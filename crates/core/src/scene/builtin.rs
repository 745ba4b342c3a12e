//! Built-in scenes embedded in the binary (`builtin:NAME`).

use glam::{Vec2, Vec3, Vec4};

use super::{Material, Scene, SceneError, Triangle, gltf_load};

/// Names accepted by [`load`].
pub const NAMES: &[&str] = &["cornell", "conference", "dense-3m", "dense-8m"];

/// The dense scenes: the conference room with a rug of `2 x n x m` triangles on its floor
/// (`with_rug`), 3.0 M and 8.39 M triangles in all (the most the GPU data holds is 2^23 = 8,388,608):
/// what the BVH traversal and every ray-tracing pass cost on big meshes (`scripts/gpu-bench`).
pub const DENSE: &[(&str, u32, u32)] = &[("dense-3m", 1225, 1224), ("dense-8m", 2048, 2047)];

/// The embedded GLB of a built-in scene.
pub fn bytes(name: &str) -> Option<&'static [u8]> {
    match name {
        "cornell" => Some(include_bytes!("../../../../assets/cornell.glb")),
        "conference" => Some(include_bytes!("../../../../assets/conference.glb")),
        _ => None,
    }
}

/// Loads built-in scene `name` (without the `builtin:` prefix); the scene is named `builtin:NAME`.
pub fn load(name: &str) -> Result<Scene, SceneError> {
    let label = format!("builtin:{name}");
    if let Some(&(_, n, m)) = DENSE.iter().find(|d| d.0 == name) {
        let mut s = load("conference")?;
        s.name = label;
        with_rug(&mut s, n, m);
        return Ok(s);
    }
    match bytes(name) {
        Some(b) => gltf_load::load_slice(b, &label),
        None => Err(SceneError::new(
            label,
            format!("unknown built-in scene (known: {})", NAMES.join(", ")),
        )),
    }
}

/// Adds a rug to the conference room's floor: an `n x m` grid of quads (two triangles each) over
/// x in [-3.8, 3.8], z in [-2.3, 2.3], 1 cm above the floor with 2 mm bumps (a product of sines,
/// 40 x 25 periods), smooth normals from the height's derivatives, a grey diffuse material of its
/// own. Fine enough that every quad is a few pixels or less at 1024 x 720.
pub fn with_rug(s: &mut Scene, n: u32, m: u32) {
    let (x0, x1, z0, z1) = (-3.8f32, 3.8f32, -2.3f32, 2.3f32);
    let (kx, kz) = (
        40.0 * std::f32::consts::TAU / (x1 - x0),
        25.0 * std::f32::consts::TAU / (z1 - z0),
    );
    let amp = 0.002f32;
    let point = |i: u32, j: u32| {
        let x = x0 + (x1 - x0) * i as f32 / n as f32;
        let z = z0 + (z1 - z0) * j as f32 / m as f32;
        let (sx, cx) = (kx * (x - x0)).sin_cos();
        let (sz, cz) = (kz * (z - z0)).sin_cos();
        let p = Vec3::new(x, 0.01 + amp * sx * sz, z);
        // The normal of y = h(x, z): (-dh/dx, 1, -dh/dz).
        let nrm = Vec3::new(-amp * kx * cx * sz, 1.0, -amp * kz * sx * cz).normalize();
        (p, nrm)
    };
    let material = s.materials.len() as u32;
    s.materials.push(Material {
        name: "rug".into(),
        base_color: Vec4::new(0.45, 0.42, 0.38, 1.0),
        ..Default::default()
    });
    s.triangles.reserve(2 * n as usize * m as usize);
    let tri = |a: (Vec3, Vec3), b: (Vec3, Vec3), c: (Vec3, Vec3)| Triangle {
        p: [a.0, b.0, c.0],
        n: [a.1, b.1, c.1],
        uv: [Vec2::ZERO; 3],
        color: [Vec4::ONE; 3],
        material,
    };
    for j in 0..m {
        for i in 0..n {
            let (a, b) = (point(i, j), point(i + 1, j));
            let (c, d) = (point(i, j + 1), point(i + 1, j + 1));
            // Counter-clockwise seen from above (+y).
            s.triangles.push(tri(a, c, b));
            s.triangles.push(tri(b, c, d));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rug: 2nm triangles facing up, inside the room, above the floor; the dense scenes hold
    /// 3.0 M and 8.39 M triangles, within the GPU data's 2^23.
    #[test]
    fn the_rug_is_a_fine_upward_grid_on_the_floor() {
        let mut s = load("conference").unwrap();
        let before = s.triangles.len();
        with_rug(&mut s, 30, 20);
        let rug = &s.triangles[before..];
        assert_eq!(rug.len(), 2 * 30 * 20);
        for t in rug {
            let face = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
            assert!(face.y > 0.0, "a rug triangle faces down: {face}");
            for (p, n) in t.p.iter().zip(t.n) {
                assert!((0.0079..=0.0121).contains(&p.y), "height {}", p.y);
                assert!(p.x.abs() <= 3.8 + 1e-6 && p.z.abs() <= 2.3 + 1e-6);
                assert!((n.length() - 1.0).abs() < 1e-5 && n.y > 0.9);
            }
        }
        let room = 1448;
        assert_eq!(before, room);
        for &(name, n, m) in DENSE {
            let total = room + 2 * n as usize * m as usize;
            assert!(total <= 1 << 23, "{name}: {total}");
        }
        assert_eq!(room + 2 * 2048 * 2047, 8_385_960);
        // The smaller dense scene whole (the larger takes 1.2 GB; its count is the sum above).
        let d = load("dense-3m").unwrap();
        assert_eq!(
            (d.name.as_str(), d.triangles.len()),
            ("builtin:dense-3m", 3_000_248)
        );
        assert_eq!(d.cameras.len(), 1);
    }

    #[test]
    fn every_builtin_loads() {
        for name in NAMES.iter().filter(|n| !n.starts_with("dense")) {
            let s = load(name).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.name, format!("builtin:{name}"));
            assert!(!s.triangles.is_empty());
            assert!(s.path.is_none());
        }
    }

    #[test]
    fn unknown_builtin_is_an_error() {
        let e = load("nope").unwrap_err().to_string();
        assert!(e.contains("builtin:nope"), "{e}");
        assert!(e.contains("cornell") && e.contains("conference"), "{e}");
    }
}
