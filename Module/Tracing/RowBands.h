// Tracing the rows of a frame a band at a time: the records of FrameTracer::traceRows, handed on
// as they are finished instead of returned together, so that a large frame never holds them all.
#ifndef asrt_RowBands_h
#define asrt_RowBands_h

#include "FrameTracer.h"
#include "RayRecord.h"
#include "asrtTracingModule.h"

#include <cstddef>
#include <functional>

namespace asrt
{
/// Pixels a band traces at once by default: enough for every thread to stay busy, and records
/// (about 270 bytes each) of a few tens of megabytes.
constexpr std::size_t kBandPixels = std::size_t(1) << 16;

/// Traces rows [rowBegin, rowEnd) (clamped to the frame) and hands their records to `sink` in
/// the order of tracer.traceRows(rowBegin, rowEnd), whole rows at a time, each record bit for bit
/// the one traceRows returns, Jacobians included: a row is handed on once the rows either side of
/// it are traced (the rows just outside [rowBegin, rowEnd) are traced for this and dropped, as
/// traceRows does). At most about `bandPixels` records (at least a row), and one row more, are
/// held at once. `progress` is as FrameTracer::tracePixels', over all the rows traced; if it
/// returns false tracing stops and this returns false, the sink having had only the first rows.
ASRTTRACING_EXPORT bool traceRowsInBands(
  const FrameTracer& tracer, int rowBegin, int rowEnd,
  const std::function<void(const RayRecord* records, std::size_t count)>& sink,
  const std::function<bool(double)>& progress = nullptr, std::size_t bandPixels = kBandPixels);
}

#endif
