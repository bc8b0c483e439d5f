// asrt::RayStore against a real throwaway PostgreSQL 15 server: schema, bit-exact round trips,
// frame identity, predicates, hostile input, connection failures, interrupted writers, paths,
// and what deleted, replaced and failed frames leave behind (nothing). The measurement behind the
// storage layout is a benchmark: bench/bench_store.cxx.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

using asrt::RayRecord;
using asrt::RayStore;
using asrt::StoreError;
using namespace asrt::testing;

namespace
{
/// A database of its own for each test, so that tests do not see each other's frames.
std::string freshDatabase()
{
  return databaseNamed("rs_" + currentTestSuiteName() + "_" + currentTestName());
}

asrt::SceneDescription scene(double mass = 1.0)
{
  asrt::SceneDescription d;
  d.name = "three cylinders";
  d.spacetime.mass = mass;
  d.spacetime.spin = 0.25;
  d.camera.width = 64;
  d.camera.height = 48;
  return d;
}

/// Deterministic synthetic records with the values that break careless storage: NaN with a
/// payload, −0, denormals, the largest doubles, infinities.
std::vector<RayRecord> synthetic(std::size_t count, int width, std::uint64_t seed = 1)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(-10, 10);
  const double specials[] = { fromBits(0x7FF8DEADBEEF0001ull),
                              -0.0,
                              std::numeric_limits<double>::denorm_min(),
                              -4.9406564584124654e-320,
                              std::numeric_limits<double>::max(),
                              -std::numeric_limits<double>::max(),
                              std::numeric_limits<double>::infinity(),
                              1e-310,
                              0.1 };
  std::vector<RayRecord> out(count);
  for (std::size_t k = 0; k < count; ++k)
  {
    RayRecord& r = out[k];
    r.i = int(k % std::size_t(width));
    r.j = int(k / std::size_t(width));
    r.origin = asrt::Vec3(0, -30, 0);
    r.direction = asrt::Vec3(u(g), u(g), u(g));
    r.momentum = asrt::Vec4(u(g), u(g), u(g), u(g));
    r.termination = asrt::Termination(g() % 6);
    r.objectId = int(g() % 5) - 1;
    r.hitPoint = asrt::Vec3(u(g), u(g), u(g));
    r.hitNormal = asrt::Vec3(u(g), u(g), u(g));
    r.u = std::abs(u(g)) / 10;
    r.v = std::abs(u(g)) / 10;
    r.chordError = std::abs(u(g)) * 1e-9;
    r.affineLength = std::abs(u(g)) * 10;
    r.winding = u(g);
    r.imageOrder = int(g() % 3);
    r.steps = std::int64_t(g() % 300000) + (std::int64_t(1) << 40) * std::int64_t(k % 2);
    r.maxAbsH = std::abs(u(g)) * 1e-12;
    r.color = asrt::Vec3(u(g), u(g), u(g));
    r.dudi = u(g);
    r.dudj = u(g);
    r.dvdi = u(g);
    r.dvdj = u(g);
    if (k % 7 == 3)
    {
      r.dudi = r.dudj = r.dvdi = r.dvdj = std::numeric_limits<double>::quiet_NaN();
    }
    if (k % 11 == 5)
    {
      const std::size_t s = (k / 11) % (sizeof(specials) / sizeof(specials[0]));
      r.hitPoint.x() = specials[s];
      r.u = specials[(s + 1) % 9];
      r.dvdj = specials[(s + 2) % 9];
      r.winding = specials[(s + 3) % 9];
    }
    r.raysPerPixel = k % 3 == 0 ? 1 : k % 3 == 1 ? 9 : 1024;
  }
  return out;
}

/// Every field, compared bit for bit.
::testing::AssertionResult sameBits(const RayRecord& a, const RayRecord& b)
{
  const std::vector<std::uint64_t> x = recordBits(a), y = recordBits(b);
  for (std::size_t k = 0; k < x.size(); ++k)
    if (x[k] != y[k])
      return ::testing::AssertionFailure()
             << "field " << k << " (integers first, then doubles) differs at pixel (" << a.i << ", "
             << a.j << ")";
  return ::testing::AssertionSuccess();
}

void expectSame(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    ASSERT_TRUE(sameBits(a[k], b[k])) << "record " << k;
  }
}

}

// readFrame's result comes from allocateRecords: its pages are faulted in by several threads
// (in slices of at least 16 MB) before the records are constructed; whatever the slicing, every
// record must be a default one and the vector exactly as long as asked.
TEST(RayStoreMemory, AllocatedRecordsAreDefaultRecords)
{
  const RayRecord fresh;
  // 0 and 1 records; one slice; several slices with a remainder (about 74 MB of records).
  for (const std::size_t count :
       { std::size_t(0), std::size_t(1), std::size_t(4099), std::size_t(271829) })
  {
    for (const int threads : { 0, 1, 3 })
    {
      const std::vector<RayRecord> records = asrt::allocateRecords(count, threads);
      ASSERT_EQ(records.size(), count) << threads << " threads";
      for (std::size_t k = 0; k < count; k += (k < 1000 || k + 1000 > count) ? 1 : 97)
        ASSERT_TRUE(sameBits(records[k], fresh))
          << "record " << k << " of " << count << ", " << threads << " threads";
    }
  }
}

