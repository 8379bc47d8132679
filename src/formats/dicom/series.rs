//! A folder holding several DICOM series: which one is loaded (the one `--series` names, else the largest) and
//! the list of them that `volcast info`, the notes and the viewer's chooser show.

use super::slice::Slice;
use crate::volume::{SeriesInfo, VolumeError};

/// The series in `slices`, in order of SeriesNumber (then UID), none marked loaded yet.
fn list(slices: &[Slice]) -> Vec<SeriesInfo> {
    let mut series: Vec<SeriesInfo> = Vec::new();
    for s in slices {
        match series.iter_mut().find(|i| i.uid == s.series) {
            Some(i) => i.slices += 1,
            None => series.push(SeriesInfo {
                number: s.series_number,
                uid: s.series.clone(),
                description: s.series_description.clone(),
                modality: s.modality.clone(),
                slices: 1,
                size: [s.columns, s.rows],
                loaded: false,
            }),
        }
    }
    series.sort_by(|a, b| (a.number, &a.uid).cmp(&(b.number, &b.uid)));
    series
}

/// Keeps the slices of one series: the one `wanted` names (a SeriesNumber or a SeriesInstanceUID), else the one
/// with the most slices (the first of those as large). Returns them with the list of every series (empty for a
/// single series); an unknown `wanted` is an error that lists them.
pub(super) fn choose(
    slices: Vec<Slice>,
    wanted: Option<&str>,
    label: &str,
) -> Result<(Vec<Slice>, Vec<SeriesInfo>), VolumeError> {
    let mut series = list(&slices);
    let chosen = match wanted.map(str::trim) {
        Some(w) => series
            .iter()
            .position(|s| s.uid == w)
            .or_else(|| series.iter().position(|s| s.number.is_some_and(|n| n.to_string() == w)))
            .ok_or_else(|| VolumeError::UnknownSeries {
                file: label.to_string(),
                given: w.to_string(),
                list: series
                    .iter()
                    .map(|s| format!("  {}", s.line()))
                    .collect::<Vec<_>>()
                    .join("\n"),
            })?,
        // The first of the largest in file order, as before the list was kept.
        None => {
            let most = series.iter().map(|s| s.slices).max().unwrap_or(0);
            let first = slices
                .iter()
                .find(|s| series.iter().any(|i| i.uid == s.series && i.slices == most));
            first
                .and_then(|f| series.iter().position(|i| i.uid == f.series))
                .unwrap_or(0)
        }
    };
    // One series is listed too (`info` shows its description and modality), loaded, with no note.
    if series.len() < 2 {
        series.iter_mut().for_each(|s| s.loaded = true);
        return Ok((slices, series));
    }
    series[chosen].loaded = true;
    let uid = series[chosen].uid.clone();
    let kept = slices.into_iter().filter(|s| s.series == uid).collect();
    Ok((kept, series))
}

/// Which series was loaded and that others exist; none for a folder of one series.
pub(super) fn note(series: &[SeriesInfo]) -> Option<String> {
    if series.len() < 2 {
        return None;
    }
    let loaded = series.iter().find(|s| s.loaded)?;
    let description = if loaded.description.is_empty() {
        String::new()
    } else {
        format!("'{}', ", loaded.description)
    };
    Some(format!(
        "the folder holds {} series; loaded series {} ({description}{} slices); --series N or UID picks another \
         (volcast info lists them)",
        series.len(),
        loaded.selector(series),
        loaded.slices
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(series: &str, number: Option<i64>) -> Slice {
        let mut s = crate::formats::dicom::tests::slice(0.0, 1);
        s.series = series.into();
        s.series_number = number;
        s
    }

    #[test]
    fn the_largest_by_default_else_the_one_named_by_number_or_uid() {
        let slices = || {
            vec![
                slice("1.2.9", Some(3)),
                slice("1.2.5", Some(2)),
                slice("1.2.5", Some(2)),
                slice("1.2.7", None),
            ]
        };
        let (kept, list) = choose(slices(), None, "x").unwrap();
        assert_eq!(kept.len(), 2);
        // Unnumbered first, then by number.
        let order: Vec<&str> = list.iter().map(|s| s.uid.as_str()).collect();
        assert_eq!(order, ["1.2.7", "1.2.5", "1.2.9"]);
        assert!(list[1].loaded && !list[0].loaded && !list[2].loaded);
        let n = note(&list).unwrap();
        assert!(
            n.contains("holds 3 series; loaded series 2 (2 slices); --series"),
            "{n}"
        );
        let (kept, list) = choose(slices(), Some("3"), "x").unwrap();
        assert_eq!((kept.len(), kept[0].series.as_str()), (1, "1.2.9"));
        assert!(list[2].loaded);
        let (kept, _) = choose(slices(), Some("1.2.7"), "x").unwrap();
        assert_eq!(kept[0].series, "1.2.7");
        let e = choose(slices(), Some("4"), "x").err().unwrap().to_string();
        assert!(
            e.contains("no series '4'") && e.contains("UID 1.2.9") && e.contains("2: "),
            "{e}"
        );
    }

    #[test]
    fn one_series_is_listed_as_loaded_with_no_note() {
        let (kept, list) = choose(vec![slice("1", Some(1)), slice("1", Some(1))], None, "x").unwrap();
        assert_eq!((kept.len(), list.len()), (2, 1));
        assert!(list[0].loaded && list[0].slices == 2);
        assert!(note(&list).is_none());
        assert!(choose(vec![slice("1", Some(1))], Some("1"), "x").is_ok());
    }
}
