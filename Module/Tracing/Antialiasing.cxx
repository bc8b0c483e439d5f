#include "Antialiasing.h"

#include "AdaptiveGrid.h"

#include "SceneDescription.h"

#include <cmath>
#include <sstream>

namespace asrt
{
const char* toString(AntialiasMode m)
{
  switch (m)
  {
    case AntialiasMode::None:
      return "none";
    case AntialiasMode::Filter:
      return "filter";
    case AntialiasMode::Adaptive:
      return "adaptive";
  }
  return "none";
}

AntialiasMode antialiasModeFromString(const std::string& s)
{
  if (s == "none")
    return AntialiasMode::None;
  if (s == "filter")
    return AntialiasMode::Filter;
  if (s == "adaptive")
    return AntialiasMode::Adaptive;
  throw InvalidParameter("unknown anti-aliasing mode \"" + s.substr(0, 40) +
                         "\" (use none, filter or adaptive)");
}

AntialiasOptions renderingPreset(const std::string& name)
{
  AntialiasOptions o;
  if (name == "fast")
    o.mode = AntialiasMode::Filter;
  else if (name == "balanced")
  {
    o.mode = AntialiasMode::Adaptive;
    o.maxRaysPerPixel = 9;
  }
  else if (name == "accurate")
  {
    o.mode = AntialiasMode::Adaptive;
    o.maxRaysPerPixel = 25;
    o.gridLattice = 1;
  }
  else
    throw InvalidParameter("unknown preset \"" + name.substr(0, 40) +
                           "\" (use fast, balanced or accurate)");
  return o;
}

void validateRendering(const AntialiasOptions& o, long long pixels)
{
  auto refuse = [](const char* field, const std::string& msg)
  { throw InvalidParameter(std::string("rendering.") + field + ": " + msg); };
  if (o.maxRaysPerPixel < 1 || o.maxRaysPerPixel > kMaxRaysPerPixel)
    refuse("maxRaysPerPixel", "must lie in [1, " + std::to_string(kMaxRaysPerPixel) + "], got " +
                                std::to_string(o.maxRaysPerPixel));
  if (o.supersample < 1 || o.supersample > 32)
    refuse("supersample", "must lie in [1, 32], got " + std::to_string(o.supersample));
  if (!(o.colorThreshold >= 0.0 && o.colorThreshold <= 1.0))
  {
    std::ostringstream os;
    os << o.colorThreshold;
    refuse("colorThreshold", "must lie in [0, 1], got " + os.str());
  }
  if (o.gridLattice < 1 || o.gridLattice > kMaxGridLattice)
    refuse("gridLattice", "must lie in [1, " + std::to_string(kMaxGridLattice) + "], got " +
                            std::to_string(o.gridLattice));
  if (!(o.gridTolerance >= 0.0 && std::isfinite(o.gridTolerance)))
  {
    std::ostringstream os;
    os << o.gridTolerance;
    refuse("gridTolerance", "must be finite and at least 0, got " + os.str());
  }
  // Rays, not memory, are what a supersample multiplies (the samples of a pixel are folded into
  // its colour as they come); the bound is the frame's: a frame of more rays would take days.
  const long long rays = static_cast<long long>(patternRays(o.supersample)) * pixels;
  if (pixels > 0 && rays > kMaxFramePixels)
    refuse("supersample", std::to_string(o.supersample) + " x " + std::to_string(o.supersample) +
                            " samples (" + std::to_string(patternRays(o.supersample)) +
                            " rays) on each of " + std::to_string(pixels) + " pixels make " +
                            std::to_string(rays) + " rays, more than the " +
                            std::to_string(kMaxFramePixels) + " a frame may trace");
}
}
