//! The clipping plane (rule 10's [`ClipPlane`]) in the 3D view: its outline where it cuts the volume's box, an
//! arrow along its normal (into the half that is kept), a handle at the outline's centre and a ring around it.
//! Dragging the handle slides the plane along its normal; dragging the ring turns it about the handle, as if the
//! ring were the front of a ball (the same feel as turning the camera). C shows a new plane (through the centre,
//! facing away from the viewer: the near half is cut away) or removes it, F flips it. Pure geometry in
//! [`ClipHandles`]; [`clip_widget`] draws and takes the input.

use crate::scene::clip::ClipPlane;
use crate::viewer::model::{ClipGrab, Model};
use crate::viewer::widgets::screen::{box_corners, project};
use egui::{Color32, Pos2, Stroke};
use glam::{DVec3, Quat, Vec2, Vec3};

/// The plane's colour in the 3D and slice views.
pub const COLOR: Color32 = Color32::from_rgb(70, 220, 255);
/// The handle's radius and the ring's radius, points.
pub const HANDLE: f32 = 7.0;
pub const RING: f32 = 34.0;
/// The normal arrow's length, render-world units (the box's longest side is 1).
pub const ARROW: f32 = 0.2;

/// The widget's geometry for one frame: the outline in the render world and the handle and arrow on screen.
#[derive(Clone, Debug)]
pub struct ClipHandles {
    /// Where the plane cuts the box (render world), in order; empty when it misses.
    pub outline: Vec<Vec3>,
    /// The handle (render world): the outline's centre, or the plane's point nearest the box's centre.
    pub centre: Vec3,
    /// The handle and the arrow's tip on screen (points), when in front of the camera.
    pub handle: Option<Pos2>,
    pub tip: Option<Pos2>,
}

/// The widget for `model`'s plane in the 3D view `rect`; None without a plane.
pub fn handles(model: &Model, rect: egui::Rect) -> Option<ClipHandles> {
    let plane = model.look.cut.clip_plane?;
    let wpm = model.geometry.world_per_mm(model.dims) as f32;
    let n = plane.normal();
    let corners = box_corners(model.tex_to_world(), Vec3::ZERO, Vec3::ONE).map(|c| c.as_dvec3());
    let outline: Vec<Vec3> =
        crate::scene::slice::plane_section(&corners, n.as_dvec3(), f64::from(plane.offset() * wpm))
            .into_iter()
            .map(|p| p.as_vec3())
            .collect();
    let centre = if outline.is_empty() {
        n * plane.offset() * wpm
    } else {
        outline.iter().copied().sum::<Vec3>() / outline.len() as f32
    };
    let vp = model.view_projection(rect);
    Some(ClipHandles {
        handle: project(vp, centre, rect),
        tip: project(vp, centre + n * ARROW, rect),
        outline,
        centre,
    })
}

/// A new plane for the C key: through the box's centre, its normal along the view direction (what stays is the far
/// half, so the cut faces the viewer).
pub fn facing_away(model: &Model) -> ClipPlane {
    let forward = model.camera.orbit.camera().forward();
    ClipPlane::new(forward, 0.0).unwrap_or_else(|_| ClipPlane::new(Vec3::Z, 0.0).expect("a unit normal"))
}

/// The plane slid by a drag of `delta` points from the handle: along the arrow's screen direction when it shows
/// one (the plane then follows the pointer's motion along it), else by the vertical motion (up moves the plane
/// away from the viewer). Kept within the box's half diagonal of its centre.
pub fn slid(model: &Model, h: &ClipHandles, plane: ClipPlane, delta: Vec2, rect: egui::Rect) -> ClipPlane {
    let wpm = model.geometry.world_per_mm(model.dims) as f32;
    let along_world = match (h.handle, h.tip) {
        (Some(a), Some(b)) if (b - a).length() >= 12.0 => {
            let s = Vec2::new(b.x - a.x, b.y - a.y);
            ARROW * delta.dot(s) / s.length_squared()
        }
        _ => {
            let forward = model.camera.orbit.camera().forward();
            let away = if plane.normal().dot(forward) >= 0.0 { 1.0 } else { -1.0 };
            -delta.y / rect.height().max(1.0) * away
        }
    };
    let reach = half_diagonal_mm(model);
    let offset = (plane.offset() + along_world / wpm).clamp(-reach, reach);
    plane.with_offset(offset).unwrap_or(plane)
}

