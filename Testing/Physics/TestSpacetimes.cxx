// Spacetimes: analytic gradients against automatic differentiation of the Hamiltonian as written
// from its metric, horizons and photon orbits against the closed forms, and parameter checks.
#include "Spacetime.h"

#include <gtest/gtest.h>
#include <unsupported/Eigen/AutoDiff>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <utility>

using namespace asrt;

namespace
{
using AD = Eigen::AutoDiffScalar<Eigen::Matrix<double, 8, 1>>;
using Vec4AD = Eigen::Matrix<AD, 4, 1>;

template<class ST>
void expectGradientMatchesAutoDiff(const ST& st, double rMin, double rMax, unsigned seed)
{
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), radius(rMin, rMax);
  for (int trial = 0; trial < 200; ++trial)
  {
    Vec3 dir(unit(gen), unit(gen), unit(gen));
    dir.normalize();
    const Vec4 x(unit(gen) * 10, 0, 0, 0);
    Vec4 xs = x;
    xs.tail<3>() = radius(gen) * dir;
    const Vec4 p(-1.0 + 0.3 * unit(gen), unit(gen), unit(gen), unit(gen));
    Vec4AD xa, pa;
    for (int i = 0; i < 4; ++i)
    {
      xa[i] = AD(xs[i], 8, i);
      pa[i] = AD(p[i], 8, 4 + i);
    }
    const AD H = st.template hamiltonian<AD>(xa, pa);
    Vec4 dHdx, dHdp;
    const double value = st.gradient(xs, p, dHdx, dHdp);
    EXPECT_NEAR(value, H.value(), 1e-13 * (1 + std::abs(H.value())));
    EXPECT_NEAR(st.value(xs, p), value, 1e-14 * (1 + std::abs(value)));
    for (int i = 0; i < 4; ++i)
    {
      const double scale = 1e-12 * (1.0 + H.derivatives().cwiseAbs().maxCoeff());
      EXPECT_NEAR(dHdx[i], H.derivatives()[i], scale) << st.name() << " dH/dx" << i;
      EXPECT_NEAR(dHdp[i], H.derivatives()[4 + i], scale) << st.name() << " dH/dp" << i;
    }
    // g^{μν} is the Hessian of H in p, and metric() must be its inverse.
    const Mat4 ginv = st.inverseMetric(xs);
    EXPECT_NEAR(0.5 * p.dot(ginv * p), value, 1e-12 * (1 + std::abs(value)));
    EXPECT_LT((st.metric(xs) * ginv - Mat4::Identity()).cwiseAbs().maxCoeff(), 1e-11);
  }
}
}

TEST(Spacetime, MinkowskiGradientMatchesAutoDiff)
{
  MinkowskiSpacetime st;
  Vec4 x(0, 1, 2, 3), p(-1, 0.2, 0.3, 0.4), gx, gp;
  st.gradient(x, p, gx, gp);
  EXPECT_EQ(gx, Vec4::Zero());
  EXPECT_EQ(gp, Vec4(1, 0.2, 0.3, 0.4));
}

TEST(Spacetime, SchwarzschildGradientMatchesAutoDiff)
{
  expectGradientMatchesAutoDiff(SchwarzschildSpacetime(1.0), 2.1, 50.0, 1);
}

TEST(Spacetime, ReissnerNordstromGradientMatchesAutoDiff)
{
  expectGradientMatchesAutoDiff(ReissnerNordstromSpacetime(1.0, 0.7), 1.9, 50.0, 2);
}

TEST(Spacetime, KerrGradientMatchesAutoDiff)
{
  expectGradientMatchesAutoDiff(KerrSpacetime(1.0, 0.9), 1.6, 50.0, 3);
  expectGradientMatchesAutoDiff(KerrSpacetime(1.0, -0.5), 2.0, 50.0, 4);
  expectGradientMatchesAutoDiff(KerrSpacetime(1.0, 1.0), 1.2, 20.0, 5);
}

TEST(Spacetime, KerrReducesToSchwarzschildAtZeroSpin)
{
  KerrSpacetime kerr(1.0, 0.0);
  SchwarzschildSpacetime schw(1.0);
  const Vec4 x(0.3, 3.0, -4.0, 1.5), p(-1.0, 0.3, -0.2, 0.7);
  EXPECT_NEAR(kerr.value(x, p), schw.value(x, p), 1e-15);
  EXPECT_NEAR(kerr.radius(x), std::sqrt(9.0 + 16.0 + 2.25), 1e-14);
}

TEST(Spacetime, KerrRadiusSolvesTheQuartic)
{
  // x² + y² + z² = r² + a² − a² z²/r² (physics.md), also for points inside R < a.
  KerrSpacetime st(1.0, 0.99);
  for (const Vec4& x : { Vec4(0, 3, 4, 5), Vec4(0, 0.1, 0.2, 0.05), Vec4(0, 0.5, 0, 0.01) })
  {
    const double r = st.radius(x), a = 0.99;
    const double R2 = x.tail<3>().squaredNorm();
    EXPECT_NEAR(R2, r * r + a * a - a * a * x[3] * x[3] / (r * r), 1e-13);
  }
}

