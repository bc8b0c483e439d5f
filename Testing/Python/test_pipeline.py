"""The Python face of ASRT: VTK's own wrapping of the filters, used next to the vtk package.

A pipeline traced, stored in PostgreSQL, read back (and, once the filter exists, interpolated),
checked against independent facts: the hole's shadow at the centre of the picture and the sky at
its corner, the frame read back bit for bit equal to the one written, and vtk's own filters
accepting the outputs. Run with PYTHONPATH at the build tree's site-packages and
ASRT_TEST_CONNINFO naming a throwaway server (ctest does both).

Usage: python3 test_pipeline.py SCENES_DIR
"""

import os
import sys
import tempfile
import unittest

import vtk
from vtkmodules.util import numpy_support

import asrt
from asrt import (
    vtkGeodesicDistributedSource,
    vtkGeodesicPostgreSQLReader,
    vtkGeodesicPostgreSQLWriter,
    vtkGeodesicSource,
)

SCENES = sys.argv.pop(1) if len(sys.argv) > 1 else "Data/scenes"
CONNINFO = os.environ.get("ASRT_TEST_CONNINFO", "")
W, H = 40, 30
CAPTURED, HIT_OBJECT = 2, 5  # asrt::Termination
RECORD_ARRAYS = ["Pixel", "Origin", "Direction", "Momentum", "Termination", "ObjectId",
                 "HitNormal", "UV", "ChordError", "PathLength", "Winding", "ImageOrder", "Steps",
                 "MaxAbsH", "Color", "Jacobian"]


def array(data, name):
    return numpy_support.vtk_to_numpy(data.GetPointData().GetArray(name))


def kerr_source():
    source = vtkGeodesicSource()
    source.SetSceneFileName(os.path.join(SCENES, "kerr-disk.json"))
    source.SetResolution(W, H)
    return source


class Pipeline(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.source = kerr_source()
        cls.source.Update()

    def test_the_filters_are_vtk_algorithms(self):
        self.assertIsInstance(self.source, vtk.vtkImageAlgorithm)
        self.assertIsInstance(self.source.GetImageOutput(), vtk.vtkImageData)
        self.assertIsInstance(self.source.GetHitsOutput(), vtk.vtkPolyData)
        self.assertTrue(hasattr(asrt, "vtkGeodesicSceneGeometry"))

    def test_trace_shows_the_shadow_at_the_centre_and_the_sky_at_the_corner(self):
        image = self.source.GetImageOutput()
        self.assertEqual(image.GetDimensions(), (W, H, 1))
        termination = array(image, "Termination").reshape(H, W)
        objects = array(image, "ObjectId").reshape(H, W)
        # The camera looks straight at the hole: the central ray falls in.
        self.assertEqual(termination[H // 2, W // 2], CAPTURED)
        # 20 degrees off the axis, far outside the shadow and the disk: the galaxy (object 0).
        self.assertEqual(termination[0, 0], HIT_OBJECT)
        self.assertEqual(objects[0, 0], 0)
        self.assertEqual(self.source.GetHitsOutput().GetNumberOfPoints(), W * H)

    def test_vtk_filters_take_the_outputs(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "kerr.png")
            png = vtk.vtkPNGWriter()
            png.SetInputConnection(self.source.GetOutputPort(0))
            png.SetFileName(path)
            png.Write()
            reader = vtk.vtkPNGReader()
            reader.SetFileName(path)
            reader.Update()
            self.assertEqual(reader.GetOutput().GetDimensions(), (W, H, 1))
            colours = array(reader.GetOutput(), "PNGImage")
            self.assertTrue((colours == array(self.source.GetImageOutput(), "Colors")).all())

    def test_store_then_read_back_bit_for_bit_then_interpolate(self):
        writer = vtkGeodesicPostgreSQLWriter()
        writer.SetInputConnection(self.source.GetOutputPort(1))
        writer.SetConnectionString(CONNINFO)
        writer.SetLabel("python")
        writer.ReplaceExistingOn()
        writer.Write()
        frame = writer.GetFrameId()
        self.assertGreaterEqual(frame, 0)

        reader = vtkGeodesicPostgreSQLReader()
        reader.SetConnectionString(CONNINFO)
        reader.UpdateInformation()
        self.assertIn(frame, [reader.GetFrameIdAt(k) for k in range(reader.GetNumberOfFrames())])
        reader.SetFrameId(frame)
        reader.Update()
        hits, stored = self.source.GetHitsOutput(), reader.GetHitsOutput()
        self.assertEqual(stored.GetNumberOfPoints(), W * H)
        for name in RECORD_ARRAYS:
            # Bit for bit, NaN Jacobians included: compare the bytes.
            self.assertEqual(array(stored, name).tobytes(), array(hits, name).tobytes(), name)
        self.assertEqual(numpy_support.vtk_to_numpy(stored.GetPoints().GetData()).tobytes(),
                         numpy_support.vtk_to_numpy(hits.GetPoints().GetData()).tobytes())
        self.assertTrue((array(reader.GetImageOutput(), "Colors") ==
                         array(self.source.GetImageOutput(), "Colors")).all())

        # Then a frame half-way between two stored ones, through the wrapped interpolator.
        self.interpolate(frame)

    def interpolate(self, first):
        # Frame B: the same scene with a heavier hole, stored and read back like A.
        heavier = kerr_source()
        heavier.SetMass(1.1)
        writer = vtkGeodesicPostgreSQLWriter()
        writer.SetInputConnection(heavier.GetOutputPort(1))
        writer.SetConnectionString(CONNINFO)
        writer.ReplaceExistingOn()
        writer.Write()
        self.assertGreaterEqual(writer.GetFrameId(), 0)
        readers = []
        for frame in (first, writer.GetFrameId()):
            reader = vtkGeodesicPostgreSQLReader()
            reader.SetConnectionString(CONNINFO)
            reader.SetFrameId(frame)
            readers.append(reader)
        interpolator = asrt.vtkGeodesicFrameInterpolator()
        interpolator.SetFrameAConnection(readers[0].GetOutputPort(1))
        interpolator.SetFrameBConnection(readers[1].GetOutputPort(1))
        interpolator.UpdateTimeStep(0.5)
        image = interpolator.GetOutputDataObject(0)
        self.assertIsInstance(image, vtk.vtkImageData)
        self.assertEqual(image.GetDimensions(), (W, H, 1))
        # Half-way, the mass is half-way too.
        mass = image.GetFieldData().GetArray("Mass").GetValue(0)
        self.assertAlmostEqual(mass, 1.05, places=12)
        # At t = 0 the interpolator gives frame A itself, to the byte.
        interpolator.UpdateTimeStep(0.0)
        self.assertEqual(array(interpolator.GetOutputDataObject(0), "Colors").tobytes(),
                         array(readers[0].GetImageOutput(), "Colors").tobytes())

    def test_the_distributed_source_takes_a_vtk_controller(self):
        controller = vtk.vtkDummyController()
        distributed = vtkGeodesicDistributedSource()
        distributed.SetController(controller)
        distributed.SetSceneFileName(os.path.join(SCENES, "kerr-disk.json"))
        distributed.SetResolution(W, H)
        distributed.Update()
        self.assertEqual(array(distributed.GetImageOutput(), "Colors").tobytes(),
                         array(self.source.GetImageOutput(), "Colors").tobytes())
        work = numpy_support.vtk_to_numpy(distributed.GetRankWork())
        self.assertEqual(work.shape, (1, 4))
        self.assertEqual(work[0, 0], array(self.source.GetHitsOutput(), "Steps").sum())


if __name__ == "__main__":
    unittest.main(verbosity=2)
