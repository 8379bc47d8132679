//! `volcast.Volume`: a volume in memory, read from a file by volcast's own readers ([`open`]) or made from a numpy
//! array's bytes ([`from_bytes`]). Its voxels are shared, never copied, between Python (`Volume.array`, a read-only
//! view where the stored type is the array's) and the renderer.

use crate::errors::{to_py, While};
use crate::wait::on_thread;
use numpy::ndarray::{Array2, Array3, ArrayView3};
use numpy::{PyArray2, PyArray3, PyArrayDescrMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use volcast::volume::{Geometry, Volume, VoxelData, VoxelType};

/// A volume and the number that tells it from every other volume of this process (the device keeps the last one
/// placed by it, so that rendering it again uploads nothing).
#[pyclass(name = "Volume", module = "volcast._volcast", frozen)]
pub struct PyVolume {
    pub id: u64,
    pub inner: Arc<Volume>,
    /// Made by [`builtin`]: rendered as `--builtin` is (the colormap model), not as data.
    pub builtin: bool,
}

impl PyVolume {
    pub fn new(volume: Volume) -> PyVolume {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        PyVolume {
            id: NEXT.fetch_add(1, Ordering::Relaxed),
            inner: Arc::new(volume),
            builtin: false,
        }
    }
}

/// `shape` (z, y, x) of `data` as an array of `T`, viewed without a copy; `owner` keeps the voxels alive.
fn view<'py, T: numpy::Element>(
    owner: &Bound<'py, PyVolume>,
    shape: [usize; 3],
    data: &[T],
) -> PyResult<Bound<'py, PyAny>> {
    let view = ArrayView3::from_shape(shape, data).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the elements belong to the Arc<Volume> of `owner`, a frozen pyclass that never mutates or replaces
    // them; the array holds `owner` as its base, so they outlive it.
    let array = unsafe { PyArray3::borrow_from_array(&view, owner.clone().into_any()) };
    array.getattr("flags")?.setattr("writeable", false)?;
    Ok(array.into_any())
}

/// `data` shifted back by the bias volcast stores signed integers with (int8 +128, int16 +32768), as a new array.
fn unbiased<'py, T: numpy::Element, S: Copy>(
    py: Python<'py>,
    shape: [usize; 3],
    data: &[S],
    f: impl Fn(S) -> T,
) -> PyResult<Bound<'py, PyAny>> {
    let values = Array3::from_shape_vec(shape, data.iter().map(|&v| f(v)).collect())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray3::from_owned_array(py, values).into_any())
}

#[pymethods]
impl PyVolume {
    /// The voxels as a numpy array of shape (z, y, x): a read-only view without a copy for uint8, uint16 and float32
    /// volumes (and the float32 that float64, int32 and uint32 volumes are stored as); a copy for int8 and int16,
    /// which volcast stores biased.
    #[getter]
    fn array<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let v = &slf.get().inner;
        let shape = [v.dims[2] as usize, v.dims[1] as usize, v.dims[0] as usize];
        match (v.source_type, &v.data) {
            (VoxelType::I8, VoxelData::U8(d)) => unbiased(slf.py(), shape, d, |b: u8| (b as i16 - 128) as i8),
            (VoxelType::I16, VoxelData::U16(d)) => unbiased(slf.py(), shape, d, |b: u16| (b as i32 - 32768) as i16),
            (_, VoxelData::U8(d)) => view(slf, shape, d),
            (_, VoxelData::U16(d)) => view(slf, shape, d),
            (_, VoxelData::F32(d)) => view(slf, shape, d),
        }
    }

    /// Voxels along x, y and z.
    #[getter]
    fn dims(&self) -> (u32, u32, u32) {
        let [x, y, z] = self.inner.dims;
        (x, y, z)
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The voxel type as the file or array had it (uint8, int16, float64, ...).
    #[getter]
    fn dtype(&self) -> &'static str {
        self.inner.source_type.name()
    }

    /// The voxel size along x, y and z (millimetres for scans).
    #[getter]
    fn spacing(&self) -> (f32, f32, f32) {
        let [x, y, z] = self.inner.spacing();
        (x, y, z)
    }

    /// The 4×4 voxel-to-world matrix for voxel (x, y, z) = array[z, y, x]: RAS+ millimetres where `anatomical`.
    #[getter]
    fn affine<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.inner.geometry.rows();
        let m = Array2::from_shape_vec((4, 4), rows.iter().flatten().copied().collect())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyArray2::from_owned_array(py, m))
    }

    /// Whether the file said which way the patient lies (then the affine is to RAS+ and views are anatomical).
    #[getter]
    fn anatomical(&self) -> bool {
        self.inner.geometry.anatomical
    }

    /// The smallest and largest value (after the file's rescale, if any).
    #[getter]
    fn value_range(&self) -> (f64, f64) {
        (self.inner.range[0], self.inner.range[1])
    }

    /// What the reader noted (orientation ignored, levels read, series skipped, ...).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.inner.notes.clone()
    }

    /// `volcast info --json` of this volume, as JSON text.
    fn info_json(&self) -> PyResult<String> {
        serde_json::to_string(&volcast::render::info::Info::of(&self.inner))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }
}

