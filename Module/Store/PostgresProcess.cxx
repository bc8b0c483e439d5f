#include "PostgresProcess.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#ifdef __linux__
#include <linux/close_range.h>
#endif

extern char** environ;

namespace asrt
{
namespace embedded
{
std::string errnoText(int err)
{
  return std::strerror(err);
}

ServerUser serverUser()
{
  ServerUser su;
  const uid_t me = geteuid();
  if (me == 0)
  {
    const passwd* pw = getpwnam("postgres");
    if (!pw)
      throw std::runtime_error(
        "running as root, but there is no 'postgres' system user to run the PostgreSQL server as "
        "(PostgreSQL refuses to run as root): install the Debian package postgresql-15, or run "
        "as a normal user");
    su.Uid = pw->pw_uid;
    su.Gid = pw->pw_gid;
    su.Name = pw->pw_name;
    su.Home = pw->pw_dir ? pw->pw_dir : "/";
    su.Switch = true;
    int n = 0;
    getgrouplist(pw->pw_name, pw->pw_gid, nullptr, &n);
    su.Groups.resize(static_cast<std::size_t>(std::max(n, 1)));
    if (getgrouplist(pw->pw_name, pw->pw_gid, su.Groups.data(), &n) < 0)
      n = 0;
    su.Groups.resize(static_cast<std::size_t>(n));
    if (su.Groups.empty())
      su.Groups.push_back(su.Gid);
    return su;
  }
  su.Uid = me;
  su.Gid = getegid();
  const passwd* pw = getpwuid(me);
  if (!pw)
    throw std::runtime_error("the current user (uid " + std::to_string(me) +
                             ") has no passwd entry, so it has no name to use as database role");
  su.Name = pw->pw_name;
  su.Home = pw->pw_dir ? pw->pw_dir : "";
  return su;
}

int dropPrivileges(const ServerUser& su)
{
  if (!su.Switch)
    return 0;
  if (setgroups(su.Groups.size(), su.Groups.data()) != 0 || setgid(su.Gid) != 0 ||
      setuid(su.Uid) != 0)
    return errno;
  return 0;
}

namespace
{

/// Why a forked child could not execute its program, sent to the parent over a pipe.
struct ChildFailure
{
  int Stage;
  int Err;
};

/// The environment of a PostgreSQL program: ours without the PG* variables (so that a user's
/// PGHOST or PGPORT cannot redirect it) and, when it runs as the server user, with that user's
/// HOME, USER and LOGNAME.
std::vector<std::string> commandEnvironment(const ServerUser& su, const Command& cmd)
{
  std::vector<std::string> envStrings;
  for (char** e = environ; e && *e; ++e)
  {
    const std::string kv = *e;
    const std::string key = kv.substr(0, kv.find('='));
    if (key.rfind("PG", 0) == 0 || key == "LC_ALL" || key == "LC_MESSAGES")
      continue;
    if (su.Switch && (key == "HOME" || key == "USER" || key == "LOGNAME"))
      continue;
    envStrings.push_back(kv);
  }
  // Server messages in English, so that errors read the same everywhere and tests can match them.
  envStrings.push_back("LC_MESSAGES=C");
  if (!cmd.PgData.empty())
    envStrings.push_back("PGDATA=" + cmd.PgData);
  if (su.Switch)
  {
    envStrings.push_back("HOME=" + su.Home);
    envStrings.push_back("USER=" + su.Name);
    envStrings.push_back("LOGNAME=" + su.Name);
  }
  return envStrings;
}

/// In the forked child: sets up its descriptors and user and executes the program; on failure,
/// reports the stage to `errFd` and exits. Only async-signal-safe calls (see dropPrivileges).
[[noreturn]] void execChild(const ServerUser& su, const Command& cmd, char* const* argv,
                            char* const* envp, int maxFd, int errFd, int outFd)
{
  auto fail = [&](int stage)
  {
    const ChildFailure report{ stage, errno };
    if (write(errFd, &report, sizeof report) < 0)
    {
    }
    _exit(127);
  };
  const int devNull = open("/dev/null", O_RDONLY);
  if (devNull < 0 || dup2(devNull, 0) < 0)
    fail(1);
  if (const int err = dropPrivileges(su))
  {
    errno = err;
    fail(2);
  }
  if (chdir("/") != 0)
    fail(3);
  if (outFd >= 0)
  {
    if (dup2(outFd, 1) < 0 || dup2(outFd, 2) < 0)
      fail(4);
  }
  else
  {
    // Opened after dropping privileges, so the log belongs to the server user.
    const int log =
      open(cmd.LogPath.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_NOFOLLOW | O_CLOEXEC, 0600);
    if (log < 0 || dup2(log, 1) < 0 || dup2(log, 2) < 0)
      fail(5);
  }
  // Inherited descriptors (our lock file above all) must not live on in the postmaster.
#ifdef CLOSE_RANGE_CLOEXEC
  if (close_range(3, ~0u, CLOSE_RANGE_CLOEXEC) != 0)
#endif
    for (int fd = 3; fd < maxFd; ++fd)
      fcntl(fd, F_SETFD, FD_CLOEXEC);
  execve(argv[0], argv, envp);
  fail(6);
  _exit(127);
}

/// Collects the output of child `pid` from `outFd` (none if negative, which is then closed by the
/// caller) until it has exited and closed it; returns its wait status. Kills it and throws after
/// cmd.TimeoutSeconds.
int awaitChild(pid_t pid, int outFd, const Command& cmd, std::string& output)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(cmd.TimeoutSeconds);
  int status = 0;
  bool exited = false;
  bool eof = outFd < 0;
  while (!exited || !eof)
  {
    if (!eof)
    {
      pollfd p{ outFd, POLLIN, 0 };
      if (poll(&p, 1, 50) > 0)
      {
        char buf[4096];
        const ssize_t n = read(outFd, buf, sizeof buf);
        if (n > 0)
          output.append(buf, static_cast<std::size_t>(n));
        else if (n == 0 || errno != EINTR)
          eof = true;
      }
    }
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (!exited)
    {
      const pid_t w = waitpid(pid, &status, WNOHANG);
      exited = w == pid || (w < 0 && errno != EINTR);
    }
    if (std::chrono::steady_clock::now() > deadline)
    {
      if (!exited)
      {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
      }
      throw std::runtime_error(cmd.Argv[0] + " did not finish within " +
                               std::to_string(cmd.TimeoutSeconds) + " s" +
                               (output.empty() ? "" : ":\n" + output));
    }
  }
  return status;
}
}

Outcome runCommand(const ServerUser& su, const Command& cmd)
{
  const std::vector<std::string> envStrings = commandEnvironment(su, cmd);
  std::vector<char*> argv, envp;
  for (const std::string& a : cmd.Argv)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (const std::string& e : envStrings)
    envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);

