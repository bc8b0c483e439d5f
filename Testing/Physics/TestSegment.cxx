// The stepping API hands out each step as a Segment whose cubic Hermite interpolant must follow the
// true ray inside the step to O(h⁴), so that hit points can be refined to the integrator's accuracy
// instead of the chord's.
#include "RayFixtures.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace asrt;

namespace
{
/// Distance between the segment's interpolated midpoint and the ray's true midpoint (in s), the
/// latter from a half step of Gauss–Legendre 6 (error O(h⁷), negligible here), and the chord's.
void midpointErrors(double h, double& hermite, double& chord)
{
  const SchwarzschildSpacetime st(1.0);
  const PhasePoint z = asrt::testing::equatorialRay(st, 8.0, 6.0); // curving strongly near 3–8 M
  GeneralPropagator full(st, std::make_unique<GaussLegendre>(3), h, true);
  GeneralPropagator half(st, std::make_unique<GaussLegendre>(3), 0.5 * h, true);
  full.start(z);
  half.start(z);
  Segment seg, halfSeg;
  ASSERT_TRUE(full.advance(seg));
  ASSERT_TRUE(half.advance(halfSeg));
  const Vec3 truth = halfSeg.x1.tail<3>();
  hermite = (seg.position(0.5).tail<3>() - truth).norm();
  chord = (0.5 * (seg.x0 + seg.x1)).tail<3>().operator-(truth).norm();
}
}

TEST(Segment, HermiteInterpolantIsFourthOrderInsideTheStep)
{
  double e1, c1, e2, c2;
  midpointErrors(0.2, e1, c1);
  midpointErrors(0.1, e2, c2);
  // Halving h divides the interpolation error by ~2⁴ = 16 (the chord's by ~2² = 4).
  EXPECT_NEAR(std::log2(e1 / e2), 4.0, 0.4) << e1 << " " << e2;
  EXPECT_NEAR(std::log2(c1 / c2), 2.0, 0.4) << c1 << " " << c2;
  EXPECT_LT(e2, 1e-2 * c2);
}

TEST(Segment, EndsAndTangentsAreConsistent)
{
  const SchwarzschildSpacetime st(1.0);
  for (const char* method : { "SchwarzschildSplit4", "GaussLegendre4", "RK4", "Tao4" })
  {
    IntegratorConfig cfg;
    cfg.method = method;
    cfg.step = 0.05;
    auto prop = makePropagator(st, cfg);
    prop->start(asrt::testing::equatorialRay(st, 30.0, 7.0));
    Segment a, b;
    ASSERT_TRUE(prop->advance(a));
    ASSERT_TRUE(prop->advance(b));
    // Consecutive segments join, and the interpolant passes through both ends.
    EXPECT_EQ(a.x1, b.x0) << method;
    EXPECT_EQ(a.lambda1, b.lambda0) << method;
    EXPECT_LT((a.position(0.0) - a.x0).norm(), 1e-14) << method;
    EXPECT_LT((a.position(1.0) - a.x1).norm(), 1e-12) << method;
    EXPECT_GT(a.lambda1, a.lambda0) << method;
    EXPECT_NEAR(a.lambda(0.0), a.lambda0, 1e-12) << method;
    EXPECT_NEAR(a.lambda(1.0), a.lambda1, 1e-12 * a.lambda1) << method;
    EXPECT_GT(a.dl0, 0.0) << method; // dλ/dτ > 0: the affine parameter runs forward
    EXPECT_GT(a.dl1, 0.0) << method;
    // The end tangents point along the step (a smooth ray, a short step).
    const Vec3 chord = (a.x1 - a.x0).tail<3>();
    EXPECT_GT(a.d0.tail<3>().normalized().dot(chord.normalized()), 0.99) << method;
    EXPECT_GT(a.d1.tail<3>().normalized().dot(chord.normalized()), 0.99) << method;
  }
}
