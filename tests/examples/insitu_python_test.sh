#!/usr/bin/env bash
# examples/insitu.py and the `dfbwall` Python module: installed under a fresh prefix, the example
# on 3 ranks renders the C++ example's image byte for byte (the same grid and steps); from the
# build tree, input the session refuses (a wrong dtype on one rank) is a dfbwall.InputError on
# every rank, after which the session renders; borrowed arrays render as copied ones, add no copy
# to the rank's peak memory, show values changed in place after data_changed() and are let go
# once replaced; and a rank that leaves without close() makes the others raise at once, naming it.
# Environment: BUILD, SOURCE, MPIEXEC, PYTHON (the interpreter the module was built for), INSITU
# (the C++ example built by example_insitu_installed is not shared: this builds its own).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d /tmp/dfbwall-insitu-py.XXXXXX)
trap 'rm -rf "$work"' EXIT
start=$SECONDS

cmake --install "$BUILD" --prefix "$work/prefix" >/dev/null
site=$(ls -d "$work"/prefix/lib*/python3*/site-packages)
ls "$site"/dfbwall*.so >/dev/null
cxx=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
launcher=$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
cmake -S "$SOURCE/examples/insitu" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$cxx" \
  ${launcher:+-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher} >/dev/null
cmake --build "$work/build" -j2 >/dev/null

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1 --size 320x240)
timeout 120 "$MPIEXEC" -np 1 "$work/build/insitu" "${args[@]}" --image "$work/cpp.png" >/dev/null
PYTHONPATH=$site timeout 120 "$MPIEXEC" -np 3 "$PYTHON" "$SOURCE/examples/insitu.py" "${args[@]}" \
  --image "$work/py.png"
cmp "$work/cpp.png" "$work/py.png"
echo "examples/insitu.py on 3 ranks renders the C++ example's image byte for byte"

# From the build tree: errors as exceptions on every rank, and numpy in and out.
cat >"$work/errors.py" <<'PY'
import gc, sys, time, weakref
import numpy as np
from mpi4py import MPI
import dfbwall

rank = MPI.COMM_WORLD.Get_rank()
s = dfbwall.Session(MPI.COMM_WORLD, width=64, height=48, tile_size=16, threads=1, timeout=60)
s.set_style({"volumes": [{"dims": (16, 16, 16), "origin": (0, 0, 0), "spacing": (1, 1, 1)}],
             "seed": 3})
s.set_camera((30, 20, -30), look_at=(7.5, 7.5, 7.5))
field = np.fromfunction(lambda z, y, x: np.sin(x / 3) + np.cos(y / 4) + z / 16, (16, 16, 16))
def add(dtype):
    s.clear_bricks()
    if rank == 0:
        s.add_brick(0, (0, 0, 0), (15, 15, 15), volumes=[((0, 0, 0), field.astype(dtype))])
add(np.complex64 if rank == 0 else np.float32)
try:
    s.render_frame()
    sys.exit("rank %d: no error" % rank)
except dfbwall.InputError as e:
    assert "render rank 0 refused its input: brick 0: voxels of dtype complex64" in str(e), str(e)
    assert isinstance(e, ValueError)
add(np.float32)
s.render_frame()
image = s.image()
if rank == 0:
    assert image.shape == (48, 64, 4) and image.dtype == np.uint8, (image.shape, image.dtype)
    assert len(np.unique(image.reshape(-1, 4), axis=0)) > 20, "a blank image"
else:
    assert image is None

# Borrowed voxels: a float32 array is read in place (the session holds the array, not a copy),
# renders the copy's image, and values changed in place show after data_changed(), as a fresh
# copy of them renders; the session lets the array go once a frame replaced its brick.
def frame(volume, copy):
    s.clear_bricks()
    if rank == 0:
        s.add_brick(0, (0, 0, 0), (15, 15, 15), volumes=[((0, 0, 0), volume)], copy=copy)
    s.render_frame()
    return s.image()
u = np.ascontiguousarray(field, dtype=np.float32)
copied = frame(u, True)
if rank == 0:
    held = s.scene_bytes
    assert s.borrowed_bytes == 0
borrowed = frame(u, False)
if rank == 0:
    assert (borrowed == copied).all(), "borrowed voxels render another image"
    assert s.borrowed_bytes == u.nbytes, (s.borrowed_bytes, u.nbytes)
    assert s.scene_bytes + u.nbytes <= held, (s.scene_bytes, held)
u *= 0.5
u += np.float32(0.3) * np.sin(u * 7)
s.data_changed()
s.render_frame()
changed = s.image()
fresh = frame(u, True)
if rank == 0:
    assert not (changed == borrowed).all(), "the changed values do not show"
    assert (changed == fresh).all(), "the changed values render another image than their copy"
temporary = np.ascontiguousarray(field[::-1], dtype=np.float32)
alive = weakref.ref(temporary)
frame(temporary, False)
del temporary
gc.collect()
assert alive() is not None or rank != 0, "the session let a borrowed array go"
frame(u, True)
gc.collect()
assert alive() is None, "the session holds an array it no longer reads"
# A 32 MiB array borrowed on rank 0: its peak memory grows by under a tenth of that.
big = np.random.default_rng(rank).random((128, 256, 256), dtype=np.float32)
def kb(key):
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) for l in f if l.startswith(key + ":"))
big_style = {"volumes": [{"dims": (256, 256, 128)}], "seed": 3}
s.set_style(big_style)
s.clear_bricks()
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")
before = kb("VmRSS")
if rank == 0:
    s.add_brick(0, (0, 0, 0), (255, 255, 127), volumes=[((0, 0, 0), big)])
s.render_frame()
grown = (kb("VmHWM") - before) * 1024
assert grown < big.nbytes / 10, "rank %d: peak RSS grew by %d bytes" % (rank, grown)
if rank == 0:
    assert s.borrowed_bytes == big.nbytes and s.scene_bytes < big.nbytes / 10, s.scene_bytes
# Rank 2 leaves without close(); the others' next frame raises at once, naming it.
if rank == 2:
    s.release()
    sys.exit(0)
began = time.monotonic()
try:
    s.render_frame()
    sys.exit("rank %d: no error after rank 2 left" % rank)
except RuntimeError as e:
    assert "rank 2 (" in str(e) and "left without closing" in str(e), str(e)
    assert time.monotonic() - began < 10, time.monotonic() - began
s.release()
print("rank %d: errors raised as they should" % rank)
PY
PYTHONPATH=$BUILD/python timeout 60 "$MPIEXEC" -np 3 "$PYTHON" "$work/errors.py"
echo "PASS in $((SECONDS - start)) s"
