//! Volumes larger than memory or the device, shown within budgets (`pyramid::budget`): the level of the resolution
//! pyramid that fits is read, never the full resolution first. A file whose voxels lie in place on disk (raw,
//! uncompressed NRRD, NIfTI, Analyze and MetaImage) is read level by level from the file with positioned reads, on
//! every core ([`read`]); an OME-Zarr store gives its own level; any other file is read whole and then reduced.
//! docs/large-volumes.md states the rules and what is still to come (bricks behind a page table).

pub mod cache;
pub mod finer;
pub mod level0;
pub mod preview;
pub mod read;

use crate::convert::source::Source;
use crate::formats;
use crate::formats::in_place::{in_place, InPlace};
use crate::formats::OpenOptions;
use crate::pyramid::budget::{self, Budgets, Shape};
use crate::pyramid::geometry::level_dims;
use crate::volume::{self, Volume, VolumeError, VoxelType};
use cache::{Lookup, PyramidCache};
use std::path::Path;

/// Opens `path` as [`formats::open`] does, within `budgets`: the finest level that fits them, with a note saying
/// why when that is not full resolution. A volume that fits no budget (not even one voxel) is refused before it is
/// read; `--no-downsample` (`opts.no_downsample`) refuses any level but full resolution. With `cache`, a level of a
/// file read in place is read from the pyramid cache where it is there, and kept there where it is not.
pub fn open(
    path: &Path,
    opts: &OpenOptions,
    budgets: Budgets,
    cache: Option<&PyramidCache>,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    let opened = open_deferred(path, opts, budgets, cache, progress)?;
    Ok(match opened.keep {
        Some(keep) => keep.write(opened.volume),
        None => opened.volume,
    })
}

/// What [`open_deferred`] opened, and the cache write it left to the caller.
pub struct Opened {
    pub volume: Volume,
    pub keep: Option<Keep>,
}

/// A level read from its file, to keep in the pyramid cache.
pub struct Keep {
    cache: PyramidCache,
    place: InPlace,
    level: u32,
}

impl Keep {
    /// Writes `v` into the cache and gives it back, with a note if the cache could not be written.
    pub fn write(self, v: Volume) -> Volume {
        let (mut v, kept) = self.cache.store(&self.place, self.level, v);
        if let Err(e) = kept {
            v.notes.push(format!("the pyramid cache was not written: {e}"));
        }
        v
    }
}

/// [`open`], leaving the cache write to the caller (the viewer shows the volume first). One slice of a DICOM
/// series opens its whole series, that slice's series chosen unless `opts.series` names one
/// ([`series_of_file`](crate::formats::dicom::series_of_file)).
pub fn open_deferred(
    path: &Path,
    opts: &OpenOptions,
    budgets: Budgets,
    cache: Option<&PyramidCache>,
    progress: &mut dyn FnMut(f32),
) -> Result<Opened, VolumeError> {
    match crate::formats::dicom::series_of_file(path) {
        Some((folder, uid)) => {
            let opts = OpenOptions {
                series: opts.series.clone().or(Some(uid)),
                ..opts.clone()
            };
            open_path(&folder, &opts, budgets, cache, progress)
        }
        None => open_path(path, opts, budgets, cache, progress),
    }
}

