// Tiled frames: the ranks of a parallel trace each stream their tile of one frame
// to PostgreSQL, concurrently, from separate processes. The frame is visible only once every
// tile is in; a rank that dies leaves an invisible, deletable frame; schema 1 databases upgrade.
//
// As in TestStoreFaults.cxx, forked children never touch gtest: they report by exit code and
// leave with _exit; each has an alarm() and the parent a deadline.
#include "RayStore.h"
#include "SceneFile.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

using asrt::RayRecord;
using asrt::RayStore;
using asrt::StoreError;
using asrt::testing::ThrowawayPostgres;
using namespace asrt::testing;

namespace
{
constexpr int Width = 101;

/// Record k of the frame (pixel k in row order), a pure function of (seed, k) so that children
/// and parent agree without talking. Includes values that careless storage loses.
RayRecord record(std::uint64_t seed, std::size_t k)
{
  return syntheticRecord(seed, k, Width);
}

/// The first index at which `got` differs from records [first, first + count) of `seed`, or -1;
/// with `migrated`, from those records as an older version stored them (one ray a pixel).
long firstDifference(const std::vector<RayRecord>& got, std::uint64_t seed, std::size_t first,
                     std::size_t count, bool migrated = false)
{
  for (std::size_t k = 0; k < std::min(got.size(), count); ++k)
  {
    const RayRecord expected = record(seed, first + k);
    if (recordBits(got[k]) != recordBits(migrated ? singleRay(expected) : expected))
    {
      return long(k);
    }
  }
  return got.size() == count ? -1 : long(std::min(got.size(), count));
}

/// Tiles as consecutive bands of rows, of unequal sizes (whole rows, then a ragged last one),
/// so that tile offsets matter.
struct Tiling
{
  std::vector<std::size_t> first, count;
  std::size_t total = 0;
  explicit Tiling(const std::vector<std::size_t>& sizes)
  {
    for (std::size_t n : sizes)
    {
      this->first.push_back(this->total);
      this->count.push_back(n);
      this->total += n;
    }
  }
};

asrt::SceneDescription scene(double mass)
{
  asrt::SceneDescription d;
  d.name = "tiled scene";
  d.spacetime.mass = mass;
  d.camera.width = Width;
  d.camera.height = 64;
  return d;
}

/// Children: writing a tile that is already written is the error these tests expect.
constexpr int AlreadyWritten = ExpectedError;

template<typename F>
pid_t spawn(unsigned alarmSeconds, F&& body)
{
  return spawnChild(alarmSeconds, "already written", std::forward<F>(body));
}

void writeTileOf(RayStore& s, std::int64_t id, int tile, const Tiling& t, std::uint64_t seed)
{
  const std::size_t first = t.first[std::size_t(tile)];
  s.writeTile(id, tile, t.count[std::size_t(tile)],
              [&](std::size_t k, RayRecord& r) { r = record(seed, first + k); });
}
}

// -----------------------------------------------------------------------------------------------

