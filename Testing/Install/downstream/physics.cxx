// A fact of the Schwarzschild spacetime from ASRT::Physics alone: the photon sphere lies at
// r = 3M (both circular photon orbits), the horizon at r = 2M, and the critical impact parameter
// is b_c = 3 sqrt(3) M (Misner, Thorne & Wheeler, section 25.6).
#include "Spacetime.h"

#include <cmath>
#include <cstdio>

int main()
{
  const double mass = 1.5;
  const asrt::SchwarzschildSpacetime spacetime(mass);
  const auto orbits = spacetime.photonOrbits();
  const bool photonSphere = orbits && std::abs(orbits->prograde - 3 * mass) < 1e-12 &&
                            std::abs(orbits->retrograde - 3 * mass) < 1e-12;
  const bool horizon = std::abs(spacetime.outerHorizon() - 2 * mass) < 1e-12;
  const bool impact =
    std::abs(spacetime.criticalImpactParameter() - 3 * std::sqrt(3.0) * mass) < 1e-12;
  std::printf("photon sphere r = %.15g (3M = %.15g), horizon r = %.15g, b_c = %.15g\n",
              orbits ? orbits->prograde : 0.0, 3 * mass, spacetime.outerHorizon(),
              spacetime.criticalImpactParameter());
  return photonSphere && horizon && impact ? 0 : 1;
}
