#include "SceneDescription.h"

#include "RayRecord.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace asrt
{
namespace
{
/// FNV-1a, 64 bits, over little-endian bytes.
struct Fnv1a64
{
  std::uint64_t h = 14695981039346656037ULL;
  void feed(std::uint64_t u, int bytes)
  {
    for (int b = 0; b < bytes; ++b)
    {
      this->h ^= (u >> (8 * b)) & 0xffu;
      this->h *= 1099511628211ULL;
    }
  }
  void feed(std::int32_t v) { this->feed(static_cast<std::uint32_t>(v), 4); }
  void feed(double v)
  {
    std::uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    this->feed(u, 8);
  }
  std::string hex() const
  {
    char out[17];
    std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(this->h));
    return out;
  }
};
}

PixelSubsetId pixelSubsetId(std::vector<std::pair<int, int>> pixels)
{
  std::sort(pixels.begin(), pixels.end());
  pixels.erase(std::unique(pixels.begin(), pixels.end()), pixels.end());
  PixelSubsetId id;
  id.count = static_cast<std::int64_t>(pixels.size());
  if (pixels.empty())
    return id;
  Fnv1a64 h;
  for (const auto& [i, j] : pixels)
  {
    h.feed(static_cast<std::int32_t>(i));
    h.feed(static_cast<std::int32_t>(j));
  }
  id.digest = h.hex();
  return id;
}

std::string borderDigest(std::vector<JacobianSample> border)
{
  if (border.empty())
    return {};
  std::sort(border.begin(), border.end(),
            [](const JacobianSample& a, const JacobianSample& b)
            { return std::pair(a.j, a.i) < std::pair(b.j, b.i); });
  Fnv1a64 h;
  for (const JacobianSample& s : border)
  {
    h.feed(s.i);
    h.feed(s.j);
    h.feed(s.u);
    h.feed(s.v);
    h.feed(s.objectId);
    h.feed(s.imageOrder);
    h.feed(static_cast<std::int32_t>(s.termination));
  }
  return h.hex();
}

