#!/usr/bin/env python3
"""Oracle DICOM files for volcast's compressed and multi-frame pixel data (tests/formats/dicom.rs).

Run from the repository root (rewrites tests/data/dicom/ except this script and README-listed notes):

    /work/venv/bin/python tests/data/dicom/make.py

Needs pydicom and numpy (writers of the native files) and gdcmconv (GDCM, `apt-get install libgdcm-tools`),
which writes every compressed file. Expected values come from a second reader: each compressed file is turned back
into native with `gdcmconv --raw` and read by pydicom; lossless ones must equal the native originals exactly (and
RLE is also decoded by pydicom's own RLE decoder). Lossy JPEG keeps GDCM's (libjpeg's) decoded values; volcast's
jpeg-decoder may differ by a small IDCT rounding (tolerance in expected.json).

Series (16 columns x 12 rows x 6 slices, one file per slice, files named in reverse slice order):
  u16: MR, uint16, 12 bits stored, axial, pixel spacing 0.5\0.75, 2.5 mm apart
  i16: CT, int16, rescale intercept -1024, coronal, 0.6\0.8, 3 mm apart
  u8:  8-bit, axial, 0.7\0.8, 1.5 mm apart, smooth (for lossy JPEG)
Multi-frame: enhanced CT, int16, six frames stored shuffled, oblique (30 degrees about S-I), geometry and rescale
(slope 2, intercept -1000) only in the functional groups.
World: RAS; DICOM's LPS is flipped (x, y negated). Deterministic: fixed UIDs, no dates.
"""

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.uid import ExplicitVRLittleEndian, RLELossless

HERE = Path(__file__).resolve().parent
COLS, ROWS, N = 16, 12, 6
ROOT_UID = "1.2.826.0.1.3680043.8.498.12"  # pydicom's prefix + fixed suffixes


def uid(*parts):
    return ".".join([ROOT_UID, *map(str, parts)])


def series_values(kind):
    k, j, i = np.meshgrid(np.arange(N), np.arange(ROWS), np.arange(COLS), indexing="ij")
    if kind == "u16":
        return ((i * 37 + j * 101 + k * 523 + 7) % 4096).astype(np.uint16)
    if kind == "i16":
        return ((i * 37 + j * 101 + k * 523) % 4000 - 1000).astype(np.int16)
    return (i * 6 + j * 8 + k * 10 + 10).astype(np.uint8)


GEOM = {
    # IOP, spacing (between rows, between columns), first IPP, step along the normal (LPS mm)
    "u16": ([1, 0, 0, 0, 1, 0], [0.5, 0.75], [-20.0, -15.0, 10.0], 2.5),
    "i16": ([1, 0, 0, 0, 0, -1], [0.6, 0.8], [-20.0, -30.0, 40.0], 3.0),
    "u8": ([1, 0, 0, 0, 1, 0], [0.7, 0.8], [5.0, -7.0, -3.0], 1.5),
}
C30, S30 = math.cos(math.radians(30)), math.sin(math.radians(30))
ENHANCED_GEOM = ([C30, S30, 0, -S30, C30, 0], [0.6, 0.9], [-10.0, -12.0, -5.0], 2.0)


def normal(iop):
    return np.cross(np.array(iop[:3], float), np.array(iop[3:], float))


def base(sop_class, sop_uid, series_uid, bits, signed):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = sop_class
    meta.MediaStorageSOPInstanceUID = sop_uid
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    meta.ImplementationClassUID = uid(999)
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID = sop_class
    ds.SOPInstanceUID = sop_uid
    ds.StudyInstanceUID = uid(1)
    ds.SeriesInstanceUID = series_uid
    ds.PatientName = "Phantom^Codec"
    ds.PatientID = "volcast"
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.Rows, ds.Columns = ROWS, COLS
    ds.BitsAllocated = 8 if bits == 8 else 16
    ds.BitsStored = bits
    ds.HighBit = bits - 1
    ds.PixelRepresentation = 1 if signed else 0
    return ds


def write_series(kind):
    vals = series_values(kind)
    iop, ps, ipp0, step = GEOM[kind]
    n = normal(iop)
    folder = HERE / f"{kind}_native"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    sop = {"u16": "1.2.840.10008.5.1.4.1.1.4", "i16": "1.2.840.10008.5.1.4.1.1.2", "u8": "1.2.840.10008.5.1.4.1.1.7"}[kind]
    bits = {"u16": 12, "i16": 16, "u8": 8}[kind]
    for k in range(N):
        ds = base(sop, uid(2, kind, k), uid(3, kind), bits, kind == "i16")
        ds.Modality = {"u16": "MR", "i16": "CT", "u8": "OT"}[kind]
        ds.InstanceNumber = N - k
        ds.ImageOrientationPatient = iop
        ds.ImagePositionPatient = [round(float(x), 4) for x in np.array(ipp0) + n * step * k]
        ds.PixelSpacing = ps
        ds.SliceThickness = step
        if kind == "i16":
            ds.RescaleIntercept, ds.RescaleSlope, ds.RescaleType = -1024, 1, "HU"
        ds.PixelData = vals[k].tobytes()
        ds.save_as(folder / f"{N - 1 - k:02d}.dcm", enforce_file_format=True)
    return folder


