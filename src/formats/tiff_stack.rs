//! TIFF stacks: a multi-page TIFF (one page per z slice) or a folder of single-page TIFFs, grey samples only.
//! Decoding is the `tiff` crate's (strips or tiles; none, LZW, Deflate, PackBits, JPEG); volcast walks the pages
//! itself first and checks every claim against the file before the crate allocates anything.
//!
//! Spacing: ImageJ metadata (`spacing=` for z, `unit=`) with XResolution/YResolution (pixels per unit) for x/y,
//! or OME-XML `PhysicalSizeX/Y/Z`; converted to millimetres. No orientation: the affine is the spacing alone.

use super::decode::{try_vec, DecodeError, Progress};
use super::format::{self, header_error};
use crate::volume::{check_dims, ChannelInfo, Volume, VolumeError, VoxelData, VoxelType, MAX_DIM};
use ::tiff::decoder::ifd::Value;
use ::tiff::decoder::{Decoder, DecodingResult, Limits};
use ::tiff::tags::Tag;
use ::tiff::{ColorType, TiffError};
use std::cmp::Ordering;

mod meta;
use meta::{layout, metadata, Layout, Metadata};
use std::fs::File;
use std::io::{BufReader, Cursor, ErrorKind, Read, Seek};
use std::path::{Path, PathBuf};

/// Most pages walked in one file: an ImageJ hyperstack may hold channels × slices × frames pages, but a file
/// claiming more than this is refused before more directories are read.
const MAX_PAGES: usize = 4 * MAX_DIM as usize;

/// Most files looked at in a folder (as for DICOM series).
pub(crate) const MAX_FILES: usize = 20_000;

/// Largest single TIFF value (an offset table, an OME-XML description) read: the crate's default is 1 MiB.
const MAX_IFD_VALUE: usize = 16 << 20;

pub(crate) fn is_tiff(prefix: &[u8]) -> bool {
    prefix.starts_with(b"II*\0")
        || prefix.starts_with(b"MM\0*")
        || prefix.starts_with(b"II+\0")
        || prefix.starts_with(b"MM\0+")
}

/// One page as its directory declares it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Page {
    width: u32,
    height: u32,
    voxel_type: VoxelType,
}

fn tiff_error(file: &str, e: TiffError) -> VolumeError {
    let problem = match e {
        TiffError::IoError(io) if io.kind() == ErrorKind::UnexpectedEof => {
            format!("the TIFF data end early (truncated file?): {io}")
        }
        TiffError::LimitsExceeded => "a TIFF value or page is larger than the file can hold".to_string(),
        other => format!("not a readable TIFF: {other}"),
    };
    header_error(file, problem)
}

/// How far each compression can expand; a page claiming more than its compressed bytes can give is refused before
/// its buffer is allocated.
fn max_expansion(compression: u16) -> u64 {
    match compression {
        1 => 1,
        // PackBits: a 2-byte run gives at most 128 bytes.
        32773 => 64,
        // Deflate (8, 32946): ~1032:1.
        8 | 32946 => 1032,
        // LZW: one code of at least 9 bits gives at most 4096 bytes; others (JPEG, ...) get the same loose bound.
        _ => 4096,
    }
}

/// Reads the current page's directory and checks it: grey single-sample type, size within the limits, every
/// strip or tile inside the file, compressed bytes enough for the declared size. Returns the page and how many
/// strips/tiles it has.
fn page_info<R: Read + Seek>(
    dec: &mut Decoder<R>,
    file: &str,
    index: usize,
    len: u64,
) -> Result<(Page, u64), VolumeError> {
    let page_name = format!("page {}", index + 1);
    let (width, height) = page_size(dec, file, &page_name)?;
    let voxel_type = page_voxel_type(dec, file, index)?;
    let compression = dec
        .find_tag_unsigned::<u16>(Tag::Compression)
        .map_err(|e| tiff_error(file, e))?
        .unwrap_or(1);
    let (compressed, pieces) = page_data_bytes(dec, file, &page_name, len)?;
    let needed = u64::from(width) * u64::from(height) * voxel_type.size() as u64;
    if needed
        > compressed
            .saturating_mul(max_expansion(compression))
            .saturating_add(1024)
    {
        return Err(header_error(
            file,
            format!(
                "{page_name} claims {width}x{height} {voxel_type} ({needed} bytes) but holds only {compressed} bytes \
                 of image data (compression {compression}); the sizes are wrong or the file is truncated"
            ),
        ));
    }
    Ok((
        Page {
            width,
            height,
            voxel_type,
        },
        pieces,
    ))
}