fn open_path(
    path: &Path,
    opts: &OpenOptions,
    budgets: Budgets,
    cache: Option<&PyramidCache>,
    progress: &mut dyn FnMut(f32),
) -> Result<Opened, VolumeError> {
    let named = |problem: String| VolumeError::Header {
        file: path.display().to_string(),
        problem,
    };
    // A file in place is read level by level with positioned reads; a compressed one is decoded once, front to
    // back, into the level (never held whole). Either only where the level is not full resolution: level 0 is read
    // by the format's own loader.
    let place = match in_place(path, opts)? {
        Some(p) => Some(p),
        None => match crate::formats::in_place::compressed(path, opts)? {
            Some(p) => Some(p),
            None => dicom_by_slices(path, opts, &budgets)?,
        },
    };
    if let Some(place) = place {
        let shape = Shape {
            dims: place.dims,
            voxel_type: place.voxel_type,
            steps: place.timesteps,
        };
        let level = budget::choose(&shape, &budgets).map_err(named)?;
        if level.level > 0 {
            refuse_if_asked(opts, shape.dims, &level).map_err(named)?;
            return read_place(place, &level, &budgets, opts, cache, progress);
        }
        if place.blocks.is_some() {
            // Appended `.vti` data are decoded by range at full resolution too: the file is never held beside its
            // voxels (the format's reader holds both). Level 0 is not cached: it is the file.
            return read_place(place, &level, &budgets, opts, None, progress);
        }
    }
    refuse_whole_over_budget(path, &budgets).map_err(named)?;
    let v = formats::open_within(path, opts, Some(&budgets), progress)?;
    let volume = fit(v, &budgets, opts.no_downsample).map_err(|e| match e {
        VolumeError::Header { problem, .. } => named(problem),
        e => e,
    })?;
    Ok(Opened {
        volume: with_store_finer(volume, path, opts),
        keep: None,
    })
}

/// A folder of DICOM slices that may not fit `budgets` at full resolution (its first image times its files, an
/// upper bound read from one header): the series read slice by slice (`dicom::slices`), so that its level is made
/// without holding it. One multi-frame DICOM file that does not fit them is read frame by frame the same way.
/// `None` for any other file, and for a series or file that fits: the loader reads it whole.
fn dicom_by_slices(path: &Path, opts: &OpenOptions, budgets: &Budgets) -> Result<Option<InPlace>, VolumeError> {
    use crate::formats::dicom::slices;
    use crate::formats::in_place::{frames_in_place, series_in_place};
    let fits = |dims: [u32; 3], voxel_type: VoxelType| {
        let shape = Shape {
            dims,
            voxel_type,
            steps: 1,
        };
        budget::choose(&shape, budgets).is_ok_and(|l| l.level == 0)
    };
    if !path.is_dir() {
        return frames_in_place(path, &fits);
    }
    match slices::claimed_bound(path) {
        Some((dims, voxel_type)) if !fits(dims, voxel_type) => series_in_place(path, opts.series.as_deref()),
        _ => Ok(None),
    }
}

/// `v` as read from `place`: its arrays, and a DICOM series' modality and the folder's series, as its loader says.
fn described(mut v: Volume, place: &InPlace) -> Volume {
    v.format = place.format.to_string();
    v.arrays = place.arrays.clone();
    v.modality = place.modality.clone();
    v.channels = place.channels.clone();
    if let Some(s) = &place.slices {
        v.series = s.series.clone();
    }
    v
}

