#include "StoreConnection.h"

#include "EmbeddedPostgres.h"

#include <cstdlib>

namespace asrt
{
std::string storeConnection(const char* given)
{
  if (given && *given)
    return given;
  for (const char* var : { "PGHOST", "PGHOSTADDR", "PGPORT", "PGDATABASE", "PGSERVICE", "PGUSER" })
  {
    const char* v = std::getenv(var);
    if (v && *v)
      return std::string(); // the user set up a connection the standard way
  }
  EmbeddedPostgres server(EmbeddedPostgres::defaultDataDirectory());
  return server.ensureRunning();
}
}
