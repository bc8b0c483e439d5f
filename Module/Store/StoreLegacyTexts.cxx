#include "StoreLegacyTexts.h"

#include "PgSession.h"
#include "StoreSchemaHistory.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
namespace storage
{
namespace
{
/// The rows (id, text) of `sql`, a query of two columns.
std::vector<std::pair<std::int64_t, std::string>> idsAndTexts(PGconn* conn, const char* sql,
                                                              const std::string& what)
{
  pg::Result r = pg::exec(conn, sql, what);
  std::vector<std::pair<std::int64_t, std::string>> rows;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    rows.emplace_back(pg::getI64(r.get(), row, 0), pg::getText(r.get(), row, 1));
  }
  return rows;
}

/// A stored text's rewrite, and the SQL condition (on the column `$TEXT`) of the texts it applies
/// to.
using Rewrite = std::string (*)(const std::string& text, const std::string& what);

std::string conditionOn(const char* condition, const char* column)
{
  std::string sql = condition;
  const std::string key = "$TEXT";
  for (std::size_t at = sql.find(key); at != std::string::npos; at = sql.find(key, at))
    sql.replace(at, key.size(), column);
  return sql;
}

/// Scene rows are shared by the frames of a scene: a row whose new text is that of a row stored
/// with it since hands its frames over to that row and goes.
void migrateSceneTexts(PGconn* conn, const char* condition, Rewrite rewrite,
                       const std::string& what)
{
  const std::string select = "SELECT id, description_text FROM scenes WHERE " +
                             conditionOn(condition, "description_text") + " ORDER BY id";
  for (const auto& [id, old] : idsAndTexts(conn, select.c_str(), what))
  {
    const std::string text = rewrite(old, what);
    pg::Result same = pg::Params().bytes(text).i64(id).exec(
      conn, "SELECT id FROM scenes WHERE content_hash = sha256($1) AND id <> $2", what);
    if (PQntuples(same.get()) > 0)
    {
      pg::Params()
        .i64(id)
        .i64(pg::getI64(same.get(), 0, 0))
        .exec(conn, "UPDATE frames SET scene_id = $2 WHERE scene_id = $1", what);
      pg::Params().i64(id).exec(conn, "DELETE FROM scenes WHERE id = $1", what);
      continue;
    }
    pg::Params().i64(id).bytes(text).text(text).exec(
      conn,
      "UPDATE scenes SET content_hash = sha256($2), description = $3::jsonb, description_text = "
      "$3 WHERE id = $1",
      what);
  }
}

/// `before` says how the frames were traced that a rewritten text now shares with another frame.
void migrateFrameTexts(PGconn* conn, const char* condition, Rewrite rewrite, const char* before,
                       const std::string& what)
{
  const std::string select = "SELECT id, effective_text FROM frames WHERE " +
                             conditionOn(condition, "effective_text") + " ORDER BY id";
  for (const auto& [id, old] : idsAndTexts(conn, select.c_str(), what))
  {
    const std::string text = rewrite(old, what);
    pg::Result same = pg::Params().bytes(text).i64(id).exec(
      conn, "SELECT id, label FROM frames WHERE frame_hash = sha256($1) AND id <> $2", what);
    if (PQntuples(same.get()) > 0)
    {
      const std::string other = std::to_string(pg::getI64(same.get(), 0, 0));
      throw StoreError(what + ": frame " + std::to_string(id) + ", stored " + before +
                       ", and frame " + other + " (label \"" + pg::getText(same.get(), 0, 1) +
                       "\"), stored with those settings written out, are the same frame, and a "
                       "frame can be stored once; delete one of them (DELETE FROM frames WHERE "
                       "id = " +
                       other + ", or " + std::to_string(id) + ") and migrate again");
    }
    pg::Params().i64(id).bytes(text).text(text).exec(
      conn, "UPDATE frames SET effective_text = $3, frame_hash = sha256($2) WHERE id = $1", what);
  }
}

nlohmann::json parsedObject(const std::string& text, const std::string& what)
{
  nlohmann::json j;
  try
  {
    j = nlohmann::json::parse(text);
  }
  catch (const nlohmann::json::exception& e)
  {
    throw StoreError(what + ": a stored scene text is no JSON (" + e.what() + ")");
  }
  if (!j.is_object())
  {
    throw StoreError(what + ": a stored scene text is no JSON object");
  }
  return j;
}

std::string withRenderingSectionV5(const std::string& text, const std::string& what)
{
  return withRenderingSection(text, RenderingSectionV5, what);
}
}

std::string withRenderingSection(const std::string& text, const char* section,
                                 const std::string& what)
{
  nlohmann::json j = parsedObject(text, what);
  if (j.contains("rendering"))
  {
    return text;
  }
  j["rendering"] = nlohmann::json::parse(section);
  return j.dump();
}

std::string withGridLattice(const std::string& text, const std::string& what)
{
  nlohmann::json j = parsedObject(text, what);
  auto rendering = j.find("rendering");
  if (rendering == j.end() || !rendering->is_object() || rendering->contains("gridLattice"))
  {
    return text;
  }
  (*rendering)["gridLattice"] = 1;
  return j.dump();
}

void addRenderingSections(PGconn* conn, const std::string& what)
{
  const char* condition = "NOT ($TEXT::jsonb ? 'rendering')";
  migrateSceneTexts(conn, condition, withRenderingSectionV5, what);
  migrateFrameTexts(conn, condition, withRenderingSectionV5,
                    "before anti-aliasing (one ray a pixel)", what);
}

void addGridLattices(PGconn* conn, const std::string& what)
{
  const char* condition = "NOT (($TEXT::jsonb -> 'rendering') ? 'gridLattice')";
  migrateSceneTexts(conn, condition, withGridLattice, what);
  migrateFrameTexts(conn, condition, withGridLattice,
                    "before the adaptive ray grid (every pixel traced)", what);
}
}
}
