// Closed-form results for Schwarzschild light rays: the independent truth the integrators are
// measured against (physics.md; Darwin 1959 in the form of Iyer & Petters 2007; Bozza 2002).
#ifndef asrt_Analytic_h
#define asrt_Analytic_h

#include "asrtPhysicsModule.h"

namespace asrt
{
namespace analytic
{
/// b = r0 / √(1 − 2M/r0): impact parameter of the ray whose closest approach is r0.
ASRTPHYSICS_EXPORT double impactParameter(double r0, double M);
/// r0 = (2b/√3) cos[⅓ arccos(−3√3 M/b)], for b > b_c.
ASRTPHYSICS_EXPORT double closestApproach(double b, double M);
/// Exact deflection angle α̂ for closest approach r0 > 3M (Darwin).
ASRTPHYSICS_EXPORT double darwinDeflection(double r0, double M);
/// Weak-field series 4M/b + (15π/4)(M/b)² + (128/3)(M/b)³ + (3465π/64)(M/b)⁴ + (3584/5)(M/b)⁵.
ASRTPHYSICS_EXPORT double weakFieldDeflection(double b, double M);
/// Strong-field limit −ln(b/b_c − 1) + ln(216(7 − 4√3)) − π (Bozza 2002).
ASRTPHYSICS_EXPORT double strongFieldDeflection(double b, double M);
/// Angle swept by the ray of impact parameter b between radius r (r ≫ r0, on the unbound branch)
/// and infinity: ∫₀^{1/r} du / √(1/b² − u² + 2Mu³), by Gauss–Legendre quadrature in long double.
/// Added to the angle swept between two finite radii it gives the full π + α̂.
ASRTPHYSICS_EXPORT double sweepToInfinity(double b, double M, double r);
/// Half-angle of the shadow seen by a static observer at r_o: sin α = (b_c/r_o)√(1 − 2M/r_o).
ASRTPHYSICS_EXPORT double shadowAngularRadius(double ro, double M);
}
}

#endif
