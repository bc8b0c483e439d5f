#include "SettingsError.h"

#include "AsrtTypes.h"
#include "ErrorEstimate.h"
#include "FrameTracer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace asrt
{
namespace
{
constexpr int kStrata = kSettingsStrata;
/// Standard errors added to a stratum's mean, as completePathFrame's probe bound.
constexpr double kSettingsConfidence = 2.0;

constexpr std::uint8_t kSampledStratum = 0, kEdgeStratum = 3;
/// The hash seed of the pixels a partly refined stratum traces converged: another draw than the
/// probes' (kSettingsProbeSeed), which measured the stratum's error.
constexpr std::uint64_t kRefinedPixelSeed = 0x2545f4914f6cdd1dULL;

/// Whether two neighbours' centre rays show alike: the same object, image order and termination.
bool showAlike(const RayRecord& a, const RayRecord& b)
{
  return a.objectId == b.objectId && a.imageOrder == b.imageOrder && a.termination == b.termination;
}

[[noreturn]] void invalid(const std::string& what)
{
  throw InvalidParameter("settings error: " + what);
}
}

double SettingsError::mse() const
{
  double mse = 0;
  for (const SettingsStratum& s : this->strata)
    if (s.count > 0)
      mse += s.share * s.sum / s.count;
  return mse;
}

double SettingsError::mseBound() const
{
  return this->mseBoundWithout(RefinedStrata{});
}

double SettingsError::mseBoundWithout(const RefinedStrata& refined) const
{
  double mse = 0, variance = 0;
  for (int k = 0; k < kStrata; ++k)
  {
    const SettingsStratum& s = this->strata[k];
    if (s.share <= 0 || (refined.whole & (1u << k)))
      continue;
    if (s.count <= 0)
      return std::numeric_limits<double>::infinity(); // a stratum nobody probed
    const double left = k == refined.partial ? 1.0 - refined.fraction : 1.0;
    const double mean = s.sum / s.count;
    mse += left * s.share * mean;
    if (s.count >= s.pixels)
      continue; // probed whole: its mean is exact
    const double spread = std::max(0.0, s.sum2 / s.count - mean * mean);
    variance += left * left * s.share * s.share * spread / s.count;
  }
  return mse + kSettingsConfidence * std::sqrt(variance);
}

std::size_t SettingsError::probes() const
{
  double n = 0;
  for (const SettingsStratum& s : this->strata)
    n += s.count;
  return static_cast<std::size_t>(n);
}

double SettingsError::psnr() const
{
  return psnrOfMse(this->mseBound());
}

std::vector<std::uint8_t> settingsStrata(const std::vector<RayRecord>& frame)
{
  // The frame's width: its records run row by row, the first row from index 0.
  std::size_t width = 0;
  while (width < frame.size() && frame[width].j == frame.front().j)
    ++width;
  std::vector<std::uint8_t> strata(frame.size());
  for (std::size_t p = 0; p < frame.size(); ++p)
  {
    const RayRecord& r = frame[p];
    if (r.raysPerPixel > 1)
    {
      strata[p] = kSampledStratum;
      continue;
    }
    const std::size_t i = width > 0 ? p % width : 0;
    const bool edge = (i > 0 && !showAlike(r, frame[p - 1])) ||
                      (i + 1 < width && p + 1 < frame.size() && !showAlike(r, frame[p + 1])) ||
                      (p >= width && !showAlike(r, frame[p - width])) ||
                      (p + width < frame.size() && !showAlike(r, frame[p + width]));
    strata[p] = edge ? kEdgeStratum : r.traced ? 2 : 1;
  }
  return strata;
}

std::vector<std::int32_t> settingsProbes(const std::vector<RayRecord>& frame,
                                         std::size_t perStratum, std::uint64_t seed)
{
  const std::vector<std::uint8_t> strata = settingsStrata(frame);
  std::vector<std::int32_t> members[kStrata];
  for (std::size_t p = 0; p < frame.size(); ++p)
    members[strata[p]].push_back(static_cast<std::int32_t>(p));
  std::vector<std::int32_t> probes;
  for (int s = 0; s < kStrata; ++s)
  {
    // probePixels ranks indices into the stratum by a fixed hash: the same frame, the same probes.
    // Where the error lies (the strata's order): the sampled pixels twice, the unsampled edges
    // once, the grid's and the traced single rays, which hold little, half each.
    const std::size_t count = s == kSampledStratum ? 2 * perStratum
                              : s == kEdgeStratum  ? perStratum
                                                   : (perStratum + 1) / 2;
    const std::vector<std::int32_t> picked =
      probePixels(members[s].size(), 0.0, count, seed + static_cast<unsigned>(s));
    for (std::int32_t k : picked)
      probes.push_back(members[s][static_cast<std::size_t>(k)]);
  }
  std::sort(probes.begin(), probes.end());
  return probes;
}

SettingsError settingsError(const std::vector<RayRecord>& frame,
                            const std::vector<std::int32_t>& probes,
                            const std::vector<RayRecord>& probed,
                            const std::vector<RayRecord>& converged)
{
  if (converged.size() != probes.size())
    invalid(std::to_string(converged.size()) + " converged records for " +
            std::to_string(probes.size()) + " probes");
  if (probed.size() != probes.size())
    invalid(std::to_string(probed.size()) + " probed records for " + std::to_string(probes.size()) +
            " probes");
  SettingsError out;
  const std::vector<std::uint8_t> strata = settingsStrata(frame);
  for (std::uint8_t s : strata)
    out.strata[s].pixels += 1;
  for (SettingsStratum& s : out.strata)
    s.share = frame.empty() ? 0.0 : s.pixels / static_cast<double>(frame.size());
  for (std::size_t q = 0; q < probes.size(); ++q)
  {
    if (probes[q] < 0 || static_cast<std::size_t>(probes[q]) >= frame.size())
      invalid("probe " + std::to_string(probes[q]) + " lies outside the frame of " +
              std::to_string(frame.size()) + " pixels");
    const RayRecord& r = probed[q];
    // Per channel, in double: colorError2's float would round a frame's sum.
    const double e = (255.0 * (r.color - converged[q].color)).squaredNorm() / 3.0;
    SettingsStratum& s = out.strata[strata[static_cast<std::size_t>(probes[q])]];
    s.count += 1;
    s.sum += e;
    s.sum2 += e * e;
  }
  return out;
}

SettingsError settingsError(const std::vector<RayRecord>& frame,
                            const std::vector<std::int32_t>& probes,
                            const std::vector<RayRecord>& converged)
{
  std::vector<RayRecord> probed;
  probed.reserve(probes.size());
  for (std::int32_t p : probes)
  {
    if (p < 0 || static_cast<std::size_t>(p) >= frame.size())
      invalid("probe " + std::to_string(p) + " lies outside the frame of " +
              std::to_string(frame.size()) + " pixels");
    probed.push_back(frame[static_cast<std::size_t>(p)]);
  }
  return settingsError(frame, probes, probed, converged);
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
  const TracedPixels traced = converged(ij, {}); // every neighbour traced: the converged records
  SettingsError out = settingsError(frame, probes, traced.records);
  out.rays = traced.rays;
  return out;
}

SettingsError pooled(const SettingsError& a, const SettingsError& b)
{
  SettingsError out;
  for (int k = 0; k < kStrata; ++k)
  {
    const SettingsStratum &x = a.strata[k], &y = b.strata[k];
    SettingsStratum& s = out.strata[k];
    s.share = 0.5 * (x.share + y.share);
    s.pixels = 0.5 * (x.pixels + y.pixels);
    s.count = x.count + y.count;
    s.sum = x.sum + y.sum;
    s.sum2 = x.sum2 + y.sum2;
  }
  out.rays = a.rays + b.rays;
  return out;
}

RefinedStrata strataToRefine(const SettingsError& e, double allowedMse)
{
  std::array<int, kStrata> order;
  for (int k = 0; k < kStrata; ++k)
    order[static_cast<std::size_t>(k)] = k;
  auto mean = [&e](int k)
  {
    const SettingsStratum& s = e.strata[k];
    return s.count > 0 ? s.sum / s.count : std::numeric_limits<double>::infinity();
  };
  // Worst first; ties (strata probed alike) in stratum order, so the choice is the probes'.
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return mean(a) > mean(b); });
  RefinedStrata refined;
  for (int k : order)
  {
    if (e.mseBoundWithout(refined) <= allowedMse)
      break;
    if (e.strata[k].share <= 0)
      continue;
    RefinedStrata whole = refined;
    whole.whole |= 1u << k;
    if (e.mseBoundWithout(whole) > allowedMse || e.strata[k].count <= 0)
    {
      refined = whole;
      continue;
    }
    // Part of this stratum is enough: the least share, in thousandths, that brings the bound
    // within (the bound falls as the share grows).
    int lo = 0, hi = 1000; // the bound at hi/1000 is within, at lo/1000 it is not
    while (hi - lo > 1)
    {
      const int mid = (lo + hi) / 2;
      RefinedStrata part = refined;
      part.partial = k;
      part.fraction = mid / 1000.0;
      (e.mseBoundWithout(part) <= allowedMse ? hi : lo) = mid;
    }
    if (hi == 1000)
      refined = whole;
    else
    {
      refined.partial = k;
      refined.fraction = hi / 1000.0;
    }
    break;
  }
  return refined;
}

