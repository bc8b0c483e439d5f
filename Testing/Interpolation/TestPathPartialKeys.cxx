// Partial keys along a movie path (PathKey::known): a frame interpolated before, whose re-traced
// pixels serve as nodes for the frames beside it. Checked against frames the test traces itself
// and against the same nodes given as whole keys.
#include "FrameTracer.h"
#include "PathInterpolation.h"
#include "RampScene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::rampScene;

namespace
{
std::string errorOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return "";
}

/// As the movie interpolates: no moved edges.
PathOptions perPixelOnly()
{
  PathOptions options;
  options.movedEdges = false;
  return options;
}

std::vector<RayRecord> traceFrame(const SceneDescription& d)
{
  return FrameTracer(d).traceRows(0, d.camera.height);
}

double psnrOf(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  double sum = 0;
  for (std::size_t p = 0; p < a.size(); ++p)
    sum += (255.0 * (a[p].color - b[p].color)).squaredNorm();
  const double mse = sum / (3.0 * a.size());
  return mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
}

std::size_t countOf(const PathFrame& f, PathMethod m)
{
  return f.counts()[static_cast<std::size_t>(m)];
}
}

TEST(PathPartialKeys, BadPartialKeysAreRefusedByName)
{
  const SceneDescription d = rampScene(0.5, 4);
  std::vector<RayRecord> r(16);
  for (int p = 0; p < 16; ++p)
  {
    r[p].i = p % 4;
    r[p].j = p / 4;
  }
  const std::vector<std::uint8_t> all(16, 1), short_(15, 1);
  const Scene& scene = *d.scene;
  auto error = [&](const std::vector<PathKey>& keys, double t)
  { return errorOf([&] { interpolateAlongPath(keys, t, 4, 4, scene, perPixelOnly()); }); };
  EXPECT_NE(error({ { 0.0, &r, &all }, { 1.0, &r } }, 0.5).find("first and the last"),
            std::string::npos);
  EXPECT_NE(error({ { 0.0, &r }, { 1.0, &r, &all } }, 0.5).find("first and the last"),
            std::string::npos);
  EXPECT_NE(error({ { 0.0, &r }, { 0.5, &r, &short_ }, { 1.0, &r } }, 0.25).find("15 pixels"),
            std::string::npos);
  EXPECT_NE(error({ { 0.0, &r }, { 0.5, &r, &all }, { 1.0, &r } }, 0.5).find("partial key frame 1"),
            std::string::npos);
}

// A partial key that knows every pixel is a whole key: the frame is the same, bit for bit, as
// with the same records given whole.
TEST(PathPartialKeys, APartialKeyKnowingEveryPixelPredictsAsAWholeKey)
{
  constexpr int side = 48;
  std::vector<std::vector<RayRecord>> keys;
  const double s[4] = { 0.60, 0.65, 0.70, 0.75 };
  for (double m : s)
    keys.push_back(traceFrame(rampScene(m, side)));
  const std::vector<std::uint8_t> all(static_cast<std::size_t>(side) * side, 1);
  const double t = 0.675;
  const SceneDescription atT = rampScene(t, side);
  const PathFrame whole = interpolateAlongPath(
    { { s[0], &keys[0] }, { s[1], &keys[1] }, { s[2], &keys[2] }, { s[3], &keys[3] } }, t, side,
    side, *atT.scene, perPixelOnly());
  const PathFrame partial = interpolateAlongPath(
    { { s[0], &keys[0] }, { s[1], &keys[1] }, { s[2], &keys[2], &all }, { s[3], &keys[3] } }, t,
    side, side, *atT.scene, perPixelOnly());
  ASSERT_EQ(whole.records.size(), partial.records.size());
  std::size_t differ = 0;
  for (std::size_t p = 0; p < whole.records.size(); ++p)
    differ += whole.records[p].color != partial.records[p].color ||
              whole.records[p].u != partial.records[p].u ||
              whole.estimate[p] != partial.estimate[p] || whole.method[p] != partial.method[p];
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(countOf(whole, PathMethod::Cubic), whole.records.size() / 2);
}

