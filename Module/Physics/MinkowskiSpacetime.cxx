#include "Spacetime.h"

namespace asrt
{
double MinkowskiSpacetime::gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const
{
  dHdx.setZero();
  dHdp << -p[0], p[1], p[2], p[3];
  return this->value(x, p);
}

double MinkowskiSpacetime::radiusGradient(const Vec4& x, Vec4& grad) const
{
  const double r = x.tail<3>().norm();
  grad << 0.0, x[1] / r, x[2] / r, x[3] / r;
  return r;
}

Mat4 MinkowskiSpacetime::inverseMetric(const Vec4&) const
{
  return Vec4(-1.0, 1.0, 1.0, 1.0).asDiagonal();
}

Mat4 MinkowskiSpacetime::metric(const Vec4&) const
{
  return Vec4(-1.0, 1.0, 1.0, 1.0).asDiagonal();
}
}
