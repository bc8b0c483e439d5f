// The private PostgreSQL server: real initdb + pg_ctl clusters in temporary directories.
#include "AsrtTypes.h"
#include "EmbeddedPostgres.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <pwd.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using asrt::EmbeddedPostgres;

namespace
{
/// A private temporary directory that the server user can enter (when root, the server runs as
/// postgres and mkdtemp's directory is root's).
class TempDir
{
public:
  TempDir()
  {
    char tmpl[] = "/tmp/asrt-test-XXXXXX";
    if (!mkdtemp(tmpl))
      throw std::runtime_error("mkdtemp failed");
    Path = tmpl;
    if (geteuid() == 0)
      if (const passwd* pw = getpwnam("postgres"))
        if (chown(tmpl, pw->pw_uid, pw->pw_gid) != 0)
          throw std::runtime_error("chown failed");
  }
  ~TempDir()
  {
    std::error_code ec;
    fs::remove_all(Path, ec);
  }
  const std::string& path() const { return Path; }

private:
  std::string Path;
};

/// Stops and deletes a cluster even when a test fails half-way.
struct Cleanup
{
  EmbeddedPostgres& Db;
  ~Cleanup()
  {
    try
    {
      Db.destroy();
    }
    catch (...)
    {
    }
  }
};

EmbeddedPostgres makeServer(const std::string& dir)
{
  EmbeddedPostgres db(dir);
  db.setDurable(false);
  return db;
}

long postmasterPid(const std::string& dataDir)
{
  std::ifstream in(dataDir + "/postmaster.pid");
  long pid = 0;
  in >> pid;
  return pid;
}

/// The first column of the first row, or "ERROR: ..." when the connection or query fails.
std::string queryValue(const std::string& conninfo, const std::string& sql)
{
  PGconn* c = PQconnectdb((conninfo + " connect_timeout=5").c_str());
  std::string out;
  if (PQstatus(c) != CONNECTION_OK)
    out = std::string("ERROR: ") + PQerrorMessage(c);
  else
  {
    PGresult* r = PQexec(c, sql.c_str());
    const ExecStatusType s = PQresultStatus(r);
    if (s == PGRES_TUPLES_OK && PQntuples(r) > 0)
      out = PQgetvalue(r, 0, 0);
    else if (s != PGRES_COMMAND_OK && s != PGRES_TUPLES_OK)
      out = std::string("ERROR: ") + PQerrorMessage(c);
    PQclear(r);
  }
  PQfinish(c);
  return out;
}

template<class E, class F>
std::string messageOf(F&& f)
{
  try
  {
    f();
  }
  catch (const E& e)
  {
    return e.what();
  }
  catch (const std::exception& e)
  {
    return std::string("wrong exception type: ") + e.what();
  }
  return "no exception";
}
}

TEST(EmbeddedPostgres, StartsAServerThatAnswers)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  Cleanup cleanup{ db };
  EXPECT_FALSE(db.running());
  const auto t0 = std::chrono::steady_clock::now();
  const std::string ci = db.ensureRunning();
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("initdb + start + CREATE DATABASE: %.2f s\n", seconds);
  EXPECT_TRUE(db.running());
  EXPECT_EQ(ci, db.conninfo());
  EXPECT_NE(ci.find("host=" + tmp.path() + "/data "), std::string::npos) << ci;
  EXPECT_NE(ci.find("port=" + std::to_string(db.port())), std::string::npos) << ci;
  EXPECT_NE(ci.find("dbname=asrt"), std::string::npos) << ci;
  EXPECT_NE(ci.find("user=" + db.user()), std::string::npos) << ci;
  EXPECT_EQ(queryValue(ci, "SELECT version()").rfind("PostgreSQL 15", 0), 0u)
    << queryValue(ci, "SELECT version()");
  EXPECT_EQ(queryValue(ci, "SELECT current_database()"), "asrt");
  // Unix socket only: TCP is off.
  EXPECT_EQ(queryValue(ci, "SHOW listen_addresses"), "");
}

