//! What one DICOM file says about its slice (or, for a multi-frame object, its frames): size, pixel format,
//! rescale, place and series, read from the parsed header and its functional groups.

use super::codec::{self, Kind};
use super::geometry::Placed;
use crate::formats::format::{self, header_error};
use crate::volume::{Scaling, VolumeError};
use dicom_object::{DefaultDicomObject, InMemDicomObject, Tag};

const ROWS: Tag = Tag(0x0028, 0x0010);
const COLUMNS: Tag = Tag(0x0028, 0x0011);
const SAMPLES_PER_PIXEL: Tag = Tag(0x0028, 0x0002);
const NUMBER_OF_FRAMES: Tag = Tag(0x0028, 0x0008);
const BITS_ALLOCATED: Tag = Tag(0x0028, 0x0100);
const BITS_STORED: Tag = Tag(0x0028, 0x0101);
const PIXEL_REPRESENTATION: Tag = Tag(0x0028, 0x0103);
const PIXEL_SPACING: Tag = Tag(0x0028, 0x0030);
const RESCALE_INTERCEPT: Tag = Tag(0x0028, 0x1052);
const RESCALE_SLOPE: Tag = Tag(0x0028, 0x1053);
const IMAGE_POSITION: Tag = Tag(0x0020, 0x0032);
const IMAGE_ORIENTATION: Tag = Tag(0x0020, 0x0037);
const SERIES_UID: Tag = Tag(0x0020, 0x000E);
const SERIES_NUMBER: Tag = Tag(0x0020, 0x0011);
const SERIES_DESCRIPTION: Tag = Tag(0x0008, 0x103E);
const MODALITY: Tag = Tag(0x0008, 0x0060);
const INSTANCE_NUMBER: Tag = Tag(0x0020, 0x0013);
const SLICE_THICKNESS: Tag = Tag(0x0018, 0x0050);
const SPACING_BETWEEN_SLICES: Tag = Tag(0x0018, 0x0088);
const TEMPORAL_POSITION: Tag = Tag(0x0020, 0x0100);
const SHARED_GROUPS: Tag = Tag(0x5200, 0x9229);
const PER_FRAME_GROUPS: Tag = Tag(0x5200, 0x9230);
const PLANE_POSITION: Tag = Tag(0x0020, 0x9113);
const PLANE_ORIENTATION: Tag = Tag(0x0020, 0x9116);
const PIXEL_MEASURES: Tag = Tag(0x0028, 0x9110);
const PIXEL_VALUE_TRANSFORMATION: Tag = Tag(0x0028, 0x9145);

/// What one file says about its slice.
#[derive(Clone, Debug)]
pub(super) struct Slice {
    pub(super) source: usize,
    pub(super) rows: u32,
    pub(super) columns: u32,
    pub(super) frames: u32,
    pub(super) bits_allocated: u16,
    pub(super) bits_stored: u16,
    pub(super) signed: bool,
    pub(super) scaling: Scaling,
    pub(super) pixel_spacing: Option<[f64; 2]>,
    pub(super) position: Option<[f64; 3]>,
    pub(super) orientation: Option<[f64; 6]>,
    pub(super) series: String,
    /// SeriesNumber (0020,0011), if the file gives one.
    pub(super) series_number: Option<i64>,
    /// SeriesDescription (0008,103E); empty when absent.
    pub(super) series_description: String,
    /// Modality (0008,0060): "CT", "MR", ...; empty when absent.
    pub(super) modality: String,
    pub(super) instance: i64,
    pub(super) slice_step: Option<f64>,
    /// Implicit or explicit VR little endian: pixel bytes in the file are the values, little-endian.
    pub(super) native_little_endian: bool,
    /// How the pixel data is encoded, and the transfer syntax UID.
    pub(super) kind: Kind,
    pub(super) transfer_syntax: String,
    /// A multi-frame object's per-frame places (PerFrameFunctionalGroupsSequence), one per frame; empty when the
    /// frames are placed by one position and the slice step.
    pub(super) frame_places: Vec<Placed>,
    /// TemporalPositionIdentifier: slices of one series at several times (cine, perfusion, 4-D CT).
    pub(super) temporal: Option<i64>,
}

impl Slice {
    /// Where the slice's header places it.
    pub(super) fn placed(&self) -> Placed {
        Placed {
            position: self.position,
            orientation: self.orientation,
            instance: self.instance,
        }
    }
}

fn floats(obj: &InMemDicomObject, tag: Tag) -> Option<Vec<f64>> {
    let v = obj.element_opt(tag).ok().flatten()?.to_multi_float64().ok()?;
    v.iter().all(|x| x.is_finite()).then_some(v)
}

