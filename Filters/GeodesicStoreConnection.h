// Which PostgreSQL the VTK filters talk to when the user names none.
#ifndef asrt_GeodesicStoreConnection_h
#define asrt_GeodesicStoreConnection_h

#include <string>

namespace asrt
{
/// `given` if not empty; else "" (libpq's defaults) when any standard PG* connection variable is
/// set; else the conninfo of the private embedded server, started or reused.
std::string storeConnection(const char* given);
}

#endif