TEST(Spacetime, HorizonsAndPhotonSpheres)
{
  SchwarzschildSpacetime schw(2.0);
  EXPECT_DOUBLE_EQ(schw.outerHorizon(), 4.0);
  EXPECT_DOUBLE_EQ(schw.photonOrbits()->prograde, 6.0);
  EXPECT_NEAR(schw.criticalImpactParameter(), 2.0 * 5.196152422706632, 1e-14);

  // Reissner–Nordström: physics.md reference values.
  ReissnerNordstromSpacetime rn(1.0, 0.5);
  EXPECT_NEAR(rn.photonOrbits()->prograde, 2.822875655532, 1e-12);
  EXPECT_NEAR(rn.criticalImpactParameter(), 4.967914329471, 1e-12);
  EXPECT_NEAR(rn.outerHorizon(), 1.0 + std::sqrt(0.75), 1e-15);
  EXPECT_NEAR(rn.innerHorizon(), 1.0 - std::sqrt(0.75), 1e-15);
  ReissnerNordstromSpacetime extremalRN(1.0, 1.0);
  EXPECT_NEAR(extremalRN.photonOrbits()->prograde, 2.0, 1e-15);
  EXPECT_NEAR(extremalRN.criticalImpactParameter(), 4.0, 1e-14);
  EXPECT_DOUBLE_EQ(extremalRN.outerHorizon(), 1.0);

  // Kerr equatorial circular photon orbits, physics.md's table.
  const struct
  {
    double a, pro, retro;
  } kerrTable[] = { { 0.5, 2.3472963553338606, 3.5320888862379562 },
                    { 0.9, 1.5578546274233827, 3.910267939103037 },
                    { 0.999, 1.052080915928762, 3.9991110287870693 },
                    { 1.0, 1.0, 4.0 } };
  for (const auto& row : kerrTable)
  {
    KerrSpacetime kerr(1.0, row.a);
    EXPECT_NEAR(kerr.photonOrbits()->prograde, row.pro, 1e-12) << "a = " << row.a;
    EXPECT_NEAR(kerr.photonOrbits()->retrograde, row.retro, 1e-12) << "a = " << row.a;
    EXPECT_NEAR(kerr.outerHorizon(), 1.0 + std::sqrt(1.0 - row.a * row.a), 1e-15);
  }
  KerrSpacetime kerr(1.0, 0.9);
  EXPECT_NEAR(kerr.ergosphereRadius(0.0), 2.0, 1e-15);
  EXPECT_NEAR(kerr.ergosphereRadius(1.0), kerr.outerHorizon(), 1e-15);
}

