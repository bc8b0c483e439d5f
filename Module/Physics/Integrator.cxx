#include "Integrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace asrt
{
namespace
{
inline bool finite(const Vec4& v)
{
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) && std::isfinite(v[3]);
}

/// Hamilton's equations: ẋ = ∂H/∂p, ṗ = −∂H/∂x.
inline void flow(const HamiltonianSystem& sys, const Vec4& x, const Vec4& p, Vec4& dx, Vec4& dp)
{
  Vec4 dHdx, dHdp;
  sys.gradient(x, p, dHdx, dHdp);
  dx = dHdp;
  dp = -dHdx;
}
}

const std::vector<double>& yoshidaWeights(int order)
{
  static const std::vector<double> w2{ 1.0 };
  static const std::vector<double> w4 = []
  {
    const double c = std::cbrt(2.0);
    const double w1 = 1.0 / (2.0 - c), w0 = -c / (2.0 - c);
    return std::vector<double>{ w1, w0, w1 };
  }();
  // Yoshida 1990, solution A of the 7-stage order-6 composition.
  static const std::vector<double> w6 = []
  {
    const double w1 = -1.17767998417887, w2 = 0.235573213359357, w3 = 0.784513610477560;
    const double w0 = 1.0 - 2.0 * (w1 + w2 + w3);
    return std::vector<double>{ w3, w2, w1, w0, w1, w2, w3 };
  }();
  switch (order)
  {
    case 2:
      return w2;
    case 4:
      return w4;
    case 6:
      return w6;
    default:
    {
      std::ostringstream os;
      os << "composition order must be 2, 4 or 6, got " << order;
      throw InvalidParameter(os.str());
    }
  }
}

// ---------------------------------------------------------------------------------------------
GaussLegendre::GaussLegendre(int stages)
  : Stages(stages)
  , A{}
  , B{}
{
  const double s3 = std::sqrt(3.0), s15 = std::sqrt(15.0);
  switch (stages)
  {
    case 1:
      A[0][0] = 0.5;
      B[0] = 1.0;
      break;
    case 2:
      A[0][0] = 0.25;
      A[0][1] = 0.25 - s3 / 6.0;
      A[1][0] = 0.25 + s3 / 6.0;
      A[1][1] = 0.25;
      B[0] = B[1] = 0.5;
      break;
    case 3:
      A[0][0] = 5.0 / 36.0;
      A[0][1] = 2.0 / 9.0 - s15 / 15.0;
      A[0][2] = 5.0 / 36.0 - s15 / 30.0;
      A[1][0] = 5.0 / 36.0 + s15 / 24.0;
      A[1][1] = 2.0 / 9.0;
      A[1][2] = 5.0 / 36.0 - s15 / 24.0;
      A[2][0] = 5.0 / 36.0 + s15 / 30.0;
      A[2][1] = 2.0 / 9.0 + s15 / 15.0;
      A[2][2] = 5.0 / 36.0;
      B[0] = B[2] = 5.0 / 18.0;
      B[1] = 4.0 / 9.0;
      break;
    default:
    {
      std::ostringstream os;
      os << "Gauss-Legendre stages must be 1, 2 or 3, got " << stages;
      throw InvalidParameter(os.str());
    }
  }
}

const char* GaussLegendre::name() const
{
  switch (this->Stages)
  {
    case 1:
      return "ImplicitMidpoint";
    case 2:
      return "GaussLegendre4";
    default:
      return "GaussLegendre6";
  }
}

