#!/usr/bin/env python3
"""Times pydelatin (Delatin greedy TIN, C++) on a DEM; prints one JSON line per max error.

usage: tin_pydelatin.py KIND PATH[,PATH...] RUNS ERR [ERR...]
  KIND: png16 (height = v * 0.1) or terrain-rgb (height = -10000 + (R*65536+G*256+B)*0.1;
  four paths = a 2x2 mosaic NW, NE, SW, SE). Errors are in metres (the heights' unit).
"""
import json
from importlib.metadata import version
import statistics
import sys
import time

import numpy as np
from PIL import Image
from pydelatin import Delatin


def load(kind, paths):
    if kind == "png16":
        return np.asarray(Image.open(paths[0]), dtype=np.float64).astype(np.float32) * np.float32(0.1)
    tiles = []
    for p in paths:
        a = np.asarray(Image.open(p).convert("RGBA"), dtype=np.float64)
        tiles.append((-10000.0 + (a[..., 0] * 65536 + a[..., 1] * 256 + a[..., 2]) * 0.1).astype(np.float32))
    if len(tiles) == 1:
        return tiles[0]
    return np.vstack([np.hstack(tiles[0:2]), np.hstack(tiles[2:4])])


def main():
    kind, paths, runs = sys.argv[1], sys.argv[2].split(","), int(sys.argv[3])
    h = load(kind, paths)
    for err in map(float, sys.argv[4:]):
        times, cpu = [], []
        for _ in range(runs):
            t0, c0 = time.perf_counter(), time.thread_time()
            d = Delatin(h, max_error=err)
            cpu.append(time.thread_time() - c0)
            times.append(time.perf_counter() - t0)
        print(json.dumps({
            "max_error": err,
            "version": version("pydelatin"),
            "width": int(h.shape[1]),
            "height": int(h.shape[0]),
            "median_ms": statistics.median(times) * 1000,
            "median_cpu_ms": statistics.median(cpu) * 1000,
            "triangles": int(len(d.triangles)),
            "vertices": int(len(d.vertices)),
            "measured_error": float(d.error),
        }), flush=True)


if __name__ == "__main__":
    main()
