#include "RetraceRays.h"

#include "FrameTracer.h"

#include <algorithm>
#include <string>

namespace asrt
{
RetraceRays& RetraceRays::operator+=(const RetraceRays& o)
{
  this->centres += o.centres;
  this->neighbours += o.neighbours;
  this->midpoints += o.midpoints;
  this->samples += o.samples;
  return *this;
}

RetraceRays predictRetraceRays(const std::vector<RayRecord>& frame, int width, int height,
                               const std::vector<std::pair<int, int>>& pixels,
                               const std::vector<JacobianSample>& border)
{
  if (width <= 0 || height <= 0 ||
      frame.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw InvalidParameter("re-trace rays: " + std::to_string(frame.size()) +
                           " records for a frame of " + std::to_string(width) + " x " +
                           std::to_string(height));
  RetraceRays rays;
  auto at = [&](int i, int j) -> const RayRecord&
  { return frame[static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + i]; };
  static constexpr int kDirections[4][2] = { { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } };
  // Each differing edge once: by its midpoint in half-pixel coordinates, as the tracer keys it.
  std::vector<std::pair<int, int>> edges;
  for (const auto& [i, j] : pixels)
  {
    if (i < 0 || i >= width || j < 0 || j >= height)
      throw InvalidParameter("re-trace rays: pixel (" + std::to_string(i) + ", " +
                             std::to_string(j) + ") outside the frame");
    const RayRecord& r = at(i, j);
    int charged = 0;
    for (const auto& d : kDirections)
    {
      const int ni = i + d[0], nj = j + d[1];
      if (ni < 0 || ni >= width || nj < 0 || nj >= height)
        continue;
      const RayRecord& n = at(ni, nj);
      if (n.termination == Termination::Running || endsAlike(r, n))
        continue;
      edges.emplace_back(2 * i + d[0], 2 * j + d[1]);
      charged += d[0] + d[1] > 0;
    }
    rays.centres += 1;
    rays.samples += std::max(0, r.raysPerPixel - (r.traced ? 1 : 0) - charged);
  }
  std::sort(edges.begin(), edges.end());
  rays.midpoints = static_cast<double>(std::unique(edges.begin(), edges.end()) - edges.begin());
  rays.neighbours = static_cast<double>(neighboursToTrace(pixels, width, height, border).size());
  return rays;
}
}