bool GaussLegendre::step(const HamiltonianSystem& sys, IntegrationState& s, double& h,
                         double& hNext, StepStats& st) const
{
  hNext = h;
  const int n = this->Stages;
  Vec4 kx[3], kp[3];
  flow(sys, s.x, s.p, kx[0], kp[0]);
  ++st.evaluations;
  for (int i = 1; i < n; ++i)
  {
    kx[i] = kx[0];
    kp[i] = kp[0];
  }
  // Fixed-point iteration on the stage slopes. Stop when the update vanishes or stops shrinking
  // (round-off reached, Hairer–Lubich–Wanner VIII.6); fail if it is still large then.
  const double scale = std::max({ 1.0, s.x.norm(), s.p.norm() });
  double previous = INFINITY;
  constexpr int maxIterations = 60;
  bool converged = false;
  for (int it = 0; it < maxIterations; ++it)
  {
    double change = 0.0;
    Vec4 nx[3], np[3];
    for (int i = 0; i < n; ++i)
    {
      Vec4 X = s.x, P = s.p;
      for (int j = 0; j < n; ++j)
      {
        X += h * this->A[i][j] * kx[j];
        P += h * this->A[i][j] * kp[j];
      }
      flow(sys, X, P, nx[i], np[i]);
      ++st.evaluations;
    }
    for (int i = 0; i < n; ++i)
    {
      change = std::max(change, std::abs(h) * ((nx[i] - kx[i]).cwiseAbs().maxCoeff() +
                                               (np[i] - kp[i]).cwiseAbs().maxCoeff()));
      kx[i] = nx[i];
      kp[i] = np[i];
    }
    if (!std::isfinite(change))
    {
      return false;
    }
    if (change == 0.0 || (it > 1 && change >= previous))
    {
      converged = change <= 1e-10 * scale;
      break;
    }
    previous = change;
  }
  if (!converged)
  {
    return false;
  }
  Vec4 dx = Vec4::Zero(), dp = Vec4::Zero();
  for (int i = 0; i < n; ++i)
  {
    dx += h * this->B[i] * kx[i];
    dp += h * this->B[i] * kp[i];
  }
  s.increment(dx, dp);
  return finite(s.x) && finite(s.p);
}

// ---------------------------------------------------------------------------------------------
TaoExtendedPhaseSpace::TaoExtendedPhaseSpace(int order, double omega)
  : Order(order)
  , Omega(omega)
{
  yoshidaWeights(order); // validates the order
  if (!(omega > 0.0) || !std::isfinite(omega))
  {
    std::ostringstream os;
    os << "Tao coupling omega must be positive and finite, got " << omega;
    throw InvalidParameter(os.str());
  }
}

const char* TaoExtendedPhaseSpace::name() const
{
  switch (this->Order)
  {
    case 2:
      return "Tao2";
    case 4:
      return "Tao4";
    default:
      return "Tao6";
  }
}

void TaoExtendedPhaseSpace::strang(const HamiltonianSystem& sys, IntegrationState& s, double h,
                                   StepStats& st) const
{
  Vec4& q = s.x;
  Vec4& p = s.p;
  Vec4& x = s.xShadow;
  Vec4& y = s.pShadow;
  Vec4 dHdx, dHdp;
  // φ_A: flow of H(q, y): p −= δ ∂H/∂q(q, y), x += δ ∂H/∂p(q, y).
  auto flowA = [&](double d)
  {
    sys.gradient(q, y, dHdx, dHdp);
    ++st.evaluations;
    p -= d * dHdx;
    x += d * dHdp;
  };
  // φ_B: flow of H(x, p): q += δ ∂H/∂p(x, p), y −= δ ∂H/∂x(x, p).
  auto flowB = [&](double d)
  {
    sys.gradient(x, p, dHdx, dHdp);
    ++st.evaluations;
    q += d * dHdp;
    y -= d * dHdx;
  };
  // φ_C: exact rotation of the coupling ω(|q − x|² + |p − y|²)/2.
  auto flowC = [&](double d)
  {
    const double c = std::cos(2.0 * this->Omega * d), sn = std::sin(2.0 * this->Omega * d);
    const Vec4 sumQ = q + x, difQ = q - x, sumP = p + y, difP = p - y;
    const Vec4 rotQ = c * difQ + sn * difP;
    const Vec4 rotP = -sn * difQ + c * difP;
    q = 0.5 * (sumQ + rotQ);
    p = 0.5 * (sumP + rotP);
    x = 0.5 * (sumQ - rotQ);
    y = 0.5 * (sumP - rotP);
  };
  flowA(0.5 * h);
  flowB(0.5 * h);
  flowC(h);
  flowB(0.5 * h);
  flowA(0.5 * h);
}

bool TaoExtendedPhaseSpace::step(const HamiltonianSystem& sys, IntegrationState& s, double& h,
                                 double& hNext, StepStats& st) const
{
  hNext = h;
  if (!s.hasShadow)
  {
    s.xShadow = s.x;
    s.pShadow = s.p;
    s.hasShadow = true;
  }
  for (double w : yoshidaWeights(this->Order))
  {
    this->strang(sys, s, w * h, st);
  }
  return finite(s.x) && finite(s.p) && finite(s.xShadow) && finite(s.pShadow);
}

