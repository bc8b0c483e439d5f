// Kerr null geodesics in Mino time, explicit and exactly separable (physics.md, "Kerr, Mino time").
#ifndef asrt_KerrMinoPropagator_h
#define asrt_KerrMinoPropagator_h

#include "Propagator.h"

#include <limits>
#include <vector>

namespace asrt
{
namespace detail
{
/// Constants of one Kerr ray and of the hole, as KerrMinoPropagator steps it.
struct KerrMinoRay
{
  double M = 0, a = 0, rPlus = 0, rMinus = 0;
  double invDelta = 0; ///< 1/(r₊ − r₋), infinite for the extremal hole
  double E = 0, L = 0, Q = 0;
  double K = 0;    ///< Q + (L − aE)², the separation constant of the radial equation
  double a2E2 = 0; ///< a²E²
  /// Band of u² the exact ray can reach (between the roots of U): output positions are kept in it.
  double u2Low = 0, u2High = 1;
  /// u² above which the azimuth is kept in the chart that is regular on the axis.
  double u2Pole = 0;
};

/// The reduced state between steps: w = 1/r, u = cos θ, their Mino-time velocities, and the
/// quadratures. The Kerr–Schild azimuth is phiRadial + polar (+ azimuth in the pole chart).
struct KerrMinoState
{
  double w = 0, u = 0, vw = 0, vu = 0;
  double fw = 0, fu = 0; ///< R_w'(w)/2 and U'(u)/2 at (w, u)
  double phiRadial = 0;  ///< radial and uniform parts of φ_KS
  double polar = 0;      ///< Ω in the pole chart, the polar part of φ in the plain chart
  double azimuth = 0;    ///< unwrapped atan2(L u, v_u), pole chart only
  bool poleChart = true;
  double t = 0;      ///< Kerr–Schild time
  double lambda = 0; ///< affine parameter
};
}

/// With dλ = Σ dσ, w = 1/r and u = cos θ, the Kerr null geodesic is the separable Hamiltonian
/// h = ½(v_w² + v_u²) − ½(R_w(w) + U(u)) = 0. E, L and Q are constants of the reduced system, so
/// they are exact by construction; φ and t are quadratures. Composed by Yoshida to order 2 or 4.
/// Segments are reported in Kerr–Schild Cartesian coordinates, for scene intersection.
///
/// Every reported (x, p) is an exact null covector with the ray's E, L and Q: the velocities are
/// projected onto v_w² = R_w, v_u² = U at the integrated position (which only differs from the
/// truth by the method's error). σ has the dimension of 1/length (λ is a length, Σ a length²), so
/// the step is h/M in σ within r = 10 M: the step is h in units of M, and a hole of any mass is
/// traced as the hole of mass 1 scaled by M. Beyond r = 10 M, where Mino time runs fast
/// (dλ = Σ dσ), it shrinks as 1/r so that the point moves by ~10 h of its distance per step
/// (never more than a quarter): segments stay interpolable, accuracy still follows h, and
/// infinity (w = 0) is never reached. A step that would end inside the capture radius ends just
/// inside it instead.
///
/// With a far field (setFarField), the steps outside the scene's objects are the same, but those
/// that stay outside them (and, going out, inside the next sky sphere) are reported as one segment.
/// The segments that may meet an object, the step onto a sky sphere among them, are exactly those
/// of the ray without a far field: a shorter last step landing on the sphere cost more in its root
/// search than the interpolated step.
class ASRTPHYSICS_EXPORT KerrMinoPropagator final : public Propagator
{
public:
  /// `st` must be Kerr (or Schwarzschild, a = 0) with M > 0; throws InvalidParameter otherwise.
  /// `step` is h, in units of M.
  KerrMinoPropagator(const Spacetime& st, int order, double step);
  void start(const PhasePoint& z) override;
  bool advance(Segment& seg) override;
  PhasePoint state() const override { return this->Current; }
  double affineParameter() const override { return this->S.lambda; }
  long evaluations() const override { return this->Evaluations; }
  void setLimits(double escapeRadius, double captureRadius) override;
  void setFarField(const FarField* farField) override { this->Far = farField; }

  /// Constants of motion of the current ray (exact by construction).
  double energy() const { return this->Ray.E; }
  double angularMomentum() const { return this->Ray.L; }
  double carterConstant() const { return this->Ray.Q; }

private:
  /// One step from the current state, not yet taken: the state it ends in, its end point and
  /// dx/dσ there, and its length in σ.
  struct Move
  {
    detail::KerrMinoState s;
    PhasePoint z;
    Vec4 rate = Vec4::Zero();
    double h = 0;
  };
  bool trial(double h, detail::KerrMinoState& s, long& evaluations) const;
  void output(const detail::KerrMinoState& s, PhasePoint& z, Vec4& dxds) const;
  /// The next step as the fixed-step rule makes it (shortened to end just inside the capture
  /// sphere); false on numerical failure.
  bool nextStep(Move& next);
  /// Takes `next` and describes it as one segment.
  void take(const Move& next, Segment& seg);
  /// Takes `next` without a segment of its own (it joins a far-field segment).
  void pass(const Move& next);
  /// Through the far field in one segment, while the steps stay outside the scene's objects and,
  /// going out, inside the next sky sphere (or the escape sphere).
  bool crossFarField(double farRadius, Segment& seg);
  /// The next sky sphere above radius r, else the escape sphere.
  double nextStopRadius(double r) const;

  const Spacetime& St;
  double Step;                       ///< in σ: the given h divided by M
  std::vector<double> Kicks, Drifts; ///< fractions of h of the kick-drift-kick stages
  detail::KerrMinoRay Ray;
  detail::KerrMinoState S;
  PhasePoint Current;
  Vec4 CurrentRate = Vec4::Zero(); ///< dx/dσ at Current
  bool Valid = false;
  long Evaluations = 0;
  double CaptureRadius = 0;
  double EscapeRadius = std::numeric_limits<double>::infinity();
  const FarField* Far = nullptr;
  /// A step computed while merging far-field steps that could not join them: the next segment.
  Move Pending;
  bool HasPending = false;
};
}

#endif