/// Level `level` of the file `place` describes: from the pyramid cache where `cache` holds it, else read from the
/// file within the host budget of `budgets` (with the cache write left to the caller).
fn read_place(
    place: InPlace,
    level: &budget::Level,
    budgets: &Budgets,
    opts: &OpenOptions,
    cache: Option<&PyramidCache>,
    progress: &mut dyn FnMut(f32),
) -> Result<Opened, VolumeError> {
    let mut notes = place.notes.clone();
    if level.level > 0 {
        notes.push(budget::level_note(place.dims, level));
    }
    let miss_note = match cache.map(|c| c.lookup(&place, level.level)) {
        Some(Lookup::Hit(mut v)) => {
            notes.append(&mut v.notes);
            let kept = cache.and_then(|c| c.kept_level0(&place, level.level));
            if level0::applies(&place, level.level) {
                notes.push(match &kept {
                    Some(_) => "its finer levels are read from its level 0 kept in the pyramid cache".into(),
                    None => format!("{NOT_SHOWN}: its level 0 was not kept when this cache entry was made (`volcast cache --clear`, then open it again)"),
                });
            }
            v.notes = notes;
            let kept = kept.map(|p| level0::in_place(&place, &p));
            return Ok(Opened {
                volume: with_finer(
                    after_level(described(*v, &place), opts),
                    &place,
                    kept.as_ref(),
                    level.level,
                )?,
                keep: None,
            });
        }
        Some(Lookup::Miss { note }) => note,
        None => None,
    };
    notes.extend(miss_note);
    if place.inflate.is_some() {
        notes.push("its compressed voxels were decoded once, as a stream, into that level".into());
    }
    if place.blocks.is_some() {
        notes.push(match level.level {
            0 => "its encoded voxels were decoded once, on every core, without holding the file".into(),
            _ => "its encoded voxels were decoded once, on every core, into that level".into(),
        });
    }
    if let Some(series) = &place.slices {
        notes.push(if series.is_one_file() {
            "its frames were decoded one at a time from where they lie in the file, on every core, into that level"
                .into()
        } else {
            "its slices were decoded one file at a time, on every core, into that level".into()
        });
    }
    let source = Source::in_place(place.clone())?;
    let level0 = start_level0(&place, level.level, cache, &mut notes);
    let mut v = read::read_level_keeping(&source, level.level, budgets.host, notes, level0.as_ref(), progress)?;
    let kept = match level0.map(level0::Level0::finish) {
        Some(Ok(path)) => {
            v.notes.push(format!(
                "its level 0 ({}) was kept in the pyramid cache ({}): its finer levels are read from there as the view \
                 needs them",
                budget::show(level0::kept_bytes(&place)),
                path.display()
            ));
            Some(level0::in_place(&place, &path))
        }
        Some(Err(e)) => {
            v.notes.push(format!(
                "{NOT_SHOWN}: its level 0 was not kept in the pyramid cache ({e})"
            ));
            None
        }
        None => None,
    };
    let v = described(v, &place);
    let volume = with_finer(after_level(v, opts), &place, kept.as_ref(), level.level)?;
    let keep = cache.map(|c| Keep {
        cache: c.clone(),
        place,
        level: level.level,
    });
    Ok(Opened { volume, keep })
}

/// How a note that a decoded file's finer levels are not shown begins.
const NOT_SHOWN: &str = "its finer levels will not be shown";

/// Where `place` is a file decoded into level `level` (`level0::applies`), starts keeping its level 0 in `cache` as
/// it is decoded, so that its finer levels can be read by box; else, or where the cache cannot take it, `None` and a
/// note saying why.
fn start_level0(
    place: &InPlace,
    level: u32,
    cache: Option<&PyramidCache>,
    notes: &mut Vec<String>,
) -> Option<level0::Level0> {
    if !level0::applies(place, level) {
        return None;
    }
    let Some(cache) = cache else {
        notes.push(format!(
            "{NOT_SHOWN}: a decoded file's level 0 is kept in the pyramid cache to read them, and the cache is off \
             (--no-cache)"
        ));
        return None;
    };
    match cache.begin_level0(place, level) {
        Ok(l0) => Some(l0),
        Err(e) => {
            notes.push(format!(
                "{NOT_SHOWN}: its level 0 is not kept in the pyramid cache ({e})"
            ));
            None
        }
    }
}

/// `v`, level `level` of `place`, with its finer levels in the file ([`finer::Finer`]) where they can be read by
/// box, or in `kept`, a decoded file's level 0 kept in the pyramid cache (`level0::in_place`), and `v` is that level
/// as read (not reduced further by `--max-dim`). Either way `v` stands in for the file's own voxels (rule 6).
fn with_finer(v: Volume, place: &InPlace, kept: Option<&InPlace>, level: u32) -> Result<Volume, VolumeError> {
    let mut v = v.stand_in_for(&place.geometry, 1.0);
    if v.dims == level_dims(place.dims, level) {
        let finer = match kept {
            Some(k) => finer::Finer::of_kept(k, level)?,
            None => finer::Finer::of(place, level)?,
        };
        v.finer = finer.map(|f| std::sync::Arc::new(f) as std::sync::Arc<dyn volume::FinerLevels>);
    }
    Ok(v)
}

