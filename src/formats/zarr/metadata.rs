//! OME-Zarr group attributes (0.4's free `multiscales`/`omero`, 0.5's `ome` namespace) in volcast's terms: which
//! array axis is time, channel, z, y and x; each level's path, scale and translation in millimetres; the channels'
//! names, windows and colours; and volcast's own placement hint. Parsing is ome_zarr_metadata's; this file only
//! interprets it.

use crate::volume::ChannelInfo;
use ome_zarr_metadata::v0_4::{AxisType, AxisUnit, AxisUnitSpace, CoordinateTransform, Omero};
use ome_zarr_metadata::v0_4::{CoordinateTransformScale, CoordinateTransformTranslation};
use ome_zarr_metadata::AnyOmeFields;
use serde_json::Value;

/// What an array axis is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum AxisRole {
    Time,
    Channel,
    Space,
}

/// One axis as the multiscale names it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AxisInfo {
    pub name: String,
    pub role: AxisRole,
    /// Millimetres per unit of this (space) axis; 1 for other axes and for a space axis without a unit.
    pub to_mm: f64,
    /// The unit as the file names it, if it names one.
    pub unit: Option<String>,
}

/// One level (a `datasets` entry): its array's path in the store and its full transform per array axis (dataset
/// then multiscale transforms, as the spec composes them), space axes in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LevelInfo {
    pub path: String,
    pub scale: Vec<f64>,
    pub translation: Vec<f64>,
}

/// volcast's own placement, written by `volcast convert` (see docs/formats.md): the level-0 voxel-to-world affine
/// in millimetres and whether it is RAS.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct VolcastHint {
    pub affine: [[f64; 4]; 4],
    pub ras: bool,
    pub scaling: Option<(f64, f64)>,
}

/// The first multiscale image of a group, interpreted.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Multiscale {
    pub version: String,
    pub axes: Vec<AxisInfo>,
    pub levels: Vec<LevelInfo>,
    pub channels: Vec<ChannelInfo>,
    pub hint: Option<VolcastHint>,
    /// Things worth telling: omero ignored, units assumed, ...
    pub notes: Vec<String>,
}

impl Multiscale {
    pub fn axis_index(&self, role: AxisRole) -> Option<usize> {
        self.axes.iter().position(|a| a.role == role)
    }

    /// Array axes of space, slowest first (z, y, x or y, x).
    pub fn space_axes(&self) -> Vec<usize> {
        (0..self.axes.len())
            .filter(|&i| self.axes[i].role == AxisRole::Space)
            .collect()
    }
}

/// Whether group attributes hold OME multiscales (0.4 free or 0.5 under `ome`).
pub(crate) fn has_multiscales(attrs: &Value) -> bool {
    attrs.get("multiscales").is_some() || attrs.get("ome").and_then(|o| o.get("multiscales")).is_some()
}

/// Interprets group attributes; every error is a sentence naming what is wrong.
pub(crate) fn parse(attrs: &Value) -> Result<Multiscale, String> {
    if !has_multiscales(attrs) {
        return Err(missing_multiscales(attrs));
    }
    // omero is transitional and often partial (no min/max): parsed on its own so a loose one cannot sink the image.
    let mut stripped = attrs.clone();
    let omero_json = take_omero(&mut stripped);
    let fields: AnyOmeFields =
        serde_json::from_value(stripped).map_err(|e| format!("its OME multiscales metadata is invalid: {e}"))?;
    let version = fields.version();
    let multiscales = match fields {
        AnyOmeFields::V0_4(f) => f
            .multiscales
            .unwrap_or_default()
            .into_iter()
            .map(Image::from_v04)
            .collect(),
        AnyOmeFields::V0_5(f) => f
            .multiscales
            .unwrap_or_default()
            .into_iter()
            .map(Image::from_v05)
            .collect(),
    };
    let image: Image = Vec::into_iter(multiscales)
        .next()
        .ok_or("its multiscales list is empty")?;
    let mut notes = Vec::new();
    let axes = axes(&image.axes, &mut notes)?;
    let levels = levels(&image, axes.len(), &axes)?;
    let channels = channels(omero_json, &mut notes);
    let hint = hint(attrs, image.metadata.as_ref(), &mut notes);
    Ok(Multiscale {
        version,
        axes,
        levels,
        channels,
        hint,
        notes,
    })
}

