// asrt db: the private PostgreSQL server the tools use when given no connection.
#include "Cli.h"

#include "AsrtTypes.h"
#include "EmbeddedPostgres.h"

#include <cstdio>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt db [--dir PATH] start|status|stop|destroy

The private PostgreSQL 15 server of the ASRT tools: a cluster of your own, reachable through a
unix socket only, that "asrt trace --store", "list" and "show" use when no --db, $ASRT_DB or PG*
variable names another server. It is created and started the first time it is needed.

Commands:
  start    create the cluster if needed, start the server if it is not running, and print
           its libpq conninfo (usable with psql "CONNINFO" and --db)
  status   print whether the server runs (exit code 0 if it does, 3 if not)
  stop     stop the server (the data stay)
  destroy  stop the server and delete the cluster with all its data

Options:
  --dir PATH  the cluster directory (default: $ASRT_DB_DIR, else
              $XDG_DATA_HOME/asrt/postgres or ~/.local/share/asrt/postgres, or
              /var/lib/asrt/postgres for root)

As root, the server runs as the 'postgres' system user. ASRT_PG_BINDIR overrides where initdb
and pg_ctl are found (default /usr/lib/postgresql/15/bin).
)";
}

int runDb(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "dir", OptionSpec::Value } }, args);
  if (options.help())
  {
    std::printf("%s\n%s", kHelp, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the command: start, status, stop or destroy");
  const std::string command = options.positional()[0];
  if (command != "start" && command != "status" && command != "stop" && command != "destroy")
    throw UsageError("unknown command '" + command + "' (start, status, stop or destroy)");
  if (options.has("dir") && options.get("dir").empty())
    throw UsageError("--dir needs a non-empty path");
  const std::string dir =
    options.has("dir") ? options.get("dir") : EmbeddedPostgres::defaultDataDirectory();
  EmbeddedPostgres db(dir);
  try
  {
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
