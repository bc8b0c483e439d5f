// Cancelling a write or a read that is under way: a caller's predicate (an interrupt flag, say) is
// polled by a thread of its own while the statements run, and once it turns true the statements
// under way on the connections are cancelled on the server (PQcancel: a blocking call, a wait for
// a lock or a slow server, returns at once with an error), so that the transaction rolls back.
// Internal to ASRT::Store (RayStore's writes and reads).
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
/// cancelled write or read.
extern const char* const CancelledState;
/// What a cancelled write and a cancelled read throw.
extern const char* const WriteCancelledMessage;
extern const char* const ReadCancelledMessage;

class StatementCancellation
{
public:
  /// Watches `cancelled` (nothing to watch if empty) for the statements of `connections`; check()
  /// throws `message`.
  StatementCancellation(const std::function<bool()>& cancelled,
                        const std::vector<PGconn*>& connections,
                        const char* message = WriteCancelledMessage);
  /// Stops watching; a cancel request already sent may still reach the statement under way.
  ~StatementCancellation();
  StatementCancellation(const StatementCancellation&) = delete;
  StatementCancellation& operator=(const StatementCancellation&) = delete;

  /// Whether the predicate turned true (cheap: for every record produced).
  bool requested() const { return this->Requested.load(std::memory_order_relaxed); }
  /// Throws StoreError with the message, SQLSTATE CancelledState, if requested() or the
  /// predicate is true.
  void check() const;
  /// Stops watching now (before COMMIT: a commit is not to be cancelled half-way).
  void stop();

private:
  void watch();
  std::function<bool()> Cancelled;
  const char* Message;
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
