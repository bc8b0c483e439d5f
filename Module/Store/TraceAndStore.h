// Tracing a frame straight into the store: the COPY streams rows while later rows are traced, so
// neither the OpenMP workers nor the database wait for the other to finish.
#ifndef asrt_TraceAndStore_h
#define asrt_TraceAndStore_h

#include "FrameTracer.h"
#include "RayStore.h"
#include "asrtStoreModule.h"

#include <cstdint>
#include <functional>
#include <string>

namespace asrt
{
struct TraceAndStoreOptions
{
  std::string label;
  bool replace = false;
  int rowsPerChunk = 32; ///< rows traced per batch handed to the COPY stream
  /// Called from the calling thread with the fraction of rays stored; return false to abort (the
  /// transaction is rolled back and nothing is stored).
  std::function<bool(double)> progress;
};

/// Traces every pixel of the tracer's frame and stores the frame in one transaction. A tracing
/// thread produces bands of rows (traced with OpenMP, with the halo rows that keep their Jacobians
/// those of the whole frame) while the calling thread streams the finished bands into the COPY.
/// The stored records are exactly those of tracer.traceRows(0, height). Returns the frame id;
/// throws StoreError (database), InvalidParameter (bad frame) or std::runtime_error (aborted),
/// always with nothing stored.
ASRTSTORE_EXPORT std::int64_t traceAndStore(const FrameTracer& tracer, RayStore& store,
                                            const TraceAndStoreOptions& options = {});
}

#endif
