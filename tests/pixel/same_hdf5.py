"""Exits 0 when two HDF5 files hold the same groups, datasets and attributes (names, dtypes,
shapes, chunking, compression and every value's bytes), else prints the first difference and
exits 1 (tests/pixel_dataset_test.cc: merged shards against the whole run).

usage: same_hdf5.py A.hdf5 B.hdf5
"""
import sys

import h5py
import numpy as np


def attrs(obj):
    return {k: (v.tobytes() if isinstance(v, np.ndarray) else v) for k, v in obj.attrs.items()}


def walk(a, b, path):
    if attrs(a) != attrs(b):
        return f"{path}: attributes differ"
    if isinstance(a, h5py.Group) != isinstance(b, h5py.Group):
        return f"{path}: a group in one file only"
    if isinstance(a, h5py.Group):
        if sorted(a.keys()) != sorted(b.keys()):
            return f"{path}: members {sorted(a.keys())} against {sorted(b.keys())}"
        for k in a:
            why = walk(a[k], b[k], f"{path}/{k}")
            if why:
                return why
        return None
    for what in ("dtype", "shape", "chunks", "compression", "compression_opts", "maxshape"):
        if getattr(a, what) != getattr(b, what):
            return f"{path}: {what} {getattr(a, what)} against {getattr(b, what)}"
    x, y = a[()], b[()]
    if x.dtype == object:
        same = len(x) == len(y) and all(p.tobytes() == q.tobytes() for p, q in zip(x, y))
    else:
        same = x.tobytes() == y.tobytes()
    return None if same else f"{path}: values differ"


why = walk(h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r"), "")
print(why or "same")
sys.exit(1 if why else 0)
