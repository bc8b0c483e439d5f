// readFrame's predicates are evaluated as the role asrt_predicate, whatever the connecting role
// may do (here a superuser, as on the private server): the hostile predicates of
// Testing/Data/hostile/predicates.txt (reading and writing files, running programs, signalling
// other sessions, taking back the caller's rights with set_config, other tables, whole
// statements, the catalogs) are refused and change nothing; ordinary predicates still select what
// they say. Also: the role's own rights, a role or function that something made unsafe, a
// connecting role without CREATEROLE, several databases of one server, the predicate's error
// text, and the time limit. TestRayPredicate.cxx tests the grammar and the server's token check.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cctype>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

using asrt::RayRecord;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
/// A database of its own for each test (and `suffix`).
std::string freshDatabase(const std::string& suffix = "")
{
  return databaseNamed("pr_" + currentTestName() + suffix);
}

constexpr int Width = 8, Height = 4;

asrt::SceneDescription scene()
{
  asrt::SceneDescription d;
  d.name = "predicate target";
  d.camera.width = Width;
  d.camera.height = Height;
  return d;
}

std::vector<RayRecord> frameRecords()
{
  std::vector<RayRecord> out;
  for (std::size_t k = 0; k < std::size_t(Width * Height); ++k)
    out.push_back(syntheticRecord(7, k, Width));
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

const char* const MarkerFiles[] = { "/tmp/asrt-hostile-copy-to-program",
                                    "/tmp/asrt-hostile-lo-export" };

bool exists(const char* path)
{
  return access(path, F_OK) == 0;
}

/// Every field of every record the same, bit for bit.
void expectSameBits(const std::vector<RayRecord>& got, const std::vector<RayRecord>& expected)
{
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t k = 0; k < got.size(); ++k)
    ASSERT_EQ(recordBits(got[k]), recordBits(expected[k])) << "record " << k;
}

/// Lets `n` threads go on together once all have arrived.
class Rendezvous
{
public:
  explicit Rendezvous(int n)
    : Waiting(n)
  {
  }
  void arriveAndWait()
  {
    std::unique_lock<std::mutex> lock(this->Mutex);
    if (--this->Waiting == 0)
      this->AllHere.notify_all();
    this->AllHere.wait(lock, [this] { return this->Waiting == 0; });
  }

private:
  std::mutex Mutex;
  std::condition_variable AllHere;
  int Waiting;
};

/// The selected rays as (i, j) pairs, for comparing selections.
std::vector<std::pair<int, int>> pixels(const std::vector<RayRecord>& records)
{
  std::vector<std::pair<int, int>> out;
  for (const RayRecord& r : records)
    out.emplace_back(r.i, r.j);
  return out;
}
}

TEST(PredicateRole, HostilePredicatesAreRefusedAndHarmNothing)
{
  const std::string ci = freshDatabase();
  Db admin(ci);
  admin.value("CREATE EXTENSION IF NOT EXISTS dblink");
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> records = frameRecords();
  const std::int64_t id = store.writeFrame(scene(), "target", records);
  // Another session, as a concurrent asrt trace --store would be.
  Db victim(ci);
  const std::string victimPid = victim.value("SELECT pg_backend_pid()");
  for (const char* marker : MarkerFiles)
    std::remove(marker);

  const std::vector<std::string> hostile = hostilePredicates();
  ASSERT_GE(hostile.size(), 40u);
  for (const std::string& predicate : hostile)
  {
    const std::string e = errorOf([&] { store.readFrame(id, predicate); });
    EXPECT_EQ(e.find("the ray predicate was refused: "), 0u) << predicate << ": " << e;
    EXPECT_EQ(e.find("root:"), std::string::npos) << predicate << " showed a file: " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << predicate << ": " << e;
    EXPECT_EQ(victim.value("SELECT pg_backend_pid()"), victimPid) << predicate;
  }
  for (const char* marker : MarkerFiles)
    EXPECT_FALSE(exists(marker)) << marker;
  EXPECT_EQ(admin.value("SELECT count(*) FROM frames"), "1");
  EXPECT_EQ(admin.value("SELECT count(*) FROM pg_largeobject_metadata"), "0");
  expectSameBits(store.readFrame(id), records);
}