/// The page's width and height, each 1 to MAX_DIM.
fn page_size<R: Read + Seek>(dec: &mut Decoder<R>, file: &str, page_name: &str) -> Result<(u32, u32), VolumeError> {
    let (width, height) = dec.dimensions().map_err(|e| tiff_error(file, e))?;
    check_dims([width.max(1), height.max(1), 1]).map_err(|_| {
        header_error(
            file,
            format!("{page_name} is {width}x{height}, beyond the limit of {MAX_DIM} per axis"),
        )
    })?;
    if width == 0 || height == 0 {
        return Err(header_error(file, format!("{page_name} is {width}x{height}")));
    }
    Ok((width, height))
}

/// The page's voxel type: grey, one sample per pixel, of a bit depth and sample format volcast reads.
fn page_voxel_type<R: Read + Seek>(dec: &mut Decoder<R>, file: &str, index: usize) -> Result<VoxelType, VolumeError> {
    let err = |e| tiff_error(file, e);
    let bits = match dec.colortype().map_err(err)? {
        ColorType::Gray(bits) => bits,
        other => {
            let what = match other {
                ColorType::RGB(_) => "RGB colour".to_string(),
                ColorType::RGBA(_) => "RGBA colour".to_string(),
                ColorType::Palette(_) => "palette (indexed) colour".to_string(),
                ColorType::GrayA(_) => "grey + alpha (2 samples per pixel)".to_string(),
                ColorType::CMYK(_) | ColorType::CMYKA(_) => "CMYK colour".to_string(),
                ColorType::YCbCr(_) => "YCbCr colour".to_string(),
                ColorType::Multiband { num_samples, .. } => format!("{num_samples} samples per pixel"),
                other => format!("{other:?}"),
            };
            return Err(header_error(
                file,
                format!(
                    "page {} is {what}; volcast reads grey TIFFs (one sample per pixel) only: split the channels \
                     first",
                    index + 1
                ),
            ));
        }
    };
    let sample_format = dec
        .find_tag_unsigned_vec::<u16>(Tag::SampleFormat)
        .map_err(err)?
        .and_then(|v| v.first().copied())
        .unwrap_or(1);
    Ok(match (bits, sample_format) {
        (8, 1) => VoxelType::U8,
        (8, 2) => VoxelType::I8,
        (16, 1) => VoxelType::U16,
        (16, 2) => VoxelType::I16,
        (32, 1) => VoxelType::U32,
        (32, 2) => VoxelType::I32,
        (32, 3) => VoxelType::F32,
        (64, 3) => VoxelType::F64,
        _ => {
            let kind = match sample_format {
                1 => "unsigned integer",
                2 => "signed integer",
                3 => "floating-point",
                _ => "unknown-format",
            };
            return Err(VolumeError::UnsupportedType {
                file: file.to_string(),
                format: "TIFF",
                given: format!("{bits}-bit {kind} (page {})", index + 1),
            });
        }
    })
}

/// The page's compressed bytes, every strip or tile checked to lie inside the file of `len` bytes, and how many
/// strips or tiles there are.
fn page_data_bytes<R: Read + Seek>(
    dec: &mut Decoder<R>,
    file: &str,
    page_name: &str,
    len: u64,
) -> Result<(u64, u64), VolumeError> {
    let err = |e| tiff_error(file, e);
    let tiled = dec.find_tag(Tag::TileWidth).map_err(err)?.is_some();
    let (offsets_tag, counts_tag) = if tiled {
        (Tag::TileOffsets, Tag::TileByteCounts)
    } else {
        (Tag::StripOffsets, Tag::StripByteCounts)
    };
    let offsets = dec
        .find_tag_unsigned_vec::<u64>(offsets_tag)
        .map_err(err)?
        .unwrap_or_default();
    let counts = dec
        .find_tag_unsigned_vec::<u64>(counts_tag)
        .map_err(err)?
        .unwrap_or_default();
    if offsets.is_empty() || offsets.len() != counts.len() {
        return Err(header_error(
            file,
            format!(
                "{page_name} has {} strip/tile offsets and {} byte counts",
                offsets.len(),
                counts.len()
            ),
        ));
    }
    let mut compressed = 0u64;
    for (&o, &c) in offsets.iter().zip(&counts) {
        if o.checked_add(c).is_none_or(|end| end > len) {
            return Err(header_error(
                file,
                format!(
                    "{page_name} has a strip/tile of {c} bytes at offset {o}, beyond the end of the file ({len} \
                     bytes; truncated?)"
                ),
            ));
        }
        compressed += c;
    }
    Ok((compressed, offsets.len() as u64))
}

