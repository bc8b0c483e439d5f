// A camera orbiting the hole: the scene's camera (eye, focal point, up) turned about the hole's
// axis z, for movies and time series whose viewpoint moves.
#ifndef asrt_tools_CameraOrbit_h
#define asrt_tools_CameraOrbit_h

#include "AsrtTypes.h"

#include <string>

class vtkGeodesicSource;

namespace asrt
{
namespace tools
{
struct CameraPose
{
  Vec3 position = Vec3::Zero();
  Vec3 focalPoint = Vec3::Zero();
  Vec3 viewUp = Vec3::UnitZ();
};

/// The camera of a scene file (its images are not read). Throws InvalidParameter for a missing
/// or invalid scene.
CameraPose sceneCamera(const std::string& scenePath);
/// The same from the scene's JSON text.
CameraPose sceneCameraOfText(const std::string& sceneText);
/// The pose turned by `degrees` about the z axis through the origin (counter-clockwise seen from
/// +z): the eye keeps its distance and height, so the hole looks the same but the sky and the
/// objects move.
CameraPose turnedAboutZ(const CameraPose& pose, double degrees);
/// The angle of frame k of n on an orbit through `degrees`: a full turn (±360) closes on itself
/// (k·360/n, the last frame one step short of the first); a partial one runs from 0 to `degrees`
/// inclusive.
double orbitAngle(int k, int n, double degrees);
/// Sets the source's camera overrides to the pose.
void setCamera(vtkGeodesicSource* source, const CameraPose& pose);
}
}

#endif
