#include "Spacetime.h"
#include "SphericalKerrSchild.h"

#include <cmath>
#include <sstream>

namespace asrt
{
SchwarzschildSpacetime::SchwarzschildSpacetime(double mass)
  : Spacetime(mass)
{
  requireFinite(mass, "mass");
  if (!(mass > 0.0))
  {
    std::ostringstream os;
    os << "Schwarzschild mass must be positive, got " << mass
       << " (use MinkowskiSpacetime for M = 0)";
    throw InvalidParameter(os.str());
  }
}

double SchwarzschildSpacetime::gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const
{
  const double inv = 1.0 / x.tail<3>().norm();
  const double f = 2.0 * this->Mass * inv;
  return detail::sphericalKerrSchildGradient(x, p, inv, f, -f * inv, dHdx, dHdp);
}

double SchwarzschildSpacetime::gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx,
                                                 Vec4& dHdp, double& r, Vec4& dr) const
{
  const double twoM = 2.0 * this->Mass;
  return detail::sphericalGradientAndRadius(
    x, p,
    [twoM](double, double inv, double& f, double& fPrime)
    {
      f = twoM * inv;
      fPrime = -f * inv;
    },
    dHdx, dHdp, r, dr);
}

double SchwarzschildSpacetime::radiusGradient(const Vec4& x, Vec4& grad) const
{
  return detail::sphericalRadiusGradient(x, grad);
}

Mat4 SchwarzschildSpacetime::inverseMetric(const Vec4& x) const
{
  return detail::sphericalKerrSchildInverseMetric(x, 2.0 * this->Mass / x.tail<3>().norm());
}

Mat4 SchwarzschildSpacetime::metric(const Vec4& x) const
{
  return detail::sphericalKerrSchildMetric(x, 2.0 * this->Mass / x.tail<3>().norm());
}

std::optional<PhotonOrbitRadii> SchwarzschildSpacetime::photonOrbits() const
{
  return PhotonOrbitRadii{ 3.0 * this->Mass, 3.0 * this->Mass };
}

double SchwarzschildSpacetime::criticalImpactParameter() const
{
  return 3.0 * std::sqrt(3.0) * this->Mass;
}
}
