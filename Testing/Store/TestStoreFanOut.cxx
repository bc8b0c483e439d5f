// The store's fan-out of a large write over helper connections (StoreFanOut.h): when one share
// fails, the others stop early, and the caller hears of the failure that stopped them, not that
// they stopped. Real helper connections to a throwaway server; each share's work is a function
// the test controls, so that the order of events is fixed by the test, not by the scheduler.
#include "PgSession.h"
#include "SharedServer.h"
#include "StoreFanOut.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

using asrt::StoreError;
using namespace asrt::testing;

namespace
{
/// The message run() threw, or "(no error)".
std::string errorOf(asrt::storage::FanOut& fan,
                    const std::function<void(PGconn*, std::size_t)>& helperShare,
                    const std::function<void()>& ownShare)
{
  try
  {
    fan.run(helperShare, ownShare);
  }
  catch (const StoreError& e)
  {
    return e.what();
  }
  return "(no error)";
}
}

TEST(StoreFanOut, AShareStoppedByAnotherReportsTheFailureThatStoppedIt)
{
  asrt::pg::Connection helper = asrt::pg::connect(sharedServer().conninfo());
  // The calling thread's share waits until the helper's has failed, then stops as the store's
  // writes do: it sees failed() and throws ShareStopped.
  {
    asrt::storage::FanOut fan({ helper.get() });
    std::atomic<bool> helperThrew{ false };
    const std::string error = errorOf(
      fan,
      [&](PGconn*, std::size_t)
      {
        helperThrew = true;
        throw StoreError("writing the rays failed: could not extend file: No space left on device",
                         "53100");
      },
      [&]
      {
        while (!fan.failed())
          std::this_thread::yield();
        EXPECT_TRUE(helperThrew.load());
        throw asrt::storage::ShareStopped(
          "writing the rays failed: another connection of the write failed");
      });
    EXPECT_EQ(error, "writing the rays failed: could not extend file: No space left on device");
  }
  // The other way round: the calling thread's share fails, the helper's stops.
  {
    asrt::storage::FanOut fan({ helper.get() });
    const std::string error = errorOf(
      fan,
      [&](PGconn*, std::size_t)
      {
        while (!fan.failed())
          std::this_thread::yield();
        throw asrt::storage::ShareStopped("stopped");
      },
      [] { throw StoreError("the calling thread's own failure"); });
    EXPECT_EQ(error, "the calling thread's own failure");
  }
  // Only stopped shares (nothing else to report): that is what the caller hears.
  {
    asrt::storage::FanOut fan({ helper.get() });
    const std::string error = errorOf(
      fan, [](PGconn*, std::size_t) { throw asrt::storage::ShareStopped("helper stopped"); },
      [] {});
    EXPECT_EQ(error, "helper stopped");
  }
  // Nothing failed.
  {
    asrt::storage::FanOut fan({ helper.get() });
    EXPECT_EQ(errorOf(
                fan, [](PGconn*, std::size_t) {}, [] {}),
              "(no error)");
  }
}
