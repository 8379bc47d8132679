//! The transfer-function editor's model: what it keeps between frames ([`TfEditorState`]), the opacity points'
//! edits (here) and the colour points' ([`colors`]), and JSON save/load. Positions come in normalised units (fractions
//! of the data range, as the editor lays them out) and are stored in the transfer function's own units.

pub mod colors;

use crate::transfer::auto::{auto_transfer_function, VolumeFacts};
use crate::transfer::function::{TfUnits, TransferFunction};
use std::path::Path;
use std::sync::Arc;

/// What the editor keeps between frames. The app calls [`TfEditorState::set_volume`] whenever a volume is
/// installed.
#[derive(Clone, Debug, Default)]
pub struct TfEditorState {
    /// The opacity point being dragged.
    pub dragging: Option<usize>,
    /// The path field of save/load.
    pub path: String,
    /// The last save/load's outcome: `Ok(message)` or `Err(error)`, shown beside the buttons.
    pub message: Option<Result<String, String>>,
    /// The shown volume's facts and histogram (for "auto" and the axis unit); `None` before a volume.
    pub volume: Option<(VolumeFacts, Arc<[u64]>)>,
    /// Keep the transfer function and value window when another volume loads (else they reset: a CT's
    /// Hounsfield-unit function would leave an MRI invisible).
    pub locked: bool,
}

impl TfEditorState {
    /// Remembers what "auto" and the axis need of a newly installed volume (its value histogram over the
    /// normalised range, any bin count).
    pub fn set_volume(&mut self, volume: &crate::volume::Volume, histogram: Arc<[u64]>) {
        self.volume = Some((VolumeFacts::of(volume), histogram));
    }

    /// The values' unit ("HU" for CT).
    pub fn unit(&self) -> Option<&'static str> {
        self.volume.as_ref().and_then(|(f, _)| f.kind().unit())
    }

    /// The presets the menu offers: those of the shown volume's kind (all before a volume).
    pub fn presets(&self) -> Vec<&'static str> {
        match &self.volume {
            Some((f, _)) => f.kind().presets(),
            None => crate::transfer::function::PRESET_NAMES.to_vec(),
        }
    }

    /// The automatic transfer function for the shown volume.
    pub fn auto(&self) -> Option<TransferFunction> {
        self.volume.as_ref().map(|(f, h)| auto_transfer_function(f, h))
    }
}

/// A control point's x in normalised units for display, and back.
pub fn to_normalized(tf: &TransferFunction, x: f32, range: [f64; 2]) -> f32 {
    match tf.units {
        TfUnits::Normalized => x,
        TfUnits::Data => ((x as f64 - range[0]) / (range[1] - range[0]).max(f64::MIN_POSITIVE)) as f32,
    }
}

pub fn from_normalized(tf: &TransferFunction, u: f32, range: [f64; 2]) -> f32 {
    match tf.units {
        TfUnits::Normalized => u.clamp(0.0, 1.0),
        TfUnits::Data => (range[0] + u.clamp(0.0, 1.0) as f64 * (range[1] - range[0])) as f32,
    }
}

/// Inserts a point at normalised `u` with opacity `a`, keeping the points sorted; returns its index.
pub fn insert_point(tf: &mut TransferFunction, u: f32, a: f32, range: [f64; 2]) -> usize {
    let x = from_normalized(tf, u, range);
    let i = tf.opacity.partition_point(|p| p[0] < x);
    tf.opacity.insert(i, [x, a.clamp(0.0, 1.0)]);
    i
}

/// Moves point `i` to normalised `u`, opacity `a`, between its neighbours (points never cross).
pub fn move_point(tf: &mut TransferFunction, i: usize, u: f32, a: f32, range: [f64; 2]) {
    let mut x = from_normalized(tf, u, range);
    if i > 0 {
        x = x.max(tf.opacity[i - 1][0]);
    }
    if i + 1 < tf.opacity.len() {
        x = x.min(tf.opacity[i + 1][0]);
    }
    tf.opacity[i] = [x, a.clamp(0.0, 1.0)];
}

/// Removes point `i` unless it is the last one.
pub fn delete_point(tf: &mut TransferFunction, i: usize) -> bool {
    if tf.opacity.len() > 1 && i < tf.opacity.len() {
        tf.opacity.remove(i);
        true
    } else {
        false
    }
}

