#include "StoreFrameRows.h"

#include "SceneFile.h"
#include "StoreRecordCodec.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <exception>
#include <set>
#include <utility>

namespace asrt
{
namespace storage
{
namespace
{
/// A scene row may vanish between its upsert and its look-up only when a concurrent deletion
/// removes it as unused in that instant; five attempts in a row losing that race means the
/// scene's frames are being deleted as fast as they are written, and the caller should hear so.
constexpr int SceneRowAttempts = 5;

const char* const FrameColumns =
  "f.id, f.scene_id, encode(s.content_hash, 'hex'), encode(f.frame_hash, 'hex'), f.name, f.label, "
  "f.mass, f.spin, f.charge, f.camera_x, f.camera_y, f.camera_z, f.focal_x, f.focal_y, f.focal_z, "
  "f.up_x, f.up_y, f.up_z, f.view_angle, f.width, f.height, f.method, f.step, "
  "f.relative_tolerance, f.absolute_tolerance, f.status, coalesce(f.write_seconds, 'NaN'), "
  "coalesce(f.trace_seconds, 'NaN'), "
  "to_char(f.created_at AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T\"HH24:MI:SS.US\"Z\"'), f.ray_count, "
  "f.tile_count, (SELECT count(*) FROM ray_paths p WHERE p.frame_id = f.id) "
  "FROM frames f JOIN scenes s ON s.id = f.scene_id WHERE f.status = 'complete'";

FrameInfo frameFromRow(const PGresult* r, int row)
{
  using pg::getF64;
  using pg::getI32;
  using pg::getI64;
  using pg::getText;
  FrameInfo f;
  int c = 0;
  f.id = getI64(r, row, c++);
  f.sceneId = getI64(r, row, c++);
  f.sceneHash = getText(r, row, c++);
  f.frameHash = getText(r, row, c++);
  f.name = getText(r, row, c++);
  f.label = getText(r, row, c++);
  FrameKey& k = f.key;
  k.spacetime.mass = getF64(r, row, c++);
  k.spacetime.spin = getF64(r, row, c++);
  k.spacetime.charge = getF64(r, row, c++);
  for (Vec3* v : { &k.cameraPosition, &k.focalPoint, &k.viewUp })
  {
    for (int m = 0; m < 3; ++m)
    {
      (*v)[m] = getF64(r, row, c++);
    }
  }
  k.viewAngle = getF64(r, row, c++);
  k.width = getI32(r, row, c++);
  k.height = getI32(r, row, c++);
  k.method = getText(r, row, c++);
  k.step = getF64(r, row, c++);
  k.relativeTolerance = getF64(r, row, c++);
  k.absoluteTolerance = getF64(r, row, c++);
  f.status = getText(r, row, c++);
  f.writeSeconds = getF64(r, row, c++);
  f.traceSeconds = getF64(r, row, c++);
  f.createdAt = getText(r, row, c++);
  f.rayCount = getI64(r, row, c++);
  f.tileCount = getI32(r, row, c++);
  f.pathCount = getI64(r, row, c++);
  return f;
}
}

SceneTexts sceneTexts(const SceneDescription& d)
{
  SceneTexts t;
  try
  {
    t.frame = effectiveSceneText(d);
    nlohmann::json j = nlohmann::json::parse(t.frame);
    j.erase("spacetime");
    for (const char* k : { "position", "focalPoint", "viewUp", "viewAngle", "resolution" })
    {
      j["camera"].erase(k);
    }
    for (const char* k : { "method", "step", "relativeTolerance", "absoluteTolerance" })
    {
      j["integrator"].erase(k);
    }
    t.scene = j.dump();
  }
  catch (const std::exception& e)
  {
    throw StoreError(std::string("cannot serialise the scene description: ") + e.what());
  }
  pg::requireText(t.frame, "the scene description");
  // JSON may escape a NUL as \u0000, which the text check cannot see and jsonb refuses: refuse it
  // here, before the database, like a NUL anywhere else.
  if (t.frame.find("\\u0000") != std::string::npos)
    throw StoreError("the scene description contains a NUL character (\\u0000); it was not stored");
  return t;
}

std::int64_t sceneRow(PGconn* conn, const SceneTexts& texts)
{
  for (int attempt = 0; attempt < SceneRowAttempts; ++attempt)
  {
    const std::int64_t id = pg::transaction(
      conn, pg::WriteBegin,
      [&]
      {
        pg::Params()
          .bytes(texts.scene)
          .text(texts.scene)
          .exec(conn,
                "INSERT INTO scenes (content_hash, description, description_text) "
                "VALUES (sha256($1), $2::jsonb, $2) ON CONFLICT (content_hash) DO NOTHING",
                "storing the scene failed");
        pg::Result found = pg::Params()
                             .bytes(texts.scene)
                             .exec(conn, "SELECT id FROM scenes WHERE content_hash = sha256($1)",
                                   "finding the scene failed");
        const std::int64_t sceneId = PQntuples(found.get()) ? pg::getI64(found.get(), 0, 0) : -1;
        pg::exec(conn, "COMMIT", "committing the scene failed");
        return sceneId;
      });
    if (id >= 0)
    {
      return id;
    }
  }
  throw StoreError("storing the scene failed: its row kept disappearing under concurrent "
                   "deletions");
}

void dropUnusedScenes(PGconn* conn, std::int64_t sceneId) noexcept
{
  if (PQstatus(conn) != CONNECTION_OK || PQtransactionStatus(conn) != PQTRANS_IDLE)
  {
    return;
  }
  try
  {
    pg::Params().i64(sceneId).exec(
      conn,
      "DELETE FROM scenes WHERE id IN (SELECT s.id FROM scenes s WHERE ($1 < 0 OR s.id = $1) "
      "AND NOT EXISTS (SELECT 1 FROM frames f WHERE f.scene_id = s.id) FOR UPDATE SKIP LOCKED)",
      "removing an unused scene failed");
  }
  catch (const StoreError&)
  {
    // A frame committed in the meantime refers to it (foreign key): it stays, as it should.
  }
}

std::optional<std::int64_t> insertFrame(PGconn* conn, std::int64_t sceneId, const SceneTexts& texts,
                                        const SceneDescription& scene, const std::string& label,
                                        int tileCount, bool ifAbsent)
{
  const CameraParameters& cam = scene.camera;
  const IntegratorConfig& ic = scene.integrator;
  pg::Params ins;
  ins.i64(sceneId).bytes(texts.frame).text(texts.frame).text(scene.name).text(label);
  ins.f64(scene.spacetime.mass).f64(scene.spacetime.spin).f64(scene.spacetime.charge);
  for (const Vec3* v : { &cam.position, &cam.focalPoint, &cam.viewUp })
  {
    ins.f64(v->x()).f64(v->y()).f64(v->z());
  }
  ins.f64(cam.viewAngle).i32(cam.width).i32(cam.height).text(ic.method).f64(ic.step);
  ins.f64(ic.relativeTolerance).f64(ic.absoluteTolerance).i32(tileCount);
  try
  {
    pg::Result r = ins.exec(
      conn,
      std::string("INSERT INTO frames (scene_id, frame_hash, effective_text, name, label, mass, "
                  "spin, charge, camera_x, camera_y, camera_z, focal_x, focal_y, focal_z, up_x, "
                  "up_y, up_z, view_angle, width, height, method, step, relative_tolerance, "
                  "absolute_tolerance, tile_count, status) VALUES ($1, sha256($2), $3, $4, $5, $6, "
                  "$7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22, "
                  "$23, $24, $25, 'writing')") +
        (ifAbsent ? " ON CONFLICT (frame_hash) DO NOTHING" : "") + " RETURNING id",
      "creating the frame failed");
    if (PQntuples(r.get()) == 0)
    {
      return std::nullopt;
    }
    return pg::getI64(r.get(), 0, 0);
  }
  catch (const StoreError& e)
  {
    if (e.sqlState() == "23503")
    {
      throw SceneVanished();
    }
    throw;
  }
}

std::optional<FrameOfIdentity> findFrameOfIdentity(PGconn* conn, const SceneTexts& texts, bool lock)
{
  pg::Result r =
    pg::Params()
      .bytes(texts.frame)
      .exec(conn,
            std::string(
              "SELECT id, status, tile_count, label FROM frames WHERE frame_hash = sha256($1)") +
              (lock ? " FOR UPDATE" : ""),
            "looking for an existing frame failed");
  if (PQntuples(r.get()) == 0)
  {
    return std::nullopt;
  }
  return FrameOfIdentity{ pg::getI64(r.get(), 0, 0), pg::getText(r.get(), 0, 1),
                          pg::getI32(r.get(), 0, 2), pg::getText(r.get(), 0, 3) };
}

namespace
{
[[noreturn]] void refuseDuplicate(const FrameOfIdentity& old)
{
  throw StoreError("duplicate frame: this scene with these parameters is already stored as "
                   "frame " +
                   std::to_string(old.id) + " (label \"" + old.label +
                   "\"); pass replace = true to replace it");
}
}

void refuseIdentityClash(const FrameOfIdentity& old, bool replace)
{
  if (old.status != "complete")
  {
    throw StoreError("duplicate frame: this scene with these parameters is being "
                     "written as tiled frame " +
                     std::to_string(old.id) + " (label \"" + old.label +
                     "\"); delete it first if its writers are gone");
  }
  if (!replace)
  {
    refuseDuplicate(old);
  }
}

void deleteReplaced(PGconn* conn, const FrameOfIdentity& old, bool replace)
{
  if (!replace)
  {
    refuseDuplicate(old);
  }
  deleteFrameRow(conn, old.id, "deleting the frame to be replaced failed");
}

void deleteFrameRow(PGconn* conn, std::int64_t id, const std::string& what)
{
  pg::Params().i64(id).exec(conn, "DELETE FROM frames WHERE id = $1", what);
}

std::vector<FrameInfo> selectFrames(PGconn* conn, const pg::Params& params,
                                    const std::string& condition, const std::string& what)
{
  pg::Result r = params.exec(conn, std::string("SELECT ") + FrameColumns + condition, what);
  std::vector<FrameInfo> frames;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    frames.push_back(frameFromRow(r.get(), row));
  }
  return frames;
}

pg::Result completeFrameColumn(PGconn* conn, std::int64_t id, const std::string& column,
                               const std::string& what)
{
  pg::Result r = pg::Params().i64(id).exec(
    conn, "SELECT " + column + " FROM frames WHERE id = $1 AND status = 'complete'", what);
  if (PQntuples(r.get()) == 0)
  {
    throw StoreError("there is no frame " + std::to_string(id));
  }
  return r;
}

void checkPaths(const SceneDescription& scene, const std::vector<RayPath>& paths)
{
  std::set<std::pair<int, int>> seen;
  for (std::size_t k = 0; k < paths.size(); ++k)
  {
    const RayPath& p = paths[k];
    const std::string which = "path " + std::to_string(k) + " (pixel " + std::to_string(p.i) +
                              ", " + std::to_string(p.j) + ")";
    if (p.i < 0 || p.j < 0 || p.i >= scene.camera.width || p.j >= scene.camera.height)
    {
      throw StoreError(which + " lies outside the " + std::to_string(scene.camera.width) + " x " +
                       std::to_string(scene.camera.height) + " frame; nothing was stored");
    }
    if (!seen.insert({ p.i, p.j }).second)
    {
      throw StoreError(which + ": that pixel already has a path; nothing was stored");
    }
    if (p.points.size() > (std::size_t(1) << 30) / kPathPointBytes - 1)
    {
      throw StoreError(which + " has " + std::to_string(p.points.size()) +
                       " points, more than PostgreSQL holds in one value; nothing was stored");
    }
  }
}

void copyPaths(PGconn* conn, std::int64_t frameId, const std::vector<RayPath>& paths)
{
  if (paths.empty())
  {
    return;
  }
  pg::CopyWriter writer(conn,
                        "COPY ray_paths (frame_id, i, j, seq, termination, n, points) FROM STDIN "
                        "(FORMAT binary)",
                        "the paths");
  for (std::size_t k = 0; k < paths.size(); ++k)
  {
    const RayPath& path = paths[k];
    writer.row(7);
    writer.i64(frameId);
    writer.i32(path.i);
    writer.i32(path.j);
    writer.i32(std::int32_t(k));
    writer.i32(std::int32_t(path.termination));
    writer.i32(std::int32_t(path.points.size()));
    encodePathPoints(path.points, writer.bytes(path.points.size() * kPathPointBytes));
  }
  writer.finish();
}

std::vector<RayPath> readPathRows(PGconn* conn, std::int64_t id)
{
  std::vector<RayPath> paths;
  pg::Params().i64(id).stream(
    conn, "SELECT i, j, termination, n, points FROM ray_paths WHERE frame_id = $1 ORDER BY seq",
    "reading the paths failed",
    [&](const PGresult* row)
    {
      RayPath p;
      p.i = pg::getI32(row, 0, 0);
      p.j = pg::getI32(row, 0, 1);
      p.termination = Termination(pg::getI32(row, 0, 2));
      const std::int32_t n = pg::getI32(row, 0, 3);
      if (n < 0 || PQgetlength(row, 0, 4) != std::int64_t(n) * kPathPointBytes)
      {
        throw StoreError("reading the paths of frame " + std::to_string(id) +
                         " failed: the path of pixel (" + std::to_string(p.i) + ", " +
                         std::to_string(p.j) + ") is malformed");
      }
      decodePathPoints(PQgetvalue(row, 0, 4), std::size_t(n), p.points);
      paths.push_back(std::move(p));
    });
  return paths;
}

TiledFrameStart beginOrJoinTiledFrame(PGconn* conn, std::int64_t sceneId, const SceneTexts& texts,
                                      const SceneDescription& scene, const std::string& label,
                                      int tileCount, bool replace)
{
  return pg::transaction(
    conn, pg::WriteBegin,
    [&]() -> TiledFrameStart
    {
      TiledFrameStart start{ insertFrame(conn, sceneId, texts, scene, label, tileCount, true) };
      if (!start.id)
      {
        const std::optional<FrameOfIdentity> old = findFrameOfIdentity(conn, texts, true);
        if (!old)
        {
          pg::exec(conn, "ROLLBACK", "ending the transaction failed");
          return start;
        }
        if (old->status == "writing")
        {
          if (old->tileCount != tileCount)
          {
            throw StoreError(
              "frame " + std::to_string(old->id) + " of this scene is being written as " +
              std::to_string(old->tileCount) + " tiles, not " + std::to_string(tileCount));
          }
          pg::exec(conn, "COMMIT", "committing the frame failed");
          start.id = old->id;
          return start;
        }
        deleteReplaced(conn, *old, replace);
        start.replaced = true;
        // No conflict is possible any more: the old row is deleted and locked by us.
        start.id = insertFrame(conn, sceneId, texts, scene, label, tileCount, false);
      }
      pg::exec(conn, "COMMIT", "committing the frame failed");
      return start;
    });
}

void requireReadMemory(std::int64_t id, std::int64_t rayCount, double limit)
{
  const double bytes = static_cast<double>(rayCount) * sizeof(RayRecord);
  const double allowed = limit > 0 ? limit : defaultMemoryLimit();
  if (bytes > allowed)
  {
    char text[160];
    std::snprintf(text, sizeof text,
                  "reading frame %lld needs %.3g GB for its %lld rays (frames.ray_count), more "
                  "than the %.3g GB allowed",
                  static_cast<long long>(id), bytes / 1e9, static_cast<long long>(rayCount),
                  allowed / 1e9);
    throw StoreError(text);
  }
}
}

