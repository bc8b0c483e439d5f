#include "StoreReadLimits.h"

#include "PgSession.h"
#include "RayStore.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace asrt
{
namespace storage
{
namespace
{
/// The lock wait of a read's housekeeping: long enough not to give up on a lock that is only
/// being passed through (a commit's), short enough that a table held locked costs the read no
/// noticeable time before its own statements meet the lock.
constexpr std::chrono::milliseconds BriefLockWait{ 100 };

bool idle(PGconn* conn)
{
  return PQstatus(conn) == CONNECTION_OK && PQtransactionStatus(conn) == PQTRANS_IDLE;
}

std::string seconds(std::chrono::milliseconds t)
{
  char text[32];
  std::snprintf(text, sizeof text, "%g s", double(t.count()) / 1000);
  return text;
}
}

ReadScope::ReadScope(const std::vector<PGconn*>& connections, const ReadLimits& limits)
  : Connections(connections)
  , Limits(limits)
  , Cancel(limits.cancelled, connections, ReadCancelledMessage)
{
  this->Cancel.check();
  if (limits.lockTimeout.count() > 0)
  {
    this->setLockTimeout(limits.lockTimeout);
  }
}

ReadScope::~ReadScope()
{
  this->Cancel.stop();
  for (PGconn* conn : this->Connections)
  {
    pg::rollback(conn);
    if (this->TimeoutSet && idle(conn))
    {
      PQclear(PQexec(conn, "RESET lock_timeout"));
    }
  }
}

void ReadScope::tidyBriefly(const std::function<void()>& tidy) const
{
  const std::chrono::milliseconds own = this->Limits.lockTimeout;
  this->setLockTimeout(own.count() > 0 ? std::min(own, BriefLockWait) : BriefLockWait);
  tidy();
  if (own.count() > 0)
  {
    this->setLockTimeout(own);
  }
  else
  {
    for (PGconn* conn : this->Connections)
    {
      pg::exec(conn, "RESET lock_timeout", "reading from the store failed");
    }
    this->TimeoutSet = false;
  }
  this->Cancel.check();
}

void ReadScope::setLockTimeout(std::chrono::milliseconds timeout) const
{
  // For the session, not a transaction: the read's transactions come and go within the scope.
  this->TimeoutSet = true;
  for (PGconn* conn : this->Connections)
  {
    pg::Params()
      .text(std::to_string(timeout.count()) + "ms")
      .exec(conn, "SELECT set_config('lock_timeout', $1, false)", "reading from the store failed");
  }
}

[[noreturn]] void rethrowReadFailure(const ReadLimits& limits)
{
  // What a cancel broke is the cancellation's doing, not a failure of its own.
  const auto cancelled = [&limits] { return limits.cancelled && limits.cancelled(); };
  try
  {
    throw;
  }
  catch (const pg::LockNotAvailable& e)
  {
    if (cancelled())
    {
      throw StoreError(ReadCancelledMessage, CancelledState);
    }
    if (limits.lockTimeout.count() <= 0)
    {
      throw; // the server's own lock_timeout: its message is all there is to say
    }
    const std::string held = e.relation().empty()
                               ? std::string("another session holds a lock it needs")
                               : "the " + e.relation() + " table is locked by another session";
    throw StoreError(e.doing() + ": " + held + "; gave up after " + seconds(limits.lockTimeout),
                     e.sqlState());
  }
  catch (const StoreError&)
  {
    if (cancelled())
    {
      throw StoreError(ReadCancelledMessage, CancelledState);
    }
    throw;
  }
}
}
}
