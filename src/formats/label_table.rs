//! Label tables: the names and colours of a label map's ids, in the forms the tools write.
//! - FreeSurfer and 3D Slicer colour tables (`.txt`, `.ctbl`): `id name r g b a` per line, `#` comments. FreeSurfer
//!   writes 0 in the last column for every row; where every row has 0 there, it is ignored (opaque).
//! - ITK-SNAP label descriptions: `id r g b a visible mesh "name"`, opacity a in [0, 1].
//! - mricron's pair beside an atlas: `atlas.nii.txt` (`id name code`) and `atlas.nii.lut`, 768 bytes: 256 reds,
//!   256 greens, 256 blues, indexed by id.

use crate::volume::labels::{LabelEntry, LabelTable};
use std::path::{Path, PathBuf};

/// Why a label table could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    #[error("cannot read the label table {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}, line {line}: '{text}' is not a label row ({why})")]
    Row {
        path: PathBuf,
        line: usize,
        text: String,
        why: &'static str,
    },
    #[error("{path} is {len} bytes; an mricron .lut is 768 (256 reds, greens and blues)")]
    Lut { path: PathBuf, len: usize },
}

/// A table read from `path`, and warnings for the user (duplicate ids: the last row wins).
pub fn read(path: &Path) -> Result<(LabelTable, Vec<String>), TableError> {
    let io = |source| TableError::Io {
        path: path.to_path_buf(),
        source,
    };
    let text = std::fs::read_to_string(path).map_err(io)?;
    let lut = lut_beside(path).map(|p| read_lut(&p)).transpose()?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let row = parse_row(line, lut.as_ref()).map_err(|why| TableError::Row {
            path: path.to_path_buf(),
            line: i + 1,
            text: line.chars().take(60).collect(),
            why,
        })?;
        rows.push(row);
    }
    // FreeSurfer's last column is 0 on every row: not an opacity.
    if rows.iter().all(|(_, alpha_given)| *alpha_given) && rows.iter().all(|(e, _)| e.rgba[3] == 0) {
        for (e, _) in &mut rows {
            e.rgba[3] = 255;
        }
    }
    Ok(table_of(rows.into_iter().map(|(e, _)| e).collect(), path))
}

/// The entries sorted by id, the last row of a duplicated id kept, with a warning naming each duplicate.
fn table_of(mut entries: Vec<LabelEntry>, path: &Path) -> (LabelTable, Vec<String>) {
    let mut warnings = Vec::new();
    entries.reverse();
    entries.sort_by_key(|e| e.id);
    let mut kept: Vec<LabelEntry> = Vec::with_capacity(entries.len());
    for e in entries {
        if kept.last().is_some_and(|k| k.id == e.id) {
            warnings.push(format!(
                "{}: id {} is listed more than once; the last row ('{}') is used",
                path.display(),
                e.id,
                kept.last().map_or("", |k| k.name.as_str())
            ));
            continue;
        }
        kept.push(e);
    }
    (LabelTable { entries: kept }, warnings)
}

/// One row: the entry and whether it gave an opacity.
fn parse_row(line: &str, lut: Option<&Vec<[u8; 3]>>) -> Result<(LabelEntry, bool), &'static str> {
    if let Some(q) = line.find('"') {
        return itk_snap_row(line, q).map(|e| (e, false));
    }
    let fields: Vec<&str> = line.split_whitespace().collect();
    let id: u32 = fields[0].parse().map_err(|_| "its first field is not an id")?;
    let name = fields.get(1).ok_or("it has no name")?.to_string();
    let numbers: Vec<&str> = fields[2..].to_vec();
    if numbers.len() >= 3 {
        let c: Vec<u8> = numbers[..numbers.len().min(4)]
            .iter()
            .map(|f| f.parse::<u8>())
            .collect::<Result<_, _>>()
            .map_err(|_| "its colour is not three or four numbers 0-255")?;
        let alpha = c.get(3).copied();
        let entry = LabelEntry {
            id,
            name,
            rgba: [c[0], c[1], c[2], alpha.unwrap_or(255)],
        };
        return Ok((entry, alpha.is_some()));
    }
    // mricron's `id name code`: the colour from the .lut beside it, else the default.
    let rgb = lut.and_then(|l| l.get(id as usize).copied());
    let [r, g, b] = rgb.unwrap_or_else(|| crate::volume::labels::default_colour(id));
    Ok((
        LabelEntry {
            id,
            name,
            rgba: [r, g, b, 255],
        },
        false,
    ))
}

/// ITK-SNAP: `id r g b a visible mesh "name"`.
fn itk_snap_row(line: &str, quote: usize) -> Result<LabelEntry, &'static str> {
    let name = line[quote + 1..].trim_end().trim_end_matches('"').to_string();
    let f: Vec<&str> = line[..quote].split_whitespace().collect();
    if f.len() < 6 {
        return Err("an ITK-SNAP row has id, r, g, b, a, visibility, mesh and a quoted name");
    }
    let id: u32 = f[0].parse().map_err(|_| "its first field is not an id")?;
    let c: Vec<u8> = f[1..4]
        .iter()
        .map(|x| x.parse::<u8>())
        .collect::<Result<_, _>>()
        .map_err(|_| "its colour is not three numbers 0-255")?;
    let a: f64 = f[4].parse().map_err(|_| "its opacity is not a number 0-1")?;
    let visible = f[5] != "0";
    let alpha = if visible {
        (a.clamp(0.0, 1.0) * 255.0).round() as u8
    } else {
        0
    };
    Ok(LabelEntry {
        id,
        name,
        rgba: [c[0], c[1], c[2], alpha],
    })
}