TEST(TiledFramesConcurrent, FourRanksWriteOneFrameVisibleOnlyWhenComplete)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const std::uint64_t seed = 41;
  // Whole rows of 101 pixels (tile 3 ragged), several blocks each, of unequal sizes.
  const Tiling tiling({ 101 * 90, 101 * 120 + 7, 101 * 60, 101 * 150 - 7 });
  const int tiles = 4;

  StartGate start, last;
  std::vector<pid_t> children;
  for (int tile = 0; tile < tiles; ++tile)
  {
    children.push_back(spawn(60,
                             [&, tile]
                             {
                               start.wait();
                               RayStore s(ci);
                               const std::int64_t id =
                                 s.beginTiledFrame(scene(1.0), "four ranks", tiles);
                               if (tile == tiles - 1)
                               {
                                 // The last rank holds back until the parent has looked at the
                                 // three-quarter frame.
                                 last.wait();
                               }
                               writeTileOf(s, id, tile, tiling, seed);
                               return int(Ok);
                             }));
  }
  start.open();
  const auto t0 = Clock::now();
  for (int tile = 0; tile < tiles - 1; ++tile)
  {
    EXPECT_EQ(waitChild(children[std::size_t(tile)], Clock::now() + std::chrono::seconds(60)),
              int(Ok))
      << "rank " << tile;
  }
  const double threeTiles = secondsSince(t0);

  // Three tiles committed: the frame exists, but nobody sees it.
  ASSERT_EQ(db.value("SELECT count(*) FROM frames"), "1") << "the ranks disagreed on the frame";
  const std::int64_t id = std::stoll(db.value("SELECT id FROM frames"));
  EXPECT_EQ(db.value("SELECT status || ':' || tile_count FROM frames"), "writing:4");
  EXPECT_EQ(db.value("SELECT count(*) FROM frame_tiles"), "3");
  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_FALSE(store.findFrame(scene(1.0)).has_value());
  EXPECT_NE(errorOf([&] { store.readFrame(id); }).find("there is no frame"), std::string::npos);
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v WHERE frame_id = " + std::to_string(id)), "0");

  last.open();
  const auto t1 = Clock::now();
  EXPECT_EQ(waitChild(children.back(), Clock::now() + std::chrono::seconds(60)), int(Ok));
  const double lastTile = secondsSince(t1);

  const std::vector<asrt::FrameInfo> frames = store.listFrames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, id);
  EXPECT_EQ(frames[0].status, "complete");
  EXPECT_EQ(frames[0].tileCount, tiles);
  EXPECT_EQ(frames[0].rayCount, std::int64_t(tiling.total));
  EXPECT_EQ(store.findFrame(scene(1.0)), std::optional<std::int64_t>(id));

  const auto t2 = Clock::now();
  const std::vector<RayRecord> all = store.readFrame(id);
  const double readSeconds = secondsSince(t2);
  EXPECT_EQ(firstDifference(all, seed, 0, tiling.total), -1)
    << "the frame is not the concatenation of its tiles";

  // SQL numbers the rays of the frame as readFrame returns them, across tiles.
  const std::vector<RayRecord> third = store.readFrame(id, "tile = 2");
  EXPECT_EQ(firstDifference(third, seed, tiling.first[2], tiling.count[2]), -1);
  EXPECT_EQ(db.value("SELECT min(ray) || '-' || max(ray) || ':' || max(tile_ray) FROM rays_v "
                     "WHERE tile = 2"),
            std::to_string(tiling.first[2]) + "-" +
              std::to_string(tiling.first[2] + tiling.count[2] - 1) + ":" +
              std::to_string(tiling.count[2] - 1));
  const std::vector<RayRecord> row = store.readFrame(id, "j = 200");
  ASSERT_EQ(row.size(), std::size_t(Width));
  EXPECT_EQ(firstDifference(row, seed, 200 * Width, Width), -1);

  std::printf("[ tiles ] 4 ranks, %zu rays: three tiles in %.3f s, the last in %.3f s, "
              "read back in %.3f s\n",
              tiling.total, threeTiles, lastTile, readSeconds);
}

// Many rounds of all tiles at once: the last two tiles often commit together, and exactly one of
// them must complete the frame (neither may miss the other, nor may they deadlock).
TEST(TiledFramesConcurrent, SimultaneousLastTilesAlwaysCompleteTheFrame)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  const Tiling tiling({ 3000, 3001, 2999, 3000 });
  const auto t0 = Clock::now();
  const int rounds = 8;
  for (int round = 0; round < rounds; ++round)
  {
    StartGate start;
    std::vector<pid_t> children;
    for (int tile = 0; tile < 4; ++tile)
    {
      children.push_back(spawn(60,
                               [&, tile]
                               {
                                 RayStore s(ci);
                                 start.wait();
                                 const std::int64_t id =
                                   s.beginTiledFrame(scene(10.0 + round), "race", 4);
                                 writeTileOf(s, id, tile, tiling, std::uint64_t(round));
                                 return int(Ok);
                               }));
    }
    start.open();
    for (pid_t c : children)
    {
      EXPECT_EQ(waitChild(c, Clock::now() + std::chrono::seconds(60)), int(Ok))
        << "round " << round;
    }
    const std::optional<std::int64_t> id = store.findFrame(scene(10.0 + round));
    ASSERT_TRUE(id.has_value()) << "round " << round << ": all tiles in, frame not complete";
    EXPECT_EQ(firstDifference(store.readFrame(*id), std::uint64_t(round), 0, tiling.total), -1);
  }
  EXPECT_EQ(store.listFrames().size(), std::size_t(rounds));
  std::printf("[ tiles ] %d rounds of 4 simultaneous ranks in %.3f s\n", rounds, secondsSince(t0));
}

