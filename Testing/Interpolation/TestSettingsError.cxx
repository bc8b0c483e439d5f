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
  /// The frame at T predicted from the four keys, moved edges included (before any re-trace).
  static PathFrame predictedAtT()
  {
    PathOptions options;
    options.pointIndex = kdTreeIndexFactory();
    return interpolateAlongPath(keyPath(), T, Side, Side, *rampScene(T, Side).scene, options);
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

TEST_F(SettingsErrorRamp, WithoutItsRefinedStrataTheErrorIsTheOtherPixelsAlone)
{
  // Every pixel probed: the bound without some strata is the frame's error with those strata's
  // pixels replaced by their converged records (which leave none), brute force.
  const std::vector<RayRecord>& key = Keys[1];
  const std::vector<std::int32_t> all = settingsProbes(key, 2 * key.size());
  std::vector<RayRecord> probes;
  for (std::int32_t p : all)
    probes.push_back(KeyTruth[static_cast<std::size_t>(p)]);
  const SettingsError e = settingsError(key, all, probes);
  const std::vector<std::uint8_t> strata = settingsStrata(key);
  for (unsigned mask = 0; mask < (1u << kSettingsStrata); ++mask)
  {
    std::vector<RayRecord> refined = key;
    const std::vector<std::int32_t> pixels = pixelsOfStrata(key, RefinedStrata{ mask });
    for (std::int32_t p : pixels)
      refined[static_cast<std::size_t>(p)] = KeyTruth[static_cast<std::size_t>(p)];
    const double brute = frameMse(refined, KeyTruth);
    EXPECT_NEAR(e.mseBoundWithout(RefinedStrata{ mask }), brute, 1e-9 * frameMse(key, KeyTruth))
      << mask;
    std::size_t q = 0;
    for (std::size_t p = 0; p < key.size(); ++p)
      if (mask & (1u << strata[p]))
      {
        ASSERT_LT(q, pixels.size());
        EXPECT_EQ(pixels[q++], static_cast<std::int32_t>(p));
      }
    EXPECT_EQ(q, pixels.size());
  }
  EXPECT_EQ(e.mseBoundWithout(RefinedStrata{ (1u << kSettingsStrata) - 1 }), 0.0);
  // A stratum refined in part: about that share of its pixels, drawn across it, none of another.
  for (int k = 0; k < kSettingsStrata; ++k)
  {
    const double size = static_cast<double>(std::count(strata.begin(), strata.end(), k));
    for (double fraction : { 0.1, 0.5, 0.9 })
    {
      const std::vector<std::int32_t> part = pixelsOfStrata(key, RefinedStrata{ 0, k, fraction });
      for (std::int32_t p : part)
        EXPECT_EQ(strata[static_cast<std::size_t>(p)], k);
      EXPECT_TRUE(std::is_sorted(part.begin(), part.end()));
      EXPECT_NEAR(static_cast<double>(part.size()), fraction * size, 3.0 * std::sqrt(size) + 1.0)
        << k << " " << fraction;
    }
  }
}

TEST(SettingsError, TheStrataToRefineAreTheWorstFirstAndNoMoreThanNeeded)
{
  // Four strata probed as a frame's are: means 40, 0.1, 2 and 100 levels², shares of a frame.
  SettingsError e;
  const double share[kSettingsStrata] = { 0.09, 0.45, 0.44, 0.02 };
  const double mean[kSettingsStrata] = { 40.0, 0.1, 2.0, 100.0 };
  for (int k = 0; k < kSettingsStrata; ++k)
  {
    SettingsStratum& s = e.strata[k];
    s.share = share[k];
    s.pixels = 1000 * share[k];
    s.count = 20;
    s.sum = 20 * mean[k];
    s.sum2 = 20 * mean[k] * mean[k] * 1.5; // a spread: the bound lies above the mean
  }
  const double full = e.mseBound();
  EXPECT_GT(full, e.mse());
  auto touched = [](const RefinedStrata& r, int k)
  { return (r.whole & (1u << k)) || (r.partial == k && r.fraction > 0); };
  for (double allowed : { 0.0, 0.05, 0.5, 1.0, 2.0, 5.0, full, 2 * full })
  {
    const RefinedStrata r = strataToRefine(e, allowed);
    // Enough: the strata left keep the bound within what is allowed (all refined leave none).
    EXPECT_LE(e.mseBoundWithout(r), allowed) << allowed;
    EXPECT_TRUE(r.partial < 0 ||
                (r.fraction > 0 && r.fraction < 1 && !(r.whole & (1u << r.partial))));
    // Worst first: every stratum refined whole has a mean at least the partial one's, and that
    // at least every untouched one's.
    for (int a = 0; a < kSettingsStrata; ++a)
      for (int b = 0; b < kSettingsStrata; ++b)
      {
        if ((r.whole & (1u << a)) && !(r.whole & (1u << b)))
        {
          EXPECT_GE(mean[a], mean[b]) << allowed;
        }
        if (touched(r, a) && !touched(r, b))
        {
          EXPECT_GE(mean[a], mean[b]) << allowed;
        }
      }
    // No more than needed: a thousandth less of the partial stratum, or else the whole stratum
    // of the least mean left out, exceeds the allowance.
    RefinedStrata less = r;
    if (r.partial >= 0)
      less.fraction -= 0.001;
    else
    {
      int least = -1;
      for (int k = 0; k < kSettingsStrata; ++k)
        if ((r.whole & (1u << k)) && (least < 0 || mean[k] < mean[least]))
          least = k;
      if (least < 0)
        continue;
      less.whole &= ~(1u << least);
    }
    EXPECT_GT(e.mseBoundWithout(less), allowed) << allowed;
  }
  EXPECT_EQ(strataToRefine(e, full).whole, 0u);
  EXPECT_LT(strataToRefine(e, full).partial, 0);
  // A stratum with pixels and no probe is refined first, and whole: its error is unknown.
  e.strata[1].count = e.strata[1].sum = e.strata[1].sum2 = 0;
  EXPECT_TRUE(std::isinf(e.mseBound()));
  EXPECT_TRUE(strataToRefine(e, 1e9).whole & 2u);
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
  const SceneDescription atT = rampScene(T, Side);
  const FrameTracer tracer(atT);
  const double tracedDb = psnrOfMse(frameMse(traceFrame(atT), Truth));
  std::printf("[ settings ] traced at M = %.2f: %.2f dB against converged; keys' bound %.2f dB\n",
              T, tracedDb, settings.psnr());
  for (double target : { 30.0, 35.0, tracedDb })
  {
    PathFrame against = predictedAtT();
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

TEST_F(SettingsErrorRamp, ATargetAboveTheKeysSettingsIsMetByTracingTheirErrorConverged)
{
  const SettingsError settings = pooled(measured(1), measured(2));
  const SceneDescription atT = rampScene(T, Side);
  // Above the keys' bound by more than their frames miss it by.
  const double target = settings.psnr() + 3.0;
  // The picture that judges the target (convergedSideFor: 8 × 8 above 36 dB), which the refined
  // pixels are traced with; and a denser one, 16 × 16, which nothing here traces with.
  SceneDescription judge = atT, dense = atT;
  judge.rendering = convergedRendering(convergedSideFor(target));
  dense.rendering = convergedRendering(16);
  const FrameTracer tracer(atT), convergedAtT(judge);
  const std::vector<RayRecord> judgeTruth = traceFrame(judge), denseTruth = traceFrame(dense);
  const double tracedDb = psnrOfMse(frameMse(traceFrame(atT), judgeTruth));
  PathFrame raised = predictedAtT();
  PathFrame held = raised;
  const PathCompletion r = completePathFrame(raised, pixelTracerOf(tracer), target, 0.01,
                                             refinementFor(settings, convergedAtT));
  const PathCompletion h = completePathFrame(held, tracer, target, 0.01, settings.mseBound());
  const double raisedDb = psnrOfMse(frameMse(raised.records, judgeTruth));
  const double heldDb = psnrOfMse(frameMse(held.records, judgeTruth));
  const double raisedDense = psnrOfMse(frameMse(raised.records, denseTruth));
  const double heldDense = psnrOfMse(frameMse(held.records, denseTruth));
  std::printf("[ settings ] target %.2f dB (keys' bound %.2f, the frame traced at t %.2f against "
              "its judge): raised %.2f dB against the judge, %.2f against 16x16 (estimated %.2f, "
              "%zu re-traced, %zu converged, %.0f rays); held %.2f / %.2f dB (estimated %.2f, %zu, "
              "%.0f rays)\n",
              target, settings.psnr(), tracedDb, raisedDb, raisedDense, r.estimatedPsnr, r.retraced,
              r.refined, r.raysTraced, heldDb, heldDense, h.estimatedPsnr, h.retraced,
              h.raysTraced);
  EXPECT_GT(r.refined, 0u);
  EXPECT_EQ(h.refined, 0u);
  EXPECT_GE(r.estimatedPsnr, target - 1e-9);
  EXPECT_LT(h.estimatedPsnr, target);
  // The frame reaches the target against the picture that judges it, and against the denser
  // one, which the frame traced at t with the keys' settings does not.
  EXPECT_GE(raisedDb, target - 1.0);
  EXPECT_GE(raisedDense, target - 1.0);
  EXPECT_LT(tracedDb, target - 1.0);
  EXPECT_GT(raisedDense, heldDense + 1.0);
  // A target the settings reach leaves the rendering alone: the same frame as without.
  PathFrame within = predictedAtT();
  PathFrame plain = within;
  const PathCompletion w = completePathFrame(within, pixelTracerOf(tracer), 30.0, 0.01,
                                             refinementFor(settings, convergedAtT));
  const PathCompletion p = completePathFrame(plain, tracer, 30.0, 0.01, settings.mseBound());
  EXPECT_EQ(w.refined, 0u);
  EXPECT_EQ(w.retraced, p.retraced);
  EXPECT_EQ(frameMse(within.records, plain.records), 0.0);
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

TEST_F(SettingsErrorRamp, ARefinementWithoutAConvergedTracerIsRefused)
{
  const FrameTracer tracer(rampScene(T, Side));
  PathFrame f = predictedAtT();
  SettingsRefinement none;
  none.settings = pooled(measured(1), measured(2));
  try
  {
    completePathFrame(f, pixelTracerOf(tracer), 40.0, 0.01, none);
    ADD_FAILURE() << "a refinement without a tracer was taken";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("no converged pixel tracer"), std::string::npos)
      << e.what();
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
