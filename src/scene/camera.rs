//! Orbit camera and the matrices the passes use. Pure maths, no Vulkan.
//!
//! World space: the volume's box is centred on the origin with side lengths [`crate::volume::Volume::extent`]
//! (dims × spacing, scaled so the longest side is 1). Texture space is the same box mapped to [0,1]³:
//! `tex = world / extent + 0.5`. +z is "up" for orbiting, as in VTK and in scanner coordinates (slices stack along z).

use glam::{Mat4, Vec3, Vec4};

/// A perspective pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Distance of the near plane from the eye along the view direction (world units).
    pub near: f32,
    pub far: f32,
    /// Orthographic projection, `2·|eye − target|·tan(fov/2)` high (so switching keeps the framing).
    #[serde(default)]
    pub ortho: bool,
}

pub const DEFAULT_FOV_Y_DEG: f32 = 30.0;
pub const DEFAULT_NEAR: f32 = 0.01;
pub const DEFAULT_FAR: f32 = 100.0;

impl Camera {
    /// A camera on a sphere around `target`. Azimuth turns about +z starting on the +y axis (VTK's convention:
    /// positive azimuth is counter-clockwise seen from above); elevation lifts towards +z. Up is the direction of
    /// rising elevation: +z as seen from the side, and at ±90° (straight above or below, where +z is the view
    /// axis) the limit of that, so the azimuth still turns the image and nothing jumps there.
    pub fn orbit(azimuth_deg: f32, elevation_deg: f32, distance: f32, target: Vec3) -> Camera {
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        let dir = Vec3::new(-az.sin() * el.cos(), az.cos() * el.cos(), el.sin());
        let mut c = Camera::looking_at(target + dir * distance, target);
        // (Rounding noise snapped to zero, so that presets' up vectors are exact.)
        let up = Vec3::new(az.sin() * el.sin(), -az.cos() * el.sin(), el.cos());
        c.up = Vec3::select(up.abs().cmplt(Vec3::splat(1e-6)), Vec3::ZERO, up).normalize();
        c
    }

    /// A camera at `eye` looking at `target`, +z up unless the view is (nearly) along z, then +y.
    pub fn looking_at(eye: Vec3, target: Vec3) -> Camera {
        let forward = (target - eye).normalize_or_zero();
        let up = if forward.cross(Vec3::Z).length() < 1e-3 {
            Vec3::Y
        } else {
            Vec3::Z
        };
        Camera {
            eye,
            target,
            up,
            fov_y_deg: DEFAULT_FOV_Y_DEG,
            near: DEFAULT_NEAR,
            far: DEFAULT_FAR,
            ortho: false,
        }
    }

    /// The distance at which a sphere of `radius` around the target just fits the vertical field of view.
    pub fn fit_distance(radius: f32, fov_y_deg: f32) -> f32 {
        radius / (fov_y_deg.to_radians() * 0.5).sin()
    }

    /// Unit vector from the eye towards the target.
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize()
    }

    /// Right-handed view matrix (camera looks down its -z).
    pub fn view(&self) -> Mat4 {
        let f = self.forward();
        let s = f.cross(self.up).normalize();
        let u = s.cross(f);
        Mat4::from_cols(
            Vec4::new(s.x, u.x, -f.x, 0.0),
            Vec4::new(s.y, u.y, -f.y, 0.0),
            Vec4::new(s.z, u.z, -f.z, 0.0),
            Vec4::new(-s.dot(self.eye), -u.dot(self.eye), f.dot(self.eye), 1.0),
        )
    }

    /// Perspective projection into Vulkan clip space: x right, **y down** (framebuffer row 0 is the top of the
    /// image), depth 0 at the near plane and 1 at the far plane. Y is flipped here on purpose, not by naga
    /// (build.rs turns naga's coordinate adjustment off).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let f = 1.0 / (self.fov_y_deg.to_radians() * 0.5).tan();
        let (n, fa) = (self.near, self.far);
        if self.ortho {
            // Half-height of the view at the target's distance, as the perspective view shows it.
            let half_h = (self.eye - self.target).length() / f;
            let half_w = half_h * aspect;
            return Mat4::from_cols(
                Vec4::new(1.0 / half_w, 0.0, 0.0, 0.0),
                Vec4::new(0.0, -1.0 / half_h, 0.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0 / (n - fa), 0.0),
                Vec4::new(0.0, 0.0, n / (n - fa), 1.0),
            );
        }
        Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, -f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, fa / (n - fa), -1.0),
            Vec4::new(0.0, 0.0, n * fa / (n - fa), 0.0),
        )
    }
}

