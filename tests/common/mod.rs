//! Shared helpers for GPU tests (they run on lavapipe in CI: `apt-get install mesa-vulkan-drivers`).
#![allow(dead_code)]

use fuzzy_vpl::cpu::kmeans::RepPoint;
use fuzzy_vpl::cpu::shading::CpuScene;
use fuzzy_vpl::gi::primary::ShadingPoint;
use fuzzy_vpl::gpu::GpuContext;
use fuzzy_vpl::render::pipeline::Renderer;
use fuzzy_vpl::scene::Scene;

pub fn gpu() -> GpuContext {
    GpuContext::new_headless().unwrap_or_else(|e| {
        panic!("no wgpu adapter: {e:#}. Install Mesa's software Vulkan driver: apt-get install mesa-vulkan-drivers")
    })
}

pub fn all_finite(img: &[[f32; 3]]) -> bool {
    img.iter().flatten().all(|c| c.is_finite())
}

/// Deterministic xorshift for test data.
pub struct Rand(pub u64);
impl Rand {
    pub fn next_u32(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 32) as u32
    }
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / 16777216.0
    }
}

/// A scratch directory unique to this test.
pub fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("fuzzy-vpl-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The CPU twins' view of what `r` uploaded for scene `s` (the scene as loaded: the twins shade in
/// its units, as the frames come back in them).
pub fn cpu_scene<'a>(r: &'a Renderer<'_>, s: &'a Scene) -> CpuScene<'a> {
    CpuScene {
        scene: s,
        bvh: &r.bvh,
        info: r.gpu.info,
        emitters: &r.gpu.emitters,
    }
}

/// The lines of stderr that are ours (drivers and X libraries may print their own).
pub fn error_lines(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("error: "))
        .collect()
}

/// A cold start's representative points: each cluster's member pixel's shading point (`reps`: the
/// GPU's (distance bits, member) pairs, the member `u32::MAX` for an unused cluster).
pub fn cold_rep_points(sps: &[ShadingPoint], reps: &[u32]) -> Vec<RepPoint> {
    reps.chunks(2)
        .map(|x| match x[1] {
            u32::MAX => RepPoint::NONE,
            m => RepPoint {
                pos: sps[m as usize].pos,
                valid: true,
                nrm: sps[m as usize].normal,
                previous: false,
            },
        })
        .collect()
}

