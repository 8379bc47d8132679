//! The one place the model turns into renderer parameters: a still frame's [`Model::render_settings`], and
//! [`Model::frame_settings`], which lowers the detail while the view moves.

use super::Model;
use crate::scene::quality::{moving_view, Gradients, Quality};
use crate::scene::settings::RenderSettings;

impl Model {
    /// The renderer's parameters for a `width`×`height` frame.
    pub fn render_settings(&self, width: u32, height: u32) -> RenderSettings {
        let mut s = self.look.clone();
        s.width = width.max(1);
        s.height = height.max(1);
        s.camera = self.view_camera(s.width as f32, s.height as f32);
        for (axis, &(pos, width)) in self.slabs.iter().enumerate() {
            s.cut.set_slab(axis, pos, width);
            // A slab thinner than the slider's resolution would be empty: keep a sliver.
            if s.cut.slab_hi[axis] <= s.cut.slab_lo[axis] {
                s.cut.slab_hi[axis] = (s.cut.slab_lo[axis] + 1e-3).min(1.0);
                s.cut.slab_lo[axis] = s.cut.slab_hi[axis] - 1e-3;
            }
        }
        if s.colour.window[0] >= s.colour.window[1] {
            s.colour.window[1] = (s.colour.window[0] + 1e-3).min(1.0);
            s.colour.window[0] = s.colour.window[1] - 1e-3;
        }
        if let Some(q) = self.sampling.quality {
            q.apply(&mut s, self.volume.range);
        }
        let gradients = if self.sampling.gradient_texture {
            Gradients::Auto
        } else {
            Gradients::Samples
        };
        gradients.apply(&mut s, self.dims.iter().map(|&d| u64::from(d)).product());
        s.layers = self.layers.frame_styles(&s);
        s
    }

    /// What a frame of `width`×`height` renders: full quality, or — while the view moves, with `lod` on — the
    /// moving view's frame ([`moving_view`]) reduced by [`Model::lod_divisor`].
    pub fn frame_settings(&self, width: u32, height: u32, moving: bool) -> RenderSettings {
        let still = self.render_settings(width, height);
        if self.sampling.lod && moving {
            moving_view(&still, self.lod_divisor(), self.sampling.quality, self.volume.range)
        } else {
            still
        }
    }

    /// How much to shrink each side while moving: aims the reduced frame (which also takes half the steps) at
    /// ~12 ms of GPU time from the last full-quality frame's, between 2 and 6. Measured on lavapipe at 512²:
    /// halving gave 68 ms per frame for the helix (15 fps), quartering 27 ms (37 fps).
    pub fn lod_divisor(&self) -> u32 {
        let full_ms = self.stats.full_frame_ms.unwrap_or(100.0);
        ((full_ms / 2.0 / 12.0).sqrt().ceil() as u32).clamp(2, 6)
    }
}

/// The Q key's cycle: one level lower, from draft to converged (a custom step goes to normal).
pub fn next_lower(q: Option<Quality>) -> Quality {
    match q {
        Some(Quality::Converged) | None => Quality::Normal,
        Some(Quality::Normal) => Quality::Fast,
        Some(Quality::Fast) => Quality::Draft,
        Some(Quality::Draft) => Quality::Converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn initial_state_renders_what_render_renders() {
        let extent = Vec3::new(1.0, 1.0, 0.5);
        let model = Model::new(extent, "x".into());
        let viewer = model.render_settings(320, 200);
        let mut cli = RenderSettings::new(320, 200, extent);
        assert!((viewer.camera.eye - cli.camera.eye).length() < 1e-5);
        assert!(
            viewer.camera.view().abs_diff_eq(cli.camera.view(), 1e-5),
            "same view matrix"
        );
        cli.camera = viewer.camera;
        // `render`'s default quality, resolved on the same value range.
        Quality::Normal.apply(&mut cli, model.volume.range);
        assert_eq!(viewer, cli);
    }

    #[test]
    fn sliders_map_to_slabs_and_degenerate_values_stay_valid() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        model.slabs[0] = (0.25, 0.3);
        model.slabs[2] = (0.9, 0.0);
        model.look.colour.window = [0.6, 0.6];
        let s = model.render_settings(10, 10);
        assert!((s.cut.slab_lo.x - 0.1).abs() < 1e-6 && (s.cut.slab_hi.x - 0.4).abs() < 1e-6);
        assert!(s.cut.slab_hi.z > s.cut.slab_lo.z, "zero width keeps a sliver");
        s.validate().expect("always valid");
    }

    #[test]
    fn quality_sets_the_still_step_and_draft_the_moving_one() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        model.stats.full_frame_ms = Some(40.0);
        let plain = model.render_settings(401, 300);
        let mut cli = model.render_settings(401, 300);
        for q in Quality::ALL {
            model.sampling.quality = Some(q);
            Quality::apply(q, &mut cli, model.volume.range);
            assert_eq!(
                model.frame_settings(401, 300, false).sampling.step_length,
                cli.sampling.step_length,
                "{q:?}"
            );
            let moving = model.frame_settings(401, 300, true).sampling.step_length;
            assert_eq!(
                moving,
                cli.sampling.step_length.max(3.0),
                "{q:?} while moving: draft's 3 voxels"
            );
        }
        // Strong opacity shortens every level's step, the draft's while moving too (to a quarter at most).
        model.look.colour.step_alpha = 1.0;
        model.sampling.quality = Some(Quality::Normal);
        let moving = model.frame_settings(401, 300, true).sampling.step_length;
        assert!((0.75..3.0).contains(&moving), "{moving}");
        assert!(model.frame_settings(401, 300, false).sampling.step_length < 0.4);
        // Q walks down the levels and wraps; a custom step keeps the slider's.
        assert_eq!(next_lower(Some(Quality::Normal)), Quality::Fast);
        assert_eq!(next_lower(Some(Quality::Draft)), Quality::Converged);
        assert_eq!(next_lower(None), Quality::Normal);
        model.sampling.quality = None;
        model.look.sampling.step_length = 0.7;
        assert_eq!(model.frame_settings(401, 300, false).sampling.step_length, 0.7);
        assert_eq!(
            plain.sampling.step_length,
            Quality::Normal.step_length(&plain, [0.0, 1.0])
        );
        // Shaded frames take the gradient texture where the viewer kept the volume for it.
        model.look.lighting.shading = Some(crate::scene::settings::Shading::default());
        assert!(!model.render_settings(8, 8).lighting.gradient_texture);
        model.sampling.gradient_texture = true;
        assert!(model.render_settings(8, 8).lighting.gradient_texture);
        model.look.lighting.shading = None;
        assert!(
            !model.render_settings(8, 8).lighting.gradient_texture,
            "unshaded frames read no gradient"
        );
    }

    #[test]
    fn level_of_detail_while_moving() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        model.sampling.quality = None;
        let still = model.frame_settings(401, 300, false);
        assert_eq!((still.width, still.height, still.sampling.step_length), (401, 300, 1.0));
        model.stats.full_frame_ms = Some(40.0);
        let moving = model.frame_settings(401, 300, true);
        assert_eq!(
            (moving.width, moving.height, moving.sampling.step_length),
            (201, 150, 2.0)
        );
        model.stats.full_frame_ms = Some(400.0);
        assert_eq!(model.lod_divisor(), 5, "slow frames shrink more");
        model.stats.full_frame_ms = Some(10_000.0);
        assert_eq!(model.lod_divisor(), 6);
        assert_eq!(moving.camera, still.camera);
        model.sampling.lod = false;
        assert_eq!(model.frame_settings(401, 300, true), still);
    }
}
