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

/// The panel as the window lays it out (at its fixed width, in a vertical scroll area),
/// run for a few frames with `events` in the second (to open a section), then the text it painted.
fn panel_frames(
    model: &mut Model,
    events: impl Fn(&[(TextShape, egui::Rect)]) -> Vec<egui::Event>,
) -> Vec<(TextShape, egui::Rect)> {
    let ctx = egui::Context::default();
    let panel = crate::viewer::widgets::layout::PANEL_WIDTH;
    let mut texts = Vec::new();
    for frame in 0..12 {
        let input = egui::RawInput {
            // 1280 wide as the default window; tall enough that no line is scrolled out of view (egui skips
            // painting what is out of view), while each line's width is what the default window gives it.
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1280.0, 4000.0))),
            // A tenth of a second a frame: opening animations end within the run.
            time: Some(frame as f64 * 0.1),
            events: if frame == 2 { events(&texts) } else { Vec::new() },
            ..Default::default()
        };
        let out = ctx.run_ui(input, |ui| {
            egui::Panel::left("settings")
                .resizable(false)
                .exact_size(panel)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| super::settings_panel(ui, model));
                });
        });
        texts.clear();
        for ClippedShape { clip_rect, shape } in out.shapes {
            collect_text(shape, clip_rect, &mut texts);
        }
    }
    texts
}

/// A click at `at`, as egui receives one.
fn click(at: egui::Pos2) -> Vec<egui::Event> {
    let button = |pressed| egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: Default::default(),
    };
    vec![egui::Event::PointerMoved(at), button(true), button(false)]
}

/// Every line of the whole panel at the default 1280×800 window, on a CT (anatomical axes, HU) played as a
/// series, with timings and a raw path typed, and the one section closed by default (Lighting) opened by a click:
/// the text each widget painted that was cut short (egui elided it) or runs past the panel's edges.
fn cut_text_at_default_size() -> (Vec<String>, usize) {
    let ct = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/enhanced_ct_native.dcm");
    let v = crate::formats::open(&ct, &Default::default()).expect("the CT");
    let mut model = Model::new(glam::Vec3::ONE, String::new());
    model.show_volume(&v, vec![1; 8].into(), false);
    model.time = crate::viewer::model::time::TimeControl::new(12, 0);
    model.stats.frame_ms = 123.4;
    model.stats.gpu = Some(crate::render::PassTimings {
        entry_ms: Some(12.34),
        exit_ms: Some(12.34),
        march_ms: 1234.56,
        total_ms: 1259.24,
    });
    model.files.load_path = "/data/skull_256x256x256_uint8.raw".into();
    model.files.path_edited();
    let texts = panel_frames(&mut model, |texts| {
        let header = texts.iter().find(|(t, _)| t.galley.text() == "Lighting");
        header
            .map(|(t, _)| click(t.visual_bounding_rect().center()))
            .unwrap_or_default()
    });
    // The panel's content ends its frame's inner margin before its edge.
    let right = crate::viewer::widgets::layout::PANEL_WIDTH - 8.0;
    let cut = texts
        .iter()
        .filter(|(t, clip)| {
            let rect = t.visual_bounding_rect();
            let past = rect.right() > clip.right().min(right) + 0.5 || rect.left() < clip.left() - 0.5;
            t.galley.elided || past
        })
        .map(|(t, clip)| format!("{} {:?} {:?}", t.galley.text(), t.visual_bounding_rect(), clip.right()))
        .collect();
    (cut, texts.len())
}

#[test]
fn no_text_in_the_panel_is_cut_at_the_default_window_size() {
    let (cut, seen) = cut_text_at_default_size();
    // The Lighting section's own lines are among those read (it opened).
    assert!(seen > 80, "only {seen} lines laid out");
    assert!(cut.is_empty(), "cut or running past the panel: {cut:?}");
}