fn limits(page_bytes: usize) -> Limits {
    let mut limits = Limits::default();
    limits.decoding_buffer_size = page_bytes;
    limits.intermediate_buffer_size = limits.intermediate_buffer_size.max(page_bytes);
    limits.ifd_value_size = MAX_IFD_VALUE;
    limits
}

/// Every page's directory in one file, checked; the caller decodes the ones it keeps. `len` is the file size.
fn walk_pages<R: Read + Seek>(
    reader: R,
    file: &str,
    len: u64,
    single: bool,
) -> Result<(Decoder<R>, Vec<Page>, Metadata), VolumeError> {
    let err = |e| tiff_error(file, e);
    // The largest page volcast accepts; each page is checked against its own declared size before decoding.
    // The tiff crate also sizes each directory value's list by `decoding_buffer_size` (a count of values, each a
    // `Value`, before reading them), so while only directories are read that limit is what the file can hold: at
    // most one value per byte. (Found by the tiff fuzz target: a tag claiming 89 M values reserved 2 GiB.)
    let most = (MAX_DIM as usize).pow(2) * 8;
    let listable = usize::try_from(len)
        .unwrap_or(usize::MAX)
        .saturating_mul(std::mem::size_of::<Value>());
    let mut dec = Decoder::new(reader)
        .map_err(err)?
        .with_limits(limits(most.min(listable)));
    let meta = metadata(&mut dec, file)?;
    let mut pages = Vec::new();
    let mut chunks = 0u64;
    loop {
        let (page, n) = page_info(&mut dec, file, pages.len(), len)?;
        pages.push(page);
        // Each strip or tile takes at least 4 bytes of offset table in its own directory; more than the file can
        // hold means directories share tables, a loop in disguise.
        chunks += n;
        if chunks > len / 4 + pages.len() as u64 {
            return Err(header_error(
                file,
                format!(
                    "{} pages declare {chunks} strips/tiles, more than a {len}-byte file can hold",
                    pages.len()
                ),
            ));
        }
        if !dec.more_images() {
            break;
        }
        if single {
            return Err(header_error(
                file,
                "has more than one page; in a folder stack every file must be one slice".into(),
            ));
        }
        if pages.len() >= MAX_PAGES {
            return Err(header_error(file, format!("has more than {MAX_PAGES} pages")));
        }
        dec.next_image().map_err(err)?;
    }
    Ok((dec, pages, meta))
}

/// Appends one decoded page to the volume's buffer in the representation `voxel_type` maps to.
fn append(file: &str, decoded: DecodingResult, out: &mut VoxelData, expected: usize) -> Result<(), VolumeError> {
    let got = match &decoded {
        DecodingResult::U8(v) => v.len(),
        DecodingResult::I8(v) => v.len(),
        DecodingResult::U16(v) => v.len(),
        DecodingResult::I16(v) => v.len(),
        DecodingResult::U32(v) => v.len(),
        DecodingResult::I32(v) => v.len(),
        DecodingResult::F32(v) => v.len(),
        DecodingResult::F64(v) => v.len(),
        _ => 0,
    };
    if got < expected {
        return Err(header_error(
            file,
            format!("a page decoded to {got} samples, not the {expected} it declares"),
        ));
    }
    match (decoded, out) {
        (DecodingResult::U8(v), VoxelData::U8(o)) => o.extend_from_slice(&v[..expected]),
        (DecodingResult::I8(v), VoxelData::U8(o)) => o.extend(v[..expected].iter().map(|&x| x as u8 ^ 0x80)),
        (DecodingResult::U16(v), VoxelData::U16(o)) => o.extend_from_slice(&v[..expected]),
        (DecodingResult::I16(v), VoxelData::U16(o)) => o.extend(v[..expected].iter().map(|&x| x as u16 ^ 0x8000)),
        (DecodingResult::U32(v), VoxelData::F32(o)) => o.extend(v[..expected].iter().map(|&x| x as f32)),
        (DecodingResult::I32(v), VoxelData::F32(o)) => o.extend(v[..expected].iter().map(|&x| x as f32)),
        (DecodingResult::F32(v), VoxelData::F32(o)) => o.extend_from_slice(&v[..expected]),
        (DecodingResult::F64(v), VoxelData::F32(o)) => o.extend(v[..expected].iter().map(|&x| x as f32)),
        _ => {
            return Err(header_error(
                file,
                "a page decoded to a different sample type than its directory declares".into(),
            ))
        }
    }
    Ok(())
}