fn missing_multiscales(attrs: &Value) -> String {
    let keys: Vec<&str> = attrs
        .as_object()
        .map(|m| m.keys().map(String::as_str).collect())
        .unwrap_or_default();
    let what = if attrs.get("ome").is_some() {
        "its \"ome\" attributes have no \"multiscales\""
    } else {
        "its attributes have no OME \"multiscales\" (0.4) or \"ome\".\"multiscales\" (0.5)"
    };
    if keys.is_empty() {
        format!("a Zarr group without OME-Zarr metadata: {what}")
    } else {
        format!(
            "a Zarr group without OME-Zarr metadata: {what} (it has {})",
            keys.join(", ")
        )
    }
}

fn take_omero(attrs: &mut Value) -> Option<Value> {
    let top = attrs.as_object_mut().and_then(|m| m.remove("omero"));
    let nested = attrs
        .get_mut("ome")
        .and_then(Value::as_object_mut)
        .and_then(|m| m.remove("omero"));
    top.or(nested)
}

/// The parts of a 0.4 or 0.5 multiscale image volcast uses.
struct Image {
    axes: Vec<ome_zarr_metadata::v0_4::Axis>,
    datasets: Vec<(String, Vec<CoordinateTransform>)>,
    transforms: Vec<CoordinateTransform>,
    metadata: Option<serde_json::Map<String, Value>>,
}

/// An [`Image`] from either version's multiscale: the crate's two types have the same fields.
macro_rules! image_from {
    ($m:expr) => {{
        let m = $m;
        Image {
            axes: m.axes,
            datasets: m
                .datasets
                .into_iter()
                .map(|d| (d.path, d.coordinate_transformations))
                .collect(),
            transforms: m.coordinate_transformations.unwrap_or_default(),
            metadata: m.metadata.map(|m| m.0),
        }
    }};
}

impl Image {
    fn from_v04(m: ome_zarr_metadata::v0_4::MultiscaleImage) -> Image {
        image_from!(m)
    }

    fn from_v05(m: ome_zarr_metadata::v0_5::MultiscaleImage) -> Image {
        image_from!(m)
    }
}

fn axes(list: &[ome_zarr_metadata::v0_4::Axis], notes: &mut Vec<String>) -> Result<Vec<AxisInfo>, String> {
    let mut out = Vec::with_capacity(list.len());
    for axis in list {
        let role = match (&axis.r#type, axis.name.as_str()) {
            (Some(AxisType::Space), _) | (None, "x" | "y" | "z") => AxisRole::Space,
            (Some(AxisType::Time), _) | (None, "t") => AxisRole::Time,
            (Some(AxisType::Channel), _) | (None, "c") => AxisRole::Channel,
            (other, name) => {
                return Err(format!(
                    "axis '{name}' is of type {other:?}; volcast reads time, channel and space axes only"
                ))
            }
        };
        let (to_mm, unit) = match (&axis.unit, role) {
            (Some(AxisUnit::Space(u)), AxisRole::Space) => (space_unit_mm(*u), Some(unit_name(&axis.unit))),
            (None, AxisRole::Space) => (1.0, None),
            (Some(u), AxisRole::Space) => {
                return Err(format!(
                    "space axis '{}' has unit {}, which is not a length",
                    axis.name,
                    unit_name(&Some(u.clone()))
                ))
            }
            (u, _) => (1.0, u.as_ref().map(|u| unit_name(&Some(u.clone())))),
        };
        out.push(AxisInfo {
            name: axis.name.clone(),
            role,
            to_mm,
            unit,
        });
    }
    check_axis_order(&out)?;
    let unitless: Vec<&str> = out
        .iter()
        .filter(|a| a.role == AxisRole::Space && a.unit.is_none())
        .map(|a| a.name.as_str())
        .collect();
    if !unitless.is_empty() {
        notes.push(format!(
            "space axes without a unit ({}): their scale is taken as millimetres",
            unitless.join(", ")
        ));
    }
    Ok(out)
}

