// Cancelling a write that is under way: a caller's predicate (an interrupt flag, say) is polled by
// a thread of its own while the write's statements run, and once it turns true the statements
// under way on the write's connections are cancelled on the server (PQcancel: a blocking call, a
// wait for a lock or a slow server, returns at once with an error), so that the transaction rolls
// back. Internal to ASRT::Store (RayStore's writes).
#ifndef asrt_StoreCancellation_h
#define asrt_StoreCancellation_h

#include <libpq-fe.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace asrt
{
namespace storage
{
/// The SQLSTATE of a cancelled statement (query_canceled), also given to the StoreError of a
/// cancelled write.
extern const char* const CancelledState;

class WriteCancellation
{
public:
  /// Watches `cancelled` (nothing to watch if empty) for the statements of `connections`.
  WriteCancellation(const std::function<bool()>& cancelled,
                    const std::vector<PGconn*>& connections);
  /// Stops watching; a cancel request already sent may still reach the statement under way.
  ~WriteCancellation();
  WriteCancellation(const WriteCancellation&) = delete;
  WriteCancellation& operator=(const WriteCancellation&) = delete;

  /// Whether the predicate turned true (cheap: for every record produced).
  bool requested() const { return this->Requested.load(std::memory_order_relaxed); }
  /// Throws StoreError "writing the frame was cancelled" if requested() or the predicate is true.
  void check() const;
  /// Stops watching now (before COMMIT: a commit is not to be cancelled half-way).
  void stop();

private:
  void watch();
  std::function<bool()> Cancelled;
  std::vector<PGcancel*> Cancels;
  std::atomic<bool> Requested{ false };
  std::mutex Mutex;
  std::condition_variable Wake;
  bool Stopping = false;
  std::thread Watcher;
};
}
}

#endif