TEST(EmbeddedPostgres, EnsureRunningTwiceReusesTheServer)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  Cleanup cleanup{ db };
  const std::string ci = db.ensureRunning();
  const long pid = postmasterPid(db.dataDirectory());
  ASSERT_GT(pid, 0);
  // A second object on the same directory, as a second tool run would make.
  EmbeddedPostgres again = makeServer(tmp.path() + "/data/");
  EXPECT_EQ(again.ensureRunning(), ci);
  EXPECT_EQ(db.ensureRunning(), ci);
  EXPECT_EQ(postmasterPid(db.dataDirectory()), pid);
}

TEST(EmbeddedPostgres, StopThenEnsureRunningRestartsWithTheData)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  Cleanup cleanup{ db };
  const std::string ci = db.ensureRunning();
  const long pid = postmasterPid(db.dataDirectory());
  ASSERT_EQ(queryValue(ci, "CREATE TABLE kept (v int); INSERT INTO kept VALUES (42)"), "");
  db.stop();
  EXPECT_FALSE(db.running());
  EXPECT_NO_THROW(db.stop()); // stopping a stopped server is not an error

  // A stopped server must give a libpq error promptly, not a hang.
  const auto t0 = std::chrono::steady_clock::now();
  PGconn* c = PQconnectdb((ci + " connect_timeout=2").c_str());
  EXPECT_NE(PQstatus(c), CONNECTION_OK);
  EXPECT_NE(std::string(PQerrorMessage(c)), "");
  PQfinish(c);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 3.0);

  EXPECT_EQ(db.ensureRunning(), ci);
  EXPECT_TRUE(db.running());
  EXPECT_NE(postmasterPid(db.dataDirectory()), pid);
  EXPECT_EQ(queryValue(ci, "SELECT v FROM kept"), "42");

  db.stop(true); // immediate: crash recovery at the next start
  EXPECT_FALSE(db.running());
  EXPECT_EQ(queryValue(db.ensureRunning(), "SELECT count(*) FROM kept"), "1");
}

TEST(EmbeddedPostgres, ServerNeverRunsAsRoot)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  Cleanup cleanup{ db };
  db.ensureRunning();
  const long pid = postmasterPid(db.dataDirectory());
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  long realUid = -1, effectiveUid = -1;
  while (std::getline(status, line))
    if (line.rfind("Uid:", 0) == 0)
      std::istringstream(line.substr(4)) >> realUid >> effectiveUid;
  ASSERT_GE(realUid, 0) << "no Uid line for pid " << pid;
  EXPECT_NE(realUid, 0);
  EXPECT_NE(effectiveUid, 0);
  if (geteuid() == 0)
  {
    EXPECT_EQ(db.user(), "postgres");
    EXPECT_EQ(static_cast<uid_t>(realUid), getpwnam("postgres")->pw_uid);
  }
  else
    EXPECT_EQ(static_cast<uid_t>(realUid), geteuid());
}

TEST(EmbeddedPostgres, ConcurrentProcessesShareOneCluster)
{
  TempDir tmp;
  const std::string dir = tmp.path() + "/data";
  EmbeddedPostgres db = makeServer(dir);
  Cleanup cleanup{ db };
  pid_t children[2];
  for (int i = 0; i < 2; ++i)
  {
    children[i] = fork();
    ASSERT_GE(children[i], 0);
    if (children[i] == 0)
    {
      int code = 0;
      try
      {
        EmbeddedPostgres mine = makeServer(dir);
        std::ofstream(tmp.path() + "/child" + std::to_string(i)) << mine.ensureRunning();
      }
      catch (const std::exception& e)
      {
        std::fprintf(stderr, "child %d: %s\n", i, e.what());
        code = 1;
      }
      std::fflush(nullptr);
      _exit(code);
    }
  }
  for (pid_t child : children)
  {
    int status = -1;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (waitpid(child, &status, WNOHANG) == 0 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (std::chrono::steady_clock::now() >= deadline)
    {
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
    }
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  }
  std::string ci[2];
  for (int i = 0; i < 2; ++i)
    std::getline(std::ifstream(tmp.path() + "/child" + std::to_string(i)), ci[i]);
  EXPECT_FALSE(ci[0].empty());
  EXPECT_EQ(ci[0], ci[1]);
  EXPECT_TRUE(db.running());
  EXPECT_EQ(db.conninfo(), ci[0]);
  EXPECT_EQ(queryValue(ci[0], "SELECT count(*) FROM pg_database WHERE datname = 'asrt'"), "1");
}

TEST(EmbeddedPostgres, DestroyRemovesTheCluster)
{
  TempDir tmp;
  const std::string dir = tmp.path() + "/data";
  EmbeddedPostgres db = makeServer(dir);
  db.ensureRunning();
  const long pid = postmasterPid(dir);
  db.destroy();
  EXPECT_FALSE(db.running());
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_FALSE(fs::exists(dir + ".lock"));
  // pg_ctl returns once postmaster.pid is gone, a moment before the process itself exits.
  auto gone = [pid]
  {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(status, line))
      if (line.rfind("State:", 0) == 0)
        return line.find('Z') != std::string::npos;
    return true;
  };
  // It exits by itself: the deadline only bounds a failure, so it is generous for a loaded machine.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!gone() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(gone()) << "postmaster " << pid << " still alive";
  EXPECT_NO_THROW(db.destroy()); // nothing left: nothing to do
  EXPECT_NO_THROW(db.stop());
}

