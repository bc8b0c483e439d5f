// A real, private PostgreSQL 15 server for one test program: a fresh cluster in a temporary
// directory, listening only on a unix socket there, run as a non-root user when the tests run as
// root. Started in the constructor, stopped and deleted in the destructor.
#ifndef asrt_ThrowawayPostgres_h
#define asrt_ThrowawayPostgres_h

#include <string>

namespace asrt
{
namespace testing
{
class ThrowawayPostgres
{
public:
  ThrowawayPostgres();  ///< initdb + start; throws std::runtime_error with the server's log on
                        ///< failure
  ~ThrowawayPostgres(); ///< stop (immediate) and remove the directory
  ThrowawayPostgres(const ThrowawayPostgres&) = delete;
  ThrowawayPostgres& operator=(const ThrowawayPostgres&) = delete;

  /// libpq conninfo for the database "asrt" of this server (host = the socket directory).
  std::string conninfo() const;
  /// Conninfo for a database of another name on the same server (created if missing).
  std::string conninfo(const std::string& database) const;
  void stop(bool immediate = true);
  void start();
  void restart();
  bool running() const;
  const std::string& directory() const;

private:
  struct Impl;
  Impl* P;
};
}
}

#endif