/// Reads a file (or a built-in, `--builtin`) as `volcast render` does, with its volume options (`argv`: the path,
/// then `--dims`, `--type`, ...), on a thread of its own.
#[pyfunction]
pub fn open(py: Python<'_>, argv: Vec<String>) -> PyResult<PyVolume> {
    let args = crate::options::parse_open(argv).map_err(|e| to_py(e, While::Reading))?;
    let loaded = on_thread(py, move || args.load_without_notes())?;
    loaded.map(PyVolume::new).map_err(|e| to_py(e, While::Reading))
}

/// A built-in volume (helix, box, colormap, marschner-lobb) of edge `size`.
#[pyfunction]
#[pyo3(signature = (name, size=None))]
pub fn builtin(name: &str, size: Option<u32>) -> PyResult<PyVolume> {
    volcast::volume::builtin(name, size)
        .map(|v| PyVolume {
            builtin: true,
            ..PyVolume::new(v)
        })
        .map_err(|e| to_py(e.into(), While::Converting))
}

/// A volume of a C-ordered numpy array of shape (z, y, x) in the host's byte order, `dtype` its type's name; placed
/// by `affine` (voxel (x, y, z) to world, anatomical: RAS+ millimetres) where given, else by `spacing`.
#[pyfunction]
#[pyo3(signature = (array, dtype, name, spacing, affine=None, anatomical=false))]
pub fn from_bytes(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    dtype: &str,
    name: &str,
    spacing: (f32, f32, f32),
    affine: Option<[[f64; 4]; 4]>,
    anatomical: bool,
) -> PyResult<PyVolume> {
    let bad = |m: String| PyValueError::new_err(m);
    let voxel_type: VoxelType = dtype
        .parse()
        .map_err(|e: volcast::volume::VolumeError| bad(e.to_string()))?;
    let shape = array.shape();
    if shape.len() != 3 || !array.is_c_contiguous() {
        return Err(bad(format!(
            "an array of shape (z, y, x), C-ordered, is needed; got shape {shape:?}"
        )));
    }
    // The bytes read below are the array's only if its elements are what `dtype` says.
    let descr = array.dtype();
    let kind = match voxel_type {
        VoxelType::U8 | VoxelType::U16 | VoxelType::U32 => b'u',
        VoxelType::I8 | VoxelType::I16 | VoxelType::I32 => b'i',
        VoxelType::F32 | VoxelType::F64 => b'f',
    };
    if descr.itemsize() != voxel_type.size() || descr.kind() != kind || descr.is_native_byteorder() == Some(false) {
        return Err(bad(format!(
            "the array's dtype is not {dtype} in the host's byte order"
        )));
    }
    let too_big = |n: usize| u32::try_from(n).map_err(|_| bad(format!("an axis of {n} voxels is too long")));
    let dims = [too_big(shape[2])?, too_big(shape[1])?, too_big(shape[0])?];
    let bytes_len = shape.iter().product::<usize>() * voxel_type.size();
    // SAFETY: a C-contiguous array of `shape` and this dtype holds `bytes_len` bytes at its data pointer; `array` is
    // held (borrowed from the caller) until the slice's last use below.
    let bytes = unsafe { std::slice::from_raw_parts((*array.as_array_ptr()).fields.data as *const u8, bytes_len) };
    let geometry = affine.map(|rows| {
        let m = volcast::volume::geometry::from_rows([rows[0], rows[1], rows[2]]);
        Geometry { affine: m, anatomical }
    });
    let made = py.detach(|| -> anyhow::Result<Volume> {
        if matches!(voxel_type, VoxelType::F32 | VoxelType::F64) && !finite(bytes, voxel_type) {
            anyhow::bail!("{name}: the array holds NaN or infinite values; replace them (numpy.nan_to_num) first");
        }
        let s = [spacing.0, spacing.1, spacing.2];
        let mut v = volcast::formats::from_native_bytes(name, dims, voxel_type, s, bytes)?;
        if let Some(g) = geometry {
            v = v.with_geometry(g)?;
        }
        Ok(v)
    });
    made.map(PyVolume::new).map_err(|e| to_py(e, While::Converting))
}

/// Whether every float in `bytes` (host order) is finite.
fn finite(bytes: &[u8], t: VoxelType) -> bool {
    match t {
        VoxelType::F32 => bytes
            .chunks_exact(4)
            .all(|c| f32::from_ne_bytes([c[0], c[1], c[2], c[3]]).is_finite()),
        _ => bytes
            .chunks_exact(8)
            .all(|c| f64::from_ne_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]).is_finite()),
    }
}
