//! The viewer's camera control, pure maths with no window or GPU: an arcball (Shoemake) orbit camera with zoom
//! and pan, turntable auto-rotation, the rotations that look along an axis, and the fly-to animation.

use crate::scene::camera::Camera;
use glam::{Mat3, Quat, Vec2, Vec3};

/// A camera orbiting `target` at `distance`. `rotation` maps camera axes to world axes: the camera's right is
/// `rotation * X`, its up `rotation * Y`, and it sits on `rotation * Z` from the target (looking along -Z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitView {
    pub rotation: Quat,
    pub distance: f32,
    pub target: Vec3,
    pub fov_y_deg: f32,
}

impl OrbitView {
    /// The orbit view that reproduces `camera` (same eye, target, up and field of view).
    pub fn from_camera(camera: &Camera) -> OrbitView {
        let back = (camera.eye - camera.target).normalize();
        let right = camera.up.cross(back).normalize();
        let up = back.cross(right);
        OrbitView {
            rotation: Quat::from_mat3(&Mat3::from_cols(right, up, back)).normalize(),
            distance: (camera.eye - camera.target).length(),
            target: camera.target,
            fov_y_deg: camera.fov_y_deg,
        }
    }

    pub fn camera(&self) -> Camera {
        let mut c = Camera::looking_at(self.target + self.rotation * Vec3::Z * self.distance, self.target);
        c.up = self.rotation * Vec3::Y;
        c.fov_y_deg = self.fov_y_deg;
        c
    }

    /// Rotates the view as if the mouse dragged the scene from `from` to `to` (pixels, y down) on a virtual
    /// trackball filling `viewport`.
    pub fn arcball(&mut self, from: Vec2, to: Vec2, viewport: Vec2) {
        let a = arcball_point(from, viewport);
        let b = arcball_point(to, viewport);
        let turn = Quat::from_rotation_arc(a, b);
        // The scene turns by `turn` in camera space, so the camera turns the other way.
        self.rotation = (self.rotation * turn.inverse()).normalize();
    }

    /// Wheel zoom: each notch (1.0) brings the camera 10% closer; clamped so the target stays in front.
    pub fn zoom(&mut self, notches: f32) {
        self.distance = (self.distance * 0.9f32.powf(notches)).clamp(0.02, 50.0);
    }

    /// Moves the target so the scene follows a drag of `delta` pixels in a `viewport`-sized view.
    pub fn pan(&mut self, delta: Vec2, viewport: Vec2) {
        let world_per_px = 2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan() / viewport.y.max(1.0);
        let right = self.rotation * Vec3::X;
        let up = self.rotation * Vec3::Y;
        self.target += (-delta.x * right + delta.y * up) * world_per_px;
    }

    /// Turntable rotation about world +z (auto-rotate).
    pub fn turn(&mut self, radians: f32) {
        self.rotation = (Quat::from_rotation_z(radians) * self.rotation).normalize();
    }
}

/// Shoemake's arcball: a point in the viewport mapped onto a unit sphere in camera space (x right, y up, z
/// towards the viewer), or onto the hyperbolic sheet outside it so drags stay smooth at the rim.
pub fn arcball_point(p: Vec2, viewport: Vec2) -> Vec3 {
    let r = viewport.x.min(viewport.y).max(1.0) * 0.5;
    let x = (p.x - viewport.x * 0.5) / r;
    let y = (viewport.y * 0.5 - p.y) / r;
    let d2 = x * x + y * y;
    if d2 <= 0.5 {
        Vec3::new(x, y, (1.0 - d2).sqrt())
    } else {
        Vec3::new(x, y, 0.5 / d2.sqrt()).normalize()
    }
}

/// The rotation that looks along `-axis` from its positive side (so the clicked axis points at the viewer),
/// +z up, or +y up when looking along z.
pub fn look_along(axis: usize, positive: bool) -> Quat {
    let mut back = Vec3::ZERO;
    back[axis] = if positive { 1.0 } else { -1.0 };
    let up0 = if axis == 2 { Vec3::Y } else { Vec3::Z };
    let right = up0.cross(back).normalize();
    let up = back.cross(right);
    Quat::from_mat3(&Mat3::from_cols(right, up, back)).normalize()
}

/// A fly-to animation of the view's rotation.
#[derive(Clone, Copy, Debug)]
pub struct RotationAnimation {
    pub from: Quat,
    pub to: Quat,
    /// Seconds since start.
    pub elapsed: f32,
    pub duration: f32,
}