TEST(TiledFramesFaults, RankKilledMidCopyLeavesAnInvisibleDeletableFrame)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const std::uint64_t seed = 5;
  const Tiling tiling({ 20000, 20000, 98304 });

  const std::int64_t id = store.beginTiledFrame(scene(2.0), "doomed", 3);
  writeTileOf(store, id, 0, tiling, seed);
  const pid_t child =
    spawn(60,
          [&]
          {
            RayStore s(ci);
            const std::int64_t mine = s.beginTiledFrame(scene(2.0), "doomed", 3);
            const std::size_t first = tiling.first[2], n = tiling.count[2];
            s.writeTile(mine, 2, n,
                        [&](std::size_t k, RayRecord& r)
                        {
                          // Stalls after half, inside the COPY, until killed.
                          if (k >= n / 2)
                          {
                            std::this_thread::sleep_for(std::chrono::milliseconds(10));
                          }
                          r = record(seed, first + k);
                        });
            return int(Ok);
          });
  ASSERT_GT(child, 0);
  writeTileOf(store, id, 1, tiling, seed);

  const std::string progress = pollUntil(
    db,
    "SELECT coalesce(max(p.tuples_processed), 0) FROM pg_stat_progress_copy p JOIN "
    "pg_stat_activity a USING (pid) WHERE a.query LIKE 'COPY ray_blocks%'",
    [](const std::string& v) { return std::stoll(v) >= 8; }, 20);
  const std::string backend = db.value(
    "SELECT pid FROM pg_stat_activity WHERE query LIKE 'COPY ray_blocks%' AND state = 'active'");
  kill(child, SIGKILL);
  EXPECT_EQ(waitChild(child, Clock::now() + std::chrono::seconds(10)), 128 + SIGKILL);
  ASSERT_GE(std::stoll(progress), 8) << "the third tile's COPY never got going";
  const auto t0 = Clock::now();
  EXPECT_EQ(pollUntil(
              db, "SELECT count(*) FROM pg_stat_activity WHERE pid = " + backend,
              [](const std::string& v) { return v == "0"; }, 10),
            "0");
  std::printf("[ tiles ] killed rank's COPY had %s blocks; its backend was gone after %.3f s\n",
              progress.c_str(), secondsSince(t0));

  // Two tiles in, the third rolled back: the frame stays invisible.
  EXPECT_EQ(db.value("SELECT string_agg(tile::text, ',' ORDER BY tile) FROM frame_tiles"), "0,1");
  EXPECT_EQ(db.value("SELECT count(*) FROM ray_blocks WHERE tile = 2"), "0");
  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_FALSE(store.findFrame(scene(2.0)).has_value());
  EXPECT_NE(errorOf([&] { store.readFrame(id); }).find("there is no frame"), std::string::npos);
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v"), "0");
  EXPECT_TRUE(store.abandonedFrames(std::chrono::seconds(3600)).empty());
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  EXPECT_EQ(store.abandonedFrames(std::chrono::seconds(1)), std::vector<std::int64_t>{ id });
  // A complete frame is never abandoned.
  const std::int64_t other = store.writeFrame(scene(3.0), "whole", std::vector<RayRecord>(5));
  EXPECT_EQ(store.abandonedFrames(std::chrono::seconds(0)), std::vector<std::int64_t>{ id });

  store.deleteFrame(id);
  EXPECT_EQ(db.value("SELECT count(*) || ':' || (SELECT count(*) FROM frame_tiles) || ':' || "
                     "(SELECT count(*) FROM ray_blocks) FROM frames"),
            "1:1:1");
  EXPECT_TRUE(store.abandonedFrames(std::chrono::seconds(0)).empty());

  // The frame can then be written again, completely.
  const auto t1 = Clock::now();
  const std::int64_t again = store.beginTiledFrame(scene(2.0), "again", 3);
  EXPECT_NE(again, id);
  for (int tile : { 2, 0, 1 })
  {
    writeTileOf(store, again, tile, tiling, seed);
  }
  EXPECT_EQ(store.findFrame(scene(2.0)), std::optional<std::int64_t>(again));
  EXPECT_EQ(firstDifference(store.readFrame(again), seed, 0, tiling.total), -1);
  EXPECT_EQ(store.listFrames().size(), 2u);
  EXPECT_EQ(store.readFrame(other).size(), 5u);
  std::printf("[ tiles ] rewriting the frame as 3 tiles (%zu rays) took %.3f s\n", tiling.total,
              secondsSince(t1));
}

