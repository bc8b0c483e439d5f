// The store's schema: its version, the migrations that bring a database to it (from the frozen
// texts of StoreSchemaHistory.h), and the per-tile tables of ray_blocks that writes create.
// Internal to ASRT::Store.
#ifndef asrt_StoreSchema_h
#define asrt_StoreSchema_h

#include <libpq-fe.h>

#include <cstdint>
#include <optional>
#include <string>

namespace asrt
{
namespace storage
{
/// The key of the transaction-scoped advisory lock that serialises migrators: "ASRT" as four
/// ASCII bytes (0x41535254), a number no other application is likely to lock in the same
/// database. WriterLockClass (StoreTileRows.h) is the next number.
constexpr std::int64_t SchemaLockKey = 1095979604;

/// A tile statement of StoreSchemaHistory.h with its placeholders filled in. Made from numbers
/// (and the store's own table names) only: nothing a caller gives reaches this text.
std::string tileStatement(const char* statement, std::int64_t frame, std::int32_t tile,
                          const std::string& parent = std::string());

/// The table holding the rays of one tile of one frame.
std::string blockTable(std::int64_t frame, std::int32_t tile);
/// Creates a tile's table (not attached to anything yet).
std::string createBlockTable(std::int64_t frame, std::int32_t tile);
/// Attaches a tile's table to the partitioned table `parent`.
std::string attachBlockTable(const std::string& parent, std::int64_t frame, std::int32_t tile);

/// The database's schema version; 0 if it has none yet.
int readSchemaVersion(PGconn* conn);
/// Throws StoreError unless the database is at RayStore::kSchemaVersion.
void requireCurrentSchema(PGconn* conn);
/// Brings the database from its version to `targetVersion` (1 to kSchemaVersion) in one
/// transaction, serialised against concurrent migrators; refuses a newer database and never
/// goes back. Without `createSchema`, a database with no ASRT schema is refused (StoreError)
/// and left untouched. At version 4 and later it also sets up again the role that evaluates
/// predicates, or its function, if something undid them (see predicateRoleProblem); a role
/// granted more than the views is left to the administrator.
void migrateSchema(PGconn* conn, int targetVersion, bool createSchema = true);

/// What keeps predicates from being evaluated with the rights of the role asrt_predicate alone,
/// their tokens checked by the server (the current schema version): the role or the function
/// asrt_selected_rays missing, the function running as another role or not the one of schema
/// version 6 (which checks the tokens), or the role holding more than its grants on the views (an
/// attribute such as SUPERUSER, or membership in any role). Empty when all is well. One catalog
/// query, cheap enough to run before every predicate.
std::optional<std::string> predicateRoleProblem(PGconn* conn);
}
}

#endif