/// The segments a 3D Slicer segmentation (`.seg.nrrd`) names in its header (`SegmentN_Name`, `_Color` in 0–1,
/// `_LabelValue`, `_Layer`): per segment, its layer and its entry; None where the file names no segment.
pub fn seg_nrrd(path: &Path) -> Result<Option<Vec<(u32, LabelEntry)>>, TableError> {
    use std::io::Read;
    let io = |source| TableError::Io {
        path: path.to_path_buf(),
        source,
    };
    // The header is text up to the first blank line; 1 MiB holds thousands of segments.
    let mut head = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(1 << 20)
        .read_to_end(&mut head)
        .map_err(io)?;
    let text = String::from_utf8_lossy(&head);
    let header = text.split("\n\n").next().unwrap_or("");
    let field = |n: usize, key: &str| {
        let prefix = format!("Segment{n}_{key}:=");
        header.lines().find_map(|l| l.strip_prefix(&prefix).map(str::trim))
    };
    let mut segments = Vec::new();
    for n in 0.. {
        let Some(value) = field(n, "LabelValue") else { break };
        let bad = |why| TableError::Row {
            path: path.to_path_buf(),
            line: 0,
            text: format!("Segment{n}"),
            why,
        };
        let id: u32 = value.parse().map_err(|_| bad("its LabelValue is not an id"))?;
        let layer: u32 = field(n, "Layer")
            .unwrap_or("0")
            .parse()
            .map_err(|_| bad("its Layer is not a number"))?;
        let colour: Vec<f64> = field(n, "Color")
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|c| c.parse().ok())
            .collect();
        let rgb = match colour[..] {
            [r, g, b] => [r, g, b].map(|c: f64| (c.clamp(0.0, 1.0) * 255.0).round() as u8),
            _ => crate::volume::labels::default_colour(id),
        };
        let name = field(n, "Name").unwrap_or("").to_string();
        segments.push((
            layer,
            LabelEntry {
                id,
                name,
                rgba: [rgb[0], rgb[1], rgb[2], 255],
            },
        ));
    }
    Ok((!segments.is_empty()).then_some(segments))
}

/// The table of one layer of a segmentation's segments.
pub fn layer_table(segments: &[(u32, LabelEntry)], layer: u32) -> LabelTable {
    let mut entries: Vec<LabelEntry> = segments
        .iter()
        .filter(|(l, _)| *l == layer)
        .map(|(_, e)| e.clone())
        .collect();
    entries.sort_by_key(|e| e.id);
    LabelTable { entries }
}

/// mricron's `.lut` beside `atlas.nii.txt`: `atlas.nii.lut`.
fn lut_beside(path: &Path) -> Option<PathBuf> {
    let lut = path.with_extension("lut");
    (path.extension().is_some_and(|e| e == "txt") && lut.is_file()).then_some(lut)
}

fn read_lut(path: &Path) -> Result<Vec<[u8; 3]>, TableError> {
    let bytes = std::fs::read(path).map_err(|source| TableError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.len() != 768 {
        return Err(TableError::Lut {
            path: path.to_path_buf(),
            len: bytes.len(),
        });
    }
    Ok((0..256).map(|i| [bytes[i], bytes[256 + i], bytes[512 + i]]).collect())
}

/// The table beside a label map, where the tools put it: `aal.nii.gz` → `aal.nii.txt`, `aal.txt`, `aal.ctbl`,
/// `aal.label` (ITK-SNAP), `aal.nii.ctbl`.
pub fn beside(map: &Path) -> Option<PathBuf> {
    let name = map.file_name()?.to_string_lossy().into_owned();
    let no_gz = name.strip_suffix(".gz").unwrap_or(&name);
    let stem = no_gz.rsplit_once('.').map_or(no_gz, |(s, _)| s);
    [
        format!("{no_gz}.txt"),
        format!("{stem}.txt"),
        format!("{stem}.ctbl"),
        format!("{no_gz}.ctbl"),
        format!("{stem}.label"),
    ]
    .into_iter()
    .map(|n| map.with_file_name(n))
    .find(|p| p.is_file() && p != map)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(name: &str, text: &str) -> Result<(LabelTable, Vec<String>), TableError> {
        let dir = std::env::temp_dir().join(format!("volcast-labels-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        read(&p)
    }

    #[test]
    fn slicer_freesurfer_and_itk_snap_rows() {
        let (t, w) = table("a.ctbl", "# Slicer\n0 Background 0 0 0 0\n2 liver 221 130 101 255\n").unwrap();
        assert!(w.is_empty());
        assert_eq!(t.get(2).unwrap().rgba, [221, 130, 101, 255]);
        let (t, _) = table("fs.txt", "2 Left-WM 245 245 245 0\n3 Left-Cortex 205 62 78 0\n").unwrap();
        assert_eq!(
            t.get(3).unwrap().rgba,
            [205, 62, 78, 255],
            "FreeSurfer's zeros are not opacities"
        );
        let snap = "    0     0    0    0        0  0  0    \"Clear Label\"\n    5   255    0    0     0.5  1  1    \"Tumour core\"\n";
        let (t, _) = table("s.label", snap).unwrap();
        assert_eq!(t.get(5).unwrap().name, "Tumour core");
        assert_eq!(t.get(5).unwrap().rgba, [255, 0, 0, 128]);
    }

    #[test]
    fn duplicates_warn_and_bad_rows_name_the_line() {
        let (t, w) = table("d.ctbl", "1 a 1 2 3 255\n1 b 4 5 6 255\n").unwrap();
        assert_eq!(t.get(1).unwrap().name, "b");
        assert!(w[0].contains("id 1 is listed more than once"), "{w:?}");
        let e = table("bad.ctbl", "1 a 1 2 3 255\nx y\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("bad.ctbl"), "{e}");
    }
}
