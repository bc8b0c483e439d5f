// Large vectors of ray records, their memory faulted in by several threads at once.
#ifndef asrt_RecordAllocation_h
#define asrt_RecordAllocation_h

#include "RayRecord.h"
#include "asrtStoreModule.h"

#include <cstddef>
#include <vector>

namespace asrt
{
/// `count` default records in a new vector whose memory `threads` threads (0: one per core) fault
/// in at once before the records are constructed. Faulting in fresh pages (the kernel clears each
/// one) is most of what filling a large result costs, and the kernel's batched population
/// (MADV_POPULATE_WRITE, Linux 5.14) shares it out between threads; on other kernels the records
/// are simply constructed. RayStore::readFrame() returns its records in such a vector.
ASRTSTORE_EXPORT std::vector<RayRecord> allocateRecords(std::size_t count, int threads = 0);

/// The bytes a read may allocate when its caller sets no limit: 80 % of this machine's physical
/// memory (of 8 GB when the system does not say), as vtkGeodesicSource allows a trace. Beyond
/// it the kernel would rather kill the process than fail the allocation.
ASRTSTORE_EXPORT double defaultMemoryLimit();
}

#endif