def write_enhanced():
    vals = series_values("i16")
    iop, ps, ipp0, step = ENHANCED_GEOM
    n = normal(iop)
    stored_order = [3, 0, 5, 1, 4, 2]  # frame f holds slice stored_order[f]
    ds = base("1.2.840.10008.5.1.4.1.1.2.1", uid(4, 1), uid(4, 2), 16, True)
    ds.Modality = "CT"
    ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL", "NONE"]
    ds.NumberOfFrames = N
    shared = Dataset()
    pm = Dataset()
    pm.PixelSpacing = ps
    pm.SliceThickness = step
    shared.PixelMeasuresSequence = Sequence([pm])
    po = Dataset()
    po.ImageOrientationPatient = iop
    shared.PlaneOrientationSequence = Sequence([po])
    pvt = Dataset()
    pvt.RescaleIntercept, pvt.RescaleSlope, pvt.RescaleType = -1000, 2, "HU"
    shared.PixelValueTransformationSequence = Sequence([pvt])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    frames = []
    for f in range(N):
        item = Dataset()
        pp = Dataset()
        pp.ImagePositionPatient = [round(float(x), 4) for x in np.array(ipp0) + n * step * stored_order[f]]
        item.PlanePositionSequence = Sequence([pp])
        frames.append(item)
    ds.PerFrameFunctionalGroupsSequence = Sequence(frames)
    ds.PixelData = np.stack([vals[s] for s in stored_order]).tobytes()
    path = HERE / "enhanced_ct_native.dcm"
    ds.save_as(path, enforce_file_format=True)
    return path


def gdcm(*args):
    subprocess.run(["gdcmconv", *map(str, args)], check=True)


def compress(src, dst, *opts):
    if src.is_dir():
        shutil.rmtree(dst, ignore_errors=True)
        dst.mkdir()
        for f in sorted(src.iterdir()):
            gdcm(*opts, f, dst / f.name)
    else:
        gdcm(*opts, src, dst)
    return dst


def geometry_of(datasets):
    """Slices sorted along the normal; the RAS affine volcast should report (rows of a 3x4 matrix)."""
    def place(ds):
        if "PerFrameFunctionalGroupsSequence" in ds:
            sh = ds.SharedFunctionalGroupsSequence[0]
            iop = [float(x) for x in sh.PlaneOrientationSequence[0].ImageOrientationPatient]
            ps = [float(x) for x in sh.PixelMeasuresSequence[0].PixelSpacing]
            ipps = [[float(x) for x in fr.PlanePositionSequence[0].ImagePositionPatient]
                    for fr in ds.PerFrameFunctionalGroupsSequence]
            return iop, ps, ipps
        return ([float(x) for x in ds.ImageOrientationPatient], [float(x) for x in ds.PixelSpacing],
                [[float(x) for x in ds.ImagePositionPatient]])
    return place


