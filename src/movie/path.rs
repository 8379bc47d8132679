//! The camera and settings of each movie frame: a turntable around the vertical axis, or a path through keyframes.
//! Pure maths (f64 inside, like the reference), no GPU.
//!
//! **Turntable.** Frame k of N is the base frame with its camera turned about the vertical axis through the point
//! it looks at by `360°·k/N`: the eye (relative to the target) and the up vector rotate about world +z, the axis
//! [`crate::scene::camera::Camera::orbit`]'s azimuth turns about, so an orbit camera at azimuth a becomes the one at
//! a + 360°·k/N (same elevation, distance, target). Nothing else changes; a light fixed to the volume stays fixed,
//! a headlight follows the camera. Frame 0 is the base frame exactly; the loop closes (frame N would be frame 0).
//!
//! **Keyframes.** K states make K − 1 segments of equal duration; N frames (N ≥ 2) are spread evenly over the path:
//! frame k is at `u = k·(K − 1)/(N − 1)`, in segment `i = min(floor(u), K − 2)` at `t = u − i`. A frame at a
//! keyframe (t = 0, or the last frame) *is* that keyframe's settings, bit for bit. Between two keyframes:
//! - camera: the view's orientation (right, up, back) is slerped along the shorter rotation (an azimuth change of
//!   350° turns 10° the other way), the distance to the target interpolated geometrically (zooming at a steady
//!   rate), the target, field of view and near/far planes linearly; orthographic or not from the segment's start;
//! - linearly: the value window, the slab box, the first iso-surface's value and opacity, step alpha, the density
//!   factor, the light's colour and intensity, the background, and the gradient-opacity reference when both
//!   states have one;
//! - the light's direction is slerped when both states fix a light to the volume (a headlight in either: the
//!   segment start's light);
//! - everything else, discrete or not meaningfully continuous (mode, transfer function or colormap, shading and
//!   its coefficients, shadows, occlusion, extra iso-surfaces, jitter, quality and step length, strides, method,
//!   image size), is the segment's starting state's.
//!
//! The path is continuous (each segment starts where the previous one ended) and, within a segment, the camera
//! turns at a constant angular rate; it is not smoothed across keyframes (the rate may change there).

use crate::scene::camera::Camera;
use crate::scene::settings::RenderSettings;
use glam::{DMat3, DQuat, DVec3, Vec3};

/// Frame `k` of an `n`-frame turntable of `base` (`k < n`).
pub fn turntable_frame(base: &RenderSettings, k: u32, n: u32) -> RenderSettings {
    let mut s = base.clone();
    if k == 0 || n == 0 {
        return s;
    }
    let angle = std::f64::consts::TAU * f64::from(k) / f64::from(n);
    let turn = DQuat::from_rotation_z(angle);
    let c = &base.camera;
    let target = c.target.as_dvec3();
    s.camera.eye = (target + turn * (c.eye.as_dvec3() - target)).as_vec3();
    s.camera.up = (turn * c.up.as_dvec3()).as_vec3();
    s
}

/// The turntable's angle of frame `k` of `n`, in degrees (for the unit tests and messages).
pub fn turntable_angle_deg(k: u32, n: u32) -> f64 {
    360.0 * f64::from(k) / f64::from(n.max(1))
}

/// Where frame `k` of `n` lies on a path of `keys` keyframes: (segment, t in [0, 1]).
pub fn keyframe_position(k: u32, n: u32, keys: usize) -> (usize, f64) {
    let segments = keys.saturating_sub(1).max(1);
    if n < 2 {
        return (0, 0.0);
    }
    let u = f64::from(k.min(n - 1)) * segments as f64 / f64::from(n - 1);
    let i = (u.floor() as usize).min(segments - 1);
    (i, (u - i as f64).clamp(0.0, 1.0))
}

