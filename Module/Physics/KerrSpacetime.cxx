#include "Spacetime.h"

#include <cmath>
#include <sstream>

namespace asrt
{
namespace
{
// Boyer–Lindquist r from Kerr–Schild Cartesian x: the positive root of
// r⁴ − (R² − a²) r² − a² z² = 0 (physics.md). Written to avoid cancellation when R² < a².
inline double kerrRadius(const Vec4& x, double a)
{
  const double R2 = x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
  const double h = 0.5 * (R2 - a * a);
  const double disc = std::sqrt(h * h + a * a * x[3] * x[3]);
  const double r2 = h >= 0.0 ? h + disc : (a * a * x[3] * x[3]) / (disc - h);
  return std::sqrt(r2);
}

// ∂r/∂x^j from implicit differentiation of the quartic: ∂r/∂(x,y) = (x,y) r³/Σ',
// ∂r/∂z = z r (r² + a²)/Σ', with Σ' = r⁴ + a² z².
inline void kerrRadiusGradient(const Vec4& x, double a, double r, Vec4& grad)
{
  const double r2 = r * r;
  const double inv = 1.0 / (r2 * r2 + a * a * x[3] * x[3]);
  grad << 0.0, x[1] * r2 * r * inv, x[2] * r2 * r * inv, x[3] * r * (r2 + a * a) * inv;
}

inline Vec4 kerrNullCovector(const Vec4& x, double a, double r)
{
  const double D = r * r + a * a;
  return Vec4(1.0, (r * x[1] + a * x[2]) / D, (r * x[2] - a * x[1]) / D, x[3] / r);
}

inline double kerrF(const Vec4& x, double M, double a, double r)
{
  return 2.0 * M * r * r * r / (r * r * r * r + a * a * x[3] * x[3]);
}
}

KerrSpacetime::KerrSpacetime(double mass, double spin)
  : Spacetime(mass)
  , Spin(spin)
{
  requireFinite(mass, "mass");
  requireFinite(spin, "spin");
  if (!(mass > 0.0))
  {
    std::ostringstream os;
    os << "Kerr mass must be positive, got " << mass;
    throw InvalidParameter(os.str());
  }
  if (std::abs(spin) > mass)
  {
    std::ostringstream os;
    os << "spin |a| = " << exactNumber(std::abs(spin))
       << " exceeds the mass M = " << exactNumber(mass)
       << ": a naked singularity, not a black hole";
    throw InvalidParameter(os.str());
  }
}

double KerrSpacetime::radius(const Vec4& x) const
{
  return kerrRadius(x, this->Spin);
}

double KerrSpacetime::radiusGradient(const Vec4& x, Vec4& grad) const
{
  const double r = kerrRadius(x, this->Spin);
  kerrRadiusGradient(x, this->Spin, r, grad);
  return r;
}

double KerrSpacetime::gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const
{
  return this->gradientAt(x, p, kerrRadius(x, this->Spin), dHdx, dHdp);
}

double KerrSpacetime::gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp,
                                        double& r, Vec4& dr) const
{
  r = kerrRadius(x, this->Spin);
  kerrRadiusGradient(x, this->Spin, r, dr);
  return this->gradientAt(x, p, r, dHdx, dHdp);
}

double KerrSpacetime::gradientAt(const Vec4& x, const Vec4& p, double r, Vec4& dHdx,
                                 Vec4& dHdp) const
{
  const double M = this->Mass, a = this->Spin;
  const double X = x[1], Y = x[2], Z = x[3];
  const double r2 = r * r;
  const double D = r2 + a * a;
  const double invD = 1.0 / D;
  const double Sigma = r2 * r2 + a * a * Z * Z;
  const double invSigma = 1.0 / Sigma;
  const double lx = (r * X + a * Y) * invD;
  const double ly = (r * Y - a * X) * invD;
  const double lz = Z / r;
  const double f = 2.0 * M * r2 * r * invSigma;
  const double s = -p[0] + lx * p[1] + ly * p[2] + lz * p[3];
  const double fs = f * s;

  dHdp[0] = -p[0] + fs;
  dHdp[1] = p[1] - fs * lx;
  dHdp[2] = p[2] - fs * ly;
  dHdp[3] = p[3] - fs * lz;

  // ∂r/∂x^j
  const double drx = X * r2 * r * invSigma;
  const double dry = Y * r2 * r * invSigma;
  const double drz = Z * r * D * invSigma;
  // ∂s/∂x^j = direct_j + C ∂r/∂x^j, from differentiating l_i at fixed r and then through r.
  const double C =
    (p[1] * (X * D - 2.0 * r * (r * X + a * Y)) + p[2] * (Y * D - 2.0 * r * (r * Y - a * X))) *
      invD * invD -
    p[3] * Z / r2;
  const double dsx = (r * p[1] - a * p[2]) * invD + C * drx;
  const double dsy = (a * p[1] + r * p[2]) * invD + C * dry;
  const double dsz = p[3] / r + C * drz;
  // ∂f/∂x^j = ∂r/∂x^j · 2M r² (3a²z² − r⁴)/Σ'² − δ_jz 4M a² z r³/Σ'².
  const double fr = 2.0 * M * r2 * (3.0 * a * a * Z * Z - r2 * r2) * invSigma * invSigma;
  const double fzDirect = -4.0 * M * a * a * Z * r2 * r * invSigma * invSigma;
  const double halfS2 = 0.5 * s * s;
  dHdx[0] = 0.0;
  dHdx[1] = -(halfS2 * fr * drx + fs * dsx);
  dHdx[2] = -(halfS2 * fr * dry + fs * dsy);
  dHdx[3] = -(halfS2 * (fr * drz + fzDirect) + fs * dsz);
  return 0.5 * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - f * s * s);
}

