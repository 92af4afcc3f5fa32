#!/usr/bin/env python3
"""examples/insitu in Python: the same heat-equation simulation (numpy slabs, the stencil's ghost
planes exchanged with mpi4py), the same flags, the same pixels, through the `dfbwall` module,
which exchanges the renderer's ghosts itself (add_brick(..., ghosts="exchange")).

  mpirun -np 6 python3 insitu.py --wall 2x2.toml --capture caps    # 2 simulating, 4 wall ranks
  mpirun -np 2 python3 insitu.py --size 400x300 --image last.png   # no wall: the last frame
  mpirun -np 2 python3 insitu.py --connect wall0:7000 --token-file F

The module: <prefix>/lib/python3.X/site-packages (installed) or <build>/python, on PYTHONPATH.
"""
import argparse
import sys

import numpy as np
from mpi4py import MPI

import dfbwall

GHOST = 1  # planes each side for the stencil (the renderer's ghosts: the session's)
F = np.float32


def parse():
    p = argparse.ArgumentParser(prog="insitu.py")
    p.add_argument("--grid", type=int, default=48)
    p.add_argument("--blocks", type=int, default=4)
    p.add_argument("--steps", type=int, default=40)
    p.add_argument("--show-every", type=int, default=10)
    p.add_argument("--wall", default="")
    p.add_argument("--windows", action="store_true")
    p.add_argument("--capture", default="")
    p.add_argument("--connect", default="")
    p.add_argument("--token-file", default="")
    p.add_argument("--server-key", default="")
    p.add_argument("--codec", default="snappy")
    p.add_argument("--wait", action="store_true")
    p.add_argument("--window", default="")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--size", default="800x600")
    p.add_argument("--image", default="")
    a = p.parse_args()
    try:
        a.width, a.height = (int(v) for v in a.size.split("x"))
    except ValueError:
        p.error("--size wants WxH")
    if a.grid < 8 or a.blocks < 1 or a.steps < 1 or a.show_every < 1:
        p.error("bad numbers")
    return a


class Slab:
    """Planes [z0, z1) of the N^3 grid, with GHOST planes either side, indexed [z, y, x]."""

    def __init__(self, sid, n, blocks):
        self.id, self.z0, self.z1 = sid, n * sid // blocks, n * (sid + 1) // blocks
        self.u = np.zeros((self.z1 - self.z0 + 2 * GHOST, n, n), dtype=F)
        h = F(2.0) / F(n - 1)
        z, y, x = np.meshgrid(np.arange(self.z0, self.z1), np.arange(n), np.arange(n),
                              indexing="ij")
        px, py, pz = (F(-1) + h * c.astype(F) for c in (x, y, z))
        a = (px - F(0.35)) * (px - F(0.35)) + py * py + (pz + F(0.3)) * (pz + F(0.3))
        b = (px + F(0.4)) * (px + F(0.4)) + (py - F(0.3)) * (py - F(0.3)) + \
            (pz - F(0.35)) * (pz - F(0.35))
        # exp in float64 rounded to float32: what the C library's expf gives the C++ example.
        ea = np.exp((-a / F(0.04)).astype(np.float64)).astype(F)
        eb = np.exp((-b / F(0.08)).astype(np.float64)).astype(F)
        self.u[GHOST:GHOST + self.z1 - self.z0] = ea + F(0.8) * eb

    def owned(self, array):
        return array[GHOST:GHOST + self.z1 - self.z0]


def exchange_ghosts(mine, blocks, comm):
    ranks = comm.Get_size()
    requests = []
    for s in mine:
        owned = s.z1 - s.z0
        if s.id > 0:
            peer = (s.id - 1) % ranks
            requests.append(comm.Irecv(s.u[:GHOST], source=peer, tag=2 * s.id))
            requests.append(comm.Isend(s.u[GHOST:2 * GHOST], dest=peer, tag=2 * (s.id - 1) + 1))
        if s.id + 1 < blocks:
            peer = (s.id + 1) % ranks
            requests.append(comm.Irecv(s.u[GHOST + owned:], source=peer, tag=2 * s.id + 1))
            requests.append(comm.Isend(s.u[owned:owned + GHOST], dest=peer, tag=2 * (s.id + 1)))
    MPI.Request.Waitall(requests)


