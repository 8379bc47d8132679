//! What a TIFF says about its voxels' size and which pages are slices: the first page's ImageDescription
//! (ImageJ `spacing=`/`unit=`/hyperstack fields, OME-XML `PhysicalSize*`) and resolution tags, into a
//! [`Layout`].

use super::tiff_error;
use crate::volume::VolumeError;
use ::tiff::decoder::ifd::Value;
use ::tiff::decoder::Decoder;
use ::tiff::tags::Tag;
use std::io::{Read, Seek};

/// What the first page says about the physical size of a voxel.
#[derive(Clone, Debug, Default)]
pub(super) struct Metadata {
    pub(super) description: Option<String>,
    pub(super) x_resolution: Option<f64>,
    pub(super) y_resolution: Option<f64>,
    /// TIFF ResolutionUnit: 1 none, 2 inch, 3 centimetre.
    pub(super) resolution_unit: Option<u16>,
}

/// A resolution as a number: RATIONAL as the TIFF spec says, or whatever numeric type a writer used.
pub(super) fn as_f64(v: Value) -> Option<f64> {
    match v {
        Value::Rational(n, d) if d != 0 => Some(f64::from(n) / f64::from(d)),
        Value::SRational(n, d) if d != 0 => Some(f64::from(n) / f64::from(d)),
        Value::Double(x) => Some(x),
        Value::Float(x) => Some(f64::from(x)),
        Value::Short(x) => Some(f64::from(x)),
        Value::Unsigned(x) => Some(f64::from(x)),
        Value::List(l) => l.into_iter().next().and_then(as_f64),
        _ => None,
    }
}

pub(super) fn metadata<R: Read + Seek>(dec: &mut Decoder<R>, file: &str) -> Result<Metadata, VolumeError> {
    let err = |e| tiff_error(file, e);
    let description = match dec.find_tag(Tag::ImageDescription).map_err(err)? {
        Some(v) => v.into_string().ok(),
        None => None,
    };
    let resolution = |dec: &mut Decoder<R>, tag| -> Result<Option<f64>, VolumeError> {
        Ok(match dec.find_tag(tag).map_err(err)? {
            Some(v) => as_f64(v).filter(|r| r.is_finite() && *r > 0.0),
            None => None,
        })
    };
    Ok(Metadata {
        description,
        x_resolution: resolution(&mut *dec, Tag::XResolution)?,
        y_resolution: resolution(&mut *dec, Tag::YResolution)?,
        resolution_unit: dec.find_tag_unsigned::<u16>(Tag::ResolutionUnit).map_err(err)?,
    })
}

/// Millimetres per unit; `None` for no unit ("pixel", "none", unknown words).
pub(super) fn unit_to_mm(unit: &str) -> Option<f64> {
    let u = unit.trim().trim_matches('"').to_ascii_lowercase();
    match u.as_str() {
        "micron" | "microns" | "um" | "µm" | "\u{3bc}m" | "\\u00b5m" | "micrometer" | "micrometre" => Some(1e-3),
        "nm" | "nanometer" | "nanometre" => Some(1e-6),
        "mm" | "millimeter" | "millimetre" => Some(1.0),
        "cm" | "centimeter" | "centimetre" => Some(10.0),
        "m" | "meter" | "metre" => Some(1000.0),
        "inch" | "in" | "inches" => Some(25.4),
        _ => None,
    }
}

/// `key=value` lines of an ImageJ description.
pub(super) fn imagej_fields(description: &str) -> Option<Vec<(&str, &str)>> {
    if !description.starts_with("ImageJ=") {
        return None;
    }
    Some(
        description
            .lines()
            .filter_map(|l| l.split_once('='))
            .map(|(k, v)| (k.trim(), v.trim()))
            .collect(),
    )
}

/// An attribute of the first `Pixels` element of an OME-XML description.
pub(super) fn ome_pixels(description: &str) -> Option<&str> {
    if !description.contains("<OME") && !description.contains(":OME") {
        return None;
    }
    let start = description.find("<Pixels ").or_else(|| description.find(":Pixels "))?;
    let rest = &description[start..];
    Some(&rest[..rest.find('>').unwrap_or(rest.len())])
}

pub(super) fn xml_attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=");
    let at = element.find(&key)? + key.len();
    let rest = &element[at..];
    let quote = rest.chars().next()?;
    if quote != '"' && quote != '\'' {
        return None;
    }
    let rest = &rest[1..];
    Some(&rest[..rest.find(quote)?])
}

/// Which pages are the z slices and the voxel size in millimetres.
pub(super) struct Layout {
    pub(super) slices: Vec<usize>,
    pub(super) spacing: [f64; 3],
    pub(super) notes: Vec<String>,
    /// The channels of a hyperstack or an OME-TIFF (1 for others), and the one `slices` holds.
    pub(super) channels: usize,
    pub(super) channel: usize,
}

pub(super) fn positive(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0)
}

