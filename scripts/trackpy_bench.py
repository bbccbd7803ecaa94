#!/usr/bin/env python3
"""trackpy beside `rbc-bench analyze`: locate and link the cells of one recording, timed.

Usage: trackpy_bench.py RECORDING_DIR OUT_CSV [--diameter-um 7.0] [--search-um 35.0] [--memory 2]

Reads the frames (PNG/TIFF, file-name order) and recording.toml (fps, um_per_px) of a
recording folder, runs trackpy.batch (locate) and trackpy.link on the inverted images
(cells are dark on a bright background), writes the located features to OUT_CSV
(columns frame, x_px, y_px, particle; trackpy's pixel coordinates, pixel centres at integers),
and prints one JSON line: {"frames", "features", "tracks", "read_s", "locate_s", "link_s"}.
Only the locate and link times are compared with rbc-analyze (reading the frames is
reported separately). Requires: pip install trackpy
"""
import argparse
import json
import pathlib
import sys
import time
import tomllib

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("recording")
    ap.add_argument("out_csv")
    ap.add_argument("--diameter-um", type=float, default=7.0, help="feature diameter for trackpy.locate, um")
    ap.add_argument("--search-um", type=float, default=35.0, help="linking search range per frame, um")
    ap.add_argument("--memory", type=int, default=2, help="frames a particle may vanish and be linked again")
    args = ap.parse_args()

    import pandas as pd
    import trackpy as tp
    from PIL import Image

    rec = pathlib.Path(args.recording)
    cfg = tomllib.loads((rec / "recording.toml").read_text())
    um_per_px = float(cfg["um_per_px"])
    files = sorted(p for p in rec.iterdir() if p.suffix.lower() in (".png", ".tif", ".tiff"))
    if not files:
        sys.exit(f"{rec}: no frames")

    t0 = time.perf_counter()
    frames = []
    for p in files:
        a = np.asarray(Image.open(p), dtype=np.float64)
        frames.append(a.max() - a)  # invert: dark cells become bright features
    t1 = time.perf_counter()

    d = int(round(args.diameter_um / um_per_px)) | 1  # trackpy wants an odd diameter in px
    tp.quiet()
    f = tp.batch(frames, d, invert=False, processes=1)
    t2 = time.perf_counter()
    t = tp.link(f, search_range=args.search_um / um_per_px, memory=args.memory)
    t3 = time.perf_counter()

    out = pd.DataFrame({"frame": t["frame"], "x_px": t["x"], "y_px": t["y"], "particle": t["particle"]})
    out.to_csv(args.out_csv, index=False)
    print(json.dumps({
        "frames": len(frames),
        "features": int(len(t)),
        "tracks": int(t["particle"].nunique()) if len(t) else 0,
        "read_s": t1 - t0,
        "locate_s": t2 - t1,
        "link_s": t3 - t2,
    }))


if __name__ == "__main__":
    main()
