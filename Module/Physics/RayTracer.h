// Tracing one ray to its end: the loop that steps a Propagator and decides termination.
#ifndef asrt_RayTracer_h
#define asrt_RayTracer_h

#include "Propagator.h"

namespace asrt
{
struct TraceOptions
{
  double escapeRadius = 1000.0; ///< escaped once r ≥ this and moving outwards
  double horizonEpsilon = 1e-3; ///< captured once r ≤ r_+ (1 + ε)
  long maxSteps = 200000;       ///< step budget
  /// A ray whose |H| exceeds this times |p|² (Euclidean, the scale of the terms that cancel in H)
  /// has left the light cone: the integrator diverged, and whatever it "escaped" to is not a light
  /// ray. It ends as a numerical failure.
  double maxHamiltonianError = 1e-3;
  /// Where the scene lets a propagator skip object tests (none by default); see FarField.
  FarField farField;
};

struct TraceResult
{
  Termination termination = Termination::Running;
  long steps = 0;
  long evaluations = 0;
  double affineLength = 0; ///< λ_end − λ_start
  double winding = 0;      ///< accumulated angle swept around the origin (radians)
  double maxAbsH = 0;      ///< largest |H| at step ends
  PhasePoint final;

  /// Image order: the number of half-turns, floor(winding / π).
  int imageOrder() const;
};

/// Called for each step; return true to stop the ray there (a hit). The visitor may keep
/// whatever it wants from the segment.
using SegmentVisitor = std::function<bool(const Segment&)>;

/// Traces from `start` until escape, capture, the step budget, numerical failure or a hit.
/// `prop` is restarted at `start`. The winding is summed per step (compensated) from the angle
/// between consecutive positions, so it stays exact through many turns.
ASRTPHYSICS_EXPORT TraceResult traceRay(const Spacetime& st, Propagator& prop,
                                        const PhasePoint& start, const TraceOptions& opts,
                                        const SegmentVisitor& visitor = nullptr);
}

#endif
