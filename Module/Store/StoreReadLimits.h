// Limits on the store's reads (RayStore::setReadLockTimeout, setReadCancellation): a lock timeout
// on their statements, so that a read that meets a table another session has locked gives up with
// a message naming the table instead of waiting for as long as the lock is held; and their
// cancellation by a caller's predicate (an interrupt flag), which a wait for a lock does not
// delay. Internal to ASRT::Store (RayStore's reads).
#ifndef asrt_StoreReadLimits_h
#define asrt_StoreReadLimits_h

#include "StoreCancellation.h"

#include <libpq-fe.h>

#include <chrono>
#include <functional>
#include <vector>

namespace asrt
{
namespace storage
{
struct ReadLimits
{
  std::chrono::milliseconds lockTimeout; ///< zero: a read waits as long as a lock is held
  std::function<bool()> cancelled;       ///< empty: never
};

/// The limits in force over one read on `connections` (idle when it begins), from construction to
/// destruction: their session's lock_timeout set (and reset afterwards), the predicate watched.
/// Throws the cancellation at once if the predicate is already true.
class ReadScope
{
public:
  ReadScope(const std::vector<PGconn*>& connections, const ReadLimits& limits);
  /// Stops watching, rolls back a transaction that a late cancel left open (it may have hit the
  /// statement that ended it) and resets lock_timeout. Never throws.
  ~ReadScope();
  ReadScope(const ReadScope&) = delete;
  ReadScope& operator=(const ReadScope&) = delete;

  /// Runs `tidy`, housekeeping that may be left for a later call and keeps its errors to itself,
  /// with lock waits cut short, so that it gives way to a lock in its path instead of holding the
  /// read up; then throws the cancellation if it came meanwhile.
  void tidyBriefly(const std::function<void()>& tidy) const;

private:
  void setLockTimeout(std::chrono::milliseconds timeout) const;
  std::vector<PGconn*> Connections;
  const ReadLimits& Limits;
  mutable bool TimeoutSet = false; ///< lock_timeout is to be reset at the end
  StatementCancellation Cancel;
};

/// The error a read ends with, for the exception in flight (call it from a catch block): once the
/// predicate is true, any StoreError as the cancellation (StoreError ReadCancelledMessage, SQLSTATE
/// CancelledState); a statement that gave up waiting for a lock as StoreError "<what failed>: the
/// frames table is locked by another session; gave up after 30 s" (SQLSTATE 55P03); anything else
/// as it is.
[[noreturn]] void rethrowReadFailure(const ReadLimits& limits);
}
}

#endif
