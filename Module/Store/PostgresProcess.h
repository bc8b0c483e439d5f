// Running PostgreSQL's programs (initdb, pg_ctl) for EmbeddedPostgres: as the account the
// server runs as, with a clean environment, their output captured or logged. Internal to
// ASRT::Store.
#ifndef asrt_PostgresProcess_h
#define asrt_PostgresProcess_h

#include <sys/types.h>

#include <string>
#include <vector>

namespace asrt
{
namespace embedded
{
/// strerror(err).
std::string errnoText(int err);

/// The operating-system account the server runs as.
struct ServerUser
{
  uid_t Uid = 0;
  gid_t Gid = 0;
  std::string Name;
  std::string Home;
  std::vector<gid_t> Groups;
  bool Switch = false; ///< true when we are root and must drop to this user in children
};

/// The account the server runs as: the `postgres` system user when we are root (PostgreSQL
/// refuses to run as root), else ourselves. Throws std::runtime_error when there is none.
ServerUser serverUser();

/// Switches a forked child to the server user; returns 0 or the errno. Async-signal-safe calls
/// only: the parent may have other threads (OpenMP) whose locks a fork child must not touch.
int dropPrivileges(const ServerUser& su);

/// A program to run: its argument vector (the program's path first), its environment and output.
struct Command
{
  std::vector<std::string> Argv;
  std::string PgData;  ///< PGDATA for the child when not empty
  std::string LogPath; ///< when set, stdout and stderr append here; else they are captured
  int TimeoutSeconds = 120;
};

/// How a program ended: its exit code (128 + signal when a signal ended it), and its output
/// when it was captured.
struct Outcome
{
  int ExitCode = 0;
  std::string Output;
};

/// Runs a PostgreSQL program with an argument vector (never through a shell: paths may hold
/// spaces and quotes), as the server user, from "/", with PG* variables removed from its
/// environment so that a user's PGHOST or PGPORT cannot redirect it.
Outcome runCommand(const ServerUser& su, const Command& cmd);
}
}

#endif