TEST(EmbeddedPostgres, RefusesANonEmptyDirectoryThatIsNoCluster)
{
  TempDir tmp;
  const std::string dir = tmp.path() + "/notes";
  fs::create_directory(dir);
  std::ofstream(dir + "/keep.txt") << "precious";
  EmbeddedPostgres db = makeServer(dir);
  const std::string msg = messageOf<asrt::InvalidParameter>([&] { db.ensureRunning(); });
  EXPECT_NE(msg.find("neither a PostgreSQL cluster nor empty"), std::string::npos) << msg;
  EXPECT_NE(msg.find(dir), std::string::npos) << msg;
  const std::string destroyMsg = messageOf<asrt::InvalidParameter>([&] { db.destroy(); });
  EXPECT_NE(destroyMsg.find("refusing"), std::string::npos) << destroyMsg;
  EXPECT_TRUE(fs::exists(dir + "/keep.txt"));
  EXPECT_FALSE(db.running());

  std::ofstream(tmp.path() + "/file") << "x";
  EmbeddedPostgres onFile = makeServer(tmp.path() + "/file");
  const std::string fileMsg = messageOf<asrt::InvalidParameter>([&] { onFile.ensureRunning(); });
  EXPECT_NE(fileMsg.find("not a directory"), std::string::npos) << fileMsg;
}

