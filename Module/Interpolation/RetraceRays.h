// What re-tracing some pixels of a frame costs, in rays integrated, predicted from the whole
// frame's records at the same parameters without tracing a ray: the movie planner's measure of an
// interpolated frame's re-trace (MoviePlan.h), in the unit of a whole frame's cost
// (FrameTracer::raysIntegrated).
//
// FrameTracer::tracePixels, with the scattered-pixel rendering (lattice 1), integrates for one
// list of pixels:
//  - the centre ray of each pixel, and of each edge neighbour neither in the list (edgeNeighbours)
//    nor given beside it (FrameTracer::tracePixelsBeside), which it traces for the Jacobians and
//    the anti-aliasing judgement and then drops;
//  - one ray through the midpoint of every edge between 4-adjacent centres that end differently
//    (another object, image order or termination), one of them in the list: each edge once a list;
//  - the anti-aliasing samples of the pixels in the list.
// The first two follow from the pixels and the frame's centre rays. The samples are the whole
// frame's: a record's raysPerPixel less its centre ray (when traced) and the midpoint rays charged
// to it there (those of its right and upper edges, FrameTracer::antialias). On the adaptive grid a
// pixel the grid filled was judged from interpolated neighbours, so its samples may differ a
// little from the re-trace's; a pixel re-traced again in a later list (a neighbour of it) counts
// again, as the tracer traces it again.
#ifndef asrt_RetraceRays_h
#define asrt_RetraceRays_h

#include "RayRecord.h"
#include "asrtInterpolationModule.h"

#include <utility>
#include <vector>

namespace asrt
{
/// The rays re-tracing one list of pixels integrates, by kind.
struct RetraceRays
{
  double centres = 0;    ///< the pixels' own centre rays
  double neighbours = 0; ///< the edge neighbours' centre rays, traced and dropped
  double midpoints = 0;  ///< edge midpoints
  double samples = 0;    ///< anti-aliasing samples of the pixels
  double total() const { return centres + neighbours + midpoints + samples; }
  RetraceRays& operator+=(const RetraceRays& o);
};

/// The rays FrameTracer::tracePixelsBeside integrates to re-trace `pixels` (each once, inside the
/// frame) beside the neighbour samples `border` (empty: tracePixels, every neighbour traced) of
/// the frame whose whole records, width × height in pixel order (record p is pixel
/// (p mod width, p / width)), are `frame`: the edge neighbours given in `border` are not traced.
/// The midpoints and samples are counted from the frame's own neighbours. Throws
/// InvalidParameter for a frame of another size or a pixel outside it.
ASRTINTERPOLATION_EXPORT RetraceRays predictRetraceRays(
  const std::vector<RayRecord>& frame, int width, int height,
  const std::vector<std::pair<int, int>>& pixels, const std::vector<JacobianSample>& border = {});
}

#endif
