#include "Analytic.h"

#include <algorithm>
#include <cmath>

namespace asrt
{
namespace analytic
{
double impactParameter(double r0, double M)
{
  return r0 / std::sqrt(1.0 - 2.0 * M / r0);
}

double closestApproach(double b, double M)
{
  return 2.0 * b / std::sqrt(3.0) * std::cos(std::acos(-3.0 * std::sqrt(3.0) * M / b) / 3.0);
}

double darwinDeflection(double r0, double M)
{
  const long double R = r0, m = M;
  const long double Q = std::sqrt((R - 2 * m) * (R + 6 * m));
  const long double k2 = (Q - R + 6 * m) / (2 * Q);
  const long double sin2phi = (Q - R + 2 * m) / (Q - R + 6 * m);
  const long double k = std::sqrt(k2);
  const long double phi0 = std::asin(std::sqrt(sin2phi));
  const long double K = std::comp_ellint_1(k);
  const long double F = std::ellint_1(k, phi0);
  return static_cast<double>(-M_PIl + 4 * std::sqrt(R / Q) * (K - F));
}

double weakFieldDeflection(double b, double M)
{
  const double x = M / b;
  return 4 * x + 15 * M_PI / 4 * x * x + 128.0 / 3 * x * x * x + 3465 * M_PI / 64 * x * x * x * x +
         3584.0 / 5 * x * x * x * x * x;
}

double strongFieldDeflection(double b, double M)
{
  const double bc = 3.0 * std::sqrt(3.0) * M;
  return -std::log(b / bc - 1.0) + std::log(216.0 * (7.0 - 4.0 * std::sqrt(3.0))) - M_PI;
}

double sweepToInfinity(double b, double M, double r)
{
  // 20-point Gauss–Legendre on each of 16 panels of [0, 1/r]. The integrand is smooth there as
  // long as 1/r stays well below the turning point 1/r0.
  static const long double x[10] = {
    0.0765265211334973337546404093988382L, 0.2277858511416450780804961953685746L,
    0.3737060887154195606725481770249272L, 0.5108670019508270980043640509552510L,
    0.6360536807265150254528366962262859L, 0.7463319064601507926143050703556416L,
    0.8391169718222188233945290617015207L, 0.9122344282513259058677524412032981L,
    0.9639719272779137912676661311972772L, 0.9931285991850949247861223884713203L
  };
  static const long double w[10] = {
    0.1527533871307258506980843319550976L, 0.1491729864726037467878287370019694L,
    0.1420961093183820513292983250671649L, 0.1316886384491766268984944997481631L,
    0.1181945319615184173123773777113823L, 0.1019301198172404350367501354803499L,
    0.0832767415767047487247581432220463L, 0.0626720483341090635695065351870417L,
    0.0406014298003869413310399522749396L, 0.0176140071391521183118619623518529L
  };
  const long double ib2 = 1.0L / ((long double)b * b), m = M, uEnd = 1.0L / r;
  auto integrand = [&](long double u) { return 1.0L / std::sqrt(ib2 - u * u + 2 * m * u * u * u); };
  constexpr int panels = 16;
  long double sum = 0;
  for (int k = 0; k < panels; ++k)
  {
    const long double a = uEnd * k / panels, c = uEnd * (k + 1) / panels;
    const long double mid = 0.5L * (a + c), half = 0.5L * (c - a);
    for (int i = 0; i < 10; ++i)
    {
      sum += half * w[i] * (integrand(mid - half * x[i]) + integrand(mid + half * x[i]));
    }
  }
  return static_cast<double>(sum);
}

double shadowAngularRadius(double ro, double M)
{
  const double bc = 3.0 * std::sqrt(3.0) * M;
  return std::asin(std::min(1.0, bc / ro * std::sqrt(1.0 - 2.0 * M / ro)));
}
}
}
