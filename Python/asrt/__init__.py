"""ASRT: black-hole ray tracing as VTK filters.

The classes are VTK's own Python wrappings of ASRT's C++ filters (module asrtFilters), so they
take and give the types of the `vtk` package and join its pipelines:

    import vtk
    from asrt import vtkGeodesicSource

    source = vtkGeodesicSource()
    source.SetSceneFileName("Data/scenes/kerr-disk.json")
    writer = vtk.vtkPNGWriter()
    writer.SetInputConnection(source.GetOutputPort(0))
"""

# The wrapped filters derive from these modules' classes; importing them first registers the
# base types with VTK's wrapping.
import vtkmodules.vtkCommonCore  # noqa: F401
import vtkmodules.vtkCommonExecutionModel  # noqa: F401
import vtkmodules.vtkParallelCore  # noqa: F401

from .asrtFilters import *  # noqa: F401,F403
