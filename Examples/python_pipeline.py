# %% [markdown]
# # ASRT from Python
#
# The filters are VTK algorithms wrapped by VTK's own Python wrapping, so they sit in `vtk`
# pipelines and their outputs are `vtk` data sets (and NumPy arrays through
# `vtkmodules.util.numpy_support`). Run it as a script or cell by cell (`# %%` cells, as in
# Jupyter or VS Code):
#
#     PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 \
#         Examples/python_pipeline.py OUTPUT_DIR [WIDTH] [CONNINFO]
#
# With a CONNINFO ("" for the PG* variables or the private server of `asrt db`), the frame is
# also accumulated in PostgreSQL and read back.

# %%
import os
import sys

import vtk
from vtkmodules.util import numpy_support

from asrt import vtkGeodesicPostgreSQLReader, vtkGeodesicPostgreSQLWriter, vtkGeodesicSource

here = os.path.dirname(os.path.abspath(__file__))
out = sys.argv[1] if len(sys.argv) > 1 else "."
width = int(sys.argv[2]) if len(sys.argv) > 2 else 320
conninfo = sys.argv[3] if len(sys.argv) > 3 else None

# %% [markdown]
# ## Trace a frame: a thin disk around a Kerr hole (a = 0.9 M)

# %%
source = vtkGeodesicSource()
source.SetSceneFileName(os.path.join(here, "..", "Data", "scenes", "kerr-disk.json"))
source.SetResolution(width, width * 3 // 4)
source.Update()
image = source.GetImageOutput()
print("traced", image.GetDimensions()[:2], "pixels")

# %% [markdown]
# ## The rays as NumPy arrays
# Every pixel's record is on the hit points (port 1): where the ray ended, how many times it
# went round the hole, how many integration steps it took.

# %%
hits = source.GetHitsOutput()
termination = numpy_support.vtk_to_numpy(hits.GetPointData().GetArray("Termination"))
order = numpy_support.vtk_to_numpy(hits.GetPointData().GetArray("ImageOrder"))
steps = numpy_support.vtk_to_numpy(hits.GetPointData().GetArray("Steps"))
print(f"shadow (captured rays): {(termination == 2).mean():.1%} of the pixels")
print(f"secondary images (image order >= 1): {(order >= 1).mean():.1%}")
print(f"integration steps per ray: median {int(sorted(steps)[len(steps) // 2])}, max {steps.max()}")

# %% [markdown]
# ## Into a VTK pipeline: the picture as PNG

# %%
png = vtk.vtkPNGWriter()
png.SetInputConnection(source.GetOutputPort(0))
png.SetFileName(os.path.join(out, "kerr-disk-python.png"))
png.Write()
print("wrote", png.GetFileName())

# %% [markdown]
# ## Accumulate it in PostgreSQL, and read back only the photon ring with SQL

# %%
if conninfo is not None:
    writer = vtkGeodesicPostgreSQLWriter()
    writer.SetInputConnection(source.GetOutputPort(1))
    writer.SetConnectionString(conninfo)
    writer.SetLabel("python example")
    writer.ReplaceExistingOn()
    writer.Write()
    print("stored as frame", writer.GetFrameId())

    ring = vtkGeodesicPostgreSQLReader()
    ring.SetConnectionString(conninfo)
    ring.SetFrameId(writer.GetFrameId())
    ring.SetPredicate("image_order >= 1")
    ring.Update()
    print("rays of the photon ring read back:", ring.GetHitsOutput().GetNumberOfPoints())
    ring_png = vtk.vtkPNGWriter()
    ring_png.SetInputConnection(ring.GetOutputPort(0))
    ring_png.SetFileName(os.path.join(out, "kerr-disk-python-ring.png"))
    ring_png.Write()
    print("wrote", ring_png.GetFileName())
