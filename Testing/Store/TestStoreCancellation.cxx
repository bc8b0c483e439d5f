// Cancelling a write (FrameWriteOptions::cancelled, what Ctrl-C does in asrt): a write waiting
// for a lock that another session holds stops once the predicate turns true, rolls back, and
// leaves the store as it was and usable; a write cancelled before it starts stores nothing.
#include "RayStore.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

using asrt::FrameWriteOptions;
using asrt::RayRecord;
using asrt::RayStore;
using asrt::StoreError;
using asrt::testing::ThrowawayPostgres;
using namespace asrt::testing;

namespace
{
constexpr int Width = 97, Height = 64;

asrt::SceneDescription scene(double mass)
{
  asrt::SceneDescription d;
  d.name = "cancel scene";
  d.spacetime.mass = mass;
  d.camera.width = Width;
  d.camera.height = Height;
  return d;
}

std::vector<RayRecord> records(std::uint64_t seed)
{
  std::vector<RayRecord> out(std::size_t(Width) * Height);
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = syntheticRecord(seed, k, Width);
  return out;
}
}

TEST(StoreCancellation, AWriteWaitingForALockIsCancelledAndRolledBack)
{
  ThrowawayPostgres server;
  RayStore store(server.conninfo());
  store.migrate();
  const std::int64_t kept = store.writeFrame(scene(0.5), "kept", records(1));

  // Another session holds a lock that makes the frame's insert wait; once the write is seen
  // waiting, the predicate turns true. Should the write not stop, the lock is let go after a
  // while, so that the test fails instead of hanging.
  std::atomic<bool> cancel{ false }, writeEnded{ false };
  Db locker(server.conninfo());
  locker.value("BEGIN");
  locker.value("LOCK TABLE frames IN SHARE MODE");
  std::thread canceller(
    [&]
    {
      Db watcher(server.conninfo());
      pollUntil(
        watcher,
        "SELECT count(*) FROM pg_stat_activity WHERE wait_event_type = 'Lock' AND pid = " +
          std::to_string(store.backendPid()),
        [](const std::string& v) { return v == "1"; }, 60);
      cancel = true;
      const auto t0 = Clock::now();
      while (!writeEnded && secondsSince(t0) < 30)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      locker.value("ROLLBACK");
    });
  std::string state = "(no error)", message;
  try
  {
    store.writeFrame(scene(1.0), "cancelled", records(2),
                     FrameWriteOptions().cancelledWhen([&] { return cancel.load(); }));
  }
  catch (const StoreError& e)
  {
    state = e.sqlState();
    message = e.what();
  }
  writeEnded = true;
  canceller.join();
  EXPECT_TRUE(cancel) << "the write never waited for the lock";
  EXPECT_EQ(state, "57014") << message;
  EXPECT_NE(message.find("cancelled"), std::string::npos) << message;
  const std::vector<asrt::FrameInfo> frames = store.listFrames();
  ASSERT_EQ(frames.size(), 1u) << "the cancelled frame was stored";
  EXPECT_EQ(frames[0].id, kept);
  // The connection is usable, and the frame can be written after all.
  EXPECT_GT(store.writeFrame(scene(1.0), "after", records(2)), kept);
  EXPECT_EQ(store.listFrames().size(), 2u);
}

TEST(StoreCancellation, AWriteCancelledFromTheStartStoresNothing)
{
  ThrowawayPostgres server;
  RayStore store(server.conninfo());
  store.migrate();
  const std::string error = errorOf(
    [&]
    {
      store.writeFrame(scene(1.0), "cancelled", records(3),
                       FrameWriteOptions().cancelledWhen([] { return true; }));
    });
  EXPECT_NE(error.find("writing the frame was cancelled"), std::string::npos) << error;
  EXPECT_TRUE(store.listFrames().empty());
  Db db(server.conninfo());
  EXPECT_EQ(db.value("SELECT count(*) FROM scenes"), "0") << "the frame's scene row was left";
}