/// Writes `tf` as JSON to `path`; the message names the file.
pub fn save_tf(tf: &TransferFunction, path: &str) -> Result<String, String> {
    let path = path.trim();
    if path.is_empty() {
        return Err("enter a file name to save to".into());
    }
    std::fs::write(path, tf.to_json()).map_err(|e| format!("cannot write {path}: {e}"))?;
    let shown = std::path::absolute(path).map_or_else(|_| path.to_string(), |p| p.display().to_string());
    Ok(format!("saved {shown}"))
}

/// Reads a transfer function from `path` (validated; the error names the file and the problem).
pub fn load_tf(path: &str) -> Result<TransferFunction, String> {
    let path = path.trim();
    if path.is_empty() {
        return Err("enter a file name to load".into());
    }
    TransferFunction::load(Path::new(path)).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tf(units: TfUnits) -> TransferFunction {
        TransferFunction {
            name: "t".into(),
            units,
            colors: vec![],
            colormap: Default::default(),
            opacity: vec![[0.2, 0.0], [0.8, 0.5]],
        }
    }

    #[test]
    fn points_stay_sorted_and_between_neighbours() {
        let mut t = tf(TfUnits::Normalized);
        let i = insert_point(&mut t, 0.5, 0.3, [0.0, 1.0]);
        assert_eq!(i, 1);
        assert_eq!(t.opacity, vec![[0.2, 0.0], [0.5, 0.3], [0.8, 0.5]]);
        move_point(&mut t, 1, 0.95, 1.4, [0.0, 1.0]);
        assert_eq!(
            t.opacity[1],
            [0.8, 1.0],
            "clamped to the right neighbour and to opacity 1"
        );
        assert!(delete_point(&mut t, 0));
        assert!(delete_point(&mut t, 0));
        assert!(!delete_point(&mut t, 0), "the last point stays");
        t.validate().unwrap();
    }

    #[test]
    fn data_units_convert_through_the_range() {
        let mut t = tf(TfUnits::Data);
        t.opacity = vec![[-1024.0, 0.0], [2986.0, 1.0]];
        let range = [-1024.0, 2986.0];
        assert!((to_normalized(&t, 981.0, range) - 0.5).abs() < 1e-6);
        insert_point(&mut t, 0.5, 0.2, range);
        assert!((t.opacity[1][0] - 981.0).abs() < 1e-3);
    }

    #[test]
    fn save_and_load_name_the_file_and_round_trip() {
        let dir = std::env::temp_dir().join(format!("volcast-tf-panel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tf = TransferFunction::preset("ct-lung").unwrap();
        let path = dir.join("lung.json").display().to_string();
        assert!(save_tf(&tf, &path).unwrap().contains("lung.json"));
        assert_eq!(load_tf(&format!("  {path} ")).unwrap(), tf);
        assert!(save_tf(&tf, " ").unwrap_err().contains("file name"));
        let missing = dir.join("nope/x.json").display().to_string();
        assert!(save_tf(&tf, &missing).unwrap_err().contains("nope/x.json"));
        assert!(load_tf(&missing).unwrap_err().contains("nope/x.json"));
        std::fs::write(dir.join("bad.json"), "{\"opacity\": []}").unwrap();
        let err = load_tf(&dir.join("bad.json").display().to_string()).unwrap_err();
        assert!(err.contains("at least one opacity point"), "{err}");
    }

    #[test]
    fn auto_and_unit_follow_the_volume() {
        let mut state = TfEditorState::default();
        assert!(state.auto().is_none() && state.unit().is_none());
        let data: Vec<u16> = (0..8u32).map(|i| (32768 - 1024 + i * 500) as u16).collect();
        let v = crate::volume::Volume::new(
            "ct",
            [2, 2, 2],
            [1.0; 3],
            crate::volume::VoxelType::I16,
            crate::volume::VoxelData::U16(data),
        )
        .unwrap();
        state.set_volume(&v, Arc::from([1, 1, 1, 1]));
        assert_eq!(state.unit(), Some("HU"));
        assert!(state.auto().unwrap().name.contains("ct-bone"));
    }
}