def expected(paths, kind_type, tolerance=0, rle_check=False, native_twin=None):
    """Reads the files back (gdcmconv --raw, then pydicom) and returns what volcast must report."""
    tmp = HERE / "_raw.dcm"
    frames, places = [], []
    iop = ps = None
    for p in paths:
        gdcm("--raw", p, tmp)
        ds = pydicom.dcmread(tmp)
        arr = ds.pixel_array
        if rle_check:
            assert np.array_equal(pydicom.dcmread(p).pixel_array, arr), f"pydicom's RLE decoder disagrees on {p}"
        arr = arr.reshape(-1, ROWS, COLS)
        if "PerFrameFunctionalGroupsSequence" in ds:
            sh = ds.SharedFunctionalGroupsSequence[0]
            iop = [float(x) for x in sh.PlaneOrientationSequence[0].ImageOrientationPatient]
            ps = [float(x) for x in sh.PixelMeasuresSequence[0].PixelSpacing]
            pvt = sh.PixelValueTransformationSequence[0]
            slope, intercept = float(pvt.RescaleSlope), float(pvt.RescaleIntercept)
            for f, fr in enumerate(ds.PerFrameFunctionalGroupsSequence):
                places.append([float(x) for x in fr.PlanePositionSequence[0].ImagePositionPatient])
                frames.append(arr[f])
        else:
            iop = [float(x) for x in ds.ImageOrientationPatient]
            ps = [float(x) for x in ds.PixelSpacing]
            slope = float(getattr(ds, "RescaleSlope", 1))
            intercept = float(getattr(ds, "RescaleIntercept", 0))
            places.append([float(x) for x in ds.ImagePositionPatient])
            frames.append(arr[0])
    tmp.unlink()
    n = normal(iop)
    order = sorted(range(len(places)), key=lambda f: float(np.dot(places[f], n)))
    vol = np.stack([frames[f] for f in order])
    if native_twin is not None and tolerance == 0:
        assert np.array_equal(vol, native_twin), f"lossless round trip differs for {paths[0]}"
    d = [float(np.dot(places[f], n)) for f in order]
    step = (d[-1] - d[0]) / (len(d) - 1)
    row, col = np.array(iop[:3]), np.array(iop[3:])
    lps = np.column_stack([row * ps[1], col * ps[0], n * step, places[order[0]]])
    ras = lps * np.array([[-1], [-1], [1]])
    return {
        "dims": [COLS, ROWS, len(frames)],
        "type": kind_type,
        "spacing": [ps[1], ps[0], step],
        "affine": [[round(float(x), 9) for x in r] for r in ras],
        "slope": slope,
        "intercept": intercept,
        "tolerance": tolerance,
        "sum": int(vol.astype(np.int64).sum()),
        "stored": [int(x) for x in vol.ravel()],
    }


def ts_of(path):
    f = next(path.iterdir()) if path.is_dir() else path
    return str(pydicom.dcmread(f, stop_before_pixels=True).file_meta.TransferSyntaxUID)


def main():
    out = {}
    natives = {k: write_series(k) for k in ("u16", "i16", "u8")}
    enhanced = write_enhanced()
    twins = {}
    for kind, folder in natives.items():
        files = sorted(folder.iterdir())
        e = expected(files, kind)
        twins[kind] = np.array(e["stored"]).reshape(N, ROWS, COLS)
        out[f"{kind}_native"] = e
        for codec, opts in (("rle", ["--rle"]), ("jpeg", ["--jpeg"]), ("j2k", ["--j2k"]), ("jpegls", ["--jpegls"])):
            name = f"{kind}_{codec}"
            dst = compress(folder, HERE / name, *opts)
            out[name] = expected(sorted(dst.iterdir()), kind, rle_check=codec == "rle", native_twin=twins[kind])
    # Baseline (process 1) lossy JPEG of the 8-bit series; GDCM's decoded values are the oracle.
    dst = compress(natives["u8"], HERE / "u8_jpeg_lossy", "--jpeg", "--lossy", "-q", "90")
    out["u8_jpeg_lossy"] = expected(sorted(dst.iterdir()), "u8", tolerance=3)
    # Near-lossless JPEG-LS (NEAR=2) of the 16-bit series; GDCM's decoded values are the oracle (GDCM decodes with
    # CharLS too, so they must agree exactly; the originals are within 2).
    dst = compress(natives["u16"], HERE / "u16_jpegls_near", "--jpegls", "--lossy", "-e", "2")
    out["u16_jpegls_near"] = expected(sorted(dst.iterdir()), "u16", tolerance=0)
    near = np.array(out["u16_jpegls_near"]["stored"]).reshape(N, ROWS, COLS)
    assert 0 < np.abs(near.astype(np.int64) - twins["u16"]).max() <= 2, "NEAR=2 stays within 2 and is lossy"
    en = expected([enhanced], "i16")
    out["enhanced_ct_native.dcm"] = en
    twin = np.array(en["stored"]).reshape(N, ROWS, COLS)
    for codec, opts in (("rle", ["--rle"]), ("j2k", ["--j2k"])):
        name = f"enhanced_ct_{codec}.dcm"
        dst = compress(enhanced, HERE / name, *opts)
        out[name] = expected([dst], "i16", rle_check=codec == "rle", native_twin=twin)
    for name, e in out.items():
        e["transfer_syntax"] = ts_of(HERE / name)
    version = subprocess.run(["gdcmconv", "--version"], capture_output=True, text=True).stdout.strip()
    meta = {"writers": {"pydicom": pydicom.__version__, "numpy": np.__version__, "gdcmconv": version}}
    (HERE / "expected.json").write_text(json.dumps({"meta": meta, "cases": out}, indent=1) + "\n")
    for name, e in out.items():
        print(name, e["transfer_syntax"], e.get("sum"))


if __name__ == "__main__":
    sys.exit(main())
