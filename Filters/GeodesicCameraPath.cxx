#include "GeodesicCameraPath.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace asrt
{
namespace
{
using json = nlohmann::json;

Vec3 vector3(const json& keys, std::size_t k, const char* field, const std::string& name)
{
  const std::string where = name + ": keys[" + std::to_string(k) + "]." + field;
  const json& key = keys[k];
  if (!key.contains(field))
    throw InvalidParameter(where + " is missing");
  const json& v = key[field];
  if (!v.is_array() || v.size() != 3)
    throw InvalidParameter(where + " must be an array of 3 numbers");
  Vec3 out;
  for (std::size_t c = 0; c < 3; ++c)
  {
    if (!v[c].is_number() || !std::isfinite(v[c].get<double>()))
      throw InvalidParameter(where + "[" + std::to_string(c) + "] is not a finite number");
    out[static_cast<int>(c)] = v[c].get<double>();
  }
  return out;
}

/// The uniform Catmull-Rom segment from p1 (f = 0) to p2 (f = 1).
Vec3 catmullRom(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double f)
{
  const double f2 = f * f, f3 = f2 * f;
  return 0.5 * ((2 * p1) + (p2 - p0) * f + (2 * p0 - 5 * p1 + 4 * p2 - p3) * f2 +
                (3 * p1 - p0 - 3 * p2 + p3) * f3);
}
}

std::vector<CameraPose> parseCameraKeys(const std::string& text, const std::string& name)
{
  json root;
  try
  {
    root = json::parse(text);
  }
  catch (const json::exception& e)
  {
    throw InvalidParameter(name + ": not valid JSON (" + e.what() + ")");
  }
  if (!root.is_object() || !root.contains("keys") || !root["keys"].is_array())
    throw InvalidParameter(name + ": expected {\"keys\": [{\"position\": [x, y, z], "
                                  "\"focalPoint\": [x, y, z], \"viewUp\": [x, y, z]}, ...]}");
  for (const auto& item : root.items())
    if (item.key() != "keys")
      throw InvalidParameter(name + ": unknown field \"" + item.key() + "\"");
  const json& keys = root["keys"];
  if (keys.size() < 2)
    throw InvalidParameter(name + ": keys: a path needs at least 2 key cameras, got " +
                           std::to_string(keys.size()));
  std::vector<CameraPose> poses;
  for (std::size_t k = 0; k < keys.size(); ++k)
  {
    if (!keys[k].is_object())
      throw InvalidParameter(name + ": keys[" + std::to_string(k) + "] must be an object");
    for (const auto& item : keys[k].items())
      if (item.key() != "position" && item.key() != "focalPoint" && item.key() != "viewUp")
        throw InvalidParameter(name + ": keys[" + std::to_string(k) + "]: unknown field \"" +
                               item.key() + "\"");
    poses.push_back({ vector3(keys, k, "position", name), vector3(keys, k, "focalPoint", name),
                      vector3(keys, k, "viewUp", name) });
  }
  return poses;
}

CameraPose cameraOnPath(const std::vector<CameraPose>& keys, double u)
{
  const int last = static_cast<int>(keys.size()) - 1;
  const int a = std::clamp(static_cast<int>(std::floor(u)), 0, last - 1);
  const double f = std::clamp(u - a, 0.0, 1.0);
  auto at = [&keys, last](int k, Vec3 CameraPose::*field)
  {
    if (k < 0) // reflected: the end tangent is the first chord's
      return Vec3(2 * (keys[0].*field) - keys[1].*field);
    if (k > last)
      return Vec3(2 * (keys[static_cast<std::size_t>(last)].*field) -
                  keys[static_cast<std::size_t>(last - 1)].*field);
    return Vec3(keys[static_cast<std::size_t>(k)].*field);
  };
  auto spline = [&](Vec3 CameraPose::*field)
  { return catmullRom(at(a - 1, field), at(a, field), at(a + 1, field), at(a + 2, field), f); };
  CameraPose pose{ spline(&CameraPose::position), spline(&CameraPose::focalPoint),
                   spline(&CameraPose::viewUp) };
  if (pose.viewUp.norm() > 0)
    pose.viewUp.normalize();
  return pose;
}

MoviePath cameraKeyMoviePath(const std::vector<CameraPose>& keys, int n)
{
  if (n < 2 || n > kMaxMovieFrames)
    throw InvalidParameter("frames: a movie has 2 to " + std::to_string(kMaxMovieFrames) +
                           " frames, got " + std::to_string(n));
  if (keys.size() < 2)
    throw InvalidParameter("keys: a path needs at least 2 key cameras, got " +
                           std::to_string(keys.size()));
  MoviePath path;
  path.parameter = "camera key";
  const double last = static_cast<double>(keys.size() - 1);
  for (int k = 0; k < n; ++k)
  {
    // Frame k at u = (K - 1) k / (n - 1): the keys at u = 0 ... K - 1, the first and last frames
    // the first and last keys.
    const double u = last * k / (n - 1);
    const CameraPose pose = cameraOnPath(keys, u);
    path.s.push_back(u);
    path.apply.push_back([pose](vtkGeodesicSource* src) { setCamera(src, pose); });
  }
  return path;
}
}
