#include "Measurements.h"

#include "Analytic.h"
#include "Spacetime.h"
#include "vtkGeodesicSource.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace asrt
{
namespace tools
{
double Deflection::relativeError() const
{
  return std::abs(this->measured / this->exact - 1.0);
}

Deflection schwarzschildDeflection(const IntegratorConfig& cfg, double b)
{
  if (!(b > 3.0 * std::sqrt(3.0)))
  {
    std::ostringstream os;
    os << "impact parameter " << b << " M is not above b_c = 3√3 M = 5.196 M";
    throw InvalidParameter(os.str());
  }
  const SchwarzschildSpacetime st(1.0);
  const double R = std::max(1000.0, 20.0 * b);
  PhasePoint z;
  z.x = Vec4(0, R, 0, 0);
  z.p = completeNullMomentum(st, z.x, Vec4(-1, 0, b / R, 0), Vec4(0, 1, 0, 0), false);
  TraceOptions options;
  options.escapeRadius = R;
  const auto propagator = makePropagator(st, cfg);
  Deflection d;
  d.trace = traceRay(st, *propagator, z, options);
  // The ray starts and ends at finite radii: add the sweep of the exact orbit beyond each end.
  d.measured = d.trace.winding + analytic::sweepToInfinity(b, 1.0, R) +
               analytic::sweepToInfinity(b, 1.0, d.trace.final.x.tail<3>().norm()) - M_PI;
  d.exact = analytic::darwinDeflection(analytic::closestApproach(b, 1.0), 1.0);
  return d;
}

ImageLoader vtkImageLoader()
{
  return [](const std::string& path)
  {
    ImagePixels px;
    vtkGeodesicSource::LoadImagePixels(path, px.width, px.height, px.rgb);
    return px;
  };
}
}
}