Mat4 KerrSpacetime::inverseMetric(const Vec4& x) const
{
  const double r = kerrRadius(x, this->Spin);
  Vec4 l = kerrNullCovector(x, this->Spin, r);
  l[0] = -1.0; // raised with η
  Mat4 g = Vec4(-1.0, 1.0, 1.0, 1.0).asDiagonal();
  g -= kerrF(x, this->Mass, this->Spin, r) * l * l.transpose();
  return g;
}

Mat4 KerrSpacetime::metric(const Vec4& x) const
{
  const double r = kerrRadius(x, this->Spin);
  const Vec4 l = kerrNullCovector(x, this->Spin, r);
  Mat4 g = Vec4(-1.0, 1.0, 1.0, 1.0).asDiagonal();
  g += kerrF(x, this->Mass, this->Spin, r) * l * l.transpose();
  return g;
}

double KerrSpacetime::outerHorizon() const
{
  const double M = this->Mass, a = this->Spin;
  return M + std::sqrt(std::max(0.0, M * M - a * a));
}

double KerrSpacetime::innerHorizon() const
{
  const double M = this->Mass, a = this->Spin;
  return M - std::sqrt(std::max(0.0, M * M - a * a));
}

std::optional<PhotonOrbitRadii> KerrSpacetime::photonOrbits() const
{
  // Bardeen, Press & Teukolsky 1972: r = 2M{1 + cos[(2/3) arccos(∓|a|/M)]}, upper sign prograde.
  const double M = this->Mass, chi = std::abs(this->Spin) / M;
  const double pro = 2.0 * M * (1.0 + std::cos(2.0 / 3.0 * std::acos(-chi)));
  const double retro = 2.0 * M * (1.0 + std::cos(2.0 / 3.0 * std::acos(chi)));
  return PhotonOrbitRadii{ pro, retro };
}

double KerrSpacetime::ergosphereRadius(double cosTheta) const
{
  const double M = this->Mass, a = this->Spin;
  return M + std::sqrt(std::max(0.0, M * M - a * a * cosTheta * cosTheta));
}

Vec4 completeNullMomentum(const Spacetime& st, const Vec4& x, const Vec4& p, const Vec4& d,
                          bool largerRoot)
{
  // H(p + μd) = ½[(d·G·d) μ² + 2 (p·G·d) μ + p·G·p], G = g^{μν}(x).
  const Mat4 G = st.inverseMetric(x);
  const double A = d.dot(G * d);
  const double B = p.dot(G * d);
  const double C = p.dot(G * p);
  double mu;
  if (std::abs(A) < 1e-300)
  {
    if (B == 0.0)
      throw InvalidParameter("completeNullMomentum: direction leaves H unchanged");
    mu = -C / (2.0 * B);
  }
  else
  {
    const double disc = B * B - A * C;
    if (!(disc >= 0.0))
      throw InvalidParameter("completeNullMomentum: no null momentum along this direction");
    // Stable quadratic roots.
    const double q = -(B + std::copysign(std::sqrt(disc), B));
    const double m1 = q / A;
    const double m2 = q != 0.0 ? C / q : 0.0;
    mu = largerRoot ? std::max(m1, m2) : std::min(m1, m2);
  }
  return p + mu * d;
}
}
