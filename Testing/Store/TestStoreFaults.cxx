// asrt::RayStore under real faults: writers killed in the middle of a COPY, servers
// stopped between and during writes, wrong credentials and schema versions, concurrent writers in
// separate processes, hostile text through the whole path. Each test that breaks its server gets
// a server of its own.
//
// Forked children never touch gtest: they report by exit code (and a line on stderr), and they
// leave with _exit so that no destructor of the parent's objects (servers, connections) runs in
// them. Every child has an alarm() and the parent a deadline, so that a deadlock fails the test
// instead of hanging it.
#include "RayStore.h"
#include "SceneFile.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
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
std::vector<RayRecord> synthetic(std::uint64_t seed, std::size_t count, int width = 97)
{
  std::vector<RayRecord> out(count);
  for (std::size_t k = 0; k < count; ++k)
  {
    out[k] = syntheticRecord(seed, k, width);
  }
  return out;
}

/// The index of the first record that differs in any bit, or -1.
long firstDifference(const std::vector<RayRecord>& got, std::uint64_t seed, std::size_t count,
                     int width = 97)
{
  if (got.size() != count)
    return long(std::min(got.size(), count));
  for (std::size_t k = 0; k < count; ++k)
    if (recordBits(got[k]) != recordBits(syntheticRecord(seed, k, width)))
      return long(k);
  return -1;
}

/// A complete scene file, with an object whose name is text too.
const char* const sceneJson = R"({"name": "x", "description": "x",
  "spacetime": {"mass": 1, "spin": 0, "charge": 0},
  "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
             "viewAngle": 30, "resolution": [97, 64]},
  "objects": [{"type": "sphere", "id": 1, "name": "x", "center": [0, 10, 0], "radius": 1,
               "texture": {"color": [1, 0, 0]}}]})";

asrt::SceneDescription scene(double mass)
{
  asrt::SceneDescription d;
  d.name = "fault scene";
  d.spacetime.mass = mass;
  d.camera.width = 97;
  d.camera.height = 64;
  return d;
}

/// Children: a duplicate-frame error is the one these tests expect.
constexpr int Duplicate = ExpectedError;

template<typename F>
pid_t spawn(unsigned alarmSeconds, F&& body)
{
  return spawnChild(alarmSeconds, "duplicate frame", std::forward<F>(body));
}

std::string countsOf(Db& db)
{
  return db.value("SELECT (SELECT count(*) FROM frames) || ' frames, ' || (SELECT count(*) FROM "
                  "ray_blocks) || ' blocks, ' || (SELECT count(*) FROM ray_blocks b JOIN frames "
                  "f ON f.id = b.frame_id WHERE f.status <> 'complete') || ' incomplete blocks'");
}
}

// -----------------------------------------------------------------------------------------------
// 1. A writer killed with SIGKILL in the middle of its COPY leaves nothing, and the frame can be
// written again.

TEST(StoreFaultsKill, WriterKilledInTheMiddleOfCopyLeavesNothing)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  // Long enough (130 MB of COPY data at the stall) to be caught in the middle.
  const std::size_t count = 131072;
  const std::uint64_t seed = 7;

  const pid_t child =
    spawn(60,
          [&]
          {
            RayStore s(ci);
            s.writeFrame(scene(1.0), "doomed", count,
                         [&](std::size_t k, RayRecord& r)
                         {
                           // Stalls after half: the COPY stays open until the
                           // parent kills us.
                           if (k >= count / 2)
                           {
                             std::this_thread::sleep_for(std::chrono::milliseconds(10));
                           }
                           r = syntheticRecord(seed, k, 97);
                         });
            return int(Ok);
          });
  ASSERT_GT(child, 0);

  // Some of the half that was sent must have reached the server inside the COPY.
  const auto t0 = Clock::now();
  const std::string progress = pollUntil(
    db,
    "SELECT coalesce(max(p.tuples_processed), 0) FROM pg_stat_progress_copy p JOIN "
    "pg_stat_activity a USING (pid) WHERE a.query LIKE 'COPY ray_blocks%'",
    [](const std::string& v) { return std::stoll(v) >= 8; }, 20);
  const double untilCopy = secondsSince(t0);
  const std::string backend = db.value(
    "SELECT pid FROM pg_stat_activity WHERE query LIKE 'COPY ray_blocks%' AND state = 'active'");
  kill(child, SIGKILL);
  const int code = waitChild(child, Clock::now() + std::chrono::seconds(10));
  ASSERT_GE(std::stoll(progress), 8) << "the COPY never got going";
  EXPECT_EQ(code, 128 + SIGKILL);
  std::printf("[ fault ] COPY in progress after %.3f s (%s blocks received); child killed\n",
              untilCopy, progress.c_str());

  // The server notices the dead client and rolls its transaction back.
  const auto t1 = Clock::now();
  const std::string left = pollUntil(
    db, "SELECT count(*) FROM pg_stat_activity WHERE pid = " + backend,
    [](const std::string& v) { return v == "0"; }, 10);
  EXPECT_EQ(left, "0") << "the killed writer's backend " << backend << " lingers";
  std::printf("[ fault ] the killed writer's backend was gone %.3f s after the kill\n",
              secondsSince(t1));

  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_FALSE(store.findFrame(scene(1.0)).has_value());
  EXPECT_EQ(countsOf(db), "0 frames, 0 blocks, 0 incomplete blocks");

  const auto t2 = Clock::now();
  const std::int64_t id = store.writeFrame(scene(1.0), "again", synthetic(seed, count));
  std::printf("[ fault ] rewriting the frame (%zu rays) took %.3f s\n", count, secondsSince(t2));
  EXPECT_EQ(firstDifference(store.readFrame(id), seed, count), -1);
  ASSERT_EQ(store.listFrames().size(), 1u);
  EXPECT_EQ(store.listFrames()[0].label, "again");
  EXPECT_EQ(store.findFrame(scene(1.0)), id);
}

