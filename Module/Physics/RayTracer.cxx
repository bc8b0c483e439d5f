#include "RayTracer.h"

#include <cmath>
#include <limits>

namespace asrt
{
int TraceResult::imageOrder() const
{
  return static_cast<int>(std::floor(this->winding / M_PI));
}

TraceResult traceRay(const Spacetime& st, Propagator& prop, const PhasePoint& start,
                     const TraceOptions& opts, const SegmentVisitor& visitor)
{
  TraceResult res;
  const double rPlus = st.outerHorizon();
  const double captureRadius = rPlus > 0.0 ? rPlus * (1.0 + opts.horizonEpsilon) : 0.0;
  prop.setLimits(opts.escapeRadius, captureRadius);
  prop.setFarField(std::isfinite(opts.farField.objectRadius) ? &opts.farField : nullptr);
  prop.start(start);
  res.final = start;
  if (!start.x.allFinite() || !start.p.allFinite())
  {
    res.termination = Termination::NumericalFailure;
    return res;
  }
  if (st.radius(start.x) <= captureRadius)
  {
    res.termination = Termination::Captured;
    return res;
  }
  // Kahan-compensated sum of the per-step angles about the origin.
  double sum = 0.0, carry = 0.0;
  Segment seg;
  while (res.termination == Termination::Running)
  {
    if (res.steps >= opts.maxSteps)
    {
      res.termination = Termination::StepBudget;
      break;
    }
    seg.sweep = std::numeric_limits<double>::quiet_NaN();
    if (!prop.advance(seg) || !seg.x1.allFinite() || !seg.p1.allFinite())
    {
      res.termination = Termination::NumericalFailure;
      break;
    }
    ++res.steps;
    const Vec3 a = seg.x0.tail<3>(), b = seg.x1.tail<3>();
    const double dphi = std::isnan(seg.sweep) ? std::atan2(a.cross(b).norm(), a.dot(b)) : seg.sweep;
    const double y = dphi - carry;
    const double t = sum + y;
    carry = (t - sum) - y;
    sum = t;
    const double absH = std::abs(st.value(seg.x1, seg.p1));
    res.maxAbsH = std::max(res.maxAbsH, absH);
    if (!(absH <= opts.maxHamiltonianError * seg.p1.squaredNorm()))
    {
      res.termination = Termination::NumericalFailure;
      break;
    }
    if (visitor && visitor(seg))
    {
      res.termination = Termination::HitObject;
      break;
    }
    const double r = st.radius(seg.x1);
    if (r <= captureRadius)
    {
      res.termination = Termination::Captured;
    }
    else if (r >= opts.escapeRadius && b.dot(seg.d1.tail<3>()) > 0.0)
    {
      res.termination = Termination::Escaped;
    }
  }
  res.winding = sum;
  res.final = prop.state();
  res.affineLength = prop.affineParameter();
  res.evaluations = prop.evaluations();
  return res;
}
}
