//! How the 3D view frames the volume in a view of any shape and size, with the orientation gizmo in its corner.
//! The orbit's distance fits the volume's bounding sphere in the view's height (as `volcast render` frames it);
//! a view narrower than tall, or one so small that the gizmo reaches the sphere (a quarter of a small window in
//! the four-up layout), has the camera stand farther back by [`fit_factor`], so the volume stays inside the
//! view and clear of the gizmo. The gizmo itself shrinks in small views ([`gizmo_place`]).

use glam::Vec2;

/// Where the orientation gizmo is drawn in a view: its centre, arm length and the radius of its disc (points).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GizmoPlace {
    pub centre: Vec2,
    pub arm: f32,
    pub disc: f32,
    /// Its size against the full-size gizmo: 1 in views at least 560 points across, down to 0.4 at 344.
    pub scale: f32,
}

/// The gizmo in view `rect`: 60 points in from the bottom-right corner, arms of 40 and a disc of 52 at full
/// size, all scaled down with the view's smaller side below 560 points (to 0.4, so that in a square view of 300
/// points, a quarter of the default window, the sphere that fills the view's height still clears it).
pub fn gizmo_place(rect: egui::Rect) -> GizmoPlace {
    let scale = ((rect.width().min(rect.height()) - 200.0) / 360.0).clamp(0.4, 1.0);
    GizmoPlace {
        centre: Vec2::new(rect.right() - 60.0 * scale, rect.bottom() - 60.0 * scale),
        arm: 40.0 * scale,
        disc: 52.0 * scale,
        scale,
    }
}

/// How much farther than the orbit's distance the camera stands in a `width`×`height` view (1 where the sphere
/// fitted to the height is inside the view and clear of the gizmo's disc; `gizmo` false for an image without
/// it, such as an exported figure). Otherwise the sphere's radius on screen is made the largest that stays inside
/// the view and off the gizmo, less 3% so the volume does not touch the view's edge.
pub fn fit_factor(width: f32, height: f32, gizmo: bool, fov_y_deg: f32, ortho: bool) -> f32 {
    if !(width > 0.0 && height > 0.0) {
        return 1.0;
    }
    let view = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(width, height));
    let half_h = height / 2.0;
    let mut allowed = (width / 2.0).min(half_h);
    if gizmo {
        let g = gizmo_place(view);
        let clear = Vec2::new(width / 2.0, half_h).distance(g.centre) - g.disc;
        allowed = allowed.min(clear);
    }
    if allowed >= half_h {
        return 1.0;
    }
    let allowed = (allowed * 0.97).max(1.0);
    let half_fov = (fov_y_deg.to_radians() * 0.5).clamp(0.01, 1.5);
    let k = if ortho {
        // The orthographic view is 2·distance·tan(fov/2) high: the sphere fills cos(fov/2) of its height.
        half_fov.cos() * half_h / allowed
    } else {
        // The sphere's silhouette at k times the fitted distance subtends asin(sin(fov/2) / k).
        half_fov.sin() / ((allowed / half_h) * half_fov.tan()).atan().sin()
    };
    k.max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_and_large_views_keep_the_framing() {
        assert_eq!(fit_factor(640.0, 600.0, true, 30.0, false), 1.0);
        // A quarter of the default 900×600 window in the four-up layout.
        assert_eq!(fit_factor(310.0, 300.0, true, 30.0, false), 1.0);
        assert_eq!(fit_factor(300.0, 300.0, true, 30.0, true), 1.0);
        assert_eq!(fit_factor(1600.0, 1000.0, false, 30.0, true), 1.0);
        let full = gizmo_place(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(640.0, 600.0)));
        assert_eq!(
            (full.centre, full.arm, full.disc),
            (Vec2::new(580.0, 540.0), 40.0, 52.0)
        );
    }

    #[test]
    fn narrow_views_back_off_until_the_sphere_fits_across() {
        // Without the gizmo, a view half as wide as high needs the sphere at half the height's radius.
        let k = fit_factor(300.0, 600.0, false, 30.0, false);
        let half = 15f32.to_radians();
        let on_screen = (half.sin() / k).asin().tan() / half.tan() * 300.0;
        assert!((on_screen - 150.0 * 0.97).abs() < 0.01, "{on_screen}");
        assert!((fit_factor(300.0, 600.0, false, 30.0, true) - half.cos() * 2.0 / 0.97).abs() < 1e-5);
    }

    #[test]
    fn small_views_keep_the_sphere_off_the_gizmo() {
        let (w, h) = (220.0, 250.0);
        let g = gizmo_place(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(w, h)));
        assert!(g.scale < 1.0);
        let k = fit_factor(w, h, true, 30.0, false);
        let half = 15f32.to_radians();
        let radius = (half.sin() / k).asin().tan() / half.tan() * h / 2.0;
        let gap = Vec2::new(w / 2.0, h / 2.0).distance(g.centre) - radius;
        assert!(gap >= g.disc - 0.01, "gap {gap}");
        assert!(radius <= w / 2.0);
    }
}
