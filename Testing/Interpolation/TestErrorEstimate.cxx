// The error estimate's parts against independent truth: the re-trace count against a brute-force
// search over every count, the probes' calibration against the actual error of synthetic frames
// whose errors are known and whose ranking knows them roughly, the probe set's determinism, and the
// ranking's rules.
#include "ErrorEstimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

using namespace asrt;

namespace
{
/// A synthetic frame: per pixel a true squared error (summed over channels), heavy-tailed as an
/// interpolated frame's are (most pixels near zero, a few edges far off), and a ranking that
/// knows it only roughly (the true error times log-normal noise).
struct SyntheticFrame
{
  std::vector<double> error2;
  std::vector<std::int32_t> order;
};

SyntheticFrame syntheticFrame(std::size_t n, std::uint32_t seed, double noise)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> z(0, 1);
  SyntheticFrame f;
  f.error2.resize(n);
  std::vector<float> estimate(n);
  for (std::size_t p = 0; p < n; ++p)
  {
    const double level = u(rng) < 0.1 ? 255 * std::pow(u(rng), 2.0) : 3 * u(rng);
    f.error2[p] = 3 * level * level;
    estimate[p] = static_cast<float>(f.error2[p] * std::exp(noise * z(rng)) + 1e-3);
  }
  f.order = retraceOrder(estimate);
  return f;
}

/// The frame's PSNR once the first k pixels of the order and the probes are exact.
double psnrAfter(const SyntheticFrame& f, std::size_t k, const std::vector<std::int32_t>& probes)
{
  std::vector<char> exact(f.error2.size(), 0);
  for (std::size_t r = 0; r < k; ++r)
    exact[static_cast<std::size_t>(f.order[r])] = 1;
  for (std::int32_t p : probes)
    exact[static_cast<std::size_t>(p)] = 1;
  double sse = 0;
  for (std::size_t p = 0; p < f.error2.size(); ++p)
    sse += exact[p] ? 0 : f.error2[p];
  return psnrOfMse(sse / (3.0 * f.error2.size()));
}

void probeData(const SyntheticFrame& f, const std::vector<std::int32_t>& probes,
               std::vector<std::size_t>& rank, std::vector<double>& error2)
{
  std::vector<std::size_t> position(f.order.size());
  for (std::size_t r = 0; r < f.order.size(); ++r)
    position[static_cast<std::size_t>(f.order[r])] = r;
  rank.clear();
  error2.clear();
  for (std::int32_t p : probes)
  {
    rank.push_back(position[static_cast<std::size_t>(p)]);
    error2.push_back(f.error2[static_cast<std::size_t>(p)]);
  }
}
}

TEST(ErrorEstimate, RetraceCountIsTheSmallestThatABruteForceSearchAccepts)
{
  const std::size_t n = 3000;
  const SyntheticFrame f = syntheticFrame(n, 7, 1.0);
  const std::vector<std::int32_t> probes = probePixels(n, 0.05, 64, 11);
  std::vector<std::size_t> rank;
  std::vector<double> error2;
  probeData(f, probes, rank, error2);
  for (double target : { 25.0, 30.0, 35.0, 40.0 })
  {
    const RetraceChoice c = chooseRetraceCount(n, rank, error2, target);
    // Brute force: U(k) at every k from the probes of rank ≥ k (8 at least), and the smallest
    // k whose U and every later U meet the budget.
    const double budget = 3.0 * n * 255 * 255 * std::pow(10.0, -target / 10);
    std::vector<double> U(n + 1, -1);
    for (std::size_t k = 0; k <= n; ++k)
    {
      double s1 = 0, s2 = 0;
      std::size_t left = 0;
      for (std::size_t q = 0; q < rank.size(); ++q)
        if (rank[q] >= k)
        {
          ++left;
          s1 += error2[q];
          s2 += error2[q] * error2[q];
        }
      if (left < 8)
        break;
      const double mean = s1 / left, var = std::max(0.0, (s2 - left * mean * mean) / (left - 1));
      U[k] = (double(n) - k - left) * (mean + kProbeConfidence * std::sqrt(var / left));
    }
    std::size_t expected = n;
    double later = 0;
    for (std::size_t k = n + 1; k-- > 0;)
      if (U[k] >= 0)
      {
        later = std::max(later, U[k]);
        if (later <= budget)
          expected = k;
      }
    EXPECT_EQ(c.retrace, expected) << "target " << target;
    EXPECT_GE(c.estimatedPsnr, target - 3.0);
  }
}

