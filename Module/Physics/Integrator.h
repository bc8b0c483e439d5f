// Stepping rules for Hamiltonian systems on (x, p) ∈ R⁴ × R⁴, swappable in the way of VTK's
// vtkInitialValueProblemSolver family. A rule holds no per-ray state of its own: whatever a
// method carries between steps (Tao's extended copy) lives in IntegrationState.
#ifndef asrt_Integrator_h
#define asrt_Integrator_h

#include "Spacetime.h"

#include <vector>

namespace asrt
{
struct IntegrationState
{
  Vec4 x = Vec4::Zero();
  Vec4 p = Vec4::Zero();
  // Tao's extended phase space carries a second copy (x̃, p̃) of the state.
  Vec4 xShadow = Vec4::Zero();
  Vec4 pShadow = Vec4::Zero();
  bool hasShadow = false;
  // Dormand–Prince's last stage is the next step's first (FSAL): kept here while valid.
  Eigen::Matrix<double, 8, 1> lastSlope = Eigen::Matrix<double, 8, 1>::Zero();
  bool hasLastSlope = false;
  // Round-off carried by compensated summation of the step increments (Kahan): over 10⁵ steps
  // the plain sum loses ~10⁻¹¹ of the state, more than a fine step's truncation error.
  Vec4 xCarry = Vec4::Zero();
  Vec4 pCarry = Vec4::Zero();

  void increment(const Vec4& dx, const Vec4& dp)
  {
    const Vec4 yx = dx - this->xCarry, yp = dp - this->pCarry;
    const Vec4 tx = this->x + yx, tp = this->p + yp;
    this->xCarry = (tx - this->x) - yx;
    this->pCarry = (tp - this->p) - yp;
    this->x = tx;
    this->p = tp;
  }
};

/// Counters a rule adds to while it steps. One evaluation = one call of H's gradient.
struct StepStats
{
  long evaluations = 0;
  long rejectedSteps = 0;
};

class ASRTPHYSICS_EXPORT Integrator
{
public:
  virtual ~Integrator() = default;
  virtual const char* name() const = 0;
  virtual int order() const = 0;
  virtual bool isSymplectic() const = 0;
  virtual bool isAdaptive() const { return false; }
  /// Advances `s` by one step. A fixed-step rule takes exactly `h` and leaves it alone. An adaptive
  /// rule may take a smaller step: on return `h` is the step taken and `hNext` its proposal for the
  /// next one. Returns false if the step failed (non-finite state, implicit solve not converged).
  virtual bool step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
                    StepStats& stats) const = 0;
};

/// Gauss–Legendre collocation with 1, 2 or 3 stages (orders 2, 4, 6): symplectic and implicit.
/// The stage equations are solved by fixed-point iteration until the update stops shrinking,
/// i.e. to round-off.
class ASRTPHYSICS_EXPORT GaussLegendre final : public Integrator
{
public:
  explicit GaussLegendre(int stages);
  const char* name() const override;
  int order() const override { return 2 * this->Stages; }
  bool isSymplectic() const override { return true; }
  bool step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
            StepStats& stats) const override;

private:
  int Stages;
  double A[3][3];
  double B[3];
};

/// Tao 2016 explicit symplectic integrator for non-separable H in extended phase space,
/// H̄ = H(x, p̃) + H(x̃, p) + ω(|x − x̃|² + |p − p̃|²)/2, Strang-split (order 2) and composed by
/// Yoshida to order 4 or 6. ω couples the two copies; its tuning is part of the trade.
class ASRTPHYSICS_EXPORT TaoExtendedPhaseSpace final : public Integrator
{
public:
  TaoExtendedPhaseSpace(int order, double omega);
  const char* name() const override;
  int order() const override { return this->Order; }
  bool isSymplectic() const override { return true; }
  bool step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
            StepStats& stats) const override;
  double omega() const { return this->Omega; }

private:
  void strang(const HamiltonianSystem& sys, IntegrationState& s, double h, StepStats& st) const;
  int Order;
  double Omega;
};

/// Classic fourth-order Runge–Kutta: the non-symplectic fixed-step reference.
class ASRTPHYSICS_EXPORT RungeKutta4 final : public Integrator
{
public:
  const char* name() const override { return "RK4"; }
  int order() const override { return 4; }
  bool isSymplectic() const override { return false; }
  bool step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
            StepStats& stats) const override;
};

/// Dormand–Prince 5(4) with error control on max(atol, rtol·|z|): the adaptive, non-symplectic
/// family Gyoto and most GR ray tracers use.
class ASRTPHYSICS_EXPORT DormandPrince54 final : public Integrator
{
public:
  DormandPrince54(double relativeTolerance, double absoluteTolerance);
  const char* name() const override { return "DormandPrince54"; }
  int order() const override { return 5; }
  bool isSymplectic() const override { return false; }
  bool isAdaptive() const override { return true; }
  bool step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
            StepStats& stats) const override;

private:
  double RelTol;
  double AbsTol;
};

/// Poincaré time transformation K = g(x)·H with g = r − r₊ (r₊ the outer horizon, 0 in flat
/// space). On H = 0 it has the same rays, with dλ/ds = g, so a fixed step in s grows with distance
/// from the hole while a symplectic rule stays symplectic (it integrates the Hamiltonian K exactly
/// as it would H). The horizon term shrinks the step where outgoing rays' p_r grows like 1/(r − r₊)
/// in the Kerr–Schild chart, which plain g = r steps straight through.
class ASRTPHYSICS_EXPORT PoincareTimeTransform final : public HamiltonianSystem
{
public:
  explicit PoincareTimeTransform(const Spacetime& st)
    : Base(st)
    , Horizon(st.outerHorizon())
  {
  }
  double value(const Vec4& x, const Vec4& p) const override;
  double gradient(const Vec4& x, const Vec4& p, Vec4& dKdx, Vec4& dKdp) const override;
  /// dλ/ds = g at x, and its gradient.
  double timeScale(const Vec4& x) const { return this->Base.radius(x) - this->Horizon; }
  double timeScaleGradient(const Vec4& x, Vec4& grad) const
  {
    return this->Base.radiusGradient(x, grad) - this->Horizon;
  }

private:
  const Spacetime& Base;
  double Horizon;
};

/// Yoshida (1990) weights: the symmetric composition of a symmetric order-2 map with these weights
/// (order given) has that order. Order 2 is the map itself.
ASRTPHYSICS_EXPORT const std::vector<double>& yoshidaWeights(int order);
}

#endif
