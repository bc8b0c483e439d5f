#include "InterruptibleRead.h"

#include "Progress.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace asrt
{
namespace tools
{
namespace
{
/// Closes the descriptor however the reading ends.
struct Descriptor
{
  int fd = -1;
  ~Descriptor()
  {
    if (this->fd >= 0)
      close(this->fd);
  }
};
}

bool waitForDescriptor(int fd, short events)
{
  sigset_t interrupts, previous;
  sigemptyset(&interrupts);
  sigaddset(&interrupts, SIGINT);
  sigaddset(&interrupts, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &interrupts, &previous);
  bool ready = false;
  while (!interruptRequested())
  {
    pollfd p = { fd, events, 0 };
    // ppoll unblocks the signals only while it waits: one that comes after the check above
    // interrupts the wait instead of being lost.
    const int n = ppoll(&p, 1, nullptr, &previous);
    if (n > 0)
    {
      ready = true;
      break;
    }
    if (n < 0 && errno != EINTR)
    {
      ready = true; // let the read or write report the error
      break;
    }
  }
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  return ready;
}

std::string readWholeFile(const std::string& path, std::size_t limit, const std::string& what)
{
  auto failure = [&](const std::string& why)
  { return std::runtime_error("cannot read " + what + " \"" + path + "\": " + why); };
  if (interruptRequested())
    throw ReadInterrupted();
  Descriptor file;
  // Opening a FIFO blocks until someone opens it for writing; an interrupt ends the wait (EINTR).
  while ((file.fd = open(path.c_str(), O_RDONLY | O_CLOEXEC)) < 0)
  {
    if (errno != EINTR)
      throw failure(std::strerror(errno));
    if (interruptRequested())
      throw ReadInterrupted();
  }
  struct stat st;
  if (fstat(file.fd, &st) != 0)
    throw failure(std::strerror(errno));
  if (S_ISDIR(st.st_mode))
    throw failure(std::strerror(EISDIR));
  const std::runtime_error tooLarge(what + " \"" + path + "\" is larger than " +
                                    std::to_string(limit >> 20) + " MiB (" + std::to_string(limit) +
                                    " bytes), the most it may hold");
  if (S_ISREG(st.st_mode) && static_cast<unsigned long long>(st.st_size) > limit)
    throw tooLarge;
  std::string text;
  char chunk[1 << 16];
  while (true)
  {
    if (!waitForDescriptor(file.fd, POLLIN))
      throw ReadInterrupted();
    const ssize_t n = read(file.fd, chunk, sizeof chunk);
    if (n < 0 && (errno == EINTR || errno == EAGAIN))
      continue;
    if (n < 0)
      throw failure(std::strerror(errno));
    if (n == 0)
      return text;
    if (text.size() + static_cast<std::size_t>(n) > limit)
      throw tooLarge;
    text.append(chunk, static_cast<std::size_t>(n));
  }
}
}
}
