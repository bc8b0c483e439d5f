// Shared algebra of the spherically symmetric Kerr–Schild forms g^{μν} = η^{μν} − f(r) l^μ l^ν with
// l^μ = (−1, x/r, y/r, z/r). Schwarzschild and Reissner–Nordström differ only in f(r).
#ifndef asrt_SphericalKerrSchild_h
#define asrt_SphericalKerrSchild_h

#include "AsrtTypes.h"

#include <cmath>

namespace asrt
{
namespace detail
{
/// H and its analytic gradient, given 1/r and f(r), f'(r) already evaluated at r = |x| (the
/// caller's one division: sqrt and division latency dominate this function).
/// With s = l^μ p_μ = −p_t + n·p: H = ½(η p p − f s²), ∂s/∂x_j = (p_j − n_j n·p)/r.
inline double sphericalKerrSchildGradient(const Vec4& x, const Vec4& p, double inv, double f,
                                          double fPrime, Vec4& dHdx, Vec4& dHdp)
{
  const double nx = x[1] * inv, ny = x[2] * inv, nz = x[3] * inv;
  const double np = nx * p[1] + ny * p[2] + nz * p[3];
  const double s = -p[0] + np;
  const double fs = f * s;
  dHdp[0] = -p[0] + fs;
  dHdp[1] = p[1] - fs * nx;
  dHdp[2] = p[2] - fs * ny;
  dHdp[3] = p[3] - fs * nz;
  const double radial = -0.5 * fPrime * s * s;
  const double tangential = -fs * inv;
  dHdx[0] = 0.0;
  dHdx[1] = radial * nx + tangential * (p[1] - nx * np);
  dHdx[2] = radial * ny + tangential * (p[2] - ny * np);
  dHdx[3] = radial * nz + tangential * (p[3] - nz * np);
  return 0.5 * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - f * s * s);
}

/// The same with r = |x| and ∇r = (0, x/r) handed back, for time transformations.
template<class F>
inline double sphericalGradientAndRadius(const Vec4& x, const Vec4& p, const F& fAndSlope,
                                         Vec4& dHdx, Vec4& dHdp, double& r, Vec4& dr)
{
  r = x.tail<3>().norm();
  const double inv = 1.0 / r;
  dr << 0.0, x[1] * inv, x[2] * inv, x[3] * inv;
  double f, fPrime;
  fAndSlope(r, inv, f, fPrime);
  return sphericalKerrSchildGradient(x, p, inv, f, fPrime, dHdx, dHdp);
}

inline Mat4 sphericalKerrSchildInverseMetric(const Vec4& x, double f)
{
  const double r = x.tail<3>().norm();
  const Vec4 l(-1.0, x[1] / r, x[2] / r, x[3] / r);
  Mat4 g = Mat4::Identity();
  g(0, 0) = -1.0;
  g -= f * l * l.transpose();
  return g;
}

inline Mat4 sphericalKerrSchildMetric(const Vec4& x, double f)
{
  const double r = x.tail<3>().norm();
  const Vec4 l(1.0, x[1] / r, x[2] / r, x[3] / r);
  Mat4 g = Mat4::Identity();
  g(0, 0) = -1.0;
  g += f * l * l.transpose();
  return g;
}

inline double sphericalRadiusGradient(const Vec4& x, Vec4& grad)
{
  const double r = x.tail<3>().norm();
  grad << 0.0, x[1] / r, x[2] / r, x[3] / r;
  return r;
}
}
}

#endif
