// KerrMinoPropagator: Kerr rays in Mino time, w = 1/r, u = cos θ. The truth here is independent of
// the propagator: the Boyer–Lindquist metric and constants written out from physics.md, Bardeen's
// photon-orbit formulas, and Gauss–Legendre 6 on the Kerr–Schild Hamiltonian.
#include "KerrMinoPropagator.h"
#include "RayFixtures.h"
#include "RayTracer.h"
#include "Spacetime.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

using namespace asrt;

namespace
{
/// A Boyer–Lindquist event and covector: (t, r, θ, φ) and (p_t, p_r, p_θ, p_φ).
struct BLPoint
{
  double t, r, theta, phi;
  Vec4 p;
};

/// Inverse Boyer–Lindquist metric (t, r, θ, φ), written out from the textbook line element.
Mat4 blInverseMetric(double M, double a, double r, double theta)
{
  const double s2 = std::sin(theta) * std::sin(theta), c2 = 1.0 - s2;
  const double Sigma = r * r + a * a * c2, Delta = r * r - 2.0 * M * r + a * a;
  Mat4 g = Mat4::Zero();
  g(0, 0) = -((r * r + a * a) * (r * r + a * a) - a * a * Delta * s2) / (Sigma * Delta);
  g(0, 3) = g(3, 0) = -2.0 * M * a * r / (Sigma * Delta);
  g(3, 3) = (Delta - a * a * s2) / (Sigma * Delta * s2);
  g(1, 1) = Delta / Sigma;
  g(2, 2) = 1.0 / Sigma;
  return g;
}

/// ∂(t, x, y, z)_KS / ∂(t, r, θ, φ)_BL for the ingoing Kerr–Schild map
/// x + iy = (r + ia) sin θ e^{iφ_KS}, dt_KS = dt + 2Mr/Δ dr, dφ_KS = dφ + a/Δ dr
/// (`flip` = −1 uses x + iy = (r − ia) sin θ e^{iφ_KS} instead, which must fail).
Mat4 blToKsJacobian(double M, double a, double r, double theta, double phiKS, double flip = 1.0)
{
  const double Delta = r * r - 2.0 * M * r + a * a;
  const double st = std::sin(theta), ct = std::cos(theta);
  const double cp = std::cos(phiKS), sp = std::sin(phiKS);
  const double A = flip * a;
  // x = sin θ (r cos φ − A sin φ), y = sin θ (r sin φ + A cos φ), z = r cos θ.
  const Vec3 dr(st * cp, st * sp, ct);
  const Vec3 dth(ct * (r * cp - A * sp), ct * (r * sp + A * cp), -r * st);
  const Vec3 dph(-st * (r * sp + A * cp), st * (r * cp - A * sp), 0.0);
  Mat4 J = Mat4::Zero();
  J(0, 0) = 1.0;
  J(0, 1) = 2.0 * M * r / Delta;
  J.block<3, 1>(1, 1) = dr + (a / Delta) * dph;
  J.block<3, 1>(1, 2) = dth;
  J.block<3, 1>(1, 3) = dph;
  return J;
}

/// The Kerr–Schild Cartesian point of a Boyer–Lindquist covector given at Kerr–Schild (t, φ).
PhasePoint ksFromBL(double M, double a, const BLPoint& q)
{
  const double st = std::sin(q.theta), ct = std::cos(q.theta);
  const double cp = std::cos(q.phi), sp = std::sin(q.phi);
  PhasePoint z;
  z.x = Vec4(q.t, st * (q.r * cp - a * sp), st * (q.r * sp + a * cp), q.r * ct);
  // p_BL = Jᵀ p_KS.
  const Mat4 J = blToKsJacobian(M, a, q.r, q.theta, q.phi);
  z.p = J.transpose().fullPivLu().solve(q.p);
  return z;
}

/// Boyer–Lindquist r, θ, Kerr–Schild φ and the covariant p_θ of a Kerr–Schild Cartesian point.
void blAngles(const KerrSpacetime& st, const PhasePoint& z, double& r, double& theta, double& phiKS,
              double& pTheta)
{
  const double a = st.spin();
  r = st.radius(z.x);
  theta = std::acos(std::clamp(z.x[3] / r, -1.0, 1.0));
  phiKS = std::atan2(r * z.x[2] - a * z.x[1], r * z.x[1] + a * z.x[2]);
  const Mat4 J = blToKsJacobian(st.mass(), a, r, theta, phiKS);
  pTheta = J.col(2).dot(z.p);
}

/// Carter's constant from physics.md: Q = p_θ² + cos²θ (L²/sin²θ − a²E²).
double carterQ(const KerrSpacetime& st, const PhasePoint& z)
{
  double r, theta, phi, pTheta;
  blAngles(st, z, r, theta, phi, pTheta);
  const double E = -z.p[0], L = z.x[1] * z.p[2] - z.x[2] * z.p[1], a = st.spin();
  const double c = std::cos(theta), s = std::sin(theta);
  return pTheta * pTheta + c * c * (L * L / (s * s) - a * a * E * E);
}

/// A null ray at Boyer–Lindquist (r, θ) with E = 1, angular momentum L and Carter constant Q,
/// moving with the given signs of p_r and p_θ (R(r) and Θ(θ) from physics.md).
PhasePoint kerrRay(const KerrSpacetime& st, double r, double theta, double L, double Q, double sr,
                   double sth)
{
  const double M = st.mass(), a = st.spin(), E = 1.0;
  const double Delta = r * r - 2.0 * M * r + a * a;
  const double X = E * (r * r + a * a) - a * L;
  const double R = X * X - Delta * (Q + (L - a * E) * (L - a * E));
  const double c = std::cos(theta), s = std::sin(theta);
  const double Theta = Q - c * c * (L * L / (s * s) - a * a * E * E);
  if (R < -1e-12 * X * X || Theta < -1e-12 * (Q + L * L))
    throw std::invalid_argument("kerrRay: no real ray with these constants here");
  BLPoint q{ 0.0, r, theta, 0.3, Vec4::Zero() };
  q.p =
    Vec4(-E, sr * std::sqrt(std::max(0.0, R)) / Delta, sth * std::sqrt(std::max(0.0, Theta)), L);
  return ksFromBL(M, a, q);
}

/// Bardeen's spherical photon orbits: ξ = L/E and η = Q/E² of the orbit at radius r.
void bardeen(double M, double a, double r, double& xi, double& eta)
{
  xi = (r * r * (3.0 * M - r) - a * a * (r + M)) / (a * (r - M));
  eta =
    r * r * r * (4.0 * a * a * M - r * (r - 3.0 * M) * (r - 3.0 * M)) / (a * a * (r - M) * (r - M));
}

/// Every segment of a traced ray.
std::vector<Segment> traceSegments(const Spacetime& st, Propagator& prop, const PhasePoint& z,
                                   const TraceOptions& opts, TraceResult& res)
{
  std::vector<Segment> segs;
  res = traceRay(st, prop, z, opts,
                 [&](const Segment& s)
                 {
                   segs.push_back(s);
                   return false;
                 });
  return segs;
}

/// The point of a traced ray where it first crosses radius R moving outwards (or inwards), by
/// bisection on the segment's Hermite interpolant.
bool crossing(const Spacetime& st, const std::vector<Segment>& segs, double R, bool outwards,
              Vec4& x)
{
  for (const Segment& s : segs)
  {
    const double r0 = st.radius(s.x0), r1 = st.radius(s.x1);
    if (outwards ? (r0 <= R && R < r1) : (r0 > R && R >= r1))
    {
      double lo = 0.0, hi = 1.0;
      for (int i = 0; i < 100; ++i)
      {
        const double mid = 0.5 * (lo + hi);
        ((st.radius(s.position(mid)) < R) == outwards ? lo : hi) = mid;
      }
      x = s.position(0.5 * (lo + hi));
      return true;
    }
  }
  return false;
}

double logSlope(const std::vector<double>& h, const std::vector<double>& e)
{
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(h.size());
  for (std::size_t i = 0; i < h.size(); ++i)
  {
    const double x = std::log(h[i]), y = std::log(e[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

std::unique_ptr<Propagator> make(const Spacetime& st, const std::string& method, double h)
{
  IntegratorConfig cfg;
  cfg.method = method;
  cfg.step = h;
  return makePropagator(st, cfg);
}

bool endedCleanly(const TraceResult& r)
{
  return r.termination != Termination::Running && r.termination != Termination::NumericalFailure &&
         r.final.x.allFinite() && r.final.p.allFinite() && std::isfinite(r.winding) &&
         std::isfinite(r.affineLength);
}
}

// 1. The coordinate map. Transforming the Boyer–Lindquist inverse metric with the ingoing
// Kerr–Schild Jacobian must give KerrSpacetime's g^{μν} = η^{μν} − f l^μ l^ν; the other sign of ia
// does not.
TEST(KerrMinoMap, BoyerLindquistMetricTransformsToKerrSchild)
{
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  double worst = 0.0, worstFlipped = 1e300;
  for (double a : { -0.9, 0.3, 0.999, 1.0 })
  {
    const KerrSpacetime st(1.0, a);
    for (int i = 0; i < 50; ++i)
    {
      const double r = st.outerHorizon() + 0.05 + 30.0 * U(gen);
      const double theta = 0.05 + (M_PI - 0.1) * U(gen), phi = 2.0 * M_PI * U(gen);
      const Mat4 gBL = blInverseMetric(1.0, a, r, theta);
      const PhasePoint z = ksFromBL(1.0, a, { 0.0, r, theta, phi, Vec4(-1, 0, 0, 0) });
      const Mat4 gKS = st.inverseMetric(z.x);
      const Mat4 J = blToKsJacobian(1.0, a, r, theta, phi);
      worst = std::max(worst, (J * gBL * J.transpose() - gKS).norm() / gKS.norm());
      if (a != 0.0)
      {
        const Mat4 Jf = blToKsJacobian(1.0, a, r, theta, phi, -1.0);
        worstFlipped =
          std::min(worstFlipped, (Jf * gBL * Jf.transpose() - gKS).norm() / gKS.norm());
      }
      // The KS radius of the mapped point is the Boyer–Lindquist r.
      EXPECT_NEAR(st.radius(z.x), r, 1e-13 * r);
    }
  }
  std::printf("[ map ] worst relative mismatch %.2e; with x + iy = (r - ia)... %.2e\n", worst,
              worstFlipped);
  EXPECT_LT(worst, 1e-13);
  EXPECT_GT(worstFlipped, 1e-3);
}

// Null Boyer–Lindquist covectors map to H = 0 in Kerr–Schild, and the propagator reads back the
// E, L, Q they were built from and hands back the state it was given.
TEST(KerrMinoMap, ConstantsAndRoundTrip)
{
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  double worstH = 0, worstConst = 0, worstTrip = 0;
  for (double a : { -0.7, 0.0, 0.5, 0.999, 1.0 })
  {
    const KerrSpacetime st(1.0, a);
    KerrMinoPropagator prop(st, 4, 0.01);
    for (int i = 0; i < 40; ++i)
    {
      const double r = st.outerHorizon() + 0.3 + 40.0 * U(gen);
      const double theta = 0.1 + (M_PI - 0.2) * U(gen);
      const double L = 8.0 * (U(gen) - 0.5), pTheta = 6.0 * (U(gen) - 0.5);
      const double c = std::cos(theta), s = std::sin(theta);
      const double Q = pTheta * pTheta + c * c * (L * L / (s * s) - a * a);
      const double Delta = r * r - 2.0 * r + a * a, X = r * r + a * a - a * L;
      const double R = X * X - Delta * (Q + (L - a) * (L - a));
      if (R < 1e-3 * X * X)
        continue; // near a radial turning point the round trip is ill-conditioned, skip
      const double sr = U(gen) < 0.5 ? -1.0 : 1.0;
      const BLPoint q{ 1.5, r, theta, 2.0 * M_PI * U(gen),
                       Vec4(-1.0, sr * std::sqrt(R) / Delta, pTheta, L) };
      const PhasePoint z = ksFromBL(1.0, a, q);
      worstH = std::max(worstH, std::abs(st.value(z.x, z.p)) / z.p.squaredNorm());
      prop.start(z);
      worstConst = std::max({ worstConst, std::abs(prop.energy() - 1.0),
                              std::abs(prop.angularMomentum() - L) / (1.0 + std::abs(L)),
                              std::abs(prop.carterConstant() - Q) / (1.0 + std::abs(Q)) });
      const PhasePoint back = prop.state();
      worstTrip = std::max(
        { worstTrip, (back.x - z.x).norm() / z.x.norm(), (back.p - z.p).norm() / z.p.norm() });
    }
  }
  std::printf("[ map ] |H|/|p|^2 %.2e, constants %.2e, round trip %.2e\n", worstH, worstConst,
              worstTrip);
  EXPECT_LT(worstH, 1e-13);
  EXPECT_LT(worstConst, 1e-12);
  EXPECT_LT(worstTrip, 1e-12);
}

// 2. On a spherical photon orbit of a = 0.9 (Bardeen), E, L and Q read back from the Cartesian
// segment ends stay exact while the ray winds around the hole, and H stays at round-off.
TEST(KerrMinoConservation, SphericalPhotonOrbitKeepsELQExact)
{
  const double a = 0.9, rs = 2.4;
  const KerrSpacetime st(1.0, a);
  double xi, eta;
  bardeen(1.0, a, rs, xi, eta);
  ASSERT_GT(eta, 0.0);
  const PhasePoint z = kerrRay(st, rs, 0.5 * M_PI, xi, eta, 1.0, 1.0);
  KerrMinoPropagator prop(st, 4, 0.01);
  prop.start(z);
  Segment seg;
  double dE = 0, dL = 0, dQ = 0, maxH = 0, winding = 0, turnsOnOrbit = 0;
  // Round-off grows on the unstable orbit until the ray leaves it after some 20 turns.
  for (int i = 0; i < 100000 && st.radius(prop.state().x) < 10.0; ++i)
  {
    ASSERT_TRUE(prop.advance(seg));
    const PhasePoint e{ seg.x1, seg.p1 };
    dE = std::max(dE, std::abs(-e.p[0] - 1.0));
    dL = std::max(dL, std::abs(e.x[1] * e.p[2] - e.x[2] * e.p[1] - xi) / std::abs(xi));
    dQ = std::max(dQ, std::abs(carterQ(st, e) - eta) / eta);
    maxH = std::max(maxH, std::abs(st.value(e.x, e.p)) / e.p.squaredNorm());
    const Vec3 p0 = seg.x0.tail<3>(), p1 = seg.x1.tail<3>();
    winding += std::atan2(p0.cross(p1).norm(), p0.dot(p1));
    if (std::abs(st.radius(seg.x1) - rs) < 1e-3)
      turnsOnOrbit = winding / (2 * M_PI);
  }
  std::printf("[ cons ] %.1f turns (%.1f within 1e-3 M of r_s), dE %.2e dL %.2e dQ %.2e |H| %.2e\n",
              winding / (2 * M_PI), turnsOnOrbit, dE, dL, dQ, maxH);
  EXPECT_GT(turnsOnOrbit, 3.0);
  EXPECT_GT(winding, 6.0 * M_PI);
  EXPECT_LT(dE, 1e-14);
  EXPECT_LT(dL, 1e-12);
  EXPECT_LT(dQ, 1e-12);
  EXPECT_LT(maxH, 1e-13);
}

// 3. Convergence order: the Kerr–Schild position after a fixed Mino time against a 16× finer run.
TEST(KerrMinoConvergence, OrdersTwoAndFour)
{
  const double a = 0.9;
  const KerrSpacetime st(1.0, a);
  // Inclined ray from 6 M in through periapsis (~3.5 M), while it winds around the hole.
  const PhasePoint z = kerrRay(st, 6.0, 1.2, 2.0, 20.0, -1.0, -1.0);
  const double sigmaEnd = 0.6;
  auto run = [&](int order, double h)
  {
    KerrMinoPropagator prop(st, order, h);
    prop.start(z);
    Segment seg;
    const long n = std::lround(sigmaEnd / h);
    for (long i = 0; i < n; ++i)
    {
      EXPECT_TRUE(prop.advance(seg));
      // The relative-move bound must not cut these steps, or σ would not end at sigmaEnd.
      EXPECT_NEAR((seg.x1 - seg.x0).tail<3>().norm(), 0.0, 0.25 * seg.x0.tail<3>().norm());
    }
    return prop.state();
  };
  const PhasePoint ref = run(4, 0.02 / 64);
  for (int order : { 2, 4 })
  {
    std::vector<double> hs, errs;
    for (double h : { 0.02, 0.01, 0.005, 0.0025 })
    {
      const PhasePoint s = run(order, h);
      hs.push_back(h);
      errs.push_back((s.x - ref.x).norm());
    }
    const double slope = logSlope(hs, errs);
    std::printf("[ order %d ] errors %.2e %.2e %.2e %.2e slope %.3f\n", order, errs[0], errs[1],
                errs[2], errs[3], slope);
    EXPECT_NEAR(slope, order, 0.3);
  }
}

// 4. Against Gauss–Legendre 6 on the Kerr–Schild Hamiltonian (small steps, so that its segments
// interpolate to ~1e-10): rays deflected strongly by a = 0.9, compared at the end point of the Mino
// trace: beyond r = 1000 for the escaping ones, on the capture sphere (which the Mino step lands
// on) for the infalling one.
TEST(KerrMinoCrossCheck, AgreesWithGaussLegendre6)
{
  const double a = 0.9;
  const KerrSpacetime st(1.0, a);
  struct Case
  {
    double r, theta, L, Q, sr, sth;
    bool escapes;
  };
  const Case cases[] = { { 30.0, 1.1, 3.5, 20.0, -1.0, 1.0, true },
                         { 30.0, 1.3, -7.5, 15.0, -1.0, -1.0, true },
                         { 30.0, 1.3, 1.0, 12.0, -1.0, 1.0, false },
                         { 25.0, 0.9, 0.0, 25.0, -1.0, -1.0, true } };
  for (const Case& c : cases)
  {
    const PhasePoint z = kerrRay(st, c.r, c.theta, c.L, c.Q, c.sr, c.sth);
    TraceOptions opts;
    opts.escapeRadius = 1000.0;
    opts.horizonEpsilon = 0.5; // capture at 1.5 r+: both methods are accurate there
    TraceResult rg, rm;
    auto mino = make(st, "KerrMino4", 0.002);
    traceSegments(st, *mino, z, opts, rm);
    ASSERT_EQ(rm.termination, c.escapes ? Termination::Escaped : Termination::Captured)
      << c.L << " " << toString(rm.termination);
    const Vec4 xm = rm.final.x;
    const double r = st.radius(xm);
    // GL6 runs on past Mino's end point and is interpolated at the same radius and direction.
    opts.escapeRadius = 2.0 * r;
    opts.horizonEpsilon = 0.4;
    auto gl = make(st, "GaussLegendre6", 0.005);
    const std::vector<Segment> sg = traceSegments(st, *gl, z, opts, rg);
    ASSERT_NE(rg.termination, Termination::NumericalFailure);
    Vec4 xg;
    ASSERT_TRUE(crossing(st, sg, r, c.escapes, xg));
    const double dTheta = std::acos(xg[3] / r) - std::acos(xm[3] / r);
    const double dPhi =
      std::remainder(std::atan2(xg[2], xg[1]) - std::atan2(xm[2], xm[1]), 2 * M_PI);
    const double dT = (xg[0] - xm[0]) / r;
    std::printf("[ vs GL6 ] L=%5.1f Q=%5.1f %s at r=%.1f: dtheta %.2e dphi %.2e dt/r %.2e, "
                "evaluations %ld vs %ld\n",
                c.L, c.Q, toString(rm.termination), r, dTheta, dPhi, dT, rm.evaluations,
                rg.evaluations);
    EXPECT_LT(std::abs(dTheta), 1e-7);
    EXPECT_LT(std::abs(dPhi), 1e-7);
    EXPECT_LT(std::abs(dT), 1e-7);
  }
}

// 5. The prograde equatorial circular photon orbit of a = 0.9, r_ph = 2M{1 + cos[(2/3) arccos(−a)]}
// (physics.md table: 1.5578546274233827 M), with L/E = ξ(r_ph) from Bardeen's formula, for which
// η(r_ph) = 0 independently confirms the radius. The ray stays on it (the orbit is unstable:
// round-off grows by e^{2π·γ} per turn) and winds at the orbit's angular velocity dφ/dt = 1/(a +
// r^{3/2}/√M).
TEST(KerrMinoPhotonOrbit, ProgradeEquatorialCircularOrbit)
{
  const double a = 0.9;
  const KerrSpacetime st(1.0, a);
  const double rph = 2.0 * (1.0 + std::cos(2.0 / 3.0 * std::acos(-a)));
  ASSERT_NEAR(rph, 1.5578546274233827, 1e-14);
  double xi, eta;
  bardeen(1.0, a, rph, xi, eta);
  EXPECT_NEAR(eta, 0.0, 1e-12);
  const double omega = 1.0 / (a + std::pow(rph, 1.5));
  const PhasePoint z = kerrRay(st, rph, 0.5 * M_PI, xi, 0.0, 1.0, 1.0);
  for (int order : { 2, 4 })
  {
    KerrMinoPropagator prop(st, order, 0.01);
    prop.start(z);
    Segment seg;
    double winding = 0, maxZ = 0, rate = 0;
    for (;;)
    {
      const double dr = std::abs(st.radius(prop.state().x) - rph) / rph;
      if (dr < 1e-8 && winding > 0.0)
        rate = winding / (prop.state().x[0] - z.x[0]); // before the drift off the orbit shows
      if (dr > 1e-6)
        break;
      ASSERT_TRUE(prop.advance(seg));
      const Vec3 p0 = seg.x0.tail<3>(), p1 = seg.x1.tail<3>();
      winding += std::atan2(p0.cross(p1).norm(), p0.dot(p1));
      maxZ = std::max(maxZ, std::abs(seg.x1[3]));
    }
    std::printf("[ photon orbit ] order %d: %.2f turns within 1e-6 r_ph, dphi/dt %.12f vs %.12f, "
                "|z| <= %.1e\n",
                order, winding / (2 * M_PI), rate, omega, maxZ);
    // The orbit is a double root of R: rounding the constants by ε starts the ray off it at √ε,
    // and that grows by ~e^11 a turn. Two turns to reach 1e-6. While it is within 1e-8 the rate
    // can differ from Ω by ~(dΩ/dr) δr, a few 1e-8 relative, whatever the order.
    EXPECT_GT(winding, 4.0 * M_PI) << order;
    EXPECT_NEAR(rate, omega, 5e-8 * omega) << order;
    EXPECT_LT(maxZ, 1e-15); // the equatorial ray stays in the plane (z = r cos(π/2) to start)
  }
}

// 6. Extremes: near-extremal and extremal spin, camera rays traced backwards (E < 0, towards the
// past horizon), rays through the pole and in the equatorial plane, and a ray from a million M.
TEST(KerrMinoExtremes, NearExtremalAndExtremalRaysEndCleanly)
{
  for (double a : { 0.999, 1.0, -1.0 })
  {
    const KerrSpacetime st(1.0, a);
    int escaped = 0, captured = 0;
    for (double sign : { 1.0, -1.0 })
    {
      for (double b = -9.0; b <= 9.0; b += 0.75)
      {
        PhasePoint z;
        z.x = Vec4(0.0, 50.0, 0.0, 1.0);
        // sign = −1: a camera ray traced backwards in time (E = −1), heading for the past horizon.
        z.p = completeNullMomentum(st, z.x, Vec4(-sign, 0.0, sign * b / 50.0, 0.01 * sign),
                                   Vec4(0, 1, 0, 0), false);
        ASSERT_LT(z.p[1], 0.0); // heading inwards either way
        auto prop = make(st, "KerrMino4", 0.01);
        TraceOptions opts;
        opts.escapeRadius = 60.0;
        double maxH = 0.0; // relative to |p|²: camera rays reach |p| ~ 1/Δ near the past horizon
        const TraceResult r =
          traceRay(st, *prop, z, opts,
                   [&](const Segment& s)
                   {
                     maxH = std::max(maxH, std::abs(st.value(s.x1, s.p1)) / s.p1.squaredNorm());
                     return false;
                   });
        EXPECT_TRUE(endedCleanly(r)) << "a=" << a << " b=" << b << " " << toString(r.termination);
        EXPECT_LT(maxH, 1e-13) << "a=" << a << " b=" << b;
        if (r.termination == Termination::Captured)
        {
          const double rEnd = st.radius(r.final.x);
          EXPECT_LE(rEnd, st.outerHorizon() * (1.0 + opts.horizonEpsilon));
          EXPECT_GT(rEnd, st.outerHorizon() * (1.0 + opts.horizonEpsilon) * (1.0 - 1e-8));
        }
        escaped += r.termination == Termination::Escaped;
        captured += r.termination == Termination::Captured;
      }
    }
    std::printf("[ extremes ] a=%+.3f: %d escaped, %d captured\n", a, escaped, captured);
    EXPECT_GT(escaped, 0);
    EXPECT_GT(captured, 0);
  }
}

TEST(KerrMinoExtremes, PolarAndEquatorialRaysAgreeWithGaussLegendre6)
{
  const KerrSpacetime st(1.0, 0.9);
  TraceOptions opts;
  opts.escapeRadius = 500.0;
  std::vector<PhasePoint> rays;
  // Exactly through the axis: in the x–z plane with p_y = 0, so L = 0 exactly.
  rays.push_back({ Vec4(0, 20.0, 0.0, -3.0),
                   completeNullMomentum(st, Vec4(0, 20.0, 0.0, -3.0), Vec4(-1, 0, 0, 0.35),
                                        Vec4(1, 0, 0, 0), false) });
  // Nearly through the axis: L = 1e-3, the azimuth swings by ≈ π in an unresolved Mino time.
  rays.push_back({ Vec4(0, 20.0, 0.0, -3.0),
                   completeNullMomentum(st, Vec4(0, 20.0, 0.0, -3.0), Vec4(-1, 0, 5e-5, 0.35),
                                        Vec4(1, 0, 0, 0), false) });
  // Exactly in the equatorial plane, and starting on the axis.
  rays.push_back({ Vec4(0, 20.0, 0.0, 0.0),
                   completeNullMomentum(st, Vec4(0, 20.0, 0.0, 0.0), Vec4(-1, 0, 0.4, 0),
                                        Vec4(1, 0, 0, 0), false) });
  rays.push_back({ Vec4(0, 0.0, 0.0, 20.0),
                   completeNullMomentum(st, Vec4(0, 0.0, 0.0, 20.0), Vec4(-1, 0.3, 0.1, 0),
                                        Vec4(0, 0, 0, 1), false) });
  for (std::size_t i = 0; i < rays.size(); ++i)
  {
    TraceResult rg, rm;
    auto mino = make(st, "KerrMino4", 0.002);
    traceSegments(st, *mino, rays[i], opts, rm);
    ASSERT_EQ(rm.termination, Termination::Escaped) << i;
    const double r = st.radius(rm.final.x);
    TraceOptions far = opts;
    far.escapeRadius = 2.0 * r;
    auto gl = make(st, "GaussLegendre6", 0.005);
    const std::vector<Segment> sg = traceSegments(st, *gl, rays[i], far, rg);
    ASSERT_EQ(rg.termination, Termination::Escaped) << i;
    Vec4 xg;
    ASSERT_TRUE(crossing(st, sg, r, true, xg));
    const double d = (xg - rm.final.x).tail<3>().norm() / r;
    std::printf("[ special ray %zu ] angular mismatch at r = %.0f: %.2e, |H| <= %.1e\n", i, r, d,
                rm.maxAbsH);
    EXPECT_LT(d, 1e-7) << i;
    if (i == 2)
    {
      EXPECT_EQ(rm.final.x[3], 0.0); // the equatorial ray never leaves the plane
    }
  }
}

TEST(KerrMinoExtremes, RayFromAMillionMEscapes)
{
  const KerrSpacetime st(1.0, 0.9);
  for (bool outwards : { true, false })
  {
    PhasePoint z;
    z.x = Vec4(0.0, 1e6, 0.0, 0.0);
    z.p =
      completeNullMomentum(st, z.x, Vec4(-1.0, 0.0, 20.0 / 1e6, 1e-6), Vec4(0, 1, 0, 0), outwards);
    auto prop = make(st, "KerrMino4", 0.01);
    TraceOptions opts;
    opts.escapeRadius = 2e6;
    const TraceResult r = traceRay(st, *prop, z, opts);
    EXPECT_EQ(r.termination, Termination::Escaped) << outwards;
    EXPECT_TRUE(endedCleanly(r));
    EXPECT_LT(r.steps, 1000) << outwards;
    // Straight-line length to the escape sphere plus a few M of delay.
    const double rEnd = r.final.x.tail<3>().norm();
    const double straight = outwards ? rEnd - 1e6 : 1e6 + rEnd;
    std::printf("[ far ] %s: %ld steps, lambda %.6e vs straight %.6e\n", outwards ? "out" : "in",
                r.steps, r.affineLength, straight);
    EXPECT_NEAR(r.affineLength, straight, 1e-4 * straight);
  }
}

// 6b. The far field (FarField, as a scene sets it: objects within 15 M, a sky sphere at 500 M). A
// fan of rays from the Kerr disk scene's eye, traced with it and without it: merging changes no
// step, so the segments that may meet an object (here the disk's plane within 15 M, and the sky
// sphere) are the same bit for bit, the far-field segments lie outside 15 M and inside 500 M, and
// there are far fewer segments. Only the winding, a sum over chords, moves a little.
TEST(KerrMinoFarField, MergesStepsOutsideTheObjects)
{
  const KerrSpacetime st(1.0, 0.9);
  const double objectRadius = 15.0, sky = 500.0;
  FarField farField;
  farField.objectRadius = objectRadius;
  farField.skyRadii = { sky };
  const Vec4 eye(0.0, 0.0, -38.63703305156273, 10.35276180410083);
  const Vec3 in = -eye.tail<3>().normalized(), e1 = Vec3(1, 0, 0), e2 = in.cross(e1);
  // Every segment up to the first one that crosses the sky sphere outwards.
  auto trace = [&](const PhasePoint& z, bool far, TraceResult& res)
  {
    auto prop = make(st, "KerrMino4", 0.05);
    TraceOptions opts;
    opts.escapeRadius = 1000.0;
    if (far)
      opts.farField = farField;
    std::vector<Segment> segs;
    res = traceRay(st, *prop, z, opts,
                   [&](const Segment& s)
                   {
                     segs.push_back(s);
                     return s.x1.tail<3>().norm() >= sky;
                   });
    return segs;
  };
  auto mayMeetAnObject = [&](const Segment& s)
  {
    const double r0 = s.x0.tail<3>().norm(), r1 = s.x1.tail<3>().norm();
    return (s.x0[3] * s.x1[3] <= 0.0 && std::min(r0, r1) < objectRadius) || r1 >= sky;
  };
  int rays = 0, sky0 = 0, farIn = 0, farOut = 0, compared = 0;
  double segmentsWith = 0, segmentsWithout = 0, worstWinding = 0;
  for (int j = -4; j <= 4; ++j)
  {
    for (int i = -6; i <= 6; ++i)
    {
      const Vec3 n = (in + 0.07 * i * e1 + 0.07 * j * e2).normalized();
      PhasePoint z;
      z.x = eye;
      z.p = completeNullMomentum(st, eye, Vec4(-1, 0, 0, 0), Vec4(0, n[0], n[1], n[2]), true);
      TraceResult rw, ro;
      const std::vector<Segment> with = trace(z, true, rw), without = trace(z, false, ro);
      ++rays;
      EXPECT_EQ(rw.termination, ro.termination) << i << "," << j;
      EXPECT_EQ(rw.final.x, ro.final.x) << i << "," << j;
      worstWinding = std::max(worstWinding, std::abs(rw.winding - ro.winding));
      sky0 += without.back().x1.tail<3>().norm() >= sky;
      std::vector<const Segment*> a, b;
      for (const Segment& s : with)
      {
        if (s.farField)
        {
          const double r0 = s.x0.tail<3>().norm(), r1 = s.x1.tail<3>().norm();
          EXPECT_GT(std::min(r0, r1), objectRadius);
          EXPECT_LT(std::max(r0, r1), sky);
          (r1 > r0 ? farOut : farIn) += 1;
        }
        else if (mayMeetAnObject(s))
          a.push_back(&s);
      }
      for (const Segment& s : without)
      {
        if (mayMeetAnObject(s))
          b.push_back(&s);
      }
      ASSERT_EQ(a.size(), b.size()) << i << "," << j;
      for (std::size_t k = 0; k < a.size(); ++k, ++compared)
      {
        EXPECT_EQ(a[k]->x0, b[k]->x0) << i << "," << j;
        EXPECT_EQ(a[k]->x1, b[k]->x1) << i << "," << j;
        EXPECT_EQ(a[k]->d0, b[k]->d0) << i << "," << j;
        EXPECT_EQ(a[k]->d1, b[k]->d1) << i << "," << j;
        EXPECT_EQ(a[k]->lambda1, b[k]->lambda1) << i << "," << j;
      }
      segmentsWith += static_cast<double>(with.size());
      segmentsWithout += static_cast<double>(without.size());
    }
  }
  std::printf("[ far field ] %d rays, %d to the sky, %d far segments in, %d out, %d segments that "
              "may meet an object compared; %.0f segments against %.0f; winding %.1e apart\n",
              rays, sky0, farIn, farOut, compared, segmentsWith, segmentsWithout, worstWinding);
  EXPECT_GT(sky0, 30);
  EXPECT_GT(farIn, 30);
  EXPECT_GT(farOut, 30);
  EXPECT_GT(compared, 80);
  EXPECT_LT(segmentsWith, 0.5 * segmentsWithout);
  // The winding sums the angles of the chords; for these non-planar rays a merged chord spans a
  // little less angle than the steps it replaces, by far less than a pixel (~1e-3 rad) here.
  EXPECT_LT(worstWinding, 1e-4);
}

// At a = 0 (Schwarzschild's own spacetime class) the deflection matches Darwin's exact formula.
TEST(KerrMinoSchwarzschild, DarwinDeflection)
{
  const SchwarzschildSpacetime st(1.0);
  for (double b : { 5.3, 10.0, 100.0 })
  {
    const PhasePoint z = asrt::testing::equatorialRay(st, 1000.0, b);
    const double truth = analytic::darwinDeflection(analytic::closestApproach(b, 1.0), 1.0);
    auto prop = make(st, "KerrMino4", 0.002);
    TraceOptions opts;
    opts.escapeRadius = 1000.0;
    const TraceResult r = traceRay(st, *prop, z, opts);
    ASSERT_EQ(r.termination, Termination::Escaped) << b;
    const double err = asrt::testing::measuredDeflection(r, z, b, 1.0) - truth;
    std::printf("[ Darwin ] b = %5.1f: deflection %.12f, error %.1e, %ld steps\n", b, truth, err,
                r.steps);
    EXPECT_LT(std::abs(err), 3e-8) << b; // radians, at h = 0.002
  }
}

// 7. Only Kerr and Schwarzschild are modelled; orders 2 and 4; positive steps.
TEST(KerrMinoConfig, RefusesWhatItCannotModel)
{
  const ReissnerNordstromSpacetime rn(1.0, 0.5);
  const MinkowskiSpacetime flat;
  const KerrSpacetime kerr(1.0, 0.5);
  const SchwarzschildSpacetime schw(1.0);
  EXPECT_THROW(KerrMinoPropagator(rn, 4, 0.01), InvalidParameter);
  EXPECT_THROW(KerrMinoPropagator(flat, 4, 0.01), InvalidParameter);
  EXPECT_THROW(KerrMinoPropagator(kerr, 6, 0.01), InvalidParameter);
  EXPECT_THROW(KerrMinoPropagator(kerr, 4, 0.0), InvalidParameter);
  EXPECT_THROW(KerrMinoPropagator(kerr, 4, NAN), InvalidParameter);
  EXPECT_NO_THROW(KerrMinoPropagator(schw, 2, 0.01));
  IntegratorConfig cfg;
  cfg.method = "KerrMino4";
  EXPECT_THROW(makePropagator(rn, cfg), InvalidParameter);
  try
  {
    KerrMinoPropagator(rn, 4, 0.01);
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("Reissner"), std::string::npos) << e.what();
  }
}

TEST(KerrConservation, GaussLegendreKeepsCarterQBoundedWhereRK4Drifts)
{
  // A bound, inclined massive orbit (H = −½) around a = 0.9, followed for ~300 revolutions with
  // the general methods on the Kerr–Schild Hamiltonian. Carter's Q for unit rest mass is
  // p_θ² + cos²θ (a²(1 − E²) + L²/sin²θ); E and L_z are the other two invariants.
  const double M = 1.0, a = 0.9, E = 0.965, L = 3.0, Q = 5.3, r0 = 10.0, th0 = M_PI / 3;
  const KerrSpacetime st(M, a);
  const double Delta = r0 * r0 - 2 * M * r0 + a * a;
  const double X = E * (r0 * r0 + a * a) - a * L;
  const double R = X * X - Delta * (r0 * r0 + (L - a * E) * (L - a * E) + Q);
  const double c = std::cos(th0), s = std::sin(th0);
  const double Theta = Q - c * c * (a * a * (1 - E * E) + L * L / (s * s));
  ASSERT_GT(R, 0.0);
  ASSERT_GT(Theta, 0.0);
  BLPoint q{ 0.0, r0, th0, 0.3, Vec4(-E, std::sqrt(R) / Delta, std::sqrt(Theta), L) };
  const PhasePoint z = ksFromBL(M, a, q);
  ASSERT_NEAR(st.value(z.x, z.p), -0.5, 1e-12);

  auto massiveQ = [&](const PhasePoint& p)
  {
    double r, theta, phi, pTheta;
    blAngles(st, p, r, theta, phi, pTheta);
    const double e = -p.p[0], l = p.x[1] * p.p[2] - p.x[2] * p.p[1];
    const double cc = std::cos(theta), ss = std::sin(theta);
    return pTheta * pTheta + cc * cc * (a * a * (1 - e * e) + l * l / (ss * ss));
  };
  EXPECT_NEAR(massiveQ(z), Q, 1e-10);

  struct Drift
  {
    double first = 0, last = 0;
  };
  auto run = [&](const char* method, double h)
  {
    IntegratorConfig cfg;
    cfg.method = method;
    cfg.step = h;
    cfg.timeTransform = false;
    auto prop = makePropagator(st, cfg);
    prop->start(z);
    const long steps = static_cast<long>(7.0e4 / h);
    Drift d;
    Segment seg;
    for (long k = 0; k < steps; ++k)
    {
      if (!prop->advance(seg))
      {
        ADD_FAILURE() << method << " failed at step " << k;
        break;
      }
      if (k % 10 != 0)
        continue;
      const double dQ = std::abs(massiveQ({ seg.x1, seg.p1 }) - Q) / Q;
      if (k < steps / 10)
        d.first = std::max(d.first, dQ);
      else if (k > 9 * steps / 10)
        d.last = std::max(d.last, dQ);
    }
    std::printf("%-16s h=%g: max |dQ|/Q first tenth %.2e, last tenth %.2e\n", method, h, d.first,
                d.last);
    return d;
  };
  const Drift gl = run("GaussLegendre4", 1.0);
  EXPECT_LT(gl.last, 2.0 * gl.first + 1e-12);
  const Drift rk = run("RK4", 1.0);
  EXPECT_GT(rk.last, 5.0 * rk.first);
  EXPECT_GT(rk.last, 10.0 * gl.last);
}
