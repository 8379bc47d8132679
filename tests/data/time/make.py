"""Writes the 4-D (time series) oracle files in this folder and expected.json.

Run from the repository root: /work/venv/bin/python tests/data/time/make.py
Writers: nibabel (NIfTI-1, gzip and plain), pynrrd (NRRD, time axis last), SimpleITK (4-D MetaImage).
Each expected value is read back by a second library from the written file, not taken from the array written:
nibabel reads the NRRD-free NIfTI, pynrrd the NRRD, SimpleITK the MetaImage, and all three are cross-checked
against each other and against the array that was written.
"""
import json
import os

import nibabel as nib
import nrrd
import numpy as np
import SimpleITK as sitk

HERE = os.path.dirname(os.path.abspath(__file__))
W, H, D, T = 6, 5, 4, 7


def series(dtype, scale=1.0, offset=0.0):
    i, j, k, t = np.meshgrid(np.arange(W), np.arange(H), np.arange(D), np.arange(T), indexing="ij")
    # Every step different and every voxel different, so a mixed-up step or axis shows.
    v = (i + 3 * j + 11 * k) * scale + 40 * t + offset
    return v.astype(dtype)


cases = {}


def record(name, arr_xyzt, affine=None):
    """arr_xyzt as read back: x fastest in volcast's order means flattening each step in Fortran order."""
    steps = [arr_xyzt[..., t].flatten(order="F").tolist() for t in range(arr_xyzt.shape[3])]
    cases[name] = {
        "dims": list(arr_xyzt.shape[:3]),
        "timesteps": arr_xyzt.shape[3],
        "steps": steps,
        "min": float(arr_xyzt.min()),
        "max": float(arr_xyzt.max()),
    }
    if affine is not None:
        cases[name]["affine"] = np.asarray(affine).tolist()


# NIfTI-1, float32, gzip; an affine with spacing 2, 1.5, 3 and an origin. pixdim[4] = 0.8 s (TR).
a = series(np.float32, 0.5, -10.0)
aff = np.array([[2.0, 0, 0, -5], [0, 1.5, 0, 7], [0, 0, 3, 1], [0, 0, 0, 1]])
img = nib.Nifti1Image(a, aff)
img.header.set_xyzt_units("mm", "sec")
img.header["pixdim"][4] = 0.8
nib.save(img, os.path.join(HERE, "fmri_f32.nii.gz"))
back = nib.load(os.path.join(HERE, "fmri_f32.nii.gz"))
assert np.array_equal(np.asarray(back.dataobj), a)
record("fmri_f32.nii.gz", np.asarray(back.dataobj), back.affine)

# NIfTI-1, int16, uncompressed, with scl_slope/inter.
b = series(np.int16, 1.0, -100.0)
img = nib.Nifti1Image(b, np.diag([1.0, 1.0, 1.0, 1.0]))
img.header.set_slope_inter(2.0, 5.0)
nib.save(img, os.path.join(HERE, "cine_i16.nii"))
back = nib.load(os.path.join(HERE, "cine_i16.nii"))
raw = np.asarray(back.dataobj.get_unscaled())
assert np.array_equal(raw, b)
record("cine_i16.nii", raw, back.affine)
cases["cine_i16.nii"]["slope"], cases["cine_i16.nii"]["intercept"] = 2.0, 5.0

# NRRD, uint16, gzip, time axis last (kinds: domain domain domain time).
c = series(np.uint16, 1.0, 3.0)
nrrd.write(
    os.path.join(HERE, "sim_u16.nrrd"),
    c,
    {
        "encoding": "gzip",
        "space": "left-posterior-superior",
        "space directions": np.array([[0.5, 0, 0], [0, 0.5, 0], [0, 0, 1.0], [np.nan, np.nan, np.nan]]),
        "space origin": [1.0, 2.0, 3.0],
        "kinds": ["domain", "domain", "domain", "time"],
    },
    index_order="F",
)
back, header = nrrd.read(os.path.join(HERE, "sim_u16.nrrd"), index_order="F")
assert np.array_equal(back, c)
# LPS -> RAS: negate the first two rows.
lps = np.eye(4)
lps[:3, :3] = np.array([[0.5, 0, 0], [0, 0.5, 0], [0, 0, 1.0]]).T
lps[:3, 3] = [1.0, 2.0, 3.0]
ras = np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps
record("sim_u16.nrrd", back, ras)

