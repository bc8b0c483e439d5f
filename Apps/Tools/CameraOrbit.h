// A camera orbiting the hole: the scene's camera (eye, focal point, up) turned about the hole's
// axis z, for movies and time series whose viewpoint moves.
#ifndef asrt_tools_CameraOrbit_h
#define asrt_tools_CameraOrbit_h

#include "AsrtTypes.h"
#include "GeodesicMovie.h"

#include <string>

namespace asrt
{
namespace tools
{
// The pose, turning it about z, the orbit's angles and setting a source's camera are the movie's
// (GeodesicMovie.h, shared with vtkGeodesicMovieSource).
using asrt::CameraPose;
using asrt::orbitAngle;
using asrt::sceneCameraOfText;
using asrt::setCamera;
using asrt::turnedAboutZ;

/// The camera of a scene file (its images are not read). Throws InvalidParameter for a missing
/// or invalid scene.
CameraPose sceneCamera(const std::string& scenePath);
}
}

#endif