TEST(RayStoreSchema, MigrateCreatesTheSchemaAndIsIdempotent)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  EXPECT_EQ(store.schemaVersion(), 0);
  EXPECT_NE(errorOf([&] { store.listFrames(); }).find("call migrate()"), std::string::npos);
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  Db db(ci);
  EXPECT_EQ(db.value("SELECT count(*) FROM schema_version"), "1");
  for (const char* rel : { "scenes", "frames", "ray_blocks", "rays_v" })
  {
    EXPECT_EQ(db.value(std::string("SELECT to_regclass('") + rel + "') IS NOT NULL"), "t") << rel;
  }
  EXPECT_TRUE(store.listFrames().empty());
}

TEST(RayStoreSchema, NewerSchemaVersionIsRefused)
{
  const std::string ci = freshDatabase();
  {
    RayStore store(ci);
    store.migrate();
  }
  Db db(ci);
  db.value("UPDATE schema_version SET version = 99");
  RayStore store(ci);
  EXPECT_EQ(store.schemaVersion(), 99);
  const std::string m = errorOf([&] { store.migrate(); });
  EXPECT_NE(m.find("schema version mismatch: found 99, this build knows " +
                   std::to_string(RayStore::kSchemaVersion)),
            std::string::npos)
    << m;
  const std::string l = errorOf([&] { store.listFrames(); });
  EXPECT_NE(l.find("found 99, this build knows " + std::to_string(RayStore::kSchemaVersion)),
            std::string::npos)
    << l;
  EXPECT_EQ(db.value("SELECT version FROM schema_version"), "99");
}

TEST(RayStoreFrames, RoundTripIsBitExact)
{
  RayStore store(freshDatabase());
  store.migrate();
  // Not a multiple of the block size: the last block is partial.
  const auto records = synthetic(100 * RayStore::kBlockSize + 17, 97);
  asrt::SceneDescription s = scene();
  s.camera.position = asrt::Vec3(0.1, -30.000000000000004, 1e-300);
  s.integrator.relativeTolerance = 1.2345678901234567e-9;
  const std::int64_t id =
    store.writeFrame(s, "round trip", records, asrt::FrameWriteOptions().tracedIn(12.5));
  expectSame(store.readFrame(id), records);

  const asrt::FrameInfo f = store.frameInfo(id);
  EXPECT_EQ(f.id, id);
  EXPECT_EQ(f.status, "complete");
  EXPECT_EQ(f.rayCount, std::int64_t(records.size()));
  EXPECT_EQ(f.label, "round trip");
  EXPECT_EQ(f.name, "three cylinders");
  EXPECT_EQ(bitsOf(f.key.spacetime.mass), bitsOf(1.0));
  EXPECT_EQ(bitsOf(f.key.spacetime.spin), bitsOf(0.25));
  EXPECT_EQ(bitsOf(f.key.cameraPosition.y()), bitsOf(-30.000000000000004));
  EXPECT_EQ(bitsOf(f.key.cameraPosition.z()), bitsOf(1e-300));
  EXPECT_EQ(bitsOf(f.key.relativeTolerance), bitsOf(1.2345678901234567e-9));
  EXPECT_EQ(f.key.width, 64);
  EXPECT_EQ(f.key.height, 48);
  EXPECT_EQ(f.key.method, "auto");
  EXPECT_EQ(f.traceSeconds, 12.5);
  EXPECT_GT(f.writeSeconds, 0);
  EXPECT_EQ(f.sceneHash.size(), 64u);
  EXPECT_EQ(f.frameHash.size(), 64u);
  EXPECT_FALSE(f.createdAt.empty());

  // An empty frame is a frame too.
  const std::int64_t empty = store.writeFrame(scene(2.0), "empty", {});
  EXPECT_TRUE(store.readFrame(empty).empty());
  EXPECT_EQ(store.frameInfo(empty).rayCount, 0);
  EXPECT_TRUE(std::isnan(store.frameInfo(empty).traceSeconds));
}

TEST(RayStoreFrames, SqlViewDecodesEveryValueExactly)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const auto records = synthetic(500, 20);
  const std::int64_t id = store.writeFrame(scene(), "view", records);
  Db db(ci);
  // Binary results: the doubles as the server computed them.
  const auto rows = db.binaryRows(
    "SELECT ray, i, j, termination, object_id, steps, hit_x, u, "
    "dvdj, winding, dudi, record_bytes, rays_per_pixel FROM rays_v WHERE frame_id = " +
    std::to_string(id) + " ORDER BY ray");
  const PGresult* r = rows.get();
  ASSERT_EQ(PQntuples(r), int(records.size()));
  auto word = [&](int row, int col) { return resultWord(r, row, col); };
  for (int row = 0; row < PQntuples(r); ++row)
  {
    const RayRecord& e = records[std::size_t(row)];
    // The packed record: every bit, NaN payloads included.
    ASSERT_EQ(std::string(PQgetvalue(r, row, 11), std::size_t(PQgetlength(r, row, 11))),
              packedRecord(e))
      << "row " << row;
    ASSERT_EQ(std::int64_t(word(row, 0)), row);
    ASSERT_EQ(std::int32_t(word(row, 1)), e.i);
    ASSERT_EQ(std::int32_t(word(row, 2)), e.j);
    ASSERT_EQ(std::int32_t(word(row, 3)), int(e.termination));
    ASSERT_EQ(std::int32_t(word(row, 4)), e.objectId);
    ASSERT_EQ(std::int64_t(word(row, 5)), e.steps);
    ASSERT_EQ(std::int32_t(word(row, 12)), e.raysPerPixel);
    const double expected[] = { e.hitPoint.x(), e.u, e.dvdj, e.winding, e.dudi };
    for (int c = 0; c < 5; ++c)
      ASSERT_TRUE(sameFromSql(fromBits(word(row, 6 + c)), expected[c]))
        << "row " << row << " column " << c;
  }
}