bool settingsFallShort(const SettingsError& settings, double targetDb)
{
  return settings.mseBound() > kRefineSettingsAbove * mseOfPsnr(targetDb);
}

std::vector<std::int32_t> pixelsOfStrata(const std::vector<RayRecord>& frame,
                                         const RefinedStrata& refined)
{
  return pixelsOfStrata(settingsStrata(frame), refined);
}

std::vector<std::int32_t> pixelsOfStrata(const std::vector<std::uint8_t>& strata,
                                         const RefinedStrata& refined)
{
  std::vector<std::int32_t> pixels, partial;
  for (std::size_t p = 0; p < strata.size(); ++p)
    if (refined.whole & (1u << strata[p]))
      pixels.push_back(static_cast<std::int32_t>(p));
    else if (strata[p] == refined.partial)
      partial.push_back(static_cast<std::int32_t>(p));
  if (!partial.empty() && refined.fraction > 0)
  {
    for (std::int32_t k : probePixels(partial.size(), refined.fraction, 0, kRefinedPixelSeed))
      pixels.push_back(partial[static_cast<std::size_t>(k)]);
    std::sort(pixels.begin(), pixels.end());
  }
  return pixels;
}

SettingsRefinement refinementFor(const SettingsError& settings, const FrameTracer& converged)
{
  SettingsRefinement r;
  r.settings = settings;
  r.converged = pixelTracerOf(converged);
  const int side = std::max(1, converged.description().rendering.supersample);
  r.raysPerPixel = static_cast<double>(side) * side;
  return r;
}
}