/// The layout of `pages` pages, the slices those of `channel` (default 0).
pub(super) fn layout(meta: &Metadata, pages: usize, channel: Option<u32>) -> Layout {
    let mut l = Layout {
        slices: (0..pages).collect(),
        spacing: [1.0; 3],
        notes: Vec::new(),
        channels: 1,
        channel: channel.unwrap_or(0) as usize,
    };
    let description = meta.description.as_deref().unwrap_or("");
    let mut imagej = ImageJSpacing::default();
    if let Some(fields) = imagej_fields(description) {
        imagej = l.imagej_pages(&fields, pages);
    }
    if let Some(pixels) = ome_pixels(description) {
        l.ome_pages(pixels, pages);
        if let Some(spacing) = ome_spacing(pixels, &mut l.notes) {
            l.spacing = spacing;
            return l;
        }
    }
    let imagej_file = description.starts_with("ImageJ=");
    l.spacing = resolution_spacing(meta, imagej, imagej_file, &mut l.notes);
    l
}

/// What ImageJ fields say about the spacing: z in the file's unit, and the unit if a `unit=` is given (in mm;
/// None for a word that is no length).
#[derive(Default)]
struct ImageJSpacing {
    z: Option<f64>,
    unit_mm: Option<Option<f64>>,
}

impl Layout {
    /// Picks the slices of an ImageJ hyperstack; returns what the fields say about the spacing.
    fn imagej_pages(&mut self, fields: &[(&str, &str)], pages: usize) -> ImageJSpacing {
        let get = |k: &str| fields.iter().find(|(key, _)| *key == k).map(|(_, v)| *v);
        let count = |k: &str| get(k).and_then(|v| v.parse::<usize>().ok()).filter(|&n| n >= 1);
        let (c, z, t) = (
            count("channels").unwrap_or(1),
            count("slices"),
            count("frames").unwrap_or(1),
        );
        let z = z.unwrap_or_else(|| pages / c.max(1) / t.max(1));
        if c > 1 || t > 1 {
            if c.checked_mul(z).and_then(|n| n.checked_mul(t)) == Some(pages) {
                // ImageJ's page order is channel fastest, then slice, then frame.
                let k = self.channel;
                self.slices = (0..z).map(|i| i * c + k).collect();
                self.channels = c;
                self.notes.push(format!(
                    "ImageJ hyperstack of {c} channel(s) × {z} slices × {t} frame(s): channel {k} of the first frame is \
                     loaded"
                ));
            } else {
                self.notes.push(format!(
                    "ImageJ says {c} channel(s) × {z} slices × {t} frame(s) but the file has {pages} pages: every \
                     page is taken as a slice"
                ));
            }
        }
        ImageJSpacing {
            z: get("spacing").and_then(positive),
            unit_mm: get("unit").map(unit_to_mm),
        }
    }

    /// Picks the slices of an OME-TIFF with several channels or time points, by its DimensionOrder.
    fn ome_pages(&mut self, pixels: &str, pages: usize) {
        let size = |k: &str| {
            xml_attr(pixels, k)
                .and_then(|v| v.parse::<usize>().ok())
                .filter(|&n| n >= 1)
        };
        let (z, c, t) = (
            size("SizeZ").unwrap_or(1),
            size("SizeC").unwrap_or(1),
            size("SizeT").unwrap_or(1),
        );
        let order = xml_attr(pixels, "DimensionOrder").unwrap_or("XYZCT");
        if (c > 1 || t > 1) && z.checked_mul(c).and_then(|n| n.checked_mul(t)) == Some(pages) {
            // Each axis's page stride: the product of the sizes of the axes before it in the order.
            let (mut strides, mut next) = ([0usize; 3], 1);
            for axis in order.chars().skip(2) {
                let (i, n) = match axis {
                    'Z' => (0, z),
                    'C' => (1, c),
                    'T' => (2, t),
                    _ => continue,
                };
                strides[i] = next;
                next *= n;
            }
            let k = self.channel;
            self.slices = (0..z).map(|i| i * strides[0] + k * strides[1]).collect();
            self.channels = c;
            self.notes.push(format!(
                "OME-TIFF of {c} channel(s) × {z} slices × {t} time point(s): channel {k} of the first time point is \
                 loaded"
            ));
        } else if c > 1 || t > 1 {
            self.notes.push(format!(
                "OME-XML says {z} slices × {c} channel(s) × {t} time point(s) but the file has {pages} pages: every \
                 page is taken as a slice"
            ));
        }
    }
}

/// The spacing in mm from OME-XML `PhysicalSize*` (µm unless a unit is given); None without both x and y.
fn ome_spacing(pixels: &str, notes: &mut Vec<String>) -> Option<[f64; 3]> {
    let physical = |k: &str| {
        let v = xml_attr(pixels, k).and_then(positive)?;
        let unit = xml_attr(pixels, &format!("{k}Unit")).unwrap_or("µm");
        unit_to_mm(unit).map(|f| v * f)
    };
    let (x, y, zs) = (
        physical("PhysicalSizeX"),
        physical("PhysicalSizeY"),
        physical("PhysicalSizeZ"),
    );
    let (Some(x), Some(y)) = (x, y) else {
        return None;
    };
    let z = zs.unwrap_or_else(|| {
        notes.push("the OME-XML gives no PhysicalSizeZ: z spacing taken equal to x".into());
        x
    });
    notes.push("spacing from OME-XML PhysicalSize, in mm".into());
    Some([x, y, z])
}

