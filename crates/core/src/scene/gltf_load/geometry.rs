//! Mesh primitives: their vertex attributes and indices, decoded once, and their world-space
//! triangles per node instance.

use super::materials::{MaterialTable, finite_or};
use super::{accessor, uri};
use crate::scene::{LoadReport, Triangle};
use glam::{Affine2, DMat3, Mat4, Vec2, Vec3, Vec4};

/// A mesh primitive decoded once, in its local space, shared by every node that instances it.
pub(super) enum Primitive {
    Triangles {
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        /// COLOR_0 as linear RGBA (alpha 1 for RGB).
        colors: Option<Vec<Vec4>>,
        /// Vertex index triples, in glTF winding order.
        tris: Vec<[u32; 3]>,
        material: u32,
    },
    /// Points or lines: not rendered.
    Skipped,
}

/// Decodes primitive `prim` of `mesh` once: its vertex attributes, its indices as triangles, and its
/// material (`table`); points and lines are `Skipped`. Warnings go to `report`.
pub(super) fn decode_primitive(
    prim: &gltf::Primitive,
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    table: &mut MaterialTable,
    report: &mut LoadReport,
) -> Result<Primitive, String> {
    use gltf::mesh::Mode;
    let label = match mesh.name() {
        Some(n) => format!(
            "mesh {} ('{}') primitive {}",
            mesh.index(),
            uri::short(n),
            prim.index()
        ),
        None => format!("mesh {} primitive {}", mesh.index(), prim.index()),
    };
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        report.skipped_primitives += 1;
        return Ok(Primitive::Skipped);
    }

    let positions = read_positions(prim, buffers, &label)?;
    let n = positions.len();
    let normals = prim.get(&gltf::Semantic::Normals).and_then(|acc| {
        let v = accessor::read_floats::<3>(&acc, buffers, &format!("{label} NORMAL"));
        let v = v.map(|v| v.into_iter().map(Vec3::from).collect());
        per_vertex(v, &NORMAL, &label, n, report)
    });
    let uvs = prim.get(&gltf::Semantic::TexCoords(0)).and_then(|acc| {
        let v = accessor::read_floats::<2>(&acc, buffers, &format!("{label} TEXCOORD_0"));
        let v = v.map(|v| v.into_iter().map(Vec2::from).collect());
        per_vertex(v, &TEXCOORD_0, &label, n, report)
    });
    let colors = prim.get(&gltf::Semantic::Colors(0)).and_then(|acc| {
        let v = read_colors(&acc, buffers, &format!("{label} COLOR_0"));
        let v = per_vertex(v, &COLOR_0, &label, n, report)?;
        Some(clamp_colors(v, &label, report))
    });

    let indices: Vec<u32> = match prim.indices() {
        Some(acc) => {
            let idx = accessor::read_indices(&acc, buffers, &format!("{label} indices"))?;
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "{label}: index {bad} out of range (the primitive has {n} vertices)"
                ));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };
    let tris = triangles(mode, &indices, &label, report);

    Ok(Primitive::Triangles {
        positions,
        normals,
        uvs,
        colors,
        tris,
        material: table.index_for(prim.material().index()),
    })
}

/// POSITION, required: an error when it is missing or has a non-finite value.
fn read_positions(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    label: &str,
) -> Result<Vec<Vec3>, String> {
    let pos_acc = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| format!("{label} has no POSITION attribute"))?;
    let positions: Vec<Vec3> =
        accessor::read_floats::<3>(&pos_acc, buffers, &format!("{label} POSITION"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
    if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "{label} POSITION has a non-finite value ({}) at vertex {v}",
            positions[v]
        ));
    }
    Ok(positions)
}

/// An optional vertex attribute: its name and what the load does without it (in the warning after a
/// wrong entry count, and after an accessor it cannot read).
struct Optional {
    name: &'static str,
    wrong_count: &'static str,
    unreadable: &'static str,
}

const NORMAL: Optional = Optional {
    name: "NORMAL",
    wrong_count: "normals generated",
    unreadable: "normals generated",
};
const TEXCOORD_0: Optional = Optional {
    name: "TEXCOORD_0",
    wrong_count: "ignored",
    unreadable: "texture coordinates ignored",
};
const COLOR_0: Optional = Optional {
    name: "COLOR_0",
    wrong_count: "ignored",
    unreadable: "vertex colours ignored",
};

/// `read`'s values of optional attribute `attr` when there is one per vertex (`n`), else a warning
/// and `None`.
fn per_vertex<T>(
    read: Result<Vec<T>, String>,
    attr: &Optional,
    label: &str,
    n: usize,
    report: &mut LoadReport,
) -> Option<Vec<T>> {
    match read {
        Ok(v) if v.len() == n => Some(v),
        Ok(v) => {
            report.warnings.push(format!(
                "{label}: {} has {} entries for {n} vertices, {}",
                attr.name,
                v.len(),
                attr.wrong_count
            ));
            None
        }
        Err(e) => {
            report.warnings.push(format!("{e}; {}", attr.unreadable));
            None
        }
    }
}