// The rays a pixel's colour comes from: one, a 3 × 3 supersample, the most a pixel may take.
TEST(RayStoreFrames, RaysPerPixelComeBackThroughEveryPath)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  std::vector<RayRecord> records = synthetic(3 * RayStore::kBlockSize + 7, 10);
  const std::int32_t counts[] = { 1, 9, 1024 };
  for (std::size_t k = 0; k < records.size(); ++k)
    records[k].raysPerPixel = counts[(k / 5) % 3];
  const std::int64_t id = store.writeFrame(scene(), "rays per pixel", records);
  expectSame(store.readFrame(id), records);
  Db db(ci);
  EXPECT_EQ(db.value("SELECT string_agg(rays_per_pixel::text, ',' ORDER BY ray) FROM rays_v "
                     "WHERE frame_id = " +
                     std::to_string(id)),
            [&]
            {
              std::string s;
              for (const RayRecord& r : records)
                s += (s.empty() ? "" : ",") + std::to_string(r.raysPerPixel);
              return s;
            }());
  // The word sits after color_b in the record (rays_v's column order), big-endian.
  const std::string packed =
    db.value("SELECT encode(substr(record_bytes, 229, 4), 'hex') FROM rays_v WHERE frame_id = " +
             std::to_string(id) + " AND ray = 5");
  EXPECT_EQ(packed, "00000009");
  std::vector<RayRecord> supersampled;
  for (const RayRecord& r : records)
    if (r.raysPerPixel > 1)
      supersampled.push_back(r);
  expectSame(store.readFrame(id, "rays_per_pixel > 1"), supersampled);

  // A tiled frame keeps them too.
  const std::int64_t tiled = store.beginTiledFrame(scene(2.0), "tiled", 2);
  store.writeTile(tiled, 1, std::vector<RayRecord>(records.begin() + 40, records.end()));
  store.writeTile(tiled, 0, std::vector<RayRecord>(records.begin(), records.begin() + 40));
  expectSame(store.readFrame(tiled), records);
}

TEST(RayStoreFrames, SameSceneAndParametersIsTheSameFrame)
{
  RayStore store(freshDatabase());
  store.migrate();
  const auto a = synthetic(5000, 64, 1);
  const auto b = synthetic(3000, 64, 2);
  const std::int64_t first = store.writeFrame(scene(), "first", a);
  ASSERT_EQ(store.findFrame(scene()), first);

  const std::string dup = errorOf([&] { store.writeFrame(scene(), "again", b); });
  EXPECT_NE(dup.find("duplicate frame"), std::string::npos) << dup;
  EXPECT_NE(dup.find("frame " + std::to_string(first)), std::string::npos) << dup;
  expectSame(store.readFrame(first), a);

  const std::int64_t replaced =
    store.writeFrame(scene(), "replaced", b, asrt::FrameWriteOptions().replacing());
  EXPECT_NE(replaced, first);
  EXPECT_EQ(store.findFrame(scene()), replaced);
  EXPECT_NE(errorOf([&] { store.frameInfo(first); }).find("no frame"), std::string::npos);
  expectSame(store.readFrame(replaced), b);

  const std::int64_t heavier = store.writeFrame(scene(1.5), "heavier", a);
  EXPECT_NE(heavier, replaced);
  EXPECT_EQ(store.findFrame(scene(1.5)), heavier);
  EXPECT_FALSE(store.findFrame(scene(1.75)).has_value());

  const auto frames = store.listFrames();
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].id, replaced);
  EXPECT_EQ(frames[0].label, "replaced");
  EXPECT_EQ(frames[0].rayCount, 3000);
  EXPECT_EQ(frames[0].key.spacetime.mass, 1.0);
  EXPECT_EQ(frames[1].id, heavier);
  EXPECT_EQ(frames[1].rayCount, 5000);
  EXPECT_EQ(frames[1].key.spacetime.mass, 1.5);
  for (const auto& f : frames)
  {
    EXPECT_EQ(f.status, "complete");
  }
  // Frames of one scene that differ only in their varying parameters share the scene row.
  EXPECT_EQ(frames[0].sceneId, frames[1].sceneId);
  EXPECT_EQ(frames[0].sceneHash, frames[1].sceneHash);
  EXPECT_NE(frames[0].frameHash, frames[1].frameHash);

  store.deleteFrame(heavier);
  EXPECT_EQ(store.listFrames().size(), 1u);
  EXPECT_NE(errorOf([&] { store.deleteFrame(heavier); }).find("no frame"), std::string::npos);
}

