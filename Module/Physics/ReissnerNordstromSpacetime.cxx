#include "Spacetime.h"
#include "SphericalKerrSchild.h"

#include <cmath>
#include <sstream>

namespace asrt
{
ReissnerNordstromSpacetime::ReissnerNordstromSpacetime(double mass, double charge)
  : Spacetime(mass)
  , Charge(charge)
{
  requireFinite(mass, "mass");
  requireFinite(charge, "charge");
  if (!(mass > 0.0))
  {
    std::ostringstream os;
    os << "Reissner-Nordstrom mass must be positive, got " << mass;
    throw InvalidParameter(os.str());
  }
  if (std::abs(charge) > mass)
  {
    std::ostringstream os;
    os << "charge |Q| = " << exactNumber(std::abs(charge))
       << " exceeds the mass M = " << exactNumber(mass)
       << ": a naked singularity, not a black hole";
    throw InvalidParameter(os.str());
  }
}

double ReissnerNordstromSpacetime::gradient(const Vec4& x, const Vec4& p, Vec4& dHdx,
                                            Vec4& dHdp) const
{
  const double inv = 1.0 / x.tail<3>().norm();
  const double q2 = this->Charge * this->Charge;
  const double f = (2.0 * this->Mass - q2 * inv) * inv;
  const double fPrime = (-2.0 * this->Mass + 2.0 * q2 * inv) * inv * inv;
  return detail::sphericalKerrSchildGradient(x, p, inv, f, fPrime, dHdx, dHdp);
}

double ReissnerNordstromSpacetime::gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx,
                                                     Vec4& dHdp, double& r, Vec4& dr) const
{
  const double M = this->Mass, q2 = this->Charge * this->Charge;
  return detail::sphericalGradientAndRadius(
    x, p,
    [M, q2](double, double inv, double& f, double& fPrime)
    {
      f = (2.0 * M - q2 * inv) * inv;
      fPrime = (-2.0 * M + 2.0 * q2 * inv) * inv * inv;
    },
    dHdx, dHdp, r, dr);
}

double ReissnerNordstromSpacetime::radiusGradient(const Vec4& x, Vec4& grad) const
{
  return detail::sphericalRadiusGradient(x, grad);
}

Mat4 ReissnerNordstromSpacetime::inverseMetric(const Vec4& x) const
{
  const double r = x.tail<3>().norm();
  return detail::sphericalKerrSchildInverseMetric(
    x, (2.0 * this->Mass - this->Charge * this->Charge / r) / r);
}

Mat4 ReissnerNordstromSpacetime::metric(const Vec4& x) const
{
  const double r = x.tail<3>().norm();
  return detail::sphericalKerrSchildMetric(x, (2.0 * this->Mass - this->Charge * this->Charge / r) /
                                                r);
}

double ReissnerNordstromSpacetime::outerHorizon() const
{
  const double M = this->Mass, Q = this->Charge;
  return M + std::sqrt(std::max(0.0, M * M - Q * Q));
}

double ReissnerNordstromSpacetime::innerHorizon() const
{
  const double M = this->Mass, Q = this->Charge;
  return M - std::sqrt(std::max(0.0, M * M - Q * Q));
}

std::optional<PhotonOrbitRadii> ReissnerNordstromSpacetime::photonOrbits() const
{
  const double M = this->Mass, Q = this->Charge;
  const double r = 0.5 * (3.0 * M + std::sqrt(9.0 * M * M - 8.0 * Q * Q));
  return PhotonOrbitRadii{ r, r };
}

double ReissnerNordstromSpacetime::criticalImpactParameter() const
{
  const double r = this->photonOrbits()->prograde;
  const double M = this->Mass, Q = this->Charge;
  return r / std::sqrt(1.0 - 2.0 * M / r + Q * Q / (r * r));
}
}
