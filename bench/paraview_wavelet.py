"""ParaView's pvbatch rendering a dfbwall wavelet scene, for `scripts/bench paraview`.

   xvfb-run -a -s "-screen 0 1920x1080x24" mpirun -np N pvbatch --force-offscreen-rendering \
       paraview_wavelet.py SCENE.toml SIZE FRAMES ORBIT_DEGREES MAPPER [OUT.png]

Reads the dfbwall scene (configs/scenes/wavelet256-*.toml) and builds the same thing from
ParaView's own parts: the built-in Wavelet source (vtkRTAnalyticSource) over the extent
[0, n-1]^3 centred in it, which is dfbwall's `source = "wavelet"` field at dims n voxel for voxel
(both map the index range onto x = (centre - index) / (n - 1)); the volume representation with
the scene's colour and opacity points (RGB interpolation, opacity per the same unit distance);
or one Contour filter per isosurface value, each a solid colour from the scene's material. The
data is split over the MPI ranks by the source itself (each rank makes its piece); IceT
composites. dfbwall's world is the volume's box scaled to [-1, 1]^3; ParaView's is the voxel
grid [0, n-1]^3, so every camera position is mapped by p_pv = (p + 1) (n - 1) / 2. Frame k
(k = 0 ... FRAMES-1) turns the scene camera by k * ORBIT_DEGREES about the look-at point around
the up vector, as `dfbwall --orbit` does (Rodrigues' rotation, right-handed). MAPPER:
ParaView's VolumeRenderingMode ("Ray Cast Only": vtkFixedPointVolumeRayCastMapper on the CPU,
"GPU Based": the OpenGL ray caster, here on Mesa's llvmpipe, "Smart": ParaView's choice).
Prints one JSON line on rank 0 with every frame's seconds (frame 0, the set-up, included).
"""
import json
import math
import sys
import time
import tomllib

from paraview.simple import (
    Contour,
    GetActiveViewOrCreate,
    GetColorTransferFunction,
    GetOpacityTransferFunction,
    Render,
    SaveScreenshot,
    Show,
    Wavelet,
)


def rotate(v, axis, degrees):
    """v turned by `degrees` about the unit `axis`, right-handed (dfbwall's renderers::rotation)."""
    n = math.sqrt(sum(a * a for a in axis))
    x, y, z = (a / n for a in axis)
    r = math.radians(degrees)
    c, s = math.cos(r), math.sin(r)
    t = 1 - c
    # Columns of dfbwall's Affine rotation: vx, vy, vz.
    vx = (t * x * x + c, t * x * y + s * z, t * x * z - s * y)
    vy = (t * x * y - s * z, t * y * y + c, t * y * z + s * x)
    vz = (t * x * z + s * y, t * y * z - s * x, t * z * z + c)
    return tuple(vx[i] * v[0] + vy[i] * v[1] + vz[i] * v[2] for i in range(3))


def main():
    scene_path, size, frames, orbit, mapper = sys.argv[1:6]
    size, frames, orbit = int(size), int(frames), float(orbit)
    out = sys.argv[6] if len(sys.argv) > 6 else None
    with open(scene_path, "rb") as f:
        scene = tomllib.load(f)

    volume = scene["volumes"][0]
    dims = volume["dims"]
    if volume.get("source") != "wavelet" or len(set(dims)) != 1:
        raise SystemExit("paraview_wavelet.py: the scene's first volume must be a cubic wavelet")
    n = dims[0]
    half = (n - 1) / 2.0  # dfbwall world unit in voxels, and the centre index

    wavelet = Wavelet()
    wavelet.WholeExtent = [0, n - 1, 0, n - 1, 0, n - 1]
    wavelet.Center = [half, half, half]

    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [size, size]
    view.OrientationAxesVisibility = 0
    background = scene.get("environment", {}).get("color", [0.0, 0.0, 0.0])
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = background

    tf = volume.get("transfer_function", {})
    lut = GetColorTransferFunction("RTData")
    lut.AutomaticRescaleRangeMode = "Never"
    lut.ColorSpace = "RGB"
    lut.RGBPoints = [x for point in tf["colors"] for x in point]
    pwf = GetOpacityTransferFunction("RTData")
    pwf.Points = [x for v, a in tf["opacity"] for x in (v, a, 0.5, 0.0)]

    triangles = 0
    if volume.get("visible", True):
        rep = Show(wavelet, view)
        rep.SetRepresentationType("Volume")
        rep.ColorArrayName = ["POINTS", "RTData"]
        rep.LookupTable = lut
        rep.ScalarOpacityFunction = pwf
        rep.VolumeRenderingMode = mapper
        rep.Shade = 0
        # dfbwall: opacity per opacity_unit world units (default: one voxel spacing).
        rep.ScalarOpacityUnitDistance = tf.get("opacity_unit", 1.0 / half) * half
    materials = scene.get("materials", {})
    for iso in scene.get("isosurfaces", []):
        values = iso.get("values", [iso.get("value")])
        names = iso.get("materials", [iso.get("material")] * len(values))
        for value, name in zip(values, names):
            contour = Contour(Input=wavelet)
            contour.ContourBy = ["POINTS", "RTData"]
            contour.Isosurfaces = [value]
            contour.ComputeScalars = 0
            rep = Show(contour, view)
            rep.ColorArrayName = ["POINTS", ""]
            material = materials[name]
            rep.DiffuseColor = material["color"]
            rep.AmbientColor = material["color"]
            rep.Specular = material.get("specular", 0.0)
            rep.Opacity = material.get("opacity", 1.0)
            contour.UpdatePipeline()
            triangles += contour.GetDataInformation().GetNumberOfCells()

    cam = scene["camera"]
    to_pv = lambda p: [(a + 1.0) * half for a in p]  # noqa: E731
    look = cam["look_at"]
    up = cam.get("up", [0.0, 1.0, 0.0])
    offset = [p - q for p, q in zip(cam["position"], look)]
    camera = view.GetActiveCamera()
    camera.SetViewAngle(cam.get("fov", 60.0))
    view.CameraParallelProjection = 0

    def place(k):
        eye = [q + d for q, d in zip(look, rotate(offset, up, orbit * k))]
        camera.SetFocalPoint(*to_pv(look))
        camera.SetPosition(*to_pv(eye))
        camera.SetViewUp(*up)  # the clipping range follows the bounds at every render

    seconds = []
    for k in range(frames):
        place(k)
        start = time.perf_counter()
        Render(view)
        seconds.append(time.perf_counter() - start)
    if out:
        SaveScreenshot(out, view, ImageResolution=[size, size])
    print(json.dumps({"renderer": "pvbatch", "mapper": mapper, "size": size, "frames": frames,
                      "orbit_degrees": orbit, "triangles": triangles, "frame_s": seconds}),
          flush=True)


if __name__ == "__main__":
    main()
