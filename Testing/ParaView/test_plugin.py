# The ParaView plugin in pvpython (label paraview): its proxies run the same filters as the plain
# Python package, so a proxy's outputs must equal the plain source's bit for bit (one VTK, one
# build); the interpolator's time steps drive the animation scene, and each step's parameters lie
# on the straight path between the key frames; errors reach ParaView's output window naming the
# field; the PostgreSQL writer and reader proxies store a frame and read it back; the movie
# source's frames are the animation's time steps and the plain movie source's frames.
#
# Usage (under asrtWithThrowawayPostgres, which exports PG* for a throwaway server, and a display):
#   PYTHONPATH=<build>/lib/python3.11/site-packages pvpython test_plugin.py ASRT.so SCENES_DIR
import math
import os
import sys

import numpy
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow

from paraview import servermanager
from paraview.simple import CreateView, GetAnimationScene, LoadPlugin, OutputPort, Render, Show

import asrt

plugin, scenes = sys.argv[1], sys.argv[2]
scene = os.path.join(scenes, "kerr-disk.json")
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def arrays(data):
    """Every point-data array of `data` (and its points, when it has any) as NumPy arrays."""
    out = {}
    pd = data.GetPointData()
    for k in range(pd.GetNumberOfArrays()):
        a = pd.GetAbstractArray(k)
        out["point:" + a.GetName()] = numpy_support.vtk_to_numpy(a)
    if hasattr(data, "GetPoints") and data.GetPoints() is not None:
        out["points"] = numpy_support.vtk_to_numpy(data.GetPoints().GetData())
    if hasattr(data, "GetLines") and data.GetLines() is not None:
        out["lines"] = numpy_support.vtk_to_numpy(data.GetLines().GetData())
    return out


def same_data(name, proxy_data, plain_data):
    check(proxy_data.GetNumberOfPoints() == plain_data.GetNumberOfPoints(),
          f"{name}: {proxy_data.GetNumberOfPoints()} points through the plugin, "
          f"{plain_data.GetNumberOfPoints()} from the plain source")
    check(proxy_data.GetNumberOfPoints() > 0, f"{name}: no points")
    if hasattr(plain_data, "GetDimensions"):
        check(tuple(proxy_data.GetDimensions()) == tuple(plain_data.GetDimensions()),
              f"{name}: dimensions {proxy_data.GetDimensions()} against "
              f"{plain_data.GetDimensions()}")
    a, b = arrays(proxy_data), arrays(plain_data)
    check(sorted(a) == sorted(b), f"{name}: arrays {sorted(a)} against {sorted(b)}")
    for key in sorted(set(a) & set(b)):
        equal = a[key].shape == b[key].shape and numpy.array_equal(a[key], b[key], equal_nan=True)
        check(equal, f"{name}: {key} differs from the plain source's")


LoadPlugin(plugin, remote=False, ns=globals())

# 1. The geodesic source: scene values as they are, then every override group switched on.
width, height = 40, 30
cases = {
    "scene as it is": ({}, lambda s: None),
    "overrides": (
        {"OverrideSpacetime": 1, "Mass": 0.8, "Spin": 0.5, "OverrideCamera": 1,
         "CameraPosition": [0.0, -30.0, 12.0], "FocalPoint": [0.0, 0.0, 0.0],
         "ViewUp": [0.0, 0.0, 1.0], "ViewAngle": 40.0, "IntegrationPreset": "fast",
         "Antialias": "filter"},
        lambda s: (s.SetMass(0.8), s.SetSpin(0.5), s.SetCameraPosition(0.0, -30.0, 12.0),
                   s.SetFocalPoint(0.0, 0.0, 0.0), s.SetViewUp(0.0, 0.0, 1.0),
                   s.SetViewAngle(40.0), s.SetIntegrationPreset("fast"),
                   s.SetAntialias("filter"))),
}
for label, (properties, configure_plain) in cases.items():
    proxy = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height],  # noqa: F821
                               GeneratePolylines=1, PolylineStride=10, **properties)
    proxy.UpdatePipeline()
    plain = asrt.vtkGeodesicSource()
    plain.SetSceneFileName(scene)
    plain.SetResolution(width, height)
    plain.SetGeneratePolylines(1)
    plain.SetPolylineStride(10)
    configure_plain(plain)
    plain.Update()
    for port, name in enumerate(["image", "hits", "polylines"]):
        same_data(f"{label}, {name}", servermanager.Fetch(proxy, idx=port),
                  plain.GetOutputDataObject(port))
    image = servermanager.Fetch(proxy, idx=0)
    check(image.GetDimensions()[:2] == (width, height),
          f"{label}: image {image.GetDimensions()}, asked for {width} x {height}")
    for name in ["Colors", "ObjectId", "ImageOrder", "PathLength", "Termination"]:
        check(image.GetPointData().GetArray(name) is not None, f"{label}: no {name} array")

