//! Lights given on the command line: `--sun DX,DY,DZ,E[,R,G,B]` and `--point X,Y,Z,I[,R,G,B]`.

use super::{LightKind, PunctualLight};
use glam::Vec3;

/// Parses `N` numbers then optionally three more (an RGB colour, default white).
fn parse_numbers(s: &str, what: &str, form: &str) -> Result<([f32; 4], Vec3), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 4 && parts.len() != 7 {
        return Err(format!(
            "{what} '{s}': expected {form} (4 or 7 comma-separated numbers), got {}",
            parts.len()
        ));
    }
    let mut v = [0f32; 7];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p
            .parse::<f32>()
            .map_err(|_| format!("{what} '{s}': '{p}' is not a number"))?;
        if !v[i].is_finite() {
            return Err(format!("{what} '{s}': '{p}' is not a finite number"));
        }
    }
    let color = if parts.len() == 7 {
        Vec3::new(v[4], v[5], v[6])
    } else {
        Vec3::ONE
    };
    if color.min_element() < 0.0 {
        return Err(format!(
            "{what} '{s}': colour components must not be negative"
        ));
    }
    if v[3] < 0.0 {
        return Err(format!("{what} '{s}': intensity must not be negative"));
    }
    Ok(([v[0], v[1], v[2], v[3]], color))
}

/// Parses `DX,DY,DZ,E[,R,G,B]`: (DX,DY,DZ) points towards the sun (any length but zero), E is the
/// irradiance at normal incidence, RGB a linear colour (default 1,1,1). The returned light's
/// `direction` is the direction the light travels (away from the sun).
pub fn parse_sun(s: &str) -> Result<PunctualLight, String> {
    let ([dx, dy, dz, e], color) = parse_numbers(s, "sun", "DX,DY,DZ,E[,R,G,B]")?;
    let to_sun = Vec3::new(dx, dy, dz).as_dvec3();
    let len = to_sun.length();
    if !(len > 0.0 && len.is_finite()) {
        return Err(format!(
            "sun '{s}': direction must be a non-zero finite vector"
        ));
    }
    Ok(PunctualLight {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: -(to_sun / len).as_vec3(),
        color,
        intensity: e,
    })
}

/// Parses `X,Y,Z,I[,R,G,B]`: a point light at (X,Y,Z) with intensity I (W/sr) and linear RGB colour
/// (default 1,1,1).
pub fn parse_point(s: &str) -> Result<PunctualLight, String> {
    let ([x, y, z, i], color) = parse_numbers(s, "point light", "X,Y,Z,I[,R,G,B]")?;
    Ok(PunctualLight {
        kind: LightKind::Point,
        position: Vec3::new(x, y, z),
        direction: Vec3::NEG_Z,
        color,
        intensity: i,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_direction_is_negated_and_normalised() {
        let l = parse_sun("0, 2, 0, 3.5").unwrap();
        assert_eq!(l.kind, LightKind::Directional);
        assert_eq!(l.direction, Vec3::new(0.0, -1.0, 0.0));
        assert_eq!(l.intensity, 3.5);
        assert_eq!(l.color, Vec3::ONE);
        let l = parse_sun("1,1,0,1,1,0.5,0.25").unwrap();
        assert!((l.direction - Vec3::new(-1.0, -1.0, 0.0).normalize()).length() < 1e-6);
        assert!((l.direction.length() - 1.0).abs() < 1e-6);
        assert_eq!(l.color, Vec3::new(1.0, 0.5, 0.25));
        // Tiny but non-zero directions still normalise.
        let l = parse_sun("1e-30,0,0,1").unwrap();
        assert_eq!(l.direction, Vec3::NEG_X);
    }

    #[test]
    fn point_light() {
        let l = parse_point("1,2,-3,100,0.5,0.5,1").unwrap();
        assert_eq!(l.kind, LightKind::Point);
        assert_eq!(l.position, Vec3::new(1.0, 2.0, -3.0));
        assert_eq!(l.intensity, 100.0);
        assert_eq!(l.color, Vec3::new(0.5, 0.5, 1.0));
        assert_eq!(parse_point("0,0,0,0").unwrap().intensity, 0.0);
    }

    #[test]
    fn rejects_bad_input() {
        for bad in [
            "",
            "1,2,3",
            "1,2,3,4,5",
            "1,2,3,4,5,6,7,8",
            "a,0,0,1",
            "0,0,0,1",
            "NaN,1,0,1",
            "0,1,0,inf",
            "0,1,0,-1",
            "0,1,0,1,1,-1,1",
            "0,1,0,1,1,nan,1",
        ] {
            let e = parse_sun(bad).expect_err(bad);
            assert!(e.starts_with("sun"), "{e}");
        }
        for bad in [
            "1,2,3",
            "1,2,3,-4",
            "1,nan,3,4",
            "1,2,3,4,1,1,-1",
            "x,y,z,w",
        ] {
            let e = parse_point(bad).expect_err(bad);
            assert!(e.starts_with("point light"), "{e}");
        }
        assert!(parse_sun("0,0,0,1").unwrap_err().contains("non-zero"));
        assert!(parse_point("0,0,0,-1").unwrap_err().contains("negative"));
    }
}
