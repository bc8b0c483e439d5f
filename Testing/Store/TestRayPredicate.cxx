// Ray predicates are a grammar of their own (RayPredicate.h), checked twice: by the client before
// anything is sent, and by the server's function asrt_selected_rays, token by token, when a text
// reaches it. Every hostile predicate of Testing/Data/hostile/predicates.txt (the catalogs, the
// information functions, large objects, advisory locks, files, programs, statements, comments,
// casts, quotes) is refused by both and selects nothing; the predicates the README and the
// examples use select exactly the rays a filter over the whole frame selects; every column and
// function the grammar allows works on the server.
#include "RayPredicate.h"
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

using asrt::RayRecord;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
std::string freshDatabase()
{
  return databaseNamed("rp_" + currentTestName());
}

constexpr int Width = 9, Height = 7;

asrt::SceneDescription scene()
{
  asrt::SceneDescription d;
  d.name = "predicate grammar";
  d.camera.width = Width;
  d.camera.height = Height;
  return d;
}

/// A ray a pixel, with every integer field taking several values and the hit point's coordinates
/// multiples of 1/4 in [-1, 1] (finite, so that comparisons in SQL and in C++ agree).
std::vector<RayRecord> frameRecords()
{
  std::vector<RayRecord> out;
  for (int k = 0; k < Width * Height; ++k)
  {
    RayRecord r = syntheticRecord(11, std::size_t(k), Width);
    r.objectId = k % 6;
    r.imageOrder = (k / 6) % 3;
    r.termination = asrt::Termination(k % 5 + 1);
    r.hitPoint = asrt::Vec3((k % 9) * 0.25 - 1.0, (k % 5) * 0.5 - 1.0, (k % 3) * 0.25);
    out.push_back(r);
  }
  return out;
}

/// The predicates of Testing/Data/hostile/predicates.txt, without its comments.
std::vector<std::string> hostilePredicates()
{
  std::ifstream in(std::string(ASRT_SOURCE_DIR) + "/Testing/Data/hostile/predicates.txt");
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#')
      out.push_back(line);
  return out;
}

/// The rays of frame `id` that the server's function selects for `predicate`, sent to it as it
/// is (no client check), as "count:N", or "error:" and the server's message. A predicate that
/// the function failed to refuse may sleep: the time limit ends it, and the test fails.
std::string serverSelects(Db& db, std::int64_t id, const std::string& predicate)
{
  db.value("SET statement_timeout = '10s'");
  const std::string frame = std::to_string(id);
  const char* values[] = { frame.c_str(), predicate.c_str() };
  PGresult* r = PQexecParams(db.Conn, "SELECT count(*) FROM asrt_selected_rays($1::bigint, $2)", 2,
                             nullptr, values, nullptr, nullptr, 0);
  const std::string out = PQresultStatus(r) == PGRES_TUPLES_OK
                            ? std::string("count:") + PQgetvalue(r, 0, 0)
                            : std::string("error:") + PQresultErrorMessage(r);
  PQclear(r);
  return out;
}

std::vector<std::pair<int, int>> pixels(const std::vector<RayRecord>& records)
{
  std::vector<std::pair<int, int>> out;
  for (const RayRecord& r : records)
    out.emplace_back(r.i, r.j);
  return out;
}
}

TEST(RayPredicateGrammar, LegalPredicatesAreSentTokenByToken)
{
  const std::pair<const char*, const char*> cases[] = {
    { "object_id = 4 AND image_order >= 1", "object_id = 4 AND image_order >= 1" },
    { "Object_Id=4 and Image_Order>=1", "object_id = 4 AND image_order >= 1" },
    { "i BETWEEN 2 AND 5 AND j NOT IN (0, -2, +3)",
      "i BETWEEN 2 AND 5 AND j NOT IN ( 0 , - 2 , + 3 )" },
    { "abs(hit_x)<.5 OR sqrt(i*i+j*j)<=3e0",
      "abs ( hit_x ) < .5 OR sqrt ( i * i + j * j ) <= 3e0" },
    { "NOT(u IS NOT NULL)", "NOT ( u IS NOT NULL )" },
    { "winding = 'NaN' OR 'it''s' <> 'x'", "winding = 'NaN' OR 'it''s' <> 'x'" },
    { "pi() > 3 AND greatest(i, j, 1.5) != 2", "pi ( ) > 3 AND greatest ( i , j , 1.5 ) != 2" },
    { "-i^2 % 3 / 1 - 1 < 0", "- i ^ 2 % 3 / 1 - 1 < 0" },
    { "\ti\n=\r1", "i = 1" },
  };
  for (const auto& [predicate, sent] : cases)
    EXPECT_EQ(asrt::rayPredicateSql(predicate), sent) << predicate;
}

