#include "Propagator.h"

#include "KerrMinoPropagator.h"
#include "PlanarOrbitPropagator.h"
#include "PlanarSeriesPropagator.h"
#include "SchwarzschildPlanePropagator.h"

#include <cmath>
#include <sstream>

namespace asrt
{
void setAffineSegment(Segment& seg, const AffineEnd& a, const AffineEnd& b, bool farField)
{
  const double h = b.lambda - a.lambda;
  seg.x0 = a.x;
  seg.p0 = a.p;
  seg.d0 = h * a.v;
  seg.a0 = h * h * a.a;
  seg.x1 = b.x;
  seg.p1 = b.p;
  seg.d1 = h * b.v;
  seg.a1 = h * h * b.a;
  seg.quintic = true;
  seg.lambda0 = a.lambda;
  seg.lambda1 = b.lambda;
  seg.dl0 = seg.dl1 = h;
  seg.farField = farField;
}

double nextStopRadius(const FarField* far, double r, double escapeRadius)
{
  if (far)
  {
    for (const double sky : far->skyRadii)
    {
      if (sky > r)
        return sky;
    }
  }
  return escapeRadius;
}

Vec4 Segment::position(double t) const
{
  const double t2 = t * t, t3 = t2 * t;
  if (this->quintic)
  {
    const double t4 = t3 * t, t5 = t4 * t;
    return (1 - 10 * t3 + 15 * t4 - 6 * t5) * this->x0 + (t - 6 * t3 + 8 * t4 - 3 * t5) * this->d0 +
           (0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5) * this->a0 +
           (0.5 * t3 - t4 + 0.5 * t5) * this->a1 + (-4 * t3 + 7 * t4 - 3 * t5) * this->d1 +
           (10 * t3 - 15 * t4 + 6 * t5) * this->x1;
  }
  return (2 * t3 - 3 * t2 + 1) * this->x0 + (t3 - 2 * t2 + t) * this->d0 +
         (-2 * t3 + 3 * t2) * this->x1 + (t3 - t2) * this->d1;
}

double Segment::lambda(double t) const
{
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * this->lambda0 + (t3 - 2 * t2 + t) * this->dl0 +
         (-2 * t3 + 3 * t2) * this->lambda1 + (t3 - t2) * this->dl1;
}

Vec4 Segment::tangent(double t) const
{
  const double t2 = t * t;
  if (this->quintic)
  {
    const double t3 = t2 * t, t4 = t3 * t;
    return (-30 * t2 + 60 * t3 - 30 * t4) * (this->x0 - this->x1) +
           (1 - 18 * t2 + 32 * t3 - 15 * t4) * this->d0 +
           (t - 4.5 * t2 + 6 * t3 - 2.5 * t4) * this->a0 +
           (1.5 * t2 - 4 * t3 + 2.5 * t4) * this->a1 + (-12 * t2 + 28 * t3 - 15 * t4) * this->d1;
  }
  return (6 * t2 - 6 * t) * this->x0 + (3 * t2 - 4 * t + 1) * this->d0 +
         (-6 * t2 + 6 * t) * this->x1 + (3 * t2 - 2 * t) * this->d1;
}

// ---------------------------------------------------------------------------------------------
GeneralPropagator::GeneralPropagator(const Spacetime& st, std::unique_ptr<Integrator> rule,
                                     double step, bool timeTransform)
  : St(st)
  , Rule(std::move(rule))
  , Transformed(st)
  , TimeTransform(timeTransform)
  , Step(step)
  , NextStep(step)
{
}

void GeneralPropagator::start(const PhasePoint& z)
{
  this->State = IntegrationState{};
  this->State.x = z.x;
  this->State.p = z.p;
  this->Lambda = 0.0;
  this->Stats = StepStats{};
  this->NextStep = this->Step;
  this->endPoint(z.x, z.p, this->Start);
}

void GeneralPropagator::endPoint(const Vec4& x, const Vec4& p, EndPoint& e) const
{
  // dx/ds = g ∂H/∂p, and g with its slope dg/ds = ∇g · dx/ds for the λ quadrature. A rule that
  // ends its step with the slope there (Dormand–Prince's FSAL stage) has already paid for dx/ds.
  Vec4 dHdx;
  const bool known = this->State.hasLastSlope && this->State.x == x && this->State.p == p;
  if (this->TimeTransform)
  {
    Vec4 grad;
    double r;
    if (known)
    {
      e.v = this->State.lastSlope.head<4>();
      r = this->St.radiusGradient(x, grad);
      e.g = r - this->St.outerHorizon();
    }
    else
    {
      this->St.gradientAndRadius(x, p, dHdx, e.v, r, grad);
      e.g = r - this->St.outerHorizon();
      e.v *= e.g;
    }
    e.dg = grad.dot(e.v);
  }
  else
  {
    if (known)
      e.v = this->State.lastSlope.head<4>();
    else
      this->St.gradient(x, p, dHdx, e.v);
    e.g = 1.0;
    e.dg = 0.0;
  }
}

bool GeneralPropagator::advance(Segment& seg)
{
  seg.x0 = this->State.x;
  seg.p0 = this->State.p;
  seg.lambda0 = this->Lambda;
  double h = this->NextStep;
  double hNext = h;
  const HamiltonianSystem& sys = this->TimeTransform
                                   ? static_cast<const HamiltonianSystem&>(this->Transformed)
                                   : static_cast<const HamiltonianSystem&>(this->St);
  if (!this->Rule->step(sys, this->State, h, hNext, this->Stats))
  {
    return false;
  }
  this->NextStep = hNext;
  seg.x1 = this->State.x;
  seg.p1 = this->State.p;
  const EndPoint e0 = this->Start;
  this->endPoint(seg.x1, seg.p1, this->Start); // the next step starts where this one ends
  const EndPoint& e1 = this->Start;
  seg.d0 = h * e0.v;
  seg.d1 = h * e1.v;
  seg.dl0 = h * e0.g;
  seg.dl1 = h * e1.g;
  // λ = ∫ g ds over the step, by the Hermite quadrature of g(s) with its end slopes (exact for
  // cubics, O(h⁵) locally); for the affine parameter g = 1 and this is just h.
  this->Lambda += h * 0.5 * (e0.g + e1.g) + h * h * (e0.dg - e1.dg) / 12.0;
  seg.lambda1 = this->Lambda;
  return true;
}

// ---------------------------------------------------------------------------------------------
void StraightLinePropagator::start(const PhasePoint& z)
{
  this->Z = z;
  this->Lambda = 0.0;
}

bool StraightLinePropagator::advance(Segment& seg)
{
  // dx^μ/dλ = η^{μν} p_ν, exactly, forever.
  const Vec4 v(-this->Z.p[0], this->Z.p[1], this->Z.p[2], this->Z.p[3]);
  const Vec3 x = this->Z.x.tail<3>(), u = v.tail<3>();
  const double uu = u.squaredNorm();
  if (!(uu > 0.0) || !std::isfinite(uu))
  {
    return false;
  }
  // Run to the far intersection with the escape sphere, or one radius further if already out.
  const double R = this->EscapeRadius;
  const double b = x.dot(u) / uu, c = (x.squaredNorm() - R * R) / uu;
  const double disc = b * b - c;
  double dl = disc > 0.0 ? -b + std::sqrt(disc) : 0.0;
  if (dl <= 0.0)
  {
    dl = R / std::sqrt(uu);
  }
  seg.x0 = this->Z.x;
  seg.p0 = this->Z.p;
  seg.lambda0 = this->Lambda;
  this->Z.x += dl * v;
  this->Lambda += dl;
  seg.x1 = this->Z.x;
  seg.p1 = this->Z.p;
  seg.d0 = seg.d1 = dl * v;
  seg.dl0 = seg.dl1 = dl;
  seg.lambda1 = this->Lambda;
  return true;
}

// ---------------------------------------------------------------------------------------------
namespace
{
void requireStep(double h)
{
  if (!(h > 0.0) || !std::isfinite(h))
  {
    std::ostringstream os;
    os << "integration step must be positive and finite, got " << h;
    throw InvalidParameter(os.str());
  }
}

/// A general stepping rule. `timeTransformable` is false for rules that must step the affine H
/// even when the configuration asks for K = r·H.
MethodInfo general(const std::string& name, int order, bool symplectic, const std::string& what,
                   std::function<std::unique_ptr<Integrator>(const IntegratorConfig&)> rule,
                   bool timeTransformable = true)
{
  return { name,
           order,
           symplectic,
           MethodFamily::General,
           what,
           [rule, timeTransformable](const Spacetime& st,
                                     const IntegratorConfig& cfg) -> std::unique_ptr<Propagator>
           {
             return std::make_unique<GeneralPropagator>(st, rule(cfg), cfg.step,
                                                        cfg.timeTransform && timeTransformable);
           } };
}

MethodInfo schwarzschild(const std::string& name, int order,
                         SchwarzschildPlanePropagator::Splitting split, const std::string& what)
{
  return { name,
           order,
           true,
           MethodFamily::Splitting,
           what,
           [order, split](const Spacetime& st,
                          const IntegratorConfig& c) -> std::unique_ptr<Propagator>
           { return std::make_unique<SchwarzschildPlanePropagator>(st, order, c.step, split); } };
}
}

const std::vector<MethodInfo>& methodTable()
{
  static const std::vector<MethodInfo> table = {
    { "Analytic", 0, true, MethodFamily::Analytic, "exact straight lines (flat space only)",
      [](const Spacetime& st, const IntegratorConfig&) -> std::unique_ptr<Propagator>
      {
        if (!st.isFlat())
          throw InvalidParameter("method Analytic traces straight lines: flat space only");
        return std::make_unique<StraightLinePropagator>();
      } },
    general("ImplicitMidpoint", 2, true, "Gauss-Legendre, 1 stage (implicit)",
            [](const IntegratorConfig&) { return std::make_unique<GaussLegendre>(1); }),
    general("GaussLegendre4", 4, true, "Gauss-Legendre, 2 stages (implicit)",
            [](const IntegratorConfig&) { return std::make_unique<GaussLegendre>(2); }),
    general("GaussLegendre6", 6, true, "Gauss-Legendre, 3 stages (implicit)",
            [](const IntegratorConfig&) { return std::make_unique<GaussLegendre>(3); }),
    general(
      "Tao2", 2, true,
      "Tao extended phase space, Strang (explicit, affine: its coupling is unstable under K = r H)",
      [](const IntegratorConfig& c) { return std::make_unique<TaoExtendedPhaseSpace>(2, c.omega); },
      false),
    general(
      "Tao4", 4, true, "Tao extended phase space, Yoshida triple jump (explicit, affine)",
      [](const IntegratorConfig& c) { return std::make_unique<TaoExtendedPhaseSpace>(4, c.omega); },
      false),
    general(
      "Tao6", 6, true, "Tao extended phase space, Yoshida order 6 (explicit, affine)",
      [](const IntegratorConfig& c) { return std::make_unique<TaoExtendedPhaseSpace>(6, c.omega); },
      false),
    general("RK4", 4, false, "classic Runge-Kutta (non-symplectic reference)",
            [](const IntegratorConfig&) { return std::make_unique<RungeKutta4>(); }),
    general("DormandPrince54", 5, false, "adaptive Dormand-Prince 5(4) (non-symplectic reference)",
            [](const IntegratorConfig& c) {
              return std::make_unique<DormandPrince54>(c.relativeTolerance, c.absoluteTolerance);
            }),
    schwarzschild("SchwarzschildSplit2", 2, SchwarzschildPlanePropagator::Splitting::FlatExact,
                  "Schwarzschild ray plane, K = r H: exact flat line + M kick + M drift, Strang"),
    schwarzschild(
      "SchwarzschildSplit4", 4, SchwarzschildPlanePropagator::Splitting::FlatExact,
      "Schwarzschild ray plane, K = r H: exact flat line + M kick + M drift, Yoshida 4"),
    schwarzschild("SchwarzschildRadialSplit2", 2, SchwarzschildPlanePropagator::Splitting::Radial,
                  "Schwarzschild ray plane, K = r H in physics.md's three radial flows, Strang"),
    schwarzschild("SchwarzschildRadialSplit4", 4, SchwarzschildPlanePropagator::Splitting::Radial,
                  "Schwarzschild ray plane, K = r H in physics.md's three radial flows, Yoshida 4"),
    { "PlanarOrbit", 8, false, MethodFamily::Splitting,
      "Schwarzschild/Reissner-Nordstrom ray plane: the orbit as a central force in affine time, "
      "adaptive Dormand-Prince 8(5,3) on 4 numbers, far field in one segment",
      [](const Spacetime& st, const IntegratorConfig& c) -> std::unique_ptr<Propagator> {
        return std::make_unique<PlanarOrbitPropagator>(st, c.relativeTolerance,
                                                       c.absoluteTolerance);
      } },
    { "PlanarSeries", 24, false, MethodFamily::Splitting,
      "Schwarzschild/Reissner-Nordstrom ray plane: Taylor series of the Binet equation in the "
      "orbit's angle, lambda and t by quadrature, the outgoing far field as PlanarOrbit",
      [](const Spacetime& st, const IntegratorConfig& c) -> std::unique_ptr<Propagator>
      {
        return std::make_unique<PlanarSeriesPropagator>(st, c.relativeTolerance,
                                                        c.absoluteTolerance);
      } },
    { "KerrMino2", 2, true, MethodFamily::Splitting,
      "Kerr, separable Mino-time form in w = 1/r, u = cos(theta), leapfrog",
      [](const Spacetime& st, const IntegratorConfig& c) -> std::unique_ptr<Propagator>
      { return std::make_unique<KerrMinoPropagator>(st, 2, c.step); } },
    { "KerrMino4", 4, true, MethodFamily::Splitting,
      "Kerr, separable Mino-time form in w = 1/r, u = cos(theta), Yoshida order 4",
      [](const Spacetime& st, const IntegratorConfig& c) -> std::unique_ptr<Propagator>
      { return std::make_unique<KerrMinoPropagator>(st, 4, c.step); } },
  };
  return table;
}

const MethodInfo& findMethod(const std::string& name)
{
  for (const MethodInfo& m : methodTable())
  {
    if (m.name == name)
      return m;
  }
  std::ostringstream os;
  os << "unknown integration method '" << name << "'; known:";
  for (const MethodInfo& m : methodTable())
    os << ' ' << m.name;
  throw InvalidParameter(os.str());
}

std::string defaultMethod(const Spacetime& st)
{
  switch (st.kind())
  {
    case SpacetimeKind::Minkowski:
      return "Analytic";
    case SpacetimeKind::Schwarzschild:
    case SpacetimeKind::ReissnerNordstrom:
      // bench/REPORT.md: on whole frames the planar orbit is the fastest at every accuracy the
      // presets ask for, stepped in its angle by Taylor series where it bends and in λ through
      // the far field; the symplectic methods win where their bounded |H| matters, on long
      // integrations.
      return "PlanarSeries";
    case SpacetimeKind::Kerr:
      // E, L and Q exact by construction, at a fraction of the general methods' evaluations.
      return "KerrMino4";
  }
  return "DormandPrince54";
}

IntegratorConfig integratorPreset(const std::string& name)
{
  IntegratorConfig c;
  c.method = "auto";
  if (name == "fast")
    c.relativeTolerance = 1e-8;
  else if (name == "balanced")
    c.relativeTolerance = 1e-10;
  else if (name == "accurate")
    c.relativeTolerance = 1e-12;
  else
    throw InvalidParameter("unknown preset \"" + name + "\" (known: fast, balanced, accurate)");
  c.absoluteTolerance = 1e-2 * c.relativeTolerance;
  return c;
}

std::unique_ptr<Propagator> makePropagator(const Spacetime& st, const IntegratorConfig& cfg)
{
  const std::string name = cfg.method == "auto" ? defaultMethod(st) : cfg.method;
  const MethodInfo& m = findMethod(name);
  if (st.isFlat())
  {
    return std::make_unique<StraightLinePropagator>();
  }
  requireStep(cfg.step);
  return m.make(st, cfg);
}
}