// ---------------------------------------------------------------------------------------------
bool RungeKutta4::step(const HamiltonianSystem& sys, IntegrationState& s, double& h, double& hNext,
                       StepStats& st) const
{
  hNext = h;
  Vec4 k1x, k1p, k2x, k2p, k3x, k3p, k4x, k4p;
  flow(sys, s.x, s.p, k1x, k1p);
  flow(sys, s.x + 0.5 * h * k1x, s.p + 0.5 * h * k1p, k2x, k2p);
  flow(sys, s.x + 0.5 * h * k2x, s.p + 0.5 * h * k2p, k3x, k3p);
  flow(sys, s.x + h * k3x, s.p + h * k3p, k4x, k4p);
  st.evaluations += 4;
  s.increment(h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
              h / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p));
  return finite(s.x) && finite(s.p);
}

// ---------------------------------------------------------------------------------------------
DormandPrince54::DormandPrince54(double relativeTolerance, double absoluteTolerance)
  : RelTol(relativeTolerance)
  , AbsTol(absoluteTolerance)
{
  if (!(relativeTolerance > 0.0) || !(absoluteTolerance > 0.0))
  {
    std::ostringstream os;
    os << "Dormand-Prince tolerances must be positive, got rtol=" << relativeTolerance
       << " atol=" << absoluteTolerance;
    throw InvalidParameter(os.str());
  }
}

bool DormandPrince54::step(const HamiltonianSystem& sys, IntegrationState& s, double& h,
                           double& hNext, StepStats& st) const
{
  // Dormand & Prince 1980, the RK5(4)7M tableau (the stage times c_i are implicit: H does not
  // depend on the parameter).
  static const double a21 = 1.0 / 5;
  static const double a31 = 3.0 / 40, a32 = 9.0 / 40;
  static const double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  static const double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                      a54 = -212.0 / 729;
  static const double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                      a64 = 49.0 / 176, a65 = -5103.0 / 18656;
  static const double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                      b6 = 11.0 / 84;
  static const double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                      e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;
  using V8 = Eigen::Matrix<double, 8, 1>;
  auto f = [&](const V8& z)
  {
    Vec4 dx, dp;
    flow(sys, z.head<4>(), z.tail<4>(), dx, dp);
    ++st.evaluations;
    V8 out;
    out << dx, dp;
    return out;
  };
  V8 z;
  z << s.x, s.p;
  const V8 k1 = s.hasLastSlope ? s.lastSlope : f(z);
  for (int attempt = 0; attempt < 60; ++attempt)
  {
    const V8 k2 = f(z + h * (a21 * k1));
    const V8 k3 = f(z + h * (a31 * k1 + a32 * k2));
    const V8 k4 = f(z + h * (a41 * k1 + a42 * k2 + a43 * k3));
    const V8 k5 = f(z + h * (a51 * k1 + a52 * k2 + a53 * k3 + a54 * k4));
    const V8 k6 = f(z + h * (a61 * k1 + a62 * k2 + a63 * k3 + a64 * k4 + a65 * k5));
    const V8 dz = h * (b1 * k1 + b3 * k3 + b4 * k4 + b5 * k5 + b6 * k6);
    const V8 z5 = z + dz;
    const V8 k7 = f(z5);
    const V8 err = h * (e1 * k1 + e3 * k3 + e4 * k4 + e5 * k5 + e6 * k6 + e7 * k7);
    double norm = 0.0;
    for (int i = 0; i < 8; ++i)
    {
      const double sc = this->AbsTol + this->RelTol * std::max(std::abs(z[i]), std::abs(z5[i]));
      norm = std::max(norm, std::abs(err[i]) / sc);
    }
    if (!std::isfinite(norm))
    {
      h *= 0.25;
      ++st.rejectedSteps;
      continue;
    }
    const double factor = std::clamp(0.9 * std::pow(std::max(norm, 1e-10), -0.2), 0.2, 5.0);
    if (norm <= 1.0)
    {
      s.increment(dz.head<4>(), dz.tail<4>());
      s.lastSlope = k7;
      s.hasLastSlope = true;
      hNext = h * factor;
      return true;
    }
    ++st.rejectedSteps;
    h *= std::max(factor, 0.1);
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
double PoincareTimeTransform::value(const Vec4& x, const Vec4& p) const
{
  return this->timeScale(x) * this->Base.value(x, p);
}

double PoincareTimeTransform::gradient(const Vec4& x, const Vec4& p, Vec4& dKdx, Vec4& dKdp) const
{
  // ∇K = g ∇H + H ∇g: the H ∇g term vanishes on the light cone but keeps K's flow Hamiltonian.
  Vec4 dg;
  double r;
  const double H = this->Base.gradientAndRadius(x, p, dKdx, dKdp, r, dg);
  const double g = r - this->Horizon;
  dKdx = g * dKdx + H * dg;
  dKdp *= g;
  return g * H;
}
}
