#include "StoreSchema.h"

#include "PgSession.h"
#include "RayStore.h"
#include "StoreSchemaHistory.h"

namespace asrt
{
namespace storage
{
namespace
{
void replaceAll(std::string& s, const std::string& token, const std::string& value)
{
  for (std::size_t at = s.find(token); at != std::string::npos; at = s.find(token, at))
  {
    s.replace(at, token.size(), value);
    at += value.size();
  }
}

std::string mismatch(int found)
{
  return "schema version mismatch: found " + std::to_string(found) + ", this build knows " +
         std::to_string(RayStore::kSchemaVersion);
}

/// Migration 3: the tables of packed records, every tile of version 2 re-packed into a table of
/// its own attached to them, then the old table replaced.
void migrateToVersion3(PGconn* conn, const std::string& what)
{
  pg::execScript(conn, SchemaV3Tables, what);
  pg::Result tiles =
    pg::exec(conn, "SELECT DISTINCT frame_id, tile FROM ray_blocks ORDER BY frame_id, tile", what);
  for (int row = 0; row < PQntuples(tiles.get()); ++row)
  {
    const std::int64_t frame = pg::getI64(tiles.get(), row, 0);
    const std::int32_t tile = pg::getI32(tiles.get(), row, 1);
    pg::exec(conn, tileStatement(TileTableV3, frame, tile), what);
    pg::exec(conn, tileStatement(SchemaV3ConvertTile, frame, tile), what);
    pg::exec(conn, tileStatement(AttachTileV3, frame, tile, "ray_blocks_v3"), what);
  }
  pg::execScript(conn, SchemaV3Finish, what);
}

/// Migration `version` takes version − 1 to `version`, inside migrateSchema()'s transaction.
void runMigration(PGconn* conn, int version)
{
  const std::string what = "migration to schema version " + std::to_string(version) + " failed";
  if (version == 1)
  {
    pg::execScript(conn, SchemaV1, what);
  }
  else if (version == 2)
  {
    pg::execScript(conn, SchemaV2, what);
  }
  else
  {
    migrateToVersion3(conn, what);
  }
}
}

std::string tileStatement(const char* statement, std::int64_t frame, std::int32_t tile,
                          const std::string& parent)
{
  std::string s = statement;
  replaceAll(s, "{frame}", std::to_string(frame));
  replaceAll(s, "{tile}", std::to_string(tile));
  replaceAll(s, "{next_tile}", std::to_string(std::int64_t(tile) + 1));
  replaceAll(s, "{parent}", parent);
  return s;
}

std::string blockTable(std::int64_t frame, std::int32_t tile)
{
  return "ray_blocks_" + std::to_string(frame) + "_" + std::to_string(tile);
}

std::string createBlockTable(std::int64_t frame, std::int32_t tile)
{
  return tileStatement(TileTableV3, frame, tile);
}

std::string attachBlockTable(const std::string& parent, std::int64_t frame, std::int32_t tile)
{
  return tileStatement(AttachTileV3, frame, tile, parent);
}

int readSchemaVersion(PGconn* conn)
{
  pg::Result r = pg::exec(conn, "SELECT to_regclass('schema_version') IS NOT NULL",
                          "reading the schema version failed");
  if (!pg::getBool(r.get(), 0, 0))
  {
    return 0;
  }
  r = pg::exec(conn, "SELECT coalesce(max(version), 0) FROM schema_version",
               "reading the schema version failed");
  return pg::getI32(r.get(), 0, 0);
}

void requireCurrentSchema(PGconn* conn)
{
  const int v = readSchemaVersion(conn);
  if (v == 0)
  {
    throw StoreError("the database has no ASRT schema (schema version 0); call migrate() first");
  }
  if (v != RayStore::kSchemaVersion)
  {
    throw StoreError(mismatch(v) + (v < RayStore::kSchemaVersion
                                      ? "; call migrate() to upgrade the database"
                                      : "; the database was written by a newer ASRT"));
  }
}

void migrateSchema(PGconn* conn, int targetVersion)
{
  pg::transaction(
    conn, pg::WriteBegin,
    [&]
    {
      // Concurrent migrators wait for each other instead of failing on each other's tables.
      pg::Params()
        .i64(SchemaLockKey)
        .exec(conn, "SELECT pg_advisory_xact_lock($1)", "locking the schema failed");
      const int v = readSchemaVersion(conn);
      if (v > RayStore::kSchemaVersion)
      {
        throw StoreError(mismatch(v) + "; refusing to touch a database written by a newer ASRT");
      }
      if (v > targetVersion)
      {
        throw StoreError("the database is at schema version " + std::to_string(v) +
                         ", past the requested " + std::to_string(targetVersion) +
                         "; migrations never go back");
      }
      for (int m = v + 1; m <= targetVersion; ++m)
      {
        runMigration(conn, m);
      }
      if (v != targetVersion)
      {
        pg::exec(conn, "DELETE FROM schema_version", "recording the schema version failed");
        pg::Params()
          .i32(targetVersion)
          .exec(conn, "INSERT INTO schema_version (version) VALUES ($1)",
                "recording the schema version failed");
      }
      pg::exec(conn, "COMMIT", "committing the migration failed");
    });
}
}
}
