//! The ruler's measurements, kept for the session and saved as CSV or JSON (3D Slicer saves its line markups as
//! `.mrk.json` and CSV): each finished line with its ends in world millimetres (patient RAS for an anatomical
//! volume, as `volcast info` and the probe report them) and its length. Pure code.

use crate::scene::slice::SliceView;
use glam::{DMat4, DVec3};

/// One finished ruler line.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Measurement {
    /// The slice view it was drawn in ("axial", "sagittal", "coronal"; "xy", "yz", "xz" without orientation).
    pub view: String,
    /// The ends in world millimetres.
    pub start: [f64; 3],
    pub end: [f64; 3],
    pub length_mm: f64,
}

impl Measurement {
    /// The line from voxel index point `a` to `b` in `view`, placed by the volume's voxel-to-world affine.
    pub fn new(view: SliceView, anatomical: bool, affine: DMat4, a: DVec3, b: DVec3) -> Measurement {
        let (start, end) = (affine.transform_point3(a), affine.transform_point3(b));
        Measurement {
            view: view.name(anatomical).to_string(),
            start: start.to_array(),
            end: end.to_array(),
            length_mm: start.distance(end),
        }
    }
}

/// The file formats measurements are saved in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Csv,
    Json,
}

impl Format {
    pub fn extension(self) -> &'static str {
        match self {
            Format::Csv => "csv",
            Format::Json => "json",
        }
    }
}

/// The world frame's name: "RAS" for an anatomical volume, else "xyz" (the file's own frame).
fn space(anatomical: bool) -> &'static str {
    if anatomical {
        "RAS"
    } else {
        "xyz"
    }
}

/// `measured` of `volume` as a file of `format`.
pub fn write(format: Format, volume: &str, anatomical: bool, measured: &[Measurement]) -> String {
    match format {
        Format::Csv => csv(anatomical, measured),
        Format::Json => json(volume, anatomical, measured),
    }
}

/// One line per measurement under a header naming the frame's axes (`r1_mm` … for RAS).
fn csv(anatomical: bool, measured: &[Measurement]) -> String {
    let axes: Vec<char> = space(anatomical).to_lowercase().chars().collect();
    let ends = [1, 2].map(|n| axes.iter().map(|a| format!("{a}{n}_mm")).collect::<Vec<_>>().join(","));
    let mut out = format!("view,{},{},length_mm\n", ends[0], ends[1]);
    for m in measured {
        let [a, b, c] = m.start;
        let [d, e, f] = m.end;
        out += &format!("{},{a},{b},{c},{d},{e},{f},{}\n", m.view, m.length_mm);
    }
    out
}

fn json(volume: &str, anatomical: bool, measured: &[Measurement]) -> String {
    let doc = serde_json::json!({
        "volume": volume,
        "space": space(anatomical),
        "unit": "mm",
        "measurements": measured,
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default() + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two() -> Vec<Measurement> {
        // Voxels of 2 x 1 x 3 mm shifted by (10, 20, 30): index (0,0,0)-(3,4,0) is 6 x 4 mm across.
        let affine = DMat4::from_cols_array(&[
            2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.0, 10.0, 20.0, 30.0, 1.0,
        ]);
        vec![
            Measurement::new(SliceView::Axial, true, affine, DVec3::ZERO, DVec3::new(3.0, 4.0, 0.0)),
            Measurement::new(SliceView::Coronal, true, affine, DVec3::ZERO, DVec3::new(0.0, 0.0, 1.0)),
        ]
    }

    #[test]
    fn ends_are_world_millimetres_and_lengths_follow_them() {
        let m = two();
        assert_eq!((m[0].start, m[0].end), ([10.0, 20.0, 30.0], [16.0, 24.0, 30.0]));
        assert!((m[0].length_mm - 52f64.sqrt()).abs() < 1e-12);
        assert_eq!((m[1].view.as_str(), m[1].length_mm), ("coronal", 3.0));
    }

    #[test]
    fn csv_and_json_hold_every_measurement() {
        let m = two();
        let text = write(Format::Csv, "head", true, &m);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "view,r1_mm,a1_mm,s1_mm,r2_mm,a2_mm,s2_mm,length_mm");
        assert_eq!(lines[2], "coronal,10,20,30,10,20,33,3");
        assert_eq!(lines.len(), 3);
        let doc: serde_json::Value = serde_json::from_str(&write(Format::Json, "head", false, &m)).unwrap();
        assert_eq!(
            (doc["volume"].as_str(), doc["space"].as_str()),
            (Some("head"), Some("xyz"))
        );
        assert_eq!(doc["measurements"][0]["end"], serde_json::json!([16.0, 24.0, 30.0]));
        assert_eq!(doc["measurements"].as_array().unwrap().len(), 2);
    }
}
