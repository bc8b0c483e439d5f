// The parameters that pick a spacetime: the hole's mass M, spin a and charge Q (geometric units).
// One value, so that scenes, stored frame keys and interpolated movie frames carry the same three
// numbers together. Which spacetime they make is asrt::makeSpacetime's (Spacetime.h).
#ifndef asrt_SpacetimeParameters_h
#define asrt_SpacetimeParameters_h

namespace asrt
{
struct SpacetimeParameters
{
  double mass = 0;
  double spin = 0;
  double charge = 0;

  bool operator==(const SpacetimeParameters& o) const
  {
    return this->mass == o.mass && this->spin == o.spin && this->charge == o.charge;
  }
  bool operator!=(const SpacetimeParameters& o) const { return !(*this == o); }
};
}

#endif
