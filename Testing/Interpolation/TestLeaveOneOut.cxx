// The keys' leave-one-out errors (PathInterpolation.h, leaveOneOutError) and the estimate they
// weigh, against keys whose disagreement the test puts in by hand and against frames it traces
// itself at the interpolated parameter.
#include "FrameTracer.h"
#include "KdTreeIndex.h"
#include "LeaveOneOut.h"
#include "RampScene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

using namespace asrt;
using asrt::testing::rampScene;

namespace
{
std::vector<RayRecord> traceFrame(const SceneDescription& d)
{
  return FrameTracer(d).traceRows(0, d.camera.height);
}

PathOptions withMovedEdges()
{
  PathOptions options;
  options.pointIndex = kdTreeIndexFactory();
  return options;
}

double error2(const RayRecord& a, const RayRecord& b)
{
  return (255.0 * (a.color - b.color)).squaredNorm();
}

/// The share of the frame's pixels re-traced, the must-retrace ones first and then in `order`,
/// for its error against `truth` to fall to the mean squared error of `targetDb`.
double shareFor(const PathFrame& f, const std::vector<RayRecord>& truth,
                const std::vector<std::size_t>& order, double targetDb)
{
  const double n = static_cast<double>(f.records.size());
  const double allowed = 3.0 * n * 255.0 * 255.0 / std::pow(10.0, targetDb / 10.0);
  double left = 0;
  std::size_t traced = 0;
  for (std::size_t p = 0; p < f.records.size(); ++p)
    if (f.method[p] == static_cast<std::uint8_t>(PathMethod::Retrace))
      ++traced;
    else
      left += error2(f.records[p], truth[p]);
  for (std::size_t k = 0; k < order.size() && left > allowed; ++k, ++traced)
    left -= error2(f.records[order[k]], truth[order[k]]);
  return static_cast<double>(traced) / n;
}

/// The predicted pixels, worst estimate first.
std::vector<std::size_t> byEstimate(const PathFrame& f)
{
  std::vector<std::size_t> order;
  for (std::size_t p = 0; p < f.records.size(); ++p)
    if (f.method[p] != static_cast<std::uint8_t>(PathMethod::Retrace))
      order.push_back(p);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return f.estimate[a] > f.estimate[b]; });
  return order;
}
}

// Five keys with the same records but for one pixel's colour in the middle key: predicted from the
// others, that key misses by exactly its change there and nowhere else (re-shading a key's own
// surface coordinates gives its colours back), so its leave-one-out error is the change, spread
// over the square of the given radius around the pixel; where the middle key is not an inner key,
// or where it is the one the others predict from, nothing shows.
TEST(LeaveOneOut, AKeyThatDisagreesWithItsNeighboursMarksTheSquareAroundIt)
{
  constexpr int side = 24;
  const SceneDescription d = rampScene(0.7, side);
  const std::vector<RayRecord> frame = traceFrame(d);
  // A pixel on an object, traced with one ray, two pixels or more from the frame's border.
  std::size_t changed = 0;
  for (int j = 6; j < side - 6 && changed == 0; ++j)
    for (int i = 6; i < side - 6 && changed == 0; ++i)
    {
      const RayRecord& r = frame[static_cast<std::size_t>(j) * side + i];
      if (r.termination == Termination::HitObject && r.raysPerPixel == 1)
        changed = static_cast<std::size_t>(j) * side + i;
    }
  ASSERT_NE(changed, 0u) << "no single-ray object pixel in the frame";
  std::vector<RayRecord> odd = frame;
  odd[changed].color += Color(0.1, 0.0, 0.0);
  const double step = 255.0 * 255.0 * 0.01;
  std::vector<PathKey> keys;
  for (int k = 0; k < 5; ++k)
    keys.push_back({ 1.0 * k, k == 2 ? &odd : &frame });
  const int ci = static_cast<int>(changed % side), cj = static_cast<int>(changed / side);
  for (const int radius : { 0, 2 })
    for (const double t : { 1.5, 2.5 })
    {
      const std::vector<float> L =
        leaveOneOutError(keys, t, side, side, *d.scene, withMovedEdges(), radius);
      ASSERT_EQ(L.size(), frame.size());
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i)
        {
          const bool inside = std::abs(i - ci) <= radius && std::abs(j - cj) <= radius;
          const float e = L[static_cast<std::size_t>(j) * side + i];
          if (inside)
            EXPECT_NEAR(e, step, 1e-3 * step) << i << ", " << j << ", t = " << t;
          else
            EXPECT_LT(e, 1e-6 * step) << i << ", " << j << ", t = " << t;
        }
    }
  // Key 2 is no inner key of t = 0.5 or 3.5; keys 0 and 4 have no key beyond them to be left out.
  for (const double t : { 0.5, 3.5 })
  {
    const std::vector<float> L =
      leaveOneOutError(keys, t, side, side, *d.scene, withMovedEdges(), 2);
    ASSERT_EQ(L.size(), frame.size());
    EXPECT_LT(*std::max_element(L.begin(), L.end()), 1e-6 * step) << "t = " << t;
  }
  // A key left out with too few records, or t outside the keys, is refused by name.
  const std::vector<RayRecord> few(frame.begin(), frame.begin() + side);
  std::vector<PathKey> broken = keys;
  broken[2].records = &few;
  EXPECT_THROW(leaveOneOutError(broken, 2.5, side, side, *d.scene, withMovedEdges()),
               InvalidParameter);
  EXPECT_THROW(leaveOneOutError(keys, 4.5, side, side, *d.scene, withMovedEdges()),
               InvalidParameter);
  // Two keys: neither can be left out.
  EXPECT_TRUE(
    leaveOneOutError({ keys[0], keys[1] }, 0.5, side, side, *d.scene, withMovedEdges()).empty());
}