fn empty_data(voxel_type: VoxelType, count: usize, dims: [u32; 3]) -> Result<VoxelData, VolumeError> {
    let oom = |_: DecodeError| VolumeError::OutOfMemory {
        dims,
        bytes: count as u64 * voxel_type.size() as u64,
    };
    Ok(match voxel_type {
        VoxelType::U8 | VoxelType::I8 => VoxelData::U8(try_vec(count).map_err(oom)?),
        VoxelType::U16 | VoxelType::I16 => VoxelData::U16(try_vec(count).map_err(oom)?),
        _ => VoxelData::F32(try_vec(count).map_err(oom)?),
    })
}

/// All kept pages must match the first.
fn check_same(file: &str, first: &Page, page: &Page, which: &str) -> Result<(), VolumeError> {
    if page != first {
        return Err(header_error(
            file,
            format!(
                "{which} is {}x{} {} but the first slice is {}x{} {}; all slices of a stack must have the same \
                 size and type",
                page.width, page.height, page.voxel_type, first.width, first.height, first.voxel_type
            ),
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------------
// Loading.

fn finish(
    name: String,
    file: &str,
    page: Page,
    data: VoxelData,
    depth: u32,
    layout: Layout,
) -> Result<Volume, VolumeError> {
    let dims = [page.width, page.height, depth];
    let spacing = layout.spacing.map(|s| s as f32);
    let mut v = Volume::new(name, dims, spacing, page.voxel_type, data).map_err(|e| match e {
        VolumeError::BadSpacing { .. } => header_error(file, format!("{e} (from the TIFF metadata)")),
        e => e,
    })?;
    v.format = "TIFF".into();
    v.notes = layout.notes;
    v.channels = ChannelInfo::numbered(layout.channels, layout.channel);
    Ok(v)
}

/// Refuses a channel the layout does not have, naming the file.
fn check_channel(file: &str, layout: &Layout) -> Result<(), VolumeError> {
    if layout.channel < layout.channels {
        return Ok(());
    }
    Err(header_error(
        file,
        format!(
            "channel {} does not exist: the file has {} channel(s), 0 to {}",
            layout.channel,
            layout.channels,
            layout.channels - 1
        ),
    ))
}

/// The kept pages' voxel count, checked against the limits before anything is allocated.
fn plan(file: &str, pages: &[Page], slices: &[usize]) -> Result<(Page, [u32; 3], usize), VolumeError> {
    if slices.is_empty() {
        return Err(header_error(file, "holds no slices".into()));
    }
    let first = pages[slices[0]];
    for (z, &i) in slices.iter().enumerate() {
        check_same(file, &first, &pages[i], &format!("slice {} (page {})", z + 1, i + 1))?;
    }
    let depth = u32::try_from(slices.len()).unwrap_or(u32::MAX);
    let dims = [first.width, first.height, depth];
    let count = check_dims(dims).map_err(|e| header_error(file, e.to_string()))?;
    let count = usize::try_from(count).map_err(|_| VolumeError::TooLarge {
        dims,
        voxel_type: first.voxel_type,
        bytes: count * first.voxel_type.size() as u64,
    })?;
    Ok((first, dims, count))
}

fn load_reader<R: Read + Seek>(
    reader: R,
    len: u64,
    file: &str,
    name: String,
    (channel, progress): (Option<u32>, &mut Progress),
) -> Result<Volume, VolumeError> {
    let (mut dec, pages, meta) = walk_pages(reader, file, len, false)?;
    let layout = layout(&meta, pages.len(), channel);
    check_channel(file, &layout)?;
    let (first, dims, count) = plan(file, &pages, &layout.slices)?;
    let slice = first.width as usize * first.height as usize;
    let mut data = empty_data(first.voxel_type, count, dims)?;
    let err = |e| tiff_error(file, e);
    dec = dec.with_limits(limits(slice * first.voxel_type.size()));
    for (z, &i) in layout.slices.iter().enumerate() {
        dec.seek_to_image(i).map_err(err)?;
        let decoded = dec.read_image().map_err(err)?;
        append(file, decoded, &mut data, slice)?;
        progress.report((z + 1) as f64 / layout.slices.len() as f64);
    }
    finish(name, file, first, data, dims[2], layout)
}

/// Loads a TIFF stack from memory (the fuzz target's entry).
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    load_reader(
        Cursor::new(bytes),
        bytes.len() as u64,
        "tiff",
        "tiff".into(),
        (None, &mut Progress::none()),
    )
}

fn open_file(path: &Path) -> Result<(BufReader<File>, u64), VolumeError> {
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let f = File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    Ok((BufReader::new(f), len))
}

/// Compares names the way people number files: runs of digits by value, so `z2` < `z10`.
pub(crate) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a_chars, mut b_chars) = (a.chars().peekable(), b.chars().peekable());
    loop {
        match (a_chars.peek().copied(), b_chars.peek().copied()) {
            (None, None) => return a.cmp(b),
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let take = |it: &mut std::iter::Peekable<std::str::Chars>| {
                    let mut s = String::new();
                    while let Some(c) = it.peek().copied().filter(char::is_ascii_digit) {
                        s.push(c);
                        it.next();
                    }
                    s
                };
                let (da, db) = (take(&mut a_chars), take(&mut b_chars));
                let (ta, tb) = (da.trim_start_matches('0'), db.trim_start_matches('0'));
                let ord = ta.len().cmp(&tb.len()).then_with(|| ta.cmp(tb));
                if ord != Ordering::Equal {
                    return ord;
                }
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(&y);
                }
                a_chars.next();
                b_chars.next();
            }
        }
    }
}

