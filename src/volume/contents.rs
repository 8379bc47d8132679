//! What a file held beside the voxels a volume shows: its other data arrays, series or channels, each marked
//! whether it is the one loaded. `volcast info` lists them, the viewer offers them, and the readers fill them in;
//! they are the model's, so the volume can carry them without knowing any reader.

use super::clip;

/// One data array of a multi-array file, as `volcast info` lists it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ArrayInfo {
    pub name: String,
    /// The type as the file names it (`unsigned_char`, `Float32`, ...).
    #[serde(rename = "type")]
    pub type_name: String,
    pub components: u32,
    /// This is the array the volume holds.
    pub loaded: bool,
}

/// One series of a DICOM folder, as `volcast info` lists it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SeriesInfo {
    /// SeriesNumber, if the files give one.
    pub number: Option<i64>,
    /// SeriesInstanceUID (empty when the files give none).
    pub uid: String,
    pub description: String,
    pub modality: String,
    pub slices: usize,
    /// Columns x rows of its first slice.
    pub size: [u32; 2],
    /// This is the series the volume holds.
    pub loaded: bool,
}

impl SeriesInfo {
    /// What `--series` takes to pick this one: its number where that names it alone, else its UID.
    pub fn selector(&self, all: &[SeriesInfo]) -> String {
        match self.number {
            Some(n) if all.iter().filter(|s| s.number == Some(n)).count() == 1 => n.to_string(),
            _ => self.uid.clone(),
        }
    }

    /// One line: number, UID, description, modality, slice count and size.
    pub fn line(&self) -> String {
        let number = self.number.map_or_else(|| "-".to_string(), |n| n.to_string());
        let description = if self.description.is_empty() {
            "(no description)".to_string()
        } else {
            format!("'{}'", self.description)
        };
        let modality = if self.modality.is_empty() { "?" } else { &self.modality };
        format!(
            "{number}: {description}, {modality}, {} slices of {} x {}, UID {}",
            self.slices,
            self.size[0],
            self.size[1],
            clip(&self.uid)
        )
    }
}

/// The colours ImageJ gives a composite image's channels, in order: red, green, blue, grey, cyan, magenta, yellow;
/// volcast gives them to the channels of files that name none (TIFF, NIfTI).
pub const CHANNEL_COLOURS: [[u8; 3]; 7] = [
    [255, 0, 0],
    [0, 255, 0],
    [0, 0, 255],
    [255, 255, 255],
    [0, 255, 255],
    [255, 0, 255],
    [255, 255, 0],
];

impl ChannelInfo {
    /// The channels `0..count` of a file that names none, `loaded` marked: no window of their own (an empty one: the
    /// data's range stands for it) and [`CHANNEL_COLOURS`]; none for a file of one channel.
    pub fn numbered(count: usize, loaded: usize) -> Vec<ChannelInfo> {
        if count < 2 {
            return Vec::new();
        }
        (0..count)
            .map(|k| ChannelInfo {
                name: format!("channel {k}"),
                window: [0.0, 0.0],
                color: CHANNEL_COLOURS[k % CHANNEL_COLOURS.len()],
                loaded: k == loaded,
            })
            .collect()
    }
}

/// A channel's display settings from `omero`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ChannelInfo {
    pub name: String,
    /// omero `window.start`, `window.end`: the display range.
    pub window: [f64; 2],
    pub color: [u8; 3],
    /// This is the channel the volume holds.
    pub loaded: bool,
}
