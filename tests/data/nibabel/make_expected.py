"""Oracle for tests/formats/headers.rs: NIfTI-2, Analyze 7.5 and MetaImage files with what nibabel and SimpleITK
read from them (shape, dtype, RAS affine, a few voxel values), in expected.json.

Run from this folder in a scratch venv:  pip install nibabel==5.4.2 numpy SimpleITK==2.5.7; python make_expected.py
It copies three files from nibabel's own test data (NIBABEL_DATA: nibabel/tests/data of the nibabel 5.4.2 wheel,
`pip download --no-deps nibabel==5.4.2` and unzip), writes the small files below, and reads every one back.
"""

import json
import os
import shutil

import nibabel as nib
import numpy as np
import SimpleITK as sitk

HERE = os.path.dirname(os.path.abspath(__file__))
NIBABEL_DATA = os.environ.get("NIBABEL_DATA", "/tmp/hdr-nib/nibabel/tests/data")
COPIED = ["example_nifti2.nii.gz", "nifti2.hdr", "analyze.hdr"]


def path(name):
    return os.path.join(HERE, name)


def ramp(shape, dtype):
    """Distinct values in Fortran (x fastest) order, so a transposed read shows."""
    n = int(np.prod(shape))
    return (np.arange(n) * 3 - n).astype(dtype).reshape(shape, order="F")


def write_analyze():
    """A little-endian SPM2 Analyze pair with an origin voxel and a scale factor and offset. The header is filled
    by hand from nibabel's Spm2AnalyzeHeader (its image class would also write a .mat file, which needs scipy)."""
    data = ramp((5, 4, 3), np.int16)
    hdr = nib.spm2analyze.Spm2AnalyzeHeader(endianness="<")
    hdr.set_data_shape(data.shape)
    hdr.set_data_dtype(np.int16)
    hdr.set_zooms((1.5, 2.0, 2.5))
    hdr["origin"][:3] = [2, 3, 1]
    hdr["scl_slope"] = 2.0
    hdr["scl_inter"] = 0.5
    with open(path("analyze_spm.hdr"), "wb") as f:
        f.write(hdr.binaryblock)
    with open(path("analyze_spm.img"), "wb") as f:
        f.write(data.astype("<i2").tobytes(order="F"))


def write_nifti2():
    """A big-endian NIfTI-2 .hdr/.img pair with an oblique sform, and a single-file .nii with only a qform."""
    aff = np.array([[0.0, -2.0, 0.3, 10.0], [1.5, 0.0, 0.0, -20.0], [0.0, 0.2, 3.0, 5.5], [0, 0, 0, 1]])
    hdr = nib.Nifti2Header(endianness=">")
    img = nib.Nifti2Pair(ramp((4, 3, 2), np.float32), aff, hdr)
    img.set_sform(aff, code=2)
    img.set_qform(None, code=0)
    nib.save(img, path("nifti2_pair_be.hdr"))
    qaff = np.array([[-1.0, 0.0, 0.0, 3.0], [0.0, 0.0, 2.0, -4.0], [0.0, -0.5, 0.0, 6.0], [0, 0, 0, 1]])
    img = nib.Nifti2Image(ramp((3, 4, 2), np.uint16), qaff)
    img.set_qform(qaff, code=1)
    img.set_sform(None, code=0)
    nib.save(img, path("nifti2_qform.nii"))


def write_metaimage():
    """A hand-written .mha without TransformMatrix or Offset (ITK reads it in LPS with the identity direction), and
    one SimpleITK wrote with a direction and origin."""
    data = ramp((3, 4, 2), np.uint8)
    header = (
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
        "ElementSpacing = 0.5 1 2\nDimSize = 3 4 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
    )
    with open(path("mha_no_matrix.mha"), "wb") as f:
        f.write(header.encode() + data.tobytes(order="F"))
    image = sitk.GetImageFromArray(ramp((3, 4, 2), np.int16).transpose(2, 1, 0))
    image.SetSpacing((0.5, 1.0, 2.0))
    image.SetOrigin((10.0, -5.0, 3.0))
    image.SetDirection((0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0))
    sitk.WriteImage(image, path("mha_matrix.mha"), useCompression=False)


def nibabel_entry(name, has_data):
    img = nib.load(path(name))
    entry = {
        "file": name,
        "reader": "nibabel " + nib.__version__ + " " + type(img).__name__,
        "open": has_data,
        "shape": [int(s) for s in img.shape],
        "dtype": str(img.get_data_dtype().newbyteorder("=")),
        "affine": img.affine.tolist(),
    }
    if has_data:
        data = img.get_fdata()
        if data.ndim == 3:
            data = data[..., np.newaxis]
        picks = [(0, 0, 0, 0), tuple(s - 1 for s in data.shape), (1, 2, 1, data.shape[3] - 1), (2, 1, 0, 0)]
        entry["values"] = [[*map(int, p), float(data[p])] for p in picks]
    return entry


def sitk_entry(name):
    image = sitk.ReadImage(path(name))
    d = np.array(image.GetDirection()).reshape(3, 3)
    lps = np.eye(4)
    lps[:3, :3] = d @ np.diag(image.GetSpacing())
    lps[:3, 3] = image.GetOrigin()
    ras = np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps
    array = sitk.GetArrayFromImage(image).transpose(2, 1, 0)
    picks = [(0, 0, 0), tuple(s - 1 for s in array.shape), (1, 2, 1)]
    return {
        "file": name,
        "reader": "SimpleITK " + sitk.Version.VersionString(),
        "open": True,
        "shape": [int(s) for s in array.shape],
        "dtype": str(array.dtype),
        "affine": ras.tolist(),
        "values": [[*map(int, p), 0, float(array[p])] for p in picks],
    }


def main():
    for name in COPIED:
        shutil.copyfile(os.path.join(NIBABEL_DATA, name), path(name))
    write_analyze()
    write_nifti2()
    write_metaimage()
    entries = [
        nibabel_entry("example_nifti2.nii.gz", True),
        nibabel_entry("nifti2.hdr", False),
        nibabel_entry("analyze.hdr", False),
        nibabel_entry("analyze_spm.hdr", True),
        nibabel_entry("nifti2_pair_be.hdr", True),
        nibabel_entry("nifti2_qform.nii", True),
        sitk_entry("mha_no_matrix.mha"),
        sitk_entry("mha_matrix.mha"),
    ]
    with open(path("expected.json"), "w") as f:
        json.dump(entries, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
