//! The node hierarchy, its transforms, and the lights and cameras the nodes carry.

use crate::scene::{Camera, LightKind, LoadReport, PunctualLight};
use glam::{Mat4, Quat, Vec3};

/// A node's local matrix. TRS rotations are normalised (glTF requires unit quaternions; a
/// non-unit one would otherwise shear).
fn local_matrix(node: &gltf::Node) -> Mat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = Quat::from_array(rotation);
            let q = if q.length_squared() > 0.0 && q.is_finite() {
                q.normalize()
            } else {
                Quat::IDENTITY
            };
            Mat4::from_scale_rotation_translation(Vec3::from(scale), q, Vec3::from(translation))
        }
    }
}

/// `(node index, world matrix)` for every node of the scene to render, parents before children.
pub(super) fn flatten_nodes(doc: &gltf::Document) -> Result<Vec<(usize, Mat4)>, String> {
    let count = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; count];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if c == node.index() {
                return Err(format!("invalid node hierarchy: node {c} is its own child"));
            }
            if let Some(p) = parent[c] {
                return Err(format!(
                    "invalid node hierarchy: node {c} has two parents (nodes {p} and {})",
                    node.index()
                ));
            }
            parent[c] = Some(node.index());
        }
    }

    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            let roots: Vec<usize> = scene.nodes().map(|n| n.index()).collect();
            if let Some(&r) = roots.iter().find(|&&r| parent[r].is_some()) {
                return Err(format!(
                    "invalid node hierarchy: scene root node {r} is a child of node {}",
                    parent[r].unwrap_or(0)
                ));
            }
            roots
        }
        None => (0..count).filter(|&i| parent[i].is_none()).collect(),
    };

    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut visited = vec![false; count];
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    while let Some((i, parent_world)) = stack.pop() {
        if std::mem::replace(&mut visited[i], true) {
            return Err(format!(
                "invalid node hierarchy: node {i} is reached twice (a cycle or a repeated scene root)"
            ));
        }
        let world = parent_world * local_matrix(&nodes[i]);
        out.push((i, world));
        for child in nodes[i].children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child.index(), world));
        }
    }
    Ok(out)
}

/// A warning for a node whose TRS rotation is no rotation (a zero or non-finite quaternion; the
/// identity is used, `local_matrix`), naming what the node carries.
pub(super) fn zero_rotation_warning(node: &gltf::Node) -> Option<String> {
    let gltf::scene::Transform::Decomposed { rotation, .. } = node.transform() else {
        return None;
    };
    let q = Quat::from_array(rotation);
    if q.is_finite() && q.length_squared() > 0.0 {
        return None;
    }
    let mut what = Vec::new();
    if let Some(c) = node.camera() {
        what.push(format!("camera '{}'", c.name().unwrap_or("")));
    }
    if let Some(l) = node.light() {
        what.push(format!("light '{}'", l.name().unwrap_or("")));
    }
    if node.mesh().is_some() {
        what.push("a mesh".to_string());
    }
    let what = if what.is_empty() {
        String::new()
    } else {
        format!(" ({})", what.join(", "))
    };
    Some(format!(
        "node {}{what}: rotation {rotation:?} is a zero or non-finite quaternion, not a rotation; the identity is used for it",
        node.index()
    ))
}

pub(super) fn light_from_node(
    light: &gltf::khr_lights_punctual::Light,
    world: &Mat4,
    report: &mut LoadReport,
) -> Option<PunctualLight> {
    use gltf::khr_lights_punctual::Kind;
    let name = light
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("light {}", light.index()));
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    if !color.is_finite() || color.min_element() < 0.0 || !intensity.is_finite() || intensity < 0.0
    {
        report.warnings.push(format!(
            "light '{name}': invalid colour or intensity, light skipped"
        ));
        return None;
    }
    let position = world.w_axis.truncate();
    let direction = (world.as_dmat4())
        .transform_vector3(glam::DVec3::NEG_Z)
        .normalize_or_zero()
        .as_vec3();
    if !position.is_finite() || direction == Vec3::ZERO || !direction.is_finite() {
        report.warnings.push(format!(
            "light '{name}': its node transform is degenerate, light skipped"
        ));
        return None;
    }
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let half_pi = std::f32::consts::FRAC_PI_2;
            let ok =
                (0.0..outer_cone_angle).contains(&inner_cone_angle) && outer_cone_angle <= half_pi;
            if ok {
                LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                }
            } else {
                let outer = if outer_cone_angle.is_finite() {
                    outer_cone_angle.clamp(1e-3, half_pi)
                } else {
                    std::f32::consts::FRAC_PI_4
                };
                let inner = if inner_cone_angle.is_finite() {
                    inner_cone_angle.clamp(0.0, outer * 0.999)
                } else {
                    0.0
                };
                report.warnings.push(format!(
                    "light '{name}': spot cone angles must satisfy 0 <= inner < outer <= pi/2; using inner {inner:.4}, outer {outer:.4}"
                ));
                LightKind::Spot {
                    inner_cone: inner,
                    outer_cone: outer,
                }
            }
        }
    };
    Some(PunctualLight {
        kind,
        position,
        direction,
        color,
        intensity,
    })
}

pub(super) fn camera_from_node(
    doc: &gltf::Document,
    node: &gltf::Node,
    world: &Mat4,
    report: &mut LoadReport,
) -> Option<Camera> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let index = node.camera()?.index();
    let json = doc.as_json().cameras.get(index)?;
    let name = json
        .name
        .clone()
        .or_else(|| node.name().map(str::to_string))
        .unwrap_or_else(|| format!("camera {index}"));
    let yfov = match (&json.type_, &json.perspective) {
        (Checked::Valid(Type::Perspective), Some(p)) => p.yfov,
        (Checked::Valid(Type::Orthographic), _) => {
            report.warnings.push(format!(
                "camera '{name}' is orthographic, which is not supported; skipped"
            ));
            return None;
        }
        _ => {
            report
                .warnings
                .push(format!("camera '{name}' has no usable projection; skipped"));
            return None;
        }
    };
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        report
            .warnings
            .push(format!("camera '{name}': invalid yfov {yfov}; skipped"));
        return None;
    }
    // In f64: under a node scale of 1e-40 (or 1e30) the f32 decomposition is no longer finite.
    let (_, rotation, translation) = world.as_dmat4().to_scale_rotation_translation();
    let transform = Mat4::from_rotation_translation(
        rotation.normalize().as_quat().normalize(),
        translation.as_vec3(),
    );
    if !transform.is_finite() {
        report.warnings.push(format!(
            "camera '{name}': its node transform is degenerate; skipped"
        ));
        return None;
    }
    Some(Camera {
        name,
        transform,
        yfov,
    })
}