// -----------------------------------------------------------------------------------------------
// 2. The server stopped between writes: the open store fails clearly (its times are printed, not
// judged), then recovers.

TEST(StoreFaultsServer, StoppedBetweenWritesFailsClearlyAndRecovers)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  const std::size_t count = 12299;
  const std::int64_t first = store.writeFrame(scene(1.0), "first", synthetic(1, count));

  // A fast shutdown, so that the committed frame is certainly on disk (this server runs with
  // synchronous_commit = off).
  pg.stop(false);
  ASSERT_FALSE(pg.running());

  auto t0 = Clock::now();
  const std::string w = errorOf([&] { store.writeFrame(scene(2.0), "second", synthetic(2, 10)); });
  const double tw = secondsSince(t0);
  t0 = Clock::now();
  const std::string r = errorOf([&] { store.readFrame(first); });
  const double tr = secondsSince(t0);
  t0 = Clock::now();
  const std::string l = errorOf([&] { store.listFrames(); });
  const double tl = secondsSince(t0);
  std::printf("[ fault ] write %.3f s: %s\n[ fault ] read %.3f s: %s\n[ fault ] list %.3f s: %s\n",
              tw, w.c_str(), tr, r.c_str(), tl, l.c_str());
  for (const std::string* m : { &w, &r, &l })
  {
    EXPECT_EQ(m->find("(no"), std::string::npos) << *m;
    EXPECT_NE(m->find("connection"), std::string::npos) << *m;
  }

  pg.start();
  // The same store reconnects by itself.
  t0 = Clock::now();
  EXPECT_EQ(firstDifference(store.readFrame(first), 1, count), -1);
  std::printf("[ fault ] the open store's first read after the restart took %.3f s\n",
              secondsSince(t0));
  const std::int64_t second = store.writeFrame(scene(2.0), "second", synthetic(2, 10));
  EXPECT_EQ(firstDifference(store.readFrame(second), 2, 10), -1);
  // And so does a fresh one.
  RayStore fresh(ci);
  ASSERT_EQ(fresh.listFrames().size(), 2u);
  EXPECT_EQ(fresh.listFrames()[0].label, "first");
  EXPECT_EQ(firstDifference(fresh.readFrame(first), 1, count), -1);
}

// -----------------------------------------------------------------------------------------------
// 3. The server stopped (immediate) or restarted (fast) in the middle of a streaming write.

namespace
{
void interruptedWrite(bool restart)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  const std::int64_t kept = store.writeFrame(scene(1.0), "kept", synthetic(1, 1000));
  if (!restart)
  {
    // A frame committed just before an immediate stop may be lost on this non-durable server
    // (synchronous_commit = off): make it durable first.
    Db(ci).value("CHECKPOINT");
  }
  const std::size_t count = 65536;
  const auto t0 = Clock::now();
  double stopSeconds = 0;
  const std::string e = errorOf(
    [&]
    {
      store.writeFrame(scene(2.0), "interrupted", count,
                       [&](std::size_t k, RayRecord& rec)
                       {
                         if (k == count / 2)
                         {
                           const auto s0 = Clock::now();
                           if (restart)
                           {
                             pg.restart();
                           }
                           else
                           {
                             pg.stop(true);
                           }
                           stopSeconds = secondsSince(s0);
                         }
                         rec = syntheticRecord(2, k, 97);
                       });
    });
  const double failSeconds = secondsSince(t0) - stopSeconds;
  std::printf("[ fault ] %s took %.3f s; the write then failed after %.3f s more: %s\n",
              restart ? "restart" : "immediate stop", stopSeconds, failSeconds, e.c_str());
  EXPECT_EQ(e.find("(no"), std::string::npos) << e;
  EXPECT_NE(e.find("writing the rays failed"), std::string::npos) << e;
  EXPECT_NE(e.find("connection"), std::string::npos) << e;

