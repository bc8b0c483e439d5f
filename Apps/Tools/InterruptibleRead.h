// Reading a whole file that may block (a FIFO, a device, a slow network file system) in a way that
// Ctrl-C or SIGTERM can stop: the handler of installInterruptHandler() has no SA_RESTART, so a
// blocking open returns EINTR, and every read waits in ppoll(), which the signal always wakes
// (signals are blocked between the check of the request and the wait, so none is missed).
#ifndef asrt_tools_InterruptibleRead_h
#define asrt_tools_InterruptibleRead_h

#include <cstddef>
#include <stdexcept>
#include <string>

namespace asrt
{
namespace tools
{
/// Thrown when an interrupt stopped the reading.
struct ReadInterrupted : std::runtime_error
{
  ReadInterrupted()
    : std::runtime_error("interrupted while reading")
  {
  }
};

/// Waits until `fd` is ready for `events` (POLLIN, POLLOUT) or reports an error; false if an
/// interrupt was requested before or during the wait.
bool waitForDescriptor(int fd, short events);

/// The content of `path`, at most `limit` bytes. Throws std::runtime_error: "cannot read <what>
/// \"<path>\": <reason>" (no such file, a directory, ...), or "<what> \"<path>\" is larger than
/// N MiB ..." past the limit; ReadInterrupted when interruptRequested() is or becomes true before
/// the end.
std::string readWholeFile(const std::string& path, std::size_t limit, const std::string& what);
}
}

#endif
