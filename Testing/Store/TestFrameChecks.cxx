// The checks around a frame's identity and a database's schema: readers create no schema
// (upgrade()), checkFrameIdentity() refuses exactly what writeFrame() refuses, and the loser of
// two concurrent replacements of one frame is told what happened. Also: a frame row edited to a
// size no read can allocate is refused, naming the frame and the field.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cctype>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

using asrt::FrameWriteOptions;
using asrt::RayRecord;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
std::string freshDatabase()
{
  return databaseNamed("fc_" + currentTestName());
}

asrt::SceneDescription scene(double mass)
{
  return syntheticScene("identity", mass);
}

std::vector<RayRecord> records(std::uint64_t seed)
{
  return syntheticRecords(seed);
}

/// Every field of every record the same, bit for bit.
bool sameBits(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  if (a.size() != b.size())
    return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (recordBits(a[k]) != recordBits(b[k]))
      return false;
  return true;
}

/// The relations of the database's current schema, by name.
std::string relations(Db& db)
{
  return db.value("SELECT coalesce(string_agg(relname, ',' ORDER BY relname), '') FROM pg_class "
                  "WHERE relnamespace = current_schema()::regnamespace");
}
}

TEST(StoreReaders, UpgradeCreatesNoSchemaButMigratesAnOldOne)
{
  // A database that is not ASRT's: upgrade() refuses it and leaves it as it was.
  const std::string ci = freshDatabase();
  Db db(ci);
  db.value("CREATE TABLE someone_elses (x int)");
  RayStore store(ci);
  const std::string e = errorOf([&] { store.upgrade(); });
  EXPECT_NE(e.find("the database holds no ASRT schema"), std::string::npos) << e;
  EXPECT_EQ(store.schemaVersion(), 0);
  EXPECT_EQ(relations(db), "someone_elses");
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_proc WHERE proname = 'asrt_selected_rays'"), "0");

  // An ASRT schema of an older version is brought up to date.
  store.migrate(3);
  RayStore reader(ci);
  reader.upgrade();
  EXPECT_EQ(reader.schemaVersion(), RayStore::kSchemaVersion);
  const std::int64_t id = reader.writeFrame(scene(1), "new", records(1));
  EXPECT_EQ(reader.readFrame(id, "j = 0").size(), 6u);
  reader.upgrade();
  EXPECT_EQ(reader.schemaVersion(), RayStore::kSchemaVersion);
}

TEST(StoreWrites, CheckFrameIdentityRefusesExactlyWhatWriteFrameRefuses)
{
  RayStore store(freshDatabase());
  store.migrate();
  const asrt::SceneDescription stored = scene(1), tiled = scene(2), fresh = scene(3);
  store.writeFrame(stored, "stored", records(1));
  store.beginTiledFrame(tiled, "tiled", 2);
  // Each case: what checkFrameIdentity says, then what writeFrame does (it writes when nothing
  // refuses it, which is what the check then says of the next case's frame).
  struct Case
  {
    const asrt::SceneDescription& scene;
    bool replace;
    bool refused;
  };
  for (const Case& c :
       { Case{ stored, false, true }, Case{ tiled, false, true }, Case{ tiled, true, true },
         Case{ fresh, false, false }, Case{ stored, true, false } })
  {
    const std::string checked = errorOf([&] { store.checkFrameIdentity(c.scene, c.replace); });
    const std::size_t before = store.listFrames().size();
    const std::string written = errorOf(
      [&] {
        store.writeFrame(c.scene, "again", records(2), FrameWriteOptions().replacing(c.replace));
      });
    EXPECT_EQ(checked, written) << c.scene.spacetime.mass << (c.replace ? " replace" : "");
    EXPECT_EQ(written != "(no error)", c.refused) << written;
    if (c.refused)
    {
      EXPECT_EQ(store.listFrames().size(), before);
    }
  }
  // The frame written by a case above is now a duplicate for the check too.
  EXPECT_NE(errorOf([&] { store.checkFrameIdentity(fresh, false); }).find("duplicate frame"),
            std::string::npos);
}

