// The rays a re-trace integrates, predicted from a whole frame (RetraceRays.h), against the truth:
// the rays FrameTracer::raysIntegrated counts around the re-trace itself, on the mass ramp of
// Figs. 4–5.
#include "FrameTracer.h"
#include "PathInterpolation.h"
#include "RampScene.h"
#include "RetraceRays.h"
#include "SceneFile.h"
#include "TextureFiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::rampScene;

namespace
{
/// As asrt movie re-traces an interpolated frame's pixels: each its own centre ray.
SceneDescription scattered(SceneDescription d)
{
  d.rendering = scatteredPixelRendering(d.rendering);
  return d;
}

double tracedRays(const FrameTracer& tracer, const std::vector<std::pair<int, int>>& pixels)
{
  const std::int64_t before = tracer.raysIntegrated();
  tracer.tracePixels(pixels);
  return static_cast<double>(tracer.raysIntegrated() - before);
}
}

// Predicted from the frame traced as the re-trace traces (one centre ray a pixel), the count is
// the tracer's, ray for ray: for isolated pixels (each with 4 neighbours of its own), a block,
// and lists drawn at random, the edge of the frame included.
TEST(RetraceRays, FromAFrameTracedPixelByPixelTheCountIsExact)
{
  constexpr int side = 48;
  const FrameTracer tracer(scattered(rampScene(0.7, side)));
  const std::vector<RayRecord> frame = tracer.traceRows(0, side);
  std::vector<std::vector<std::pair<int, int>>> lists;
  lists.push_back({ { 3, 3 }, { 20, 24 }, { 0, 0 }, { 47, 30 } });
  lists.emplace_back();
  for (int j = 14; j < 34; ++j)
    for (int i = 10; i < 38; ++i)
      lists.back().emplace_back(i, j);
  std::mt19937 random(7);
  for (int n : { 30, 300, 1200 })
  {
    std::vector<int> all(side * side);
    for (int p = 0; p < side * side; ++p)
      all[static_cast<std::size_t>(p)] = p;
    std::shuffle(all.begin(), all.end(), random);
    lists.emplace_back();
    for (int k = 0; k < n; ++k)
      lists.back().emplace_back(all[static_cast<std::size_t>(k)] % side,
                                all[static_cast<std::size_t>(k)] / side);
  }
  for (const auto& list : lists)
  {
    const RetraceRays predicted = predictRetraceRays(frame, side, side, list);
    EXPECT_EQ(predicted.centres, static_cast<double>(list.size()));
    EXPECT_EQ(predicted.total(), tracedRays(tracer, list)) << list.size() << " pixels";
  }
  EXPECT_EQ(predictRetraceRays(frame, side, side, { { 3, 3 } }).neighbours, 4.0);
  EXPECT_THROW(predictRetraceRays(frame, side, side - 1, { { 3, 3 } }), InvalidParameter);
  EXPECT_THROW(predictRetraceRays(frame, side, side, { { side, 3 } }), InvalidParameter);
}

// As the movie measures it: the frame at t traced whole on the adaptive grid (as its keys are),
// interpolated between keys around it and completed to a target, each list of pixels the target
// asks for predicted from that frame and re-traced at t pixel by pixel. The grid fills most
// centres, so the samples of the pixels it filled come from an interpolated judgement: the
// prediction holds within 1 % over the frame's re-trace.
TEST(RetraceRays, FromAFrameTracedOnTheGridTheMovieRetraceIsPredicted)
{
  constexpr int side = 64;
  const std::vector<double> s = { 0.5, 0.6, 0.8, 0.9 };
  std::vector<std::vector<RayRecord>> keys;
  for (double m : s)
    keys.push_back(FrameTracer(rampScene(m, side)).traceRows(0, side));
  std::vector<PathKey> path;
  for (std::size_t k = 0; k < s.size(); ++k)
    path.push_back({ s[k], &keys[k] });
  PathOptions options;
  options.movedEdges = false; // as asrt movie interpolates
  for (double t : { 0.65, 0.72 })
  {
    const SceneDescription atT = rampScene(t, side);
    const std::vector<RayRecord> whole = FrameTracer(atT).traceRows(0, side);
    const FrameTracer retracer(scattered(atT));
    PathFrame frame = interpolateAlongPath(path, t, side, side, *atT.scene, options);
    double predicted = 0, actual = 0;
    int lists = 0;
    const PixelTracer trace =
      [&](const std::vector<std::pair<int, int>>& pixels, const std::vector<JacobianSample>& border)
    {
      predicted += predictRetraceRays(whole, side, side, pixels, border).total();
      const std::int64_t before = retracer.raysIntegrated();
      TracedPixels out;
      out.records = retracer.tracePixelsBeside(pixels, border);
      out.rays = static_cast<double>(retracer.raysIntegrated() - before);
      actual += out.rays;
      ++lists;
      return out;
    };
    const PathCompletion done = completePathFrame(frame, trace, 35.0);
    std::printf("[ retrace ] M = %.2f: %zu pixels re-traced in %d lists, %.0f rays predicted, "
                "%.0f integrated (%.2f a pixel)\n",
                t, done.retraced, lists, predicted, actual, actual / done.retraced);
    ASSERT_GT(done.retraced, 0u);
    EXPECT_NEAR(predicted, actual, 0.01 * actual) << "M = " << t;
  }
}
