//! The viewer's camera: one state (eye, yaw, pitch, field of view, orbit distance) driven two ways.
//! Fly: WASD/QE move the eye, the mouse turns it. Orbit: the mouse turns the eye around the point
//! `distance` ahead of it, the wheel changes that distance. Yaw 0 / pitch 0 looks down −Z with +Y up
//! (glTF's convention); pitch is kept inside ±89° so +Y stays a valid up vector.

use glam::Vec3;

use crate::scene::Camera;

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    Fly,
    Orbit,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    pub eye: Vec3,
    /// Radians, positive turns left (counter-clockwise seen from +Y).
    pub yaw: f32,
    /// Radians, positive looks up.
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub yfov: f32,
    /// Orbit radius: the orbit centre is `eye + forward × distance`.
    pub distance: f32,
}

/// Unit view direction for (yaw, pitch).
pub fn direction(yaw: f32, pitch: f32) -> Vec3 {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    Vec3::new(-sy * cp, sp, -cy * cp)
}

impl ViewCamera {
    /// The state that looks like `cam` (roll is dropped); `distance` is the orbit radius to start with.
    pub fn from_camera(cam: &Camera, distance: f32) -> Self {
        let f = cam.forward();
        let pitch = f.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = (-f.x).atan2(-f.z);
        ViewCamera {
            eye: cam.eye(),
            yaw,
            pitch,
            yfov: cam.yfov,
            distance: distance.max(1e-6),
        }
    }

    pub fn forward(&self) -> Vec3 {
        direction(self.yaw, self.pitch)
    }

    /// Unit right vector (horizontal).
    pub fn right(&self) -> Vec3 {
        let (s, c) = self.yaw.sin_cos();
        Vec3::new(c, 0.0, -s)
    }

    pub fn target(&self) -> Vec3 {
        self.eye + self.forward() * self.distance
    }

    pub fn to_camera(&self) -> Camera {
        Camera::look_at(
            "viewer",
            self.eye,
            self.eye + self.forward(),
            Vec3::Y,
            self.yfov,
        )
    }

    /// Fly: turns the view by (dyaw, dpitch) radians around the eye.
    pub fn look(&mut self, dyaw: f32, dpitch: f32) {
        self.yaw = wrap(self.yaw + dyaw);
        self.pitch = (self.pitch + dpitch).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Fly: moves along (right, up, forward) = `local` in world units.
    pub fn fly(&mut self, local: Vec3) {
        self.eye += self.right() * local.x + Vec3::Y * local.y + self.forward() * local.z;
    }

    /// Orbit: turns the eye around the target by (dyaw, dpitch); the target stays put.
    pub fn orbit(&mut self, dyaw: f32, dpitch: f32) {
        let t = self.target();
        self.look(dyaw, dpitch);
        self.eye = t - self.forward() * self.distance;
    }

    /// The self-measurement's motion (`view --animate`) at `t` seconds from `self`: the eye circles
    /// in the horizontal plane, radius 2.5% of the scene's `diagonal`, through the start eye (so it
    /// stays within 5% of it, in the free space the start camera sees from), one turn in about 10 s,
    /// while the view pans ±20° about the eye, period about 12.6 s. An orbit about a point across
    /// the scene would take the eye through walls (the conference room: within 2–3 s).
    pub fn animated(&self, diagonal: f32, t: f32) -> ViewCamera {
        let r = 0.025 * diagonal;
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize_or_zero();
        let (fwd, right) = (flat(self.forward()), flat(self.right()));
        let a = 0.6 * t;
        let centre = self.eye + right * r;
        let mut c = *self;
        c.eye = centre - right * (r * a.cos()) + fwd * (r * a.sin());
        c.yaw = self.yaw + 0.35 * (0.5 * t).sin();
        c
    }

    /// Orbit: scales the distance to the target by `factor` (the target stays put).
    pub fn zoom(&mut self, factor: f32) {
        let t = self.target();
        self.distance = (self.distance * factor).max(1e-6);
        self.eye = t - self.forward() * self.distance;
    }
}

fn wrap(a: f32) -> f32 {
    let tau = std::f32::consts::TAU;
    (a + std::f32::consts::PI).rem_euclid(tau) - std::f32::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn zero_angles_look_down_minus_z() {
        let c = ViewCamera {
            eye: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            yfov: 1.0,
            distance: 1.0,
        };
        assert!(close(c.forward(), -Vec3::Z));
        assert!(close(c.right(), Vec3::X));
        let cam = c.to_camera();
        assert!(close(cam.forward(), -Vec3::Z));
        assert!(close(cam.up(), Vec3::Y));
    }

    #[test]
    fn round_trips_through_scene_camera() {
        let cam = Camera::look_at(
            "t",
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-2.0, 0.5, -1.0),
            Vec3::Y,
            0.8,
        );
        let v = ViewCamera::from_camera(&cam, 5.0);
        let back = v.to_camera();
        assert!(close(back.eye(), cam.eye()));
        assert!(close(back.forward(), cam.forward()));
        assert!((back.yfov - 0.8).abs() < 1e-6);
    }

