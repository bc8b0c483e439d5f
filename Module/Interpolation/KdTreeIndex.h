// A nearest-point search for matchFrames (FrameMatching.h, PointIndex) over a k-d tree: nanoflann's
// KDTreeSingleIndexAdaptor (Blanco and Rai, https://github.com/jlblancoc/nanoflann), built once
// over the fixed points, its queries const and so thread-safe. Plain C++, for callers without a
// VTK locator at hand, and for the matching of the moved edges along a path (PathEdges.h), where
// the searches are most of the work.
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
