// Which PostgreSQL the tools talk to when the user names none.
#ifndef asrt_StoreConnection_h
#define asrt_StoreConnection_h

#include "asrtStoreModule.h"

#include <string>

namespace asrt
{
/// `given` if not empty; else "" (libpq's defaults) when any standard PG* connection variable is
/// set; else the conninfo of the private embedded server, started or reused.
ASRTSTORE_EXPORT std::string storeConnection(const char* given);
}

#endif
