// A private PostgreSQL 15 server for one user: a cluster in a local data directory, made with
// initdb and run with pg_ctl, reachable only through a unix socket. It lets the tools work with no
// database set-up at all: the first call creates and starts the cluster, later calls reuse it.
//
// When the calling process is root, initdb and the server run as the `postgres` system user
// (PostgreSQL refuses to run as root). Calls from several processes on the same directory are
// serialised by a lock file next to it (`<dataDir>.lock`).
#ifndef asrt_EmbeddedPostgres_h
#define asrt_EmbeddedPostgres_h

#include "asrtStoreModule.h"

#include <string>

namespace asrt
{
class ASRTSTORE_EXPORT EmbeddedPostgres
{
public:
  /// $ASRT_DB_DIR if set; otherwise $XDG_DATA_HOME/asrt/postgres or ~/.local/share/asrt/postgres,
  /// or /var/lib/asrt/postgres for root.
  static std::string defaultDataDirectory();

  /// The cluster lives in dataDir itself (the PGDATA directory). Nothing is touched until a call
  /// needs it. Throws InvalidParameter for an empty path.
  explicit EmbeddedPostgres(std::string dataDir);

  /// A durable cluster fsyncs like any PostgreSQL server (the default). A non-durable one (for
  /// tests and scratch data) skips every fsync: much faster, but an OS crash may corrupt it.
  void setDurable(bool durable) { Durable = durable; }
  bool durable() const { return Durable; }

  /// Creates the cluster (marked as ASRT's, see destroy) if the directory is empty or missing,
  /// marks a cluster an older ASRT made, starts the server if it is not running, creates the
  /// database "asrt" if missing, and returns the libpq conninfo of that database. Throws
  /// InvalidParameter for a directory that cannot hold a cluster (not empty and not a cluster, a
  /// file, a cluster of another PostgreSQL version) and std::runtime_error, with the server's log,
  /// when PostgreSQL fails.
  std::string ensureRunning();

  /// Stops the server if it runs (fast shutdown, or immediate: no checkpoint, crash recovery at the
  /// next start). Does nothing if it is not running.
  void stop(bool immediate = false);

  /// Whether a postmaster of this cluster is alive (from postmaster.pid).
  bool running() const;

  /// Stops the server and deletes the cluster directory, its lock file and its socket directory.
  /// Refuses (InvalidParameter, naming what looks wrong) to delete a non-empty directory that is
  /// not a cluster ASRT made: one without the marker file ASRT_CLUSTER that ensureRunning writes
  /// after initdb, without PG_VERSION, postgresql.conf or base/, or with anything at the top that
  /// neither PostgreSQL nor ASRT put there. A cluster made by an older ASRT, unmarked, is refused
  /// too; ensureRunning marks it (it recognises the lines ASRT added to its postgresql.conf).
  void destroy();

  /// Creates the database if it does not exist yet. The server must be running.
  void ensureDatabase(const std::string& name) const;

  /// libpq conninfo "host=<socket dir> port=<port> dbname=<database> user=<user>".
  std::string conninfo() const { return conninfo("asrt"); }
  std::string conninfo(const std::string& database) const;

  const std::string& dataDirectory() const { return DataDir; }
  /// Where the server's unix socket lives: the data directory itself when its path is short and
  /// plain enough, else /tmp/asrt-pg-<hash of the data directory>.
  std::string socketDirectory() const;
  /// The port number names the socket file only (TCP is off). Derived from the data directory.
  int port() const;
  /// The database role, which is the operating-system user the server runs as.
  std::string user() const;
  /// The server's log (stdout and stderr of the postmaster): <dataDir>/server.log.
  std::string logFile() const;

private:
  std::string DataDir;
  bool Durable = true;
};
}

#endif
