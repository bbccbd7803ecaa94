#!/usr/bin/env python3
"""Compare two results.h5 files strictly: exit 0 when equal, 1 with the differences listed, 2 on bad input.

usage: results_equal.py A.h5 B.h5

Equal means: the same groups and datasets at the same paths; every dataset of the same dtype,
shape and bytes (bit-for-bit, so NaNs compare by their bits); every attribute with the same
value (numbers bit-for-bit, strings exactly). Two attributes are provenance, not results, and
are left out: the root `created_by` (which program wrote the file: a local sweep or a merge)
and each run's `evidence_wall_s` (the run's wall-clock seconds). Reads the files with h5py,
independently of the project's own reader.
"""
import sys

import h5py
import numpy as np

IGNORED_ATTRS = {("/", "created_by")}
IGNORED_RUN_ATTRS = {"evidence_wall_s"}


def ignored(path, name):
    if (path, name) in IGNORED_ATTRS:
        return True
    parts = path.strip("/").split("/")
    return len(parts) == 2 and parts[0] == "runs" and name in IGNORED_RUN_ATTRS


def same_value(a, b):
    if isinstance(a, bytes):
        a = a.decode()
    if isinstance(b, bytes):
        b = b.decode()
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def objects(f):
    """Every path in the file with its kind ('group' or 'dataset'), the root included."""
    found = {"/": "group"}
    f.visititems(lambda name, obj: found.__setitem__("/" + name, "dataset" if isinstance(obj, h5py.Dataset) else "group"))
    return found


def compare(fa, fb):
    diffs, counts = [], {"datasets": 0, "attributes": 0}
    oa, ob = objects(fa), objects(fb)
    for p in sorted(set(oa) ^ set(ob)):
        diffs.append(f"{p}: only in {'A' if p in oa else 'B'}")
    for p in sorted(set(oa) & set(ob)):
        if oa[p] != ob[p]:
            diffs.append(f"{p}: a {oa[p]} in A, a {ob[p]} in B")
            continue
        a, b = fa[p], fb[p]
        names_a = {n for n in a.attrs if not ignored(p, n)}
        names_b = {n for n in b.attrs if not ignored(p, n)}
        for n in sorted(names_a ^ names_b):
            diffs.append(f"{p} attribute {n}: only in {'A' if n in names_a else 'B'}")
        for n in sorted(names_a & names_b):
            counts["attributes"] += 1
            if not same_value(a.attrs[n], b.attrs[n]):
                diffs.append(f"{p} attribute {n}: {a.attrs[n]!r} != {b.attrs[n]!r}")
        if oa[p] == "dataset":
            counts["datasets"] += 1
            if a.dtype != b.dtype or a.shape != b.shape:
                diffs.append(f"{p}: dtype/shape {a.dtype}{a.shape} != {b.dtype}{b.shape}")
                continue
            da, db = a[()], b[()]
            if not same_value(da, db):
                if da.dtype.kind == "f":
                    n = int(np.sum(np.asarray(da) != np.asarray(db)))
                    diffs.append(f"{p}: {n} of {da.size} values differ, max |A-B| = {np.nanmax(np.abs(da - db))}")
                else:
                    diffs.append(f"{p}: contents differ")
    return diffs, counts


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    try:
        fa, fb = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
    except OSError as e:
        print(f"results_equal: {e}", file=sys.stderr)
        return 2
    with fa, fb:
        diffs, counts = compare(fa, fb)
        runs = len(fa["runs"]) if "runs" in fa else 0
    for d in diffs:
        print(f"results_equal: {d}")
    if diffs:
        print(f"results_equal: {sys.argv[1]} and {sys.argv[2]} differ ({len(diffs)} differences)")
        return 1
    print(f"results_equal: equal ({runs} runs, {counts['datasets']} datasets, {counts['attributes']} attributes; created_by and evidence_wall_s not compared)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