// Keys of the mass ramp around a frame the test traces: weighed by the leave-one-out errors, the
// estimate keeps each way of predicting's total (what its probes calibrate), and the frames
// completed from it (completePathFrame, the pixels served from the frame traced at t) reach 35
// and 40 dB against that frame with fewer pixels re-traced over two frames and two targets than
// from the estimate without (the weights rank the edge blends, whose calibration then has no
// floor); made without estimates, the frame's colours are the same; the errors kept between
// frames give the same frames, each key left out once.
TEST(LeaveOneOut, TheWeighedEstimateCompletesFramesWithFewerPixelsAndKeepsEachWaysTotal)
{
  constexpr int side = 80;
  std::vector<std::vector<RayRecord>> records;
  std::vector<PathKey> keys;
  for (int k = 0; k < 5; ++k)
    records.push_back(traceFrame(rampScene(0.6 + 0.055 * k, side)));
  for (int k = 0; k < 5; ++k)
    keys.push_back({ 0.6 + 0.055 * k, &records[static_cast<std::size_t>(k)] });
  PathOptions plain = withMovedEdges();
  plain.leaveOneOut = false;
  PathOptions weighed = withMovedEdges();
  PathOptions kept = withMovedEdges();
  kept.leaveOneOutCache = std::make_shared<LeaveOneOutCache>();
  // Keys whose fingerprints their caller keeps (as asrt movie does), kept errors of their own.
  std::vector<PathKey> printed = keys;
  for (PathKey& key : printed)
    key.fingerprint = matchingFingerprint(*key.records);
  PathOptions keptPrinted = kept;
  keptPrinted.leaveOneOutCache = std::make_shared<LeaveOneOutCache>();
  double gained = 0;
  for (const double t : { 0.6825, 0.7375 })
  {
    const SceneDescription atT = rampScene(t, side);
    const std::vector<RayRecord> truth = traceFrame(atT);
    const PathFrame a = interpolateAlongPath(keys, t, side, side, *atT.scene, plain);
    const PathFrame b = interpolateAlongPath(keys, t, side, side, *atT.scene, weighed);
    const PathFrame c = interpolateAlongPath(keys, t, side, side, *atT.scene, kept);
    // Without estimates (as the keys left out are made): the same colours and ways.
    PathOptions colours = plain;
    colours.estimates = false;
    const PathFrame d = interpolateAlongPath(keys, t, side, side, *atT.scene, colours);
    ASSERT_EQ(a.method, d.method);
    for (std::size_t p = 0; p < a.records.size(); ++p)
      ASSERT_EQ(a.records[p].color, d.records[p].color) << p;
    ASSERT_EQ(a.method, b.method);
    ASSERT_EQ(b.estimate, c.estimate) << "t = " << t;
    ASSERT_EQ(b.estimate,
              interpolateAlongPath(printed, t, side, side, *atT.scene, keptPrinted).estimate)
      << "t = " << t;
    std::array<double, kPathMethodCount> totalA{}, totalB{};
    std::size_t moved = 0;
    for (std::size_t p = 0; p < a.records.size(); ++p)
    {
      ASSERT_EQ(a.records[p].color, b.records[p].color) << p;
      if (a.method[p] == static_cast<std::uint8_t>(PathMethod::Retrace))
        continue;
      totalA[a.method[p]] += a.estimate[p];
      totalB[a.method[p]] += b.estimate[p];
      moved += b.estimate[p] != a.estimate[p];
    }
    for (int m = 0; m < kPathMethodCount; ++m)
      EXPECT_NEAR(totalB[m], totalA[m], 1e-4 * totalA[m] + 1e-6) << toString(PathMethod(m));
    EXPECT_GT(moved, a.records.size() / 10) << "the weights change few estimates";
    const PixelTracer fromTruth =
      [&truth](const std::vector<std::pair<int, int>>& ij, const std::vector<JacobianSample>&)
    {
      TracedPixels out;
      for (const auto& [i, j] : ij)
        out.records.push_back(truth[static_cast<std::size_t>(j) * side + i]);
      return out;
    };
    for (const double target : { 35.0, 40.0 })
    {
      PathFrame completedA = a, completedB = b;
      const double n = static_cast<double>(a.records.size());
      const double before = completePathFrame(completedA, fromTruth, target).retraced / n;
      const double after = completePathFrame(completedB, fromTruth, target).retraced / n;
      std::printf("[ leave one out ] t = %.4f, %.0f dB: %.1f %% re-traced, %.1f %% weighed (in "
                  "the estimate's order alone: %.1f %%, %.1f %%)\n",
                  t, target, 100.0 * before, 100.0 * after,
                  100.0 * shareFor(a, truth, byEstimate(a), target),
                  100.0 * shareFor(b, truth, byEstimate(b), target));
      gained += before - after;
      // Not every frame and target gains (one here loses a point), none by much.
      EXPECT_LE(after, before + 0.02) << "t = " << t << ", " << target << " dB";
    }
  }
  EXPECT_GT(gained, 0.02) << "the weighed estimate re-traces no fewer pixels on the whole";
  EXPECT_EQ(kept.leaveOneOutCache->made(), 3u); // keys 1 and 2, then 2 (kept) and 3
  EXPECT_EQ(keptPrinted.leaveOneOutCache->made(), 3u);
}
