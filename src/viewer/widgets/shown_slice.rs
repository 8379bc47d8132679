//! Where a slice view's image is on screen: its pixel grid in the world and its place in the view, to go between
//! screen points and world millimetres (the slice view's input, the ruler).

use crate::scene::slice::SliceFrame;
use egui::Pos2;
use glam::{DMat4, DVec2, DVec3};

/// A slice as this frame shows it: its pixel grid in the world, and the image's place on screen.
#[derive(Clone, Copy)]
pub struct ShownSlice {
    pub frame: SliceFrame,
    /// Voxel index to world millimetres.
    pub mm: DMat4,
    /// Where the image is drawn (points).
    pub shown: egui::Rect,
    /// Points per image pixel.
    pub scale: f32,
}

impl ShownSlice {
    pub fn to_screen(self, p: DVec2) -> Pos2 {
        Pos2::new(
            self.shown.left() + p.x as f32 * self.scale,
            self.shown.top() + p.y as f32 * self.scale,
        )
    }

    /// The world point (mm) under screen point `p`.
    pub fn world_at(self, p: Pos2) -> DVec3 {
        self.frame.world(DVec2::new(
            f64::from((p.x - self.shown.left()) / self.scale),
            f64::from((p.y - self.shown.top()) / self.scale),
        ))
    }
}
