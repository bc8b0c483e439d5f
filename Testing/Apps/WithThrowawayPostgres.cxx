// Runs a command against a throwaway PostgreSQL server: starts one (Testing/Store's fixture: a
// fresh cluster in a temporary directory, unix socket only), points the standard PG* variables
// at it, runs the command, and deletes the server. Exits with the command's exit code.
// Usage: asrtWithThrowawayPostgres COMMAND [ARGS...]
#include "ThrowawayPostgres.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <string>

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s COMMAND [ARGS...]\n", argv[0]);
    return 2;
  }
  try
  {
    asrt::testing::ThrowawayPostgres server;
    // The conninfo is "host=... port=... dbname=... user=...": the same as PG* variables.
    std::istringstream fields(server.conninfo());
    std::string field;
    while (fields >> field)
    {
      const std::size_t eq = field.find('=');
      const std::string key = field.substr(0, eq), value = field.substr(eq + 1);
      const char* var = key == "host"     ? "PGHOST"
                        : key == "port"   ? "PGPORT"
                        : key == "dbname" ? "PGDATABASE"
                        : key == "user"   ? "PGUSER"
                                          : nullptr;
      if (var)
        setenv(var, value.c_str(), 1);
    }
    setenv("ASRT_TEST_CONNINFO", server.conninfo().c_str(), 1);
    unsetenv("ASRT_DB");
    const pid_t pid = fork();
    if (pid == 0)
    {
      execvp(argv[1], argv + 1);
      std::perror(argv[1]);
      _exit(127);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
      ;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
}
