// The closed-form oracles against the values physics.md printed from arbitrary-precision
// quadrature. Every integrator test leans on these, so they are checked on their own first.
#include "Analytic.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace asrt;

TEST(Analytic, DarwinTableFromPhysicsNotes)
{
  const struct
  {
    double r0, b, alpha;
  } table[] = { { 3.0001, 5.196152431366116, 19.81229906956 },
                { 3.1, 5.204106769920009, 6.086318685007748 },
                { 4, 5.656854249492381, 2.184100187727559 },
                { 10, 11.18033988749895, 0.5002356566077917 },
                { 100, 101.0152544552211, 0.04079561289280333 } };
  for (const auto& row : table)
  {
    EXPECT_NEAR(analytic::impactParameter(row.r0, 1.0), row.b, 1e-13 * row.b);
    EXPECT_NEAR(analytic::closestApproach(row.b, 1.0), row.r0, 1e-9 * row.r0);
    EXPECT_NEAR(analytic::darwinDeflection(row.r0, 1.0), row.alpha, 1e-11 * row.alpha)
      << "r0 = " << row.r0;
  }
  EXPECT_NEAR(analytic::darwinDeflection(6.0, 1.0), 1.01487543221757, 1e-13);
  EXPECT_NEAR(analytic::darwinDeflection(analytic::closestApproach(20, 1), 1), 0.23613599538847,
              1e-13);
  EXPECT_NEAR(analytic::darwinDeflection(analytic::closestApproach(1000, 1), 1),
              4.01182380992536e-3, 1e-15);
}

TEST(Analytic, NearCriticalTable)
{
  const double bc = 3.0 * std::sqrt(3.0);
  EXPECT_NEAR(analytic::darwinDeflection(analytic::closestApproach(bc * (1 + 1e-3), 1), 1),
              6.51064482660147, 1e-10);
  EXPECT_NEAR(analytic::strongFieldDeflection(bc * (1 + 1e-3), 1), 6.50752523922688, 1e-12);
  EXPECT_NEAR(analytic::darwinDeflection(analytic::closestApproach(bc * (1 + 1e-6), 1), 1),
              13.4152855577942, 1e-8);
  EXPECT_NEAR(analytic::strongFieldDeflection(bc * (1 + 1e-6), 1), 13.415280518209,
              1e-9); // b_c(1 + 1e-6) rounds to 1e-10 of b/b_c − 1
}

TEST(Analytic, WeakAndStrongLimitsAgreeWithDarwin)
{
  const double b = 101.0152544552211;
  EXPECT_NEAR(analytic::weakFieldDeflection(b, 1), analytic::darwinDeflection(100, 1), 1e-7);
  const double bc = 3.0 * std::sqrt(3.0);
  const double bNear = bc * (1 + 1.7e-9);
  EXPECT_NEAR(analytic::strongFieldDeflection(bNear, 1),
              analytic::darwinDeflection(analytic::closestApproach(bNear, 1), 1), 1e-6);
}

TEST(Analytic, SweepToInfinityIsTheFlatAngleWithoutMass)
{
  // A straight line at distance b sweeps asin(b/r) between radius r and infinity.
  for (double r : { 30.0, 100.0, 1e4 })
    EXPECT_NEAR(analytic::sweepToInfinity(10.0, 0.0, r), std::asin(10.0 / r), 1e-15);
  // First order in M: ∂/∂M ∫₀^{u_e} du (1/b² − u² + 2Mu³)^{−1/2} at M = 0 is
  // −(1/b)(1/cos θ_e + cos θ_e − 2) with sin θ_e = b/r (substituting u = sin θ / b).
  const double b = 50, r = 400, dM = 1e-4;
  const double c = std::cos(std::asin(b / r));
  const double slope =
    (analytic::sweepToInfinity(b, dM, r) - analytic::sweepToInfinity(b, -dM, r)) / (2 * dM);
  EXPECT_NEAR(slope, -(1.0 / c + c - 2.0) / b, 1e-6 * std::abs(slope));
}

TEST(Analytic, ShadowOfAStaticObserver)
{
  // Far away the shadow tends to b_c/r_o; at the photon sphere it is a hemisphere.
  EXPECT_NEAR(analytic::shadowAngularRadius(1e6, 1), 3 * std::sqrt(3.0) / 1e6, 1e-11);
  EXPECT_NEAR(analytic::shadowAngularRadius(3.0, 1), M_PI / 2, 1e-7);
}
