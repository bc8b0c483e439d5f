// asrt-db: the private PostgreSQL server the ASRT tools use when given no connection.
// Usage: asrt_db [--dir PATH] start|status|stop|destroy
#include "AsrtTypes.h"
#include "EmbeddedPostgres.h"

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

namespace
{
void usage(std::FILE* out)
{
  std::fprintf(out,
               "Usage: asrt_db [--dir PATH] COMMAND\n"
               "\n"
               "The private PostgreSQL 15 server of the ASRT tools (unix socket only).\n"
               "\n"
               "Commands:\n"
               "  start    create the cluster if needed, start the server if it is not running,\n"
               "           and print its libpq conninfo\n"
               "  status   print whether the server runs (exit code 0 if it does, 3 if not)\n"
               "  stop     stop the server (the data stay)\n"
               "  destroy  stop the server and delete the cluster with all its data\n"
               "\n"
               "Options:\n"
               "  --dir PATH  the cluster directory (default: $ASRT_DB_DIR, else\n"
               "              $XDG_DATA_HOME/asrt/postgres or ~/.local/share/asrt/postgres,\n"
               "              or /var/lib/asrt/postgres for root)\n"
               "  --help      show this help\n"
               "\n"
               "As root, the server runs as the 'postgres' system user.\n"
               "ASRT_PG_BINDIR overrides where initdb and pg_ctl are found\n"
               "(default /usr/lib/postgresql/15/bin).\n");
}
}

int main(int argc, char* argv[])
{
  std::string dir, command;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h")
    {
      usage(stdout);
      return 0;
    }
    if (arg == "--dir" || arg.rfind("--dir=", 0) == 0)
    {
      if (arg == "--dir" && i + 1 >= argc)
      {
        std::fprintf(stderr, "asrt_db: --dir needs a path\n");
        return 2;
      }
      dir = arg == "--dir" ? argv[++i] : arg.substr(6);
      if (dir.empty())
      {
        std::fprintf(stderr, "asrt_db: --dir needs a non-empty path\n");
        return 2;
      }
    }
    else if (!arg.empty() && arg[0] == '-')
    {
      std::fprintf(stderr, "asrt_db: unknown option '%s' (try --help)\n", arg.c_str());
      return 2;
    }
    else if (command.empty())
      command = arg;
    else
    {
      std::fprintf(stderr, "asrt_db: unexpected argument '%s' (try --help)\n", arg.c_str());
      return 2;
    }
  }
  if (command.empty())
  {
    usage(stderr);
    return 2;
  }
  if (command != "start" && command != "status" && command != "stop" && command != "destroy")
  {
    std::fprintf(stderr, "asrt_db: unknown command '%s' (start, status, stop or destroy)\n",
                 command.c_str());
    return 2;
  }

  try
  {
    asrt::EmbeddedPostgres db(dir.empty() ? asrt::EmbeddedPostgres::defaultDataDirectory() : dir);
    if (command == "start")
      std::printf("%s\n", db.ensureRunning().c_str());
    else if (command == "status")
    {
      const bool up = db.running();
      std::printf("%s: %s\n", db.dataDirectory().c_str(), up ? "running" : "not running");
      if (up)
        std::printf("%s\n", db.conninfo().c_str());
      return up ? 0 : 3;
    }
    else if (command == "stop")
      db.stop();
    else
    {
      db.destroy();
      std::printf("removed %s\n", db.dataDirectory().c_str());
    }
    return 0;
  }
  catch (const asrt::InvalidParameter& e)
  {
    std::fprintf(stderr, "asrt_db: %s\n", e.what());
    return 2;
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "asrt_db: %s\n", e.what());
    return 1;
  }
}
