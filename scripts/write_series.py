#!/usr/bin/env python3
"""Writes a volume time series, for tests/apps/time_series_test.sh and bench/timeseries.sh.

  write_series.py DIR STEPS NX NY NZ [--bad-dims STEP]

DIR/step-00.nrrd .. : raw little-endian float32 NRRD, NX x NY x NZ voxels: a blob that moves
across the grid and grows step by step, over a slow ramp, so every step renders differently.
With --bad-dims STEP, that step's file has one more voxel along x (a series whose dims change).
"""
import sys

import numpy as np


def step_volume(k, steps, nx, ny, nz):
    z, y, x = np.meshgrid(np.linspace(-1, 1, nz), np.linspace(-1, 1, ny), np.linspace(-1, 1, nx),
                          indexing="ij")
    t = k / max(steps - 1, 1)
    cx, cy = -0.5 + t, 0.3 * np.sin(3 * t)
    blob = np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + z ** 2) / (2 * (0.25 + 0.1 * t) ** 2))
    return (100 * blob + 20 * (x + 1) + 5 * k).astype("<f4")


def write_nrrd(path, volume):
    nz, ny, nx = volume.shape
    with open(path, "wb") as f:
        f.write(("NRRD0004\ntype: float\ndimension: 3\nsizes: %d %d %d\nencoding: raw\n"
                 "endian: little\nspacings: 1 1 1\n\n" % (nx, ny, nz)).encode())
        f.write(volume.tobytes())


def main():
    folder, steps = sys.argv[1], int(sys.argv[2])
    nx, ny, nz = (int(v) for v in sys.argv[3:6])
    bad = int(sys.argv[7]) if len(sys.argv) > 7 and sys.argv[6] == "--bad-dims" else -1
    for k in range(steps):
        write_nrrd("%s/step-%02d.nrrd" % (folder, k),
                   step_volume(k, steps, nx + (1 if k == bad else 0), ny, nz))


main()
