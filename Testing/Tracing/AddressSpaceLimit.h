// A bound on the test process's address space while a test reads hostile input: if the code under
// test allocates without bound (reads /dev/zero whole, believes a huge image header), the
// allocation fails and the test fails, instead of the machine running out of memory.
#ifndef asrt_AddressSpaceLimit_h
#define asrt_AddressSpaceLimit_h

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace asrt
{
namespace testing
{
class AddressSpaceLimit
{
public:
  /// Allows `extraBytes` beyond what the process has mapped now.
  explicit AddressSpaceLimit(double extraBytes)
  {
    this->Active = getrlimit(RLIMIT_AS, &this->Previous) == 0;
    std::ifstream statm("/proc/self/statm");
    double pages = 0;
    if (!(statm >> pages) || !this->Active)
    {
      this->Active = false;
      return;
    }
    rlimit bounded = this->Previous;
    const double limit = pages * sysconf(_SC_PAGE_SIZE) + extraBytes;
    if (this->Previous.rlim_max != RLIM_INFINITY && limit > this->Previous.rlim_max)
      return;
    bounded.rlim_cur = static_cast<rlim_t>(limit);
    this->Active = setrlimit(RLIMIT_AS, &bounded) == 0;
  }
  ~AddressSpaceLimit()
  {
    if (this->Active)
      setrlimit(RLIMIT_AS, &this->Previous);
  }
  AddressSpaceLimit(const AddressSpaceLimit&) = delete;
  AddressSpaceLimit& operator=(const AddressSpaceLimit&) = delete;

private:
  rlimit Previous{};
  bool Active = false;
};
}
}

#endif
