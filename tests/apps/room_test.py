#!/usr/bin/python3
"""Screens in a room (docs/rooms.md), end to end on the offscreen wall with real MPI ranks.

  room_test.py LAYOUT RENDER_RANKS CHECKS [dfbwall options...]

Renders LAYOUT on the wall (RENDER_RANKS render ranks and its wall processes, --capture), then
runs the checks named in CHECKS (comma-separated) on the captures of the last frame:
  views      every display's capture equals `dfbwall --view DISPLAY,... --image` (one process,
             no wall, every display at once) byte for byte;
  pinhole    the captures put together at their canvas places equal a pinhole render of the
             canvas (--size, the scene's field of view) within TOLERANCE below: the wall is flat,
             its head centred, and the scene's field of view matches it;
  disparity  a passive-stereo wall (left-eye displays' canvas, then the right eye's beside it) of
             tests/apps/room-spheres.toml: the red sphere on the screen plane has zero disparity
             between the eyes, the green one behind it positive, the blue one in front negative,
             each within half a pixel of what the geometry predicts.
Needs DFBWALL, COMPARE (compare_captures) and MPIEXEC in the environment.
"""
import atexit
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

# pinhole: the share of canvas pixels allowed to differ, and by how much at most elsewhere. The
# room's ray (eye to the pixel's point on the screen) and the pinhole's (forward + right * sx +
# up * sy) are the same direction rounded differently in float: a pixel whose ray grazes a
# sphere's edge may land on the other side. Measured on tests/apps/room-plane.toml and
# room-spheres.toml: 0 of 30000 pixels differ, for the path tracer (2 frames of 2 jittered
# samples) and for the primary renderer; allowed: 0.2 %.
PINHOLE_DIFFERING_SHARE = 0.002

env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def run(args):
    result = subprocess.run(args, env=env, capture_output=True, text=True, timeout=100)
    if result.returncode != 0:
        fail(" ".join(args) + " exited " + str(result.returncode) + "\n" + result.stdout +
             result.stderr)
    return result.stdout


def mpi(ranks, args):
    return run([env["MPIEXEC"], "-n", str(ranks), "--oversubscribe", "--bind-to", "none",
                env["DFBWALL"]] + args)


def pixels(path):
    return np.asarray(Image.open(path).convert("RGBA"))


def main():
    layout, renders, checks, options = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(","), \
        sys.argv[4:]
    processes, canvas = run([env["COMPARE"], "--info", layout]).split()
    displays = {}
    for line in run([env["COMPARE"], "--displays", layout]).splitlines():
        name, x, y, w, h = line.split()
        displays[name] = (int(x), int(y), int(w), int(h))
    width, height = (int(v) for v in canvas.split("x"))
    frames = options[options.index("--frames") + 1] if "--frames" in options else "1"
    work = tempfile.mkdtemp()
    atexit.register(shutil.rmtree, work, True)
    mpi(renders + int(processes), ["--wall", layout, "--offscreen", "--capture", work + "/cap",
                                   "--quiet"] + options)
    captures = {name: pixels(f"{work}/cap/{name}/frame-{int(frames):06d}.png")
                for name in displays}
    wall = np.zeros((height, width, 4), np.uint8)
    for name, (x, y, w, h) in displays.items():
        wall[y:y + h, x:x + w] = captures[name]
    if len({captures[n].tobytes() for n in displays}) < 2 and len(displays) > 1:
        fail("every display captured the same picture: nothing to compare")

    if "views" in checks:
        mpi(1, ["--wall", layout, "--view", ",".join(displays), "--image",
                 work + "/view-{display}.png", "--quiet"] + options)
        for name in displays:
            view = pixels(f"{work}/view-{name}.png")
            if view.shape != captures[name].shape or not np.array_equal(view, captures[name]):
                differ = np.count_nonzero(np.any(view != captures[name], axis=-1)) \
                    if view.shape == captures[name].shape else "all"
                fail(f"display {name}: the capture differs from --view in {differ} pixels")
        print(f"views: {len(displays)} displays' captures equal --view byte for byte")

    if "pinhole" in checks:
        mpi(1, ["--size", canvas, "--image", f"{work}/pinhole.png", "--quiet"] + options)
        pinhole = pixels(f"{work}/pinhole.png")
        shown = np.zeros((height, width), bool)
        for x, y, w, h in displays.values():
            shown[y:y + h, x:x + w] = True
        differ = np.any(wall != pinhole, axis=-1) & shown
        share = np.count_nonzero(differ) / np.count_nonzero(shown)
        print(f"pinhole: {np.count_nonzero(differ)} of {np.count_nonzero(shown)} pixels differ "
              f"({100 * share:.3f} %, allowed {100 * PINHOLE_DIFFERING_SHARE} %)")
        if share > PINHOLE_DIFFERING_SHARE:
            fail("the flat wall with the head centred is not the pinhole image")

    if "disparity" in checks:
        half = width // 2
        eyes = {"left": wall[:, :half, :3].astype(int), "right": wall[:, half:, :3].astype(int)}
        # Pixels per metre on the screen, and the geometry of configs/walls/stereo-2x2.toml and
        # tests/apps/room-spheres.toml: the screen 2 m away, eyes 0.065 m apart.
        per_metre, screen, separation = half / 2.0, 2.0, 0.065
        spheres = {"red (on the screen)": (0, 2.0), "green (behind)": (1, 4.0),
                   "blue (in front)": (2, 1.2)}
        for name, (channel, depth) in spheres.items():
            centres = {}
            for eye, image in eyes.items():
                others = [c for c in range(3) if c != channel]
                mask = (image[..., channel] > 128) & (image[..., others[0]] < 64) & \
                    (image[..., others[1]] < 64)
                if np.count_nonzero(mask) < 20:
                    fail(f"{name}: only {np.count_nonzero(mask)} pixels in the {eye} eye")
                centres[eye] = np.nonzero(mask)[1].mean()
            disparity = centres["right"] - centres["left"]
            expected = separation * (1 - screen / depth) * per_metre
            print(f"disparity: {name}: {disparity:+.2f} px (geometry: {expected:+.2f} px)")
            if abs(disparity - expected) > 0.5:
                fail(f"{name}: disparity {disparity:.2f} px, expected {expected:.2f} px")
            if depth > screen and not disparity > 1:
                fail(f"{name}: behind the screen but disparity {disparity:.2f} px is not positive")
            if depth < screen and not disparity < -1:
                fail(f"{name}: in front of the screen but disparity {disparity:.2f} px is not "
                     "negative")


main()