TEST(EmbeddedPostgres, RefusesADirectoryTheServerUserCannotReach)
{
  if (geteuid() != 0)
    GTEST_SKIP() << "only root runs the server as another user";
  TempDir tmp;
  const std::string privateDir = tmp.path() + "/root-only";
  fs::create_directory(privateDir);
  chmod(privateDir.c_str(), 0700); // root's, like /root
  EmbeddedPostgres db = makeServer(privateDir + "/data");
  const std::string msg = messageOf<asrt::InvalidParameter>([&] { db.ensureRunning(); });
  EXPECT_NE(msg.find("cannot use"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(privateDir + "/data"));
}

TEST(EmbeddedPostgres, RejectsBadPaths)
{
  EXPECT_THROW(EmbeddedPostgres(""), asrt::InvalidParameter);
  EXPECT_THROW(EmbeddedPostgres("/"), asrt::InvalidParameter);
  EXPECT_THROW(EmbeddedPostgres("/tmp/a\nb"), asrt::InvalidParameter);
}

TEST(EmbeddedPostgres, PathWithSpacesAndQuotesWorks)
{
  TempDir tmp;
  const std::string dir = tmp.path() + "/it's a \"quoted\" dir $HOME `true`; x";
  EmbeddedPostgres db = makeServer(dir);
  Cleanup cleanup{ db };
  const std::string ci = db.ensureRunning();
  // Such a name never reaches postgresql.conf or the conninfo: the socket moves to /tmp.
  EXPECT_EQ(db.socketDirectory().rfind("/tmp/asrt-pg-", 0), 0u) << db.socketDirectory();
  EXPECT_EQ(queryValue(ci, "SELECT 1"), "1");
  EXPECT_TRUE(fs::exists(dir + "/PG_VERSION"));
  const std::string socketDir = db.socketDirectory();
  db.destroy();
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_FALSE(fs::exists(socketDir));
}

TEST(EmbeddedPostgres, LongPathUsesAShortSocketDirectory)
{
  TempDir tmp;
  const std::string dir = tmp.path() + "/" + std::string(100, 'd');
  EmbeddedPostgres db = makeServer(dir);
  Cleanup cleanup{ db };
  const std::string ci = db.ensureRunning();
  EXPECT_LT(db.socketDirectory().size(), 40u);
  EXPECT_EQ(queryValue(ci, "SELECT 2"), "2");
}

TEST(EmbeddedPostgres, FailedStartReportsTheServerLog)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  Cleanup cleanup{ db };
  db.ensureRunning();
  db.stop();

  // Another live process of the server's user claims the socket's port.
  const pid_t squatter = fork();
  ASSERT_GE(squatter, 0);
  if (squatter == 0)
  {
    if (geteuid() == 0)
    {
      const passwd* pw = getpwnam("postgres");
      if (!pw || setgid(pw->pw_gid) != 0 || setuid(pw->pw_uid) != 0)
        _exit(1);
    }
    pause();
    _exit(0);
  }
  const std::string lockFile =
    db.socketDirectory() + "/.s.PGSQL." + std::to_string(db.port()) + ".lock";
  std::ofstream(lockFile) << squatter << "\n";
  if (geteuid() == 0)
  {
    const passwd* pw = getpwnam("postgres");
    ASSERT_EQ(chown(lockFile.c_str(), pw->pw_uid, pw->pw_gid), 0);
  }
  const std::string msg = messageOf<std::runtime_error>([&] { db.ensureRunning(); });
  kill(squatter, SIGKILL);
  waitpid(squatter, nullptr, 0);
  EXPECT_NE(msg.find("failed to start"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lock file"), std::string::npos) << msg;
  EXPECT_FALSE(db.running());

  // Once the port is free again, the same cluster starts.
  fs::remove(lockFile);
  EXPECT_EQ(queryValue(db.ensureRunning(), "SELECT 3"), "3");
}

TEST(EmbeddedPostgres, MissingBinariesAreReportedClearly)
{
  TempDir tmp;
  EmbeddedPostgres db = makeServer(tmp.path() + "/data");
  setenv("ASRT_PG_BINDIR", "/nonexistent/pg/bin", 1);
  const std::string msg = messageOf<std::runtime_error>([&] { db.ensureRunning(); });
  unsetenv("ASRT_PG_BINDIR");
  EXPECT_NE(msg.find("PostgreSQL 15 server binaries not found"), std::string::npos) << msg;
  EXPECT_NE(msg.find("/nonexistent/pg/bin/initdb"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(tmp.path() + "/data"));
}

TEST(EmbeddedPostgres, DefaultDataDirectory)
{
  const char* saved = std::getenv("ASRT_DB_DIR");
  const std::string keep = saved ? saved : "";
  setenv("ASRT_DB_DIR", "/somewhere/db", 1);
  EXPECT_EQ(EmbeddedPostgres::defaultDataDirectory(), "/somewhere/db");
  unsetenv("ASRT_DB_DIR");
  if (geteuid() == 0)
    EXPECT_EQ(EmbeddedPostgres::defaultDataDirectory(), "/var/lib/asrt/postgres");
  else
    EXPECT_NE(EmbeddedPostgres::defaultDataDirectory().find("/asrt/postgres"), std::string::npos);
  if (saved)
    setenv("ASRT_DB_DIR", keep.c_str(), 1);
}

TEST(EmbeddedPostgresThrowaway, GivesDatabasesAndCleansUp)
{
  std::string dir;
  {
    asrt::testing::ThrowawayPostgres pg;
    dir = pg.directory();
    EXPECT_TRUE(pg.running());
    EXPECT_EQ(queryValue(pg.conninfo(), "SELECT current_database()"), "asrt");
    const std::string other = pg.conninfo("other db");
    EXPECT_EQ(queryValue(other, "SELECT current_database()"), "other db");
    EXPECT_EQ(pg.conninfo("other db"), other);
    pg.restart();
    EXPECT_EQ(queryValue(other, "SELECT 1"), "1");
    pg.stop();
    EXPECT_FALSE(pg.running());
    pg.start();
    EXPECT_TRUE(pg.running());
  }
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_FALSE(fs::exists(fs::path(dir).parent_path()));
}