    #[test]
    fn fly_moves_in_view_space() {
        let mut c = ViewCamera {
            eye: Vec3::ZERO,
            yaw: std::f32::consts::FRAC_PI_2,
            pitch: 0.0,
            yfov: 1.0,
            distance: 1.0,
        };
        // Yaw +90°: looking down −X, right is −Z.
        assert!(close(c.forward(), -Vec3::X));
        c.fly(Vec3::new(0.0, 0.0, 2.0));
        assert!(close(c.eye, Vec3::new(-2.0, 0.0, 0.0)));
        c.fly(Vec3::new(1.0, 3.0, 0.0));
        assert!(close(c.eye, Vec3::new(-2.0, 3.0, -1.0)));
    }

    #[test]
    fn pitch_is_clamped() {
        let mut c = ViewCamera::from_camera(
            &Camera::look_at("t", Vec3::ZERO, -Vec3::Z, Vec3::Y, 1.0),
            1.0,
        );
        c.look(0.0, 10.0);
        assert!(c.pitch <= MAX_PITCH + 1e-6);
        assert!(c.to_camera().forward().is_finite());
    }

    /// The animation starts at the start camera, stays within 5% of the diagonal of its eye, at
    /// its height, pans at most 0.35 rad, and moves.
    #[test]
    fn the_animation_stays_near_the_start_eye() {
        let c0 = ViewCamera::from_camera(
            &Camera::look_at("t", Vec3::new(3.6, 1.5, 0.8), Vec3::ZERO, Vec3::Y, 1.0),
            4.0,
        );
        let diag = 9.9;
        let a0 = c0.animated(diag, 0.0);
        assert!(close(a0.eye, c0.eye) && (a0.yaw - c0.yaw).abs() < 1e-6);
        let mut far = 0.0f32;
        for i in 0..600 {
            let a = c0.animated(diag, i as f32 * 0.05);
            let d = (a.eye - c0.eye).length();
            assert!(d <= 0.05 * diag + 1e-4, "t {}: {d}", i as f32 * 0.05);
            assert!((a.eye.y - c0.eye.y).abs() < 1e-5);
            assert!((a.yaw - c0.yaw).abs() <= 0.35 + 1e-6 && a.pitch == c0.pitch);
            far = far.max(d);
        }
        assert!(far > 0.04 * diag, "it hardly moves: {far}");
    }

    #[test]
    fn orbit_keeps_target_and_distance() {
        let mut c = ViewCamera::from_camera(
            &Camera::look_at("t", Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0),
            5.0,
        );
        let t = c.target();
        assert!(close(t, Vec3::ZERO));
        c.orbit(0.7, -0.3);
        assert!(close(c.target(), t));
        assert!(((c.eye - t).length() - 5.0).abs() < 1e-4);
        c.orbit(std::f32::consts::PI, 0.0);
        assert!(close(c.target(), t));
        c.zoom(0.5);
        assert!(close(c.target(), t));
        assert!(((c.eye - t).length() - 2.5).abs() < 1e-4);
    }
}
