// The planar orbit stepped in its angle (PlanarSeriesPropagator): its segments' affine parameter
// and Kerr–Schild time against the radial integrals of the exact first integrals, and its segment
// ends on the light cone. (Its deflections against Darwin's: TestDeflection.cxx; whole frames:
// TestPlanarOrbitFrames.cxx.)
#include "RayFixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace asrt;
using asrt::testing::equatorialRay;

namespace
{
/// Simpson's rule on n panels.
template<class F>
double simpson(F f, double a, double b, int n = 20000)
{
  const double h = (b - a) / n;
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
  {
    const double x = a + k * h;
    sum += f(x) + 4.0 * f(x + 0.5 * h) + f(x + h);
  }
  return sum * h / 6.0;
}

std::vector<Segment> segmentsOf(const Spacetime& st, const PhasePoint& z, double rtol)
{
  IntegratorConfig cfg;
  cfg.method = "PlanarSeries";
  cfg.relativeTolerance = rtol;
  cfg.absoluteTolerance = 1e-2 * rtol;
  auto prop = makePropagator(st, cfg);
  TraceOptions opts;
  opts.escapeRadius = 200.0;
  std::vector<Segment> segments;
  traceRay(st, *prop, z, opts,
           [&](const Segment& s)
           {
             segments.push_back(s);
             return false;
           });
  return segments;
}
}

TEST(PlanarSeries, AffineParameterAndTimeFollowTheRadialIntegrals)
{
  // Coming in, r falls monotonically, and with E = 1, L = b (equatorialRay), ṙ² = 1 − (1 − 2M/r)
  // b²/r² gives dλ = dr/|ṙ| and, in Kerr–Schild time, dt/dλ = (E + f ṙ)/(1 − f), f = 2M/r.
  const SchwarzschildSpacetime st(1.0);
  for (const double b : { 5.3, 10.0, 20.0 })
  {
    const PhasePoint z = equatorialRay(st, 31.0, b);
    auto rdot = [b](double r) { return std::sqrt(1.0 - (1.0 - 2.0 / r) * b * b / (r * r)); };
    int checked = 0;
    for (const Segment& s : segmentsOf(st, z, 1e-10))
    {
      const double r0 = s.x0.tail<3>().norm(), r1 = s.x1.tail<3>().norm();
      // Incoming segments away from the periapsis, where 1/|ṙ| stays smooth.
      if (!(r1 < r0) || rdot(r1) < 0.2)
        break;
      const double dl = simpson([&](double r) { return 1.0 / rdot(r); }, r1, r0);
      const double dt = simpson(
        [&](double r)
        {
          const double f = 2.0 / r;
          return (1.0 - f * rdot(r)) / ((1.0 - f) * rdot(r));
        },
        r1, r0);
      EXPECT_NEAR(s.lambda1 - s.lambda0, dl, 1e-8 * dl) << "b = " << b << ", r = " << r0;
      EXPECT_NEAR(s.x1[0] - s.x0[0], dt, 1e-8 * dt) << "b = " << b << ", r = " << r0;
      ++checked;
    }
    EXPECT_GE(checked, 3) << "b = " << b;
  }
}

TEST(PlanarSeries, SegmentEndsStayOnTheLightCone)
{
  // The momentum is rebuilt from u and du/dφ at every end: H = 0 holds to the series' accuracy,
  // also on rays winding near the photon sphere, where the orbit is most sensitive.
  const SchwarzschildSpacetime st(1.0);
  const double bc = 3.0 * std::sqrt(3.0);
  for (const double b : { bc * (1 + 1e-6), bc * (1 - 1e-6), 6.0, 40.0 })
  {
    const PhasePoint z = equatorialRay(st, 100.0, b);
    const std::vector<Segment> segments = segmentsOf(st, z, 1e-10);
    ASSERT_FALSE(segments.empty());
    for (const Segment& s : segments)
      EXPECT_LT(std::abs(st.value(s.x1, s.p1)), 1e-9 * s.p1.squaredNorm()) << "b = " << b;
  }
}

TEST(PlanarSeries, TheFarFieldRunsOutInOneSegmentOnTheRadialIntegrals)
{
  // Beyond the objects (a ball of 20 M here) an outgoing ray runs out to the sky sphere in one
  // segment; its λ and t are the radial integrals between its end radii, and it lands on the sky.
  // Both ways in time: a ray passing the hole (E = 1), and one leaving at once along the reversed
  // momentum (E = −1, as the camera's rays traced back from the eye).
  const SchwarzschildSpacetime st(1.0);
  const double b = 10.0, sky = 500.0;
  for (const double E : { 1.0, -1.0 })
  {
    PhasePoint z = equatorialRay(st, 31.0, b);
    if (E < 0.0)
      z.p = -z.p;
    IntegratorConfig cfg = integratorPreset("balanced");
    cfg.method = "PlanarSeries";
    auto prop = makePropagator(st, cfg);
    TraceOptions opts;
    opts.escapeRadius = 1000.0;
    opts.farField.objectRadius = 20.0;
    opts.farField.skyRadii = { sky };
    std::vector<Segment> far;
    const TraceResult r = traceRay(st, *prop, z, opts,
                                   [&](const Segment& s)
                                   {
                                     const Vec3 a = s.x0.tail<3>(), e = s.x1.tail<3>();
                                     if (s.farField && e.norm() > a.norm())
                                       far.push_back(s);
                                     return false;
                                   });
    ASSERT_EQ(r.termination, Termination::Escaped) << "E = " << E;
    ASSERT_EQ(far.size(), 2u) << "one segment to the sky, one beyond it; E = " << E;
    const Segment& s = far.front();
    const double r0 = s.x0.tail<3>().norm(), r1 = s.x1.tail<3>().norm();
    EXPECT_GE(r0, 20.0);
    EXPECT_GT(r1, sky);
    EXPECT_LT(r1, sky * (1 + 1e-10)) << "lands just beyond the sky sphere";
    // ṙ² = E² − (1 − 2M/r) b²/r², dλ = dr/ṙ, dt = (E + f ṙ)/((1 − f) ṙ) dr.
    auto rdot = [b](double x) { return std::sqrt(1.0 - (1.0 - 2.0 / x) * b * b / (x * x)); };
    const double dl = simpson([&](double x) { return 1.0 / rdot(x); }, r0, r1, 200000);
    const double dt = simpson(
      [&](double x)
      {
        const double f = 2.0 / x;
        return (E + f * rdot(x)) / ((1.0 - f) * rdot(x));
      },
      r0, r1, 200000);
    EXPECT_NEAR(s.lambda1 - s.lambda0, dl, 1e-9 * dl) << "E = " << E;
    EXPECT_NEAR(s.x1[0] - s.x0[0], dt, 1e-9 * std::abs(dt)) << "E = " << E;
    EXPECT_LT(std::abs(st.value(s.x1, s.p1)), 1e-12 * s.p1.squaredNorm()) << "E = " << E;
  }
}
