// A camera path through key cameras: the movie's (GeodesicCameraPath.h, shared with
// vtkGeodesicMovieSource), under the tools' names.
#ifndef asrt_tools_CameraPath_h
#define asrt_tools_CameraPath_h

#include "CameraOrbit.h"
#include "GeodesicCameraPath.h"

namespace asrt
{
namespace tools
{
using asrt::cameraOnPath;
using asrt::parseCameraKeys;
}
}

#endif
