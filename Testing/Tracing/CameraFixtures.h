// Cameras for the tracing tests, set from where they stand and what they look at.
#ifndef asrt_CameraFixtures_h
#define asrt_CameraFixtures_h

#include "Camera.h"
#include "RayFixtures.h"

namespace asrt
{
namespace testing
{
/// A camera at `from` looking at `at`.
inline CameraParameters looking(const Vec3& from, const Vec3& at, const Vec3& up, double angle,
                                int w, int h, ObserverMotion motion = ObserverMotion::Static)
{
  CameraParameters p;
  p.position = from;
  p.focalPoint = at;
  p.viewUp = up;
  p.viewAngle = angle;
  p.width = w;
  p.height = h;
  p.observer = motion;
  return p;
}
}
}

#endif