/// In a RAS+ world, the anatomical direction at each edge of the view of `camera`: [left, right, top, bottom]
/// ('R', 'L', 'A', 'P', 'S' or 'I'), the one the screen's direction points to most.
pub fn edge_labels(camera: &Camera) -> [char; 4] {
    let forward = camera.forward().as_dvec3();
    let right = forward.cross(camera.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    let label = crate::volume::geometry::direction_label;
    [label(-right), label(right), label(up), label(-up)]
}

/// The six standard views of anatomy: where the camera stands, looking at the centre. In a RAS+ world (+x
/// right, +y anterior, +z superior) "anterior" is in front of the face; for a volume without orientation they
/// are views along the world's axes (+y, −y, −x, +x, +z, −z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ViewPreset {
    Anterior,
    Posterior,
    Left,
    Right,
    Superior,
    Inferior,
}

impl ViewPreset {
    pub const ALL: [ViewPreset; 6] = [
        ViewPreset::Anterior,
        ViewPreset::Posterior,
        ViewPreset::Left,
        ViewPreset::Right,
        ViewPreset::Superior,
        ViewPreset::Inferior,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ViewPreset::Anterior => "anterior",
            ViewPreset::Posterior => "posterior",
            ViewPreset::Left => "left",
            ViewPreset::Right => "right",
            ViewPreset::Superior => "superior",
            ViewPreset::Inferior => "inferior",
        }
    }

    pub fn parse(s: &str) -> Option<ViewPreset> {
        let key = s.trim().to_ascii_lowercase();
        ViewPreset::ALL
            .into_iter()
            .find(|v| v.name() == key || v.name()[..1] == key)
    }

    /// The camera's azimuth and elevation ([`Camera::orbit`]'s convention) for this view. Head up (+z) from the
    /// four sides; anterior up (+y) from above and below.
    pub fn angles(self) -> (f32, f32) {
        match self {
            ViewPreset::Anterior => (0.0, 0.0),
            ViewPreset::Posterior => (180.0, 0.0),
            ViewPreset::Left => (90.0, 0.0),
            ViewPreset::Right => (-90.0, 0.0),
            // From above, anterior up: the pole reached from the posterior side (orbit's up at the pole continues
            // the approach).
            ViewPreset::Superior => (180.0, 90.0),
            ViewPreset::Inferior => (0.0, -90.0),
        }
    }

    /// The camera for this view at `distance` from `target`.
    pub fn camera(self, distance: f32, target: Vec3) -> Camera {
        let (azimuth, elevation) = self.angles();
        Camera::orbit(azimuth, elevation, distance, target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn project(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        c.truncate() / c.w
    }

    #[test]
    fn orbit_turns_smoothly_through_the_poles() {
        // The image's right vector just below the pole and at it: the same, for every azimuth (it used to ignore
        // the azimuth at exactly 90° and turn the image by up to 180°).
        let right = |c: &Camera| c.forward().cross(c.up).normalize();
        for az in [0.0, 35.0, 90.0, 145.0, -120.0] {
            for pole in [90.0, -90.0] {
                let near = Camera::orbit(az, pole - 0.01f32.copysign(pole), 3.0, Vec3::ZERO);
                let at = Camera::orbit(az, pole, 3.0, Vec3::ZERO);
                assert!(right(&near).dot(right(&at)) > 0.9999, "azimuth {az}, elevation {pole}");
                assert!(at.up.dot(at.forward()).abs() < 1e-6);
            }
        }
        // Away from the poles the camera is the one looking_at gives (+z up).
        let c = Camera::orbit(35.0, 25.0, 3.0, Vec3::ZERO);
        let l = Camera::looking_at(c.eye, c.target);
        assert!(right(&c).dot(right(&l)) > 0.99999);
    }

    #[test]
    fn orbit_starts_on_plus_y_and_turns_counter_clockwise() {
        let c = Camera::orbit(0.0, 0.0, 2.0, Vec3::ZERO);
        assert!((c.eye - Vec3::new(0.0, 2.0, 0.0)).length() < 1e-6);
        let c = Camera::orbit(90.0, 0.0, 2.0, Vec3::ZERO);
        assert!((c.eye - Vec3::new(-2.0, 0.0, 0.0)).length() < 1e-5);
        let c = Camera::orbit(0.0, 90.0, 2.0, Vec3::ZERO);
        assert!((c.eye - Vec3::new(0.0, 0.0, 2.0)).length() < 1e-5);
        // Straight down, reached from the +y side: the image continues the approach (+y at the bottom).
        assert!((c.up + Vec3::Y).length() < 1e-6, "{}", c.up);
    }

    #[test]
    fn projection_is_vulkan_y_down_depth_zero_to_one() {
        let cam = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
        let vp = cam.projection(1.0) * cam.view();
        // World +z is up on screen, so it lands at negative clip y (towards framebuffer row 0).
        assert!(project(vp, Vec3::new(0.0, 0.0, 0.5)).y < 0.0);
        // Looking from +y towards -y with +z up, world -x is screen right.
        assert!(project(vp, Vec3::new(-0.5, 0.0, 0.0)).x > 0.0);
        let near_point = cam.eye + cam.forward() * cam.near;
        assert!(project(vp, near_point).z.abs() < 1e-4);
        let far_point = cam.eye + cam.forward() * cam.far;
        assert!((project(vp, far_point).z - 1.0).abs() < 1e-4);
        assert!(project(vp, Vec3::ZERO).length() < 1.0);
    }

    #[test]
    fn orthographic_projection_keeps_the_framing_at_the_target() {
        let mut cam = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
        let persp = project(cam.projection(1.5) * cam.view(), Vec3::new(0.2, 0.0, 0.3));
        cam.ortho = true;
        let vp = cam.projection(1.5) * cam.view();
        let ortho = project(vp, Vec3::new(0.2, 0.0, 0.3));
        assert!(
            (persp.truncate() - ortho.truncate()).length() < 1e-5,
            "same size in the target's plane"
        );
        let behind = project(vp, Vec3::new(0.2, -1.0, 0.3));
        assert!((behind.truncate() - ortho.truncate()).length() < 1e-5, "parallel rays");
        assert!(project(vp, cam.eye + cam.forward() * cam.near).z.abs() < 1e-5);
    }

    #[test]
    fn fit_distance_keeps_the_sphere_in_view() {
        let d = Camera::fit_distance(0.5, 30.0);
        assert!((d * (15f32).to_radians().sin() - 0.5).abs() < 1e-6);
    }

    #[test]
    fn edge_labels_name_the_patient_sides() {
        // From the front the patient's left is on the screen's right, the head at the top.
        assert_eq!(
            edge_labels(&ViewPreset::Anterior.camera(2.0, Vec3::ZERO)),
            ['R', 'L', 'S', 'I']
        );
        assert_eq!(
            edge_labels(&ViewPreset::Posterior.camera(2.0, Vec3::ZERO)),
            ['L', 'R', 'S', 'I']
        );
        // From above, anterior up: the patient's right on the screen's right (as seen from above).
        assert_eq!(
            edge_labels(&ViewPreset::Superior.camera(2.0, Vec3::ZERO)),
            ['L', 'R', 'A', 'P']
        );
        assert_eq!(
            edge_labels(&ViewPreset::Left.camera(2.0, Vec3::ZERO)),
            ['A', 'P', 'S', 'I']
        );
    }

    #[test]
    fn presets_look_at_the_named_side_head_up() {
        let c = ViewPreset::Anterior.camera(2.0, Vec3::ZERO);
        assert!(
            (c.eye - Vec3::new(0.0, 2.0, 0.0)).length() < 1e-5,
            "in front of the face (+y)"
        );
        assert_eq!(c.up, Vec3::Z);
        // From anterior the patient's left (−x) is on the screen's right.
        let vp = c.projection(1.0) * c.view();
        assert!(project(vp, Vec3::new(-0.3, 0.0, 0.0)).x > 0.0);
        let c = ViewPreset::Left.camera(2.0, Vec3::ZERO);
        assert!((c.eye - Vec3::new(-2.0, 0.0, 0.0)).length() < 1e-5);
        let c = ViewPreset::Superior.camera(2.0, Vec3::ZERO);
        assert!((c.eye - Vec3::new(0.0, 0.0, 2.0)).length() < 1e-5);
        assert_eq!(c.up, Vec3::Y, "anterior up");
        assert_eq!(ViewPreset::parse("Posterior"), Some(ViewPreset::Posterior));
        assert_eq!(ViewPreset::parse("s"), Some(ViewPreset::Superior));
        assert_eq!(ViewPreset::parse("front"), None);
    }
}
