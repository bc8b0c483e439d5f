// Long integrations: symplectic methods keep the Hamiltonian's error bounded, a non-symplectic one
// lets it drift. The orbit is a bound, eccentric Schwarzschild orbit followed for 1000 turns: the
// circular photon orbit is unstable (a perturbation grows e^{2π} per turn), so no double-precision
// ray stays near it for more than a handful of turns, whatever the integrator, while the bound
// orbit exercises the same Hamiltonian flow on the level set H = −½ for as long as we like.
#include "RayFixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

using namespace asrt;

namespace
{
struct Drift
{
  double firstTenth = 0; ///< max |H − H₀| over the first tenth of the run
  double lastTenth = 0;  ///< max |H − H₀| over the last tenth
  double maxLz = 0;      ///< max |L_z − L_z0|
  double maxE = 0;       ///< max |p_t − p_t0|
  double turns = 0;
};

/// Periapsis state of the Schwarzschild orbit with turning points r_p, r_a, at unit rest mass.
/// From E² = f(r)(1 + L²/r²) at both turning points: L² = (f_a − f_p)/(f_p/r_p² − f_a/r_a²).
PhasePoint boundOrbit(double rp, double ra, double& E, double& L)
{
  const double fp = 1 - 2 / rp, fa = 1 - 2 / ra;
  L = std::sqrt((fa - fp) / (fp / (rp * rp) - fa / (ra * ra)));
  E = std::sqrt(fp * (1 + L * L / (rp * rp)));
  PhasePoint z;
  z.x = Vec4(0, rp, 0, 0);
  // At periapsis the Schwarzschild p_r vanishes; in the ingoing Kerr–Schild chart
  // p_r = p_r^S + 2ME/(r − 2M).
  z.p = Vec4(-E, 2 * E / (rp - 2), L / rp, 0);
  return z;
}

Drift run(const std::string& method, double h, double turns)
{
  const SchwarzschildSpacetime st(1.0);
  double E, L;
  const PhasePoint z = boundOrbit(8.0, 15.0, E, L);
  const double H0 = st.value(z.x, z.p);
  EXPECT_NEAR(H0, -0.5, 1e-14); // unit rest mass: the initial state is the orbit it claims
  IntegratorConfig cfg;
  cfg.method = method;
  cfg.step = h;
  cfg.timeTransform = false; // K = g(H − H₀) would be needed off the light cone
  cfg.relativeTolerance = 1e-9;
  cfg.absoluteTolerance = 1e-12;
  auto prop = makePropagator(st, cfg);
  prop->start(z);
  // Orbital period estimated from the Keplerian value; the loop counts turns itself.
  const double a = 11.5;
  const long steps = static_cast<long>(turns * 2 * M_PI * std::pow(a, 1.5) / h * 1.1);
  Drift d;
  Segment seg;
  double swept = 0;
  for (long k = 0; k < steps && swept < turns * 2 * M_PI; ++k)
  {
    if (!prop->advance(seg))
    {
      ADD_FAILURE() << method << " failed at step " << k;
      break;
    }
    const Vec3 u = seg.x0.tail<3>(), v = seg.x1.tail<3>();
    swept += std::atan2(u.cross(v).norm(), u.dot(v));
    const double dH = std::abs(st.value(seg.x1, seg.p1) - H0);
    if (swept < 0.1 * turns * 2 * M_PI)
      d.firstTenth = std::max(d.firstTenth, dH);
    if (swept > 0.9 * turns * 2 * M_PI)
      d.lastTenth = std::max(d.lastTenth, dH);
    d.maxLz = std::max(d.maxLz, std::abs(seg.x1[1] * seg.p1[2] - seg.x1[2] * seg.p1[1] - L));
    d.maxE = std::max(d.maxE, std::abs(seg.p1[0] + E));
  }
  d.turns = swept / (2 * M_PI);
  std::printf("%-18s h=%-5g turns=%-7.1f max|dH| first tenth %.2e, last tenth %.2e; "
              "max|dLz| %.2e\n",
              method.c_str(), h, d.turns, d.firstTenth, d.lastTenth, d.maxLz);
  return d;
}
}

TEST(Conservation, SymplecticMethodsKeepHBoundedOver1000Turns)
{
  for (const auto& [method, h] :
       std::vector<std::pair<std::string, double>>{ { "GaussLegendre4", 1.0 },
                                                    { "GaussLegendre6", 2.0 },
                                                    { "ImplicitMidpoint", 0.5 },
                                                    { "Tao4", 0.5 } })
  {
    const Drift d = run(method, h, 1000);
    EXPECT_GE(d.turns, 999.0) << method;
    // Bounded: the error in the last tenth is no larger than in the first (up to the
    // oscillation's own spread), not ten times larger as a linear drift would make it.
    EXPECT_LT(d.lastTenth, 2.0 * d.firstTenth + 1e-13) << method;
    EXPECT_LT(d.lastTenth, 1e-3) << method;
    if (method.rfind("Gauss", 0) == 0 || method == "ImplicitMidpoint")
    {
      // ∂H/∂t = 0, so p_t never changes. (Tao's coupling rotates p_t against its shadow copy,
      // so there E is only kept within the method's error.)
      EXPECT_LT(d.maxE, 1e-15) << method;
      // Gauss–Legendre collocation conserves quadratic invariants such as L_z = x p_y − y p_x
      // exactly, up to round-off.
      EXPECT_LT(d.maxLz, 1e-10) << method;
    }
  }
}

TEST(Conservation, RungeKuttaDriftsOnTheSameOrbit)
{
  // Same orbit and a step at which RK4's per-step error is comparable to Gauss–Legendre 4's: its
  // error grows steadily, the signature of a non-symplectic method.
  const Drift rk = run("RK4", 1.0, 1000);
  EXPECT_GT(rk.lastTenth, 5.0 * rk.firstTenth);
  EXPECT_GT(rk.maxLz, 1e-8); // L_z is not kept either
  const Drift gl = run("GaussLegendre4", 1.0, 1000);
  EXPECT_GT(rk.lastTenth, 10.0 * gl.lastTenth);
}