TEST(Spacetime, MetricIsSingularExactlyAtTheHorizonForStaticObservers)
{
  // g_tt = −(1 − 2M/r) for Schwarzschild; zero on the horizon, positive inside. For Kerr, g_tt
  // changes sign on the ergosphere r_E(θ), outside the horizon off the poles.
  SchwarzschildSpacetime schw(1.0);
  EXPECT_NEAR(schw.metric(Vec4(0, 2.0, 0, 0))(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(schw.metric(Vec4(0, 0, 5.0, 0))(0, 0), -(1.0 - 2.0 / 5.0), 1e-15);
  KerrSpacetime kerr(1.0, 0.9);
  // On the equator the BL and KS radii coincide with √(x² + y² − a²).
  const double rE = kerr.ergosphereRadius(0.0);
  const Vec4 onErgo(0, std::sqrt(rE * rE + 0.81), 0, 0);
  EXPECT_NEAR(kerr.radius(onErgo), rE, 1e-14);
  EXPECT_NEAR(kerr.metric(onErgo)(0, 0), 0.0, 1e-14);
}

TEST(Spacetime, RejectsUnphysicalParameters)
{
  EXPECT_THROW((KerrSpacetime(1.0, 1.0 + 1e-12)), InvalidParameter);
  EXPECT_THROW((KerrSpacetime(1.0, -1.5)), InvalidParameter);
  EXPECT_THROW((KerrSpacetime(NAN, 0.5)), InvalidParameter);
  EXPECT_THROW((KerrSpacetime(1.0, NAN)), InvalidParameter);
  EXPECT_THROW((SchwarzschildSpacetime(-1.0)), InvalidParameter);
  EXPECT_THROW((SchwarzschildSpacetime(0.0)), InvalidParameter);
  EXPECT_THROW((SchwarzschildSpacetime(INFINITY)), InvalidParameter);
  EXPECT_THROW((ReissnerNordstromSpacetime(1.0, 1.01)), InvalidParameter);
  EXPECT_THROW(makeSpacetime({ -0.5, 0, 0 }), InvalidParameter);
  EXPECT_THROW(makeSpacetime({ 1.0, 0.5, 0.5 }), InvalidParameter);
  EXPECT_THROW(makeSpacetime({ 0.0, 0.5, 0.0 }), InvalidParameter);
  try
  {
    KerrSpacetime tooFast(1.0, 2.0);
    FAIL();
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("spin"), std::string::npos) << e.what();
  }
}

// A refusal prints the two values so that they differ: a = 1.000000000000001 against M = 1.
TEST(Spacetime, RefusalsPrintValuesThatDiffer)
{
  const double a = 1.000000000000001; // prints as 1 in the stream's default 6 digits
  for (const bool charged : { false, true })
  {
    SCOPED_TRACE(charged ? "charge" : "spin");
    std::string message;
    try
    {
      asrt::SpacetimeParameters p;
      p.mass = 1.0;
      (charged ? p.charge : p.spin) = a;
      asrt::makeSpacetime(p);
    }
    catch (const asrt::InvalidParameter& e)
    {
      message = e.what();
    }
    // Both numbers as printed read back as the values given.
    const std::string value = asrt::exactNumber(a);
    EXPECT_EQ(std::stod(value), a);
    EXPECT_NE(message.find("= " + value + " exceeds the mass M = 1:"), std::string::npos)
      << message;
  }
}

// exactNumber reads back as the very double it printed, for doubles of every magnitude, and
// as few digits as %.17g would need at most.
TEST(Spacetime, ExactNumberReadsBackExactly)
{
  std::mt19937_64 random(7);
  std::uniform_int_distribution<std::uint64_t> bits;
  int checked = 0;
  for (int k = 0; k < 20000; ++k)
  {
    const std::uint64_t b = bits(random);
    double v;
    std::memcpy(&v, &b, sizeof v);
    if (!std::isfinite(v))
      continue;
    const std::string text = asrt::exactNumber(v);
    ASSERT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
    char longest[64];
    std::snprintf(longest, sizeof longest, "%.17g", v);
    ASSERT_LE(text.size(), std::string(longest).size() + 4) << text << " vs " << longest;
    ++checked;
  }
  EXPECT_GT(checked, 19000);
  EXPECT_EQ(asrt::exactNumber(1.0), "1");
  EXPECT_EQ(asrt::exactNumber(0.1), "0.1");
}

TEST(Spacetime, FactoryPicksTheCheapestModel)
{
  EXPECT_EQ(makeSpacetime({ 0, 0, 0 })->kind(), SpacetimeKind::Minkowski);
  EXPECT_EQ(makeSpacetime({ 1, 0, 0 })->kind(), SpacetimeKind::Schwarzschild);
  EXPECT_EQ(makeSpacetime({ 1, 0.5, 0 })->kind(), SpacetimeKind::Kerr);
  EXPECT_EQ(makeSpacetime({ 1, 0, 0.5 })->kind(), SpacetimeKind::ReissnerNordstrom);
}

TEST(Spacetime, FactoryBuildsTheGivenParameters)
{
  const SpacetimeParameters kerr{ 1.5, -0.75, 0.0 };
  const auto k = makeSpacetime(kerr);
  EXPECT_EQ(k->mass(), 1.5);
  EXPECT_EQ(k->spin(), -0.75);
  EXPECT_EQ(k->charge(), 0.0);
  const auto rn = makeSpacetime({ 2.0, 0.0, 0.5 });
  EXPECT_EQ(rn->mass(), 2.0);
  EXPECT_EQ(rn->spin(), 0.0);
  EXPECT_EQ(rn->charge(), 0.5);
  // The default is flat space.
  EXPECT_EQ(makeSpacetime(SpacetimeParameters())->kind(), SpacetimeKind::Minkowski);
  // A non-finite parameter is refused by name.
  for (const auto& [bad, name] : { std::pair{ SpacetimeParameters{ NAN, 0, 0 }, "mass" },
                                   std::pair{ SpacetimeParameters{ 1, INFINITY, 0 }, "spin" },
                                   std::pair{ SpacetimeParameters{ 1, 0, NAN }, "charge" } })
  {
    try
    {
      makeSpacetime(bad);
      ADD_FAILURE() << name;
    }
    catch (const InvalidParameter& e)
    {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(SpacetimeParameters, EqualWhenEveryParameterIs)
{
  const SpacetimeParameters p{ 1.0, 0.5, 0.0 };
  EXPECT_EQ(p, (SpacetimeParameters{ 1.0, 0.5, 0.0 }));
  EXPECT_NE(p, (SpacetimeParameters{ 1.5, 0.5, 0.0 }));
  EXPECT_NE(p, (SpacetimeParameters{ 1.0, 0.25, 0.0 }));
  EXPECT_NE(p, (SpacetimeParameters{ 1.0, 0.5, 0.25 }));
  EXPECT_EQ(SpacetimeParameters(), (SpacetimeParameters{ 0.0, 0.0, 0.0 }));
}

TEST(Spacetime, CompleteNullMomentumGivesHZero)
{
  KerrSpacetime st(1.0, 0.7);
  const Vec4 x(0, 5.0, 2.0, 1.0);
  const Vec4 p = completeNullMomentum(st, x, Vec4(-1, 0, 0.3, 0.1), Vec4(0, 1, 0, 0), false);
  EXPECT_NEAR(st.value(x, p), 0.0, 1e-15);
  EXPECT_EQ(p[0], -1.0);
  EXPECT_EQ(p[2], 0.3);
}