/// `v`, a coarser level of the OME-Zarr store at `path`, with the store's level 0 behind it ([`finer::Finer`]) where
/// the pyramid rule makes `v` from it, so that a streamed pool reads finer bricks from the store; a note where the
/// store could not be read again.
fn with_store_finer(mut v: Volume, path: &Path, opts: &OpenOptions) -> Volume {
    // `--max-dim` asks for no more than the level chosen.
    if v.format != "OME-Zarr" || v.finer.is_some() || opts.max_dim.is_some() {
        return v;
    }
    match crate::formats::zarr::boxes::finer_of(path, &v, opts.channel) {
        Ok(Some((boxes, held))) => {
            v.finer = Some(std::sync::Arc::new(finer::Finer::of_zarr(boxes, held)));
        }
        Ok(None) => {}
        Err(e) => v.notes.push(format!("its finer levels will not be shown: {e}")),
    }
    v
}

/// A preview of `path` when it is a file read in place, a DICOM series or a multi-frame DICOM file that is large at
/// the level `budgets` give it: from the pyramid cache's coarser levels where `cache` holds that level, else strided
/// from the file ([`preview::preview`]); `None` for everything else.
pub fn preview_within(
    path: &Path,
    opts: &OpenOptions,
    budgets: Budgets,
    cache: Option<&PyramidCache>,
) -> Result<Option<Volume>, VolumeError> {
    let Some(place) = previewed(path, opts, &budgets)? else {
        return Ok(None);
    };
    let shape = Shape {
        dims: place.dims,
        voxel_type: place.voxel_type,
        steps: place.timesteps,
    };
    let Ok(level) = budget::choose(&shape, &budgets) else {
        return Ok(None);
    };
    let cached = cache.filter(|_| level.level > 0 && place.timesteps == 1);
    if let Some(v) = cached.and_then(|c| c.preview(&place, level.level, preview::PREVIEW_SIDE)) {
        return Ok(Some(v));
    }
    preview::preview(&place, level.level)
}

/// `path` as its preview reads it: in place, or a DICOM series or multi-frame file decoded slice by slice
/// ([`dicom_slice_by_slice`]). A folder's headers are read only where the bound from its first header
/// ([`claimed_bound`](crate::formats::dicom::slices::claimed_bound)) is large enough for a preview.
fn previewed(path: &Path, opts: &OpenOptions, budgets: &Budgets) -> Result<Option<InPlace>, VolumeError> {
    if let Some(place) = in_place(path, opts)? {
        return Ok(Some(place));
    }
    let large = |(dims, voxel_type): ([u32; 3], VoxelType)| {
        let shape = Shape {
            dims,
            voxel_type,
            steps: 1,
        };
        budget::choose(&shape, budgets).is_ok_and(|l| preview::large_at(dims, l.level))
    };
    if path.is_dir() && !crate::formats::dicom::slices::claimed_bound(path).is_some_and(large) {
        return Ok(None);
    }
    dicom_slice_by_slice(path, opts)
}

/// `path` as a volume read slice by slice whatever the budgets, if it is a folder holding a DICOM series (chosen by
/// `opts.series` as the loader chooses it) or one multi-frame DICOM file; `None` for anything else, and for slices at
/// several temporal positions. The loader may still read it whole: this is how its preview reads it.
pub fn dicom_slice_by_slice(path: &Path, opts: &OpenOptions) -> Result<Option<InPlace>, VolumeError> {
    use crate::formats::in_place::{frames_in_place, series_in_place};
    if path.is_dir() {
        series_in_place(path, opts.series.as_deref())
    } else {
        frames_in_place(path, &|_, _| false)
    }
}

/// A file neither in place nor a compressed stream (`in_place::compressed`), such as ASCII NRRD, is read whole before
/// it can be reduced: one whose header claims more than the host budget is refused before anything else is read,
/// saying what to do.
fn refuse_whole_over_budget(path: &Path, budgets: &Budgets) -> Result<(), String> {
    let Some((dims, voxel_type, steps)) = crate::formats::in_place::claimed_shape(path) else {
        return Ok(());
    };
    let shape = Shape {
        dims,
        voxel_type,
        steps,
    };
    let (bytes, _) = shape.level_bytes(0);
    if bytes <= budgets.host {
        return Ok(());
    }
    let [x, y, z] = dims;
    Err(format!(
        "its {x}x{y}x{z} {voxel_type} voxels{} need {} of memory to decode, and the host budget is {} \
         (--host-budget); this encoding is read whole: raise --host-budget, or store it as raw or gzip (volcast \
         reads uncompressed NIfTI, NRRD and MetaImage in place, and gzip ones as a stream, level by level, at any \
         size)",
        if steps > 1 {
            format!(" x {steps} steps")
        } else {
            String::new()
        },
        budget::show(bytes),
        budget::show(budgets.host)
    ))
}

