#!/usr/bin/python3
"""Volume files as other programs write them read as the same voxels as given raw: NIfTI-1 and
NIfTI-2 written by nibabel (.nii, .nii.gz, .hdr/.img pairs, both byte orders), NRRD written by
teem's own `unu` in every encoding (raw, gzip, bzip2, ascii, hex), both byte orders, detached
headers, line and byte skips (-1 too) and lists of data files (LIST and a format string), and VTK
image data written by VTK's own writers (.vti: ascii, base64 and appended raw or base64, zlib
and LZ4 compressed, a chosen array; .pvti pieces). Each file is read whole and in octants by
volume_probe and must equal the field exactly.
    volume_peer_writers.py PATH/TO/volume_probe
With --scene-files FOLDER it writes a smooth 48x40x32 field there instead, as raw float32
(field.raw) and with the peers' tools (field.nii.gz: NIfTI-2, field.nrrd: bzip2, field.nhdr:
ascii), and VTK's wavelet in 4 LZ4 pieces (wavelet.pvti) and raw (wavelet.raw), for
FileFormatsBricksMpiTest to render."""
import gzip
import os
import shutil
import subprocess
import sys
import tempfile

import numpy

scene_files = sys.argv[1] == '--scene-files'
probe = None if scene_files else sys.argv[1]
folder = sys.argv[2] if scene_files else tempfile.mkdtemp(prefix='dfbwall-peer-')
NX, NY, NZ = (48, 40, 32) if scene_files else (13, 9, 7)
k, j, i = numpy.meshgrid(numpy.arange(NZ), numpy.arange(NY), numpy.arange(NX), indexing='ij')
# (z, y, x), x fastest: as dfbwall holds voxels. Integers that fit int16, and exact floats.
field = ((i * 7 + j * 13 + k * 29) % 251 - 120).astype(numpy.int16)
floats = (field.astype(numpy.float32) / 4).astype(numpy.float32)
checked = []


def path(name):
    return os.path.join(folder, name)


def expect(name, want, spacing=None, label=None, array='-'):
    out = path(name + '.f32')
    run = subprocess.run([probe, '--dump', path(name), array, out], capture_output=True,
                         text=True)
    assert run.returncode == 0, f'{label or name}: {run.stderr}'
    words = run.stdout.split()
    dims = tuple(int(w) for w in words[1:4])
    assert dims == (NX, NY, NZ), f'{name}: dims {dims}'
    got = numpy.fromfile(out, dtype=numpy.float32).reshape(NZ, NY, NX)
    assert numpy.array_equal(got, want.astype(numpy.float32)), \
        f'{label or name}: voxels differ at {numpy.argwhere(got != want.astype(numpy.float32))[:3]}'
    if spacing:
        got_spacing = tuple(float(w) for w in words[5:8])
        assert got_spacing == spacing, f'{name}: spacing {got_spacing}, expected {spacing}'
    checked.append(label or name)


def nifti():
    import nibabel
    affine = numpy.diag([0.5, 1.0, 2.0, 1.0])
    for version, image, pair in ((1, nibabel.Nifti1Image, nibabel.Nifti1Pair),
                                 (2, nibabel.Nifti2Image, nibabel.Nifti2Pair)):
        header = (nibabel.Nifti1Header if version == 1 else nibabel.Nifti2Header)()
        for data, kind in ((field, 'i16'), (floats, 'f32')):
            xyz = data.T  # nibabel's arrays are (x, y, z), stored x fastest
            for order, suffix in (('<', '.nii'), ('>', '.nii.gz')) if kind == 'i16' else \
                    (('>', '.nii'), ('<', '.nii.gz')):
                h = header.as_byteswapped(order) if order == '>' else header.copy()
                name = f'n{version}-{kind}-{"be" if order == ">" else "le"}{suffix}'
                image(xyz, affine, header=h).to_filename(path(name))
                expect(name, data, spacing=(0.5, 1.0, 2.0))
            suffix = '.hdr' if kind == 'i16' else '.hdr.gz'
            name = f'n{version}-{kind}-pair{suffix}'
            pair(xyz, affine).to_filename(path(name))
            expect(name, data, spacing=(0.5, 1.0, 2.0))


def unu(*args):
    subprocess.run(['teem-unu'] + [str(a) for a in args], check=True, cwd=folder,
                   capture_output=True)


