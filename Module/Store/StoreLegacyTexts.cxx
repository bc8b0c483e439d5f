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

/// Scene rows are shared by the frames of a scene: a legacy row whose new text is that of a row
/// stored with the section since hands its frames over to that row and goes.
void migrateSceneTexts(PGconn* conn, const std::string& what)
{
  for (const auto& [id, old] : idsAndTexts(conn,
                                           "SELECT id, description_text FROM scenes WHERE NOT "
                                           "(description_text::jsonb ? 'rendering') ORDER BY id",
                                           what))
  {
    const std::string text = withRenderingSection(old, RenderingSectionV5, what);
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

void migrateFrameTexts(PGconn* conn, const std::string& what)
{
  for (const auto& [id, old] : idsAndTexts(conn,
                                           "SELECT id, effective_text FROM frames WHERE NOT "
                                           "(effective_text::jsonb ? 'rendering') ORDER BY id",
                                           what))
  {
    const std::string text = withRenderingSection(old, RenderingSectionV5, what);
    pg::Result same = pg::Params().bytes(text).i64(id).exec(
      conn, "SELECT id, label FROM frames WHERE frame_hash = sha256($1) AND id <> $2", what);
    if (PQntuples(same.get()) > 0)
    {
      const std::string other = std::to_string(pg::getI64(same.get(), 0, 0));
      throw StoreError(
        what + ": frame " + std::to_string(id) +
        ", stored before anti-aliasing (one ray a pixel), and frame " + other + " (label \"" +
        pg::getText(same.get(), 0, 1) +
        "\"), stored with the rendering section of one ray a pixel, are the same frame, and a "
        "frame can be stored once; delete one of them (DELETE FROM frames WHERE id = " +
        other + ", or " + std::to_string(id) + ") and migrate again");
    }
    pg::Params().i64(id).bytes(text).text(text).exec(
      conn, "UPDATE frames SET effective_text = $3, frame_hash = sha256($2) WHERE id = $1", what);
  }
}
}

std::string withRenderingSection(const std::string& text, const char* section,
                                 const std::string& what)
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
  if (j.contains("rendering"))
  {
    return text;
  }
  j["rendering"] = nlohmann::json::parse(section);
  return j.dump();
}

void addRenderingSections(PGconn* conn, const std::string& what)
{
  migrateSceneTexts(conn, what);
  migrateFrameTexts(conn, what);
}
}
}