TEST(PredicateRole, PredicatesRunAsTheRoleAndSelectWhatTheySay)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> records = frameRecords();
  const std::int64_t id = store.writeFrame(scene(), "target", records);
  Db admin(ci);
  ASSERT_EQ(admin.value("SELECT rolsuper FROM pg_roles WHERE rolname = current_user"), "t");

  // The predicate reads rays_v with the role's rights, not the superuser's: without its grant
  // the read is refused, whoever connected.
  admin.value("REVOKE SELECT ON rays_v FROM asrt_predicate");
  const std::string e = errorOf([&] { store.readFrame(id, "i = 0"); });
  EXPECT_EQ(e.find("the ray predicate failed: ERROR:  permission denied for view rays_v"), 0u) << e;
  admin.value("GRANT SELECT ON rays_v TO asrt_predicate");
  EXPECT_EQ(store.readFrame(id, "i = 0").size(), std::size_t(Height));

  // Taking back the caller's rights is refused before it reaches the server.
  for (const char* escape : { "set_config('role', session_user, true) IS NOT NULL",
                              "set_config('role', 'none', false) IS NOT NULL",
                              "set_config('session_authorization', session_user, true) IS NOT NULL",
                              "set_config('session_authorization', 'default', true) IS NOT NULL" })
  {
    const std::string refused = errorOf([&] { store.readFrame(id, escape); });
    EXPECT_EQ(refused.find("the ray predicate was refused: set_config() at character 1"), 0u)
      << escape << ": " << refused;
  }
  // The store's own session is untouched by all that.
  EXPECT_EQ(admin.value("SELECT count(*) FROM frames"), "1");
  EXPECT_EQ(store.listFrames().size(), 1u);

  // Ordinary predicates select exactly what they say.
  std::vector<RayRecord> expected;
  for (const RayRecord& r : records)
    if (r.objectId >= 1 && r.i < 5)
      expected.push_back(r);
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(pixels(store.readFrame(id, "object_id >= 1 AND i < 5")), pixels(expected));
  expectSameBits(store.readFrame(id, "object_id >= 1 AND i < 5"), expected);
}

TEST(PredicateRole, TheRoleMayReadTheViewsAndNothingElse)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  EXPECT_EQ(db.value("SELECT rolsuper::text || rolcreaterole::text || rolcreatedb::text || "
                     "rolreplication::text || rolbypassrls::text || rolcanlogin::text FROM "
                     "pg_roles WHERE rolname = 'asrt_predicate'"),
            "falsefalsefalsefalsefalsefalse");
  EXPECT_EQ(
    db.value("SELECT count(*) FROM pg_auth_members WHERE member = 'asrt_predicate'::regrole"), "0");
  for (const char* role : { "pg_read_server_files", "pg_write_server_files",
                            "pg_execute_server_program", "pg_signal_backend", "pg_read_all_data" })
    EXPECT_EQ(
      db.value(std::string("SELECT pg_has_role('asrt_predicate', '") + role + "', 'USAGE')"), "f")
      << role;
  for (const char* view : { "rays_v", "path_points_v" })
    EXPECT_EQ(db.value(std::string("SELECT has_table_privilege('asrt_predicate', '") + view +
                       "', 'SELECT')"),
              "t")
      << view;
  for (const char* table :
       { "frames", "scenes", "ray_blocks", "frame_tiles", "ray_paths", "schema_version" })
    EXPECT_EQ(db.value(std::string("SELECT has_table_privilege('asrt_predicate', '") + table +
                       "', 'SELECT')"),
              "f")
      << table;
  EXPECT_EQ(db.value("SELECT has_schema_privilege('asrt_predicate', current_schema(), 'CREATE')"),
            "f");
  EXPECT_EQ(db.value("SELECT proowner::regrole::text || ':' || prosecdef::text FROM pg_proc "
                     "WHERE oid = 'asrt_selected_rays(bigint,text)'::regprocedure"),
            "asrt_predicate:true");
  // Nobody but the migrating role may call it (anyone could read the rays through it).
  db.value("CREATE ROLE asrt_someone");
  EXPECT_EQ(db.value("SELECT has_function_privilege('asrt_someone', "
                     "'asrt_selected_rays(bigint,text)', 'EXECUTE')"),
            "f");
}