# 2. The interpolator's time steps drive the animation: k / (N + 1), and at each the mass lies on
# the straight line between the key frames (0.9 at t = 0, 1.1 at t = 1).
key_a = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height],  # noqa: F821
                           OverrideSpacetime=1, Mass=0.9, Spin=0.8)
key_b = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height],  # noqa: F821
                           OverrideSpacetime=1, Mass=1.1, Spin=0.8)
n = 3
movie = ASRTFrameInterpolator(FrameA=OutputPort(key_a, 1),  # noqa: F821
                              FrameB=OutputPort(key_b, 1), NumberOfIntermediateFrames=n)
animation = GetAnimationScene()
animation.UpdateAnimationUsingDataTimeSteps()
steps = list(animation.TimeKeeper.TimestepValues)
expected = [k / (n + 1) for k in range(n + 2)]
check(len(steps) == len(expected) and all(math.isclose(s, e, abs_tol=1e-12)
                                          for s, e in zip(steps, expected)),
      f"animation time steps {steps}, expected {expected}")
# A render view shows the interpolator, as in the GUI: each animation time renders the view, which
# updates the pipeline at that time (the built-in session's filter holds the frame it made).
view = CreateView("RenderView")
view.ViewSize = [width, height]
Show(movie, view)
seen = 0
for t in steps:
    animation.AnimationTime = t
    Render(view)
    frame = movie.GetClientSideObject().GetOutputDataObject(0)
    fd = frame.GetFieldData()
    time_array, mass_array = fd.GetArray("InterpolationTime"), fd.GetArray("Mass")
    if time_array is None or mass_array is None:
        check(False, f"t = {t}: no InterpolationTime or Mass in the frame's field data")
        continue
    check(math.isclose(time_array.GetValue(0), t, abs_tol=1e-12),
          f"the animation at t = {t} got the frame of t = {time_array.GetValue(0)}")
    check(math.isclose(mass_array.GetValue(0), 0.9 + 0.2 * t, abs_tol=1e-12),
          f"t = {t}: mass {mass_array.GetValue(0)}, expected {0.9 + 0.2 * t}")
    check(frame.GetDimensions()[:2] == (width, height), f"t = {t}: {frame.GetDimensions()}")
    seen += 1
check(seen == n + 2, f"stepped through {seen} frames, expected {n + 2}")

# 2b. The path interpolator takes any number of key frames on one input: key frame k is at time k,
# the mass at each step lies on the ramp through the keys, and with a quality target the frames
# between the keys come with their re-traced share.
keys = [ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height],  # noqa: F821
                           OverrideSpacetime=1, Mass=m, Spin=0.8) for m in (0.9, 1.0, 1.1)]
path = ASRTPathInterpolator(KeyFrames=[OutputPort(k, 1) for k in keys],  # noqa: F821
                            NumberOfIntermediateFrames=1, QualityTarget=30,
                            TextureDirectory=scenes)
path.UpdatePipelineInformation()
path_steps = list(path.TimestepValues)
check(path_steps == [0.0, 0.5, 1.0, 1.5, 2.0], f"path time steps {path_steps}")
for t in path_steps:
    path.UpdatePipeline(t)
    frame = servermanager.Fetch(path)
    mass_array = frame.GetFieldData().GetArray("Mass")
    check(mass_array is not None and math.isclose(mass_array.GetValue(0), 0.9 + 0.1 * t,
                                                   abs_tol=1e-12),
          f"path t = {t}: mass {mass_array.GetValue(0) if mass_array else None}")
    check(frame.GetPointData().GetArray("PathMethod") is not None, f"path t = {t}: no PathMethod")

