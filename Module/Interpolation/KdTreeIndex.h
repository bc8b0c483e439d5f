// A nearest-point search for matchFrames (FrameMatching.h, PointIndex) over a k-d tree: nanoflann's
// KDTreeSingleIndexAdaptor (Blanco and Rai, https://github.com/jlblancoc/nanoflann), built once
// over the fixed points, its queries const and so thread-safe. What the filters, the CLI and the
// benches match frames with: on two 1920×1080 frames of the mass ramp it finds the same matches as
// VTK's static point locator in a third of the time (bench/REPORT.md, the interpolation section).
#ifndef asrt_KdTreeIndex_h
#define asrt_KdTreeIndex_h

#include "FrameMatching.h"
#include "asrtInterpolationModule.h"

namespace asrt
{
/// A factory of k-d tree indices over the points given (Euclidean distance). nearestWithin returns
/// the nearest point within the radius (of equally near ones, the lowest index), within the points
/// within it, in increasing order of index.
ASRTINTERPOLATION_EXPORT PointIndexFactory kdTreeIndexFactory();
}

#endif