  if (!restart)
  {
    // While it is down, the store says so at once.
    const std::string down = errorOf([&] { store.listFrames(); });
    EXPECT_NE(down.find("could not reconnect"), std::string::npos) << down;
    pg.start();
  }
  Db db(ci);
  EXPECT_EQ(countsOf(db),
            "1 frames, " +
              std::to_string((1000 + RayStore::kBlockSize - 1) / RayStore::kBlockSize) +
              " blocks, 0 incomplete blocks");
  EXPECT_FALSE(store.findFrame(scene(2.0)).has_value());
  ASSERT_EQ(store.listFrames().size(), 1u);
  EXPECT_EQ(firstDifference(store.readFrame(kept), 1, 1000), -1);

  // The retry, on the same store.
  const std::int64_t id =
    store.writeFrame(scene(2.0), "retried", count,
                     [](std::size_t k, RayRecord& rec) { rec = syntheticRecord(2, k, 97); });
  EXPECT_EQ(firstDifference(store.readFrame(id), 2, count), -1);
  EXPECT_EQ(store.listFrames().size(), 2u);
}
}

TEST(StoreFaultsServer, ImmediateStopDuringWriteLeavesNothingAndRetrySucceeds)
{
  interruptedWrite(false);
}

TEST(StoreFaultsServer, RestartDuringWriteLeavesNothingAndRetrySucceeds)
{
  interruptedWrite(true);
}

// -----------------------------------------------------------------------------------------------
// 4. Wrong credentials, no server, a newer schema: three clear, distinct messages (times printed,
// not judged).

TEST(StoreFaultsConnection, ThreeFailuresThreeDistinctMessages)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  {
    RayStore store(ci);
    store.migrate();
    store.writeFrame(scene(1.0), "one", synthetic(1, 100));
  }

  auto t0 = Clock::now();
  const std::string user = errorOf([&] { RayStore s(ci + " user=no_such_user"); });
  const double tUser = secondsSince(t0);

  Db(ci).value("UPDATE schema_version SET version = 99");
  t0 = Clock::now();
  std::string schema;
  {
    RayStore s(ci);
    schema = errorOf([&] { s.listFrames(); });
    const std::string m = errorOf([&] { s.migrate(); });
    EXPECT_NE(m.find("schema version mismatch: found 99"), std::string::npos) << m;
    const std::string w = errorOf([&] { s.writeFrame(scene(2.0), "two", synthetic(2, 10)); });
    EXPECT_NE(w.find("schema version mismatch: found 99"), std::string::npos) << w;
  }
  const double tSchema = secondsSince(t0);
  EXPECT_EQ(Db(ci).value("SELECT version || ':' || (SELECT count(*) FROM frames) FROM "
                         "schema_version"),
            "99:1");

  pg.stop(true);
  t0 = Clock::now();
  const std::string none = errorOf([&] { RayStore s(ci); });
  const double tNone = secondsSince(t0);

  std::printf("[ fault ] wrong user %.3f s: %s\n[ fault ] no server %.3f s: %s\n"
              "[ fault ] schema 99 %.3f s: %s\n",
              tUser, user.c_str(), tNone, none.c_str(), tSchema, schema.c_str());
  EXPECT_NE(user.find("cannot connect to PostgreSQL"), std::string::npos) << user;
  EXPECT_NE(user.find("role \"no_such_user\" does not exist"), std::string::npos) << user;
  EXPECT_NE(none.find("cannot connect to PostgreSQL"), std::string::npos) << none;
  EXPECT_NE(none.find("No such file or directory"), std::string::npos) << none;
  EXPECT_NE(schema.find("schema version mismatch: found 99, this build knows " +
                        std::to_string(asrt::RayStore::kSchemaVersion)),
            std::string::npos)
    << schema;
  EXPECT_NE(schema.find("newer ASRT"), std::string::npos) << schema;
  EXPECT_NE(user, none);
  EXPECT_NE(user, schema);
  EXPECT_NE(none, schema);
  EXPECT_EQ(none.find("no_such_user"), std::string::npos);
}

// -----------------------------------------------------------------------------------------------
// 5. Concurrent writers in separate processes.