TEST(RayStoreFrames, PredicateSelectsASubset)
{
  RayStore store(freshDatabase());
  store.migrate();
  const auto records = synthetic(RayStore::kBlockSize + 2000, 100);
  const std::int64_t other = store.writeFrame(scene(3.0), "other", synthetic(3000, 100, 9));
  const std::int64_t id = store.writeFrame(scene(), "predicate", records);

  auto expectSubset = [&](const std::string& predicate, auto keep)
  {
    std::vector<RayRecord> expected;
    for (const RayRecord& r : records)
    {
      if (keep(r))
      {
        expected.push_back(r);
      }
    }
    ASSERT_FALSE(expected.empty()) << predicate;
    expectSame(store.readFrame(id, predicate), expected);
  };
  expectSubset("object_id = 2 AND image_order = 1",
               [](const RayRecord& r) { return r.objectId == 2 && r.imageOrder == 1; });
  // Float comparisons in SQL see exactly the stored doubles. PostgreSQL orders NaN above every
  // number, so NaN > 0.5 holds there.
  expectSubset("hit_x > 0.5 AND u <= 0.25 AND termination = 5",
               [](const RayRecord& r)
               {
                 return (std::isnan(r.hitPoint.x()) || r.hitPoint.x() > 0.5) && r.u <= 0.25 &&
                        r.termination == asrt::Termination::HitObject;
               });
  expectSubset("i BETWEEN 10 AND 20 AND j < 3",
               [](const RayRecord& r) { return r.i >= 10 && r.i <= 20 && r.j < 3; });
  // Text that closes the parentheses is refused before it reaches the server.
  EXPECT_EQ(errorOf([&] { store.readFrame(id, "false) OR (true"); })
              .find("the ray predicate was refused: \")\" at character 6"),
            0u);
  EXPECT_EQ(store.readFrame(other).size(), 3000u);
}

TEST(RayStoreFrames, PredicateCannotWrite)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const auto records = synthetic(3000, 50);
  const std::int64_t id = store.writeFrame(scene(), "target", records);
  Db db(ci);
  const std::string before = db.value("SELECT count(*) || ':' || sum(ray_count) FROM frames") +
                             db.value("SELECT last_value FROM frames_id_seq");

  for (const char* hostile :
       { "1=1; DELETE FROM frames", "1=1); DELETE FROM frames; SELECT (1",
         "nextval('frames_id_seq') > 0",
         "EXISTS (WITH d AS (DELETE FROM frames RETURNING 1) SELECT 1 FROM d)",
         "no_such_column = 1", "1 +", "pg_sleep(0.01) IS NOT NULL", "lo_create(0) > 0",
         "set_config('search_path', 'nowhere', false) IS NOT NULL" })
  {
    const std::string e = errorOf([&] { store.readFrame(id, hostile); });
    EXPECT_EQ(e.find("the ray predicate was refused: "), 0u) << hostile << ": " << e;
  }
  // What the grammar lets through can fail on the server, and changes nothing there either.
  const std::string e = errorOf([&] { store.readFrame(id, "i / 0 = 1"); });
  EXPECT_EQ(e.find("the ray predicate failed: ERROR:  division by zero"), 0u) << e;
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_largeobject_metadata"), "0");
  expectSame(store.readFrame(id, "object_id = 2"), store.readFrame(id, "object_id = 2"));

  EXPECT_EQ(db.value("SELECT count(*) || ':' || sum(ray_count) FROM frames") +
              db.value("SELECT last_value FROM frames_id_seq"),
            before);
  expectSame(store.readFrame(id), records);
  EXPECT_EQ(store.listFrames().size(), 1u);
}

TEST(RayStoreFrames, HostileLabelsAndNames)
{
  RayStore store(freshDatabase());
  store.migrate();
  const auto records = synthetic(100, 10);
  const std::string labels[] = { "it's; DROP TABLE frames; --",
                                 "\"quoted\" \\backslash\\ $1 %s %n ${x} E'\\x00'",
                                 "\xF0\x9F\x95\xB3\xEF\xB8\x8F black hole \xE2\x80\x94 \xCE\xBB",
                                 "tab\tnewline\ncarriage\r", "" };
  double mass = 1.0;
  for (const std::string& label : labels)
  {
    asrt::SceneDescription s = scene(mass += 0.125);
    s.name = label + "'; --";
    const std::int64_t id = store.writeFrame(s, label, records);
    const asrt::FrameInfo f = store.frameInfo(id);
    EXPECT_EQ(f.label, label);
    EXPECT_EQ(f.name, label + "'; --");
  }
  EXPECT_EQ(store.listFrames().size(), 5u);
  // Text that PostgreSQL cannot store exactly is refused before anything is written.
  for (const std::string& bad :
       { std::string("caf\xE9"), std::string("\xFF\xFE"), std::string("a\0b", 3),
         std::string("\xED\xA0\x80"), std::string("\xF0\x9F\x95") })
  {
    const std::string e = errorOf([&] { store.writeFrame(scene(100), bad, records); });
    EXPECT_NE(e.find("the label is not valid UTF-8"), std::string::npos) << e;
    asrt::SceneDescription s = scene(100);
    s.name = bad;
    const std::string n = errorOf([&] { store.writeFrame(s, "ok", records); });
    EXPECT_NE(n.find("the scene name is not valid UTF-8"), std::string::npos) << n;
  }
  EXPECT_EQ(store.listFrames().size(), 5u);
}

