// The limits on reads (RayStore::setReadCancellation, setReadLockTimeout): a read waiting for a
// table that another session holds locked stops once the predicate turns true, or gives up when
// its lock timeout runs out, naming the table; either way while the other session still holds
// the lock (the read did not wait for it), and the store is usable afterwards.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

using asrt::RayRecord;
using asrt::RayStore;
using asrt::StoreError;
using namespace asrt::testing;
using namespace std::chrono_literals;

namespace
{
constexpr int Width = 31, Height = 17;

asrt::SceneDescription scene()
{
  asrt::SceneDescription d;
  d.name = "read limits scene";
  d.camera.width = Width;
  d.camera.height = Height;
  return d;
}

std::vector<RayRecord> records()
{
  std::vector<RayRecord> out(std::size_t(Width) * Height);
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = syntheticRecord(7, k, Width);
  return out;
}

std::string conninfo()
{
  return databaseNamed("rl_" + currentTestName());
}

/// Another session that holds `table` locked in ACCESS EXCLUSIVE mode (which blocks every read of
/// it) until release(). Should a read under test not stop, the lock is let go after 30 s, so that
/// the test fails (the lock no longer held) instead of hanging.
class Locker
{
public:
  Locker(const std::string& conninfo, const std::string& table)
    : Session(conninfo)
    , Observer(conninfo)
    , Table(table)
  {
    this->Session.value("BEGIN");
    this->Session.value("LOCK TABLE " + table + " IN ACCESS EXCLUSIVE MODE");
    this->Pid = this->Session.value("SELECT pg_backend_pid()");
    this->Watchdog = std::thread(
      [this]
      {
        std::unique_lock<std::mutex> lock(this->Mutex);
        if (!this->Wake.wait_for(lock, 30s, [this] { return this->Done; }))
          this->Session.value("ROLLBACK");
      });
  }
  ~Locker() { this->release(); }

  /// Whether the session still holds the lock, as the server's lock table says.
  bool holding()
  {
    return this->Observer.value("SELECT count(*) FROM pg_locks l JOIN pg_class c ON c.oid = "
                                "l.relation WHERE l.granted AND l.mode = 'AccessExclusiveLock' "
                                "AND c.relname = '" +
                                this->Table + "' AND l.pid = " + this->Pid) == "1";
  }
  void release()
  {
    {
      std::lock_guard<std::mutex> lock(this->Mutex);
      this->Done = true;
    }
    this->Wake.notify_all();
    if (this->Watchdog.joinable())
    {
      this->Watchdog.join();
      this->Session.value("ROLLBACK");
    }
  }

private:
  Db Session, Observer;
  std::string Table, Pid;
  std::mutex Mutex;
  std::condition_variable Wake;
  bool Done = false;
  std::thread Watchdog;
};

/// What a call throws: its message and SQLSTATE ("(no error)" if nothing).
template<typename F>
std::pair<std::string, std::string> failureOf(F&& f)
{
  try
  {
    f();
  }
  catch (const StoreError& e)
  {
    return { e.what(), e.sqlState() };
  }
  return { "(no error)", "" };
}
}

TEST(ReadLimits, AReadWaitingForALockStopsOnceCancelled)
{
  RayStore store(conninfo());
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "kept", records());
  std::atomic<bool> cancel{ false };
  store.setReadCancellation([&] { return cancel.load(); });
  store.setReadLockTimeout(0ms); // only the cancellation can end the wait
  Locker locker(conninfo(), "frames");

  // Once the read is seen waiting for the lock, the predicate turns true.
  std::thread canceller(
    [&]
    {
      Db watcher(conninfo());
      pollUntil(
        watcher,
        "SELECT count(*) FROM pg_stat_activity WHERE wait_event_type = 'Lock' AND pid = " +
          std::to_string(store.backendPid()),
        [](const std::string& v) { return v == "1"; }, 60);
      cancel = true;
    });
  const auto [message, state] = failureOf([&] { store.listFrames(); });
  const bool stillHeld = locker.holding();
  canceller.join();
  EXPECT_TRUE(cancel) << "the read never waited for the lock";
  EXPECT_EQ(message, "reading from the store was cancelled");
  EXPECT_EQ(state, "57014");
  EXPECT_TRUE(stillHeld) << "the read ended only once the lock was released";

  // Once the predicate is true, no read starts; once false again, reads go on as before.
  EXPECT_EQ(failureOf([&] { store.frameInfo(id); }).second, "57014");
  locker.release();
  cancel = false;
  const std::vector<asrt::FrameInfo> frames = store.listFrames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, id);
  EXPECT_EQ(store.readFrame(id).size(), records().size());
}

TEST(ReadLimits, AReadGivesUpOnALockedTableNamingIt)
{
  RayStore store(conninfo());
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "kept", records());
  store.setReadLockTimeout(200ms);
  {
    Locker locker(conninfo(), "frames");
    // A reader's upgrade gets through: what it tidies up in passing gives way to the lock.
    EXPECT_EQ(failureOf([&] { store.upgrade(); }).first, "(no error)");
    const auto [message, state] = failureOf([&] { store.listFrames(); });
    EXPECT_EQ(message, "listing the frames failed: the frames table is locked by another "
                       "session; gave up after 0.2 s");
    EXPECT_EQ(state, "55P03");
    EXPECT_TRUE(locker.holding());
  }
  {
    // The rays only: the frame's row is read, its rays wait.
    Locker locker(conninfo(), "ray_blocks");
    const auto [message, state] = failureOf([&] { store.readFrame(id); });
    EXPECT_EQ(message, "reading the rays failed: the ray_blocks table is locked by another "
                       "session; gave up after 0.2 s");
    EXPECT_EQ(state, "55P03");
    EXPECT_TRUE(locker.holding());
  }
  // The locks gone, the same store reads.
  EXPECT_EQ(store.listFrames().size(), 1u);
  EXPECT_EQ(store.readFrame(id).size(), records().size());
}

TEST(ReadLimits, TheLockTimeoutIsCheckedWhenSet)
{
  RayStore store(conninfo());
  EXPECT_NE(errorOf([&] { store.setReadLockTimeout(-1ms); }).find("between 0 and"),
            std::string::npos);
  EXPECT_NE(
    errorOf([&] { store.setReadLockTimeout(std::chrono::hours(24 * 30)); }).find("between 0 and"),
    std::string::npos);
  store.setReadLockTimeout(std::chrono::hours(24 * 20));
  store.migrate();
  EXPECT_TRUE(store.listFrames().empty());
}