/// How far a plane may be from the box's centre and still cut it: the box's half diagonal, mm.
pub fn half_diagonal_mm(model: &Model) -> f32 {
    let corners = box_corners(model.tex_to_world(), Vec3::ZERO, Vec3::ONE);
    corners.iter().map(|c| c.length()).fold(0.0, f32::max) / model.geometry.world_per_mm(model.dims) as f32
}

/// The plane turned by a drag of `delta` points on the ring: about the axis in the screen plane perpendicular to
/// the motion, by `|delta| / RING` radians, keeping it through the handle.
pub fn turned(model: &Model, h: &ClipHandles, plane: ClipPlane, delta: Vec2) -> ClipPlane {
    let motion = Vec3::new(delta.x, -delta.y, 0.0);
    let Some(axis) = Vec3::Z.cross(motion).try_normalize() else {
        return plane;
    };
    let in_camera = Quat::from_axis_angle(axis, motion.length() / RING);
    let rotation = model.camera.orbit.rotation;
    let normal = (rotation * in_camera * rotation.inverse()) * plane.normal();
    let wpm = model.geometry.world_per_mm(model.dims) as f32;
    ClipPlane::through(normal, h.centre / wpm).unwrap_or(plane)
}

/// Draws the plane over the view `rect` and handles its input: returns true while a drag on it moves the plane (the
/// caller then leaves the camera alone).
pub fn clip_widget(ui: &egui::Ui, model: &mut Model, rect: egui::Rect, response: &egui::Response) -> bool {
    let Some(h) = handles(model, rect) else {
        model.interaction.clip_grab = None;
        return false;
    };
    if response.drag_started_by(egui::PointerButton::Primary) {
        let origin = ui.input(|i| i.pointer.press_origin());
        model.interaction.clip_grab = match (origin, h.handle) {
            (Some(o), Some(c)) if o.distance(c) <= HANDLE + 4.0 => Some(ClipGrab::Slide),
            (Some(o), Some(c)) if (o.distance(c) - RING).abs() <= 6.0 => Some(ClipGrab::Turn),
            _ => None,
        };
    }
    if !response.dragged_by(egui::PointerButton::Primary) {
        model.interaction.clip_grab = None;
    }
    let delta = response.drag_delta();
    let delta = Vec2::new(delta.x, delta.y);
    if let (Some(grab), Some(plane)) = (model.interaction.clip_grab, model.look.cut.clip_plane) {
        if delta != Vec2::ZERO {
            model.look.cut.clip_plane = Some(match grab {
                ClipGrab::Slide => slid(model, &h, plane, delta, rect),
                ClipGrab::Turn => turned(model, &h, plane, delta),
            });
        }
    }

    let painter = ui.painter_at(rect);
    let vp = model.view_projection(rect);
    let outline: Vec<Pos2> = h.outline.iter().filter_map(|&p| project(vp, p, rect)).collect();
    if outline.len() >= 3 && outline.len() == h.outline.len() {
        painter.add(egui::Shape::convex_polygon(
            outline,
            Color32::from_rgba_unmultiplied(70, 220, 255, 28),
            Stroke::new(1.5, COLOR),
        ));
    }
    if let Some(c) = h.handle {
        if let Some(t) = h.tip {
            painter.arrow(c, t - c, Stroke::new(2.0, COLOR));
        }
        let active = model.interaction.clip_grab.is_some();
        painter.circle(
            c,
            HANDLE,
            if active { COLOR } else { Color32::from_black_alpha(120) },
            Stroke::new(2.0, COLOR),
        );
        painter.circle_stroke(c, RING, Stroke::new(1.0, COLOR.gamma_multiply(0.7)));
    }
    model.interaction.clip_grab.is_some()
}

