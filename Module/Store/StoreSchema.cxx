#include "StoreSchema.h"

#include "PgSession.h"
#include "RayStore.h"
#include "StoreLegacyTexts.h"
#include "StoreSchemaHistory.h"

#include <utility>
#include <vector>

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

const char* const NoSchemaMessage =
  "the database holds no ASRT schema, and reading creates none: make one with migrate() (with "
  "the asrt tools: asrt db init, or asrt trace --store)";

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

/// Every tile attached to `oldParent` whose frame exists re-packed into a table of its own of the
/// new layout (`stage` makes it, `convert` fills it), which takes the old one's name (`replace`)
/// and is attached to the new ray_blocks. The tables of frames deleted with plain SQL are left
/// to go with the old parent.
void repackTiles(PGconn* conn, const std::string& what, const std::string& oldParent,
                 const char* stage, const char* convert, const char* replace)
{
  pg::Result tiles = pg::Params().text(oldParent).exec(
    conn,
    "SELECT m[1]::bigint, m[2]::integer FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid "
    "CROSS JOIN LATERAL regexp_match(c.relname::text, '^ray_blocks_([0-9]+)_([0-9]+)$') AS m "
    "WHERE i.inhparent = $1::regclass AND EXISTS (SELECT 1 FROM frames f WHERE f.id = "
    "m[1]::bigint) ORDER BY 1, 2",
    what);
  for (int row = 0; row < PQntuples(tiles.get()); ++row)
  {
    const std::int64_t frame = pg::getI64(tiles.get(), row, 0);
    const std::int32_t tile = pg::getI32(tiles.get(), row, 1);
    pg::exec(conn, tileStatement(stage, frame, tile), what);
    pg::exec(conn, tileStatement(convert, frame, tile), what);
    pg::execScript(conn, tileStatement(replace, frame, tile), what);
    pg::exec(conn, tileStatement(AttachTileV3, frame, tile, "ray_blocks"), what);
  }
}

/// Migration 5: every tile of version 4 re-packed into the layout with rays_per_pixel, then the
/// texts (StoreLegacyTexts.h).
void migrateToVersion5(PGconn* conn, const std::string& what)
{
  pg::execScript(conn, SchemaV5Tables, what);
  repackTiles(conn, what, "ray_blocks_v4", SchemaV5StageTile, SchemaV5ConvertTile,
              SchemaV5ReplaceTile);
  pg::execScript(conn, SchemaV5Finish, what);
  addRenderingSections(conn, what);
}

/// `text` with each of `values`' tokens replaced, in one pass: a value that happens to contain a
/// token is not read again.
std::string filled(const std::string& text,
                   const std::vector<std::pair<std::string, std::string>>& values)
{
  std::string out;
  for (std::size_t at = 0; at < text.size();)
  {
    bool replaced = false;
    for (const auto& [token, value] : values)
    {
      if (text.compare(at, token.size(), token) == 0)
      {
        out += value;
        at += token.size();
        replaced = true;
        break;
      }
    }
    if (!replaced)
    {
      out += text[at++];
    }
  }
  return out;
}

/// What predicateRoleProblem() reports, and whether setUpPredicateRole() can put it right (a
/// role that may do more than read the rays is the administrator's to change).
struct RoleProblem
{
  std::string text;
  bool fixable;
};

/// The body of the function that evaluates predicates at schema `version` (6 or later).
const char* selectedRaysBody(int version)
{
  return version >= 7 ? SelectedRaysBodyV7 : SelectedRaysBodyV6;
}