TEST(StoreFaultsConcurrent, ManyWritersAndOneDuplicatePairAllEndIntact)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  constexpr int Writers = 4, FramesEach = 5;
  const std::size_t count = 12305;
  // Every child migrates an empty database at once: migrate() must serialise them.
  StartGate gate;
  std::vector<pid_t> writers, twins;
  for (int w = 0; w < Writers; ++w)
  {
    writers.push_back(spawn(50,
                            [&, w]
                            {
                              gate.wait();
                              RayStore s(ci);
                              s.migrate();
                              for (int f = 0; f < FramesEach; ++f)
                              {
                                const std::uint64_t seed = std::uint64_t(100 * w + f);
                                s.writeFrame(scene(2.0 + w + 0.125 * f),
                                             "w" + std::to_string(w) + "f" + std::to_string(f),
                                             synthetic(seed, count));
                              }
                              return int(Ok);
                            }));
  }
  for (int t = 0; t < 2; ++t)
  {
    twins.push_back(spawn(50,
                          [&, t]
                          {
                            gate.wait();
                            RayStore s(ci);
                            s.migrate();
                            // A pause inside the COPY keeps both twins' transactions open at
                            // the same time.
                            s.writeFrame(scene(99.0), "twin" + std::to_string(t), count,
                                         [&](std::size_t k, RayRecord& r)
                                         {
                                           if (k == count / 2)
                                           {
                                             std::this_thread::sleep_for(
                                               std::chrono::milliseconds(300));
                                           }
                                           r = syntheticRecord(1000 + std::uint64_t(t), k, 97);
                                         });
                            return int(Ok);
                          }));
  }
  const auto t0 = Clock::now();
  gate.open();
  const auto deadline = t0 + std::chrono::seconds(45);
  std::vector<int> writerCodes, twinCodes;
  for (pid_t p : writers)
  {
    writerCodes.push_back(waitChild(p, deadline));
  }
  for (pid_t p : twins)
  {
    twinCodes.push_back(waitChild(p, deadline));
  }
  std::printf("[ fault ] %d writers x %d frames + 2 twins done in %.3f s; twins exited %d, %d\n",
              Writers, FramesEach, secondsSince(t0), twinCodes[0], twinCodes[1]);
  for (int w = 0; w < Writers; ++w)
  {
    EXPECT_EQ(writerCodes[std::size_t(w)], 0)
      << "writer " << w << " (-1: deadline, 142: its alarm)";
  }
  // Exactly one twin wins; the other is told it is a duplicate.
  EXPECT_EQ(std::multiset<int>(twinCodes.begin(), twinCodes.end()),
            (std::multiset<int>{ int(Ok), int(Duplicate) }))
    << twinCodes[0] << ", " << twinCodes[1];

  RayStore store(ci);
  const auto frames = store.listFrames();
  EXPECT_EQ(frames.size(), std::size_t(Writers * FramesEach + 1));
  std::set<std::string> seen;
  for (const asrt::FrameInfo& f : frames)
  {
    seen.insert(f.label);
    std::uint64_t seed;
    if (f.label.rfind("twin", 0) == 0)
    {
      const int t = f.label == "twin0" ? 0 : 1;
      EXPECT_EQ(twinCodes[std::size_t(t)], int(Ok)) << "the stored twin is the one that failed";
      EXPECT_EQ(f.key.spacetime.mass, 99.0);
      seed = 1000 + std::uint64_t(t);
    }
    else
    {
      const int w = f.label[1] - '0', k = f.label[3] - '0';
      EXPECT_EQ(bitsOf(f.key.spacetime.mass), bitsOf(2.0 + w + 0.125 * k)) << f.label;
      seed = std::uint64_t(100 * w + k);
    }
    EXPECT_EQ(f.rayCount, std::int64_t(count)) << f.label;
    EXPECT_EQ(firstDifference(store.readFrame(f.id), seed, count), -1) << f.label;
  }
  EXPECT_EQ(seen.size(), frames.size());
  Db db(ci);
  EXPECT_EQ(db.value("SELECT count(*) FROM schema_version"), "1");
  EXPECT_EQ(db.value("SELECT count(*) FROM scenes"), "1");
  EXPECT_EQ(db.value("SELECT count(*) FROM frames WHERE status <> 'complete'"), "0");
}

