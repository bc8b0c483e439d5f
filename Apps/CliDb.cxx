// asrt db: the private PostgreSQL server the tools use when given no connection, and the ASRT
// schema of a database.
#include "Cli.h"

#include "AsrtTypes.h"
#include "EmbeddedPostgres.h"
#include "RayStore.h"

#include <cstdio>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt db [--dir PATH] start|status|stop|destroy
       asrt db init [--db CONNINFO | --dir PATH]

The private PostgreSQL 15 server of the ASRT tools: a cluster of your own, reachable through a
unix socket only, that "asrt trace --store", "list" and "show" use when no --db, $ASRT_DB or PG*
variable names another server. It is created and started the first time it is needed.

Commands:
  start    create the cluster if needed, start the server if it is not running, and print
           its libpq conninfo (usable with psql "CONNINFO" and --db)
  status   print whether the server runs (exit code 0 if it does, 3 if not)
  stop     stop the server (the data stay)
  destroy  stop the server and delete the cluster with all its data; only a cluster ASRT
           made (its marker file ASRT_CLUSTER, PG_VERSION, postgresql.conf and base/, and
           nothing else at the top): anything else is refused and left as it is. A cluster
           made by an older asrt, unmarked, is marked by "start"
  init     create the ASRT schema in a database, or migrate it to this version (the
           database of --db, $ASRT_DB or the PG* variables, else the private server's).
           Commands that only read (list, show, interpolate) create none; storing a
           frame (trace --store) creates it too. The schema includes the role
           asrt_predicate, shared by the server's ASRT databases, that evaluates --where
           predicates: creating it needs a superuser or a role with CREATEROLE

Options:
  --dir PATH     the cluster directory (default: $ASRT_DB_DIR, else
                 $XDG_DATA_HOME/asrt/postgres or ~/.local/share/asrt/postgres, or
                 /var/lib/asrt/postgres for root)
  --db CONNINFO  for init: the database (a libpq connection string or URI)

As root, the server runs as the 'postgres' system user. ASRT_PG_BINDIR overrides where initdb
and pg_ctl are found (default /usr/lib/postgresql/15/bin).
)";

/// asrt db init: the schema created or migrated in the database the options name.
int initSchema(const Options& options, const std::string& dir)
{
  const std::string conninfo =
    options.has("dir") ? EmbeddedPostgres(dir).ensureRunning() : databaseConnection(options);
  RayStore store(conninfo);
  const int before = store.schemaVersion();
  store.migrate();
  const std::string done = before == 0 ? "created"
                           : before == RayStore::kSchemaVersion
                             ? "already in place"
                             : "migrated from version " + std::to_string(before);
  std::printf("ASRT schema version %d %s; predicates run as the role %s\n",
              RayStore::kSchemaVersion, done.c_str(), RayStore::kPredicateRole);
  return kOk;
}
}

int runDb(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "dir", OptionSpec::Value } } + databaseSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s", kHelp, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the command: start, status, stop, destroy or init");
  const std::string command = options.positional()[0];
  if (command != "start" && command != "status" && command != "stop" && command != "destroy" &&
      command != "init")
    throw UsageError("unknown command " + quotedArgument(command) +
                     " (start, status, stop, destroy or init)");
  if (options.has("dir") && options.get("dir").empty())
    throw UsageError("--dir needs a non-empty path");
  if (options.has("db") && command != "init")
    throw UsageError("--db goes with init only (the other commands are about the private server)");
  if (options.has("db") && options.has("dir"))
    throw UsageError("--db and --dir name two servers: give one");
  const std::string dir =
    options.has("dir") ? options.get("dir") : EmbeddedPostgres::defaultDataDirectory();
  EmbeddedPostgres db(dir);
  try
  {
    if (command == "init")
      return initSchema(options, dir);
    if (command == "start")
      std::printf("%s\n", db.ensureRunning().c_str());
    else if (command == "status")
    {
      const bool up = db.running();
      std::printf("%s: %s\n", db.dataDirectory().c_str(), up ? "running" : "not running");
      if (up)
        std::printf("%s\n", db.conninfo().c_str());
      return up ? kOk : kDatabase;
    }
    else if (command == "stop")
      db.stop();
    else
    {
      db.destroy();
      std::printf("removed %s\n", db.dataDirectory().c_str());
    }
  }
  catch (const InvalidParameter&)
  {
    throw; // a directory that cannot hold a cluster: bad input
  }
  catch (const std::exception& e)
  {
    throw DatabaseError(e.what());
  }
  return kOk;
}
}
}