TEST(StoreWrites, TheLoserOfTwoConcurrentReplacementsIsToldWhatHappened)
{
  const std::string ci = freshDatabase();
  RayStore first(ci), second(ci);
  first.migrate();
  const asrt::SceneDescription s = scene(1);
  first.writeFrame(s, "original", records(1));
  Db db(ci);

  // The first replacement holds its transaction open in the middle of its COPY (its producer
  // waits), having deleted the original frame and inserted its own row.
  std::mutex mutex;
  std::condition_variable cv;
  bool firstInCopy = false, releaseFirst = false;
  std::string firstError, secondError;
  std::thread firstWriter(
    [&]
    {
      firstError = errorOf(
        [&]
        {
          first.writeFrame(
            s, "first", 30,
            [&](std::size_t k, RayRecord& r)
            {
              if (k == 0)
              {
                std::unique_lock<std::mutex> lock(mutex);
                firstInCopy = true;
                cv.notify_all();
                cv.wait(lock, [&] { return releaseFirst; });
              }
              r = syntheticRecord(3, k, 6);
            },
            FrameWriteOptions().replacing());
        });
    });
  {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait(lock, [&] { return firstInCopy; });
  }
  // The second replacement waits for the first one's row lock on the original frame...
  const std::string secondPid = std::to_string(second.backendPid());
  std::thread secondWriter(
    [&]
    {
      secondError = errorOf(
        [&] { second.writeFrame(s, "second", records(4), FrameWriteOptions().replacing()); });
    });
  EXPECT_EQ(pollUntil(
              db,
              "SELECT coalesce(wait_event_type, '') FROM pg_stat_activity WHERE pid = " + secondPid,
              [](const std::string& v) { return v == "Lock"; }, 60),
            "Lock");
  // ... and finds, once the first one commits, the frame gone and the first one's in its place.
  {
    std::lock_guard<std::mutex> lock(mutex);
    releaseFirst = true;
    cv.notify_all();
  }
  firstWriter.join();
  secondWriter.join();
  EXPECT_EQ(firstError, "(no error)");
  EXPECT_NE(secondError.find("another writer stored this scene with these parameters at the same "
                             "time"),
            std::string::npos)
    << secondError;
  EXPECT_EQ(secondError.find("replace = true"), std::string::npos) << secondError;
  // The first replacement stands, whole; the second left nothing.
  const std::vector<asrt::FrameInfo> frames = first.listFrames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].label, "first");
  EXPECT_EQ(first.readFrame(frames[0].id).size(), 30u);
  EXPECT_EQ(db.value("SELECT count(*) FROM frames"), "1");
}

TEST(StoreReaders, AFrameRowEditedToAnImpossibleSizeIsRefusedBeforeAnythingIsAllocated)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> written = records(5);
  const std::int64_t id = store.writeFrame(scene(1), "edited", written);
  const std::string frame = "frame " + std::to_string(id) + " is inconsistent: ";
  Db db(ci);
  auto edit = [&](const std::string& set)
  { db.value("UPDATE frames SET " + set + " WHERE id = " + std::to_string(id)); };

  // Sizes as the owner could set them with SQL, and the field each error must name.
  const std::pair<const char*, const char*> cases[] = {
    { "width = 100000, height = 100000", "frames.width x frames.height = 100000 x 100000" },
    { "width = 2147483647, height = 1", "frames.width x frames.height = 2147483647 x 1" },
    { "width = 16385, height = 16384", "frames.width x frames.height = 16385 x 16384" },
    { "width = 0", "frames.width = 0" },
    { "height = -3", "frames.height = -3" },
  };
  for (const auto& [set, field] : cases)
  {
    edit(set);
    for (const std::string& predicate : { std::string(), std::string("j = 0") })
    {
      const std::string e = errorOf([&] { store.readFrame(id, predicate); });
      EXPECT_EQ(e.find(frame + field), 0u) << set << ": " << e;
      EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    edit("width = 6, height = 5");
  }
  // 2^28 pixels is the tracer's own limit, and allowed.
  edit("width = 16384, height = 16384");
  EXPECT_TRUE(sameBits(store.readFrame(id), written));

  // More rays than a frame may trace, the tiles edited to agree.
  const std::string tooMany = std::to_string((1LL << 28) + 1);
  edit("ray_count = " + tooMany);
  db.value("UPDATE frame_tiles SET ray_count = " + tooMany +
           " WHERE frame_id = " + std::to_string(id));
  const std::string e = errorOf([&] { store.readFrame(id); });
  EXPECT_EQ(e.find(frame + "frames.ray_count = " + tooMany), 0u) << e;
  edit("ray_count = -1");
  EXPECT_EQ(errorOf([&] { store.readFrame(id); }).find(frame + "frames.ray_count = -1"), 0u);
}

TEST(StoreReaders, AWholeReadBeyondTheMemoryLimitIsRefused)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> written = records(6);
  const std::int64_t id = store.writeFrame(scene(1), "memory", written);
  // The records alone take written.size() * sizeof(RayRecord) bytes.
  const double need = double(written.size() * sizeof(RayRecord));
  store.setMemoryLimit(need - 1);
  const std::string e = errorOf([&] { store.readFrame(id); });
  EXPECT_EQ(e.find("reading frame " + std::to_string(id) + " needs "), 0u) << e;
  EXPECT_NE(e.find("(frames.ray_count)"), std::string::npos) << e;
  store.setMemoryLimit(need);
  EXPECT_TRUE(sameBits(store.readFrame(id), written));
}
