// Initial conditions for test rays, set from physically meaningful parameters whose values the
// tests can check independently (E = −p_t, L = x p_y − y p_x, H = 0).
#ifndef asrt_RayFixtures_h
#define asrt_RayFixtures_h

#include "Analytic.h"
#include "RayTracer.h"
#include "Spacetime.h"

#include <cmath>

namespace asrt
{
namespace testing
{
/// An incoming ray in the equatorial plane at (R, 0, 0) with E = 1 and L_z = b (impact parameter
/// b).
inline PhasePoint equatorialRay(const Spacetime& st, double R, double b)
{
  PhasePoint z;
  z.x = Vec4(0.0, R, 0.0, 0.0);
  // p_y = L/R fixes L = x p_y − y p_x = b; p_x (radial) is the incoming root of H = 0.
  const Vec4 partial(-1.0, 0.0, b / R, 0.0);
  z.p = completeNullMomentum(st, z.x, partial, Vec4(0.0, 1.0, 0.0, 0.0), false);
  return z;
}

/// Deflection of a traced ray: the swept angle between its two finite radii plus the analytic
/// sweep from each to infinity, minus π.
inline double measuredDeflection(const TraceResult& res, const PhasePoint& start, double b,
                                 double M)
{
  const double r0 = start.x.tail<3>().norm();
  const double r1 = res.final.x.tail<3>().norm();
  return res.winding + analytic::sweepToInfinity(b, M, r0) + analytic::sweepToInfinity(b, M, r1) -
         M_PI;
}
}
}

#endif
