#include "Spacetime.h"

#include <memory>
#include <sstream>

namespace asrt
{
std::unique_ptr<Spacetime> makeSpacetime(const SpacetimeParameters& p)
{
  const double mass = p.mass, spin = p.spin, charge = p.charge;
  requireFinite(mass, "mass");
  requireFinite(spin, "spin");
  requireFinite(charge, "charge");
  if (mass < 0.0)
  {
    std::ostringstream os;
    os << "mass must be non-negative, got " << mass;
    throw InvalidParameter(os.str());
  }
  if (mass == 0.0)
  {
    if (spin != 0.0 || charge != 0.0)
    {
      throw InvalidParameter("spin and charge must be 0 when the mass is 0");
    }
    return std::make_unique<MinkowskiSpacetime>();
  }
  if (spin != 0.0 && charge != 0.0)
  {
    throw InvalidParameter("spin and charge together (Kerr-Newman) are not supported");
  }
  if (spin != 0.0)
  {
    return std::make_unique<KerrSpacetime>(mass, spin);
  }
  if (charge != 0.0)
  {
    return std::make_unique<ReissnerNordstromSpacetime>(mass, charge);
  }
  return std::make_unique<SchwarzschildSpacetime>(mass);
}
}
