// A movie's path and its frames' scenes (GeodesicMovie.h): ramps, orbits, and the frames a path
// gives a vtkGeodesicSource, each checked before anything is traced.
#include "GeodesicMovie.h"

#include "SceneFile.h"
#include "vtkGeodesicSource.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkNew.h"

#include <cmath>
#include <cstdio>

namespace asrt
{
void setRampParameter(vtkGeodesicSource* source, const std::string& parameter, double v)
{
  if (parameter == "mass")
    source->SetMass(v);
  else if (parameter == "spin")
    source->SetSpin(v);
  else if (parameter == "charge")
    source->SetCharge(v);
  else
    throw InvalidParameter("ramp: unknown parameter '" + parameter + "' (mass, spin or charge)");
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

std::string formatParameter(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

namespace
{
void checkFrameCount(int n)
{
  if (n < 2 || n > kMaxMovieFrames)
    throw InvalidParameter("frames: a movie has 2 to " + std::to_string(kMaxMovieFrames) +
                           " frames, got " + std::to_string(n));
}
}

MoviePath rampMoviePath(const std::string& parameter, double from, double to, int n)
{
  if (parameter != "mass" && parameter != "spin" && parameter != "charge")
    throw InvalidParameter("ramp: unknown parameter '" + parameter.substr(0, 40) +
                           "' (mass, spin or charge)");
  checkFrameCount(n);
  if (!std::isfinite(from) || !std::isfinite(to))
    throw InvalidParameter("ramp: FROM and TO must be finite numbers");
  if (from == to)
    throw InvalidParameter("ramp: FROM and TO are equal (" + formatParameter(from) + "): no path");
  MoviePath path;
  path.parameter = parameter;
  for (int k = 0; k < n; ++k)
  {
    // The formula of asrt trace --sweep, so that its frames are these frames.
    const double v = from + (to - from) * k / (n - 1);
    path.s.push_back(v);
    path.apply.push_back([parameter, v](vtkGeodesicSource* src)
                         { setRampParameter(src, parameter, v); });
  }
  return path;
}

MoviePath orbitMoviePath(const CameraPose& pose, double degrees, int n)
{
  checkFrameCount(n);
  if (!std::isfinite(degrees) || degrees == 0 || std::abs(degrees) > 360)
    throw InvalidParameter("orbit: DEGREES must be nonzero and at most 360 in magnitude, got " +
                           formatParameter(degrees));
  MoviePath path;
  path.parameter = "orbit angle";
  for (int k = 0; k < n; ++k)
  {
    const double angle = orbitAngle(k, n, degrees);
    const CameraPose turned = turnedAboutZ(pose, angle);
    path.s.push_back(angle);
    path.apply.push_back([turned](vtkGeodesicSource* src) { setCamera(src, turned); });
  }
  return path;
}

namespace
{
/// The first error the source reports while watched, instead of VTK's output window.
struct SourceErrors
{
  std::string first;
  static void onError(vtkObject*, unsigned long, void* clientData, void* callData)
  {
    auto* self = static_cast<SourceErrors*>(clientData);
    if (self->first.empty() && callData)
      self->first = static_cast<const char*>(callData);
  }
};
}

std::vector<MovieFrame> movieFrames(vtkGeodesicSource* source, const MoviePath& path)
{
  std::vector<MovieFrame> frames(path.s.size());
  SourceErrors errors;
  vtkNew<vtkCallbackCommand> onError;
  onError->SetClientData(&errors);
  onError->SetCallback(&SourceErrors::onError);
  const unsigned long tag = source->AddObserver(vtkCommand::ErrorEvent, onError);
  try
  {
    for (std::size_t k = 0; k < frames.size(); ++k)
    {
      MovieFrame& f = frames[k];
      f.s = path.s[k];
      f.describe = path.parameter + " = " + formatParameter(f.s);
      path.apply[k](source);
      errors.first.clear();
      // The textures, which the path does not change, are read (and so checked) once.
      f.sceneText = k == 0 ? source->GetFrameSceneText() : source->GetFrameSceneTextWithoutImages();
      if (!errors.first.empty() || f.sceneText.empty())
      {
        // VTK's messages lead with where they were raised: the reason is after the last ": ".
        std::string reason = errors.first;
        const std::size_t at = reason.find("): ");
        if (at != std::string::npos)
          reason = reason.substr(at + 3);
        while (!reason.empty() && (reason.back() == '\n' || reason.back() == ' '))
          reason.pop_back();
        throw InvalidParameter("frame " + std::to_string(k) + " (" + f.describe + "): " + reason);
      }
      f.identity = parseSceneWithoutImages(f.sceneText);
    }
  }
  catch (...)
  {
    source->RemoveObserver(tag);
    throw;
  }
  source->RemoveObserver(tag);
  return frames;
}
}