TEST(TiledFramesErrors, TileWrittenTwiceAndOtherMisusesAreRefused)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const Tiling tiling({ 5000, 4000 });
  const std::uint64_t seed = 9;

  const std::int64_t id = store.beginTiledFrame(scene(1.0), "twice", 2);
  EXPECT_EQ(store.beginTiledFrame(scene(1.0), "twice", 2), id);
  EXPECT_NE(errorOf([&] { store.beginTiledFrame(scene(1.0), "twice", 3); })
              .find("being written as 2 tiles, not 3"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { store.beginTiledFrame(scene(1.0), "none", 0); }).find("at least one"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { store.writeFrame(scene(1.0), "whole", std::vector<RayRecord>(3)); })
              .find("duplicate frame"),
            std::string::npos);
  EXPECT_NE(
    errorOf([&] { store.writeTile(id, 2, std::vector<RayRecord>(3)); }).find("tiles 0 to 1"),
    std::string::npos);
  EXPECT_NE(
    errorOf([&] { store.writeTile(id + 100, 0, std::vector<RayRecord>(3)); }).find("no such frame"),
    std::string::npos);

  // Two processes write tile 0 at once: one wins, the other is told, nothing is doubled.
  StartGate start;
  std::vector<pid_t> children;
  for (int c = 0; c < 2; ++c)
  {
    children.push_back(spawn(60,
                             [&]
                             {
                               RayStore s(ci);
                               start.wait();
                               writeTileOf(s, id, 0, tiling, seed);
                               return int(Ok);
                             }));
  }
  start.open();
  std::vector<int> codes;
  for (pid_t c : children)
  {
    codes.push_back(waitChild(c, Clock::now() + std::chrono::seconds(60)));
  }
  std::sort(codes.begin(), codes.end());
  EXPECT_EQ(codes, (std::vector<int>{ int(Ok), int(AlreadyWritten) }));

  const std::string twice = errorOf([&] { writeTileOf(store, id, 0, tiling, seed); });
  EXPECT_NE(twice.find("tile 0 of frame " + std::to_string(id) +
                       " failed: the tile is already "
                       "written"),
            std::string::npos)
    << twice;
  // The 5000 rays of tile 0 once: ceil(5000 / kBlockSize) rows.
  EXPECT_EQ(db.value("SELECT count(*) || ':' || sum(n) FROM ray_blocks"),
            std::to_string((5000 + RayStore::kBlockSize - 1) / RayStore::kBlockSize) + ":5000");
  EXPECT_TRUE(store.listFrames().empty());

  writeTileOf(store, id, 1, tiling, seed);
  EXPECT_EQ(firstDifference(store.readFrame(id), seed, 0, tiling.total), -1);
  EXPECT_NE(errorOf([&] { writeTileOf(store, id, 1, tiling, seed); }).find("already written"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { store.beginTiledFrame(scene(1.0), "twice", 2); }).find("duplicate frame"),
            std::string::npos);

  // Replacing a complete frame starts a new one; the old stays readable until then.
  const std::int64_t fresh = store.beginTiledFrame(scene(1.0), "replaced", 1, true);
  EXPECT_NE(fresh, id);
  EXPECT_TRUE(store.listFrames().empty());
  store.writeTile(fresh, 0, std::vector<RayRecord>());
  ASSERT_EQ(store.listFrames().size(), 1u);
  EXPECT_EQ(store.listFrames()[0].rayCount, 0);
  EXPECT_TRUE(store.readFrame(fresh).empty());
}

// -----------------------------------------------------------------------------------------------
// Migrations from databases written by earlier versions, stored by insertLegacyFrame()
// (StoreTestSupport.h); TestStoreMigrations.cxx checks every field of every ray.

namespace
{
std::vector<RayRecord> records(std::uint64_t seed, std::size_t first, std::size_t count)
{
  std::vector<RayRecord> out;
  for (std::size_t k = 0; k < count; ++k)
    out.push_back(record(seed, first + k));
  return out;
}
}