// While one process writes a frame of a scene (its COPY stalled, as when the records come straight
// from a slow tracer), a second process writes another frame of the same scene (another mass).
// Nothing ties the two frames together, so the second write should not wait for the first.
TEST(StoreFaultsFinding, WriterOfAnotherFrameOfTheSameSceneIsNotBlocked)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  const std::size_t count = 16384;
  // The scene row exists already, as it does for every frame of a movie after the first.
  store.writeFrame(scene(1.0), "earlier frame", synthetic(1, 100));

  double secondSeconds = -1;
  int secondCode = -100;
  std::string waitEvent, blockedBy;
  store.writeFrame(scene(2.0), "slow frame", count,
                   [&](std::size_t k, RayRecord& r)
                   {
                     if (k == count / 2)
                     {
                       const auto t0 = Clock::now();
                       const pid_t other =
                         spawn(20,
                               [&]
                               {
                                 RayStore s(ci);
                                 s.writeFrame(scene(3.0), "other frame", synthetic(3, 100));
                                 return int(Ok);
                               });
                       // It ends by itself unless a lock holds it: watch for a lock wait
                       // until it has ended. A lock wait, or no end within a minute (far more
                       // than a 100-ray frame needs on a loaded machine), is the failure.
                       const std::string locks =
                         "SELECT coalesce(string_agg(wait_event_type || '/' || wait_event || "
                         "' blocked by ' || pg_blocking_pids(pid)::text || ': ' || "
                         "left(query, 60), '; '), '') FROM pg_stat_activity WHERE "
                         "wait_event_type = 'Lock'";
                       const auto deadline = t0 + std::chrono::seconds(60);
                       for (;;)
                       {
                         int status = 0;
                         if (waitpid(other, &status, WNOHANG) == other)
                         {
                           secondCode = WIFEXITED(status) ? WEXITSTATUS(status) : -3;
                           break;
                         }
                         waitEvent = db.value(locks);
                         if (!waitEvent.empty() || Clock::now() > deadline)
                         {
                           secondCode = waitChild(other, Clock::now());
                           break;
                         }
                         std::this_thread::sleep_for(std::chrono::milliseconds(20));
                       }
                       secondSeconds = secondsSince(t0);
                     }
                     r = syntheticRecord(2, k, 97);
                   });
  std::printf("[ fault ] the other writer: exit %d after %.3f s; lock waits seen: %s\n", secondCode,
              secondSeconds, waitEvent.empty() ? "(none)" : waitEvent.c_str());
  EXPECT_EQ(secondCode, 0) << "the writer of another frame of the same scene was blocked (killed); "
                              "lock waits: "
                           << waitEvent;
  EXPECT_TRUE(waitEvent.empty()) << waitEvent;
  EXPECT_EQ(countsOf(db).substr(0, 8), secondCode == 0 ? "3 frames" : "2 frames");
}

// -----------------------------------------------------------------------------------------------
// 6. Hostile text through the whole path: scene JSON → SceneDescription → store → listFrames.

TEST(StoreFaultsText, HostileNamesAndLabelsRoundTripAndInvalidTextIsRefused)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  const auto records = synthetic(5, 300);
  const std::string hostile[] = {
    "it's \"quoted\"; DROP TABLE frames; -- and /* a comment */",
    "'); DELETE FROM frames WHERE ('1' = '1",
    "$1 $$dollar$$ %s %n \\x00 \\\\ E'\\'' ::text",
    "\xF0\x9F\x95\xB3 \xE2\x80\x94 \xCE\xBB \xE2\x80\xAE reversed",
    "line\nbreak\ttab\rreturn \x7F",
  };
  Db db(ci);
  double mass = 1.0;
  std::vector<std::pair<std::int64_t, std::string>> stored;
  for (const std::string& h : hostile)
  {
    // Through a real scene file: the name, an object's name and the description are JSON strings.
    nlohmann::json doc = nlohmann::json::parse(sceneJson);
    doc["name"] = h;
    doc["description"] = h + " (description)";
    doc["objects"][0]["name"] = h;
    doc["spacetime"]["mass"] = mass += 0.125;
    const asrt::SceneDescription s = asrt::parseScene(doc.dump(), "", nullptr);
    ASSERT_EQ(s.name, h);
    const std::string label = "label: " + h;
    const std::int64_t id = store.writeFrame(s, label, records);
    stored.emplace_back(id, h);
    EXPECT_EQ(store.findFrame(s), id) << h;
    // The stored scene text parses back to the same name.
    EXPECT_EQ(asrt::parseSceneWithoutImages(store.frameSceneText(id)).name, h);
    EXPECT_EQ(firstDifference(store.readFrame(id), 5, 300), -1);
  }
  const auto frames = store.listFrames();
  ASSERT_EQ(frames.size(), stored.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    EXPECT_EQ(frames[k].id, stored[k].first);
    EXPECT_EQ(frames[k].name, stored[k].second);
    EXPECT_EQ(frames[k].label, "label: " + stored[k].second);
  }
  EXPECT_EQ(db.value("SELECT count(*) FROM frames"), std::to_string(stored.size()));

  // Text PostgreSQL cannot hold exactly is refused, with a clear message, and leaves nothing.
  const std::string before = countsOf(db) + db.value("SELECT last_value FROM frames_id_seq");
  const std::string bad[] = { std::string("caf\xE9 ; --"),     std::string("\xC0\xAF"),
                              std::string("ok\xED\xA0\x80"),   std::string("a\0b", 3),
                              std::string("\xF4\x90\x80\x80"), std::string("trunc\xE2\x80") };
  for (const std::string& b : bad)
  {
    const std::string e = errorOf([&] { store.writeFrame(scene(50), b, records); });
    EXPECT_NE(e.find("the label is not valid UTF-8"), std::string::npos) << e;
    EXPECT_NE(e.find("it was not stored"), std::string::npos) << e;
    asrt::SceneDescription s = scene(50);
    s.name = b;
    const std::string n = errorOf([&] { store.writeFrame(s, "fine", records); });
    EXPECT_NE(n.find("the scene name is not valid UTF-8"), std::string::npos) << n;
    EXPECT_FALSE(store.findFrame(scene(50)).has_value());
  }
  // A NUL can reach the name through a valid JSON escape.
  {
    nlohmann::json doc = nlohmann::json::parse(sceneJson);
    doc["name"] = std::string("nul\0inside", 10);
    const asrt::SceneDescription s = asrt::parseScene(doc.dump(), "", nullptr);
    const std::string e = errorOf([&] { store.writeFrame(s, "fine", records); });
    EXPECT_NE(e.find("the scene name"), std::string::npos) << e;
    EXPECT_NE(e.find("NUL"), std::string::npos) << e;
  }
  EXPECT_EQ(countsOf(db) + db.value("SELECT last_value FROM frames_id_seq"), before);
  EXPECT_EQ(store.listFrames().size(), stored.size());
}