impl RotationAnimation {
    pub fn new(from: Quat, to: Quat) -> RotationAnimation {
        RotationAnimation {
            from,
            to,
            elapsed: 0.0,
            duration: 0.4,
        }
    }

    /// Advances by `dt` seconds; returns the rotation now and whether the animation has finished.
    pub fn step(&mut self, dt: f32) -> (Quat, bool) {
        self.elapsed += dt;
        let t = (self.elapsed / self.duration).clamp(0.0, 1.0);
        let eased = t * t * (3.0 - 2.0 * t);
        (self.from.slerp(self.to, eased).normalize(), t >= 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn orbit_view_round_trips_a_camera() {
        let cam = Camera::orbit(35.0, 25.0, 2.5, Vec3::new(0.1, 0.0, 0.0));
        let back = OrbitView::from_camera(&cam).camera();
        assert!(close(back.eye, cam.eye) && close(back.target, cam.target));
        // `up` comes back orthogonalised; the view it gives is the same.
        assert!(
            back.view().abs_diff_eq(cam.view(), 1e-5),
            "{} vs {}",
            back.view(),
            cam.view()
        );
        assert_eq!(back.fov_y_deg, cam.fov_y_deg);
    }

    #[test]
    fn arcball_centre_is_the_sphere_pole_and_rim_is_continuous() {
        let vp = Vec2::new(200.0, 100.0);
        assert!(close(arcball_point(Vec2::new(100.0, 50.0), vp), Vec3::Z));
        let inside = arcball_point(Vec2::new(100.0 + 35.35, 50.0), vp);
        let outside = arcball_point(Vec2::new(100.0 + 35.37, 50.0), vp);
        assert!((inside - outside).length() < 1e-2, "{inside} vs {outside}");
        assert!((arcball_point(Vec2::new(0.0, 0.0), vp).length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn dragging_right_turns_the_scene_right() {
        let mut v = OrbitView::from_camera(&Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO));
        let vp = Vec2::new(400.0, 400.0);
        // Seen from +y with +z up, world -x is screen right. Dragging right moves the front of the scene right,
        // i.e. the camera swings towards +x... so the eye's x grows.
        v.arcball(Vec2::new(200.0, 200.0), Vec2::new(260.0, 200.0), vp);
        let eye = v.camera().eye;
        assert!(eye.x > 0.1, "{eye}");
        assert!((eye.length() - 3.0).abs() < 1e-4, "orbiting keeps the distance");
        assert!(
            close(v.camera().up, Vec3::Z),
            "a horizontal drag through the centre keeps +z up"
        );
    }

    #[test]
    fn zoom_and_pan() {
        let mut v = OrbitView::from_camera(&Camera::orbit(0.0, 0.0, 2.0, Vec3::ZERO));
        v.zoom(1.0);
        assert!((v.distance - 1.8).abs() < 1e-5);
        v.zoom(-1000.0);
        assert_eq!(v.distance, 50.0);
        let mut v = OrbitView::from_camera(&Camera::orbit(0.0, 0.0, 2.0, Vec3::ZERO));
        v.pan(Vec2::new(0.0, 100.0), Vec2::new(100.0, 100.0));
        // Dragging down moves the scene down, so the target moves up by the view's full height.
        let height = 2.0 * 2.0 * (15f32).to_radians().tan();
        assert!(close(v.target, Vec3::new(0.0, 0.0, height)), "{}", v.target);
    }

    #[test]
    fn look_along_puts_the_axis_towards_the_viewer_and_animation_ends_there() {
        for axis in 0..3 {
            for positive in [true, false] {
                let q = look_along(axis, positive);
                let mut w = Vec3::ZERO;
                w[axis] = if positive { 1.0 } else { -1.0 };
                assert!(close(q * Vec3::Z, w), "axis {axis} {positive}");
            }
        }
        let mut anim = RotationAnimation::new(Quat::IDENTITY, look_along(0, true));
        let (_, done) = anim.step(0.2);
        assert!(!done);
        let (q, done) = anim.step(0.3);
        assert!(done && close(q * Vec3::Z, Vec3::X));
    }

    #[test]
    fn turntable_keeps_z_up_and_distance() {
        let mut v = OrbitView::from_camera(&Camera::orbit(10.0, 20.0, 2.0, Vec3::ZERO));
        let before = v.camera().eye;
        v.turn(std::f32::consts::FRAC_PI_2);
        let after = v.camera().eye;
        assert!((after.z - before.z).abs() < 1e-5 && (after.length() - 2.0).abs() < 1e-5);
        assert!((Vec2::new(after.x, after.y).dot(Vec2::new(before.x, before.y))).abs() < 1e-4);
    }
}