fn int(obj: &InMemDicomObject, tag: Tag) -> Option<i64> {
    obj.element_opt(tag).ok().flatten()?.to_int::<i64>().ok()
}

/// The first item of sequence `tag` in `obj`.
fn item(obj: &InMemDicomObject, tag: Tag) -> Option<&InMemDicomObject> {
    obj.element_opt(tag).ok().flatten()?.items()?.first()
}

/// `tag` inside the functional group macro `group` (e.g. PlanePositionSequence), looked up in one frame's
/// group item and then in the shared one.
fn in_groups(
    frame: Option<&InMemDicomObject>,
    shared: Option<&InMemDicomObject>,
    group: Tag,
    tag: Tag,
) -> Option<Vec<f64>> {
    let from = |g: Option<&InMemDicomObject>| g.and_then(|g| item(g, group)).and_then(|m| floats(m, tag));
    from(frame).or_else(|| from(shared))
}

pub(super) fn slice_info(obj: &DefaultDicomObject, source: usize, label: &str) -> Result<Slice, VolumeError> {
    let err = |problem: String| header_error(label, problem);
    let format = PixelFormat::read(obj, label)?;
    let shared = item(obj, SHARED_GROUPS);
    let per_frame: &[InMemDicomObject] = obj
        .element_opt(PER_FRAME_GROUPS)
        .ok()
        .flatten()
        .and_then(|e| e.items())
        .unwrap_or(&[]);
    let first_frame = per_frame.first();
    let scaling = rescale(obj, shared, per_frame, label)?;
    let two = |v: Vec<f64>| (v.len() == 2 && v.iter().all(|&s| s > 0.0)).then(|| [v[0], v[1]]);
    let pixel_spacing =
        in_groups(first_frame, shared, PIXEL_MEASURES, PIXEL_SPACING).or_else(|| floats(obj, PIXEL_SPACING));
    let orientation =
        in_groups(first_frame, shared, PLANE_ORIENTATION, IMAGE_ORIENTATION).or_else(|| floats(obj, IMAGE_ORIENTATION));
    let slice_step = in_groups(first_frame, shared, PIXEL_MEASURES, SPACING_BETWEEN_SLICES)
        .or_else(|| floats(obj, SPACING_BETWEEN_SLICES))
        .or_else(|| in_groups(first_frame, shared, PIXEL_MEASURES, SLICE_THICKNESS))
        .or_else(|| floats(obj, SLICE_THICKNESS));
    let frame_places = frame_places(per_frame, shared, orientation.as_deref(), format.dims[2]);
    let transfer_syntax = obj.meta().transfer_syntax().trim_end_matches(['\0', ' ']).to_string();
    let kind = codec::codec(&transfer_syntax).map_err(err)?;
    let dims = format.dims;
    Ok(Slice {
        source,
        rows: dims[1],
        columns: dims[0],
        frames: dims[2],
        bits_allocated: format.bits_allocated,
        bits_stored: format.bits_stored,
        signed: int(obj, PIXEL_REPRESENTATION).unwrap_or(0) == 1,
        scaling,
        pixel_spacing: pixel_spacing.and_then(two),
        position: frame_places
            .first()
            .and_then(|p| p.position)
            .or_else(|| floats(obj, IMAGE_POSITION).and_then(three)),
        orientation: orientation.and_then(six),
        series: text(obj, SERIES_UID).unwrap_or_default(),
        series_number: int(obj, SERIES_NUMBER),
        series_description: text(obj, SERIES_DESCRIPTION).unwrap_or_default(),
        modality: text(obj, MODALITY).map(|m| m.to_ascii_uppercase()).unwrap_or_default(),
        instance: int(obj, INSTANCE_NUMBER).unwrap_or(0),
        temporal: int(obj, TEMPORAL_POSITION),
        native_little_endian: matches!(
            obj.meta().transfer_syntax().trim_end_matches('\0'),
            "1.2.840.10008.1.2" | "1.2.840.10008.1.2.1"
        ),
        slice_step: slice_step.and_then(|v| v.first().copied()).filter(|&s| s > 0.0),
        kind,
        transfer_syntax,
        frame_places,
    })
}

/// A string element, trimmed.
fn text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    obj.element_opt(tag)
        .ok()
        .flatten()
        .and_then(|e| e.to_str().ok().map(|s| s.trim().to_string()))
}

fn three(v: Vec<f64>) -> Option<[f64; 3]> {
    (v.len() == 3).then(|| [v[0], v[1], v[2]])
}