// A NUL elsewhere in a valid scene (its description, an object's name) is legal JSON and legal
// in a SceneDescription, but jsonb refuses the \u0000 escape.
// EmbeddedPostgres::setDurable(false) promises only that an OS crash may corrupt the cluster. A
// server crash (here an immediate stop, as after a power-less kill of the postmaster) should then
// keep every frame whose writeFrame returned.
TEST(StoreFaultsFinding, NonDurableServerKeepsFramesCommittedBeforeAnImmediateStop)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  int lost = 0;
  const int rounds = 3;
  for (int k = 0; k < rounds; ++k)
  {
    {
      RayStore store(ci);
      store.migrate();
      store.writeFrame(scene(1.0 + k), "just committed", synthetic(1, 2000));
    }
    pg.stop(true);
    pg.start();
    RayStore store(ci);
    if (!store.findFrame(scene(1.0 + k)).has_value())
    {
      ++lost;
    }
  }
  std::printf("[ fault ] frames lost to an immediate stop right after their commit: %d of %d\n",
              lost, rounds);
  EXPECT_EQ(lost, 0);
}

TEST(StoreFaultsFinding, SceneWithNulInDescriptionIsStoredOrRefusedUpFront)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate();
  nlohmann::json doc = nlohmann::json::parse(sceneJson);
  doc["description"] = std::string("nul\0inside", 10);
  const asrt::SceneDescription s = asrt::parseScene(doc.dump(), "", nullptr);
  const std::string e = errorOf([&] { store.writeFrame(s, "fine", synthetic(5, 5)); });
  std::printf("[ fault ] a NUL in the description: %s\n", e.c_str());
  // Either outcome is acceptable: stored, or refused before touching the database, like a NUL in
  // the name ("... it was not stored").
  EXPECT_TRUE(e == "(no error)" || e.find("it was not stored") != std::string::npos) << e;
  EXPECT_EQ(Db(ci).value("SELECT count(*) FROM frames"), e == "(no error)" ? "1" : "0");
}

// -----------------------------------------------------------------------------------------------
// 7. Parallel writes: a large frame goes in over several connections, as that many tiles, and is
// still one frame made visible by one commit. The tables that helper connections commit before it
// are dropped when the write fails, and by the next migrate() when the writer died.

namespace
{
/// Tables of rays that are not (yet, or any more) partitions of ray_blocks.
std::string unattachedTables(Db& db)
{
  return db.value("SELECT count(*) FROM pg_class WHERE relname ~ '^ray_blocks_[0-9]+_[0-9]+$' AND "
                  "relkind = 'r' AND NOT relispartition");
}

/// Waits until a helper connection has committed its tile (tile 1); "1" once it has.
std::string helperTileCommitted(Db& db)
{
  return pollUntil(
    db, "SELECT count(*) FROM pg_class WHERE relname ~ '^ray_blocks_[0-9]+_1$'",
    [](const std::string& v) { return v == "1"; }, 20);
}

/// The first tile's size in a write of `count` rays over `tiles` connections, as the header
/// promises: consecutive rays, whole rows of kBlockSize in every tile but the last.
std::size_t firstTile(std::size_t count, std::size_t tiles)
{
  return count / tiles / RayStore::kBlockSize * RayStore::kBlockSize;
}

/// A write over two connections in a thread of its own, whose producer stalls at ray `stallAt`
/// (in the tile of the connection that should stall) until released.
struct StalledWrite
{
  StalledWrite(RayStore& store, std::uint64_t seed, std::size_t count, std::size_t stallAt)
    : Thread(
        [this, &store, seed, count, stallAt]
        {
          this->Error = errorOf(
            [&]
            {
              this->Id = store.writeFrame(
                scene(1.0), "stalled", count,
                [&](std::size_t k, RayRecord& r)
                {
                  while (k == stallAt && !this->Released)
                    std::this_thread::sleep_for(std::chrono::milliseconds(5));
                  r = syntheticRecord(seed, k, 97);
                },
                asrt::FrameWriteOptions().fromConcurrentProducer());
            });
        })
  {
  }
  ~StalledWrite() { this->finish(); }
  void finish()
  {
    this->Released = true;
    if (this->Thread.joinable())
      this->Thread.join();
  }
  std::atomic<bool> Released{ false };
  std::int64_t Id = -1;
  std::string Error;
  std::thread Thread;
};
}