/// At schema `version` (4 or later).
std::optional<RoleProblem> findRoleProblem(PGconn* conn, int version)
{
  const bool checksTokens = version >= 6;
  pg::Result r =
    pg::Params()
      .text(checksTokens ? selectedRaysBody(version) : "")
      .exec(
        conn,
        "SELECT r.oid IS NOT NULL, concat_ws(', ', CASE WHEN r.rolsuper THEN 'SUPERUSER' END, "
        "CASE WHEN r.rolcreaterole THEN 'CREATEROLE' END, CASE WHEN r.rolcreatedb THEN 'CREATEDB' "
        "END, CASE WHEN r.rolreplication THEN 'REPLICATION' END, CASE WHEN r.rolbypassrls THEN "
        "'BYPASSRLS' END), coalesce((SELECT string_agg(m.roleid::regrole::text, ', ' ORDER BY "
        "m.roleid::regrole::text) FROM pg_auth_members m WHERE m.member = r.oid), ''), "
        "p.oid IS NOT NULL, coalesce(o.rolname::text, ''), coalesce(p.prosecdef, false), "
        "coalesce(p.prosrc = $1, false) FROM (SELECT "
        "to_regprocedure('asrt_selected_rays(bigint,text)') AS f) x LEFT JOIN pg_proc p ON p.oid = "
        "x.f LEFT JOIN pg_roles o ON o.oid = p.proowner LEFT JOIN pg_roles r ON r.rolname = "
        "'asrt_predicate'",
        "checking the role that evaluates predicates failed");
  const std::string role =
    std::string("the role ") + PredicateRoleV4 + ", which evaluates ray predicates,";
  const std::string redo = " (migrating the database sets it up again: asrt db init)";
  if (!pg::getBool(r.get(), 0, 0))
  {
    return RoleProblem{ role + " does not exist" + redo, true };
  }
  const std::string attributes = pg::getText(r.get(), 0, 1);
  const std::string memberships = pg::getText(r.get(), 0, 2);
  if (!attributes.empty() || !memberships.empty())
  {
    return RoleProblem{
      role + " may do more than read the rays: " +
        (attributes.empty() ? "" : "it has " + attributes + (memberships.empty() ? "" : "; ")) +
        (memberships.empty() ? "" : "it is a member of " + memberships) +
        ". Take that away (ALTER ROLE, REVOKE ... FROM " + PredicateRoleV4 +
        ") and migrate again (asrt db init)",
      false
    };
  }
  const std::string function = "the function asrt_selected_rays, which evaluates ray predicates,";
  if (!pg::getBool(r.get(), 0, 3))
  {
    return RoleProblem{ function + " is missing" + redo, true };
  }
  const std::string owner = pg::getText(r.get(), 0, 4);
  if (owner != PredicateRoleV4 || !pg::getBool(r.get(), 0, 5))
  {
    return RoleProblem{ function + " would run as " + owner + ", not as " + PredicateRoleV4 + redo,
                        true };
  }
  if (checksTokens && !pg::getBool(r.get(), 0, 6))
  {
    return RoleProblem{ function + " is not the one that checks the predicate's tokens" + redo,
                        true };
  }
  return std::nullopt;
}

/// Runs one statement that a concurrent migrator of another database may be running too (roles
/// belong to the cluster, and advisory locks do not reach across databases): losing that race
/// (SQLSTATE 42710 "already exists", or 23505 on the catalog's unique index) is success. A
/// refusal for want of rights (42501) becomes `refused`'s message.
void runRoleStatement(PGconn* conn, const std::string& sql, const std::string& what,
                      const std::string& refused)
{
  pg::exec(conn, "SAVEPOINT asrt_role", what);
  try
  {
    pg::exec(conn, sql, what);
  }
  catch (const StoreError& e)
  {
    if (e.sqlState() == "42501")
    {
      throw StoreError(what + ": " + refused, e.sqlState());
    }
    if (e.sqlState() != "42710" && e.sqlState() != "23505")
    {
      throw;
    }
    pg::exec(conn, "ROLLBACK TO SAVEPOINT asrt_role", what);
  }
  pg::exec(conn, "RELEASE SAVEPOINT asrt_role", what);
}