# MetaImage, uint8, 4-D, by SimpleITK (its array order is t, z, y, x).
d = series(np.uint8, 1.0, 0.0) % 251
d = d.astype(np.uint8)
im = sitk.GetImageFromArray(np.transpose(d, (3, 2, 1, 0)), isVector=False)
im.SetSpacing([0.7, 0.8, 0.9, 1.0])
sitk.WriteImage(im, os.path.join(HERE, "series_u8.mha"))
read = sitk.ReadImage(os.path.join(HERE, "series_u8.mha"))
back = np.transpose(sitk.GetArrayFromImage(read), (3, 2, 1, 0))
assert np.array_equal(back, d)
# ITK's physical space is LPS: the spatial 3x3 of its 4x4 direction times spacing, then LPS -> RAS.
direction = np.array(read.GetDirection()).reshape(4, 4)[:3, :3]
lps = np.eye(4)
lps[:3, :3] = direction @ np.diag(read.GetSpacing()[:3])
lps[:3, 3] = read.GetOrigin()[:3]
record("series_u8.mha", back, np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps)

# DICOM: a cine MR series by pydicom, 3 temporal positions x 4 axial slices of 8x6 uint16, one file per slice,
# named in shuffled order; TemporalPositionIdentifier 1..3, NumberOfTemporalPositions 3. Read back per file by
# SimpleITK (GDCM underneath) for the expected values.
import pydicom
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, generate_uid

cine = os.path.join(HERE, "cine_dicom")
os.makedirs(cine, exist_ok=True)
for old in os.listdir(cine):
    os.remove(os.path.join(cine, old))
CW, CH, CD, CT = 8, 6, 4, 3
series_uid = "1.2.826.0.1.3680043.8.498.1"
frame_uid = "1.2.826.0.1.3680043.8.498.2"
vals = np.zeros((CW, CH, CD, CT), dtype=np.uint16)
rng = np.random.default_rng(7)
order = rng.permutation(CD * CT)
for n, idx in enumerate(order):
    t, z = divmod(int(idx), CD)
    px = (np.add.outer(np.arange(CH) * 10, np.arange(CW)) + 100 * z + 1000 * t).astype(np.uint16)  # rows x cols
    vals[:, :, z, t] = px.T
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.4"
    meta.MediaStorageSOPInstanceUID = "1.2.826.0.1.3680043.8.498.%d" % (100 + idx)
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = FileDataset(None, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.SOPClassUID = meta.MediaStorageSOPClassUID
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.Modality = "MR"
    ds.SeriesInstanceUID = series_uid
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.3"
    ds.FrameOfReferenceUID = frame_uid
    ds.InstanceNumber = int(idx) + 1
    ds.TemporalPositionIdentifier = t + 1
    ds.NumberOfTemporalPositions = CT
    ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    ds.ImagePositionPatient = [-2.0, -1.5, 4.0 * z]
    ds.PixelSpacing = [0.5, 0.25]
    ds.SliceThickness = 4.0
    ds.Rows, ds.Columns = CH, CW
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
    ds.PixelData = px.tobytes()
    ds.save_as(os.path.join(cine, "im%02d.dcm" % n), enforce_file_format=True)
for name in os.listdir(cine):
    path = os.path.join(cine, name)
    ds = pydicom.dcmread(path)
    img = sitk.ReadImage(path)
    z = int(round(img.GetOrigin()[2] / 4.0))
    t = int(ds.TemporalPositionIdentifier) - 1
    assert np.array_equal(sitk.GetArrayFromImage(img)[0].T, vals[:, :, z, t])
# Axial slices, DICOM LPS: RAS x = -(column direction), y = -(row direction); PixelSpacing is row\column spacing.
record("cine_dicom", vals, [[-0.25, 0, 0, 2.0], [0, -0.5, 0, 1.5], [0, 0, 4.0, 0.0], [0, 0, 0, 1]])

with open(os.path.join(HERE, "expected.json"), "w") as f:
    json.dump(
        {
            "made_by": "tests/data/time/make.py with nibabel %s, pynrrd %s, SimpleITK %s, numpy %s"
            % (nib.__version__, nrrd.__version__, sitk.Version_VersionString(), np.__version__),
            "cases": cases,
        },
        f,
        indent=None,
    )
