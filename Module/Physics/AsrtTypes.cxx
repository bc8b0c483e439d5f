#include "AsrtTypes.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace asrt
{
const char* toString(Termination t)
{
  switch (t)
  {
    case Termination::Running:
      return "running";
    case Termination::Escaped:
      return "escaped";
    case Termination::Captured:
      return "captured";
    case Termination::StepBudget:
      return "step budget spent";
    case Termination::NumericalFailure:
      return "numerical failure";
    case Termination::HitObject:
      return "hit object";
  }
  return "unknown";
}

std::string exactNumber(double v)
{
  char text[64];
  const auto [end, error] = std::to_chars(text, text + sizeof(text), v);
  return error == std::errc() ? std::string(text, end) : std::to_string(v);
}

void requireFinite(double v, const char* what)
{
  if (!std::isfinite(v))
  {
    std::ostringstream os;
    os << what << " must be finite, got " << exactNumber(v);
    throw InvalidParameter(os.str());
  }
}
}