/// Runs the fuzzy-vpl binary with `args`: (exit code, stdout, stderr).
pub fn run_cli(args: &[&str]) -> (i32, String, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_fuzzy-vpl"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Asserts that the CLI refuses `args` with exit 2 and one error line containing `needle`.
pub fn assert_refused(args: &[&str], needle: &str) {
    let (code, _, err) = run_cli(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    let lines = error_lines(&err);
    assert_eq!(lines.len(), 1, "{args:?}: {err}");
    assert!(lines[0].contains(needle), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

/// How far a GPU value is from its CPU twin's: the largest channel difference over 1 + the twin's
/// largest channel (relative above 1, absolute below).
pub fn twin_diff(c: glam::Vec3, g: glam::Vec3) -> f32 {
    (c - g).abs().max_element() / (1.0 + c.abs().max_element())
}

/// A twin comparison's bound on a scalar measure: `software` on a software adapter (lavapipe: the
/// measured maximum × 2, or 0 where the twins are bit-exact; docs/testing.md, "Twin tolerances"); on
/// a GPU 1e-3, not measured (other rounding, fused multiply-adds).
pub fn twin_tol(ctx: &GpuContext, software: f32) -> f32 {
    if ctx.software { software } else { 1e-3 }
}

/// Asserts every (CPU twin, GPU) pair finite and, on a software adapter, every one within `software`
/// (`twin_diff`; docs/testing.md, "Twin tolerances"); on a GPU, not measured, the former rule: at most
/// 1% of them beyond 1e-3 (rays grazing an edge may go another way there). Prints the worst
/// difference (the figure docs/testing.md records) and returns it.
pub fn assert_twins(
    ctx: &GpuContext,
    name: &str,
    pairs: impl IntoIterator<Item = (glam::Vec3, glam::Vec3)>,
    software: f32,
) -> f32 {
    let (mut worst, mut at, mut n, mut beyond) = (0f32, None, 0usize, 0usize);
    for (i, (c, g)) in pairs.into_iter().enumerate() {
        assert!(
            c.is_finite() && g.is_finite(),
            "{name}: item {i}: CPU {c}, GPU {g}"
        );
        let d = twin_diff(c, g);
        if d > worst {
            (worst, at) = (d, Some((i, c, g)));
        }
        beyond += (d > 1e-3) as usize;
        n += 1;
    }
    println!("twin {name}: worst {worst:.3e} of {n} (bound {software:.1e} on software) at {at:?}");
    if ctx.software {
        assert!(
            worst <= software,
            "{name}: worst difference {worst:e} > {software:e} at (item, CPU, GPU) {at:?}"
        );
    } else {
        assert!(beyond * 100 <= n, "{name}: {beyond} of {n} beyond 1e-3");
    }
    worst
}

/// The failure mode of cornell_wgpu (docs/methods.md, "Indirect light, per method") in a
/// built-in room: builtin:cornell with its ceiling light replaced by a closed emitting slab of the
/// same footprint and emission, 1.7e-3 scene diagonals thick, its top 5.9e-5 diagonals under the
/// ceiling (cornell_wgpu's 0.0058 and 0.0002 in its 3.4 diagonal). Half its light goes up into the
/// gap, where the VPLs it makes on the ceiling are hidden from the room.
pub fn slab_under_ceiling() -> Scene {
    use glam::{Vec2, Vec3, Vec4};
    let mut s = fuzzy_vpl::scene::load("builtin:cornell").unwrap();
    let emitting: Vec<bool> = s
        .materials
        .iter()
        .map(|m| m.emissive != Vec3::ZERO)
        .collect();
    let emits = |t: &fuzzy_vpl::scene::Triangle| emitting[t.material as usize];
    let lamp: Vec<_> = s.triangles.iter().filter(|t| emits(t)).copied().collect();
    assert!(!lamp.is_empty());
    let material = lamp[0].material;
    s.triangles.retain(|t| !emits(t));
    let (lo, hi) = lamp.iter().flat_map(|t| t.p).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let (blo, bhi) = s.bounds();
    let diag = (bhi - blo).length();
    let top = bhi.y - 5.9e-5 * diag;
    let bottom = top - 1.7e-3 * diag;
    let (x0, x1, z0, z1) = (lo.x, hi.x, lo.z, hi.z);
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // The six faces, each as a quad (a, b, c, d) wound outwards.
    let quads = [
        [
            c(x0, top, z0),
            c(x0, top, z1),
            c(x1, top, z1),
            c(x1, top, z0),
        ],
        [
            c(x0, bottom, z0),
            c(x1, bottom, z0),
            c(x1, bottom, z1),
            c(x0, bottom, z1),
        ],
        [
            c(x0, bottom, z0),
            c(x0, bottom, z1),
            c(x0, top, z1),
            c(x0, top, z0),
        ],
        [
            c(x1, bottom, z0),
            c(x1, top, z0),
            c(x1, top, z1),
            c(x1, bottom, z1),
        ],
        [
            c(x0, bottom, z0),
            c(x0, top, z0),
            c(x1, top, z0),
            c(x1, bottom, z0),
        ],
        [
            c(x0, bottom, z1),
            c(x1, bottom, z1),
            c(x1, top, z1),
            c(x0, top, z1),
        ],
    ];
    for q in quads {
        for [a, b, d] in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            let n = (b - a).cross(d - a).normalize();
            s.triangles.push(fuzzy_vpl::scene::Triangle {
                p: [a, b, d],
                n: [n; 3],
                uv: [Vec2::ZERO; 3],
                color: [Vec4::ONE; 3],
                material,
            });
        }
    }
    s.name = "slab-under-ceiling".into();
    s
}
