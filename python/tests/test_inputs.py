"""Inputs as they come: files through volcast.open, nibabel and SimpleITK images in the patient space `volcast info
--json` gives for the same file."""

import json
import subprocess

import numpy as np
import pytest

import volcast


def cli_info(cli, path, *extra):
    out = subprocess.run([cli, "info", str(path), "--json", *extra], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def affine_of(info):
    return np.array(info["affine_ras"], dtype=float)


def formats(data):
    """One file of each format the command line reads, from tests/data (made by the formats' own tools)."""
    found = [data / "ramp.nhdr", data / "ramp.mhd", data / "ramp.vtk", data / "nibabel" / "nifti2_qform.nii",
             data / "nibabel" / "analyze_spm.hdr", data / "slice.dcm"]
    found += sorted((data / "zarr").glob("*.zarr"))[:2] + sorted((data / "vtk").glob("*.vti"))[:1]
    found += sorted((data / "tiff").glob("*.tif"))[:1]
    return [f for f in found if f.exists()]


def test_open_reads_every_format_as_info_does(cli, data):
    files = formats(data)
    assert len(files) >= 8, files
    for f in files:
        ours = volcast.open(f).info()
        theirs = cli_info(cli, f)
        for key in ("dims", "type", "format", "value_range", "affine_ras"):
            assert ours.get(key) == theirs.get(key), f"{f.name}: {key} {ours.get(key)} != {theirs.get(key)}"


def test_open_takes_the_raw_options(cli, tmp_path):
    raw = tmp_path / "scan.raw"
    (np.arange(4 * 5 * 6, dtype="<i2").reshape(6, 5, 4) - 50).tofile(raw)
    v = volcast.open(raw, dims=(4, 5, 6), type="int16", spacing=(0.5, 0.5, 2))
    assert v.dims == (4, 5, 6) and v.dtype == "int16" and v.spacing == (0.5, 0.5, 2.0)
    assert v.array[0, 0, 0] == -50 and v.array.shape == (6, 5, 4)
    assert v.info() == cli_info(cli, raw, "--dims", "4", "5", "6", "--type", "int16", "--spacing", "0.5", "0.5", "2")


NIFTI = ["native/colin27_t1/ch2.nii.gz", "native/motor_zmap/image_10426.nii.gz", "native/dwi_s0_10slices/S0_10slices.nii.gz"]


@pytest.mark.parametrize("name", NIFTI)
def test_a_nibabel_image_lands_where_the_file_does(cli, shared, name):
    nib = pytest.importorskip("nibabel")
    path = shared / name
    theirs = cli_info(cli, path)
    v = volcast.volume(nib.load(path))
    assert v.dims == tuple(theirs["dims"])
    assert np.allclose(v.affine, affine_of(theirs), atol=1e-4), f"{v.affine}\n{affine_of(theirs)}"
    assert v.anatomical
    assert np.allclose(v.value_range, theirs["value_range"], rtol=1e-5)


# ITK refuses S0_10slices's non-orthonormal direction cosines; a DICOM series takes its place.
@pytest.mark.parametrize("name", NIFTI[:2] + ["native/brain_pd_mr"])
def test_a_simpleitk_image_lands_where_the_file_does(cli, shared, name):
    sitk = pytest.importorskip("SimpleITK")
    path = shared / name
    theirs = cli_info(cli, path)
    if path.is_dir():
        reader = sitk.ImageSeriesReader()
        reader.SetFileNames(reader.GetGDCMSeriesFileNames(str(path)))
        image = reader.Execute()
    else:
        image = sitk.ReadImage(str(path))
    v = volcast.volume(image)
    assert v.dims == tuple(theirs["dims"])
    assert np.allclose(v.affine, affine_of(theirs), atol=1e-3), f"{v.affine}\n{affine_of(theirs)}"


def test_a_nibabel_image_renders_as_its_file(shared):
    nib = pytest.importorskip("nibabel")
    path = shared / "native/colin27_t1/ch2.nii.gz"
    ours = volcast.render(nib.load(path), size=64, preset="mr-default")
    theirs = volcast.render(path, size=64, preset="mr-default")
    assert np.array_equal(ours, theirs), f"{np.count_nonzero(ours != theirs)} bytes differ"


def test_a_zarr_array_is_read(tmp_path):
    zarr = pytest.importorskip("zarr")
    z = zarr.open_array(str(tmp_path / "a.zarr"), mode="w", shape=(8, 9, 10), chunks=(4, 4, 4), dtype="uint16")
    z[:] = np.arange(720, dtype=np.uint16).reshape(8, 9, 10)
    frame = volcast.render(z, size=24)
    assert np.array_equal(frame, volcast.render(np.asarray(z), size=24))


def test_a_zarr_array_over_the_limit_is_read_from_a_file_in_place(tmp_path, monkeypatch):
    zarr = pytest.importorskip("zarr")
    import volcast._inputs as inputs

    monkeypatch.setattr(inputs, "LAZY_LIMIT", 1000)
    monkeypatch.setattr(inputs, "SLAB_BYTES", 3 * 30 * 40)  # several slabs
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    a = np.random.default_rng(6).integers(0, 60000, (20, 30, 40), dtype=np.uint16)
    z = zarr.open_array(str(tmp_path / "big.zarr"), mode="w", shape=a.shape, chunks=(8, 8, 8), dtype="uint16")
    z[:] = a
    v = volcast.volume(z, spacing=(1, 1, 2))
    assert v.info()["format"] == "raw" and v.spacing == (1.0, 1.0, 2.0)
    assert np.array_equal(v.array, a)
    assert np.array_equal(volcast.render(v, size=32), volcast.render(volcast.Volume.from_array(a, spacing=(1, 1, 2)), size=32))
    spilled = list((tmp_path / "cache" / "volcast" / "python").glob("*.raw"))
    assert len(spilled) == 1
    del v
    import gc

    gc.collect()
    assert not spilled[0].exists(), "the file goes with its volume"


def test_a_dask_array_is_read(tmp_path, monkeypatch):
    da = pytest.importorskip("dask.array")
    import volcast._inputs as inputs

    a = np.random.default_rng(7).random((12, 14, 16)).astype(np.float32)
    lazy = da.from_array(a, chunks=(4, 7, 8)) * 2
    expected = volcast.render(a * 2, size=24)
    assert np.array_equal(volcast.render(lazy, size=24), expected)
    monkeypatch.setattr(inputs, "LAZY_LIMIT", 1000)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    assert np.array_equal(volcast.render(lazy, size=24), expected)


def test_spacing_applies_to_a_file_as_the_option_does(cli, tmp_path):
    raw = tmp_path / "cube_12x12x12_uint8.raw"
    np.random.default_rng(10).integers(0, 255, (12, 12, 12), dtype=np.uint8).tofile(raw)
    ours = volcast.render(raw, spacing=(1, 1, 3), size=32)
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", str(raw), "--spacing", "1", "1", "3", "--size", "32x32", "-o", str(out)], check=True)
    from PIL import Image as PILImage

    assert np.array_equal(ours, np.asarray(PILImage.open(out).convert("RGBA")))
    with pytest.raises(ValueError, match="header"):
        volcast.render(raw, origin=(1, 2, 3))