def nrrd():
    for data, kind, typ in ((field, 'i16', 'short'), (floats, 'f32', 'float')):
        data.astype('<' + data.dtype.str[1:]).tofile(path(f'{kind}.raw'))
        unu('make', '-i', f'{kind}.raw', '-t', typ, '-s', NX, NY, NZ, '-en', 'little', '-e', 'raw',
            '-sp', 0.5, 1, 2, '-o', f'{kind}.nrrd')
        expect(f'{kind}.nrrd', data, spacing=(0.5, 1.0, 2.0))
        for encoding in ('gzip', 'bzip2', 'ascii', 'hex'):
            # Text has no byte order (unu's `-en big` with ascii writes byte-swapped numbers).
            for endian in ('little',) if encoding == 'ascii' else ('little', 'big'):
                name = f'{kind}-{encoding}-{endian}.nrrd'
                unu('save', '-f', 'nrrd', '-e', encoding, '-en', endian, '-i', f'{kind}.nrrd',
                    '-o', name)
                expect(name, data)
            # Detached: the header names a data file beside it.
            unu('save', '-f', 'nrrd', '-e', encoding, '-i', f'{kind}.nrrd', '-o',
                f'{kind}-{encoding}-detached.nhdr')
            expect(f'{kind}-{encoding}-detached.nhdr', data)
    raw = field.astype('<i2')
    # Line skip then byte skip; byte skip -1 (the data ends the file).
    with open(path('skip.raw'), 'wb') as f:
        f.write(b'a first line\nand a second\nXYZ' + raw.tobytes())
    unu('make', '-h', '-i', 'skip.raw', '-ls', 2, '-bs', 3, '-t', 'short', '-s', NX, NY, NZ,
        '-en', 'little', '-o', 'skip.nhdr')
    expect('skip.nhdr', field)
    with open(path('end.raw'), 'wb') as f:
        f.write(b'anything before the data' + raw.tobytes())
    unu('make', '-h', '-i', 'end.raw', '-bs', -1, '-t', 'short', '-s', NX, NY, NZ, '-en',
        'little', '-o', 'end.nhdr')
    expect('end.nhdr', field)
    # One file per slice: a LIST and a format string, raw and gzipped; one per two-slice slab
    # would need subdim 3, so a LIST of rows (subdim 1) stands for "any subdim".
    slices = [f'slice{n:03d}.raw' for n in range(NZ)]
    for n, name in enumerate(slices):
        raw[n].tofile(path(name))
        with gzip.open(path(name + '.gz'), 'wb') as f:
            f.write(raw[n].tobytes())
    unu('make', '-h', '-i', *slices, '-t', 'short', '-s', NX, NY, NZ, '-en', 'little', '-o',
        'list.nhdr')
    expect('list.nhdr', field)
    unu('make', '-h', '-i', 'slice%03d.raw', 0, NZ - 1, 1, '-t', 'short', '-s', NX, NY, NZ,
        '-en', 'little', '-o', 'format.nhdr')
    expect('format.nhdr', field)
    unu('make', '-h', '-i', 'slice%03d.raw.gz', 0, NZ - 1, 1, '-t', 'short', '-s', NX, NY, NZ,
        '-en', 'little', '-e', 'gzip', '-o', 'format-gzip.nhdr')
    expect('format-gzip.nhdr', field)
    rows = [f'row{n:03d}.raw' for n in range(NY * NZ)]
    for n, name in enumerate(rows):
        raw.reshape(NY * NZ, NX)[n].tofile(path(name))
    unu('make', '-h', '-i', *rows, '-fd', 1, '-t', 'short', '-s', NX, NY, NZ, '-en', 'little',
        '-o', 'rows.nhdr')
    expect('rows.nhdr', field)


