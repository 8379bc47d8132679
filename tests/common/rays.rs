//! Rule 1's rays, built from the camera's eye, target, up and field of view directly (not from `Camera::view` or
//! `Camera::projection`), and the slab method that finds a ray's segment inside a box.

use glam::DVec3;
use volcast::scene::settings::RenderSettings;

/// The ray of pixel (x, y), row 0 at the top: its origin (the eye, or for an orthographic camera the pixel's point
/// on the plane through the eye perpendicular to the view direction) and unit direction.
pub fn pixel_ray(s: &RenderSettings, x: u32, y: u32) -> (DVec3, DVec3) {
    let (origin, dir, _) = CameraBasis::new(s).ray(x, y);
    (origin, dir)
}

/// The part of the ray `origin + t·dir` (t in world units, `dir` a unit vector) inside the axis-aligned box
/// `[lo, hi]` and at `t ≥ t_min`, by the slab method; `None` if empty.
pub fn ray_segment(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3, t_min: f64) -> Option<(f64, f64)> {
    let mut t0 = t_min;
    let mut t1 = f64::INFINITY;
    for a in 0..3 {
        if dir[a] == 0.0 {
            // Parallel to this slab: inside it everywhere or nowhere (avoids 0/0 on the boundary).
            if origin[a] < lo[a] || origin[a] > hi[a] {
                return None;
            }
            continue;
        }
        let ta = (lo[a] - origin[a]) / dir[a];
        let tb = (hi[a] - origin[a]) / dir[a];
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 < t1).then_some((t0, t1))
}

/// The camera as an orthonormal basis: `forward` towards the target, `right`, and `up` completing it.
pub struct CameraBasis {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half_fov: f64,
    aspect: f64,
    width: f64,
    height: f64,
    /// Orthographic: half the view's height, `|eye − target|·tan(fov/2)`.
    ortho_half_height: Option<f64>,
    near: f64,
}

impl CameraBasis {
    pub fn new(s: &RenderSettings) -> CameraBasis {
        let c = &s.camera;
        let eye = c.eye.as_dvec3();
        let target = c.target.as_dvec3();
        let forward = (target - eye).normalize();
        let right = forward.cross(c.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let tan_half_fov = (f64::from(c.fov_y_deg).to_radians() * 0.5).tan();
        CameraBasis {
            eye,
            forward,
            right,
            up,
            tan_half_fov,
            // Rule 12: spaced rays are framed as the output is, over fewer pixels.
            aspect: f64::from(s.width) / f64::from(s.height),
            width: f64::from(super::stretch::marched(s).0),
            height: f64::from(super::stretch::marched(s).1),
            ortho_half_height: c.ortho.then(|| (target - eye).length() * tan_half_fov),
            near: f64::from(c.near),
        }
    }

    /// Normalised device coordinates of pixel (x, y)'s centre; y grows downwards with the row.
    fn ndc(&self, x: u32, y: u32) -> (f64, f64) {
        (
            2.0 * (f64::from(x) + 0.5) / self.width - 1.0,
            2.0 * (f64::from(y) + 0.5) / self.height - 1.0,
        )
    }

    /// Rule 1: pixel (x, y)'s ray origin, unit direction, and the distance along it at which the view depth
    /// `dot(p − eye, forward)` reaches the near plane.
    pub fn ray(&self, x: u32, y: u32) -> (DVec3, DVec3, f64) {
        let (nx, ny) = self.ndc(x, y);
        match self.ortho_half_height {
            Some(half_h) => {
                // Parallel to the view direction from the plane through the eye perpendicular to it: the view
                // depth of origin + t·forward is t itself.
                let origin = self.eye + nx * half_h * self.aspect * self.right - ny * half_h * self.up;
                (origin, self.forward, self.near)
            }
            None => {
                let dir = (self.forward + nx * self.tan_half_fov * self.aspect * self.right
                    - ny * self.tan_half_fov * self.up)
                    .normalize();
                // A unit ray from the eye reaches view depth `near` after near / cos(angle to forward).
                (self.eye, dir, self.near / dir.dot(self.forward))
            }
        }
    }
}
