#include "CameraOrbit.h"

#include "SceneFile.h"
#include "vtkGeodesicSource.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace asrt
{
namespace tools
{
CameraPose sceneCamera(const std::string& scenePath)
{
  std::ifstream in(scenePath, std::ios::binary);
  if (!in)
    throw InvalidParameter("cannot read scene file \"" + scenePath + "\"");
  std::ostringstream text;
  text << in.rdbuf();
  return sceneCameraOfText(text.str());
}

CameraPose sceneCameraOfText(const std::string& sceneText)
{
  const SceneDescription scene = parseSceneWithoutImages(sceneText);
  return { scene.camera.position, scene.camera.focalPoint, scene.camera.viewUp };
}

CameraPose turnedAboutZ(const CameraPose& pose, double degrees)
{
  const double t = degrees * M_PI / 180.0, c = std::cos(t), s = std::sin(t);
  auto turn = [c, s](const Vec3& v)
  { return Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()); };
  return { turn(pose.position), turn(pose.focalPoint), turn(pose.viewUp) };
}

double orbitAngle(int k, int n, double degrees)
{
  if (n <= 1)
    return 0.0;
  const bool closed = std::abs(std::abs(degrees) - 360.0) < 1e-9;
  return degrees * k / (closed ? n : n - 1);
}

void setCamera(vtkGeodesicSource* source, const CameraPose& pose)
{
  source->SetCameraPosition(pose.position.x(), pose.position.y(), pose.position.z());
  source->SetFocalPoint(pose.focalPoint.x(), pose.focalPoint.y(), pose.focalPoint.z());
  source->SetViewUp(pose.viewUp.x(), pose.viewUp.y(), pose.viewUp.z());
}
}
}
