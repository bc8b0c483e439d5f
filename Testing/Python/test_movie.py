"""vtkGeodesicMovieSource from Python: the movie of `asrt movie` as a temporal VTK source.

Checked against independent facts: its time steps are the movie's frames; its key frames are the
frames vtkGeodesicSource traces at their parameters, bit for bit; its interpolated frames reach
the quality target less 1 dB against frames this test traces itself; they are the frames that
`asrt movie` writes for the same settings; a second source over the same store makes the same
frames tracing no ray; bad settings are errors naming the setting.
Run with PYTHONPATH at the build tree's site-packages and the PG* variables naming a throwaway
server (ctest does both).

Usage: python3 test_movie.py SCENES_DIR ASRT_PROGRAM
"""

import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy
import vtk
from vtkmodules.util import numpy_support

from asrt import vtkGeodesicMovieSource, vtkGeodesicSource

SCENES = sys.argv.pop(1) if len(sys.argv) > 1 else "Data/scenes"
ASRT = sys.argv.pop(1) if len(sys.argv) > 1 else "asrt"
SIDE, FRAMES, FROM, TO, TARGET = 48, 7, 0.65, 0.8, 35.0
KEY, INTERPOLATED = 1, 3  # asrt::FrameMethod (2: traced)


def scene():
    return os.path.join(SCENES, "fig4-mass-start.json")


def movie_source(store=""):
    movie = vtkGeodesicMovieSource()
    movie.SetSceneFileName(scene())
    movie.SetPathParameter("mass")
    movie.SetRampFrom(FROM)
    movie.SetRampTo(TO)
    movie.SetNumberOfFrames(FRAMES)
    movie.SetQualityTarget(TARGET)
    # Held to the frames traced at their parameters, the truth this test traces.
    movie.SetHoldToConverged(False)
    movie.SetResolution(SIDE, SIDE)
    movie.SetStoreConnection(store)
    movie.SetStoreLabel("python movie test")
    return movie


def mass(k):
    return FROM + (TO - FROM) * k / (FRAMES - 1)


def frame(movie, time):
    movie.UpdateTimeStep(time)
    image = vtk.vtkImageData()
    image.DeepCopy(movie.GetOutput())
    return image


def colours(image):
    return numpy_support.vtk_to_numpy(image.GetPointData().GetArray("Colors")).astype(float)


def traced(m):
    source = vtkGeodesicSource()
    source.SetSceneFileName(scene())
    source.SetResolution(SIDE, SIDE)
    source.SetMass(m)
    source.Update()
    return source.GetOutput()


def psnr(a, b):
    mse = numpy.mean((a - b) ** 2)
    return math.inf if mse == 0 else 10 * math.log10(255.0 ** 2 / mse)


class Errors:
    """The text of every ErrorEvent of an algorithm."""

    def __init__(self, algorithm):
        self.texts = []
        algorithm.AddObserver("ErrorEvent", self.on_error)
        algorithm.GetExecutive().AddObserver("ErrorEvent", self.on_error)

    @vtk.calldata_type(vtk.VTK_STRING)
    def on_error(self, caller, event, text):
        self.texts.append(text)


class MovieSource(unittest.TestCase):
    def test_time_steps_keys_and_quality_then_reuse_through_the_store(self):
        movie = movie_source("default")
        errors = Errors(movie)
        movie.UpdateInformation()
        self.assertEqual(errors.texts, [])
        info = movie.GetOutputInformation(0)
        steps = info.Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
        self.assertEqual(list(steps), list(range(FRAMES)))
        # The first frame asked for makes the keys; the plan is final then.
        made = {0: colours(frame(movie, 0))}
        methods = [movie.GetPlannedMethod(k) for k in range(FRAMES)]
        self.assertEqual(methods[0], KEY)
        self.assertEqual(methods[-1], KEY)
        self.assertIn(INTERPOLATED, methods)
        for k in range(FRAMES):
            image = frame(movie, k)
            self.assertEqual(errors.texts, [])
            made[k] = colours(image)
            truth = colours(traced(mass(k)))
            method = image.GetFieldData().GetAbstractArray("FrameMethod").GetValue(0)
            if methods[k] != INTERPOLATED:
                self.assertEqual(method, "key" if methods[k] == KEY else "traced")
                self.assertTrue(numpy.array_equal(made[k], truth), "key frame %d" % k)
            else:
                self.assertEqual(method, "interpolated")
                estimated = image.GetFieldData().GetArray("EstimatedPsnr").GetValue(0)
                self.assertGreaterEqual(estimated, TARGET)
                self.assertGreaterEqual(psnr(made[k], truth), TARGET - 1, "frame %d" % k)
        self.assertGreater(movie.GetRaysTraced(), 2 * SIDE * SIDE)

        # Another source, the same movie, the same store: every frame read, none traced.
        again = movie_source("default")
        again_errors = Errors(again)
        for k in reversed(range(FRAMES)):
            self.assertTrue(numpy.array_equal(colours(frame(again, k)), made[k]), "frame %d" % k)
        self.assertEqual(again_errors.texts, [])
        self.assertEqual(again.GetRaysTraced(), 0)
        first = frame(again, 0)
        self.assertEqual(first.GetFieldData().GetAbstractArray("FrameMethod").GetValue(0),
                         "reused")

    def test_the_frames_are_those_asrt_movie_writes(self):
        movie = movie_source()
        with tempfile.TemporaryDirectory() as out:
            subprocess.run([ASRT, "movie", scene(), "--ramp", "mass=%r:%r" % (FROM, TO),
                            "-n", str(FRAMES), "-r", "%dx%d" % (SIDE, SIDE), "--quality",
                            str(TARGET), "--against-traced", "-q", "-o", out + "/"],
                           check=True, stdout=subprocess.DEVNULL)
            for k in range(FRAMES):
                reader = vtk.vtkXMLImageDataReader()
                reader.SetFileName(os.path.join(out, "fig4-mass-start-%03d.vti" % k))
                reader.Update()
                written = reader.GetOutput().GetPointData()
                made = frame(movie, k).GetPointData()
                for name in ("Colors", "ObjectId", "ImageOrder", "PathLength", "Termination"):
                    self.assertTrue(
                        numpy.array_equal(numpy_support.vtk_to_numpy(made.GetArray(name)),
                                          numpy_support.vtk_to_numpy(written.GetArray(name)),
                                          equal_nan=True),
                        "frame %d, %s" % (k, name))

    def test_bad_settings_are_errors_naming_the_setting(self):
        cases = [
            ("NumberOfFrames", lambda m: m.SetNumberOfFrames(1)),
            ("QualityTarget", lambda m: m.SetQualityTarget(0)),
            ("QualityTarget", lambda m: m.SetQualityTarget(float("nan"))),
            ("QualityTarget", lambda m: m.SetQualityTarget(120)),
            ("PathParameter", lambda m: m.SetPathParameter("temperature")),
            ("SceneFileName", lambda m: m.SetSceneFileName("")),
        ]
        for field, setting in cases:
            movie = movie_source()
            errors = Errors(movie)
            setting(movie)
            movie.UpdateTimeStep(0)
            self.assertTrue(any(field in t for t in errors.texts), (field, errors.texts))
            self.assertEqual(movie.GetOutput().GetNumberOfPoints(), 0)
            self.assertEqual(movie.GetRaysTraced(), 0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