// A refused connection fails at once with the server's reason; a hang would be the suite's
// timeout, and a server that never answers is the connect_timeout's (SilentServerTimesOut).
TEST(RayStoreConnection, WrongCredentialsFailClearly)
{
  const std::string e =
    errorOf([&] { RayStore store(sharedServer().conninfo() + " user=no_such_user"); });
  EXPECT_NE(e.find("cannot connect to PostgreSQL"), std::string::npos) << e;
  EXPECT_NE(e.find("no_such_user"), std::string::npos) << e;
  const std::string db =
    errorOf([&] { RayStore store(sharedServer().conninfo() + " dbname=no_such_db"); });
  EXPECT_NE(db.find("no_such_db"), std::string::npos) << db;
}

TEST(RayStoreConnection, NoServerFailsClearly)
{
  char dir[] = "/tmp/asrt-noserver-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string e =
    errorOf([&] { RayStore store(std::string("host=") + dir + " dbname=asrt user=asrt"); });
  EXPECT_NE(e.find("cannot connect to PostgreSQL"), std::string::npos) << e;
  EXPECT_NE(e.find(dir), std::string::npos) << e;
  const std::string bad = errorOf([&] { RayStore store("host='unterminated"); });
  EXPECT_NE(bad.find("cannot connect to PostgreSQL"), std::string::npos) << bad;
  rmdir(dir);
}

// A server that takes the connection and never answers (a socket nobody reads) must not hang the
// store: the connect_timeout every store connection carries ends the wait with libpq's reason.
TEST(RayStoreConnection, SilentServerTimesOut)
{
  char dir[] = "/tmp/asrt-silent-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string socketPath = std::string(dir) + "/.s.PGSQL.5432";
  const int listener = socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(listener, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, socketPath.c_str(), sizeof(address.sun_path) - 1);
  ASSERT_EQ(bind(listener, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  ASSERT_EQ(listen(listener, 4), 0); // connections wait in the backlog, never accepted
  const std::string e =
    errorOf([&] { RayStore store(std::string("host=") + dir + " dbname=asrt user=asrt"); });
  close(listener);
  unlink(socketPath.c_str());
  rmdir(dir);
  EXPECT_NE(e.find("cannot connect to PostgreSQL"), std::string::npos) << e;
  EXPECT_NE(e.find("timeout expired"), std::string::npos) << e;
}

TEST(RayStoreFrames, FailedWriterLeavesNothing)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const auto records = synthetic(16384, 128);
  Db db(ci);

  // The record source throws halfway through the COPY.
  struct Halfway : std::runtime_error
  {
    using std::runtime_error::runtime_error;
  };
  EXPECT_THROW(store.writeFrame(scene(), "doomed", records.size(),
                                [&](std::size_t k, RayRecord& r)
                                {
                                  if (k == records.size() / 2)
                                  {
                                    throw Halfway("tracer failed");
                                  }
                                  r = records[k];
                                }),
               Halfway);
  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_FALSE(store.findFrame(scene()).has_value());
  EXPECT_EQ(db.value("SELECT count(*) FROM frames"), "0");
  EXPECT_EQ(db.value("SELECT count(*) FROM ray_blocks"), "0");
  // Nor a scene row: it was committed before the frame's transaction, and removed after.
  EXPECT_EQ(db.value("SELECT count(*) FROM scenes"), "0");

  // The connection dies halfway through the COPY.
  const int pid = store.backendPid();
  const std::string e = errorOf(
    [&]
    {
      store.writeFrame(scene(), "killed", records.size(),
                       [&](std::size_t k, RayRecord& r)
                       {
                         if (k == records.size() / 2)
                         {
                           db.value("SELECT pg_terminate_backend(" + std::to_string(pid) + ")");
                         }
                         r = records[k];
                       });
    });
  EXPECT_NE(e.find("failed"), std::string::npos) << e;
  EXPECT_EQ(db.value("SELECT count(*) FROM frames"), "0");
  EXPECT_EQ(db.value("SELECT count(*) FROM ray_blocks"), "0");

  // The same store reconnects and the next write succeeds.
  const std::int64_t id = store.writeFrame(scene(), "survivor", records);
  expectSame(store.readFrame(id), records);
  EXPECT_EQ(store.listFrames().size(), 1u);
}

// -----------------------------------------------------------------------------------------------
// Paths, and what frames leave behind.

namespace
{
/// Paths with the values that break careless storage, of 0 to 5000 points (a long one goes out of
/// line into TOAST).
std::vector<asrt::RayPath> syntheticPaths()
{
  std::vector<asrt::RayPath> paths;
  const int lengths[] = { 3, 0, 5000, 1, 250 };
  const int pixels[][2] = { { 5, 7 }, { 63, 47 }, { 0, 0 }, { 10, 20 }, { 7, 5 } };
  std::uint64_t s = 42;
  for (int k = 0; k < 5; ++k)
  {
    asrt::RayPath p;
    p.i = pixels[k][0];
    p.j = pixels[k][1];
    p.termination = asrt::Termination(k % 6);
    for (int m = 0; m < lengths[k]; ++m)
    {
      auto real = [&]
      {
        const std::uint64_t w = splitmix(s);
        return w % 13 == 0   ? fromBits(0x7FF0000000000F0Full | (w & 0x8000000000000000ull))
               : w % 13 == 1 ? -0.0
               : w % 13 == 2 ? std::numeric_limits<double>::denorm_min()
               : w % 13 == 3 ? -std::numeric_limits<double>::infinity()
                             : fromBits((w >> 12) | 0x4000000000000000ull) - 3.0;
      };
      p.points.push_back({ asrt::Vec3(real(), real(), real()), real(), real(), real() });
    }
    paths.push_back(p);
  }
  return paths;
}

void expectSamePaths(const std::vector<asrt::RayPath>& a, const std::vector<asrt::RayPath>& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    ASSERT_EQ(a[k].i, b[k].i) << "path " << k;
    ASSERT_EQ(a[k].j, b[k].j) << "path " << k;
    ASSERT_EQ(a[k].termination, b[k].termination) << "path " << k;
    ASSERT_EQ(a[k].points.size(), b[k].points.size()) << "path " << k;
    for (std::size_t m = 0; m < a[k].points.size(); ++m)
    {
      const asrt::PathPoint &p = a[k].points[m], &q = b[k].points[m];
      const double x[] = { p.x.x(), p.x.y(), p.x.z(), p.lambda, p.r, p.absH };
      const double y[] = { q.x.x(), q.x.y(), q.x.z(), q.lambda, q.r, q.absH };
      for (int c = 0; c < 6; ++c)
        ASSERT_EQ(bitsOf(x[c]), bitsOf(y[c])) << "path " << k << " point " << m << " value " << c;
    }
  }
}

/// The tables of rays attached to ray_blocks.
std::string blockTables(Db& db)
{
  return db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass");
}
}

