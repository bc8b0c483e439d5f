#include "EmbeddedPostgres.h"

#include "AsrtTypes.h"
#include "PgSession.h"
#include "PostgresProcess.h"

#include <libpq-fe.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace asrt
{
namespace
{
using embedded::Command;
using embedded::dropPrivileges;
using embedded::errnoText;
using embedded::Outcome;
using embedded::runCommand;
using embedded::ServerUser;
using embedded::serverUser;

constexpr int LockTimeoutSeconds = 120;
constexpr int PgCtlTimeoutSeconds = 60;
// A unix socket path (with its terminating NUL) must fit in sockaddr_un::sun_path (108 bytes);
// PostgreSQL appends "/.s.PGSQL.<port>" (at most 15 characters) to the directory.
constexpr std::size_t MaxSocketPath = 107;

struct Binaries
{
  std::string InitDb, PgCtl;
};

Binaries findBinaries()
{
  const char* env = std::getenv("ASRT_PG_BINDIR");
  const std::string dir = (env && *env) ? env : "/usr/lib/postgresql/15/bin";
  Binaries b{ dir + "/initdb", dir + "/pg_ctl" };
  for (const std::string& p : { b.InitDb, b.PgCtl, dir + "/postgres" })
    if (access(p.c_str(), X_OK) != 0)
      throw std::runtime_error(
        "PostgreSQL 15 server binaries not found: " + p + " is missing or not executable (" +
        errnoText(errno) +
        "); install the Debian package postgresql-15, or set ASRT_PG_BINDIR to the directory "
        "holding initdb, pg_ctl and postgres");
  return b;
}

std::uint64_t fnv1a(const std::string& s)
{
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : s)
  {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

/// The path a name should be hashed by: symlinks resolved as far as the path exists, so two
/// spellings of one directory give one port and one socket directory.
std::string identity(const std::string& dir)
{
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(dir, ec);
  return ec ? dir : p.string();
}

bool plainPath(const std::string& s)
{
  // postgresql.conf quoting, the comma-separated list syntax of unix_socket_directories and
  // libpq's conninfo syntax all treat some characters specially: keep the socket away from them.
  return std::all_of(s.begin(), s.end(),
                     [](unsigned char c) {
                       return std::isalnum(c) || c == '/' || c == '.' || c == '_' || c == '-' ||
                              c == '+';
                     });
}

std::string conninfoValue(const std::string& v)
{
  const bool plain =
    !v.empty() && std::none_of(v.begin(), v.end(),
                               [](unsigned char c)
                               { return std::isspace(c) || c == '\'' || c == '\\' || c == '='; });
  if (plain)
    return v;
  std::string q = "'";
  for (char c : v)
  {
    if (c == '\'' || c == '\\')
      q += '\\';
    q += c;
  }
  return q + "'";
}

/// Reads at most maxBytes from the end of a file, without following a symlink (root reads files
/// in a directory another user owns).
std::string readTail(const std::string& path, std::size_t maxBytes, off_t notBefore = 0)
{
  const int fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0)
    return {};
  struct stat st
  {
  };
  std::string out;
  if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode))
  {
    const off_t size = st.st_size;
    const off_t from = std::min(
      size, std::max({ notBefore, size - static_cast<off_t>(maxBytes), static_cast<off_t>(0) }));
    out.resize(static_cast<std::size_t>(size - from));
    const ssize_t n = pread(fd, out.data(), out.size(), from);
    out.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  }
  close(fd);
  return out;
}

std::string lastLines(const std::string& text, int lines)
{
  std::size_t pos = text.size();
  if (pos > 0 && text[pos - 1] == '\n')
    --pos;
  while (pos > 0 && lines > 0)
  {
    pos = text.rfind('\n', pos - 1);
    if (pos == std::string::npos)
      return text;
    --lines;
  }
  return lines > 0 ? text : text.substr(pos + 1);
}