def vtk_image():
    import vtk
    from vtk.util import numpy_support
    image = vtk.vtkImageData()
    image.SetDimensions(NX, NY, NZ)
    image.SetSpacing(0.5, 1, 2)
    image.SetOrigin(1, 2, 3)
    for data, name in ((floats, 'other'), (field, 'wanted')):  # the second is asked for by name
        array = numpy_support.numpy_to_vtk(data.ravel(), deep=1)
        array.SetName(name)
        image.GetPointData().AddArray(array)
    writer = vtk.vtkXMLImageDataWriter()
    writer.SetInputData(image)
    writer.SetBlockSize(296)  # several compressed blocks, so bricks start inside and across them
    modes = (('ascii', 0, None), ('base64', 1, None), ('appended', 2, 0), ('appended64', 2, 1))
    # Each mode and compressor once, the header widths and byte orders taking turns.
    combos = [(h, o) for h in ('UInt32', 'UInt64') for o in ('little', 'big')]
    written = 0
    names = {}
    for label, mode, encode in modes:
        for compressor in ('none', 'zlib', 'lz4') if mode else ('none',):
            header, order = combos[written % len(combos)]
            written += 1
            name = f'{label}-{compressor}-{header}-{order}.vti'
            writer.SetFileName(path(name))
            writer.SetDataMode(mode)
            if encode is not None:
                writer.SetEncodeAppendedData(encode)
            getattr(writer, {'none': 'SetCompressorTypeToNone', 'zlib': 'SetCompressorTypeToZLib',
                             'lz4': 'SetCompressorTypeToLZ4'}[compressor])()
            getattr(writer, f'SetHeaderTypeTo{header}')()
            getattr(writer, f'SetByteOrderTo{order.capitalize()}Endian')()
            assert writer.Write() == 1, name
            expect(name, field, spacing=(0.5, 1.0, 2.0), array='wanted')
            names[label, compressor] = name
    expect(names['base64', 'none'], floats, label='the first array by default')
    wavelet_pieces('pieces.pvti', 'zlib')
    expect('pieces.pvti', wavelet_voxels(), array='RTData')


def wavelet_pieces(name, compressor):
    """VTK's wavelet source in 4 pieces as ParaView writes them in parallel (a .pvti and a .vti
    per piece, pieces sharing their boundary points)."""
    import vtk
    source = vtk.vtkRTAnalyticSource()
    source.SetWholeExtent(0, NX - 1, 0, NY - 1, 0, NZ - 1)
    pieces = vtk.vtkXMLPImageDataWriter()
    pieces.SetInputConnection(source.GetOutputPort())
    pieces.SetNumberOfPieces(4)
    pieces.SetStartPiece(0)
    pieces.SetEndPiece(3)
    getattr(pieces, {'zlib': 'SetCompressorTypeToZLib', 'lz4': 'SetCompressorTypeToLZ4'}[compressor])()
    pieces.SetFileName(path(name))
    assert pieces.Write() == 1
    with open(path(name)) as f:
        assert f.read().count('<Piece ') == 4, 'the pieces are sub-extents'


def wavelet_voxels():
    import vtk
    from vtk.util import numpy_support
    source = vtk.vtkRTAnalyticSource()
    source.SetWholeExtent(0, NX - 1, 0, NY - 1, 0, NZ - 1)
    source.Update()
    scalars = source.GetOutput().GetPointData().GetScalars()
    return numpy_support.vtk_to_numpy(scalars).reshape(NZ, NY, NX).astype(numpy.float32)


def write_scene_files():
    """A blob and a ripple, in eighths (exact in every format's text too)."""
    x, y, z = (i - NX / 2) / NX, (j - NY / 2) / NY, (k - NZ / 2) / NZ
    blob = numpy.exp(-8 * (x * x + y * y + z * z)) * 100 + 10 * numpy.sin(12 * x) * numpy.cos(9 * y)
    data = (numpy.round(blob * 8) / 8).astype(numpy.float32)
    data.astype('<f4').tofile(path('field.raw'))
    import nibabel
    nibabel.Nifti2Image(data.T, numpy.eye(4)).to_filename(path('field.nii.gz'))
    unu('make', '-i', 'field.raw', '-t', 'float', '-s', NX, NY, NZ, '-en', 'little', '-e', 'raw',
        '-o', 'plain.nrrd')
    unu('save', '-f', 'nrrd', '-e', 'bzip2', '-i', 'plain.nrrd', '-o', 'field.nrrd')
    unu('save', '-f', 'nrrd', '-e', 'ascii', '-i', 'plain.nrrd', '-o', 'field.nhdr')
    wavelet_pieces('wavelet.pvti', 'lz4')
    wavelet_voxels().astype('<f4').tofile(path('wavelet.raw'))

if scene_files:
    write_scene_files()
    sys.exit(0)
try:
    nifti()
    nrrd()
    vtk_image()
finally:
    shutil.rmtree(folder)
print(f'{len(checked)} files written by other programs read as their raw voxels:')
print(' '.join(checked))