TEST(RayStorePaths, RoundTripIsBitExactAndSqlSeesEveryPoint)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const auto records = synthetic(300, 64);
  const auto paths = syntheticPaths();
  const std::int64_t id =
    store.writeFrame(scene(), "paths", records, asrt::FrameWriteOptions().withPaths(paths));
  expectSame(store.readFrame(id), records);
  expectSamePaths(store.readPaths(id), paths);
  EXPECT_EQ(store.frameInfo(id).pathCount, 5);
  // A frame without paths has none.
  const std::int64_t bare = store.writeFrame(scene(2.0), "bare", records);
  EXPECT_TRUE(store.readPaths(bare).empty());
  EXPECT_EQ(store.frameInfo(bare).pathCount, 0);
  EXPECT_NE(errorOf([&] { store.readPaths(bare + 100); }).find("no frame"), std::string::npos);

  // path_points_v: one row per point, each value exact (every NaN is SQL's NaN).
  Db db(ci);
  const auto rows = db.binaryRows("SELECT path, point, i, j, x, y, z, lambda, r, abs_h FROM "
                                  "path_points_v WHERE frame_id = " +
                                  std::to_string(id) + " ORDER BY path, point");
  const PGresult* r = rows.get();
  ASSERT_EQ(PQntuples(r), 3 + 0 + 5000 + 1 + 250);
  auto word = [&](int row, int col) { return resultWord(r, row, col); };
  for (int row = 0; row < PQntuples(r); ++row)
  {
    const std::size_t path = word(row, 0), point = word(row, 1);
    ASSERT_LT(path, paths.size());
    const asrt::RayPath& p = paths[path];
    ASSERT_LT(point, p.points.size());
    ASSERT_EQ(std::int32_t(word(row, 2)), p.i);
    ASSERT_EQ(std::int32_t(word(row, 3)), p.j);
    const asrt::PathPoint& q = p.points[point];
    const double expected[] = { q.x.x(), q.x.y(), q.x.z(), q.lambda, q.r, q.absH };
    for (int c = 0; c < 6; ++c)
      ASSERT_TRUE(sameFromSql(fromBits(word(row, 4 + c)), expected[c]))
        << "row " << row << " column " << c;
  }
}

TEST(RayStorePaths, BadPathsAreRefusedBeforeTheDatabase)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const auto records = synthetic(100, 64);
  auto paths = syntheticPaths();
  paths[3].i = 64; // the frame is 64 × 48
  std::string e = errorOf(
    [&]
    { store.writeFrame(scene(), "outside", records, asrt::FrameWriteOptions().withPaths(paths)); });
  EXPECT_NE(e.find("path 3 (pixel 64, 20) lies outside the 64 x 48 frame"), std::string::npos) << e;
  paths = syntheticPaths();
  paths[4].i = 5;
  paths[4].j = 7;
  e = errorOf(
    [&]
    { store.writeFrame(scene(), "twice", records, asrt::FrameWriteOptions().withPaths(paths)); });
  EXPECT_NE(e.find("path 4 (pixel 5, 7): that pixel already has a path"), std::string::npos) << e;
  paths[4].j = -1;
  e = errorOf(
    [&] {
      store.writeFrame(scene(), "negative", records, asrt::FrameWriteOptions().withPaths(paths));
    });
  EXPECT_NE(e.find("lies outside"), std::string::npos) << e;
  EXPECT_EQ(db.value("SELECT (SELECT count(*) FROM frames) + (SELECT count(*) FROM scenes) + "
                     "(SELECT count(*) FROM ray_paths)"),
            "0");
}