TEST(ErrorEstimate, ProbesCalibrateTheTargetForARankingThatKnowsTheErrorsRoughly)
{
  // Over many synthetic frames whose ranking is the true error times a log-normal factor of
  // σ = 0.5, the completed frame meets the target minus 1 dB nearly always. (With σ ≥ 1 it does
  // not: the errors the ranking leaves are then a few heavy pixels that 2 % of probes rarely
  // see. The probes calibrate the ranking; they cannot replace it.)
  const std::size_t n = 20000;
  for (double noise : { 0.5 })
  {
    int misses = 0, frames = 0;
    double retraced = 0;
    for (std::uint32_t seed = 1; seed <= 40; ++seed)
    {
      const SyntheticFrame f = syntheticFrame(n, seed, noise);
      const std::vector<std::int32_t> probes = probePixels(n, 0.02, 256, seed);
      std::vector<std::size_t> rank;
      std::vector<double> error2;
      probeData(f, probes, rank, error2);
      for (double target : { 30.0, 35.0, 40.0 })
      {
        const RetraceChoice c = chooseRetraceCount(n, rank, error2, target);
        ++frames;
        misses += psnrAfter(f, c.retrace, probes) < target - 1.0;
        retraced += double(c.retrace) / n;
      }
    }
    EXPECT_LE(misses, frames / 20) << "ranking noise " << noise;
    EXPECT_LT(retraced / frames, 0.2); // the heavy tenth of the pixels, roughly
  }
}

TEST(ErrorEstimate, ABetterRankingNeedsFewerRetracedPixels)
{
  const std::size_t n = 20000;
  double good = 0, poor = 0;
  for (std::uint32_t seed = 1; seed <= 10; ++seed)
    for (double noise : { 0.3, 3.0 })
    {
      const SyntheticFrame f = syntheticFrame(n, seed, noise);
      const std::vector<std::int32_t> probes = probePixels(n, 0.02, 256, seed);
      std::vector<std::size_t> rank;
      std::vector<double> error2;
      probeData(f, probes, rank, error2);
      (noise < 1 ? good : poor) += chooseRetraceCount(n, rank, error2, 35.0).retrace;
    }
  EXPECT_LT(good, 0.7 * poor);
}

TEST(ErrorEstimate, ProbePixelsAreFixedByTheirArgumentsAndSpreadOut)
{
  const auto a = probePixels(10000, 0.03, 100, 5), b = probePixels(10000, 0.03, 100, 5),
             c = probePixels(10000, 0.03, 100, 6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(a.size(), 300u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::set<std::int32_t>(a.begin(), a.end()).size(), a.size());
  // Spread: each tenth of the frame holds a tenth of the probes, within sampling noise.
  std::vector<int> tenth(10, 0);
  for (std::int32_t p : a)
    ++tenth[static_cast<std::size_t>(p / 1000)];
  for (int t : tenth)
  {
    EXPECT_GT(t, 10);
    EXPECT_LT(t, 55);
  }
  EXPECT_EQ(probePixels(10000, 0.0, 100, 5).size(), 100u);
  EXPECT_EQ(probePixels(50, 0.03, 100, 5).size(), 50u);
}

TEST(ErrorEstimate, TargetsOutOfRangeAreRefused)
{
  const std::vector<std::size_t> rank{ 0, 1 };
  const std::vector<double> error2{ 0, 0 };
  for (double bad : { 0.0, -1.0, 100.5, std::numeric_limits<double>::quiet_NaN(),
                      std::numeric_limits<double>::infinity() })
    EXPECT_THROW(chooseRetraceCount(10, rank, error2, bad), InvalidParameter) << bad;
  EXPECT_NO_THROW(chooseRetraceCount(10, rank, error2, kMaxQualityTargetDb));
}

TEST(ErrorEstimate, RankingPutsUnvouchedPixelsFirstAndGrowsWithDisagreementAndContrast)
{
  InterpolatedFrame f;
  f.width = 6;
  f.height = 1;
  f.rgb = { 0, 0, 0, 0, 0, 0, 0, 0, 0, 200, 200, 200, 200, 200, 200, 200, 200, 200 };
  f.pixelClass.assign(6, PixelClass::Matched);
  f.pixelClass[0] = PixelClass::HoleFilled;
  const std::vector<std::uint8_t> disagreement{ 0, 0, 100, 0, 0, 0 };
  std::vector<float> e;
  estimatePixelErrors(f, disagreement, e);
  ASSERT_EQ(e.size(), 6u);
  EXPECT_FLOAT_EQ(e[1], 1.0f); // flat, agreed: the least
  EXPECT_GT(e[3], e[4]);       // the edge (200 levels) against its flat side
  EXPECT_GT(e[2], e[3]);       // the same edge, and disagreement
  for (int p = 1; p < 6; ++p)
    EXPECT_GT(e[0], e[p]);
  const std::vector<std::int32_t> order = retraceOrder(e);
  EXPECT_EQ(order[0], 0);
  EXPECT_EQ(order[1], 2);
  EXPECT_EQ(order[2], 3);
  EXPECT_EQ((std::vector<std::int32_t>(order.begin() + 3, order.end())),
            (std::vector<std::int32_t>{ 1, 4, 5 })); // ties by index
}