/// A throwaway server with the schema, a store and a plain connection to look behind its back.
/// After a failure: the frame can be written again, as two tiles, and reads back bit-exact.
void expectWrittenAgain(RayStore& store, std::uint64_t seed, std::size_t count)
{
  const std::int64_t id = store.writeFrame(scene(1.0), "again", synthetic(seed, count));
  EXPECT_EQ(firstDifference(store.readFrame(id), seed, count), -1);
  EXPECT_EQ(store.frameInfo(id).tileCount, 2);
}

class StoreParallelWrite : public ::testing::Test
{
protected:
  void SetUp() override { this->Store.migrate(); }
  ThrowawayPostgres Pg;
  const std::string Ci = Pg.conninfo();
  RayStore Store{ Ci };
  Db Database{ Ci };
};

TEST_F(StoreParallelWrite, LargeFrameIsOneFrameOfOneTilePerConnection)
{
  RayStore& store = this->Store;
  Db& db = this->Database;
  EXPECT_EQ(store.writeConnections(), 2);
  EXPECT_NE(errorOf([&] { store.setWriteConnections(0); }).find("at least one connection"),
            std::string::npos);

  const std::size_t count = 2 * RayStore::kParallelMinRays + 45;
  const std::vector<RayRecord> recs = synthetic(3, count);
  const std::int64_t two = store.writeFrame(scene(1.0), "two", recs);
  EXPECT_EQ(store.frameInfo(two).tileCount, 2);
  EXPECT_EQ(store.frameInfo(two).rayCount, std::int64_t(count));
  EXPECT_EQ(firstDifference(store.readFrame(two), 3, count), -1);
  const std::size_t half = firstTile(count, 2);
  const std::string id = std::to_string(two);
  EXPECT_EQ(db.value("SELECT string_agg(tile || ':' || ray_count, ',' ORDER BY tile) FROM "
                     "frame_tiles WHERE frame_id = " +
                     id),
            "0:" + std::to_string(half) + ",1:" + std::to_string(count - half));
  // SQL numbers the rays of the frame straight through the tiles.
  EXPECT_EQ(
    db.value("SELECT count(*) || ':' || min(ray) || ':' || max(ray) || ':' || count(DISTINCT "
             "ray) FROM rays_v WHERE frame_id = " +
             id),
    std::to_string(count) + ":0:" + std::to_string(count - 1) + ":" + std::to_string(count));
  const std::vector<RayRecord> across = store.readFrame(
    two, "ray BETWEEN " + std::to_string(half - 2) + " AND " + std::to_string(half + 1));
  ASSERT_EQ(across.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_EQ(recordBits(across[k]), recordBits(syntheticRecord(3, half - 2 + k, 97))) << k;
  EXPECT_EQ(unattachedTables(db), "0");

  // One connection: the same rays as one tile. Four: four tiles.
  RayStore one(this->Ci);
  one.setWriteConnections(1);
  const std::int64_t single = one.writeFrame(scene(2.0), "one", recs);
  EXPECT_EQ(one.frameInfo(single).tileCount, 1);
  EXPECT_EQ(firstDifference(one.readFrame(single), 3, count), -1);
  RayStore four(this->Ci);
  four.setWriteConnections(4);
  const std::size_t count4 = 4 * RayStore::kParallelMinRays + 7;
  const std::int64_t quad = four.writeFrame(scene(3.0), "four", synthetic(4, count4));
  EXPECT_EQ(four.frameInfo(quad).tileCount, 4);
  EXPECT_EQ(firstDifference(four.readFrame(quad), 4, count4), -1);
  // A frame too small to share goes over one connection whatever the setting.
  const std::int64_t small = four.writeFrame(scene(4.0), "small", synthetic(5, 1000));
  EXPECT_EQ(four.frameInfo(small).tileCount, 1);
  EXPECT_EQ(unattachedTables(db), "0");
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass"),
            "8");
}

