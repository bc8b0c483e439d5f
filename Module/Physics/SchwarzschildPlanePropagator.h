// Schwarzschild rays in their own plane, by an explicit splitting of K = r·H into exact flows.
#ifndef asrt_SchwarzschildPlanePropagator_h
#define asrt_SchwarzschildPlanePropagator_h

#include "Propagator.h"

namespace asrt
{
/// Every Schwarzschild ray is planar. In Schwarzschild coordinates of that plane, with dλ = r ds,
/// K = r·H splits into three exactly solvable flows, Strang-composed (order 2) and
/// Yoshida-composed (order 4). E and L are exact by construction; no spin terms are paid for.
///
/// Two splittings are offered:
///  - FlatExact (the default): K = K_flat + K_A + K_B with
///      K_flat = r(p_r² − E²)/2 + L²/(2r)  the flat-space line, solved in closed form,
///      K_A = −E² M r/(r − 2M)             a kick in p_r,
///      K_B = −M p_r²                      a drift r ← r − 2M p_r h.
///    Every splitting error carries a factor M, so far-field rays (b ≫ M) keep the relative
///    accuracy of their deflection instead of paying a flat-space error comparable to it.
///  - Radial (physics.md's form): K₁ = −E² r/(2f) + L²/(2r) (kick), K₂ = r p_r²/2
///    (r ← r q², p_r ← p_r/q, q = 1 + p_r h/2), K₃ = −M p_r² (drift).
class ASRTPHYSICS_EXPORT SchwarzschildPlanePropagator final : public Propagator
{
public:
  enum class Splitting
  {
    FlatExact,
    Radial
  };
  /// `st` must be Schwarzschild; throws InvalidParameter otherwise.
  SchwarzschildPlanePropagator(const Spacetime& st, int order, double step,
                               Splitting splitting = Splitting::FlatExact);
  void start(const PhasePoint& z) override;
  bool advance(Segment& seg) override;
  PhasePoint state() const override;
  double affineParameter() const override { return this->Lambda; }
  long evaluations() const override { return this->Evaluations; }

  double energy() const { return this->E; }
  double angularMomentum() const { return this->L; }
  /// Polar angle swept in the ray's plane since start.
  double sweptAngle() const { return this->Phi.value; }

private:
  void strangFlatExact(double h);
  void strangRadial(double h);
  void tangent(const PhasePoint& z, Vec4& dxds) const;
  const Spacetime& St;
  double M;
  int Order;
  double Step;
  Splitting Split;
  double E = 0, L = 0;
  /// A sum kept with Kahan compensation. A ray collects ~10⁵ increments of r, p_r and φ; their
  /// round-off would otherwise dominate far-field deflections (α ~ 4M/b) and, amplified by the
  /// photon sphere's instability, near-critical ones.
  struct Compensated
  {
    double value = 0, carry = 0;
    void add(double inc)
    {
      const double y = inc - this->carry;
      const double t = this->value + y;
      this->carry = (t - this->value) - y;
      this->value = t;
    }
    void reset(double v)
    {
      this->value = v;
      this->carry = 0;
    }
  };
  Compensated R, Pr, Phi; // Schwarzschild r, p_r, in-plane φ
  double T = 0;           // Schwarzschild t
  Vec3 E1, E2;            // in-plane basis: φ = 0 along E1, increasing to E2
  double Lambda = 0;
  long Evaluations = 0;
  PhasePoint Current;  // Cartesian state at the end of the last step
  Vec4 CurrentTangent; // and its dx/ds
};
}

#endif