// The mass ramp between whole keys 0.1 apart. The frame midway is interpolated and completed to
// 35 dB; its re-traced pixels are the records traced there, so as a partial key it halves the
// span over which the edges move for the frames beside it. The frame at 0.675 then leaves far
// fewer pixels that must be traced, re-traces fewer in all, and still meets the target against
// the frame the test traces there.
TEST(PathPartialKeys, APartialKeyNarrowsWhatMustBeTracedAndTheFrameStillMeetsItsTarget)
{
  constexpr int side = 96;
  constexpr double target = 35.0;
  const double s[4] = { 0.55, 0.65, 0.75, 0.85 };
  std::vector<std::vector<RayRecord>> keys;
  for (double m : s)
    keys.push_back(traceFrame(rampScene(m, side)));
  std::vector<PathKey> whole;
  for (int k = 0; k < 4; ++k)
    whole.push_back({ s[k], &keys[static_cast<std::size_t>(k)] });

  // The partial key at 0.70: completed, its re-traced pixels known.
  const SceneDescription atMiddle = rampScene(0.70, side);
  const FrameTracer middleTracer(atMiddle);
  PathFrame middle = interpolateAlongPath(whole, 0.70, side, side, *atMiddle.scene, perPixelOnly());
  completePathFrame(middle, middleTracer, target);
  std::vector<std::uint8_t> known(middle.records.size(), 0);
  const std::vector<RayRecord> middleTruth = middleTracer.traceRows(0, side);
  std::size_t knownCount = 0, knownWrong = 0;
  for (std::size_t p = 0; p < known.size(); ++p)
    if (middle.method[p] == static_cast<std::uint8_t>(PathMethod::Retraced))
    {
      known[p] = 1;
      ++knownCount;
      knownWrong += middle.records[p].color != middleTruth[p].color ||
                    middle.records[p].u != middleTruth[p].u ||
                    middle.records[p].objectId != middleTruth[p].objectId;
    }
  ASSERT_GT(knownCount, 0u);
  EXPECT_EQ(knownWrong, 0u) << "a partial key's known records are the records traced there";

  std::vector<PathKey> withPartial = whole;
  withPartial.insert(withPartial.begin() + 2, PathKey{ 0.70, &middle.records, &known });

  const double t = 0.675;
  const SceneDescription atT = rampScene(t, side);
  const FrameTracer tracer(atT);
  const std::vector<RayRecord> truth = tracer.traceRows(0, side);
  PathFrame before = interpolateAlongPath(whole, t, side, side, *atT.scene, perPixelOnly());
  PathFrame after = interpolateAlongPath(withPartial, t, side, side, *atT.scene, perPixelOnly());
  const std::size_t mustBefore = countOf(before, PathMethod::Retrace);
  const std::size_t mustAfter = countOf(after, PathMethod::Retrace);
  const PathCompletion doneBefore = completePathFrame(before, tracer, target);
  const PathCompletion doneAfter = completePathFrame(after, tracer, target);
  const double psnrBefore = psnrOf(before.records, truth), psnrAfter = psnrOf(after.records, truth);
  std::printf("[ path ] M = %.3f: must re-trace %zu -> %zu pixels, re-traced %zu -> %zu, "
              "%.1f -> %.1f dB against the traced frame (partial key at 0.70 knows %zu)\n",
              t, mustBefore, mustAfter, doneBefore.retraced, doneAfter.retraced, psnrBefore,
              psnrAfter, knownCount);
  EXPECT_GT(mustBefore, 0u);
  // The band the edges sweep is halved; the ring around it, a pixel wide, is not.
  EXPECT_LT(mustAfter, mustBefore * 17 / 20);
  EXPECT_LT(doneAfter.retraced, doneBefore.retraced);
  EXPECT_GE(psnrAfter, target - 1.0);
}