std::vector<std::string> splitLines(const std::string& text)
{
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

/// Whether a forked child running as the server user can use the directory: a parent directory
/// that only root may search (a home of mode 0700) would stop initdb with a cryptic error.
bool serverCanReach(const ServerUser& su, const std::string& dir, int mode)
{
  if (!su.Switch)
    return access(dir.c_str(), mode) == 0;
  const pid_t pid = fork();
  if (pid == 0)
  {
    if (dropPrivileges(su) != 0)
      _exit(2);
    _exit(access(dir.c_str(), mode) == 0 ? 0 : 1);
  }
  if (pid < 0)
    throw std::runtime_error("fork: " + errnoText(errno));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
  {
  }
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

/// An exclusive flock on <dataDir>.lock, held for the lifetime of the object. The lock file is
/// next to the directory, not in it, because initdb wants an empty directory.
class DirectoryLock
{
public:
  explicit DirectoryLock(std::string path)
    : Path(std::move(path))
  {
    const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::seconds(LockTimeoutSeconds);
    for (;;)
    {
      Fd = open(Path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0600);
      if (Fd < 0)
        throw std::runtime_error("cannot open the lock file " + Path + ": " + errnoText(errno));
      while (flock(Fd, LOCK_EX | LOCK_NB) != 0)
      {
        if (errno != EWOULDBLOCK && errno != EINTR)
        {
          const int err = errno;
          close(Fd);
          throw std::runtime_error("cannot lock " + Path + ": " + errnoText(err));
        }
        if (std::chrono::steady_clock::now() > deadline)
        {
          close(Fd);
          throw std::runtime_error("timed out after " + std::to_string(LockTimeoutSeconds) +
                                   " s waiting for another process holding " + Path);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      // destroy() unlinks the lock file while holding it: a waiter that then gets the lock on
      // the unlinked file must start over, or two processes would each hold "the" lock.
      struct stat held
      {
      }, named{};
      if (fstat(Fd, &held) == 0 && stat(Path.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
          held.st_ino == named.st_ino)
        return;
      close(Fd);
    }
  }
  ~DirectoryLock() { close(Fd); }
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  void unlinkFile() { unlink(Path.c_str()); }

private:
  std::string Path;
  int Fd = -1;
};

enum class DirState
{
  Missing,
  Empty,
  Cluster,
  NotDirectory,
  Foreign
};

DirState classify(const std::string& dir)
{
  struct stat st
  {
  };
  if (lstat(dir.c_str(), &st) != 0)
  {
    if (errno == ENOENT)
      return DirState::Missing;
    throw std::runtime_error("cannot examine " + dir + ": " + errnoText(errno));
  }
  if (!S_ISDIR(st.st_mode))
    return DirState::NotDirectory;
  struct stat version
  {
  };
  if (stat((dir + "/PG_VERSION").c_str(), &version) == 0)
    return DirState::Cluster;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec)
    throw std::runtime_error("cannot list " + dir + ": " + ec.message());
  return it == fs::directory_iterator() ? DirState::Empty : DirState::Foreign;
}

std::string notAClusterMessage(const std::string& dir)
{
  return "the data directory " + dir +
         " is neither a PostgreSQL cluster nor empty: refusing to touch it (choose an empty or new "
         "directory with --dir or ASRT_DB_DIR)";
}

/// The file that says ASRT made a cluster (initdb through ensureRunning): destroy() deletes no
/// other cluster.
constexpr const char* kMarkerName = "ASRT_CLUSTER";
constexpr const char* kMarkerText =
  "This PostgreSQL cluster was made by ASRT (asrt db start, or the first asrt command that\n"
  "needed its private server). asrt db destroy deletes it with all its data.\n";
/// What ensureRunning appends to postgresql.conf after initdb; clusters made by versions of ASRT
/// without the marker carry it too.
constexpr const char* kAsrtInclude =
  "\n# Written once by ASRT: settings that follow the directory, rewritten at each start.\n"
  "include_if_exists = 'asrt.conf'\n";

bool isEntry(const std::string& path, mode_t type)
{
  struct stat st
  {
  };
  return lstat(path.c_str(), &st) == 0 && (st.st_mode & S_IFMT) == type;
}

/// Whether postgresql.conf holds the lines ASRT appends to it when it makes a cluster.
bool hasAsrtInclude(const std::string& dir)
{
  return readTail(dir + "/postgresql.conf", 1 << 20).find(kAsrtInclude) != std::string::npos;
}

/// Whether `name`, at the top of a cluster's directory, is something PostgreSQL 15 or ASRT puts
/// there: the cluster's own folders and files, the server's socket and its lock (when the socket
/// lives in the directory), ASRT's marker, settings and log.
bool belongsToCluster(const std::string& name)
{
  static const char* const kNames[] = { "PG_VERSION",       "base",
                                        "global",           "pg_commit_ts",
                                        "pg_dynshmem",      "pg_logical",
                                        "pg_multixact",     "pg_notify",
                                        "pg_replslot",      "pg_serial",
                                        "pg_snapshots",     "pg_stat",
                                        "pg_stat_tmp",      "pg_subtrans",
                                        "pg_tblspc",        "pg_twophase",
                                        "pg_wal",           "pg_xact",
                                        "postgresql.conf",  "postgresql.auto.conf",
                                        "pg_hba.conf",      "pg_ident.conf",
                                        "postmaster.opts",  "postmaster.pid",
                                        "current_logfiles", "log",
                                        "backup_label",     "backup_label.old",
                                        "tablespace_map",   "tablespace_map.old",
                                        "backup_manifest",  "recovery.signal",
                                        "standby.signal",   "postgresql.auto.conf.tmp",
                                        kMarkerName,        "asrt.conf",
                                        "server.log" };
  for (const char* known : kNames)
    if (name == known)
      return true;
  // .s.PGSQL.<port> and .s.PGSQL.<port>.lock
  const std::string socket = ".s.PGSQL.";
  if (name.compare(0, socket.size(), socket) != 0)
    return false;
  std::string port = name.substr(socket.size());
  if (port.size() > 5 && port.compare(port.size() - 5, 5, ".lock") == 0)
    port.resize(port.size() - 5);
  return !port.empty() && port.size() <= 5 &&
         port.find_first_not_of("0123456789") == std::string::npos;
}

/// A name from a directory listing, quoted, with control characters shown as '?'.
std::string quotedName(const std::string& name)
{
  std::string out = "'";
  for (unsigned char c : name)
    out += c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c);
  return out + "'";
}

/// Why the non-empty directory `dir` is not a cluster that ASRT made, or "" if it is one: ASRT's
/// marker, PG_VERSION, postgresql.conf and base/, and nothing at the top that neither PostgreSQL
/// nor ASRT put there.
std::string whyNotAsrtCluster(const std::string& dir)
{
  if (!isEntry(dir + "/" + kMarkerName, S_IFREG))
  {
    if (isEntry(dir + "/PG_VERSION", S_IFREG) && hasAsrtInclude(dir))
      return std::string("it has no ") + kMarkerName +
             " marker: it looks like a cluster made by an older ASRT, which did not mark its "
             "clusters; start it once with this version (asrt db start, with the same --dir), "
             "which marks it, then destroy it";
    return std::string("it has no ") + kMarkerName +
           " marker, so ASRT did not make it (delete it yourself if it is to go)";
  }
  if (!isEntry(dir + "/PG_VERSION", S_IFREG))
    return "it has no PG_VERSION file: it is not a PostgreSQL cluster";
  if (!isEntry(dir + "/postgresql.conf", S_IFREG))
    return "it has no postgresql.conf: it is not a whole PostgreSQL cluster";
  if (!isEntry(dir + "/base", S_IFDIR))
    return "it has no base/ folder: it is not a whole PostgreSQL cluster";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
  {
    const std::string name = it->path().filename().string();
    if (!belongsToCluster(name))
      return quotedName(name) + " in it is not part of a PostgreSQL cluster";
  }
  if (ec)
    return "it cannot be listed: " + ec.message();
  return std::string();
}

/// Writes a file in the (server-owned) data directory without following a symlink there, and
/// gives it to the server user.
void writeServerFile(const ServerUser& su, const std::string& path, const std::string& text,
                     bool append)
{
  const int fd =
    open(path.c_str(), O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC | (append ? O_APPEND : O_TRUNC),
         0600);
  if (fd < 0)
    throw std::runtime_error("cannot write " + path + ": " + errnoText(errno));
  const bool ok = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                  (!su.Switch || fchown(fd, su.Uid, su.Gid) == 0);
  const int err = errno;
  close(fd);
  if (!ok)
    throw std::runtime_error("cannot write " + path + ": " + errnoText(err));
}

struct PidFile
{
  long Pid = 0;
  int Port = 0;
  std::string SocketDir;
  std::string Status;
};

/// postmaster.pid: pid, data directory, start time, port, first socket directory, listen
/// address, shared memory key, status.
bool readPidFile(const std::string& dir, PidFile& out)
{
  const std::vector<std::string> lines = splitLines(readTail(dir + "/postmaster.pid", 1 << 16));
  if (lines.empty())
    return false;
  out.Pid = std::atol(lines[0].c_str());
  if (lines.size() > 3)
    out.Port = std::atoi(lines[3].c_str());
  if (lines.size() > 4)
    out.SocketDir = lines[4];
  if (lines.size() > 7)
  {
    out.Status = lines[7];
    out.Status.erase(out.Status.find_last_not_of(' ') + 1);
  }
  return out.Pid > 0;
}

bool postmasterAlive(const std::string& dir, long pid)
{
  if (pid <= 0 || (kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM))
    return false;
  // A stale postmaster.pid may name a pid that now belongs to something else.
  std::string comm = readTail("/proc/" + std::to_string(pid) + "/comm", 256);
  comm.erase(comm.find_last_not_of('\n') + 1);
  if (!comm.empty() && comm != "postgres" && comm != "postmaster")
    return false;
  // The postmaster's working directory is its data directory (readable for our own processes
  // and for root).
  char cwd[4096];
  const ssize_t n =
    readlink(("/proc/" + std::to_string(pid) + "/cwd").c_str(), cwd, sizeof cwd - 1);
  if (n > 0)
  {
    std::error_code ec;
    const fs::path canon = fs::canonical(dir, ec);
    if (!ec && std::string(cwd, static_cast<std::size_t>(n)) != canon.string())
      return false;
  }
  return true;
}

/// A socket directory outside the data directory: created for the server user, or checked to
/// be that user's directory.
void prepareSocketDirectory(const ServerUser& su, const std::string& socketDir)
{
  struct stat st
  {
  };
  if (lstat(socketDir.c_str(), &st) != 0)
  {
    if (mkdir(socketDir.c_str(), 0700) != 0 ||
        (su.Switch && chown(socketDir.c_str(), su.Uid, su.Gid) != 0))
      throw std::runtime_error("cannot create the socket directory " + socketDir + ": " +
                               errnoText(errno));
  }
  else if (!S_ISDIR(st.st_mode) || st.st_uid != su.Uid)
    throw std::runtime_error("the socket directory " + socketDir +
                             " exists but is not a directory owned by " + su.Name + ": remove it");
  chmod(socketDir.c_str(), 0700);
}
}

std::string EmbeddedPostgres::defaultDataDirectory()
{
  if (const char* dir = std::getenv("ASRT_DB_DIR"); dir && *dir)
    return dir;
  if (geteuid() == 0)
    return "/var/lib/asrt/postgres";
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && xdg[0] == '/')
    return std::string(xdg) + "/asrt/postgres";
  std::string home;
  if (const char* h = std::getenv("HOME"); h && *h)
    home = h;
  else if (const passwd* pw = getpwuid(geteuid()); pw && pw->pw_dir)
    home = pw->pw_dir;
  if (home.empty())
    throw std::runtime_error(
      "cannot choose a database directory: neither HOME nor ASRT_DB_DIR is set");
  return home + "/.local/share/asrt/postgres";
}

EmbeddedPostgres::EmbeddedPostgres(std::string dataDir)
{
  if (dataDir.empty())
    throw InvalidParameter("the database directory must not be empty");
  if (std::any_of(dataDir.begin(), dataDir.end(), [](unsigned char c) { return c < 0x20; }))
    throw InvalidParameter("the database directory must not contain control characters (newlines "
                           "would corrupt postmaster.pid): '" +
                           dataDir + "'");
  fs::path p = fs::absolute(dataDir).lexically_normal();
  std::string s = p.string();
  while (s.size() > 1 && s.back() == '/')
    s.pop_back();
  if (s == "/")
    throw InvalidParameter("the database directory must not be the root directory /");
  DataDir = s;
}

std::string EmbeddedPostgres::socketDirectory() const
{
  const std::string socketFile = "/.s.PGSQL." + std::to_string(port());
  if (DataDir.size() + socketFile.size() < MaxSocketPath && plainPath(DataDir))
    return DataDir;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx",
                static_cast<unsigned long long>(fnv1a(identity(DataDir))));
  return std::string("/tmp/asrt-pg-") + hex;
}