TEST(RayPredicateGrammar, WhatIsRefusedIsNamedWithItsPlace)
{
  const std::pair<std::string, std::string> cases[] = {
    { "(SELECT count(*) FROM pg_settings) > 0", "\"SELECT\" at character 2" },
    { "version() IS NOT NULL", "version() at character 1: not a function a predicate may call" },
    { "session_user IS NOT NULL", "\"session_user\" at character 1: neither a column" },
    { "lo_creat(-1) > 0", "lo_creat() at character 1" },
    { "i = 0 AND pg_advisory_lock(1) IS NOT NULL", "pg_advisory_lock() at character 11" },
    { "i::text = '0'", "a cast (::) at character 2" },
    { "i = 1; DROP TABLE frames", "\";\" at character 6" },
    { "i = 1 -- x", "a comment at character 7" },
    { "i = 1 /* x */", "a comment at character 7" },
    { "\"i\" = 1", "a quoted identifier at character 1" },
    { "i = $$1$$", "\"$\" at character 5" },
    { "i = '\\'", "a backslash at character 6" },
    { "rays_v.i = 1", "\"rays_v\" at character 1" },
    { "i = 'open", "an unterminated string at character 5" },
    { "i = 1)", "\")\" at character 6: expected AND, OR, an operator or the end" },
    { "(i = 1", "the end at character 7: expected \")\"" },
    { "i IN (j)", "\"j\" at character 7: expected a number, a string, TRUE, FALSE or NULL" },
    { "i IN (-'1')", "\"'1'\" at character 8: expected a number" },
    { "abs(i, j) > 0", "abs() at character 1: it takes 1 argument, not 2" },
    { "atan2(i) > 0", "atan2() at character 1: it takes 2 arguments, not 1" },
    { "i(1) = 1", "\"(\" at character 2" },
    { "i = 1 AND \xc3\xa9", "a character outside printable ASCII at character 11" },
    { "i = 1 AND NOT", "the end at character 14" },
    { "i NOT 5", "\"5\" at character 7: expected BETWEEN or IN" },
    { "i < 0 IS TRUE", "\"IS\" at character 7" },
    { " \t ", "it is empty" },
    { std::string(70000, ' '), "it is longer than 65536 bytes" },
    { std::string(65, '(') + "i = 1" + std::string(65, ')'), "nesting deeper than 64" },
    { []
        {
          std::string minus;
          for (int k = 0; k < 65; ++k)
            minus += "- ";
          return minus;
        }() +
        "1 = 1",
      "nesting deeper than 64" },
  };
  for (const auto& [predicate, refused] : cases)
  {
    const std::string e = errorOf([&] { asrt::rayPredicateSql(predicate); });
    EXPECT_EQ(e.find("the ray predicate was refused: " + refused), 0u)
      << predicate.substr(0, 80) << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  // Nested as deep as allowed is fine.
  EXPECT_NO_THROW(asrt::rayPredicateSql(std::string(63, '(') + "i = 1" + std::string(63, ')')));
}

TEST(RayPredicates, HostilePredicatesAreRefusedByTheClientAndByTheServer)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "target", frameRecords());
  Db db(ci);
  db.value("CREATE EXTENSION IF NOT EXISTS dblink");
  const std::vector<std::string> hostile = hostilePredicates();
  ASSERT_GE(hostile.size(), 40u);
  for (const std::string& predicate : hostile)
  {
    // Nothing selected: the read is refused as a whole.
    const std::string e = errorOf([&] { store.readFrame(id, predicate); });
    EXPECT_EQ(e.find("the ray predicate was refused: "), 0u) << predicate << ": " << e;
    // Sent to the server as it is, the server refuses it too, before running it.
    const std::string server = serverSelects(db, id, predicate);
    EXPECT_EQ(server.find("error:ERROR:  the predicate may not "), 0u)
      << predicate << ": " << server;
  }
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_largeobject_metadata"), "0");
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_locks WHERE locktype = 'advisory'"), "0");
}