fn unit_name(unit: &Option<AxisUnit>) -> String {
    unit.as_ref()
        .and_then(|u| serde_json::to_value(u).ok())
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

/// The spec orders axes time, channel, space, with two or three space axes and at most one of the others.
fn check_axis_order(axes: &[AxisInfo]) -> Result<(), String> {
    let names = || axes.iter().map(|a| a.name.as_str()).collect::<Vec<_>>().join(", ");
    let space = axes.iter().filter(|a| a.role == AxisRole::Space).count();
    if !(2..=3).contains(&space) {
        return Err(format!(
            "it has {space} space axes ({}); OME-Zarr images have 2 or 3",
            names()
        ));
    }
    let rank = |r: AxisRole| match r {
        AxisRole::Time => 0,
        AxisRole::Channel => 1,
        AxisRole::Space => 2,
    };
    let ordered = axes
        .windows(2)
        .all(|w| rank(w[0].role) < rank(w[1].role) || (w[0].role, w[1].role) == (AxisRole::Space, AxisRole::Space));
    if !ordered {
        return Err(format!(
            "its axes ({}) are not ordered time, channel, space with one time and one channel axis at most",
            names()
        ));
    }
    Ok(())
}

/// Millimetres per unit, for the UDUNITS-2 lengths the spec allows.
pub(crate) fn space_unit_mm(unit: AxisUnitSpace) -> f64 {
    use AxisUnitSpace as U;
    match unit {
        U::Angstrom => 1e-7,
        U::Attometer => 1e-15,
        U::Centimeter => 10.0,
        U::Decimeter => 100.0,
        U::Exameter => 1e21,
        U::Femtometer => 1e-12,
        U::Foot => 304.8,
        U::Gigameter => 1e12,
        U::Hectometer => 1e5,
        U::Inch => 25.4,
        U::Kilometer => 1e6,
        U::Megameter => 1e9,
        U::Meter => 1e3,
        U::Micrometer => 1e-3,
        U::Mile => 1_609_344.0,
        U::Millimeter => 1.0,
        U::Nanometer => 1e-6,
        U::Parsec => 3.085_677_581_491_367e19,
        U::Petameter => 1e18,
        U::Picometer => 1e-9,
        U::Terameter => 1e15,
        U::Yard => 914.4,
        U::Yoctometer => 1e-21,
        U::Yottameter => 1e27,
        U::Zeptometer => 1e-18,
        U::Zettameter => 1e24,
        _ => 1.0,
    }
}

/// Scale and translation of `transforms` (identity where absent); a transform stored in a binary path is refused.
fn scale_translation(
    transforms: &[CoordinateTransform],
    n: usize,
    whose: &str,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (mut scale, mut translation) = (vec![1.0; n], vec![0.0; n]);
    for t in transforms {
        let values: Vec<f64> = match t {
            CoordinateTransform::Identity => continue,
            CoordinateTransform::Scale(CoordinateTransformScale::List { scale }) => {
                scale.iter().map(|&v| f64::from(v)).collect()
            }
            CoordinateTransform::Translation(CoordinateTransformTranslation::List { translation }) => {
                translation.iter().map(|&v| f64::from(v)).collect()
            }
            _ => {
                return Err(format!(
                    "{whose} stores a transform in a binary path; volcast reads listed scales and translations only"
                ))
            }
        };
        if values.len() != n {
            return Err(format!(
                "{whose} has a transform of {} values for {n} axes",
                values.len()
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("{whose} has a transform that is not finite: {values:?}"));
        }
        match t {
            CoordinateTransform::Scale(_) => {
                // A scale after a translation scales it too.
                for i in 0..n {
                    scale[i] *= values[i];
                    translation[i] *= values[i];
                }
            }
            _ => (0..n).for_each(|i| translation[i] += values[i]),
        }
    }
    Ok((scale, translation))
}

fn levels(image: &Image, n: usize, axes: &[AxisInfo]) -> Result<Vec<LevelInfo>, String> {
    if image.datasets.is_empty() {
        return Err("its multiscale lists no datasets (levels)".into());
    }
    let (outer_scale, outer_shift) = scale_translation(&image.transforms, n, "the multiscale")?;
    let mut out = Vec::with_capacity(image.datasets.len());
    for (k, (path, transforms)) in image.datasets.iter().enumerate() {
        check_level_path(path)?;
        let (s, t) = scale_translation(transforms, n, &format!("level {k} ('{path}')"))?;
        let scale: Vec<f64> = (0..n).map(|i| s[i] * outer_scale[i] * axes[i].to_mm).collect();
        let translation: Vec<f64> = (0..n)
            .map(|i| (t[i] * outer_scale[i] + outer_shift[i]) * axes[i].to_mm)
            .collect();
        out.push(LevelInfo {
            path: path.clone(),
            scale,
            translation,
        });
    }
    Ok(out)
}

/// A level's path must name a node inside the store: relative, no `..`, no empty or `.` parts.
pub(crate) fn check_level_path(path: &str) -> Result<(), String> {
    let bad = path.is_empty()
        || path.starts_with('/')
        || path.contains('\\')
        || path.contains(':')
        || path.split('/').any(|p| p.is_empty() || p == "." || p == "..");
    if bad {
        return Err(format!(
            "dataset path '{}' leaves the store or is not a plain relative path; volcast reads levels inside the store only",
            crate::formats::format::clip(path)
        ));
    }
    Ok(())
}

fn channels(omero: Option<Value>, notes: &mut Vec<String>) -> Vec<ChannelInfo> {
    let Some(json) = omero else { return Vec::new() };
    if let Some(colour) = non_ascii_colour(&json) {
        notes.push(format!(
            "omero channel metadata ignored: colour {colour:?} is not six hexadecimal digits"
        ));
        return Vec::new();
    }
    match serde_json::from_value::<Omero>(json.clone()) {
        Ok(o) => o
            .channels
            .iter()
            .enumerate()
            .map(|(i, c)| ChannelInfo {
                name: c
                    .other
                    .get("label")
                    .and_then(Value::as_str)
                    .map_or_else(|| format!("channel {i}"), str::to_string),
                window: [c.window.start, c.window.end],
                color: [c.color.r, c.color.g, c.color.b],
                loaded: false,
            })
            .collect(),
        Err(e) => {
            notes.push(format!("omero channel metadata ignored: {e}"));
            Vec::new()
        }
    }
}

/// A channel colour that is a string with a character outside ASCII: ome_zarr_metadata 0.3.1 slices colours by byte
/// index and panics inside such a character (found by the `zarr_meta` fuzzer), so they never reach it.
fn non_ascii_colour(omero: &Value) -> Option<&str> {
    omero
        .get("channels")?
        .as_array()?
        .iter()
        .filter_map(|c| c.get("color")?.as_str())
        .find(|c| !c.is_ascii())
}

/// volcast's hint: where `volcast convert` writes it, the first multiscale's own `volcast` key (0.4's top-level
/// `multiscales` or 0.5's under `ome`); also its `metadata.volcast`, or the group attributes' `volcast` (top or
/// under `ome`).
fn hint(
    attrs: &Value,
    metadata: Option<&serde_json::Map<String, Value>>,
    notes: &mut Vec<String>,
) -> Option<VolcastHint> {
    let multiscale = attrs
        .get("multiscales")
        .or_else(|| attrs.get("ome").and_then(|o| o.get("multiscales")))
        .and_then(|m| m.get(0));
    let json = multiscale
        .and_then(|m| m.get("volcast"))
        .or_else(|| metadata.and_then(|m| m.get("volcast")))
        .or_else(|| attrs.get("volcast"))
        .or_else(|| attrs.get("ome").and_then(|o| o.get("volcast")))?;
    match parse_hint(json) {
        Some(h) => Some(h),
        None => {
            notes.push("volcast placement metadata ignored: it is not a finite 4x4 affine".into());
            None
        }
    }
}

fn parse_hint(json: &Value) -> Option<VolcastHint> {
    let rows = json.get("affine")?.as_array()?;
    if rows.len() != 4 {
        return None;
    }
    let mut affine = [[0.0; 4]; 4];
    for (r, row) in rows.iter().enumerate() {
        let row = row.as_array()?;
        if row.len() != 4 {
            return None;
        }
        for (c, v) in row.iter().enumerate() {
            affine[r][c] = v.as_f64().filter(|v| v.is_finite())?;
        }
    }
    let ras = json.get("frame").and_then(Value::as_str) == Some("RAS");
    let scaling = json
        .get("scaling")
        .and_then(|s| Some((s.get("slope")?.as_f64()?, s.get("intercept")?.as_f64()?)));
    Some(VolcastHint { affine, ras, scaling })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn v04(datasets: Value, extra: Value) -> Value {
        let mut m = json!({
            "version": "0.4",
            "axes": [{"name": "z", "type": "space", "unit": "micrometer"},
                     {"name": "y", "type": "space", "unit": "micrometer"},
                     {"name": "x", "type": "space", "unit": "nanometer"}],
            "datasets": datasets,
        });
        if let Some(o) = extra.as_object() {
            m.as_object_mut().unwrap().extend(o.clone());
        }
        json!({ "multiscales": [m] })
    }

    #[test]
    fn transforms_compose_and_convert_to_millimetres() {
        let attrs = v04(
            json!([{"path": "0", "coordinateTransformations": [
                {"type": "scale", "scale": [2.0, 0.5, 1000.0]},
                {"type": "translation", "translation": [10.0, 0.0, 0.0]}]}]),
            json!({"coordinateTransformations": [{"type": "scale", "scale": [2.0, 1.0, 1.0]}]}),
        );
        let m = parse(&attrs).unwrap();
        assert_eq!(m.levels[0].scale, vec![4.0 * 1e-3, 0.5e-3, 1000.0 * 1e-6]);
        assert!((m.levels[0].translation[0] - 20.0e-3).abs() < 1e-12);
        assert_eq!(m.space_axes(), vec![0, 1, 2]);
    }

    #[test]
    fn paths_that_leave_the_store_are_refused() {
        for p in ["../0", "/abs", "a/../../b", "", "c:/x", "./0"] {
            let attrs = v04(
                json!([{"path": p, "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 1.0]}]}]),
                json!({}),
            );
            let e = parse(&attrs).unwrap_err();
            assert!(e.contains("leaves the store"), "{p}: {e}");
        }
    }

    #[test]
    fn a_group_without_multiscales_is_named() {
        let e = parse(&json!({"foo": 1})).unwrap_err();
        assert!(e.contains("without OME-Zarr metadata") && e.contains("foo"), "{e}");
    }

    /// A 0.4 image of one level at unit scale: the ground the omero tests put their channels on.
    fn one_level() -> Value {
        v04(
            json!([{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 1.0]}]}]),
            json!({}),
        )
    }

    #[test]
    fn a_non_ascii_colour_is_a_note_not_a_panic() {
        // The zarr_meta fuzzer's finding: a two-byte character across the crate's byte slice of the colour.
        let mut attrs = one_level();
        attrs["omero"] = json!({"channels": [{"label": "a", "color": "0\u{279}0000",
            "window": {"start": 0.0, "end": 1.0, "min": 0.0, "max": 1.0}}]});
        let m = parse(&attrs).unwrap();
        assert!(m.channels.is_empty(), "{:?}", m.channels);
        assert!(
            m.notes.iter().any(|n| n.contains("not six hexadecimal digits")),
            "{:?}",
            m.notes
        );
    }

    #[test]
    fn loose_omero_is_a_note_and_channels_read() {
        let mut attrs = one_level();
        attrs["omero"] = json!({"channels": [{"label": "DAPI", "color": "0000FF",
            "window": {"min": 0.0, "max": 255.0, "start": 10.0, "end": 200.0}}]});
        let m = parse(&attrs).unwrap();
        assert_eq!(
            m.channels,
            vec![ChannelInfo {
                name: "DAPI".into(),
                window: [10.0, 200.0],
                color: [0, 0, 255],
                loaded: false
            }]
        );
        attrs["omero"] = json!({"channels": [{"label": "x"}]});
        let m = parse(&attrs).unwrap();
        assert!(m.channels.is_empty() && m.notes.iter().any(|n| n.contains("omero")));
    }
}