int EmbeddedPostgres::port() const
{
  // TCP is off, so the number only names the socket file; deriving it from the directory keeps
  // two clusters that share the fallback socket directory of a hash collision apart too.
  return 20000 + static_cast<int>(fnv1a(identity(DataDir) + "#port") % 20000);
}

std::string EmbeddedPostgres::user() const
{
  return serverUser().Name;
}

std::string EmbeddedPostgres::logFile() const
{
  return DataDir + "/server.log";
}

bool EmbeddedPostgres::running() const
{
  PidFile pf;
  return readPidFile(DataDir, pf) && postmasterAlive(DataDir, pf.Pid);
}

std::string EmbeddedPostgres::conninfo(const std::string& database) const
{
  std::string host = socketDirectory();
  int p = port();
  PidFile pf;
  if (readPidFile(DataDir, pf) && !pf.SocketDir.empty() && pf.Port > 0 &&
      postmasterAlive(DataDir, pf.Pid))
  {
    host = pf.SocketDir;
    p = pf.Port;
  }
  return "host=" + conninfoValue(host) + " port=" + std::to_string(p) +
         " dbname=" + conninfoValue(database) + " user=" + conninfoValue(user());
}

void EmbeddedPostgres::ensureDatabase(const std::string& name) const
{
  if (name.empty() || name.size() > 63)
    throw InvalidParameter("a database name must have 1 to 63 bytes, got '" + name + "'");
  pg::Connection conn;
  try
  {
    conn = pg::connect(conninfo("postgres"));
  }
  catch (const StoreError& e)
  {
    throw std::runtime_error(std::string(e.what()) + " (the server of " + DataDir + ")");
  }
  auto exists = [&]
  {
    const pg::Result r = pg::Params().text(name).exec(
      conn.get(), "SELECT 1 FROM pg_database WHERE datname = $1", "cannot list databases");
    return PQntuples(r.get()) > 0;
  };
  if (exists())
    return;
  std::string ident;
  try
  {
    ident = pg::quoteIdentifier(conn.get(), name, "bad database name '" + name + "'");
  }
  catch (const StoreError& e)
  {
    throw InvalidParameter(e.what());
  }
  try
  {
    pg::exec(conn.get(), "CREATE DATABASE " + ident, "cannot create database '" + name + "'");
  }
  catch (const StoreError&)
  {
    // Another client may have created it in between (duplicate_database, or a unique violation
    // on pg_database): what matters is that it exists now.
    if (!exists())
      throw;
  }
}