TEST(RayPredicates, LegalPredicatesSelectWhatAFilterOverTheFrameSelects)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> records = frameRecords();
  const std::int64_t id = store.writeFrame(scene(), "target", records);
  Db db(ci);
  using Keep = std::function<bool(const RayRecord&)>;
  const std::pair<const char*, Keep> cases[] = {
    { "object_id = 4 AND image_order >= 1",
      [](const RayRecord& r) { return r.objectId == 4 && r.imageOrder >= 1; } },
    { "image_order >= 1", [](const RayRecord& r) { return r.imageOrder >= 1; } },
    { "i BETWEEN 2 AND 5 AND j NOT IN (0, 2)",
      [](const RayRecord& r) { return r.i >= 2 && r.i <= 5 && r.j != 0 && r.j != 2; } },
    { "abs(hit_x) < 0.5 OR sqrt(i * i + j * j) <= 3", [](const RayRecord& r)
      { return std::fabs(r.hitPoint.x()) < 0.5 || r.i * r.i + r.j * r.j <= 9; } },
    { "mod(i, 3) = 0 AND greatest(i, j) > 2 AND NOT termination = 5", [](const RayRecord& r)
      { return r.i % 3 == 0 && std::max(r.i, r.j) > 2 && int(r.termination) != 5; } },
    { "floor(hit_y * 2) = -1 OR hit_z IN (0.5)", [](const RayRecord& r)
      { return std::floor(r.hitPoint.y() * 2) == -1 || r.hitPoint.z() == 0.5; } },
    { "i % 2 = 1 AND -j < -1", [](const RayRecord& r) { return r.i % 2 == 1 && -r.j < -1; } },
  };
  for (const auto& [predicate, keep] : cases)
  {
    std::vector<RayRecord> expected;
    for (const RayRecord& r : records)
      if (keep(r))
        expected.push_back(r);
    ASSERT_FALSE(expected.empty()) << predicate;
    ASSERT_LT(expected.size(), records.size()) << predicate;
    const std::vector<RayRecord> got = store.readFrame(id, predicate);
    EXPECT_EQ(pixels(got), pixels(expected)) << predicate;
    // The server's own check lets the text the client sends through, with the same rays.
    EXPECT_EQ(serverSelects(db, id, asrt::rayPredicateSql(predicate)),
              "count:" + std::to_string(expected.size()))
      << predicate;
  }
}

TEST(RayPredicates, EveryColumnAndFunctionOfTheGrammarWorksOnTheServer)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "target", frameRecords());
  Db db(ci);
  // The grammar's columns are the view's, in its order.
  std::string columns;
  for (const std::string& c : asrt::rayPredicateColumns())
    columns += (columns.empty() ? "" : ",") + c;
  EXPECT_EQ(db.value("SELECT string_agg(column_name, ',' ORDER BY ordinal_position) FROM "
                     "information_schema.columns WHERE table_name = 'rays_v' AND table_schema = "
                     "current_schema()"),
            columns);
  const std::string all = std::to_string(Width * Height);
  for (const std::string& c : asrt::rayPredicateColumns())
  {
    EXPECT_EQ(store.readFrame(id, c + " IS NOT NULL").size(), std::size_t(Width * Height)) << c;
    EXPECT_EQ(serverSelects(db, id, c + " IS NOT NULL"), "count:" + all) << c;
  }
  for (const asrt::RayPredicateFunction& f : asrt::rayPredicateFunctions())
  {
    std::string call = std::string(f.name) + "(";
    for (int k = 0; k < f.minArguments; ++k)
      call += k == 0 ? "0.5" : ", 0.5";
    const std::string predicate = call + ") IS NOT NULL";
    EXPECT_EQ(store.readFrame(id, predicate).size(), std::size_t(Width * Height)) << predicate;
    EXPECT_EQ(serverSelects(db, id, asrt::rayPredicateSql(predicate)), "count:" + all) << predicate;
  }
}

TEST(RayPredicates, VersionFiveGetsTheServersCheck)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(5);
  Db db(ci);
  const std::string version = "version() IS NOT NULL";
  // Version 5's function runs whatever it is given (there is no frame 1 yet: no rays).
  EXPECT_EQ(serverSelects(db, 1, version), "count:0");
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  const std::int64_t id = store.writeFrame(scene(), "target", frameRecords());
  EXPECT_EQ(serverSelects(db, id, version).find("error:ERROR:  the predicate may not use version"),
            0u);
  EXPECT_EQ(store.readFrame(id, "i = 0").size(), std::size_t(Height));
}