TEST(RayStorePaths, LateFailureLeavesNeitherRaysNorPaths)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  // The server refuses the frame's last statement, after both COPYs went through.
  db.value("ALTER TABLE frame_tiles ADD CONSTRAINT veto CHECK (ray_count <> 777)");
  const auto records = synthetic(777, 64);
  const std::string e = errorOf(
    [&]
    {
      store.writeFrame(scene(), "vetoed", records,
                       asrt::FrameWriteOptions().withPaths(syntheticPaths()));
    });
  EXPECT_NE(e.find("recording the frame's rays failed"), std::string::npos) << e;
  EXPECT_NE(e.find("veto"), std::string::npos) << e;
  EXPECT_EQ(db.value("SELECT (SELECT count(*) FROM frames) || ':' || (SELECT count(*) FROM "
                     "ray_paths) || ':' || (SELECT count(*) FROM ray_blocks) || ':' || (SELECT "
                     "count(*) FROM scenes) || ':' || (SELECT count(*) FROM pg_class WHERE "
                     "relname LIKE 'ray\\_blocks\\_%')"),
            "0:0:0:0:0");
  EXPECT_TRUE(store.listFrames().empty());
  db.value("ALTER TABLE frame_tiles DROP CONSTRAINT veto");
  const std::int64_t id = store.writeFrame(scene(), "allowed", records,
                                           asrt::FrameWriteOptions().withPaths(syntheticPaths()));
  expectSame(store.readFrame(id), records);
  expectSamePaths(store.readPaths(id), syntheticPaths());
}

TEST(RayStoreFrames, ReplacedAndDeletedFramesLeaveNothingBehind)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const std::int64_t first = store.writeFrame(scene(), "first", synthetic(5000, 64), {});
  const std::int64_t other = store.writeFrame(scene(1.5), "other", synthetic(100, 64, 2));
  EXPECT_EQ(blockTables(db), "2");
  // Replacing drops the old frame's table of rays once the new frame is in.
  const std::int64_t second =
    store.writeFrame(scene(), "second", synthetic(3000, 64, 3),
                     asrt::FrameWriteOptions().withPaths(syntheticPaths()).replacing());
  EXPECT_NE(second, first);
  EXPECT_EQ(blockTables(db), "2");
  EXPECT_EQ(db.value("SELECT sum(n) FROM ray_blocks"), "3100");
  // Deleting drops its tables and paths; the scene row stays while another frame uses it.
  store.deleteFrame(second);
  EXPECT_EQ(blockTables(db), "1");
  EXPECT_EQ(db.value("SELECT count(*) || ':' || (SELECT count(*) FROM ray_paths) FROM scenes"),
            "1:0");
  // A frame deleted with plain SQL is invisible at once; migrate() drops what it left.
  db.value("DELETE FROM frames WHERE id = " + std::to_string(other));
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v"), "0");
  EXPECT_EQ(blockTables(db), "1");
  store.migrate();
  EXPECT_EQ(blockTables(db), "0");
  EXPECT_EQ(db.value("SELECT count(*) || ':' || (SELECT count(*) FROM ray_blocks) FROM scenes"),
            "0:0");
  // The scene comes back with the next frame.
  const std::int64_t again = store.writeFrame(scene(), "again", synthetic(10, 64));
  EXPECT_EQ(store.frameInfo(again).rayCount, 10);
}

namespace
{
/// The statements of the README's block of example queries (after "Researchers ask in SQL"),
/// comments dropped, one string each.
std::vector<std::string> readmeQueries()
{
  std::ifstream in(std::string(ASRT_SOURCE_DIR) + "/README.md");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t intro = text.find("Researchers ask in SQL");
  const std::size_t begin = text.find("```sql\n", intro);
  const std::size_t end = text.find("```", begin + 7);
  if (intro == std::string::npos || begin == std::string::npos || end == std::string::npos)
    return {};
  std::istringstream block(text.substr(begin + 7, end - begin - 7));
  std::vector<std::string> queries;
  std::string line, query;
  while (std::getline(block, line))
  {
    if (line.rfind("--", 0) == 0)
      continue;
    query += line + "\n";
    if (!line.empty() && line.back() == ';')
    {
      queries.push_back(query);
      query.clear();
    }
  }
  return queries;
}

/// Rows of a query as text (doubles in the server's shortest exact form), or the server's error.
std::vector<std::vector<std::string>> textRows(Db& db, const std::string& sql)
{
  std::unique_ptr<PGresult, void (*)(PGresult*)> r(PQexec(db.Conn, sql.c_str()), PQclear);
  if (PQresultStatus(r.get()) != PGRES_TUPLES_OK)
    throw std::runtime_error(sql + ": " + PQresultErrorMessage(r.get()));
  std::vector<std::vector<std::string>> rows(std::size_t(PQntuples(r.get())));
  for (int row = 0; row < PQntuples(r.get()); ++row)
    for (int col = 0; col < PQnfields(r.get()); ++col)
      rows[std::size_t(row)].push_back(PQgetvalue(r.get(), row, col));
  return rows;
}
}