TEST(PredicateRole, AnUnsafeRoleOrFunctionIsRefusedBeforeThePredicateRuns)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::vector<RayRecord> records = frameRecords();
  const std::int64_t id = store.writeFrame(scene(), "target", records);
  Db db(ci);

  // Someone grants the role more: predicates are refused until that is taken back (migrate()
  // cannot take it back; writing and plain reads go on).
  db.value("GRANT pg_read_server_files TO asrt_predicate");
  std::string e = errorOf([&] { store.readFrame(id, "true"); });
  EXPECT_NE(e.find("may do more than read the rays: it is a member of pg_read_server_files"),
            std::string::npos)
    << e;
  store.migrate();
  EXPECT_NE(errorOf([&] { store.readFrame(id, "true"); }).find("pg_read_server_files"),
            std::string::npos);
  asrt::SceneDescription another = scene();
  another.spacetime.mass = 0.5;
  const std::int64_t other = store.writeFrame(another, "meanwhile", records);
  expectSameBits(store.readFrame(other), records);
  db.value("REVOKE pg_read_server_files FROM asrt_predicate");
  EXPECT_EQ(store.readFrame(id, "true").size(), records.size());

  db.value("ALTER ROLE asrt_predicate CREATEDB");
  EXPECT_NE(errorOf([&] { store.readFrame(id, "true"); }).find("it has CREATEDB"),
            std::string::npos);
  db.value("ALTER ROLE asrt_predicate NOCREATEDB");

  // The function ends up owned by the superuser (a restore without roles, say): it would run
  // predicates with every right, so it is not called; migrate() gives it back.
  db.value("ALTER FUNCTION asrt_selected_rays(bigint, text) OWNER TO CURRENT_USER");
  e = errorOf([&] { store.readFrame(id, "true"); });
  EXPECT_NE(e.find("would run as"), std::string::npos) << e;
  store.migrate();
  EXPECT_EQ(db.value("SELECT proowner::regrole::text FROM pg_proc WHERE oid = "
                     "'asrt_selected_rays(bigint,text)'::regprocedure"),
            "asrt_predicate");
  EXPECT_EQ(store.readFrame(id, "true").size(), records.size());

  // The function replaced by one that runs the predicate unchecked (version 4's, say): the
  // server's check of the tokens would be gone, so it is not called; migrate() puts it back.
  db.value("CREATE OR REPLACE FUNCTION asrt_selected_rays(frame bigint, predicate text) RETURNS "
           "TABLE (ray bigint, record_bytes bytea) LANGUAGE plpgsql SECURITY DEFINER AS $f$ "
           "BEGIN RETURN QUERY EXECUTE 'SELECT r.ray::bigint, r.record_bytes FROM (SELECT * FROM "
           "rays_v WHERE frame_id = $1) r WHERE (' || predicate || ')' USING frame; END $f$");
  e = errorOf([&] { store.readFrame(id, "true"); });
  EXPECT_NE(e.find("is not the one that checks the predicate's tokens"), std::string::npos) << e;
  store.migrate();
  EXPECT_EQ(store.readFrame(id, "true").size(), records.size());
  EXPECT_NE(db.value("SELECT prosrc FROM pg_proc WHERE oid = "
                     "'asrt_selected_rays(bigint,text)'::regprocedure")
              .find("the predicate may not use"),
            std::string::npos);

  db.value("DROP FUNCTION asrt_selected_rays(bigint, text)");
  EXPECT_NE(errorOf([&] { store.readFrame(id, "true"); }).find("is missing"), std::string::npos);
  store.migrate();
  EXPECT_EQ(store.readFrame(id, "true").size(), records.size());
  // Reads without a predicate never needed the role.
  expectSameBits(store.readFrame(id), records);
}

TEST(PredicateRole, ARoleWithoutCreateRoleIsToldWhatToDo)
{
  // A fresh server: the role asrt_predicate does not exist yet.
  ThrowawayPostgres pg;
  Db admin(pg.conninfo("postgres"));
  admin.value("CREATE ROLE asrt_plain LOGIN");
  admin.value("CREATE DATABASE asrt_plain_db OWNER asrt_plain");
  admin.value("CREATE ROLE asrt_creator LOGIN CREATEROLE");
  admin.value("CREATE DATABASE asrt_creator_db OWNER asrt_creator");
  const std::string plain = pg.conninfo("postgres") + " dbname=asrt_plain_db user=asrt_plain";
  const std::string creator = pg.conninfo("postgres") + " dbname=asrt_creator_db user=asrt_creator";

  RayStore plainStore(plain);
  std::string e = errorOf([&] { plainStore.migrate(); });
  EXPECT_NE(e.find("needs a superuser or a role with CREATEROLE"), std::string::npos) << e;
  EXPECT_NE(
    e.find("run CREATE ROLE asrt_predicate NOLOGIN; GRANT asrt_predicate TO \"asrt_plain\";"),
    std::string::npos)
    << e;
  // Nothing of the schema was left behind.
  EXPECT_EQ(plainStore.schemaVersion(), 0);
  EXPECT_EQ(Db(plain).value("SELECT count(*) FROM pg_class WHERE relnamespace = "
                            "current_schema()::regnamespace"),
            "0");
  EXPECT_EQ(admin.value("SELECT count(*) FROM pg_roles WHERE rolname = 'asrt_predicate'"), "0");

  // A role with CREATEROLE (no superuser) sets the role up itself.
  RayStore creatorStore(creator);
  creatorStore.migrate();
  const std::int64_t made = creatorStore.writeFrame(scene(), "creator", frameRecords());
  EXPECT_EQ(creatorStore.readFrame(made, "true").size(), std::size_t(Width * Height));
  EXPECT_EQ(Db(creator).value("SELECT proowner::regrole::text FROM pg_proc WHERE oid = "
                              "'asrt_selected_rays(bigint,text)'::regprocedure"),
            "asrt_predicate");

  // The role exists now, but the plain role may not act as it: still told what to do.
  e = errorOf([&] { plainStore.migrate(); });
  EXPECT_NE(e.find("run GRANT asrt_predicate TO \"asrt_plain\";"), std::string::npos) << e;
  // Doing what it says is enough.
  admin.value("GRANT asrt_predicate TO asrt_plain");
  plainStore.migrate();
  const std::int64_t id = plainStore.writeFrame(scene(), "plain", frameRecords());
  EXPECT_EQ(plainStore.readFrame(id, "true").size(), std::size_t(Width * Height));
}

