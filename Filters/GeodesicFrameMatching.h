// The VTK side of frame matching: a frame's samples read straight from the hit-point arrays of
// vtkGeodesicSource or vtkGeodesicPostgreSQLReader (port 1), without building whole ray records.
// The searches matchFrames needs are the k-d tree's (KdTreeIndex.h).
#ifndef asrt_GeodesicFrameMatching_h
#define asrt_GeodesicFrameMatching_h

#include "FrameMatching.h"
#include "asrtFiltersModule.h" // for export macro

#include <string>

class vtkPolyData;

namespace asrt
{
/// The samples of a whole frame from its hit points; `scene` is the frame's description (its
/// resolution and view angle are used). Throws InvalidParameter, naming `which` frame, for a
/// missing or malformed array, a frame that is not whole, or non-finite values.
ASRTFILTERS_EXPORT FrameSamples frameSamplesFromHits(vtkPolyData* hits,
                                                     const SceneDescription& scene,
                                                     const std::string& which);
}

#endif
