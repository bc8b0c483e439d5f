// The paper's splats between two frames of the mass ramp (Figs. 4–5), whose hole grows between
// them: Fig. 4's cylinders run through it, and the parts of them that its horizon swallows between
// the frames are seen by the first frame alone. Their splats, drawn at t, show a surface where the
// frame the test traces at t shows the hole. Given the horizon at t (renderFrame's horizonRadius),
// they are not drawn.
#include "FrameInterpolation.h"
#include "FrameTracer.h"
#include "KdTreeIndex.h"
#include "RampScene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

using namespace asrt;

namespace
{
constexpr int kSide = 96;

std::vector<RayRecord> rampFrame(double mass)
{
  return FrameTracer(asrt::testing::rampScene(mass, kSide)).traceRows(0, kSide);
}

FrameSamples samplesOf(const std::vector<RayRecord>& records, const char* which)
{
  return samplesFromRecords(records, kSide, kSide,
                            asrt::testing::rampScene(0.5, kSide).camera.viewAngle, which);
}

/// Squared 8-bit colour error summed over the channels and pixels.
double error2(const std::vector<std::uint8_t>& rgb, const std::vector<RayRecord>& truth)
{
  double sum = 0;
  for (std::size_t p = 0; p < truth.size(); ++p)
  {
    const auto c = imageColor(truth[p].color);
    for (int k = 0; k < 3; ++k)
    {
      const double d = double(rgb[3 * p + k]) - double(c[static_cast<std::size_t>(k)]);
      sum += d * d;
    }
  }
  return sum;
}
}

TEST(SplatHorizon, AGrowingHoleHidesTheSplatsOfWhatItSwallowed)
{
  const double ma = 0.56, mb = 0.67;
  const FrameSamples a = samplesOf(rampFrame(ma), "A"), b = samplesOf(rampFrame(mb), "B");
  const SplatSet set = buildSplats(a, b, matchFrames(a, b, kdTreeIndexFactory()));
  ASSERT_EQ(set.hitRadius.size(), set.splats.size());
  InterpolationWorkspace ws;
  for (const double t : { 0.25, 0.5 })
  {
    const double mass = ma + t * (mb - ma);
    const std::vector<RayRecord> truth = rampFrame(mass);
    const double horizon = 2.0 * mass; // Schwarzschild's
    InterpolatedFrame hidden, drawn;
    renderFrame(set, t, hidden, ws, SplatSides::Both, horizon);
    renderFrame(set, t, drawn, ws);
    std::size_t shownInside = 0, insideBefore = 0, swallowedShown = 0, swallowedBefore = 0;
    for (std::size_t p = 0; p < truth.size(); ++p)
    {
      const bool hole = truth[p].termination == Termination::Captured;
      if (hidden.source[p] >= 0)
      {
        const float r = set.hitRadius[static_cast<std::size_t>(hidden.source[p])];
        shownInside += r <= horizon;
        swallowedShown += hole && std::isfinite(r);
      }
      if (drawn.source[p] >= 0)
      {
        const float r = set.hitRadius[static_cast<std::size_t>(drawn.source[p])];
        insideBefore += r <= horizon;
        swallowedBefore += hole && std::isfinite(r);
      }
    }
    const double errorHidden = error2(hidden.rgb, truth), errorDrawn = error2(drawn.rgb, truth);
    std::printf("[ splats ] M = %.4f between %.2f and %.2f: %zu pixels showed a point inside the "
                "horizon, %zu now; a surface where the traced frame shows the hole at %zu pixels, "
                "%zu before; squared error %.0f, %.0f before\n",
                mass, ma, mb, insideBefore, shownInside, swallowedShown, swallowedBefore,
                errorHidden, errorDrawn);
    EXPECT_GT(insideBefore, 20u);
    EXPECT_EQ(shownInside, 0u);
    EXPECT_LT(swallowedShown, swallowedBefore);
    EXPECT_LT(errorHidden, errorDrawn);
    if (t == 0.5) // where the first frame's swallowed points have moved furthest
    {
      EXPECT_LE(swallowedShown, 0.6 * swallowedBefore);
      EXPECT_LT(errorHidden, 0.8 * errorDrawn);
    }
  }
  InterpolatedFrame f;
  for (const double bad : { -1.0, std::nan(""), std::numeric_limits<double>::infinity() })
    EXPECT_THROW(renderFrame(set, 0.5, f, ws, SplatSides::Both, bad), InvalidParameter) << bad;
  SplatSet without = set;
  without.hitRadius.clear();
  EXPECT_THROW(renderFrame(without, 0.5, f, ws, SplatSides::Both, 1.0), InvalidParameter);
  EXPECT_NO_THROW(renderFrame(without, 0.5, f, ws));
}