/// The TIFF files of a folder (by magic bytes; hidden files and others skipped), in natural order of their names.
pub(crate) fn folder_files(path: &Path) -> Result<Vec<PathBuf>, VolumeError> {
    let label = format::file_label(path);
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    let mut seen = 0usize;
    for entry in std::fs::read_dir(path).map_err(io)? {
        let p = entry.map_err(io)?.path();
        let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if hidden || !p.is_file() {
            continue;
        }
        seen += 1;
        if seen > MAX_FILES {
            return Err(header_error(
                &label,
                format!("more than {MAX_FILES} files in the folder"),
            ));
        }
        if format::read_prefix(&p, 4).is_ok_and(|prefix| is_tiff(&prefix)) {
            files.push(p);
        }
    }
    files.sort_by(|a, b| natural_cmp(&format::file_label(a), &format::file_label(b)));
    Ok(files)
}

/// Loads a multi-page TIFF file (`channel` of a hyperstack or an OME-TIFF, default 0), or a folder of single-page
/// TIFFs (one slice each, in natural name order).
pub(crate) fn load(path: &Path, channel: Option<u32>, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let label = format::file_label(path);
    let name = format::volume_name(path);
    if !path.is_dir() {
        let (reader, len) = open_file(path)?;
        return load_reader(reader, len, &label, name, (channel, progress));
    }
    let files = folder_files(path)?;
    if files.is_empty() {
        return Err(header_error(&label, "the folder holds no TIFF files".into()));
    }
    // Pass 1: every file's directory, so the whole volume is checked before it is allocated.
    let mut pages = Vec::with_capacity(files.len());
    let mut meta = Metadata::default();
    for (i, f) in files.iter().enumerate() {
        let f_label = format::file_label(f);
        let (reader, len) = open_file(f)?;
        let (_, p, m) = walk_pages(reader, &f_label, len, true)?;
        if i == 0 {
            meta = m;
        }
        pages.push(p[0]);
    }
    for (f, page) in files.iter().zip(&pages) {
        check_same(&label, &pages[0], page, &format::file_label(f))?;
    }
    let mut layout = layout(&meta, 1, channel);
    check_channel(&label, &layout)?;
    layout.slices = (0..files.len()).collect();
    let (first, dims, count) = plan(&label, &pages, &layout.slices)?;
    let slice = first.width as usize * first.height as usize;
    let mut data = empty_data(first.voxel_type, count, dims)?;
    for (z, f) in files.iter().enumerate() {
        let f_label = format::file_label(f);
        let err = |e| tiff_error(&f_label, e);
        let (reader, _) = open_file(f)?;
        let mut dec = Decoder::new(reader)
            .map_err(err)?
            .with_limits(limits(slice * first.voxel_type.size()));
        let decoded = dec.read_image().map_err(err)?;
        append(&f_label, decoded, &mut data, slice)?;
        progress.report((z + 1) as f64 / files.len() as f64);
    }
    let mut v = finish(name, &label, first, data, dims[2], layout)?;
    v.notes.insert(
        0,
        format!("{} TIFF slices from the folder, in natural name order", files.len()),
    );
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order() {
        let mut names = vec!["z10.tif", "z2.tif", "z1.tif", "z01.tif", "a.tif", "z12.tif", "Z3.tif"];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            ["Z3.tif", "a.tif", "z01.tif", "z1.tif", "z2.tif", "z10.tif", "z12.tif"]
        );
        assert_eq!(natural_cmp("img2", "img10"), Ordering::Less);
        assert_eq!(natural_cmp("s_0099", "s_0100"), Ordering::Less);
    }
}
