#include "StoreCancellation.h"

#include "RayStore.h"

#include <chrono>

namespace asrt
{
namespace storage
{
const char* const CancelledState = "57014";
const char* const WriteCancelledMessage = "writing the frame was cancelled; nothing was stored";
const char* const ReadCancelledMessage = "reading from the store was cancelled";

namespace
{
/// How often the predicate is asked; also how often a cancel is sent again while the write has
/// not yet stopped (a request that reached the server between two statements cancels nothing).
constexpr std::chrono::milliseconds PollInterval{ 20 };
}

StatementCancellation::StatementCancellation(const std::function<bool()>& cancelled,
                                             const std::vector<PGconn*>& connections,
                                             const char* message)
  : Cancelled(cancelled)
  , Message(message)
{
  if (!this->Cancelled)
  {
    return;
  }
  for (PGconn* conn : connections)
  {
    if (PGcancel* c = PQgetCancel(conn))
    {
      this->Cancels.push_back(c);
    }
  }
  this->Watcher = std::thread([this] { this->watch(); });
}

StatementCancellation::~StatementCancellation()
{
  this->stop();
  for (PGcancel* c : this->Cancels)
  {
    PQfreeCancel(c);
  }
}

void StatementCancellation::check() const
{
  // The predicate itself too: it may have turned true since the watcher last asked.
  if (this->requested() || (this->Cancelled && this->Cancelled()))
  {
    throw StoreError(this->Message, CancelledState);
  }
}

void StatementCancellation::stop()
{
  {
    std::lock_guard<std::mutex> lock(this->Mutex);
    this->Stopping = true;
  }
  this->Wake.notify_all();
  if (this->Watcher.joinable())
  {
    this->Watcher.join();
  }
}

void StatementCancellation::watch()
{
  std::unique_lock<std::mutex> lock(this->Mutex);
  while (!this->Wake.wait_for(lock, PollInterval, [this] { return this->Stopping; }))
  {
    if (!this->requested() && !this->Cancelled())
    {
      continue;
    }
    this->Requested.store(true, std::memory_order_relaxed);
    for (PGcancel* c : this->Cancels)
    {
      char why[256];
      PQcancel(c, why, int(sizeof why)); // best effort: the write's own checks stop it too
    }
  }
}
}
}