// The README's example queries run as printed, and each answers what its comment says, checked
// against the records and paths as written (counted here, not by the server).
TEST(RayStoreSql, ReadmeQueriesAnswerWhatTheySay)
{
  const std::vector<std::string> queries = readmeQueries();
  ASSERT_EQ(queries.size(), 5u) << "the README's block of example queries changed";
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  std::vector<RayRecord> a = synthetic(1500, 64, 7), b = synthetic(2100, 64, 8);
  // Real windings are finite (SQL orders NaN above every number, so it would count as large).
  for (auto* records : { &a, &b })
    for (RayRecord& r : *records)
      if (std::isnan(r.winding))
        r.winding = 7.0;
  std::vector<asrt::RayPath> paths(3);
  for (std::size_t k = 0; k < paths.size(); ++k)
  {
    paths[k].i = int(3 * k + 1);
    paths[k].j = int(2 * k + 5);
    for (int m = 0; m < 40 + int(k); ++m)
    {
      const double r = 30.0 - 0.7 * m + 0.02 * m * m + double(k);
      paths[k].points.push_back({ asrt::Vec3(r, 0, 0), 0.5 * m, r, 1e-13 });
    }
  }
  const std::int64_t first = store.writeFrame(scene(1.0), "first", a);
  const std::int64_t second =
    store.writeFrame(scene(2.0), "second", b, asrt::FrameWriteOptions().withPaths(paths));
  // The README asks about frame 2; here that is whatever id the second frame got.
  auto forSecond = [&](std::string q)
  {
    const std::string id = "frame_id = " + std::to_string(second);
    for (std::size_t at = 0; (at = q.find("frame_id = 2", at)) != std::string::npos;
         at += id.size())
      q.replace(at, 12, id);
    return q;
  };
  Db db(ci);
  // std::stod refuses the denormals that the records hold (ERANGE); strtod reads them exactly.
  auto number = [](const std::string& text) { return std::strtod(text.c_str(), nullptr); };

  // The frames, with what varies between them.
  const auto frames = textRows(db, queries[0]);
  ASSERT_EQ(frames.size(), 2u);
  for (const auto& row : frames)
  {
    const bool isFirst = row[0] == std::to_string(first);
    EXPECT_TRUE(isFirst || row[0] == std::to_string(second)) << row[0];
    EXPECT_EQ(row[2], isFirst ? "first" : "second");
    EXPECT_EQ(number(row[3]), isFirst ? 1.0 : 2.0);
    EXPECT_EQ(row[8], std::to_string(isFirst ? a.size() : b.size()));
  }

  // The rays of frame 2 that hit object 2 in image order 1, with their hit points and lengths.
  std::map<std::pair<int, int>, const RayRecord*> hits;
  for (const RayRecord& r : b)
    if (r.objectId == 2 && r.imageOrder == 1)
      hits[{ r.i, r.j }] = &r;
  ASSERT_GT(hits.size(), 20u);
  const auto selected = textRows(db, forSecond(queries[1]));
  ASSERT_EQ(selected.size(), hits.size());
  for (const auto& row : selected)
  {
    const auto it = hits.find({ std::stoi(row[0]), std::stoi(row[1]) });
    ASSERT_NE(it, hits.end()) << "pixel " << row[0] << ", " << row[1] << " was not selected";
    const RayRecord& r = *it->second;
    const double expected[] = { r.hitPoint.x(), r.hitPoint.y(), r.hitPoint.z(), r.affineLength };
    for (int c = 0; c < 4; ++c)
    {
      const double got = number(row[std::size_t(2 + c)]);
      EXPECT_TRUE(got == expected[c] || (std::isnan(got) && std::isnan(expected[c])))
        << "column " << 2 + c << " of pixel " << row[0] << ", " << row[1];
    }
  }

  // How much of each frame the hole swallows: the fraction of captured rays.
  auto captured = [](const std::vector<RayRecord>& records)
  {
    std::size_t n = 0;
    for (const RayRecord& r : records)
      n += r.termination == asrt::Termination::Captured;
    return double(n) / double(records.size());
  };
  const auto fractions = textRows(db, queries[2]);
  ASSERT_EQ(fractions.size(), 2u);
  for (const auto& row : fractions)
    EXPECT_NEAR(number(row[1]), captured(row[0] == std::to_string(first) ? a : b), 1e-12)
      << "frame " << row[0];

  // Rays that wound round the hole more than once, by frame.
  auto wound = [](const std::vector<RayRecord>& records)
  {
    std::size_t n = 0;
    for (const RayRecord& r : records)
      n += r.winding > 2 * M_PI;
    return n;
  };
  const auto windings = textRows(db, queries[3]);
  ASSERT_EQ(windings.size(), 2u);
  for (const auto& row : windings)
    EXPECT_EQ(std::stoul(row[1]), wound(row[0] == std::to_string(first) ? a : b))
      << "frame " << row[0];

  // The closest approach to the hole along each stored path of frame 2, closest first.
  const auto approaches = textRows(db, forSecond(queries[4]));
  ASSERT_EQ(approaches.size(), paths.size());
  double previous = -1;
  for (const auto& row : approaches)
  {
    const asrt::RayPath* p = nullptr;
    for (const asrt::RayPath& q : paths)
      if (std::to_string(q.i) == row[0] && std::to_string(q.j) == row[1])
        p = &q;
    ASSERT_NE(p, nullptr) << "pixel " << row[0] << ", " << row[1];
    double rMin = p->points.front().r;
    for (const asrt::PathPoint& q : p->points)
      rMin = std::min(rMin, q.r);
    EXPECT_EQ(number(row[2]), rMin);
    EXPECT_GE(rMin, previous);
    previous = rMin;
  }
}