TEST(PredicateRole, DatabasesOfOneServerShareTheRoleWithoutBreakingEachOther)
{
  ThrowawayPostgres pg;
  const std::string a = pg.conninfo("asrt_a"), b = pg.conninfo("asrt_b");
  Db(a).value("CREATE EXTENSION dblink");
  // Two migrators at once, each creating the role if it is missing (roles belong to the cluster;
  // the schema lock of one database does not reach the other).
  Rendezvous start(2);
  std::string errors[2];
  std::thread threads[2];
  for (int k = 0; k < 2; ++k)
    threads[k] = std::thread(
      [&, k]
      {
        RayStore store(k == 0 ? a : b);
        start.arriveAndWait();
        errors[k] = errorOf([&] { store.migrate(); });
      });
  for (std::thread& t : threads)
    t.join();
  EXPECT_EQ(errors[0], "(no error)");
  EXPECT_EQ(errors[1], "(no error)");

  RayStore storeA(a), storeB(b);
  const std::int64_t inA = storeA.writeFrame(scene(), "a", frameRecords());
  const std::int64_t inB = storeB.writeFrame(scene(), "b", frameRecords());
  EXPECT_EQ(storeA.readFrame(inA, "j = 1").size(), std::size_t(Width));
  EXPECT_EQ(storeB.readFrame(inB, "j = 2").size(), std::size_t(Width));
  // A predicate in one database cannot reach the other, through dblink or otherwise.
  const std::string reach = errorOf(
    [&]
    {
      storeA.readFrame(inA, "EXISTS (SELECT 1 FROM dblink('dbname=asrt_b', 'SELECT 1') AS t(x "
                            "int))");
    });
  EXPECT_EQ(reach.find("the ray predicate was refused: exists() at character 1"), 0u) << reach;
  // One database gone, the other keeps working, and a third sets up without trouble.
  Db(pg.conninfo("postgres")).value("DROP DATABASE asrt_a WITH (FORCE)");
  storeB.migrate();
  EXPECT_EQ(storeB.readFrame(inB, "i = 0").size(), std::size_t(Height));
  RayStore storeC(pg.conninfo("asrt_c"));
  storeC.migrate();
  EXPECT_EQ(storeB.readFrame(inB, "true").size(), std::size_t(Width * Height));
}

TEST(PredicateRole, AFailingPredicateGivesOneShortLine)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "target", frameRecords());
  // Within the grammar, but no integer: the server's message quotes the whole string.
  const std::string e =
    errorOf([&] { store.readFrame(id, "i = '" + std::string(5000, 'x') + "'"); });
  EXPECT_EQ(e.find("the ray predicate failed: ERROR:  invalid input syntax for type integer"), 0u)
    << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_LT(e.size(), 300u) << e;
}

TEST(PredicateRole, LocksAreRefusedAndTheTimeLimitHolds)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t id = store.writeFrame(scene(), "target", frameRecords());
  Db other(ci);
  // A session-level advisory lock would outlive the read: refused, and none is held.
  for (const char* lock :
       { "pg_advisory_lock(4242) IS NOT NULL", "pg_try_advisory_xact_lock(4242)" })
  {
    const std::string e = errorOf([&] { store.readFrame(id, lock); });
    EXPECT_EQ(e.find("the ray predicate was refused: pg_"), 0u) << e;
  }
  EXPECT_EQ(other.value("SELECT pg_try_advisory_lock(4242)"), "t");
  other.value("SELECT pg_advisory_unlock(4242)");
  // A read that cannot finish (another session holds the frame's rays locked until the read is
  // over) ends at the time limit.
  store.setPredicateTimeout(std::chrono::milliseconds(200));
  other.value("BEGIN");
  other.value("LOCK TABLE ray_blocks_" + std::to_string(id) + "_0 IN ACCESS EXCLUSIVE MODE");
  const std::string e = errorOf([&] { store.readFrame(id, "i = 0"); });
  other.value("ROLLBACK");
  EXPECT_EQ(
    e.find("the ray predicate failed: ERROR:  canceling statement due to statement timeout"), 0u)
    << e;
  EXPECT_EQ(store.readFrame(id, "i = 0").size(), std::size_t(Height));
}
