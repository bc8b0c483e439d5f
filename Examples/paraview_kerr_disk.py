# ASRT in ParaView, from pvpython: the plugin's proxies in a ParaView pipeline.
#
# Traces the thin disk around a Kerr hole (a = 0.9 M) with the geodesic source, shows the picture
# beside the 3D ray bundle (the rays as polylines, with the horizon and the disk from the scene
# geometry) in two render views of one layout, saves a screenshot of the layout, and plays an
# interpolated movie (the hole's mass from 0.9 to 1.1 M, through the frame interpolator's time
# steps) into PNGs. Run it under a display (pvpython renders through X; xvfb-run gives one, and
# -noreset keeps its server from resetting between ParaView's OpenGL probe and its first view):
#
#     PV_PLUGIN_PATH=build/lib/paraview-5.11/plugins/ASRT \
#         xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" \
#         pvpython Examples/paraview_kerr_disk.py OUTPUT_DIR [WIDTH [STATE.pvsm]]
#
# The plugin is loaded from PV_PLUGIN_PATH (or give its ASRT.so as ASRT_PLUGIN). Outputs, in
# OUTPUT_DIR: kerr-disk-paraview.png (the two views), kerr-disk-movie.NNNN.png (the movie); with
# STATE, the two views' state for ParaView's GUI (Examples/paraview_kerr_disk.pvsm was made so,
# from the source tree's root).
import glob
import os
import sys

from paraview.simple import (
    AssignViewToLayout,
    ColorBy,
    CreateLayout,
    CreateView,
    GetAnimationScene,
    GetColorTransferFunction,
    LoadPlugin,
    OutputPort,
    SaveAnimation,
    SaveScreenshot,
    SaveState,
    Show,
)

here = os.path.dirname(os.path.abspath(__file__))
out = sys.argv[1] if len(sys.argv) > 1 else "."
width = int(sys.argv[2]) if len(sys.argv) > 2 else 240
height = width * 3 // 4
state = sys.argv[3] if len(sys.argv) > 3 else None
scene = os.path.normpath(os.path.join(here, "..", "Data", "scenes", "kerr-disk.json"))
if not os.path.relpath(scene).startswith(".."):
    # Relative to the working directory when it holds the scene, so that a saved state opens
    # from any copy of the source tree (run from the tree's root).
    scene = os.path.relpath(scene)
os.makedirs(out, exist_ok=True)


def plugin_path():
    """ASRT.so: ASRT_PLUGIN, else the first ASRT.so in a folder of PV_PLUGIN_PATH."""
    if os.environ.get("ASRT_PLUGIN"):
        return os.environ["ASRT_PLUGIN"]
    for folder in os.environ.get("PV_PLUGIN_PATH", "").split(os.pathsep):
        found = glob.glob(os.path.join(folder, "ASRT.so"))
        if found:
            return found[0]
    sys.exit("paraview_kerr_disk.py: set PV_PLUGIN_PATH to the folder of ASRT.so (or ASRT_PLUGIN)")


# The plugin's proxies become functions of this module, named by their labels, as ParaView's own
# sources are: ASRTGeodesicSource, ASRTSceneGeometry, ASRTFrameInterpolator, ...
LoadPlugin(plugin_path(), remote=False, ns=globals())

# %% The picture, and the rays of a 12 x 9 grid of pixels as polylines (port 2).
source = ASRTGeodesicSource(SceneFileName=scene)  # noqa: F821 (made by LoadPlugin)
source.Resolution = [width, height]
source.GeneratePolylines = 1
source.PolylineStride = max(1, width // 12)
source.UpdatePipeline()

picture_view = CreateView("RenderView")
picture_view.ViewSize = [width * 2, height * 2]
picture_view.OrientationAxesVisibility = 0
picture = Show(OutputPort(source, 0), picture_view)
picture.SetRepresentationType("Slice")
picture.ColorArrayName = ["POINTS", "Colors"]
picture.MapScalars = 0  # the traced RGB colours as they are
picture_view.InteractionMode = "2D"
picture_view.ResetCamera()

# %% The ray bundle in 3D: the polylines coloured by how far each point lies from the hole, the
# horizon and the disk from the scene's own geometry.
geometry = ASRTSceneGeometry(SceneFileName=scene)  # noqa: F821
bundle_view = CreateView("RenderView")
bundle_view.ViewSize = [width * 2, height * 2]
bundle_view.OrientationAxesVisibility = 0
rays = Show(OutputPort(source, 2), bundle_view)
ColorBy(rays, ("POINTS", "R"))
# The rays run out to the escape radius; the colours resolve the hole's neighbourhood.
GetColorTransferFunction("R").RescaleTransferFunction(0.0, 40.0)
surfaces = Show(geometry, bundle_view)
surfaces.DiffuseColor = [0.9, 0.6, 0.2]
# The camera frames the hole, not the rays' full extent (ResetCamera would show r = 1000).
bundle_view.CameraPosition = [60.0, -45.0, 35.0]
bundle_view.CameraFocalPoint = [0.0, 0.0, 0.0]
bundle_view.CameraViewUp = [0.0, 0.0, 1.0]
bundle_view.CameraViewAngle = 30.0

layout = CreateLayout("ASRT: Kerr disk")
AssignViewToLayout(view=picture_view, layout=layout, hint=0)
AssignViewToLayout(view=bundle_view, layout=layout, hint=2)
layout.SetSize(width * 4, height * 2)
SaveScreenshot(os.path.join(out, "kerr-disk-paraview.png"), layout)
print("wrote", os.path.join(out, "kerr-disk-paraview.png"))
if state:
    # The two views and their layout, for the GUI: paraview --state=STATE (with the plugin on
    # PV_PLUGIN_PATH).
    SaveState(state)
    print("wrote", state)

# %% An interpolated movie: two key frames (M = 0.9 and 1.1) matched ray by ray, and the frames in
# between made by the interpolator, one per time step of the animation scene.
key_a = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height])  # noqa: F821
key_a.OverrideSpacetime = 1
key_a.Mass = 0.9
key_a.Spin = 0.8
key_b = ASRTGeodesicSource(SceneFileName=scene, Resolution=[width, height])  # noqa: F821
key_b.OverrideSpacetime = 1
key_b.Mass = 1.1
key_b.Spin = 0.8
movie = ASRTFrameInterpolator(  # noqa: F821
    FrameA=OutputPort(key_a, 1), FrameB=OutputPort(key_b, 1), NumberOfIntermediateFrames=4)

movie_view = CreateView("RenderView")
movie_view.ViewSize = [width, height]
movie_view.OrientationAxesVisibility = 0
frame = Show(movie, movie_view)
frame.SetRepresentationType("Slice")
frame.ColorArrayName = ["POINTS", "Colors"]
frame.MapScalars = 0
movie_view.InteractionMode = "2D"
movie_view.ResetCamera()

animation = GetAnimationScene()
animation.UpdateAnimationUsingDataTimeSteps()  # the interpolator's TIME_STEPS: k / (N + 1)
print("movie time steps:", list(animation.TimeKeeper.TimestepValues))
SaveAnimation(os.path.join(out, "kerr-disk-movie.png"), movie_view, ImageResolution=[width, height])
print("wrote", len(glob.glob(os.path.join(out, "kerr-disk-movie.*.png"))), "movie frames")