# 3. Errors reach ParaView's output window and name the field.
window = vtkStringOutputWindow()
vtkOutputWindow.SetInstance(window)
bad = ASRTGeodesicSource(SceneFileName=scene, Resolution=[8, 6],  # noqa: F821
                         OverrideSpacetime=1, Mass=1.0, Spin=1.5)
bad.UpdatePipeline()
text = window.GetOutput()
check("spin" in text.lower(), f"a spin above the mass gave no error naming the spin: {text!r}")
check(servermanager.Fetch(bad, idx=0).GetNumberOfPoints() == 0,
      "a refused scene still gave an image")
vtkOutputWindow.SetInstance(None)

# 4. The PostgreSQL writer and reader proxies (the connection from PG*: a throwaway server).
source = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height])  # noqa: F821
writer = servermanager.writers.ASRTPostgreSQLWriter(Input=OutputPort(source, 1),
                                                         Label="paraview plugin test")
writer.UpdatePipeline()
writer.UpdatePropertyInformation()
frame_id = writer.GetPropertyValue("FrameId")
check(frame_id is not None and frame_id >= 0, f"the writer reports frame id {frame_id}")
reader = ASRTPostgreSQLReader(FrameId=frame_id)  # noqa: F821
reader.UpdatePipeline()
same_data("stored and read back, image", servermanager.Fetch(reader, idx=0),
          servermanager.Fetch(source, idx=0))
ring = ASRTPostgreSQLReader(FrameId=frame_id, Predicate="image_order >= 1")  # noqa: F821
ring.UpdatePipeline()
hits = servermanager.Fetch(source, idx=1)
order = numpy_support.vtk_to_numpy(hits.GetPointData().GetArray("ImageOrder"))
selected = servermanager.Fetch(ring, idx=1).GetNumberOfPoints()
check(selected == int((order >= 1).sum()),
      f"the predicate image_order >= 1 selected {selected} rays, the frame has "
      f"{int((order >= 1).sum())}")

# 5. The movie source: its frames are the animation's time steps 0 ... N - 1, and each frame the
# proxy makes is the plain movie source's frame bit for bit, with its method in the field data.
frames = 4
movie_source = ASRTMovieSource(SceneFileName=scene, Resolution=[width, height],  # noqa: F821
                               PathParameter="mass", RampFrom=0.9, RampTo=1.1,
                               NumberOfFrames=frames, QualityTarget=30)
movie_source.UpdatePipelineInformation()
movie_steps = list(movie_source.TimestepValues)
check(movie_steps == [float(k) for k in range(frames)], f"movie time steps {movie_steps}")
animation.UpdateAnimationUsingDataTimeSteps()
animation_steps = list(animation.TimeKeeper.TimestepValues)
check(all(float(k) in animation_steps for k in range(frames)),
      f"the animation's time steps {animation_steps} lack the movie's frames")
plain_movie = asrt.vtkGeodesicMovieSource()
plain_movie.SetSceneFileName(scene)
plain_movie.SetResolution(width, height)
plain_movie.SetRampFrom(0.9)
plain_movie.SetRampTo(1.1)
plain_movie.SetNumberOfFrames(frames)
plain_movie.SetQualityTarget(30)
for k in range(frames):
    movie_source.UpdatePipeline(float(k))
    made = servermanager.Fetch(movie_source)
    plain_movie.UpdateTimeStep(float(k))
    same_data(f"movie frame {k}", made, plain_movie.GetOutput())
    method = made.GetFieldData().GetAbstractArray("FrameMethod")
    check(method is not None and method.GetValue(0) in ("key", "interpolated", "traced"),
          f"movie frame {k}: method {method.GetValue(0) if method else None}")

if failures:
    print(f"test_plugin: {len(failures)} failures")
    sys.exit(1)
print("test_plugin: all checks passed")