/// The spacing from the resolution tags (pixels per unit) and ImageJ's z spacing, in mm where a unit is known:
/// ImageJ's `unit=`, else the TIFF ResolutionUnit. Without a unit, ImageJ's figures are used as written and
/// anything else is spacing 1.
fn resolution_spacing(meta: &Metadata, imagej: ImageJSpacing, imagej_file: bool, notes: &mut Vec<String>) -> [f64; 3] {
    let unit_mm = match imagej.unit_mm {
        Some(unit_mm) => unit_mm,
        None => match meta.resolution_unit {
            Some(2) => Some(25.4),
            Some(3) => Some(10.0),
            _ => None,
        },
    };
    let in_units = [
        meta.x_resolution.map(|r| 1.0 / r),
        meta.y_resolution.map(|r| 1.0 / r),
        imagej.z,
    ];
    match unit_mm {
        Some(f) => {
            let x = in_units[0].unwrap_or(1.0);
            let y = in_units[1].unwrap_or(x);
            let z = in_units[2].unwrap_or_else(|| {
                notes.push("the file gives no z spacing: taken equal to x".into());
                x
            });
            notes.push("spacing from the TIFF resolution / ImageJ metadata, converted to mm".into());
            [x * f, y * f, z * f]
        }
        None if imagej_file => {
            let x = in_units[0].unwrap_or(1.0);
            let y = in_units[1].unwrap_or(x);
            let z = in_units[2].unwrap_or(x);
            notes.push("ImageJ metadata without a length unit: spacing used as written".into());
            [x, y, z]
        }
        None => [1.0; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_and_imagej_spacing() {
        assert_eq!(unit_to_mm("micron"), Some(1e-3));
        assert_eq!(unit_to_mm("\\u00B5m"), Some(1e-3));
        assert_eq!(unit_to_mm("inch"), Some(25.4));
        assert_eq!(unit_to_mm("pixel"), None);
        let meta = Metadata {
            description: Some("ImageJ=1.11a\nimages=5\nslices=5\nunit=micron\nspacing=2.5\n".into()),
            x_resolution: Some(4.0),
            y_resolution: Some(2.0),
            resolution_unit: Some(1),
        };
        let l = layout(&meta, 5, None);
        assert_eq!(l.slices, [0, 1, 2, 3, 4]);
        let want = [0.25e-3, 0.5e-3, 2.5e-3];
        for (got, want) in l.spacing.iter().zip(want) {
            assert!((got - want).abs() < 1e-12, "{:?}", l.spacing);
        }
        // A hyperstack: the first channel of the first frame.
        let meta = Metadata {
            description: Some("ImageJ=1.11a\nimages=12\nchannels=2\nslices=3\nframes=2\nhyperstack=true\n".into()),
            ..Metadata::default()
        };
        let l = layout(&meta, 12, None);
        assert_eq!(l.slices, [0, 2, 4]);
        assert_eq!((layout(&meta, 12, Some(1)).slices, l.channels), (vec![1, 3, 5], 2));
        assert_eq!(l.spacing, [1.0; 3]);
        // No unit, no ImageJ: spacing 1 whatever the resolution.
        let meta = Metadata {
            x_resolution: Some(72.0),
            y_resolution: Some(72.0),
            ..Metadata::default()
        };
        assert_eq!(layout(&meta, 3, None).spacing, [1.0; 3]);
        // Inches: 72 dpi, z taken equal to x.
        let meta = Metadata {
            resolution_unit: Some(2),
            ..meta
        };
        let s = layout(&meta, 3, None).spacing;
        assert!((s[0] - 25.4 / 72.0).abs() < 1e-12 && s[2] == s[0], "{s:?}");
    }

    #[test]
    fn ome_xml() {
        let xml = r#"<?xml version="1.0"?><OME xmlns="x"><Image ID="Image:0"><Pixels DimensionOrder="XYCZT" ID="Pixels:0" SizeC="2" SizeT="1" SizeX="9" SizeY="7" SizeZ="5" Type="uint16" PhysicalSizeX="0.5" PhysicalSizeY="0.25" PhysicalSizeZ="2" PhysicalSizeZUnit="mm"><Channel/></Pixels></Image></OME>"#;
        let meta = Metadata {
            description: Some(xml.into()),
            ..Metadata::default()
        };
        let l = layout(&meta, 10, None);
        assert_eq!(l.slices, [0, 2, 4, 6, 8]);
        assert_eq!(layout(&meta, 10, Some(1)).slices, [1, 3, 5, 7, 9]);
        assert_eq!(l.spacing, [0.5e-3, 0.25e-3, 2.0]);
    }
}
