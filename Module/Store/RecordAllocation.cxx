#include "RecordAllocation.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <thread>

namespace asrt
{
std::vector<RayRecord> allocateRecords(std::size_t count, int threads)
{
  std::vector<RayRecord> records;
  records.reserve(count);
#ifdef MADV_POPULATE_WRITE
  if (threads <= 0)
  {
    threads = int(std::max(1u, std::thread::hardware_concurrency()));
  }
  // Only whole pages inside the reserved block; the kernel may refuse (older kernels: EINVAL),
  // and then construction faults the pages in as usual.
  const std::uintptr_t page = std::uintptr_t(sysconf(_SC_PAGESIZE));
  const std::uintptr_t begin = (std::uintptr_t(records.data()) + page - 1) / page * page;
  const std::uintptr_t end = (std::uintptr_t(records.data() + count)) / page * page;
  constexpr std::uintptr_t minSlice = std::uintptr_t(16) << 20;
  if (end > begin)
  {
    const std::uintptr_t pages = (end - begin) / page;
    const std::uintptr_t slices = std::max<std::uintptr_t>(
      1, std::min<std::uintptr_t>(std::uintptr_t(threads), (end - begin) / minSlice));
    auto populate = [&](std::uintptr_t k)
    {
      const std::uintptr_t a = begin + pages * k / slices * page;
      const std::uintptr_t b = begin + pages * (k + 1) / slices * page;
      madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_WRITE);
    };
    std::vector<std::thread> others;
    for (std::uintptr_t k = 1; k < slices; ++k)
    {
      others.emplace_back(populate, k);
    }
    populate(0);
    for (std::thread& t : others)
    {
      t.join();
    }
  }
#else
  (void)threads;
#endif
  records.resize(count);
  return records;
}

double defaultMemoryLimit()
{
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return 0.8 * (pages > 0 && size > 0 ? static_cast<double>(pages) * size : 8e9);
}
}
