"""Reads an OME-Zarr store volcast wrote with zarr-python and with ome-zarr-py, and prints what each sees as JSON.

    read_back.py STORE [DUMP_DIR]

Per level: shape, dtype, chunk (and shard) shape, scale, translation, sum, first and last values, the compressor;
the multiscale's axes, name and "volcast" attributes; and what ome-zarr-py's Reader makes of the same store
(level count, axes, shapes, transforms, and whether its data equals zarr-python's). With DUMP_DIR, each level's
values are written there as little-endian float64 (level<k>.f64, C order) for the Rust test to compare voxel by
voxel.
"""

import json
import os
import sys

import numpy as np
import zarr
from ome_zarr.io import parse_url
from ome_zarr.reader import Multiscales, Reader


def transforms(dataset):
    out = {}
    for t in dataset.get("coordinateTransformations", []):
        out[t["type"]] = t.get(t["type"])
    return out


def main():
    path = sys.argv[1]
    dump = sys.argv[2] if len(sys.argv) > 2 else None
    root = zarr.open_group(path, mode="r")
    attrs = root.attrs.asdict()
    ome = attrs.get("ome", attrs)
    version = ome.get("version")
    multiscale = ome["multiscales"][0]
    version = version or multiscale.get("version")
    result = {
        "zarr_format": root.metadata.zarr_format,
        "ome_version": version,
        "name": multiscale.get("name"),
        "axes": multiscale["axes"],
        "volcast": (multiscale.get("metadata") or {}).get("volcast"),
        "levels": [],
    }
    arrays = []
    for dataset in multiscale["datasets"]:
        a = root[dataset["path"]]
        data = a[...]
        arrays.append(data)
        t = transforms(dataset)
        flat = data.astype(np.float64).ravel()
        level = {
            "path": dataset["path"],
            "shape": list(a.shape),
            "dtype": str(a.dtype),
            "chunks": list(a.chunks),
            "shards": list(a.shards) if getattr(a, "shards", None) else None,
            "compressors": [type(c).__name__ for c in a.compressors],
            "scale": t.get("scale"),
            "translation": t.get("translation"),
            "sum": float(flat.sum()),
            "first": [float(v) for v in flat[:4]],
            "last": float(flat[-1]),
        }
        result["levels"].append(level)
        if dump:
            k = dataset["path"]
            with open(os.path.join(dump, f"level{k}.f64"), "wb") as f:
                f.write(flat.astype("<f8").tobytes())

    reader = Reader(parse_url(path, mode="r"))
    images = [n for n in reader() if n.load(Multiscales)]
    node = images[0]
    result["ome_zarr_py"] = {
        "levels": len(node.data),
        "axes": [a["name"] if isinstance(a, dict) else a for a in node.metadata.get("axes", [])],
        "shapes": [list(d.shape) for d in node.data],
        "transforms": node.metadata.get("coordinateTransformations"),
        "name": node.metadata.get("name"),
        "data_equal": all(np.array_equal(np.asarray(d), a, equal_nan=True) for d, a in zip(node.data, arrays)),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
