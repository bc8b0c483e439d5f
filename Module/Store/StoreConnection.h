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
/// Whether storeConnection(given) names the private embedded server (no conninfo given, no PG*
/// variable set). Its database "asrt" exists for ASRT alone, so even a reading tool may create
/// the schema there; in a database the user names, only writers and asrt db init do.
ASRTSTORE_EXPORT bool storeConnectionIsPrivate(const char* given);
}

#endif