  rlimit lim{};
  const int maxFd =
    (getrlimit(RLIMIT_NOFILE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY && lim.rlim_cur < 65536)
      ? static_cast<int>(lim.rlim_cur)
      : 65536;

  int errPipe[2];
  if (pipe2(errPipe, O_CLOEXEC) != 0)
    throw std::runtime_error("pipe: " + errnoText(errno));
  int outPipe[2] = { -1, -1 };
  if (cmd.LogPath.empty() && pipe2(outPipe, O_CLOEXEC) != 0)
  {
    const int err = errno;
    close(errPipe[0]);
    close(errPipe[1]);
    throw std::runtime_error("pipe: " + errnoText(err));
  }

  const pid_t pid = fork();
  if (pid == 0)
    execChild(su, cmd, argv.data(), envp.data(), maxFd, errPipe[1], outPipe[1]);
  const int forkErr = errno;
  close(errPipe[1]);
  if (outPipe[1] >= 0)
    close(outPipe[1]);
  if (pid < 0)
  {
    close(errPipe[0]);
    if (outPipe[0] >= 0)
      close(outPipe[0]);
    throw std::runtime_error("fork: " + errnoText(forkErr));
  }

  ChildFailure report{ 0, 0 };
  ssize_t got;
  do
    got = read(errPipe[0], &report, sizeof report);
  while (got < 0 && errno == EINTR);
  close(errPipe[0]);

  Outcome result;
  int status = 0;
  try
  {
    status = awaitChild(pid, outPipe[0], cmd, result.Output);
  }
  catch (...)
  {
    if (outPipe[0] >= 0)
      close(outPipe[0]);
    throw;
  }
  if (outPipe[0] >= 0)
    close(outPipe[0]);

  if (got == static_cast<ssize_t>(sizeof report))
  {
    static const char* const stages[] = { "start",   "open /dev/null",  "switch user",
                                          "chdir /", "redirect output", "open the log file",
                                          "execute" };
    const std::string what = report.Stage == 2   ? "switch to user " + su.Name
                             : report.Stage == 5 ? "open the log file " + cmd.LogPath
                             : (report.Stage > 0 && report.Stage < 7) ? stages[report.Stage]
                                                                      : stages[0];
    throw std::runtime_error("could not run " + cmd.Argv[0] + ": " + what +
                             " failed: " + errnoText(report.Err));
  }
  result.ExitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}
}
}
