#include "KerrMinoPropagator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

// Conventions, checked numerically (TestKerrMino.cxx, KerrMinoMap.*) against KerrSpacetime's
// l_μ = (1, (rx + ay)/(r² + a²), (ry − ax)/(r² + a²), z/r):
//   x + iy = (r + ia) sin θ e^{iφ},  z = r cos θ               (φ, t: ingoing Kerr–Schild)
//   dt = dt_BL + 2Mr/Δ dr,  dφ = dφ_BL + a/Δ dr.
// So ∂x^i/∂r = l_i, and in the spheroidal Kerr–Schild chart (t, r, θ, φ)
//   p_r = p_r^BL + (2Mr E − aL)/Δ,  p_θ and p_φ = L as in Boyer–Lindquist.
// The integrated φ and t are the Kerr–Schild ones: their rates are regular on the future horizon,
// whereas φ_BL and t_BL diverge there and would have to be cancelled against ∫a/Δ dr, ∫2Mr/Δ dr.

namespace asrt
{
namespace
{
using Consts = detail::KerrMinoRay;
using State = detail::KerrMinoState;

/// Radius (in M) beyond which the Mino step shrinks as 1/r, and the largest relative displacement
/// |Δx|/|x| a step may make (predicted from the velocity at its start).
constexpr double kFixedStepRadius = 10.0;
constexpr double kMaxRelativeMove = 0.25;
/// A trial step is rejected if any drift leaves w ∈ [w₀/4, ∞): never at or past infinity.
constexpr double kMinWRatio = 0.25;
/// The capture step ends with w in [w_c(1 + lo), w_c(1 + hi)]: just inside the capture sphere.
constexpr double kCaptureLow = 1e-12, kCaptureHigh = 1e-9;
/// Outside the scene's objects and beyond this many M, steps merge into far-field segments (an
/// outgoing ray may still turn back near the photon region).
constexpr double kFarFieldMinRadius = 4.0;
/// Largest angle about the hole one far-field segment may sweep: the tracer's per-segment winding
/// (the angle between the ends) is exact only below π.
constexpr double kMaxMergedSweep = 1.5;
const double kCosMaxMergedSweep = std::cos(kMaxMergedSweep);

/// X w² = E(1 + a²w²) − aLw², with X = E(r² + a²) − aL.
double xw(const Consts& c, double w)
{
  return c.E * (1.0 + c.a * c.a * w * w) - c.a * c.L * w * w;
}

/// w²Δ = 1 − 2Mw + a²w² = (1 − r₊w)(1 − r₋w).
double deltaW(const Consts& c, double w)
{
  return 1.0 - 2.0 * c.M * w + c.a * c.a * w * w;
}

/// R_w(w) = w⁴ R(r) = (Xw²)² − w²(1 − 2Mw + a²w²) K (physics.md).
double radialPotential(const Consts& c, double w)
{
  const double X = xw(c, w);
  return X * X - w * w * deltaW(c, w) * c.K;
}

/// τ log(1 + d/b)/d = ∫₀^τ ds/(b + d s/τ), also for d → 0 (two divisions: divisions dominate the
/// drift's cost).
double logQuotient(double tau, double b, double d)
{
  const double x = d / b;
  return std::abs(x) < 1e-8 ? tau * (1.0 - 0.5 * x) / b : tau * std::log1p(x) / d;
}

/// ∫₀^τ ds/(1 − k w) for w = w₀ + v s, exactly; NaN if the drift reaches the pole w = 1/k.
double poleIntegral(double k, double w0, double w1, double tau)
{
  const double b0 = 1.0 - k * w0, b1 = 1.0 - k * w1;
  if (!(b0 > 0.0 && b1 > 0.0))
    return std::numeric_limits<double>::quiet_NaN();
  return logQuotient(tau, b0, b1 - b0);
}

/// jd = ∫₀^τ ds/D̃ and jw = ∫₀^τ w ds/D̃ with D̃ = w²Δ = (1 − r₊w)(1 − r₋w), for w = w₀ + v s,
/// exactly: the horizon poles of the radial quadratures are integrated, not sampled. NaN if the
/// drift reaches a horizon.
void horizonIntegrals(const Consts& c, double w0, double v, double tau, double& jd, double& jw)
{
  const double w1 = w0 + v * tau;
  const double delta = c.rPlus - c.rMinus;
  // Partial fractions lose ~ε·(distance to the pole)/δ; below δ = 1e-7 M the double pole of the
  // extremal hole is closer to the truth than that (error ~ (δ/distance)²).
  if (delta > 1e-7 * c.M)
  {
    const double ip = poleIntegral(c.rPlus, w0, w1, tau);
    const double im = poleIntegral(c.rMinus, w0, w1, tau);
    jd = (c.rPlus * ip - c.rMinus * im) * c.invDelta;
    jw = (ip - im) * c.invDelta;
    return;
  }
  const double k = 0.5 * (c.rPlus + c.rMinus);
  const double b0 = 1.0 - k * w0, b1 = 1.0 - k * w1;
  if (!(b0 > 0.0 && b1 > 0.0))
  {
    jd = jw = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  jd = tau / (b0 * b1);
  jw = (jd - poleIntegral(k, w0, w1, tau)) / k; // w/b² = (1/b² − 1/b)/k, b = 1 − k w
}

/// Exact drift w += τ v_w, u += τ v_u, with the quadratures of φ, t and λ over it: exact but for
/// Ω, whose midpoint rule is symmetric in the interval, so that the Strang step stays symmetric and
/// Yoshida's composition keeps its order for the quadratures too.
bool drift(const Consts& c, State& s, double tau)
{
  const double a = c.a, a2 = a * a, E = c.E, L = c.L;
  const double w0 = s.w, u0 = s.u, vw = s.vw, vu = s.vu;
  const double w1 = w0 + tau * vw, u1 = u0 + tau * vu;
  const double um = 0.5 * (u0 + u1);
  const double intU2 = tau * (u0 * u0 + u0 * u1 + u1 * u1) / 3.0; // ∫u² dσ, exact
  const double intW2 = tau / (w0 * w1);                           // ∫dσ/w², exact

  // The Kerr–Schild rates (the Boyer–Lindquist ones of physics.md plus 2Mr/Δ and a/Δ times
  // dr/dσ = −v_w/w²), split into partial fractions in w at fixed v = v_w:
  //   dφ/dσ = −L + [L − a v + 2M(aE − L) w]/D̃ + L/(1 − u²),
  //   dt/dσ = E/w² + 2M(E − v)/w + [4M²(E − v) + 2Ma(a v − L) w]/D̃ + a²E u².
  // w is linear along the drift, so each term integrates in closed form: the radial quadratures
  // are exact, even over the long steps at large r and next to the horizon poles. (On the
  // infalling branch the pole terms cancel against each other at r₊; on the outgoing one the
  // divergence is real: the past horizon.)
  double jd, jw;
  horizonIntegrals(c, w0, vw, tau, jd, jw);
  const double j1 = logQuotient(tau, w0, w1 - w0); // ∫dσ/w
  const double dPhi = -L * tau + (L - a * vw) * jd + 2.0 * c.M * (a * E - L) * jw;
  const double dT = E * intW2 + 2.0 * c.M * (E - vw) * j1 +
                    2.0 * c.M * (2.0 * c.M * (E - vw) * jd + a * (a * vw - L) * jw) +
                    a2 * E * intU2;
  double dPolar;
  if (s.poleChart)
  {
    // Ω' = L a²E²u²/(Q + a²E²u²): see KerrMinoPropagator::start for the chart.
    const double q = c.a2E2 * um * um;
    const double den = c.Q + q;
    if (den > 0.0)
      dPolar = tau * L * q / den;
    else if (c.Q == 0.0)
      dPolar = tau * L; // equatorial: φ' = L, the atan2 term is constant
    else
      return false;
  }
  else
  {
    // ∫L/(1 − u²) dσ along the straight drift in u, exactly: L/v_u [atanh u₁ − atanh u₀].
    const double one = 1.0 - u0 * u1;
    if (!(one > 0.0))
      return false;
    const double y = tau * vu / one;
    dPolar = std::abs(y) < 1e-8 ? L * tau / one : L * std::atanh(y) / vu;
  }
  s.w = w1;
  s.u = u1;
  s.phiRadial += dPhi;
  s.polar += dPolar;
  s.t += dT;
  s.lambda += intW2 + a2 * intU2; // ∫Σ dσ
  return std::isfinite(s.phiRadial) && std::isfinite(s.t) && std::isfinite(s.polar) &&
         std::isfinite(s.lambda);
}

/// R_w'(w)/2 and U'(u)/2 at the current position: one force evaluation.
void force(const Consts& c, State& s)
{
  const double w = s.w, u = s.u, a = c.a, a2 = a * a;
  s.fw = 2.0 * xw(c, w) * w * (a2 * c.E - a * c.L) -
         0.5 * c.K * w * (2.0 - 6.0 * c.M * w + 4.0 * a2 * w * w);
  s.fu = (c.a2E2 - c.Q - c.L * c.L) * u - 2.0 * c.a2E2 * u * u * u;
}

/// Exact kick v_w += τ R_w'(w)/2, v_u += τ U'(u)/2, with the force at the current position.
void kick(State& s, double tau)
{
  s.vw += tau * s.fw;
  s.vu += tau * s.fu;
}

/// atan2(L u, v_u): the polar part of φ minus the smooth Ω. Where both vanish (on the axis with
/// L = 0, or on the equator of an equatorial ray) the ray leaves the axis, so v_u → −u·0⁺.
double azimuthTerm(const Consts& c, double u, double vu, double fallback)
{
  double y = c.L * u, x = vu;
  if (y == 0.0 && x == 0.0)
  {
    if (u == 0.0)
      return fallback;
    x = -u;
  }
  return std::atan2(y, x);
}

bool wantsPoleChart(const Consts& c, double u)
{
  return u * u > c.u2Pole;
}

double wrapAngle(double d)
{
  d = std::remainder(d, 2.0 * M_PI);
  return d <= -M_PI ? d + 2.0 * M_PI : d;
}
}

KerrMinoPropagator::KerrMinoPropagator(const Spacetime& st, int order, double step)
  : St(st)
  , Step(step / st.mass())
{
  if (st.kind() != SpacetimeKind::Kerr && st.kind() != SpacetimeKind::Schwarzschild)
  {
    std::ostringstream os;
    os << "method KerrMino models Kerr (or Schwarzschild) only, got " << st.name() << " spacetime";
    throw InvalidParameter(os.str());
  }
  if (order != 2 && order != 4)
  {
    std::ostringstream os;
    os << "KerrMino order must be 2 or 4, got " << order;
    throw InvalidParameter(os.str());
  }
  if (!(step > 0.0) || !std::isfinite(step))
  {
    std::ostringstream os;
    os << "KerrMino Mino-time step must be positive and finite, got " << step;
    throw InvalidParameter(os.str());
  }
  // The step in σ is h/M (see the class comment); it must stay a finite positive number.
  if (!(st.mass() > 0.0) || !(this->Step > 0.0) || !std::isfinite(this->Step))
  {
    std::ostringstream os;
    os << "KerrMino needs a mass for which the step h/M is finite and positive, got M = "
       << st.mass() << " with h = " << step;
    throw InvalidParameter(os.str());
  }
  // Kick-drift-kick Strang steps composed with the weights c_k, neighbouring kicks merged (kicks
  // are exact flows, so merging them changes nothing): K(c₁/2) D(c₁) K((c₁ + c₂)/2) D(c₂) …
  // D(c_m) K(c_m/2). The drifts are not merged: the quadratures are not exact flows, and the
  // composition keeps order 4 only as a composition of the symmetric Strang steps themselves.
  const std::vector<double>& c = yoshidaWeights(order);
  this->Drifts = c;
  this->Kicks.push_back(0.5 * c.front());
  for (std::size_t k = 0; k + 1 < c.size(); ++k)
    this->Kicks.push_back(0.5 * (c[k] + c[k + 1]));
  this->Kicks.push_back(0.5 * c.back());

  this->Ray.M = st.mass();
  this->Ray.a = st.spin();
  this->Ray.rPlus = st.outerHorizon();
  this->Ray.rMinus = st.innerHorizon();
  this->Ray.invDelta = 1.0 / (this->Ray.rPlus - this->Ray.rMinus);
}

void KerrMinoPropagator::setLimits(double escapeRadius, double captureRadius)
{
  // The relative-move bound already keeps every step short of w = 0; the escape sphere bounds an
  // outgoing far-field segment if no sky sphere is in the way.
  this->EscapeRadius = escapeRadius;
  this->CaptureRadius = std::isfinite(captureRadius) ? std::max(0.0, captureRadius) : 0.0;
}

void KerrMinoPropagator::start(const PhasePoint& z)
{
  this->Evaluations = 0;
  this->HasPending = false;
  this->S = State{};
  this->Current = z;
  this->CurrentRate = Vec4::Zero();
  this->Valid = false;
  Consts& c = this->Ray;
  const double a = c.a, M = c.M;
  const double r = this->St.radius(z.x);
  if (!z.x.allFinite() || !z.p.allFinite() || !(r > 0.0) || !std::isfinite(r))
    return;
  const double x = z.x[1], y = z.x[2], zz = z.x[3];
  const double px = z.p[1], py = z.p[2], pz = z.p[3];
  const double c2 = r * r + a * a, cc = std::sqrt(c2);
  const double u = std::clamp(zz / r, -1.0, 1.0);
  const double w = 1.0 / r;

  c.E = -z.p[0];
  c.L = x * py - y * px;
  c.a2E2 = a * a * c.E * c.E;
  const double P = x * px + y * py;
  // Spheroidal Kerr–Schild components: p_r = l_i p_i (∂x^i/∂r = l_i), v_u = −sin θ p_θ.
  const double pr = (r * P - a * c.L) / c2 + u * pz;
  const double vu = -u * P + r * (1.0 - u * u) * pz;
  // Q = p_θ² + L²/sin²θ − L² − a²E²u² = |V|² − a²E²u² with V = u√(r²+a²) p⊥ − r p_z x⊥/√(r²+a²):
  // a sum of squares, regular on the axis and free of cancellation far away.
  const double Vx = u * cc * px - r * pz * x / cc, Vy = u * cc * py - r * pz * y / cc;
  c.Q = Vx * Vx + Vy * Vy - c.a2E2 * u * u;
  c.K = c.Q + (c.L - a * c.E) * (c.L - a * c.E);
  // v_w = −w² dr/dσ with dr/dσ = Δ p_r^BL = Δ p_r − 2MrE + aL.
  const double vw = -deltaW(c, w) * pr + 2.0 * M * c.E * w - a * c.L * w * w;

  // Band of u² the ray can reach: U(y = u²) = Q + βy − αy² ≥ 0.
  const double alpha = c.a2E2, beta = alpha - c.Q - c.L * c.L;
  c.u2Low = 0.0;
  c.u2High = 1.0;
  if (c.L != 0.0)
  {
    if (alpha > 0.0)
    {
      const double disc = beta * beta + 4.0 * alpha * c.Q;
      if (disc >= 0.0)
      {
        const double sq = std::sqrt(disc);
        const double yPlus = beta >= 0.0 ? (beta + sq) / (2.0 * alpha) : 2.0 * c.Q / (sq - beta);
        if (yPlus > 0.0)
        {
          c.u2High = std::min(1.0, yPlus);
          if (c.Q < 0.0)
            c.u2Low = std::min(c.u2High, -c.Q / (alpha * yPlus));
        }
      }
    }
    else if (c.Q >= 0.0)
    {
      c.u2High = c.Q / (c.Q + c.L * c.L);
    }
  }
  else if (c.Q < 0.0 && alpha > 0.0)
  {
    c.u2Low = std::min(1.0, -c.Q / alpha); // L = 0: U = (1 − u²)(Q + a²E²u²)
  }
  // The azimuth φ_θ (φ' = L/(1 − u²)) is singular at the poles, where a ray with small L swings by
  // ≈ π in a Mino time ~L/(Q + a²E²) that no step resolves. On the ray,
  //   φ_θ = Ω + atan2(L u, v_u),  Ω' = L a²E²u²/(Q + a²E²u²),
  // and Ω is smooth wherever Q + a²E²u² > 0 (for a = 0 it is the node of the great circle): the
  // swing lives in the atan2 of the well-resolved v_u, and a ray through the axis (L = 0) flips by
  // exactly π. Away from the poles φ_θ itself is better: there the atan2 turns once per polar
  // oscillation whatever its amplitude, so the method's phase error in u would enter φ at full
  // size even for a ray a hair off the equator. The pole chart is used within 45° of the axis,
  // and for Q < 0 only past the middle between u² = −Q/(a²E²) (where Q + a²E²u² = 0) and 1.
  c.u2Pole = 0.5;
  if (c.Q < 0.0)
    c.u2Pole = alpha > 0.0 ? std::max(0.5, 0.5 * (1.0 - c.Q / alpha))
                           : std::numeric_limits<double>::infinity();

  double phi;
  if (x != 0.0 || y != 0.0)
    phi = std::atan2(r * y - a * x, r * x + a * y); // e^{iφ} ∝ (x + iy)(r − ia)
  else if (px != 0.0 || py != 0.0)
    phi = std::atan2(r * py - a * px, r * px + a * py); // on the axis: it leaves along p⊥
  else
    phi = 0.0;

  State& s = this->S;
  s.w = w;
  s.u = u;
  s.vw = vw;
  s.vu = vu;
  s.poleChart = wantsPoleChart(c, u);
  s.azimuth = s.poleChart ? azimuthTerm(c, u, vu, 0.0) : 0.0;
  s.polar = 0.0;
  s.phiRadial = phi - s.azimuth;
  s.t = z.x[0];
  s.lambda = 0.0;
  force(c, s);
  this->Evaluations = 1;
  if (!(std::isfinite(c.Q) && std::isfinite(vw) && std::isfinite(vu) && std::isfinite(phi)))
    return;
  this->Valid = true;
  this->output(s, this->Current, this->CurrentRate);
  this->Valid = this->Current.x.allFinite() && this->Current.p.allFinite();
}

bool KerrMinoPropagator::trial(double h, State& s, long& evaluations) const
{
  const Consts& c = this->Ray;
  const double w0 = s.w, polar0 = s.polar;
  double wMin = w0;
  // The force at the start is the one the last kick of the previous step evaluated (FSAL).
  kick(s, this->Kicks.front() * h);
  for (std::size_t k = 0; k < this->Drifts.size(); ++k)
  {
    if (!drift(c, s, this->Drifts[k] * h))
      return false;
    wMin = std::min(wMin, s.w);
    force(c, s);
    ++evaluations;
    kick(s, this->Kicks[k + 1] * h);
  }
  if (!(wMin >= kMinWRatio * w0) || !std::isfinite(s.vw) || !std::isfinite(s.vu))
    return false;
  if (s.poleChart)
  {
    // Unwrap the atan2 term. φ_θ is monotonic (sign of L h), so a wrapped jump that runs the
    // wrong way by more than π/2 is the other branch of a swing by ≈ π past the pole.
    double d = wrapAngle(azimuthTerm(c, s.u, s.vu, s.azimuth) - s.azimuth);
    const double total = (s.polar - polar0) + d;
    if (c.L * h > 0.0 && total < -0.5 * M_PI)
      d += 2.0 * M_PI;
    else if (c.L * h < 0.0 && total > 0.5 * M_PI)
      d -= 2.0 * M_PI;
    s.azimuth += d;
  }
  const bool pole = wantsPoleChart(c, s.u);
  if (pole != s.poleChart)
  {
    const double polarPart = s.polar + (s.poleChart ? s.azimuth : 0.0);
    s.azimuth = pole ? azimuthTerm(c, s.u, s.vu, 0.0) : 0.0;
    s.polar = polarPart - s.azimuth;
    s.poleChart = pole;
  }
  return true;
}

bool KerrMinoPropagator::nextStep(Move& next)
{
  // Step fraction. Within kFixedStepRadius the step is the fixed h/M in σ (symplectic). Beyond it
  // a Mino step would move the point by ~h r/M relative, without bound as r grows (dλ = Σ dσ), so
  // the step shrinks as 1/r: the relative move stays ~h·kFixedStepRadius, like a step of K = r·H,
  // the accuracy there still follows h, and w = 0 is never reached. kMaxRelativeMove caps huge h.
  double theta = std::min(1.0, kFixedStepRadius * this->Ray.M * this->S.w);
  const double speed = this->CurrentRate.tail<3>().norm(), dist = this->Current.x.tail<3>().norm();
  if (theta * speed * this->Step > kMaxRelativeMove * dist)
    theta = kMaxRelativeMove * dist / (speed * this->Step);

  // A step that would end inside the capture sphere is cut to end just inside it (a root search on
  // the step fraction), so the tracer sees a capture and not the degenerate chart at Δ = 0.
  const double wCap = this->CaptureRadius > 0.0 ? 1.0 / this->CaptureRadius : 0.0;
  const bool capturing = wCap > 0.0 && this->S.w < wCap;
  const double wOut = wCap * (1.0 + kCaptureHigh);

  // Halve the fraction until the trial is valid (finite, w kept off infinity and the horizons).
  State& best = next.s;
  bool ok = false;
  for (const double theta0 = theta; theta > 1e-12 * theta0; theta *= 0.5)
  {
    best = this->S;
    if ((ok = this->trial(theta * this->Step, best, this->Evaluations)))
      break;
  }
  if (!ok)
    return false;
  if (capturing && best.w > wOut)
  {
    // Regula falsi (Illinois) on the fraction for w in [w_in, w_out], between the start (short of
    // it) and this trial (beyond it); an invalid trial counts as beyond and halves the bracket.
    // If none lands, the last trial short of it is kept.
    const double mid = 0.5 * (kCaptureLow + kCaptureHigh),
                 half = 0.5 * (kCaptureHigh - kCaptureLow);
    double lo = 0.0, hi = theta;
    double gLo = this->S.w / wCap - 1.0 - mid, gHi = best.w / wCap - 1.0 - mid;
    State shortOf = this->S;
    bool landed = false, bisect = false;
    int side = 0;
    for (int it = 0; it < 200 && hi - lo > 1e-16 * theta; ++it)
    {
      double t = bisect ? 0.5 * (lo + hi) : (lo * gHi - hi * gLo) / (gHi - gLo);
      if (!(t > lo && t < hi))
        t = 0.5 * (lo + hi);
      State s = this->S;
      bisect = !this->trial(t * this->Step, s, this->Evaluations);
      if (bisect)
      {
        hi = t;
        continue;
      }
      const double g = s.w / wCap - 1.0 - mid;
      if (std::abs(g) <= half)
      {
        best = s;
        theta = t;
        landed = true;
        break;
      }
      if (g < 0.0)
      {
        lo = t;
        gLo = g;
        shortOf = s;
        if (side == -1)
          gHi *= 0.5;
        side = -1;
      }
      else
      {
        hi = t;
        gHi = g;
        if (side == 1)
          gLo *= 0.5;
        side = 1;
      }
    }
    if (!landed)
    {
      if (!(lo > 0.0))
        return false;
      best = shortOf;
      theta = lo;
    }
  }
  next.h = theta * this->Step;
  this->output(best, next.z, next.rate);
  return next.z.x.allFinite() && next.z.p.allFinite() && next.rate.allFinite();
}

void KerrMinoPropagator::take(const Move& next, Segment& seg)
{
  // dλ/dσ = Σ = r² + a² u² at both ends.
  const double a2 = this->Ray.a * this->Ray.a;
  const double r0 = 1.0 / this->S.w, r1 = 1.0 / next.s.w;
  seg.x0 = this->Current.x;
  seg.p0 = this->Current.p;
  seg.lambda0 = this->S.lambda;
  seg.d0 = next.h * this->CurrentRate;
  seg.dl0 = next.h * (r0 * r0 + a2 * this->S.u * this->S.u);
  seg.x1 = next.z.x;
  seg.p1 = next.z.p;
  seg.d1 = next.h * next.rate;
  seg.lambda1 = next.s.lambda;
  seg.dl1 = next.h * (r1 * r1 + a2 * next.s.u * next.s.u);
  seg.farField = false;
  seg.quintic = false;
  this->pass(next);
}

void KerrMinoPropagator::pass(const Move& next)
{
  this->S = next.s;
  this->Current = next.z;
  this->CurrentRate = next.rate;
}

double KerrMinoPropagator::nextStopRadius(double r) const
{
  for (const double sky : this->Far->skyRadii)
  {
    if (sky > r)
      return sky;
  }
  return this->EscapeRadius;
}

bool KerrMinoPropagator::crossFarField(double farRadius, Segment& seg)
{
  const bool outgoing = this->S.vw < 0.0;
  const double target = outgoing ? this->nextStopRadius(this->Current.x.tail<3>().norm()) : 0.0;
  const PhasePoint from = this->Current;
  const Vec4 fromRate = this->CurrentRate;
  const double fromLambda = this->S.lambda;
  const double fromSigma = [&]
  {
    const double r = 1.0 / this->S.w;
    return r * r + this->Ray.a * this->Ray.a * this->S.u * this->S.u;
  }();
  const Vec3 a = from.x.tail<3>();
  int merged = 0;
  for (;;)
  {
    Move next;
    if (!this->nextStep(next))
      return false;
    const Vec3 b = next.z.x.tail<3>();
    const double R = b.norm();
    const bool sweepsLittle = a.dot(b) >= kCosMaxMergedSweep * a.norm() * R;
    const bool joins =
      sweepsLittle && R > farRadius && (next.s.vw < 0.0) == outgoing && !(outgoing && R >= target);
    if (!joins)
    {
      if (merged == 0)
      {
        this->take(next, seg);
        return true;
      }
      this->Pending = next;
      this->HasPending = true;
      break;
    }
    this->pass(next);
    ++merged;
  }
  // The merged segment's tangents are in λ, in which the far-field ray is nearly a straight line
  // at constant speed: its interpolant stays next to the ray, outside the objects (Segment).
  const double dl = this->S.lambda - fromLambda;
  const double r1 = 1.0 / this->S.w;
  const double sigma1 = r1 * r1 + this->Ray.a * this->Ray.a * this->S.u * this->S.u;
  seg.x0 = from.x;
  seg.p0 = from.p;
  seg.lambda0 = fromLambda;
  seg.d0 = (dl / fromSigma) * fromRate;
  seg.dl0 = dl;
  seg.x1 = this->Current.x;
  seg.p1 = this->Current.p;
  seg.d1 = (dl / sigma1) * this->CurrentRate;
  seg.lambda1 = this->S.lambda;
  seg.dl1 = dl;
  seg.farField = true;
  seg.quintic = false;
  return true;
}

bool KerrMinoPropagator::advance(Segment& seg)
{
  if (!this->Valid)
    return false;
  if (this->HasPending)
  {
    this->HasPending = false;
    this->take(this->Pending, seg);
    return true;
  }
  if (this->Far)
  {
    const double farRadius = std::max(this->Far->objectRadius, kFarFieldMinRadius * this->Ray.M);
    if (this->Current.x.tail<3>().norm() > farRadius)
      return this->crossFarField(farRadius, seg);
  }
  Move next;
  if (!this->nextStep(next))
    return false;
  this->take(next, seg);
  return true;
}

void KerrMinoPropagator::output(const State& s, PhasePoint& z, Vec4& dxds) const
{
  const Consts& c = this->Ray;
  const double a = c.a, E = c.E, L = c.L;
  const double w = s.w, r = 1.0 / w;
  // Kept in the band the exact ray can reach: outside it no real p_θ exists.
  double u = s.u;
  const double u2 = u * u;
  if (u2 > c.u2High)
    u = std::copysign(std::sqrt(c.u2High), u);
  else if (u2 < c.u2Low)
    u = std::copysign(std::sqrt(c.u2Low), u);
  const double sin2 = std::max(0.0, 1.0 - u * u), sinT = std::sqrt(sin2);
  const double c2 = r * r + a * a;
  const double Sigma = r * r + a * a * u * u, invSigma = 1.0 / Sigma;

  // On-shell velocities with the signs of the integrated ones: v_w² = R_w, p_θ² = Θ(θ).
  const double vw = std::copysign(std::sqrt(std::max(0.0, radialPotential(c, w))), s.vw);
  double theta2 = c.Q + c.a2E2 * u * u;
  if (L != 0.0 && sin2 > 0.0)
    theta2 -= L * L * u * u / sin2;
  // v_u = −sin θ p_θ; at v_u = 0 on the axis the ray is leaving it (see azimuthTerm).
  const double vuSign = s.vu != 0.0 ? s.vu : -u;
  const double pTheta = -std::copysign(std::sqrt(std::max(0.0, theta2)), vuSign);
  // p_r = (X − Y)/Δ − E in the spheroidal Kerr–Schild chart, in the form without cancellation.
  const double X = xw(c, w);
  const double pr = X * vw > 0.0 ? c.K * w * w / (X + vw) - E : (X - vw) / deltaW(c, w) - E;

  // Invert p_r = (r P − aL)/c² + u p_z, p_θ = (u/ sin θ)P − r sin θ p_z, L = x p_y − y p_x, in the
  // frame c ê = (r + ia)e^{iφ} of x⊥ (regular on the axis; the determinant is Σ/c): p⊥ = q c ê
  // + m i c ê.
  const double A1 = pr + a * L / c2;
  const double q = (u * pTheta + r * sinT * A1) * invSigma;
  const double m = sinT > 0.0 ? L / (c2 * sinT) : 0.0;
  const double pz = (u * c2 * A1 - r * sinT * pTheta) * invSigma;
  const double phi = s.phiRadial + s.polar + (s.poleChart ? s.azimuth : 0.0);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double ex = r * cp - a * sp, ey = r * sp + a * cp;
  z.x = Vec4(s.t, sinT * ex, sinT * ey, r * u);
  z.p = Vec4(-E, q * ex - m * ey, q * ey + m * ex, pz);
  // dx/dσ = Σ ∂H/∂p with H = ½(η^{μν} − f l^μ l^ν) p_μ p_ν (KerrSpacetime): at this point
  // l_i = ((rx + ay)/c², (ry − ax)/c², z/r) = (sin θ cos φ, sin θ sin φ, cos θ) and
  // f = 2Mr³/(r⁴ + a²z²) = 2Mr/Σ, so Σ f s = 2Mr s with s = l^μ p_μ.
  const double lx = sinT * cp, ly = sinT * sp;
  const double fs = 2.0 * c.M * r * (E + lx * z.p[1] + ly * z.p[2] + u * pz);
  dxds =
    Vec4(Sigma * E + fs, Sigma * z.p[1] - fs * lx, Sigma * z.p[2] - fs * ly, Sigma * pz - fs * u);
}
}
