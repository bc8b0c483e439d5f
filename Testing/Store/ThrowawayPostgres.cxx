#include "ThrowawayPostgres.h"

#include "EmbeddedPostgres.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

namespace asrt
{
namespace testing
{
struct ThrowawayPostgres::Impl
{
  std::string TempDir; ///< from mkdtemp; holds the cluster directory and its lock file
  EmbeddedPostgres Server;

  explicit Impl(std::string tempDir)
    : TempDir(tempDir)
    , Server(tempDir + "/data")
  {
    // Nothing here outlives the test program, so skip every fsync.
    Server.setDurable(false);
  }
};

namespace
{
std::string makeTempDir()
{
  // Short on purpose: the socket lives in the cluster directory, and socket paths are limited to
  // 107 characters.
  char tmpl[] = "/tmp/asrt-test-XXXXXX";
  if (!mkdtemp(tmpl))
    throw std::runtime_error(std::string("mkdtemp /tmp/asrt-test-XXXXXX: ") + std::strerror(errno));
  if (geteuid() == 0)
  {
    // mkdtemp's directory is root's and private; the server (user postgres) must get through it.
    if (const passwd* pw = getpwnam("postgres"))
    {
      if (chown(tmpl, pw->pw_uid, pw->pw_gid) != 0)
        throw std::runtime_error(std::string("chown ") + tmpl + ": " + std::strerror(errno));
    }
  }
  return tmpl;
}
}

ThrowawayPostgres::ThrowawayPostgres()
  : P(new Impl(makeTempDir()))
{
  try
  {
    P->Server.ensureRunning();
  }
  catch (...)
  {
    std::error_code ec;
    std::filesystem::remove_all(P->TempDir, ec);
    delete P;
    throw;
  }
}

ThrowawayPostgres::~ThrowawayPostgres()
{
  try
  {
    P->Server.stop(true);
  }
  catch (...)
  {
    // Removing the directory below makes a server that did not stop exit on its own soon.
  }
  try
  {
    P->Server.destroy();
  }
  catch (...)
  {
  }
  std::error_code ec;
  std::filesystem::remove_all(P->TempDir, ec);
  delete P;
}

std::string ThrowawayPostgres::conninfo() const
{
  return P->Server.conninfo();
}

std::string ThrowawayPostgres::conninfo(const std::string& database) const
{
  P->Server.ensureDatabase(database);
  return P->Server.conninfo(database);
}

void ThrowawayPostgres::stop(bool immediate)
{
  P->Server.stop(immediate);
}

void ThrowawayPostgres::start()
{
  P->Server.ensureRunning();
}

void ThrowawayPostgres::restart()
{
  P->Server.stop(false);
  P->Server.ensureRunning();
}

bool ThrowawayPostgres::running() const
{
  return P->Server.running();
}

const std::string& ThrowawayPostgres::directory() const
{
  return P->Server.dataDirectory();
}
}
}