/// Frame `k` of `n` on the path through `keys` (at least one; see the module's rule).
pub fn keyframe_frame(keys: &[RenderSettings], k: u32, n: u32) -> RenderSettings {
    if keys.len() < 2 {
        return keys.first().cloned().unwrap_or_default();
    }
    let (i, t) = keyframe_position(k, n, keys.len());
    if t == 0.0 {
        return keys[i].clone();
    }
    if t == 1.0 {
        return keys[i + 1].clone();
    }
    between(&keys[i], &keys[i + 1], t)
}

/// The settings a fraction `t` of the way from `a` to `b` (the module's rule).
pub fn between(a: &RenderSettings, b: &RenderSettings, t: f64) -> RenderSettings {
    let mut s = a.clone();
    s.camera = camera_between(&a.camera, &b.camera, t);
    s.colour.window = [
        lerp(a.colour.window[0], b.colour.window[0], t),
        lerp(a.colour.window[1], b.colour.window[1], t),
    ];
    s.cut.slab_lo = lerp3(a.cut.slab_lo, b.cut.slab_lo, t);
    s.cut.slab_hi = lerp3(a.cut.slab_hi, b.cut.slab_hi, t);
    s.compositing.iso_value = lerp(a.compositing.iso_value, b.compositing.iso_value, t);
    s.compositing.iso_opacity = lerp(a.compositing.iso_opacity, b.compositing.iso_opacity, t);
    s.colour.step_alpha = lerp(a.colour.step_alpha, b.colour.step_alpha, t);
    s.compositing.density = lerp(a.compositing.density, b.compositing.density, t);
    s.background = lerp3(a.background, b.background, t);
    s.lighting.light.color = lerp3(a.lighting.light.color, b.lighting.light.color, t);
    s.lighting.light.intensity = lerp(a.lighting.light.intensity, b.lighting.light.intensity, t);
    if let (Some(da), Some(db)) = (a.lighting.light.direction, b.lighting.light.direction) {
        s.lighting.light.direction = Some(slerp_direction(da, db, t));
    }
    if let (Some(ga), Some(gb)) = (a.lighting.gradient_opacity, b.lighting.gradient_opacity) {
        s.lighting.gradient_opacity = Some(lerp(ga, gb, t));
    }
    // A clipping plane in both states turns (normal slerped like the light's direction) and slides (offset
    // linear); otherwise the segment start's.
    if let (Some(ca), Some(cb)) = (&a.cut.clip_plane, &b.cut.clip_plane) {
        let normal = slerp_direction(ca.normal(), cb.normal(), t);
        if let Ok(plane) = crate::scene::clip::ClipPlane::new(normal, lerp(ca.offset(), cb.offset(), t)) {
            s.cut.clip_plane = Some(plane);
        }
    }
    s
}

/// The camera a fraction `t` of the way from `a` to `b`: orientation slerped the short way, distance geometric,
/// target, field of view and planes linear.
pub fn camera_between(a: &Camera, b: &Camera, t: f64) -> Camera {
    let (qa, qb) = (orientation(a), orientation(b));
    let q = qa.slerp(qb, t);
    let target = a.target.as_dvec3().lerp(b.target.as_dvec3(), t);
    let (da, db) = (a.eye.distance(a.target) as f64, b.eye.distance(b.target) as f64);
    let distance = da * (db / da).powf(t);
    Camera {
        eye: (target + q * DVec3::Z * distance).as_vec3(),
        target: target.as_vec3(),
        up: (q * DVec3::Y).as_vec3(),
        fov_y_deg: lerp(a.fov_y_deg, b.fov_y_deg, t),
        near: lerp(a.near, b.near, t),
        far: lerp(a.far, b.far, t),
        ortho: a.ortho,
    }
}

