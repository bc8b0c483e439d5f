#include "SettingsError.h"

#include "AsrtTypes.h"
#include "ErrorEstimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace asrt
{
namespace
{
constexpr int kStrata = 3;
/// Standard errors added to a stratum's mean, as completePathFrame's probe bound.
constexpr double kSettingsConfidence = 2.0;

/// 0: sampled by more than its centre ray; 1: centre interpolated by the grid; 2: one ray.
int stratumOf(const RayRecord& r)
{
  if (r.raysPerPixel > 1)
    return 0;
  return r.traced ? 2 : 1;
}

/// Squared colour difference per channel (the mean over the three), in levels² of 255.
double channelError2(const Color& a, const Color& b)
{
  const Color d = 255.0 * (a - b);
  return d.squaredNorm() / 3.0;
}

[[noreturn]] void invalid(const std::string& what)
{
  throw InvalidParameter("settings error: " + what);
}
}

double SettingsError::psnr() const
{
  return psnrOfMse(this->mseBound);
}

std::vector<std::int32_t> settingsProbes(const std::vector<RayRecord>& frame,
                                         std::size_t perStratum, std::uint64_t seed)
{
  std::vector<std::int32_t> members[kStrata];
  for (std::size_t p = 0; p < frame.size(); ++p)
    members[stratumOf(frame[p])].push_back(static_cast<std::int32_t>(p));
  std::vector<std::int32_t> probes;
  for (int s = 0; s < kStrata; ++s)
  {
    // probePixels ranks indices into the stratum by a fixed hash: the same frame, the same probes.
    const std::vector<std::int32_t> picked =
      probePixels(members[s].size(), 0.0, s == 0 ? 2 * perStratum : perStratum,
                  seed + static_cast<unsigned>(s));
    for (std::int32_t k : picked)
      probes.push_back(members[s][static_cast<std::size_t>(k)]);
  }
  std::sort(probes.begin(), probes.end());
  return probes;
}

SettingsError settingsError(const std::vector<RayRecord>& frame,
                            const std::vector<std::int32_t>& probes,
                            const std::vector<RayRecord>& converged)
{
  if (converged.size() != probes.size())
    invalid(std::to_string(converged.size()) + " converged records for " +
            std::to_string(probes.size()) + " probes");
  std::size_t size[kStrata] = {};
  for (const RayRecord& r : frame)
    ++size[stratumOf(r)];
  double count[kStrata] = {}, sum[kStrata] = {}, sum2[kStrata] = {}, largest[kStrata] = {};
  for (std::size_t q = 0; q < probes.size(); ++q)
  {
    if (probes[q] < 0 || static_cast<std::size_t>(probes[q]) >= frame.size())
      invalid("probe " + std::to_string(probes[q]) + " lies outside the frame of " +
              std::to_string(frame.size()) + " pixels");
    const RayRecord& r = frame[static_cast<std::size_t>(probes[q])];
    const int s = stratumOf(r);
    const double e = channelError2(r.color, converged[q].color);
    count[s] += 1;
    sum[s] += e;
    sum2[s] += e * e;
    largest[s] = std::max(largest[s], e);
  }
  SettingsError out;
  out.probes = probes.size();
  const double n = static_cast<double>(frame.size());
  for (int s = 0; s < kStrata; ++s)
  {
    if (size[s] == 0)
      continue;
    const double share = static_cast<double>(size[s]) / n;
    if (count[s] <= 0)
    {
      out.mseBound = std::numeric_limits<double>::infinity(); // a stratum nobody probed
      continue;
    }
    const double mean = sum[s] / count[s];
    out.mse += share * mean;
    // Every pixel of a stratum probed: its mean is exact.
    if (count[s] >= static_cast<double>(size[s]))
    {
      out.mseBound += share * mean;
      continue;
    }
    const double variance = std::max(0.0, sum2[s] / count[s] - mean * mean);
    out.mseBound += share * ((sum[s] + largest[s]) / (count[s] + 1) +
                             kSettingsConfidence * std::sqrt(variance / count[s]));
  }
  return out;
}

SettingsError measureSettingsError(const std::vector<RayRecord>& frame, int width, int height,
                                   const PixelTracer& converged, std::size_t perStratum)
{
  if (width <= 0 || height <= 0 ||
      frame.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    invalid("a frame of " + std::to_string(frame.size()) + " records is not " +
            std::to_string(width) + " x " + std::to_string(height));
  const std::vector<std::int32_t> probes = settingsProbes(frame, perStratum);
  std::vector<std::pair<int, int>> ij;
  ij.reserve(probes.size());
  for (std::int32_t p : probes)
    ij.emplace_back(p % width, p / width);
  const TracedPixels traced = converged(ij);
  SettingsError out = settingsError(frame, probes, traced.records);
  out.rays = traced.rays;
  return out;
}

SettingsError worseOf(const SettingsError& a, const SettingsError& b)
{
  SettingsError out;
  out.mse = std::max(a.mse, b.mse);
  out.mseBound = std::max(a.mseBound, b.mseBound);
  out.probes = a.probes + b.probes;
  out.rays = a.rays + b.rays;
  return out;
}
}
