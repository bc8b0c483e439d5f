// Parallel helper connections: a write or a read of a large frame shares its work out between
// the store's own connection, on the calling thread, and helper connections, each on a thread of
// its own. Internal to ASRT::Store.
#ifndef asrt_StoreFanOut_h
#define asrt_StoreFanOut_h

#include "PgSession.h"

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace asrt
{
namespace storage
{
/// The store's helper connections, opened when first needed and kept.
class HelperConnections
{
public:
  explicit HelperConnections(std::string conninfo)
    : Conninfo(std::move(conninfo))
  {
  }
  /// Up to `wanted` helper connections, connected; fewer if the server refuses more (e.g. at
  /// max_connections): the work is then shared out between the ones it got.
  std::vector<PGconn*> get(int wanted);

private:
  std::string Conninfo;
  std::vector<pg::Connection> Conns;
};

/// Thrown by a share that stops early because another share failed (FanOut::failed()): run()
/// reports the failure that stopped it, not this.
class ShareStopped : public StoreError
{
public:
  using StoreError::StoreError;
};

/// One share of the work for the calling thread on its own connection, and one for each helper
/// connection on a thread of its own, all at once. A helper's share opens and ends its own
/// transaction; if it throws, its transaction is rolled back. Once any share has failed, failed()
/// is true, so that shares that take long can stop early.
class FanOut
{
public:
  explicit FanOut(std::vector<PGconn*> helpers)
    : Helpers(std::move(helpers))
  {
  }
  std::size_t helpers() const { return this->Helpers.size(); }
  bool failed() const { return this->Failed.load(std::memory_order_relaxed); }
  /// Runs helperShare(connection, k) for helper k and ownShare() on the calling thread; returns
  /// once all have ended. Then rethrows the calling thread's error if it had one, else the first
  /// helper's, passing over a ShareStopped while another share has an error of its own (a disk
  /// that filled up under one connection is what the caller hears of, not that the others
  /// stopped).
  void run(const std::function<void(PGconn*, std::size_t)>& helperShare,
           const std::function<void()>& ownShare);

private:
  std::vector<PGconn*> Helpers;
  std::atomic<bool> Failed{ false };
};
}
}

#endif
