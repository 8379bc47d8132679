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
