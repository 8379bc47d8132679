//! The panel laid out headless (an egui context with no window and no GPU), read back from the shapes it painted.

use crate::viewer::model::Model;
use egui::epaint::{ClippedShape, Shape, TextShape};

/// Runs `ui` once in a `width`×`height` screen (two passes, as a window's first frames, so that sizes measured
/// in the first are used in the second) and returns the text it painted, each with the rect it was clipped to.
pub fn painted_text(width: f32, height: f32, mut ui: impl FnMut(&mut egui::Ui)) -> Vec<(TextShape, egui::Rect)> {
    let ctx = egui::Context::default();
    let input = || egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(width, height))),
        ..Default::default()
    };
    let _ = ctx.run_ui(input(), &mut ui);
    let mut out = ctx.run_ui(input(), &mut ui);
    let mut texts = Vec::new();
    for ClippedShape { clip_rect, shape } in std::mem::take(&mut out.shapes) {
        collect_text(shape, clip_rect, &mut texts);
    }
    texts
}

fn collect_text(shape: Shape, clip: egui::Rect, texts: &mut Vec<(TextShape, egui::Rect)>) {
    match shape {
        Shape::Text(t) => texts.push((t, clip)),
        Shape::Vec(shapes) => shapes.into_iter().for_each(|s| collect_text(s, clip, texts)),
        _ => {}
    }
}

/// A model showing a small built-in volume.
pub fn model_with(name: &str) -> Model {
    let v = crate::volume::builtin(name, Some(16)).expect("a built-in");
    let mut model = Model::new(glam::Vec3::ONE, String::new());
    model.show_volume(&v, vec![1; 8].into(), false);
    model
}

fn volume_section_text(model: &mut Model) -> Vec<String> {
    let texts = painted_text(1280.0, 800.0, |ui| {
        super::volume::volume_section(ui, model, &mut Vec::new());
    });
    texts.into_iter().map(|(t, _)| t.galley.text().to_string()).collect()
}

#[test]
fn the_raw_fields_show_only_for_a_raw_path() {
    let mut model = model_with("box");
    for (path, raw) in [
        ("/data/head.nii.gz", false),
        ("/data/ct.dcm", false),
        ("/data/v_8x8x8_uint8.raw", true),
    ] {
        model.files.load_path = path.into();
        model.files.path_edited();
        let text = volume_section_text(&mut model);
        assert_eq!(text.iter().any(|t| t == "dims"), raw, "{path}: {text:?}");
    }
}