/// `--max-dim`, where given, still applies to a level read from a file.
fn after_level(v: Volume, opts: &OpenOptions) -> Volume {
    match opts.max_dim {
        Some(m) if v.dims.iter().any(|&d| d > m) => v.map_steps(|s| crate::pyramid::max_dim::downsample_to(s, m)),
        _ => v,
    }
}

fn refuse_if_asked(opts: &OpenOptions, dims: [u32; 3], level: &budget::Level) -> Result<(), String> {
    if !opts.no_downsample {
        return Ok(());
    }
    let [x, y, z] = dims;
    Err(format!(
        "{x}x{y}x{z} does not fit at full resolution ({}), and --no-downsample refuses a coarser level; raise \
         --host-budget or --gpu-budget, or drop --no-downsample to see pyramid level {}",
        level.why.as_deref().unwrap_or("over budget"),
        level.level
    ))
}

/// `v` reduced to the finest pyramid level that fits `budgets` (itself if full resolution fits), every time step,
/// keeping what the file said (format, modality, arrays, series, channels, notes) and the shown step.
pub fn fit(v: Volume, budgets: &Budgets, no_downsample: bool) -> Result<Volume, VolumeError> {
    let shape = Shape {
        dims: v.dims,
        voxel_type: v.source_type,
        steps: v.timesteps(),
    };
    let named = |problem: String| VolumeError::Header {
        file: v.name.clone(),
        problem,
    };
    let level = budget::choose(&shape, budgets).map_err(named)?;
    if level.level == 0 {
        return Ok(v);
    }
    if no_downsample {
        return Err(named(format!(
            "it does not fit at full resolution ({}), and --no-downsample refuses a coarser level",
            level.why.as_deref().unwrap_or("over budget")
        )));
    }
    let mut notes = v.notes.clone();
    notes.push(budget::level_note(shape.dims, &level));
    let shown = v.shown_step();
    let (format, modality) = (v.format.clone(), v.modality.clone());
    let (arrays, series, channels) = (v.arrays.clone(), v.series.clone(), v.channels.clone());
    let (geometry, source_voxels) = (v.geometry, v.source_voxels);
    let source = Source::Loaded(Box::new(v));
    let mut out = read::read_level(&source, level.level, budgets.host, notes, &mut |_| {})?;
    drop(source);
    out.format = format;
    out.modality = modality;
    out.arrays = arrays;
    out.series = series;
    out.channels = channels;
    out.show_step(shown)?;
    Ok(out.stand_in_for(&geometry, source_voxels))
}

/// What the unit tests of this room share.
#[cfg(test)]
pub(crate) mod test_file {
    use crate::formats::{OpenOptions, RawOptions};
    use crate::volume::VoxelType;
    use std::path::PathBuf;

    /// `values` (x fastest) as an int16 raw file in a fresh temporary folder named by `tag`, and the options that
    /// open it; the folder is the caller's to remove.
    pub fn int16_raw(tag: &str, dims: [u32; 3], values: &[i16], spacing: Option<[f32; 3]>) -> (PathBuf, OpenOptions) {
        let dir = std::env::temp_dir().join(format!("volcast-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("v.raw");
        std::fs::write(&path, bytemuck::cast_slice::<i16, u8>(values)).unwrap();
        let opts = OpenOptions {
            raw: RawOptions {
                dims: Some(dims),
                voxel_type: Some(VoxelType::I16),
                spacing,
            },
            ..Default::default()
        };
        (path, opts)
    }
}