std::string EmbeddedPostgres::ensureRunning()
{
  const ServerUser su = serverUser();
  const Binaries bin = findBinaries();
  const fs::path parent = fs::path(DataDir).parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec)
    throw std::runtime_error("cannot create " + parent.string() + ": " + ec.message());

  DirectoryLock lock(DataDir + ".lock");
  const DirState state = classify(DataDir);
  if (state == DirState::NotDirectory)
    throw InvalidParameter("the data directory " + DataDir + " exists but is not a directory");
  if (state == DirState::Foreign)
    throw InvalidParameter(notAClusterMessage(DataDir));

  const std::string unreachable =
    "the PostgreSQL server runs as user '" + su.Name + "', which cannot use " + DataDir +
    " (a parent directory is not searchable by it, or the directory belongs to someone else): "
    "choose another directory with --dir or ASRT_DB_DIR";
  // Checked before anything is created, so that a refused directory leaves nothing behind.
  if (!serverCanReach(su, parent.string(), X_OK))
    throw InvalidParameter(unreachable);
  if (state == DirState::Missing && mkdir(DataDir.c_str(), 0700) != 0)
    throw std::runtime_error("cannot create " + DataDir + ": " + errnoText(errno));
  if (state != DirState::Cluster)
  {
    // initdb wants a directory the server user owns, and PostgreSQL insists on mode 0700.
    if (su.Switch && chown(DataDir.c_str(), su.Uid, su.Gid) != 0)
      throw std::runtime_error("cannot give " + DataDir + " to user " + su.Name + ": " +
                               errnoText(errno));
    if (chmod(DataDir.c_str(), 0700) != 0)
      throw std::runtime_error("cannot chmod " + DataDir + ": " + errnoText(errno));
  }
  if (!serverCanReach(su, DataDir, R_OK | W_OK | X_OK))
    throw InvalidParameter(unreachable);

  if (state == DirState::Cluster)
  {
    std::string version = readTail(DataDir + "/PG_VERSION", 64);
    version.erase(version.find_last_not_of(" \n") + 1);
    if (version != "15")
      throw InvalidParameter("the data directory " + DataDir + " holds a PostgreSQL " + version +
                             " cluster; ASRT runs PostgreSQL 15");
    struct stat st
    {
    };
    if (stat(DataDir.c_str(), &st) == 0 && st.st_uid != su.Uid)
      throw InvalidParameter("the cluster in " + DataDir + " belongs to uid " +
                             std::to_string(st.st_uid) + ", but its server would run as " +
                             su.Name + " (uid " + std::to_string(su.Uid) + ")");
    // A cluster an older ASRT made (its line in postgresql.conf, no marker) is marked now.
    if (!isEntry(DataDir + "/" + kMarkerName, S_IFREG) && hasAsrtInclude(DataDir))
      writeServerFile(su, DataDir + "/" + kMarkerName, kMarkerText, false);
  }
  else
  {
    Command initdb;
    initdb.Argv = { bin.InitDb,
                    "-D",
                    DataDir,
                    "-U",
                    su.Name,
                    "-E",
                    "UTF8",
                    "--locale=C",
                    "--auth-local=trust",
                    "--auth-host=reject" };
    if (!Durable)
      initdb.Argv.push_back("--no-sync");
    const Outcome out = runCommand(su, initdb);
    if (out.ExitCode != 0)
      throw std::runtime_error("initdb failed for " + DataDir + " (exit code " +
                               std::to_string(out.ExitCode) + "):\n" + lastLines(out.Output, 30));
    writeServerFile(su, DataDir + "/" + kMarkerName, kMarkerText, false);
    writeServerFile(su, DataDir + "/postgresql.conf", kAsrtInclude, true);
  }

  PidFile pf;
  if (readPidFile(DataDir, pf) && postmasterAlive(DataDir, pf.Pid))
  {
    // Started by someone else (pg_ctl by hand) and maybe still starting: wait until it accepts
    // connections, as pg_ctl -w would.
    const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::seconds(PgCtlTimeoutSeconds);
    while (pf.Status != "ready" && std::chrono::steady_clock::now() < deadline &&
           postmasterAlive(DataDir, pf.Pid))
    {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      readPidFile(DataDir, pf);
    }
    if (pf.Status != "ready")
      throw std::runtime_error("the PostgreSQL server of " + DataDir + " (pid " +
                               std::to_string(pf.Pid) + ") is running but not ready (" + pf.Status +
                               ")");
  }
  else
  {
    const std::string socketDir = socketDirectory();
    if (socketDir != DataDir)
      prepareSocketDirectory(su, socketDir);
    std::string conf =
      "# Written by ASRT at each start (the socket follows the directory).\n"
      "listen_addresses = ''\n"
      "port = " +
      std::to_string(port()) + "\nunix_socket_directories = '" + socketDir +
      "'\n"
      // Trust authentication is safe only because nobody else can reach the socket.
      "unix_socket_permissions = 0700\n"
      // A private server has no replicas and no archive, so the WAL needs only what crash
      // recovery needs: a table created in the transaction that loads it (how RayStore writes a
      // frame's rays) is then fsynced at commit instead of going through the WAL as well, so the
      // rays are written once, not twice. Durability is the same.
      "wal_level = minimal\n"
      "max_wal_senders = 0\n"
      // Every frame (tile) has a table of rays: a query over all frames locks each of them.
      "max_locks_per_transaction = 512\n";
    if (!Durable)
      // Not durable against an OS crash, but every committed write survives a stop of any kind:
      // synchronous_commit stays on so a commit has reached the WAL buffers the OS will keep.
      conf += "fsync = off\nfull_page_writes = off\n";
    writeServerFile(su, DataDir + "/asrt.conf", conf, false);

    Command start;
    // PGDATA rather than -D: pg_ctl pastes -D into a shell command line, which would break on a
    // directory name with quotes in it.
    start.Argv = { bin.PgCtl, "start", "-w", "-s", "-t", std::to_string(PgCtlTimeoutSeconds) };
    start.PgData = DataDir;
    start.LogPath = logFile();
    start.TimeoutSeconds = PgCtlTimeoutSeconds + 30;
    // Only this attempt's lines go into the error, not the history of earlier runs.
    struct stat before
    {
    };
    const off_t logStart = stat(logFile().c_str(), &before) == 0 ? before.st_size : 0;
    const Outcome out = runCommand(su, start);
    if (out.ExitCode != 0 || !running())
      throw std::runtime_error("the PostgreSQL server in " + DataDir +
                               " failed to start (pg_ctl exit code " +
                               std::to_string(out.ExitCode) + "); the end of " + logFile() + ":\n" +
                               lastLines(readTail(logFile(), 1 << 16, logStart), 25));
  }
  ensureDatabase("asrt");
  return conninfo();
}

