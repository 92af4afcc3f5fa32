"""The in-situ frame of bench/insitu_languages.py from Python (the dfbwall module, numpy): the
frame of InsituFrameBench.cpp, call for call (the slab borrowed from a numpy array), its JSON
line with "language": "python".
  mpirun -np R python3 insitu_frame_bench.py GRID FRAMES WIDTHxHEIGHT IMAGE.png"""
import json
import math
import sys
import time

import numpy as np
from mpi4py import MPI

import dfbwall


def main():
    g, frames = int(sys.argv[1]), int(sys.argv[2])
    width, height = (int(v) for v in sys.argv[3].split("x"))
    rank, ranks = MPI.COMM_WORLD.Get_rank(), MPI.COMM_WORLD.Get_size()
    z0, z1 = (g - 1) * rank // ranks, (g - 1) * (rank + 1) // ranks
    lo, hi = max(0, z0 - 2), min(g, z1 + 4)
    c = (g - 1) / 2.0
    z, y, x = np.meshgrid(np.arange(lo, hi), np.arange(g), np.arange(g), indexing="ij")
    u = (((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2) / (3 * c * c)).astype(np.float32)
    s = dfbwall.Session(MPI.COMM_WORLD, width=width, height=height, threads=1, timeout=120)
    s.set_style({"volumes": [{"dims": (g, g, g), "transfer_function": "viridis",
                              "max_opacity": 0.05, "range": (0, 1)}],
                 "isosurfaces": [{"volume": 0, "value": 0.3, "color": (1.0, 0.85, 0.4)}],
                 "seed": 7})
    ms, cpu, calls = [], [], []
    for f in range(frames):
        a, r = 0.1 * f, 2.2 * g
        s.set_camera((c + r * math.sin(a), c + 0.5 * r, c - r * math.cos(a)), look_at=(c, c, c),
                     fov_y=40)
        t0, c0 = time.perf_counter(), time.process_time()
        s.clear_bricks()
        s.add_brick(rank, (0, 0, z0), (g - 1, g - 1, z1), volumes=[((0, 0, lo), u)])
        calls.append((time.perf_counter() - t0) * 1e3)
        s.render_frame()
        ms.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    s.write_image(sys.argv[4])
    s.close()
    if rank == 0:
        print(json.dumps({"language": "python", "frame_ms": ms, "cpu_ms": cpu, "calls_ms": calls}))


main()