void checkFrameSize(std::int64_t id, int width, int height, std::int64_t rayCount)
{
  const std::string frame = "frame " + std::to_string(id) + " is inconsistent: ";
  if (width < 1 || height < 1)
  {
    throw StoreError(frame +
                     (width < 1 ? "frames.width = " + std::to_string(width)
                                : "frames.height = " + std::to_string(height)) +
                     " is no size (at least 1)");
  }
  const long long pixels = static_cast<long long>(width) * height;
  const std::string size = std::to_string(width) + " x " + std::to_string(height);
  if (pixels > kMaxFramePixels)
  {
    throw StoreError(frame + "frames.width x frames.height = " + size + " is more than the " +
                     std::to_string(kMaxFramePixels) + " pixels (2^28) a frame may have");
  }
  // Not tied to the pixels: the store keeps whatever records it is given (a subset of the
  // pixels, or synthetic rays), but never more than a frame may trace.
  if (rayCount < 0 || rayCount > kMaxFramePixels)
  {
    throw StoreError(frame + "frames.ray_count = " + std::to_string(rayCount) +
                     (rayCount < 0 ? " is negative"
                                   : " is more than the " + std::to_string(kMaxFramePixels) +
                                       " rays (2^28) a frame may trace"));
  }
}

namespace storage
{
void recordInterpolatedKeys(PGconn* conn, const SceneTexts& texts, const std::string& recipe,
                            const std::vector<std::int64_t>& keys)
{
  if (recipe.empty() || keys.empty() || keys.size() > 16)
    throw StoreError("recording an interpolated frame: " +
                     (recipe.empty() ? std::string("the recipe is empty")
                                     : std::to_string(keys.size()) + " keys (1 to 16)"));
  std::string array = "{";
  for (std::int64_t id : keys)
    array += (array.size() > 1 ? "," : "") + std::to_string(id);
  array += "}";
  // Written only when every key is a complete frame: a record never names a key that is not
  // there to make the frame from.
  pg::Result r =
    pg::Params()
      .bytes(texts.frame)
      .text(recipe)
      .text(array)
      .exec(
        conn,
        "INSERT INTO interpolated_frames (frame_hash, recipe, key_frame_ids) SELECT sha256($1), "
        "$2, "
        "$3::bigint[] WHERE (SELECT count(*) FROM frames WHERE id = ANY ($3::bigint[]) AND status "
        "= "
        "'complete') = (SELECT count(DISTINCT k) FROM unnest($3::bigint[]) k) ON CONFLICT "
        "(frame_hash, recipe) DO UPDATE SET key_frame_ids = EXCLUDED.key_frame_ids, created_at = "
        "now() RETURNING 1",
        "recording an interpolated frame failed");
  if (PQntuples(r.get()) == 0)
    throw StoreError("recording an interpolated frame: a key of " + array +
                     " is no complete stored frame");
}

std::optional<std::vector<std::int64_t>> interpolatedKeys(PGconn* conn, const SceneTexts& texts,
                                                          const std::string& recipe)
{
  pg::Result r = pg::Params()
                   .bytes(texts.frame)
                   .text(recipe)
                   .exec(conn,
                         "SELECT u.k FROM interpolated_frames f, unnest(f.key_frame_ids) WITH "
                         "ORDINALITY AS u (k, n) "
                         "WHERE f.frame_hash = sha256($1) AND f.recipe = $2 ORDER BY u.n",
                         "looking for the interpolated frame failed");
  if (PQntuples(r.get()) == 0)
    return std::nullopt;
  std::vector<std::int64_t> keys;
  for (int row = 0; row < PQntuples(r.get()); ++row)
    keys.push_back(pg::getI64(r.get(), row, 0));
  return keys;
}

namespace
{
/// The frame's text ($1), its parameters and size ($2 … $9): what narrows the rows to the frames
/// of this view before any text is parsed (kSubsetOfView).
pg::Params viewParams(const SceneTexts& texts, const SceneDescription& scene)
{
  const Vec3& eye = scene.camera.position;
  pg::Params p;
  p.text(texts.frame)
    .f64(scene.spacetime.mass)
    .f64(scene.spacetime.spin)
    .f64(scene.spacetime.charge)
    .f64(eye.x())
    .f64(eye.y())
    .f64(eye.z())
    .i32(scene.camera.width)
    .i32(scene.camera.height);
  return p;
}

/// The complete frames of the view of viewParams whose texts name a subset.
const std::string kSubsetOfView =
  "status = 'complete' AND mass = $2 AND spin = $3 AND charge = $4 AND camera_x = $5 AND "
  "camera_y = $6 AND camera_z = $7 AND width = $8 AND height = $9 AND "
  "strpos(effective_text, '\"subset\"') > 0 AND effective_text::jsonb ? 'subset'";
}

bool subsetFramesExist(PGconn* conn, const SceneTexts& texts, const SceneDescription& scene)
{
  // The texts, less what a subset frame adds (its pixels) and changes (the rendering it traces
  // scattered pixels with), are then the same identity.
  pg::Result r = viewParams(texts, scene)
                   .exec(conn,
                         "SELECT EXISTS (SELECT 1 FROM frames WHERE " + kSubsetOfView +
                           " AND (effective_text::jsonb - 'subset' - 'rendering') = ($1::jsonb - "
                           "'subset' - 'rendering'))",
                         "looking for the frame's pixel subsets failed");
  return PQntuples(r.get()) == 1 && pg::getBool(r.get(), 0, 0);
}

std::vector<std::int64_t> subsetFrameIds(PGconn* conn, const SceneTexts& texts,
                                         const SceneDescription& scene)
{
  // The texts less the pixels alone: the same identity at the same rendering.
  pg::Result r = viewParams(texts, scene)
                   .exec(conn,
                         "SELECT id FROM frames WHERE " + kSubsetOfView +
                           " AND (effective_text::jsonb - 'subset') = ($1::jsonb - 'subset') "
                           "ORDER BY id",
                         "looking for the frame's pixel subsets failed");
  std::vector<std::int64_t> ids;
  for (int row = 0; row < PQntuples(r.get()); ++row)
    ids.push_back(pg::getI64(r.get(), row, 0));
  return ids;
}
}
}