namespace
{
[[noreturn]] void refuse(const std::string& field, const std::string& msg)
{
  throw InvalidParameter(field + ": " + msg);
}

std::string shown(double v)
{
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string shown(const Vec3& v)
{
  std::ostringstream os;
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

const char* const kLengthBound = " in magnitude (the bound on a scene's lengths: beyond it r+ and "
                                 "r^4 overflow a double)";

void requireFiniteField(double v, const std::string& field)
{
  if (!std::isfinite(v))
    refuse(field, "must be finite, got " + shown(v));
}

void requirePositive(double v, const std::string& field)
{
  requireFiniteField(v, field);
  if (!(v > 0.0))
    refuse(field, "must be positive, got " + shown(v));
}

void requireLength(double v, const std::string& field)
{
  requireFiniteField(v, field);
  if (std::abs(v) > kMaxSceneLength)
    refuse(field, "must be at most " + shown(kMaxSceneLength) + kLengthBound + ", got " + shown(v));
}

void requirePoint(const Vec3& x, const std::string& field)
{
  if (!x.allFinite())
    refuse(field, "must be finite, got " + shown(x));
  if (x.cwiseAbs().maxCoeff() > kMaxSceneLength)
    refuse(field, "coordinates must be at most " + shown(kMaxSceneLength) + kLengthBound +
                    ", got " + shown(x));
}

/// A direction: finite, nonzero, and with a squared norm that neither overflows nor underflows.
void requireDirection(const Vec3& v, const std::string& field)
{
  if (!v.allFinite())
    refuse(field, "must be finite, got " + shown(v));
  const double scale = v.cwiseAbs().maxCoeff();
  if (!(scale > 1e-150))
    refuse(field, "must be a nonzero vector (norm above 1e-150), got " + shown(v));
  if (!(scale < 1e150))
    refuse(field, "components must be below 1e150 in magnitude (its squared norm would overflow), "
                  "got " +
                    shown(v));
}
}

void validateSpacetime(const SpacetimeParameters& p)
{
  requireFiniteField(p.mass, "spacetime.mass");
  if (!(p.mass >= 0.0))
    refuse("spacetime.mass", "must be non-negative, got " + shown(p.mass));
  requireLength(p.mass, "spacetime.mass");
  if (p.mass > 0.0 && p.mass < kMinSceneMass)
    refuse("spacetime.mass", "must be 0 or at least " + shown(kMinSceneMass) +
                               " (below it M^2 underflows and r+ loses the spin), got " +
                               shown(p.mass));
  requireFiniteField(p.spin, "spacetime.spin");
  requireFiniteField(p.charge, "spacetime.charge");
  try
  {
    makeSpacetime(p); // |a| <= M, |Q| <= M, not both
  }
  catch (const InvalidParameter& e)
  {
    refuse("spacetime", e.what());
  }
}

void validateCamera(const CameraParameters& c, const Spacetime& st)
{
  requirePoint(c.position, "camera.position");
  requirePoint(c.focalPoint, "camera.focalPoint");
  requireDirection(c.viewUp, "camera.viewUp");
  requireFiniteField(c.viewAngle, "camera.viewAngle");
  if (!(c.viewAngle > 0.0 && c.viewAngle < 180.0))
    refuse("camera.viewAngle", "must lie in (0, 180) degrees, got " + shown(c.viewAngle));
  const std::string size = std::to_string(c.width) + " x " + std::to_string(c.height);
  if (c.width < 1 || c.height < 1)
    refuse("camera.resolution", "must be positive, got " + size);
  if (static_cast<long long>(c.width) * c.height > kMaxFramePixels)
    refuse("camera.resolution", size + " pixels exceed the budget of " +
                                  std::to_string(kMaxFramePixels) + " pixels a frame");

  // Both points are bounded, so the view's norm is finite and only zero if they coincide.
  const Vec3 view = c.focalPoint - c.position;
  if (!(view.norm() > 0.0))
    refuse("camera.focalPoint", "coincides with camera.position");
  if (view.normalized().cross(c.viewUp.normalized()).norm() < 1e-9)
    refuse("camera.viewUp", "is parallel to the direction of view");
  // An eye inside the horizon sees nothing from outside, and a static observer cannot exist
  // where ∂_t is not timelike. (Coordinates are in the units of the mass.)
  const Vec4 x(0.0, c.position.x(), c.position.y(), c.position.z());
  const double r = st.radius(x), rPlus = st.outerHorizon();
  if (rPlus > 0.0 && !(r > rPlus))
    refuse("camera.position",
           "is inside the horizon (r = " + shown(r) + ", r+ = " + shown(rPlus) + ")");
  if (c.observer == ObserverMotion::Static && !st.isFlat() && !(st.metric(x)(0, 0) < 0.0))
    refuse("camera.observer", "a static observer cannot exist at r = " + shown(r) +
                                " (inside the ergosphere, g_tt >= 0); use \"zamo\"");
  try
  {
    Camera(st, c); // anything else its tetrad cannot be built from
  }
  catch (const InvalidParameter& e)
  {
    refuse("camera", e.what());
  }
}

void validateIntegrator(const IntegratorConfig& c, const Spacetime& st)
{
  if (c.method.empty())
    refuse("integrator.method", "must not be empty");
  if (c.method != "auto")
  {
    try
    {
      findMethod(c.method);
    }
    catch (const InvalidParameter& e)
    {
      refuse("integrator.method", e.what());
    }
  }
  requirePositive(c.step, "integrator.step");
  requirePositive(c.omega, "integrator.omega");
  requirePositive(c.relativeTolerance, "integrator.relativeTolerance");
  requirePositive(c.absoluteTolerance, "integrator.absoluteTolerance");
  // Whether the method can model this spacetime (a Schwarzschild splitting cannot trace Kerr).
  try
  {
    makePropagator(st, c);
  }
  catch (const InvalidParameter& e)
  {
    refuse("integrator.method", e.what());
  }
}

void validateTracing(const TraceOptions& t)
{
  requirePositive(t.escapeRadius, "tracing.escapeRadius");
  requireLength(t.escapeRadius, "tracing.escapeRadius");
  if (t.maxSteps < 1)
    refuse("tracing.maxSteps", "must be a positive integer, got " + std::to_string(t.maxSteps));
  requirePositive(t.horizonEpsilon, "tracing.horizonEpsilon");
  // A ray is captured within (1 + horizonEpsilon) r+: a margin beyond the horizon's own radius
  // would call rays captured that pass far outside it (1e300 makes every ray captured).
  if (!(t.horizonEpsilon <= 1.0))
    refuse("tracing.horizonEpsilon",
           "must lie in (0, 1] (the capture margin, a fraction of the horizon's radius), got " +
             shown(t.horizonEpsilon));
  requirePositive(t.maxHamiltonianError, "tracing.maxHamiltonianError");
  // |H| is relative to the ray's energy scale: 1 or more accepts a ray that is no longer null.
  if (!(t.maxHamiltonianError < 1.0))
    refuse("tracing.maxHamiltonianError",
           "must lie in (0, 1) (the largest |H| a ray may reach, relative to its energy), got " +
             shown(t.maxHamiltonianError));
}

void validateCelestialSphere(double radius, const Vec3& eye, const std::string& field)
{
  requirePositive(radius, field);
  requireLength(radius, field);
  const double distance = eye.norm();
  if (!(distance < radius))
    refuse(field, "the celestial sphere is seen from inside: it must enclose the camera "
                  "(|position| = " +
                    shown(distance) + "), got " + shown(radius));
}

void validateScene(const SceneDescription& d)
{
  validateSpacetime(d.spacetime);
  const auto st = makeSpacetime(d.spacetime);
  validateCamera(d.camera, *st);
  validateIntegrator(d.integrator, *st);
  validateTracing(d.tracing);
  if (!d.scene)
    refuse("objects", "the description has no scene");
  const auto& objects = d.scene->objects();
  for (std::size_t k = 0; k < objects.size(); ++k)
    if (const auto* sky = dynamic_cast<const CelestialSphere*>(objects[k].get()))
      validateCelestialSphere(sky->radius(), d.camera.position,
                              "objects[" + std::to_string(k) + "].radius");
  validateRendering(d.rendering, static_cast<long long>(d.camera.width) * d.camera.height);
}
}