fn six(v: Vec<f64>) -> Option<[f64; 6]> {
    (v.len() == 6).then(|| [v[0], v[1], v[2], v[3], v[4], v[5]])
}

/// The pixel grid and sample layout, checked: one sample per pixel, 8 or 16 bits allocated.
struct PixelFormat {
    /// Columns, rows, frames.
    dims: [u32; 3],
    bits_allocated: u16,
    bits_stored: u16,
}

impl PixelFormat {
    fn read(obj: &DefaultDicomObject, label: &str) -> Result<Self, VolumeError> {
        let err = |problem: String| header_error(label, problem);
        let required = |tag: Tag, name: &str| int(obj, tag).ok_or_else(|| err(format!("no {name} element")));
        let samples = int(obj, SAMPLES_PER_PIXEL).unwrap_or(1);
        if samples != 1 {
            return Err(err(format!(
                "SamplesPerPixel = {samples}: colour DICOM is not supported, only one value per voxel"
            )));
        }
        let rows = required(ROWS, "Rows")?;
        let columns = required(COLUMNS, "Columns")?;
        let frames = int(obj, NUMBER_OF_FRAMES).unwrap_or(1);
        let dims = format::dims_from(label, "Columns/Rows/NumberOfFrames", &[columns, rows, frames])?;
        let bits_allocated = required(BITS_ALLOCATED, "BitsAllocated")?;
        if bits_allocated != 8 && bits_allocated != 16 {
            return Err(err(format!(
                "BitsAllocated = {bits_allocated}: volcast reads 8- and 16-bit DICOM"
            )));
        }
        let bits_stored = int(obj, BITS_STORED).unwrap_or(bits_allocated);
        if !(1..=bits_allocated).contains(&bits_stored) {
            return Err(err(format!(
                "BitsStored = {bits_stored} does not fit BitsAllocated = {bits_allocated}"
            )));
        }
        Ok(Self {
            dims,
            bits_allocated: bits_allocated as u16,
            bits_stored: bits_stored as u16,
        })
    }
}

/// The rescale slope and intercept: the object's, unless its functional groups give them, which must then be the
/// same for every frame.
fn rescale(
    obj: &DefaultDicomObject,
    shared: Option<&InMemDicomObject>,
    per_frame: &[InMemDicomObject],
    label: &str,
) -> Result<Scaling, VolumeError> {
    let slope = floats(obj, RESCALE_SLOPE)
        .and_then(|v| v.first().copied())
        .unwrap_or(1.0);
    let intercept = floats(obj, RESCALE_INTERCEPT)
        .and_then(|v| v.first().copied())
        .unwrap_or(0.0);
    // An enhanced object's rescale lives in PixelValueTransformationSequence; volcast needs one for all frames.
    let rescale = |frame: Option<&InMemDicomObject>| {
        let pick =
            |tag: Tag| in_groups(frame, shared, PIXEL_VALUE_TRANSFORMATION, tag).and_then(|v| v.first().copied());
        (pick(RESCALE_SLOPE), pick(RESCALE_INTERCEPT))
    };
    let (group_slope, group_intercept) = rescale(per_frame.first());
    if per_frame
        .iter()
        .any(|f| rescale(Some(f)) != (group_slope, group_intercept))
    {
        return Err(header_error(
            label,
            "frames have different rescale slope/intercept (PixelValueTransformationSequence); volcast needs one per \
             series"
                .into(),
        ));
    }
    Ok(Scaling {
        slope: group_slope.unwrap_or(slope),
        intercept: group_intercept.unwrap_or(intercept),
    })
}

/// Per-frame positions (and orientations, else the object's `orientation`) place each of the `frames` frames of
/// an enhanced object; all or none are used.
fn frame_places(
    per_frame: &[InMemDicomObject],
    shared: Option<&InMemDicomObject>,
    orientation: Option<&[f64]>,
    frames: u32,
) -> Vec<Placed> {
    if frames <= 1 || per_frame.len() != frames as usize {
        return Vec::new();
    }
    let places: Vec<Placed> = per_frame
        .iter()
        .enumerate()
        .map(|(k, f)| Placed {
            position: in_groups(Some(f), shared, PLANE_POSITION, IMAGE_POSITION).and_then(three),
            orientation: in_groups(Some(f), shared, PLANE_ORIENTATION, IMAGE_ORIENTATION)
                .and_then(six)
                .or_else(|| orientation.map(<[f64]>::to_vec).and_then(six)),
            instance: k as i64,
        })
        .collect();
    if places.iter().all(|p| p.position.is_some()) {
        places
    } else {
        Vec::new()
    }
}
