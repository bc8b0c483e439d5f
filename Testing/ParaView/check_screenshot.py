# A screenshot of the example layout is not blank: it has the traced picture (many colours, the
# disk's orange among them) on the left and the rays on the right, not one background colour.
# Usage: pvpython check_screenshot.py IMAGE.png
import sys

import numpy
from vtkmodules.util import numpy_support
from vtkmodules.vtkIOImage import vtkPNGReader

reader = vtkPNGReader()
reader.SetFileName(sys.argv[1])
reader.Update()
image = reader.GetOutput()
width, height, _ = image.GetDimensions()
scalars = image.GetPointData().GetScalars()
if scalars is None or width * height == 0:
    sys.exit(f"check_screenshot: {sys.argv[1]} holds no image")
pixels = numpy_support.vtk_to_numpy(scalars)[:, :3].astype(numpy.int32).reshape(height, width, 3)

problems = []
for name, half in (("left (picture)", pixels[:, : width // 2]), ("right (ray bundle)",
                                                                   pixels[:, width // 2:])):
    flat = half.reshape(-1, 3)
    colours, counts = numpy.unique(flat, axis=0, return_counts=True)
    background = counts.max() / len(flat)
    print(f"{name}: {len(colours)} colours, the commonest covers {background:.0%}")
    if len(colours) < 50 or background > 0.9:
        problems.append(f"the {name} half is nearly blank")
# The disk's checker is orange: red high, blue low.
left = pixels[:, : width // 2].reshape(-1, 3)
orange = ((left[:, 0] > 180) & (left[:, 1] > 80) & (left[:, 2] < 90)).mean()
print(f"orange (the disk) covers {orange:.1%} of the picture half")
if orange < 0.02:
    problems.append("no disk in the picture")
if problems:
    sys.exit("check_screenshot: " + "; ".join(problems))
print("check_screenshot: not blank")
