// A frame's error against its converged picture, measured on probes (SettingsError.h), and a
// quality target held against the converged picture by completePathFrame, against converged
// frames the tests trace themselves.
#include "ErrorEstimate.h"
#include "FrameTracer.h"
#include "KdTreeIndex.h"
#include "PathInterpolation.h"
#include "RampScene.h"
#include "SettingsError.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::rampScene;

namespace
{
std::vector<RayRecord> traceFrame(const SceneDescription& d)
{
  return FrameTracer(d).traceRows(0, d.camera.height);
}

SceneDescription converged(SceneDescription d)
{
  d.rendering = convergedRendering();
  return d;
}

/// The mean squared error per channel of two frames' colours, over every pixel: the brute force.
double frameMse(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  double sum = 0;
  for (std::size_t p = 0; p < a.size(); ++p)
    sum += (255.0 * (a[p].color - b[p].color)).squaredNorm();
  return sum / (3.0 * static_cast<double>(a.size()));
}

/// The ramp of Figs. 4–5 at 96 × 96: key frames with the default rendering and their converged
/// pictures, traced once for the suite.
class SettingsErrorRamp : public ::testing::Test
{
protected:
  static constexpr int Side = 96;
  static constexpr double From = 0.6, H = 0.1, T = 0.74;
  static void SetUpTestSuite()
  {
    for (int k = 0; k < 4; ++k)
      Keys.push_back(traceFrame(rampScene(From + H * k, Side)));
    Truth = traceFrame(converged(rampScene(T, Side)));
    KeyTruth = traceFrame(converged(rampScene(From + H, Side)));
  }
  static inline std::vector<std::vector<RayRecord>> Keys;
  /// The converged pictures at T and at the second key.
  static inline std::vector<RayRecord> Truth, KeyTruth;
  static std::vector<PathKey> keyPath()
  {
    std::vector<PathKey> path;
    for (int k = 0; k < 4; ++k)
      path.push_back({ From + H * k, &Keys[static_cast<std::size_t>(k)] });
    return path;
  }
  /// The probes of `frame` drawn with `seed`, and their error against the converged picture at
  /// the second key (KeyTruth: the frame must be of that view).
  static std::pair<std::vector<std::int32_t>, SettingsError> drawnAgainstKeyTruth(
    const std::vector<RayRecord>& frame, std::uint64_t seed)
  {
    std::vector<std::int32_t> probes = settingsProbes(frame, kSettingsProbesPerStratum, seed);
    std::vector<RayRecord> truth;
    for (std::int32_t p : probes)
      truth.push_back(KeyTruth[static_cast<std::size_t>(p)]);
    const SettingsError e = settingsError(frame, probes, truth);
    return { std::move(probes), e };
  }
  /// The settings' error of key k, measured with probes traced at the converged rendering.
  static SettingsError measured(int k)
  {
    const FrameTracer probe(converged(rampScene(From + H * k, Side)));
    return measureSettingsError(Keys[static_cast<std::size_t>(k)], Side, Side,
                                pixelTracerOf(probe));
  }
};

TEST_F(SettingsErrorRamp, ProbingEveryPixelGivesTheFramesError)
{
  const std::vector<RayRecord>& key = Keys[1];
  // As many a stratum as the frame's pixels, even where a stratum takes half (settingsProbes).
  const std::vector<std::int32_t> all = settingsProbes(key, 2 * key.size());
  ASSERT_EQ(all.size(), key.size());
  std::vector<RayRecord> probes;
  for (std::int32_t p : all)
    probes.push_back(KeyTruth[static_cast<std::size_t>(p)]);
  const SettingsError e = settingsError(key, all, probes);
  const double brute = frameMse(key, KeyTruth);
  EXPECT_NEAR(e.mse(), brute, 1e-9 * brute);
  EXPECT_NEAR(e.mseBound(), brute, 1e-9 * brute); // every stratum probed whole: no margin
  EXPECT_GT(brute, 0.0);
}

TEST_F(SettingsErrorRamp, TheProbesEstimateAndBoundTheFramesError)
{
  const SettingsError e = measured(1);
  const double brute = frameMse(Keys[1], KeyTruth);
  std::printf("[ settings ] key at M = %.2f: %.2f dB against converged; probes (%zu, %.0f rays): "
              "%.2f dB, bound %.2f dB\n",
              From + H, psnrOfMse(brute), e.probes(), e.rays, psnrOfMse(e.mse()), e.psnr());
  EXPECT_LE(e.probes(), 4 * kSettingsProbesPerStratum); // 2 + 1 + 1/2 + 1/2 strata's worth
  EXPECT_GT(e.rays, 0.0);
  // Over many draws of the probes, the estimate is unbiased and the bound holds in most: the
  // rare large errors at edges make any one draw uncertain.
  const std::vector<RayRecord>& key = Keys[1];
  constexpr int Draws = 64;
  double sum = 0;
  int bounded = 0;
  for (int d = 0; d < Draws; ++d)
  {
    const SettingsError drawn = drawnAgainstKeyTruth(key, 1000 + 7 * d).second;
    sum += drawn.mse();
    bounded += drawn.mseBound() >= brute;
  }
  std::printf("[ settings ] %d draws: mean estimate %.2f dB, bound above the truth in %d\n", Draws,
              psnrOfMse(sum / Draws), bounded);
  EXPECT_NEAR(sum / Draws, brute, 0.2 * brute);
  EXPECT_GE(bounded, 3 * Draws / 4);
  // The probes are the converged frame's own records: a frame traced converged has no error.
  const FrameTracer probe(converged(rampScene(From + H, Side)));
  const SettingsError none = measureSettingsError(KeyTruth, Side, Side, pixelTracerOf(probe));
  EXPECT_EQ(none.mse(), 0.0);
}

TEST_F(SettingsErrorRamp, UnsampledEdgesAreAStratumOfTheirOwn)
{
  // A rendering that samples no pixel beyond its centre ray (the fast preset's) has its error on
  // the edges it left unsampled. The strata, against a brute force over the pixels' neighbours.
  SceneDescription d = rampScene(From + H, Side);
  d.rendering = renderingPreset("fast");
  const std::vector<RayRecord> fast = traceFrame(d);
  const std::vector<std::uint8_t> strata = settingsStrata(fast);
  ASSERT_EQ(strata.size(), fast.size());
  auto at = [&](int i, int j) -> const RayRecord&
  { return fast[static_cast<std::size_t>(j * Side + i)]; };
  std::size_t edges = 0;
  for (int j = 0; j < Side; ++j)
    for (int i = 0; i < Side; ++i)
    {
      const RayRecord& r = at(i, j);
      bool edge = false;
      for (const auto& [di, dj] : { std::pair{ 1, 0 }, { -1, 0 }, { 0, 1 }, { 0, -1 } })
      {
        const int x = i + di, y = j + dj;
        if (x < 0 || y < 0 || x >= Side || y >= Side)
          continue;
        const RayRecord& n = at(x, y);
        edge = edge || n.objectId != r.objectId || n.imageOrder != r.imageOrder ||
               n.termination != r.termination;
      }
      const int expected = r.raysPerPixel > 1 ? 0 : edge ? 3 : r.traced ? 2 : 1;
      ASSERT_EQ(strata[static_cast<std::size_t>(j * Side + i)], expected) << i << ", " << j;
      edges += expected == 3;
    }
  ASSERT_GT(edges, 0u);
  // Over many draws the stratified estimate is unbiased, and steadier than the mean of as many
  // probes drawn uniformly over the frame: the edges hold the error.
  const double brute = frameMse(fast, KeyTruth);
  constexpr int Draws = 64;
  double sum = 0, sum2 = 0, uniformSum = 0, uniformSum2 = 0;
  for (int d = 0; d < Draws; ++d)
  {
    const auto [probes, drawn] = drawnAgainstKeyTruth(fast, 1000 + 7 * d);
    const double m = drawn.mse();
    sum += m;
    sum2 += m * m;
    // As many probes, uniformly over the frame (the lowest hashes of all its pixels).
    const std::vector<std::int32_t> uniform =
      probePixels(fast.size(), 0.0, probes.size(), 5000 + 7 * d);
    double u = 0;
    for (std::int32_t p : uniform)
      u += (255.0 *
            (fast[static_cast<std::size_t>(p)].color - KeyTruth[static_cast<std::size_t>(p)].color))
             .squaredNorm() /
           3.0;
    u /= static_cast<double>(uniform.size());
    uniformSum += u;
    uniformSum2 += u * u;
  }
  const double mean = sum / Draws, variance = sum2 / Draws - mean * mean;
  const double uniformMean = uniformSum / Draws,
               uniformVariance = uniformSum2 / Draws - uniformMean * uniformMean;
  std::printf("[ settings ] the fast rendering: %.2f dB against converged; %d draws of the "
              "probes: mean %.2f dB, spread %.3g levels² (as many uniform probes: %.2f dB, %.3g)\n",
              psnrOfMse(brute), Draws, psnrOfMse(mean), std::sqrt(variance), psnrOfMse(uniformMean),
              std::sqrt(uniformVariance));
  EXPECT_NEAR(mean, brute, 0.2 * brute);
  // Without the edge stratum the fast frame's probes would fall into two strata of pixels spread
  // over the frame as uniform ones are.
  EXPECT_LT(variance, 0.5 * uniformVariance);
}

TEST_F(SettingsErrorRamp, AQualityTargetHoldsAgainstTheConvergedPicture)
{
  const SettingsError settings = pooled(measured(1), measured(2));
  const std::vector<PathKey> path = keyPath();
  PathOptions options;
  options.pointIndex = kdTreeIndexFactory();
  const SceneDescription atT = rampScene(T, Side);
  const FrameTracer tracer(atT);
  const double tracedDb = psnrOfMse(frameMse(traceFrame(atT), Truth));
  std::printf("[ settings ] traced at M = %.2f: %.2f dB against converged; keys' bound %.2f dB\n",
              T, tracedDb, settings.psnr());
  for (double target : { 30.0, 35.0, tracedDb })
  {
    PathFrame against = interpolateAlongPath(path, T, Side, Side, *atT.scene, options);
    PathFrame plain = against;
    const PathCompletion held =
      completePathFrame(against, tracer, target, 0.01, settings.mseBound());
    const PathCompletion loose = completePathFrame(plain, tracer, target);
    const double heldDb = psnrOfMse(frameMse(against.records, Truth));
    const double looseDb = psnrOfMse(frameMse(plain.records, Truth));
    std::printf("[ settings ] target %.2f dB: held to converged %.2f dB (estimated %.2f, %zu "
                "re-traced); held to the traced frame %.2f dB (%zu)\n",
                target, heldDb, held.estimatedPsnr, held.retraced, looseDb, loose.retraced);
    EXPECT_GE(heldDb, target - 1.0) << target;
    EXPECT_GE(held.retraced, loose.retraced);
    EXPECT_LE(held.estimatedPsnr, settings.psnr());
  }
}

TEST_F(SettingsErrorRamp, ASettingsErrorBelowZeroOrNotFiniteIsRefused)
{
  const std::vector<PathKey> path = keyPath();
  PathOptions options;
  options.movedEdges = false;
  const SceneDescription atT = rampScene(T, Side);
  const FrameTracer tracer(atT);
  for (double bad : { -1.0, std::nan(""), HUGE_VAL })
  {
    PathFrame f = interpolateAlongPath(path, T, Side, Side, *atT.scene, options);
    try
    {
      completePathFrame(f, tracer, 35.0, 0.01, bad);
      ADD_FAILURE() << bad << " was taken";
    }
    catch (const InvalidParameter& e)
    {
      EXPECT_NE(std::string(e.what()).find("settings' own error"), std::string::npos) << e.what();
    }
  }
}

TEST(SettingsError, ABadFrameOrProbeListIsRefused)
{
  std::vector<RayRecord> frame(12);
  const PixelTracer none =
    [](const std::vector<std::pair<int, int>>& ij, const std::vector<JacobianSample>&)
  {
    TracedPixels out;
    out.records.resize(ij.size());
    return out;
  };
  EXPECT_THROW(measureSettingsError(frame, 4, 4, none), InvalidParameter);
  EXPECT_THROW(settingsError(frame, { 0, 1 }, std::vector<RayRecord>(1)), InvalidParameter);
  EXPECT_THROW(settingsError(frame, { 40 }, std::vector<RayRecord>(1)), InvalidParameter);
}
}
