#include "StoreConnection.h"

#include "EmbeddedPostgres.h"

#include <cstdlib>

namespace asrt
{
bool storeConnectionIsPrivate(const char* given)
{
  if (given && *given)
    return false;
  for (const char* var : { "PGHOST", "PGHOSTADDR", "PGPORT", "PGDATABASE", "PGSERVICE", "PGUSER" })
  {
    const char* v = std::getenv(var);
    if (v && *v)
      return false; // the user set up a connection the standard way
  }
  return true;
}

std::string storeConnection(const char* given)
{
  if (given && *given)
    return given;
  if (!storeConnectionIsPrivate(given))
    return std::string(); // libpq's defaults and the PG* variables
  EmbeddedPostgres server(EmbeddedPostgres::defaultDataDirectory());
  return server.ensureRunning();
}
}
