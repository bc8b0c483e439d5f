#include "ErrorEstimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace asrt
{
namespace
{
/// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit hash of a counter.
std::uint64_t splitmix(std::uint64_t x)
{
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Hole-filled and ambiguous pixels rank above every other: no splat vouches for them.
constexpr float kUnvouched = 1e12f;

/// A segment of re-trace counts needs this many probes left to be judged by them.
constexpr std::size_t kMinProbesLeft = 8;
}

void estimatePixelErrors(const InterpolatedFrame& frame,
                         const std::vector<std::uint8_t>& disagreement,
                         std::vector<float>& estimate)
{
  const int W = frame.width, H = frame.height;
  const std::size_t n = static_cast<std::size_t>(W) * H;
  estimate.assign(n, 0.0f);
  const std::uint8_t* rgb = frame.rgb.data();
#pragma omp parallel for schedule(static)
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
    {
      const std::size_t p = static_cast<std::size_t>(j) * W + i;
      int g = 0;
      for (const auto& [di, dj] :
           { std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1) })
      {
        const int x = i + di, y = j + dj;
        if (x < 0 || x >= W || y < 0 || y >= H)
          continue;
        const std::size_t q = static_cast<std::size_t>(y) * W + x;
        for (int c = 0; c < 3; ++c)
          g = std::max(g, std::abs(int(rgb[3 * p + c]) - int(rgb[3 * q + c])));
      }
      const float d = p < disagreement.size() ? disagreement[p] : 0.0f;
      float e = std::sqrt(1.0f + d) * (1.0f + g) * (1.0f + g);
      if (frame.pixelClass[p] == PixelClass::HoleFilled ||
          frame.pixelClass[p] == PixelClass::Ambiguous)
        e += kUnvouched;
      estimate[p] = e;
    }
}

std::vector<std::int32_t> retraceOrder(const std::vector<float>& estimate)
{
  std::vector<std::int32_t> order(estimate.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int32_t a, std::int32_t b) { return estimate[a] > estimate[b]; });
  return order;
}

std::vector<std::int32_t> probePixels(std::size_t pixels, double fraction, std::size_t minimum,
                                      std::uint64_t seed)
{
  const double f = std::isfinite(fraction) ? std::clamp(fraction, 0.0, 1.0) : 0.0;
  const std::size_t m =
    std::min(pixels, std::max(minimum, static_cast<std::size_t>(std::llround(f * pixels))));
  std::vector<std::pair<std::uint64_t, std::int32_t>> keyed(pixels);
  for (std::size_t p = 0; p < pixels; ++p)
    keyed[p] = { splitmix(seed ^ splitmix(p)), static_cast<std::int32_t>(p) };
  std::nth_element(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(m), keyed.end());
  std::vector<std::int32_t> out;
  out.reserve(m);
  for (std::size_t k = 0; k < m; ++k)
    out.push_back(keyed[k].second);
  std::sort(out.begin(), out.end());
  return out;
}

double psnrOfMse(double mse)
{
  return mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
}

double mseOfPsnr(double psnr)
{
  return 255.0 * 255.0 * std::pow(10.0, -psnr / 10.0);
}

RetraceChoice chooseRetraceCount(std::size_t pixels, const std::vector<std::size_t>& probeRank,
                                 const std::vector<double>& probeError2, double targetDb,
                                 double confidence)
{
  if (!(targetDb > 0.0 && targetDb <= kMaxQualityTargetDb))
  {
    std::ostringstream os;
    os << "quality target must lie in (0, " << kMaxQualityTargetDb << "] dB, got " << targetDb;
    throw InvalidParameter(os.str());
  }
  if (probeRank.size() != probeError2.size())
    throw InvalidParameter("chooseRetraceCount: one error per probe");
  // The squared error the whole frame may carry, summed over pixels and channels.
  const double budget = 3.0 * pixels * 255.0 * 255.0 * std::pow(10.0, -targetDb / 10.0);

  // Probes by rank; suffix sums of their errors: the probes left at re-trace count k are those
  // of rank ≥ k, a uniform sample of the pixels of rank ≥ k.
  std::vector<std::size_t> idx(probeRank.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(),
            [&](std::size_t a, std::size_t b) { return probeRank[a] < probeRank[b]; });
  const std::size_t P = idx.size();
  std::vector<double> s1(P + 1, 0.0), s2(P + 1, 0.0);
  for (std::size_t q = P; q-- > 0;)
  {
    const double e = probeError2[idx[q]];
    s1[q] = s1[q + 1] + e;
    s2[q] = s2[q + 1] + e * e;
  }

  // Between consecutive probe ranks the probes left are fixed, and the pixels left interpolated,
  // M(k) = pixels − k − (probes left), fall by one per re-traced pixel. The bound on the error
  // left, U(k) = M(k) · (mean + confidence · standard error), is unbiased at a fixed k but
  // jumps down whenever k passes a probe of large error; the true error left never grows with k,
  // so the count is judged by the upper envelope max_{k' ≥ k} U(k'), which such a jump cannot
  // lower. Segment q spans k ∈ [start(q), rank of probe q].
  struct Segment
  {
    std::size_t lo, hi, left;
    double mean, se;
  };
  std::vector<Segment> segments;
  std::size_t lo = 0;
  for (std::size_t q = 0; q < P; ++q)
  {
    const std::size_t hi = probeRank[idx[q]], left = P - q;
    if (hi >= lo && left >= kMinProbesLeft)
    {
      const double mean = s1[q] / left;
      const double var = std::max(0.0, (s2[q] - left * mean * mean) / (left - 1.0));
      segments.push_back({ lo, hi, left, mean, std::sqrt(var / left) });
    }
    lo = std::max(lo, hi + 1);
  }
  auto bound = [&](const Segment& g, std::size_t k)
  { return (static_cast<double>(pixels) - k - g.left) * (g.mean + confidence * g.se); };
  std::vector<double> laterMax(segments.size() + 1, 0.0); // max of U over later segments
  for (std::size_t q = segments.size(); q-- > 0;)
    laterMax[q] = std::max(laterMax[q + 1], bound(segments[q], segments[q].lo));

  RetraceChoice best;
  best.retrace = pixels;
  for (std::size_t q = 0; q < segments.size(); ++q)
  {
    const Segment& g = segments[q];
    const double perPixel = g.mean + confidence * g.se;
    if (laterMax[q + 1] > budget)
      continue;
    // (pixels − k − left) · perPixel ≤ budget.
    const double kMin =
      static_cast<double>(pixels) - g.left - (perPixel > 0 ? budget / perPixel : 1e300);
    const std::size_t k =
      kMin <= static_cast<double>(g.lo) ? g.lo : static_cast<std::size_t>(std::ceil(kMin));
    if (k <= g.hi)
    {
      const double interpolated = static_cast<double>(pixels) - k - g.left;
      best.retrace = k;
      best.estimatedMse = interpolated * g.mean / (3.0 * pixels);
      best.standardError = interpolated * g.se / (3.0 * pixels);
      best.estimatedPsnr = psnrOfMse(best.estimatedMse);
      best.probesLeft = g.left;
      return best;
    }
  }
  // No probes are left to vouch for the rest: everything is re-traced, exactly.
  best.estimatedPsnr = psnrOfMse(0);
  return best;
}
}