/// The plane as a slice view draws it: a point of it and its normal in the slice views' millimetres (`mm` maps
/// voxel indices there).
pub fn plane_in_slices(model: &Model, plane: &ClipPlane, mm: glam::DMat4) -> (DVec3, DVec3) {
    let d = DVec3::new(
        f64::from(model.dims[0]),
        f64::from(model.dims[1]),
        f64::from(model.dims[2]),
    );
    // Millimetres → voxel index → texture (i + ½)/dims → render world.
    let tex_from_index = glam::DMat4::from_scale(1.0 / d) * glam::DMat4::from_translation(DVec3::splat(0.5));
    let to_world = model.geometry.tex_to_world(model.dims, model.look.voxel_axes) * tex_from_index * mm.inverse();
    plane.point_normal_in(to_world, model.geometry.world_per_mm(model.dims))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::geometry::Geometry;

    fn model() -> Model {
        let mut s = Model::new(Vec3::new(1.0, 0.8, 0.6), "test".into());
        let geometry = Geometry::from_spacing([1.0, 1.0, 1.0]);
        s.set_volume(Vec3::new(1.0, 0.8, 0.6), geometry, [100, 80, 60], "test".into());
        s
    }

    fn rect() -> egui::Rect {
        egui::Rect::from_min_size(Pos2::new(300.0, 0.0), egui::vec2(600.0, 500.0))
    }

    #[test]
    fn a_new_plane_faces_away_through_the_centre() {
        let mut s = model();
        let plane = facing_away(&s);
        assert!(
            plane
                .normal()
                .dot(s.camera.orbit.camera().target - s.camera.orbit.camera().eye)
                > 0.99
        );
        s.look.cut.clip_plane = Some(plane);
        let h = handles(&s, rect()).unwrap();
        assert!(h.centre.length() < 1e-5, "{}", h.centre);
        assert!(h.outline.len() >= 4);
        assert!(h.handle.unwrap().distance(rect().center()) < 1.0);
    }

    #[test]
    fn sliding_follows_the_arrow_and_turning_follows_the_pointer() {
        let mut s = model();
        // A plane seen edge on: its normal along the camera's right.
        let right = s.camera.orbit.rotation * Vec3::X;
        let plane = ClipPlane::new(right, 0.0).unwrap();
        s.look.cut.clip_plane = Some(plane);
        let h = handles(&s, rect()).unwrap();
        let (a, b) = (h.handle.unwrap(), h.tip.unwrap());
        assert!(b.x > a.x + 12.0, "the arrow points right on screen");
        // Dragging the handle by the arrow's screen length moves the plane by the arrow's length.
        let moved = slid(&s, &h, plane, Vec2::new(b.x - a.x, b.y - a.y), rect());
        let wpm = s.geometry.world_per_mm(s.dims) as f32;
        assert!((moved.offset() - ARROW / wpm).abs() < 1e-3, "{}", moved.offset());
        // A drag across the arrow does not move it.
        let across = slid(&s, &h, plane, Vec2::new(a.y - b.y, b.x - a.x), rect());
        assert!(across.offset().abs() < 1e-3);
        // Far drags stop at the box's half diagonal.
        let far = slid(&s, &h, plane, Vec2::new(1e6, 0.0), rect());
        assert!(far.offset() * wpm <= 0.75 && far.offset() > 0.0);

        // A sideways drag turns about the camera's up: the normal stays in the screen's horizontal plane.
        let up_vec = s.camera.orbit.rotation * Vec3::Y;
        let side = turned(&s, &h, plane, Vec2::new(RING * 0.3, 0.0));
        assert!(side.normal().dot(up_vec).abs() < 1e-5);
        assert!((side.normal().angle_between(plane.normal()) - 0.3).abs() < 1e-4);
        assert!(
            (side.normal().dot(h.centre / wpm) - side.offset()).abs() < 1e-3,
            "through the handle still"
        );

        // Facing away, a drag up turns the plane like the back of a ball: the normal's far end goes down.
        let away = facing_away(&s);
        s.look.cut.clip_plane = Some(away);
        let h = handles(&s, rect()).unwrap();
        let up = turned(&s, &h, away, Vec2::new(0.0, -RING * 0.5));
        assert!((up.normal().angle_between(away.normal()) - 0.5).abs() < 1e-4);
        assert!(up.normal().dot(up_vec) < -0.4, "{}", up.normal());
    }

    #[test]
    fn the_slices_get_the_same_plane() {
        let mut s = model();
        let plane = ClipPlane::new(Vec3::new(0.3, -1.0, 0.4), 7.0).unwrap();
        s.look.cut.clip_plane = Some(plane);
        let mm = crate::scene::slice::mm_from_index(&s.geometry, s.look.voxel_axes);
        let (point, normal) = plane_in_slices(&s, &plane, mm);
        // The geometry's millimetres relative to the box's centre: the plane's own frame.
        let centre = mm.transform_point3(DVec3::new(99.0, 79.0, 59.0) * 0.5);
        let rel = (point - centre).as_vec3();
        assert!((rel.dot(plane.normal()) - plane.offset()).abs() < 1e-3);
        assert!(normal.normalize().as_vec3().dot(plane.normal()) > 0.9999);
    }
}
