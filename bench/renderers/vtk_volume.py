#!/usr/bin/python3
"""VTK's CPU volume ray caster on the wavelet, as scivis_bench renders it, for scripts/bench.

   xvfb-run -a vtk_volume.py RESOLUTION SIZE THREADS FRAMES [OUT.png]

vtkRTAnalyticSource over [0, RESOLUTION-1]^3 centred in it (the field scivis_bench samples),
vtkFixedPointVolumeRayCastMapper with one sample per voxel (no automatic adjustment), colour
blue-white-red over 37..277, opacity ramp 0..0.4 per voxel, ResetCamera's view turned by
360/FRAMES degrees a frame. Prints one JSON line; the median frame excludes the first (set-up).
"""
import json
import sys
import time

import vtk


def main():
    resolution, size, threads, frames = (int(a) for a in sys.argv[1:5])
    out = sys.argv[5] if len(sys.argv) > 5 else None
    vtk.vtkMultiThreader.SetGlobalMaximumNumberOfThreads(threads)

    source = vtk.vtkRTAnalyticSource()
    source.SetWholeExtent(0, resolution - 1, 0, resolution - 1, 0, resolution - 1)
    # VTK centres the field at Center (default: the origin, a corner of this extent); ParaView's
    # Wavelet centres it in its extent, as scivis_bench does.
    half = (resolution - 1) / 2.0
    source.SetCenter(half, half, half)
    source.Update()

    color = vtk.vtkColorTransferFunction()
    color.AddRGBPoint(37.0, 0.23, 0.30, 0.75)
    color.AddRGBPoint(157.0, 0.87, 0.87, 0.87)
    color.AddRGBPoint(277.0, 0.71, 0.02, 0.15)
    opacity = vtk.vtkPiecewiseFunction()
    opacity.AddPoint(37.0, 0.0)
    opacity.AddPoint(277.0, 0.4)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.0)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()

    mapper = vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputConnection(source.GetOutputPort())
    mapper.AutoAdjustSampleDistancesOff()
    mapper.SetSampleDistance(1.0)
    mapper.SetImageSampleDistance(1.0)
    mapper.SetNumberOfThreads(threads)
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    renderer = vtk.vtkRenderer()
    renderer.AddVolume(volume)
    renderer.SetBackground(0, 0, 0)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(size, size)
    renderer.ResetCamera()
    camera = renderer.GetActiveCamera()

    window.Render()  # set-up: textures, first traversal
    if out:
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.Update()
        writer = vtk.vtkPNGWriter()
        writer.SetFileName(out)
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()
    seconds, cpu = [], []
    for _ in range(frames):
        camera.Azimuth(360.0 / frames)
        start, cpuStart = time.perf_counter(), time.process_time()
        window.Render()
        seconds.append(time.perf_counter() - start)
        cpu.append(time.process_time() - cpuStart)  # all of this process's threads
    seconds.sort()
    cpu.sort()
    print(json.dumps({"renderer": "vtkFixedPointVolumeRayCastMapper", "vtk": vtk.vtkVersion.GetVTKVersion(),
                      "resolution": resolution, "size": size, "threads": threads, "frames": frames,
                      "median_frame_s": seconds[len(seconds) // 2],
                      "median_cpu_frame_s": cpu[len(cpu) // 2]}))


if __name__ == "__main__":
    main()
