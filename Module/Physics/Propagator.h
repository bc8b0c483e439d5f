// Per-ray stepping: a Propagator advances one ray and hands out each step as a Segment of the
// spacetime's Cartesian chart, with the end tangents needed to interpolate inside it.
//
// General methods (Gauss–Legendre, Tao, RK4, Dormand–Prince) step H or K = (r − r₊)·H on the
// Cartesian state. Splittings that model only what the scene requires (Schwarzschild in the ray's
// plane, Kerr in Mino time) keep their own reduced state and convert to Cartesian once per step.
#ifndef asrt_Propagator_h
#define asrt_Propagator_h

#include "Integrator.h"

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace asrt
{
/// One step x_k → x_{k+1}. Inside it the position follows the cubic Hermite interpolant of the end
/// points and the tangents d0, d1 (dx/dτ for τ ∈ [0, 1]), accurate to O(h⁴) locally, or the quintic
/// one that also matches the second derivatives a0, a1.
struct Segment
{
  Vec4 x0, x1;                     ///< positions (t, x, y, z) at the ends
  Vec4 p0, p1;                     ///< covariant momenta at the ends
  Vec4 d0, d1;                     ///< dx/dτ at the ends, τ the step fraction
  double lambda0 = 0, lambda1 = 0; ///< affine parameter at the ends
  /// dλ/dτ at the ends (step length × dλ/ds): λ is no more linear in τ than x is, since methods
  /// step a transformed parameter s with dλ/ds = g(x).
  double dl0 = 0, dl1 = 0;
  /// True for a segment that a propagator ran through the far field (see FarField) in one go: its
  /// ends and end tangents are exact, but the interpolant in between is not the ray, and the
  /// segment lies wholly outside FarField::objectRadius. Only the sky can be hit on it, and only
  /// at its end.
  bool farField = false;
  /// Propagators that know the acceleration at the ends set `quintic` and a0, a1 = d²x/dτ²: the
  /// interpolant is then the quintic Hermite one, accurate to O(h⁶) locally, so that long steps of
  /// a high-order method keep hit points as accurate as the steps themselves.
  bool quintic = false;
  Vec4 a0 = Vec4::Zero(), a1 = Vec4::Zero();

  /// Position at step fraction τ ∈ [0, 1].
  Vec4 position(double tau) const;
  /// Affine parameter at τ, on the cubic Hermite interpolant of λ (O(h⁴) like position()).
  double lambda(double tau) const;
  /// dx/dτ at τ.
  Vec4 tangent(double tau) const;
};

/// A step's end as a propagator stepping in the affine parameter knows it: position, momentum,
/// dx/dλ and d²x/dλ² (its t component may be left at 0), and λ.
struct AffineEnd
{
  Vec4 x = Vec4::Zero(), p = Vec4::Zero(), v = Vec4::Zero(), a = Vec4::Zero();
  double lambda = 0;
};

/// The segment from `a` to `b` interpolated in λ: quintic Hermite in τ = (λ − λ_a)/h with
/// dx/dτ = h dx/dλ and d²x/dτ² = h² d²x/dλ² at the ends, and λ linear in τ.
ASRTPHYSICS_EXPORT void setAffineSegment(Segment& seg, const AffineEnd& a, const AffineEnd& b,
                                         bool farField);

/// Settings of a propagation method; `method` names a row of methodTable().
struct IntegratorConfig
{
  std::string method = "auto";
  double step = 0.05;        ///< h: affine for plain methods, s for time-transformed ones
  bool timeTransform = true; ///< general methods: integrate K = (r − r₊)·H (Poincaré), else H
  double omega = 1.0;        ///< Tao's coupling
  double relativeTolerance = 1e-10; ///< adaptive methods (Dormand–Prince, PlanarOrbit)
  double absoluteTolerance = 1e-12; ///< adaptive methods
};

/// What a scene lets a propagator skip: outside the ball of `objectRadius` about the origin nothing
/// can be hit but the sky spheres about the origin (radii `skyRadii`, ascending, hit only from
/// inside). A propagator may cross that region in one farField segment that ends just beyond the
/// next sky sphere (or the escape sphere), or beyond objectRadius coming in.
struct FarField
{
  double objectRadius = std::numeric_limits<double>::infinity();
  std::vector<double> skyRadii;
  /// A lower bound on the distance from a point to every object but the sky, if known: a segment
  /// whose whole path stays nearer its start than that cannot hit one, and may be long.
  std::function<double(const Vec3&)> objectDistance;
};

/// Where a ray going out from radius r stops next: the smallest sky radius of `far` beyond r, or
/// the escape radius (`far` may be null).
ASRTPHYSICS_EXPORT double nextStopRadius(const FarField* far, double r, double escapeRadius);

class ASRTPHYSICS_EXPORT Propagator
{
public:
  virtual ~Propagator() = default;
  /// Starts a new ray. The momentum is taken as given (it should satisfy H = 0).
  virtual void start(const PhasePoint& z) = 0;
  /// Advances one step and describes it. Returns false on numerical failure.
  virtual bool advance(Segment& seg) = 0;
  virtual PhasePoint state() const = 0;
  virtual double affineParameter() const = 0;
  /// Gradient evaluations (or exact-flow force evaluations) so far on this ray.
  virtual long evaluations() const = 0;
  /// Where the tracer will stop the ray: escaped at r >= escapeRadius moving out, captured at
  /// r <= captureRadius. A straight line may run in one segment to the escape sphere; a method
  /// whose chart degenerates at the horizon may end its last step at the capture radius.
  virtual void setLimits(double escapeRadius, double captureRadius)
  {
    (void)escapeRadius;
    (void)captureRadius;
  }
  /// The scene's far field, or null for none (every segment then follows the ray). It stays owned
  /// by the caller and must outlive the rays traced with it. Propagators that cannot use it ignore
  /// it.
  virtual void setFarField(const FarField* farField) { (void)farField; }
};

enum class MethodFamily
{
  Analytic, ///< straight lines in flat space, no integration
  General,  ///< any Hamiltonian, Cartesian state
  Splitting ///< a spacetime-specific explicit splitting
};

struct MethodInfo
{
  std::string name;
  int order;
  bool symplectic;
  MethodFamily family;
  std::string description;
  /// Builds the propagator; throws InvalidParameter if the method cannot model `st`.
  std::function<std::unique_ptr<Propagator>(const Spacetime& st, const IntegratorConfig& cfg)> make;
};

/// Every method ASRT knows. Adding a method is adding a row here (Propagator.cxx).
ASRTPHYSICS_EXPORT const std::vector<MethodInfo>& methodTable();
ASRTPHYSICS_EXPORT const MethodInfo& findMethod(const std::string& name);
/// The method "auto" resolves to for this spacetime (see bench/REPORT.md for the measurements).
ASRTPHYSICS_EXPORT std::string defaultMethod(const Spacetime& st);

/// The named speed/accuracy presets, measured in bench/REPORT.md on the paper's scene: "fast"
/// (rtol 1e-8), "balanced" (rtol 1e-10, the default: hit points within 1e-6 M at the 99th
/// percentile with the method "auto" picks) and "accurate" (rtol 1e-12), each with
/// atol = 1e-2 rtol. Throws InvalidParameter for any other name.
ASRTPHYSICS_EXPORT IntegratorConfig integratorPreset(const std::string& name);

/// Builds the propagator for `cfg` on `st`. Flat space is always solved analytically, whatever
/// method is asked for: it has nothing to integrate. Throws InvalidParameter for an unknown method,
/// a non-positive or non-finite step, or a method that cannot model this spacetime.
ASRTPHYSICS_EXPORT std::unique_ptr<Propagator> makePropagator(const Spacetime& st,
                                                              const IntegratorConfig& cfg);

/// Propagator for any general stepping rule on H or on K = (r − r₊)·H.
class ASRTPHYSICS_EXPORT GeneralPropagator final : public Propagator
{
public:
  GeneralPropagator(const Spacetime& st, std::unique_ptr<Integrator> rule, double step,
                    bool timeTransform);
  void start(const PhasePoint& z) override;
  bool advance(Segment& seg) override;
  PhasePoint state() const override { return { this->State.x, this->State.p }; }
  double affineParameter() const override { return this->Lambda; }
  long evaluations() const override { return this->Stats.evaluations; }
  const Integrator& rule() const { return *this->Rule; }

private:
  /// What the Hermite interpolant and the λ quadrature need at a step's end.
  struct EndPoint
  {
    Vec4 v = Vec4::Zero(); ///< dx/ds
    double g = 1, dg = 0;  ///< dλ/ds and its s-derivative
  };
  void endPoint(const Vec4& x, const Vec4& p, EndPoint& e) const;
  const Spacetime& St;
  std::unique_ptr<Integrator> Rule;
  PoincareTimeTransform Transformed;
  bool TimeTransform;
  double Step, NextStep;
  IntegrationState State;
  double Lambda = 0;
  StepStats Stats;
  EndPoint Start; ///< of the current step: computed once, as the previous step's end
};

/// Flat space: the exact straight line, one segment to the escape sphere.
class ASRTPHYSICS_EXPORT StraightLinePropagator final : public Propagator
{
public:
  void start(const PhasePoint& z) override;
  bool advance(Segment& seg) override;
  PhasePoint state() const override { return this->Z; }
  double affineParameter() const override { return this->Lambda; }
  long evaluations() const override { return 0; }
  void setLimits(double escapeRadius, double) override { this->EscapeRadius = escapeRadius; }

private:
  PhasePoint Z;
  double Lambda = 0;
  double EscapeRadius = 1e3;
};
}

#endif