/// COLOR_0 clamped to [0, 1] (a non-finite value becomes 1), with a warning when any was outside.
fn clamp_colors(v: Vec<Vec4>, label: &str, report: &mut LoadReport) -> Vec<Vec4> {
    if v.iter()
        .any(|c| !c.is_finite() || c.cmplt(Vec4::ZERO).any() || c.cmpgt(Vec4::ONE).any())
    {
        report.warnings.push(format!(
            "{label}: COLOR_0 has values outside [0, 1], clamped"
        ));
    }
    v.into_iter()
        .map(|c| finite_or(c, Vec4::ONE).clamp(Vec4::ZERO, Vec4::ONE))
        .collect()
}

/// The vertex index triples of `indices` drawn in `mode` (a triangle mode), in glTF winding order.
fn triangles(
    mode: gltf::mesh::Mode,
    indices: &[u32],
    label: &str,
    report: &mut LoadReport,
) -> Vec<[u32; 3]> {
    use gltf::mesh::Mode;
    match mode {
        Mode::Triangles => {
            if !indices.len().is_multiple_of(3) {
                report.warnings.push(format!(
                    "{label}: {} indices is not a multiple of 3, the last {} ignored",
                    indices.len(),
                    indices.len() % 3
                ));
            }
            indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect()
        }
        // glTF: triangle i = (v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]).
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        // glTF: triangle i = (v[i + 1], v[i + 2], v[0]).
        _ => (0..indices.len().saturating_sub(2))
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
    }
}

/// COLOR_0: VEC3 or VEC4 of float or normalised unsigned byte / short, as linear RGBA.
fn read_colors(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec4>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let ok_type = match acc.data_type() {
        DataType::F32 => true,
        DataType::U8 | DataType::U16 => acc.normalized(),
        _ => false,
    };
    if !ok_type {
        return Err(format!(
            "{what} (accessor {}) must be float or normalised unsigned byte or short",
            acc.index()
        ));
    }
    match acc.dimensions() {
        Dimensions::Vec3 => Ok(accessor::read_floats::<3>(acc, buffers, what)?
            .into_iter()
            .map(|c| Vec3::from(c).extend(1.0))
            .collect()),
        _ => Ok(accessor::read_floats::<4>(acc, buffers, what)?
            .into_iter()
            .map(Vec4::from)
            .collect()),
    }
}

/// Appends the world-space triangles of one primitive instance. Invalid normals are left as
/// `Vec3::ZERO` and filled in later with the face normal.
pub(super) fn emit(
    prim: &Primitive,
    world: &Mat4,
    node: usize,
    uv_transform: &[Option<Affine2>],
    out: &mut Vec<Triangle>,
) -> Result<(), String> {
    let Primitive::Triangles {
        positions,
        normals,
        uvs,
        colors,
        tris,
        material,
    } = prim
    else {
        return Ok(());
    };
    let world_pos: Vec<Vec3> = positions
        .iter()
        .map(|&p| world.transform_point3(p))
        .collect();
    if let Some(p) = world_pos.iter().find(|p| !p.is_finite()) {
        return Err(format!(
            "node {node}: a vertex position is not finite after the node transform ({p})"
        ));
    }
    // In f64 so that tiny (or huge) scales keep a usable determinant sign and inverse.
    let m3 = DMat3::from_mat4(world.as_dmat4());
    let det = m3.determinant();
    let normal_matrix = (det != 0.0 && det.is_finite())
        .then(|| m3.inverse().transpose().as_mat3())
        .filter(|m| m.is_finite());
    let world_n: Option<Vec<Vec3>> = match (normals, normal_matrix) {
        (Some(ns), Some(nm)) => Some(
            ns.iter()
                .map(|&n| {
                    let v = (nm * n).normalize_or_zero();
                    if v.is_finite() { v } else { Vec3::ZERO }
                })
                .collect(),
        ),
        _ => None,
    };
    let xf = uv_transform[*material as usize];
    let world_uv: Option<Vec<Vec2>> = uvs.as_ref().map(|uvs| match xf {
        Some(a) => uvs.iter().map(|&uv| a.transform_point2(uv)).collect(),
        None => uvs.clone(),
    });

    out.reserve(tris.len());
    for &t in tris {
        // A mirroring transform reverses the winding; swap to keep the front face.
        let t = if det < 0.0 { [t[0], t[2], t[1]] } else { t };
        let [a, b, c] = t.map(|i| i as usize);
        out.push(Triangle {
            p: [world_pos[a], world_pos[b], world_pos[c]],
            n: match &world_n {
                Some(n) => [n[a], n[b], n[c]],
                None => [Vec3::ZERO; 3],
            },
            uv: match &world_uv {
                Some(uv) => [uv[a], uv[b], uv[c]],
                None => [Vec2::ZERO; 3],
            },
            color: match colors {
                Some(col) => [col[a], col[b], col[c]],
                None => [Vec4::ONE; 3],
            },
            material: *material,
        });
    }
    Ok(())
}

