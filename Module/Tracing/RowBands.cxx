#include "RowBands.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace asrt
{
namespace
{
/// Appends the Jacobian inputs of records [from, from + count).
void appendSamples(const std::vector<RayRecord>& records, std::size_t from, std::size_t count,
                   std::vector<JacobianSample>& out)
{
  for (std::size_t k = from; k < from + count; ++k)
    out.push_back(jacobianSample(records[k]));
}
}

bool traceRowsInBands(const FrameTracer& tracer, int rowBegin, int rowEnd,
                      const std::function<void(const RayRecord*, std::size_t)>& sink,
                      const std::function<bool(double)>& progress, std::size_t bandPixels)
{
  const int W = tracer.description().camera.width, H = tracer.description().camera.height;
  rowBegin = std::clamp(rowBegin, 0, H);
  rowEnd = std::clamp(rowEnd, rowBegin, H);
  if (rowEnd == rowBegin || W <= 0)
    return true;
  const std::size_t width = static_cast<std::size_t>(W);
  // A Jacobian needs the rows either side (FrameTracer::computeJacobians): trace one row more at
  // each end of the band, as traceRows does.
  const int first = std::max(0, rowBegin - 1), last = std::min(H, rowEnd + 1);
  const int bandRows = static_cast<int>(std::clamp<std::size_t>(bandPixels / width, 1, H));
  const double total = static_cast<double>(last - first) * W;

  // Rows [from, to) of `records`, whose first row is `firstRow`, anti-aliased in place and handed
  // to the sink; those outside [rowBegin, rowEnd) are dropped, and `records` is left with [from,
  // to) alone. The rows either side of [from, to) are in `records` or in `around`.
  double done = 0;
  std::vector<JacobianSample> bordering;
  auto handOn = [&](std::vector<RayRecord>& records, int firstRow, int from, int to,
                    const std::vector<JacobianSample>& around)
  {
    from = std::max(from, rowBegin);
    to = std::min(to, rowEnd);
    if (from >= to)
      return true;
    bordering = around;
    const int lastRow = firstRow + static_cast<int>(records.size() / width);
    for (int j : { from - 1, to })
      if (j >= firstRow && j < lastRow)
        appendSamples(records, static_cast<std::size_t>(j - firstRow) * width, width, bordering);
    records.resize(static_cast<std::size_t>(to - firstRow) * width);
    records.erase(records.begin(),
                  records.begin() + static_cast<std::ptrdiff_t>(from - firstRow) * W);
    std::function<bool(double)> keepGoing;
    if (progress)
      keepGoing = [&](double) { return progress(done / total); };
    if (!tracer.antialias(records, bordering, keepGoing))
      return false;
    sink(records.data(), records.size());
    return true;
  };

  // The last row traced waits for the row above it; `below` has the samples of the row under it.
  std::vector<RayRecord> held;
  std::vector<JacobianSample> below, edge;
  std::vector<std::pair<int, int>> pixels;
  const int lattice = effectiveGridLattice(tracer.description().rendering);
  for (int b = first; b < last;)
  {
    // On the adaptive grid a band ends on the lattice where it can: a lattice block is then
    // processed by one band, not by the two it would straddle (the records are the same either
    // way).
    int e = b + bandRows;
    if (lattice > 1)
    {
      const int down = e / lattice * lattice;
      e = down > b ? down : (b / lattice + 1) * lattice;
    }
    e = std::min(last, e);
    pixels.clear();
    for (int j = b; j < e; ++j)
      for (int i = 0; i < W; ++i)
        pixels.emplace_back(i, j);
    bool stopped = false;
    const double share = static_cast<double>(pixels.size());
    std::function<bool(double)> bandProgress;
    if (progress)
      bandProgress = [&](double f)
      {
        stopped = !progress((done + f * share) / total);
        return !stopped;
      };
    std::vector<RayRecord> band = tracer.traceCentres(pixels, bandProgress);
    if (stopped)
      return false;
    done += share;

    edge.clear();
    if (!held.empty())
    {
      // Row b − 1 completes row b's Jacobians, and row b those of row b − 1.
      appendSamples(held, 0, width, edge);
      FrameTracer::computeJacobians(band, edge);
      appendSamples(band, 0, width, below);
      FrameTracer::computeJacobians(held, below);
      if (!handOn(held, b - 1, b - 1, b, below))
        return false;
    }
    // Rows b .. e − 2 have both neighbours; row e − 1 waits for row e. The band is anti-aliased
    // in place: what the next band needs of it is taken first.
    std::vector<JacobianSample> nextBelow;
    if (e - b >= 2)
      appendSamples(band, static_cast<std::size_t>(e - 2 - b) * width, width, nextBelow);
    std::vector<RayRecord> nextHeld(band.end() - static_cast<std::ptrdiff_t>(width), band.end());
    if (!handOn(band, b, b, e - 1, edge))
      return false;
    if (e - b >= 2)
      below.swap(nextBelow);
    else
      below.swap(edge); // row e − 2 is the row held before (none before the first band)
    held.swap(nextHeld);
    b = e;
  }
  FrameTracer::computeJacobians(held, below);
  return handOn(held, last - 1, last - 1, last, below);
}
}