namespace
{
void stopServer(const std::string& dataDir, bool immediate)
{
  const ServerUser su = serverUser();
  const Binaries bin = findBinaries();
  Command stop;
  stop.Argv = { bin.PgCtl, "stop",
                "-w",      "-s",
                "-t",      std::to_string(PgCtlTimeoutSeconds),
                "-m",      immediate ? "immediate" : "fast" };
  stop.PgData = dataDir;
  stop.TimeoutSeconds = PgCtlTimeoutSeconds + 30;
  const Outcome out = runCommand(su, stop);
  if (out.ExitCode != 0)
    throw std::runtime_error("could not stop the PostgreSQL server in " + dataDir +
                             " (pg_ctl exit code " + std::to_string(out.ExitCode) + "):\n" +
                             lastLines(out.Output, 20));
}
}

void EmbeddedPostgres::stop(bool immediate)
{
  if (!running())
    return;
  DirectoryLock lock(DataDir + ".lock");
  if (running())
    stopServer(DataDir, immediate);
}

void EmbeddedPostgres::destroy()
{
  const fs::path parent = fs::path(DataDir).parent_path();
  struct stat st
  {
  };
  if (lstat(parent.c_str(), &st) != 0)
    return; // nothing was ever made here
  DirectoryLock lock(DataDir + ".lock");
  const DirState state = classify(DataDir);
  if (state == DirState::NotDirectory)
    throw InvalidParameter("refusing to destroy " + DataDir + ": it is not a directory");
  if (state == DirState::Foreign)
    throw InvalidParameter("refusing to destroy " + DataDir +
                           ": it is not a PostgreSQL cluster and not empty");
  // Only a cluster ASRT made goes, with all that is in it: a folder that merely holds a
  // PG_VERSION, or another program's cluster, is left as it is.
  if (state == DirState::Cluster)
  {
    const std::string why = whyNotAsrtCluster(DataDir);
    if (!why.empty())
      throw InvalidParameter("refusing to destroy " + DataDir + ": " + why);
  }
  if (state == DirState::Cluster && running())
    stopServer(DataDir, true);
  const std::string socketDir = socketDirectory();
  std::error_code ec;
  if (state != DirState::Missing)
  {
    fs::remove_all(DataDir, ec);
    if (ec)
      throw std::runtime_error("cannot remove " + DataDir + ": " + ec.message());
  }
  if (socketDir != DataDir && lstat(socketDir.c_str(), &st) == 0 && S_ISDIR(st.st_mode) &&
      st.st_uid == serverUser().Uid)
    fs::remove_all(socketDir, ec);
  lock.unlinkFile();
}
}