/// A mesh instance placed so far from the origin, for its size, that f32 positions cannot resolve it.
pub(super) struct FarNode {
    node: usize,
    /// The largest coordinate magnitude of its vertices (world units, computed in f64).
    far: f64,
    /// Its bounding-box diagonal (world units, f64).
    size: f64,
}

impl FarNode {
    pub(super) fn describe(&self) -> String {
        format!(
            "node {} lies {:.3e} from the origin, where f32 positions are {:.1e} apart, and its mesh is only {:.3e} across",
            self.node,
            self.far,
            self.far * f32::EPSILON as f64,
            self.size
        )
    }
}

/// `Some` when an instance of `prim` under `world` spans fewer than 10 f32 spacings at its distance
/// from the origin (its shape is then quantised to a few positions or collapses to nothing).
pub(super) fn too_far_for_f32(prim: &Primitive, world: &Mat4, node: usize) -> Option<FarNode> {
    let Primitive::Triangles { positions, .. } = prim else {
        return None;
    };
    let w = world.as_dmat4();
    let mut lo = glam::DVec3::splat(f64::INFINITY);
    let mut hi = glam::DVec3::splat(f64::NEG_INFINITY);
    for p in positions {
        let q = w.transform_point3(p.as_dvec3());
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let far = lo.abs().max(hi.abs()).max_element();
    let size = (hi - lo).length();
    (size > 0.0 && far * (f32::EPSILON as f64) > 0.1 * size).then_some(FarNode { node, far, size })
}

/// Whether a triangle has (numerically) no area, relative to the scene and to its own size.
pub(super) fn is_degenerate(t: &Triangle, extent_sq: f64) -> bool {
    let p = t.p.map(|v| v.as_dvec3());
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let twice_area = e[0].cross(-e[2]).length();
    let longest_sq = e.iter().map(|v| v.length_squared()).fold(0.0, f64::max);
    twice_area <= 2.0 * DEGENERATE_AREA_REL * extent_sq
        || twice_area <= DEGENERATE_SLIVER_REL * longest_sq
}

/// A triangle is degenerate when its area is at most this fraction of the squared scene extent
/// (bounding-box diagonal), which keeps the test scale-free.
const DEGENERATE_AREA_REL: f64 = 1e-12;
/// …or when twice its area is at most this fraction of its longest edge squared (numerically
/// collinear vertices: its height is below f32 precision relative to its length).
const DEGENERATE_SLIVER_REL: f64 = 1e-7;

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh is too far for f32 when its distance from the origin times f32's epsilon passes a tenth
    /// of its size: a 10-unit mesh at 5·10⁶ (0.60 against 1.0) is not, at 2·10⁷ (2.4) it is
    /// (cargo-mutants: `0.1 * size` as `0.1 / size` survived; the loader's test mesh is 1 unit wide,
    /// where the two agree).
    #[test]
    fn too_far_for_f32_compares_with_a_tenth_of_the_size() {
        let at = |x: f32| Primitive::Triangles {
            positions: vec![
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 10.0, 0.0, 0.0),
                Vec3::new(x, 0.0, 0.0),
            ],
            normals: None,
            uvs: None,
            colors: None,
            tris: vec![[0, 1, 2]],
            material: 0,
        };
        assert!(too_far_for_f32(&at(5e6), &Mat4::IDENTITY, 0).is_none());
        let far = too_far_for_f32(&at(2e7), &Mat4::IDENTITY, 3).unwrap();
        assert_eq!(far.node, 3);
        assert!((far.size - 10.0).abs() < 1e-6 && (far.far - 2e7 - 10.0).abs() < 1.0);
    }

    /// At the bound, far · ε = 0.1 · size exactly, a mesh is not too far: a 6 × 8 triangle (diagonal
    /// 10, 0.1 · 10 = 1 in f64) reaching 2²³ (2²³ · 2⁻²³ = 1). A mesh of one point (size 0) is
    /// never too far, wherever it is (cargo-mutants: both `>` as `>=` survived).
    #[test]
    fn too_far_for_f32_at_its_bound_and_for_a_point() {
        let tri = |p: [Vec3; 3]| Primitive::Triangles {
            positions: p.to_vec(),
            normals: None,
            uvs: None,
            colors: None,
            tris: vec![[0, 1, 2]],
            material: 0,
        };
        let x = 8388608.0;
        let bound = tri([
            Vec3::new(x - 6.0, 0.0, 0.0),
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x - 6.0, 8.0, 0.0),
        ]);
        assert!(too_far_for_f32(&bound, &Mat4::IDENTITY, 0).is_none());
        // One unit further, it is.
        let past = Mat4::from_translation(Vec3::X);
        assert!(too_far_for_f32(&bound, &past, 0).is_some());
        let point = tri([Vec3::splat(1e30); 3]);
        assert!(too_far_for_f32(&point, &Mat4::IDENTITY, 0).is_none());
    }
}