def step(s, n):
    """u_t = laplace(u), r = 0.15; the faces stay cold, the source hot: every voxel computed as
    the C++ example computes it, in the same order of float32 operations."""
    u, r = s.u, F(0.15)
    nxt = u.copy()
    lo, hi = max(s.z0, 1), min(s.z1, n - 1)
    if lo < hi:
        z = slice(lo - s.z0 + GHOST, hi - s.z0 + GHOST)
        zm = slice(lo - s.z0 + GHOST - 1, hi - s.z0 + GHOST - 1)
        zp = slice(lo - s.z0 + GHOST + 1, hi - s.z0 + GHOST + 1)
        i, m, p = slice(1, n - 1), slice(0, n - 2), slice(2, n)
        c = u[z, i, i]
        total = u[z, i, m] + u[z, i, p] + u[z, m, i] + u[z, p, i] + u[zm, i, i] + u[zp, i, i]
        nxt[z, i, i] = c + r * (total - F(6) * c)
    owned = s.owned(nxt)
    owned[:, 0, :] = 0
    owned[:, n - 1, :] = 0
    owned[:, :, 0] = 0
    owned[:, :, n - 1] = 0
    if s.z0 == 0:
        owned[0] = 0
    if s.z1 == n:
        owned[-1] = 0
    c0, rad = n // 2, max(1, n // 16)
    for zz in range(max(s.z0, c0 - rad), min(s.z1, c0 + rad + 1)):
        nxt[zz - s.z0 + GHOST, n // 4 - rad:n // 4 + rad + 1, c0 - rad:c0 + rad + 1] = 1
    s.u = nxt


def add_slab(session, s, n):
    """The slab as a brick: clipped to its own planes, voxels the planes it owns, handed over as a
    view of the simulation's array; the session exchanges the ghosts its renderer reads."""
    h = F(2.0) / F(n - 1)
    session.add_brick(s.id, (-1, -1, F(-1) + h * F(s.z0)),
                      (1, 1, F(-1) + h * F(min(s.z1, n - 1))),
                      volumes=[((0, 0, s.z0), s.owned(s.u))], ghosts="exchange")


def style(n):
    h = float(F(2.0) / F(n - 1))
    return {
        "volumes": [{"name": "temperature", "dims": (n, n, n), "origin": (-1, -1, -1),
                     "spacing": (h, h, h), "transfer_function": "inferno", "range": (0, 1),
                     "max_opacity": 0.5}],
        "isosurfaces": [{"volume": 0, "value": 0.1, "color": (0.3, 0.6, 1.0), "opacity": 0.3},
                        {"volume": 0, "value": 0.4, "color": (1.0, 0.85, 0.4), "opacity": 1.0}],
        "background": (0.005, 0.005, 0.01),
        "seed": 7,
    }


def main():
    a = parse()
    session = dfbwall.Session(MPI.COMM_WORLD, width=a.width, height=a.height, wall=a.wall,
                              offscreen=not a.windows, capture=a.capture, threads=a.threads,
                              connect=a.connect, window=a.window, token_file=a.token_file,
                              server_key=a.server_key, codec=a.codec, wait=a.wait)
    if session.is_wall_rank:
        session.run_wall()  # until the simulation's ranks close the session
        return 0
    sim = session.render_comm
    rank, ranks, n = sim.Get_rank(), sim.Get_size(), a.grid
    if n // a.blocks < GHOST:
        if rank == 0:
            print(f"insitu.py: slabs under {GHOST} planes thick", file=sys.stderr)
        return 2
    mine = [Slab(b, n, a.blocks) for b in range(rank, a.blocks, ranks)]
    session.set_style(style(n))
    session.set_camera((1.7, 1.2, -2.0), look_at=(0, 0, 0), fov_y=40)
    exchange_ghosts(mine, a.blocks, sim)
    for t in range(1, a.steps + 1):
        for s in mine:
            step(s, n)
        exchange_ghosts(mine, a.blocks, sim)
        if t % a.show_every:
            continue
        session.clear_bricks()
        for s in mine:
            add_slab(session, s, n)
        session.render_frame()
        if rank == 0:
            print(f"step {t} shown (frame {session.frames_rendered})", flush=True)
    if rank == 0:
        print(f"brick data on rank 0: {session.scene_bytes} bytes")
    if a.image:
        session.write_image(a.image)
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