TEST_F(StoreParallelWrite, KilledWriterLeavesNothingVisibleAndMigrateSweepsItsCommittedTile)
{
  RayStore& store = this->Store;
  Db& db = this->Database;
  const std::size_t count = 2 * RayStore::kParallelMinRays;
  const std::size_t half = firstTile(count, 2);
  const std::uint64_t seed = 11;

  // The main connection's tile stalls half-way; the helper's runs through and commits.
  const pid_t child = spawnChild(60, "",
                                 [&]
                                 {
                                   RayStore s(this->Ci);
                                   s.writeFrame(
                                     scene(1.0), "doomed", count,
                                     [&](std::size_t k, RayRecord& r)
                                     {
                                       if (k >= half / 2 && k < half)
                                         std::this_thread::sleep_for(std::chrono::milliseconds(10));
                                       r = syntheticRecord(seed, k, 97);
                                     },
                                     asrt::FrameWriteOptions().fromConcurrentProducer());
                                   return int(Ok);
                                 });
  ASSERT_GT(child, 0);
  const std::string committed = helperTileCommitted(db);
  const std::string mainBackend = pollUntil(
    db,
    "SELECT coalesce(max(pid), 0) FROM pg_stat_activity WHERE query LIKE 'COPY ray_blocks%' AND "
    "state = 'active'",
    [](const std::string& v) { return v != "0"; }, 20);
  kill(child, SIGKILL);
  EXPECT_EQ(waitChild(child, Clock::now() + std::chrono::seconds(10)), 128 + SIGKILL);
  ASSERT_EQ(committed, "1") << "the helper connection never committed its tile";
  ASSERT_NE(mainBackend, "0") << "the main connection's COPY was not under way";
  EXPECT_EQ(pollUntil(
              db, "SELECT count(*) FROM pg_stat_activity WHERE pid = " + mainBackend,
              [](const std::string& v) { return v == "0"; }, 10),
            "0");

  // Nothing of the frame is visible; the committed tile is a table that nothing shows.
  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_EQ(countsOf(db), "0 frames, 0 blocks, 0 incomplete blocks");
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v"), "0");
  EXPECT_EQ(unattachedTables(db), "1");
  store.migrate();
  EXPECT_EQ(unattachedTables(db), "0") << "migrate() left the dead writer's tile";

  expectWrittenAgain(store, seed, count);
}

TEST_F(StoreParallelWrite, SweepDuringAWriteLeavesItsCommittedTileAlone)
{
  RayStore& store = this->Store;
  Db& db = this->Database;
  const std::size_t count = 2 * RayStore::kParallelMinRays + 3;
  StalledWrite write(store, 12, count, firstTile(count, 2) / 2);
  ASSERT_EQ(helperTileCommitted(db), "1");
  EXPECT_EQ(unattachedTables(db), "1");
  // Another process's sweep: the tile's frame does not exist for it yet, but its writer lives.
  RayStore other(this->Ci);
  other.migrate();
  EXPECT_EQ(unattachedTables(db), "1") << "a sweep dropped the tile of a write under way";
  write.finish();
  ASSERT_EQ(write.Error, "(no error)");
  EXPECT_EQ(firstDifference(store.readFrame(write.Id), 12, count), -1);
  EXPECT_EQ(store.frameInfo(write.Id).tileCount, 2);
  EXPECT_EQ(unattachedTables(db), "0");
}

TEST_F(StoreParallelWrite, BrokenHelperConnectionFailsTheWriteCleanlyAndRetrySucceeds)
{
  RayStore& store = this->Store;
  Db& db = this->Database;
  const std::size_t count = 2 * RayStore::kParallelMinRays + 3;
  const std::size_t half = firstTile(count, 2);
  const std::string mainPid = std::to_string(store.backendPid());
  {
    // The helper's tile stalls; its backend is terminated in the middle of the COPY.
    StalledWrite write(store, 13, count, half + (count - half) / 2);
    const std::string helper = pollUntil(
      db,
      "SELECT coalesce(max(pid), 0) FROM pg_stat_activity WHERE query LIKE 'COPY ray_blocks%' "
      "AND state = 'active' AND pid <> " +
        mainPid,
      [](const std::string& v) { return v != "0"; }, 20);
    ASSERT_NE(helper, "0");
    db.value("SELECT pg_terminate_backend(" + helper + ")");
    write.finish();
    EXPECT_NE(write.Error, "(no error)");
    EXPECT_NE(write.Error.find("writing the rays failed"), std::string::npos) << write.Error;
  }
  EXPECT_TRUE(store.listFrames().empty());
  EXPECT_EQ(countsOf(db), "0 frames, 0 blocks, 0 incomplete blocks");
  EXPECT_EQ(unattachedTables(db), "0");
  expectWrittenAgain(store, 13, count);
}

TEST_F(StoreParallelWrite, BrokenMainConnectionDropsTheCommittedTileAndRetrySucceeds)
{
  RayStore& store = this->Store;
  Db& db = this->Database;
  const std::size_t count = 2 * RayStore::kParallelMinRays + 3;
  {
    StalledWrite write(store, 14, count, firstTile(count, 2) / 2);
    ASSERT_EQ(helperTileCommitted(db), "1");
    db.value("SELECT pg_terminate_backend(" + std::to_string(store.backendPid()) + ")");
    write.finish();
    EXPECT_NE(write.Error, "(no error)");
  }
  EXPECT_EQ(countsOf(db), "0 frames, 0 blocks, 0 incomplete blocks");
  // Dropped by the failed write itself, through the connection that still worked.
  EXPECT_EQ(unattachedTables(db), "0");
  expectWrittenAgain(store, 14, count);
}