/// The camera's view rotation: its columns are the image's right, up and back (towards the eye) in the world, as
/// [`Camera::view`] builds them.
pub fn orientation(c: &Camera) -> DQuat {
    let forward = (c.target - c.eye).as_dvec3().normalize();
    let right = forward.cross(c.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    DQuat::from_mat3(&DMat3::from_cols(right, up, -forward)).normalize()
}

fn lerp(a: f32, b: f32, t: f64) -> f32 {
    (f64::from(a) + (f64::from(b) - f64::from(a)) * t) as f32
}

fn lerp3(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    a.as_dvec3().lerp(b.as_dvec3(), t).as_vec3()
}

/// The unit direction a fraction `t` of the way from `a` to `b` along the great circle (either need not be unit).
fn slerp_direction(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    let (a, b) = (a.as_dvec3().normalize(), b.as_dvec3().normalize());
    (DQuat::IDENTITY.slerp(DQuat::from_rotation_arc(a, b), t) * a).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orbit_settings(azimuth: f32, elevation: f32, distance: f32) -> RenderSettings {
        let mut s = RenderSettings::new(64, 48, Vec3::ONE);
        s.camera = Camera::orbit(azimuth, elevation, distance, Vec3::new(0.1, -0.05, 0.0));
        s
    }

    /// The camera's azimuth about +z through its target, in degrees ([`Camera::orbit`]'s convention).
    fn azimuth(c: &Camera) -> f64 {
        let d = (c.eye - c.target).as_dvec3();
        (-d.x).atan2(d.y).to_degrees()
    }

    fn assert_near(a: Vec3, b: Vec3, tol: f32, what: &str) {
        assert!((a - b).length() < tol, "{what}: {a} vs {b}");
    }

    #[test]
    fn turntable_frames_are_the_orbit_at_the_turned_azimuth() {
        let base = orbit_settings(35.0, 25.0, 2.5);
        let n = 12;
        assert_eq!(turntable_frame(&base, 0, n), base, "frame 0 is the base frame exactly");
        for k in 0..n {
            let s = turntable_frame(&base, k, n);
            let angle = turntable_angle_deg(k, n);
            assert!((angle - 30.0 * k as f64).abs() < 1e-9);
            let want = Camera::orbit(35.0 + angle as f32, 25.0, 2.5, base.camera.target);
            assert_near(s.camera.eye, want.eye, 1e-5, "eye");
            assert_near(s.camera.up, want.up, 1e-5, "up");
            assert_eq!(s.camera.target, base.camera.target);
            let mut rest = s.clone();
            rest.camera = base.camera;
            assert_eq!(rest, base, "only the camera turns");
        }
        // A view straight down (up along +y) spins about the view axis.
        let mut top = base.clone();
        top.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
        let s = turntable_frame(&top, 1, 4);
        assert_near(s.camera.eye, top.camera.eye, 1e-6, "top eye");
        assert_near(s.camera.up, Vec3::new(-1.0, 0.0, 0.0), 1e-6, "top up");
    }

    #[test]
    fn keyframe_positions_spread_evenly_and_end_on_the_keys() {
        assert_eq!(keyframe_position(0, 9, 3), (0, 0.0));
        assert_eq!(keyframe_position(4, 9, 3), (1, 0.0));
        assert_eq!(keyframe_position(8, 9, 3), (1, 1.0));
        assert_eq!(keyframe_position(2, 9, 3), (0, 0.5));
        assert_eq!(keyframe_position(1, 2, 2), (0, 1.0));
    }

    #[test]
    fn path_endpoints_and_keys_are_the_states_exactly() {
        let mut a = orbit_settings(10.0, 20.0, 2.0);
        a.colour.window = [0.2, 0.9];
        let mut b = orbit_settings(100.0, -30.0, 3.0);
        b.compositing.iso_value = 0.7;
        b.compositing.mode = crate::scene::settings::CompositeMode::Isosurface;
        let c = orbit_settings(200.0, 60.0, 1.5);
        let keys = [a.clone(), b.clone(), c.clone()];
        let n = 11;
        assert_eq!(keyframe_frame(&keys, 0, n), a);
        assert_eq!(keyframe_frame(&keys, 5, n), b);
        assert_eq!(keyframe_frame(&keys, n - 1, n), c);
        // Discrete settings are the segment's start's; continuous ones in between.
        let mid = keyframe_frame(&keys, 2, n);
        assert_eq!(mid.compositing.mode, a.compositing.mode);
        assert!(
            mid.compositing.iso_value > a.compositing.iso_value && mid.compositing.iso_value < b.compositing.iso_value
        );
        assert!(
            mid.colour.window[0] < 0.2 && mid.colour.window[0] > 0.1,
            "{:?}",
            mid.colour.window
        );
        assert_eq!(keyframe_frame(&keys, 7, n).compositing.mode, b.compositing.mode);
    }

    #[test]
    fn path_is_monotone_and_continuous() {
        let a = orbit_settings(-20.0, 10.0, 2.0);
        let b = orbit_settings(80.0, 10.0, 4.0);
        let n = 41;
        let frames: Vec<_> = (0..n).map(|k| keyframe_frame(&[a.clone(), b.clone()], k, n)).collect();
        let dist = |s: &RenderSettings| s.camera.eye.distance(s.camera.target);
        for w in frames.windows(2) {
            let (p, q) = (&w[0].camera, &w[1].camera);
            let turn = azimuth(q) - azimuth(p);
            // 100° in 40 frames, evenly: 2.5° a frame.
            assert!((turn - 2.5).abs() < 1e-3, "azimuth step {turn}");
            assert!(dist(&w[1]) > dist(&w[0]), "the distance grows monotonically");
            assert!(p.eye.distance(q.eye) < 0.2, "no jump");
            // A turn about +z keeps the horizon level (elevation and roll unchanged).
            assert!((q.up.z - a.camera.up.z).abs() < 1e-5);
        }
        // Zoom at a steady rate: every frame's distance is the same factor over the last.
        let ratios: Vec<f32> = frames.windows(2).map(|w| dist(&w[1]) / dist(&w[0])).collect();
        assert!(ratios.iter().all(|r| (r - ratios[0]).abs() < 1e-4), "{ratios:?}");
    }

    #[test]
    fn azimuth_wraps_the_short_way() {
        let a = orbit_settings(350.0, 25.0, 2.0);
        let b = orbit_settings(10.0, 25.0, 2.0);
        let mid = keyframe_frame(&[a, b], 2, 5);
        let az = azimuth(&mid.camera);
        assert!(az.abs() < 1e-3, "halfway from 350° to 10° is 0°, got {az}");
        // Every 20° arc around the circle, whichever sign each orientation's quaternion happens to take.
        for centre in (0..360).step_by(15) {
            let centre = centre as f32;
            // (The second azimuth a full turn further on: the same view, so the same short way.)
            let keys = [
                orbit_settings(centre - 10.0, 25.0, 2.0),
                orbit_settings(centre + 10.0 + 360.0, 25.0, 2.0),
            ];
            for k in 0..5 {
                let az = azimuth(&keyframe_frame(&keys, k, 5).camera);
                let off = (az - f64::from(centre) + 540.0).rem_euclid(360.0) - 180.0;
                assert!(
                    off.abs() <= 10.0 + 1e-3,
                    "{centre}° ± 10°: frame {k} at {az}° leaves the 20° arc"
                );
            }
        }
    }

    #[test]
    fn fixed_lights_turn_along_the_great_circle() {
        let mut a = orbit_settings(0.0, 0.0, 2.0);
        a.lighting.light.direction = Some(Vec3::X * 3.0);
        let mut b = a.clone();
        b.lighting.light.direction = Some(Vec3::Y);
        let d = between(&a, &b, 0.5).lighting.light.direction.unwrap();
        assert_near(d, Vec3::new(1.0, 1.0, 0.0).normalize(), 1e-6, "light");
        b.lighting.light.direction = None;
        assert_eq!(
            between(&a, &b, 0.5).lighting.light.direction,
            a.lighting.light.direction
        );
    }
}
