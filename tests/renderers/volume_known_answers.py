#!/usr/bin/python3
"""Known answers on the real files Debian ships: voxel values of the Colin27 head (ch2.nii.gz,
mricron-data) read here with gzip + struct from NIfTI-1's documented layout (348-byte header,
vox_offset 352, uint8, x fastest), and of the Levitus ocean temperature (ferret-datasets) read
here with netCDF4, equal what dfbwall reads, from the whole grid and from a brick around each
voxel; the land's missing value is NaN and out of dfbwall's value range.
    volume_known_answers.py PATH/TO/volume_probe"""
import gzip
import math
import struct
import subprocess
import sys

import netCDF4
import numpy

probe = sys.argv[1]


def dfbwall_values(path, name, points):
    args = [probe, path, name] + [str(c) for p in points for c in p]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split('\n')
    # %.9g round-trips a float32: compare as float32.
    pairs = [tuple(float(numpy.float32(v)) for v in line.split()) for line in out[:len(points)]]
    rng = tuple(float(numpy.float32(v)) for v in out[len(points)].split()[1:])
    return pairs, rng


def check(label, expected, pairs):
    for (i, j, k), want, (whole, brick) in zip(points, expected, pairs):
        same = (math.isnan(want) and math.isnan(whole) and math.isnan(brick)) or \
               (want == whole == brick)
        assert same, f'{label} voxel {(i, j, k)}: expected {want}, whole read {whole}, brick {brick}'


# ch2.nii.gz: 181 x 217 x 181 uint8.
head = '/usr/share/mricron/templates/ch2.nii.gz'
raw = gzip.open(head).read()
assert struct.unpack('<i', raw[:4])[0] == 348
dims = struct.unpack('<3h', raw[42:48])
assert dims == (181, 217, 181), dims
offset = int(struct.unpack('<f', raw[108:112])[0])
points = [(90, 108, 90), (0, 0, 0), (180, 216, 180), (45, 150, 120), (120, 60, 30), (91, 20, 100),
          (60, 108, 150)]
expected = [float(raw[offset + (k * dims[1] + j) * dims[0] + i]) for i, j, k in points]
assert len(set(expected)) > 3, f'points should hit different tissue: {expected}'
pairs, rng = dfbwall_values(head, '-', points)
check('ch2.nii.gz', expected, pairs)
values = numpy.frombuffer(raw, dtype=numpy.uint8, offset=offset)
assert rng == (float(values.min()), float(values.max())), rng
print(f'ch2.nii.gz: {len(points)} voxels equal ({expected}), range {rng}')

# Levitus TEMP: (depth 20, lat 180, lon 360) float32, land = -1e10.
ocean = '/usr/share/ferret-vis/data/levitus_climatology.cdf'
data = netCDF4.Dataset(ocean)
temp = data.variables['TEMP']
temp.set_auto_mask(False)
t = temp[:]
fill = temp.getncattr('_FillValue')
points = [(0, 90, 0), (200, 90, 0), (330, 60, 5), (160, 100, 19), (30, 170, 2), (100, 45, 10),
          (280, 110, 0)]
expected = [float('nan') if t[k, j, i] == fill else float(t[k, j, i]) for i, j, k in points]
assert sum(math.isnan(v) for v in expected) >= 1 and sum(not math.isnan(v) for v in expected) >= 4
pairs, rng = dfbwall_values(ocean, 'TEMP', points)
check('levitus TEMP', expected, pairs)
sea = t[t != fill]
assert rng == (float(sea.min()), float(sea.max())), (rng, sea.min(), sea.max())
print(f'levitus TEMP: {len(points)} voxels equal ({expected}), range {rng} without the land')