TEST(TiledFramesSchema, VersionOneDatabaseMigratesKeepingItsFrames)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  const std::size_t count = 3 * LegacyBlock + 11;
  RayStore store(ci);
  store.migrate(1);
  EXPECT_EQ(store.schemaVersion(), 1);
  Db db(ci);
  const std::int64_t id = insertLegacyFrame(db.Conn, 1, scene(1.0), { records(77, 0, count) });
  const std::int64_t empty = insertLegacyFrame(db.Conn, 1, scene(1.5), { {} });
  EXPECT_NE(errorOf([&] { store.listFrames(); }).find("call migrate()"), std::string::npos);

  const auto t0 = Clock::now();
  store.migrate();
  const double migrateSeconds = secondsSince(t0);
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(db.value("SELECT count(*) FROM schema_version"), "1");
  ASSERT_EQ(store.listFrames().size(), 2u);
  EXPECT_EQ(store.frameInfo(id).tileCount, 1);
  EXPECT_EQ(store.findFrame(scene(1.0)), id);
  EXPECT_EQ(firstDifference(store.readFrame(id), 77, 0, count, true), -1);
  EXPECT_TRUE(store.readFrame(empty).empty());
  EXPECT_EQ(db.value("SELECT string_agg(tile || ':' || ray_count, ',' ORDER BY frame_id) FROM "
                     "frame_tiles"),
            "0:" + std::to_string(count) + ",0:0");
  EXPECT_EQ(db.value("SELECT count(*) || ':' || max(ray) || ':' || max(tile) FROM rays_v"),
            std::to_string(count) + ":" + std::to_string(count - 1) + ":0");
  const std::vector<RayRecord> some = store.readFrame(id, "ray >= " + std::to_string(count - 3));
  EXPECT_EQ(firstDifference(some, 77, count - 3, 3, true), -1);
  // The rays moved into the new layout: rows of kBlockSize, one table for the frame.
  EXPECT_EQ(db.value("SELECT count(*) || ':' || sum(n) || ':' || max(n) FROM ray_blocks"),
            std::to_string((count + RayStore::kBlockSize - 1) / RayStore::kBlockSize) + ":" +
              std::to_string(count) + ":" + std::to_string(RayStore::kBlockSize));
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass"),
            "1");

  // The upgraded database takes tiled frames, and migrate() stays idempotent.
  const std::int64_t tiled = store.beginTiledFrame(scene(2.0), "tiled", 2);
  store.writeTile(tiled, 1, std::vector<RayRecord>{ record(1, 1) });
  store.writeTile(tiled, 0, std::vector<RayRecord>{ record(1, 0) });
  EXPECT_EQ(firstDifference(store.readFrame(tiled), 1, 0, 2), -1);
  store.migrate();
  EXPECT_EQ(store.listFrames().size(), 3u);

  // Migrations never go back, and a newer schema is refused.
  EXPECT_NE(errorOf([&] { store.migrate(2); }).find("never go back"), std::string::npos);
  const std::string current = std::to_string(RayStore::kSchemaVersion);
  const std::string next = std::to_string(RayStore::kSchemaVersion + 1);
  EXPECT_NE(errorOf([&] { store.migrate(RayStore::kSchemaVersion + 1); })
              .find("knows versions 1 to " + current),
            std::string::npos);
  db.value("UPDATE schema_version SET version = " + next);
  RayStore later(ci);
  EXPECT_NE(
    errorOf([&] { later.migrate(); }).find("found " + next + ", this build knows " + current),
    std::string::npos);
  std::printf("[ tiles ] migrating a version 1 database with %zu rays took %.3f s\n", count,
              migrateSeconds);
}

TEST(TiledFramesSchema, VersionTwoTiledFramesMigrateWhetherCompleteOrNot)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate(2);
  Db db(ci);
  // A complete frame of three tiles (the middle one empty), and a frame whose second tile was
  // never written.
  const std::vector<std::size_t> sizes = { 5000, 0, 4200 };
  std::vector<std::vector<RayRecord>> tiles;
  for (std::size_t t = 0, first = 0; t < sizes.size(); first += sizes[t++])
    tiles.push_back(records(31, first, sizes[t]));
  const std::int64_t whole = insertLegacyFrame(db.Conn, 2, scene(1.0), tiles);
  const std::int64_t half =
    insertLegacyFrame(db.Conn, 2, scene(2.0), { records(32, 0, 700) }, "writing");
  db.value("UPDATE frames SET tile_count = 2 WHERE id = " + std::to_string(half));

  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  ASSERT_EQ(store.listFrames().size(), 1u);
  EXPECT_EQ(firstDifference(store.readFrame(whole), 31, 0, 9200, true), -1);
  EXPECT_EQ(db.value("SELECT min(ray) || '-' || max(ray) || ':' || count(*) FROM rays_v WHERE "
                     "tile = 2"),
            "5000-9199:4200");
  // The abandoned frame is still abandoned; finishing it completes it with both tiles exact.
  EXPECT_EQ(store.abandonedFrames(std::chrono::seconds(0)), std::vector<std::int64_t>{ half });
  store.writeTile(half, 1, records(32, 700, 300));
  const std::vector<RayRecord> both = store.readFrame(half);
  ASSERT_EQ(both.size(), 1000u);
  EXPECT_EQ(firstDifference({ both.begin(), both.begin() + 700 }, 32, 0, 700, true), -1);
  EXPECT_EQ(firstDifference({ both.begin() + 700, both.end() }, 32, 700, 300), -1);
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass"),
            "4");
  store.deleteFrame(whole);
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass"),
            "2");
}
