#include "LeaveOneOut.h"

#include "AsrtTypes.h"
#include "RecordHashing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>

namespace asrt
{
namespace
{
/// Per pixel of a width × height frame, the largest of `in` within `radius` pixels along the
/// direction (di, dj), one of (1, 0) and (0, 1).
std::vector<float> largestAlong(const std::vector<float>& in, int width, int height, int radius,
                                int di, int dj)
{
  std::vector<float> out(in.size());
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
    {
      float m = 0.0f;
      for (int k = -radius; k <= radius; ++k)
      {
        const int x = i + k * di, y = j + k * dj;
        if (x >= 0 && x < width && y >= 0 && y < height)
          m = std::max(m, in[static_cast<std::size_t>(y) * width + x]);
      }
      out[static_cast<std::size_t>(j) * width + i] = m;
    }
  return out;
}
}

LeaveOneOutCache::LeaveOneOutCache(std::size_t capacity)
  : Kept(capacity)
{
}

std::shared_ptr<const std::vector<float>> LeaveOneOutCache::errors(
  std::uint64_t key, const std::function<std::vector<float>()>& make)
{
  return this->Kept.get(key, make);
}

std::size_t LeaveOneOutCache::made() const
{
  return this->Kept.made();
}

std::vector<float> leaveOneOutError(const std::vector<PathKey>& keys, double t, int width,
                                    int height, const Scene& scene, const PathOptions& options,
                                    int radius)
{
  // interpolateAlongPath checks the keys, when it predicts one of them from the others.
  if (keys.size() < 2 || !(t >= keys.front().s && t <= keys.back().s))
    throw InvalidParameter("leaveOneOutError: t lies outside the keys");
  std::size_t a = 0;
  while (a + 2 < keys.size() && keys[a + 1].s <= t)
    ++a;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<float> worst;
  // The keys' own correspondences stay kept for the frames: those of the pairs that skip a key
  // are matched once per key left out, where its errors are kept.
  PathOptions inner = options;
  inner.leaveOneOut = false;
  inner.matchCache = nullptr;
  inner.estimates = false;
  // Each key's fingerprint, once: the two keys left out share most of the keys that predict them.
  std::map<std::size_t, std::uint64_t> fingerprints;
  const auto fingerprint = [&](std::size_t q)
  {
    const auto found = fingerprints.find(q);
    if (found != fingerprints.end())
      return found->second;
    return fingerprints[q] = mixWord(bitsOf(keys[q].s), keyFingerprint(keys[q]));
  };
  for (const std::size_t k : { a, a + 1 })
  {
    if (k == 0 || k + 1 == keys.size())
      continue;
    if (!keys[k].records || keys[k].records->size() != n)
      throw InvalidParameter("leaveOneOutError: key " + std::to_string(k) + " has " +
                             std::to_string(keys[k].records ? keys[k].records->size() : 0) +
                             " records, not " + std::to_string(width) + " x " +
                             std::to_string(height));
    // The prediction at keys[k].s reads the two keys on either side of it, at most.
    std::vector<PathKey> others;
    std::vector<std::size_t> used;
    for (std::size_t q = k >= 2 ? k - 2 : 0; q <= std::min(k + 2, keys.size() - 1); ++q)
      if (q != k)
      {
        others.push_back(keys[q]);
        used.push_back(q);
      }
    const auto make = [&]()
    {
      const std::vector<RayRecord>& own = *keys[k].records;
      std::vector<float> e(n);
      if (inner.movedEdges)
      {
        const PathFrame left = interpolateAlongPath(others, keys[k].s, width, height, scene, inner);
        for (std::size_t p = 0; p < n; ++p)
          e[p] = colorError2(left.records[p].color, own[p].color);
      }
      else
      {
        // The colours alone, without the records a frame would write.
        const std::vector<Color> left =
          interpolatedColours(others, keys[k].s, width, height, scene);
        for (std::size_t p = 0; p < n; ++p)
          e[p] = colorError2(left[p], own[p].color);
      }
      return e;
    };
    std::shared_ptr<const std::vector<float>> e;
    if (options.leaveOneOutCache)
    {
      std::uint64_t id = mixWord(0x5851f42d4c957f2dULL, fingerprint(k));
      id = mixWord(id, (options.movedEdges ? 1u : 0u) | (options.hedgeMovedEdges ? 2u : 0u) |
                         (options.hedgeNearShadow ? 4u : 0u) | (options.spacetimeAt ? 8u : 0u));
      for (const std::size_t q : used)
        id = mixWord(id, fingerprint(q));
      e = options.leaveOneOutCache->errors(id, make);
    }
    else
      e = std::make_shared<const std::vector<float>>(make());
    worst.resize(n, 0.0f);
    for (std::size_t p = 0; p < n; ++p)
      worst[p] = std::max(worst[p], (*e)[p]);
  }
  if (worst.empty() || radius <= 0)
    return worst;
  // The largest within the square of side 2 radius + 1: along the rows, then the columns.
  return largestAlong(largestAlong(worst, width, height, radius, 1, 0), width, height, radius, 0,
                      1);
}

void weighByLeaveOneOut(PathFrame& f, const std::vector<float>& L,
                        const std::vector<std::uint8_t>& unweighed)
{
  if (L.empty())
    return;
  const auto weighed = [&](std::size_t p)
  { return isPrediction(f.method[p]) && (unweighed.empty() || !unweighed[p]); };
  // The weights move each way's estimated error among its pixels without adding to it: the
  // way's total, which its probes calibrate, stays as it was.
  std::array<double, kPathMethodCount> before{}, after{};
  for (std::size_t p = 0; p < L.size(); ++p)
    if (weighed(p) && std::isfinite(f.estimate[p]))
    {
      before[f.method[p]] += f.estimate[p];
      after[f.method[p]] += f.estimate[p] * leaveOneOutWeight(L[p]);
    }
  for (std::size_t p = 0; p < L.size(); ++p)
    if (weighed(p) && after[f.method[p]] > 0)
      f.estimate[p] = static_cast<float>(f.estimate[p] * leaveOneOutWeight(L[p]) *
                                         (before[f.method[p]] / after[f.method[p]]));
}
}