/// Creates the role that evaluates predicates if it is missing, lets the migrating role act as it,
/// refuses a role that may do more than read the rays, then gives it the views and the function
/// of schema `version` (SchemaV4, then SchemaV6's from version 6 on, SchemaV7's from version 7
/// on). Idempotent: migrations 4, 6 and 7, and the repair of what something undid since.
void setUpPredicateRole(PGconn* conn, const std::string& what, int version)
{
  pg::Result me = pg::exec(conn,
                           "SELECT current_user::text, coalesce(current_schema()::text, ''), "
                           "(SELECT rolsuper FROM pg_roles WHERE rolname = current_user), "
                           "EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'asrt_predicate')",
                           what);
  const std::string user = pg::getText(me.get(), 0, 0);
  const std::string schema = pg::getText(me.get(), 0, 1);
  if (schema.empty())
  {
    throw StoreError(what + ": the search_path names no existing schema to hold the store");
  }
  const std::string quotedUser = pg::quoteIdentifier(conn, user, what);
  const bool roleExists = pg::getBool(me.get(), 0, 3);
  const std::string refused =
    std::string("setting up the role ") + PredicateRoleV4 +
    ", which evaluates ray predicates with no rights beyond reading the rays, needs a superuser "
    "or a role with CREATEROLE, and " +
    quotedUser +
    " is neither: migrate the database once as such a role (asrt db init --db \"... "
    "user=ADMIN\"), or have an administrator run " +
    (roleExists ? "" : std::string("CREATE ROLE ") + PredicateRoleV4 + " NOLOGIN; ") + "GRANT " +
    PredicateRoleV4 + " TO " + quotedUser + ";";
  if (!roleExists)
  {
    runRoleStatement(conn, CreatePredicateRoleV4, what, refused);
  }
  const bool superuser = pg::getBool(me.get(), 0, 2);
  pg::Result member =
    pg::exec(conn, "SELECT pg_has_role(current_user, 'asrt_predicate', 'MEMBER')", what);
  if (!superuser && !pg::getBool(member.get(), 0, 0))
  {
    // Owning what it owns is acting as it: the ALTER ... OWNER of SchemaV4 needs the membership.
    runRoleStatement(conn, std::string("GRANT ") + PredicateRoleV4 + " TO " + quotedUser, what,
                     refused);
  }
  if (const std::optional<RoleProblem> problem = findRoleProblem(conn, version))
  {
    if (!problem->fixable)
    {
      throw StoreError(what + ": " + problem->text);
    }
  }
  const std::string quotedSchema = pg::quoteIdentifier(conn, schema, what);
  pg::execScript(conn, filled(SchemaV4, { { "{schema}", quotedSchema }, { "{user}", quotedUser } }),
                 what);
  if (version >= 6)
  {
    pg::execScript(
      conn, filled(version >= 7 ? SchemaV7 : SchemaV6, { { "{schema}", quotedSchema } }), what);
  }
}

/// Migration 7: every tile of version 6 re-packed into the layout with traced (every record
/// traced), then the function that evaluates predicates, whose tokens may now name traced; then
/// the texts of those frames, which traced every pixel, name their lattice, since a text without
/// one now reads as the default grid (StoreLegacyTexts.h).
void migrateToVersion7(PGconn* conn, const std::string& what)
{
  pg::execScript(conn, SchemaV7Tables, what);
  repackTiles(conn, what, "ray_blocks_v6", SchemaV7StageTile, SchemaV7ConvertTile,
              SchemaV7ReplaceTile);
  pg::execScript(conn, SchemaV7Finish, what);
  setUpPredicateRole(conn, what, 7);
  addGridLattices(conn, what);
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
  else if (version == 3)
  {
    migrateToVersion3(conn, what);
  }
  else if (version == 4 || version == 6)
  {
    setUpPredicateRole(conn, what, version);
  }
  else if (version == 5)
  {
    migrateToVersion5(conn, what);
  }
  else if (version == 7)
  {
    migrateToVersion7(conn, what);
  }
  else if (version == 8)
  {
    pg::execScript(conn, SchemaV8, what);
  }
  else
  {
    pg::execScript(conn, SchemaV9, what);
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

std::optional<std::string> predicateRoleProblem(PGconn* conn)
{
  const std::optional<RoleProblem> problem = findRoleProblem(conn, RayStore::kSchemaVersion);
  return problem ? std::optional<std::string>(problem->text) : std::nullopt;
}

void migrateSchema(PGconn* conn, int targetVersion, bool createSchema)
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
      if (v == 0 && !createSchema)
      {
        throw StoreError(NoSchemaMessage);
      }
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
      // What something undid since (a restore without roles, a dropped function) is set up
      // again; a role granted more than the views is the administrator's to put right, and
      // until then readFrame() refuses predicates while everything else goes on.
      const std::optional<RoleProblem> problem =
        targetVersion >= 4 ? findRoleProblem(conn, targetVersion) : std::nullopt;
      if (problem && problem->fixable)
      {
        const std::string what = "setting up the role that evaluates predicates failed";
        setUpPredicateRole(conn, what, targetVersion);
        if (const std::optional<RoleProblem> still = findRoleProblem(conn, targetVersion))
        {
          throw StoreError(what + ": " + still->text);
        }
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
