// Migration 5 (anti-aliasing): databases of schema version 4, made by migrate(4) (the frozen SQL
// of StoreSchemaHistory.cxx) and filled as version 4's writers filled them (insertVersion4Frame,
// written out here: a table of 260-byte records per tile attached to ray_blocks, texts without a
// rendering section), then migrated. Every ray must come back with every other field bit for bit
// and raysPerPixel = 1, every frame must be found by its description with singleRayRendering(),
// and a migration that fails or is interrupted must leave version 4 as it was.
#include "RayStore.h"
#include "SceneFile.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <utility>
#include <vector>

using asrt::RayPath;
using asrt::RayRecord;
using asrt::RayStore;
using asrt::SceneDescription;
using namespace asrt::testing;

namespace
{
/// Rays per row of ray_blocks in versions 3 and 4.
constexpr std::size_t Version4Block = 31;

std::string freshDatabase()
{
  return databaseNamed("rm_" + currentTestName());
}

std::string num(double x)
{
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

/// The scene of Fig. 1 at `width` × `height` and mass `mass`, with a description that a careless
/// rewrite of its text would change (non-ASCII, quotes, a backslash, a tab).
SceneDescription scene(int width, int height, double mass = 1.0)
{
  std::ifstream in(std::string(ASRT_SOURCE_DIR) + "/Data/scenes/fig1-cylinders.json");
  nlohmann::json j = nlohmann::json::parse(std::string(std::istreambuf_iterator<char>(in), {}));
  j["description"] = "légende ✓ \"quoted\" \\ and\ta tab";
  SceneDescription d = asrt::parseSceneWithoutImages(j.dump());
  d.camera.width = width;
  d.camera.height = height;
  d.spacetime.mass = mass;
  // The frames these scenes stand for were stored before anti-aliasing: one ray a pixel.
  d.rendering = asrt::singleRayRendering();
  return d;
}

/// The rays of a frame `width` pixels wide, [first, first + count) of `seed`.
std::vector<RayRecord> rays(std::uint64_t seed, std::size_t first, std::size_t count, int width)
{
  std::vector<RayRecord> out;
  for (std::size_t k = first; k < first + count; ++k)
    out.push_back(syntheticRecord(seed, k, width));
  return out;
}

std::vector<RayRecord> joined(const std::vector<std::vector<RayRecord>>& tiles)
{
  std::vector<RayRecord> all;
  for (const auto& t : tiles)
    all.insert(all.end(), t.begin(), t.end());
  return all;
}

/// A frame as version 4's writer stored it.
struct Version4Frame
{
  Version4Frame(SceneDescription s, std::vector<std::vector<RayRecord>> t)
    : scene(std::move(s))
    , tiles(std::move(t))
  {
  }
  SceneDescription scene;
  std::vector<std::vector<RayRecord>> tiles;
  std::string label = "v4";
  std::string status = "complete";
  /// Its effective text: legacyTexts(scene) unless given (a frame stored with a rendering
  /// section, as version 4 did once effectiveSceneText() wrote one).
  std::string text;
  std::vector<RayPath> paths;
};

/// Stores `f` as version 4's RayStore::writeFrame() and writeTile() did, in one transaction: the
/// scene row, the frame row, for each tile that has rays a table of its own made LIKE
/// ray_block_layout, its rows of 31 packed records of 260 bytes, attached to ray_blocks, the rows
/// of frame_tiles of the tiles written, the paths. Returns the frame's id.
std::int64_t insertVersion4Frame(Db& db, const Version4Frame& f)
{
  const StoredTexts texts = f.text.empty() ? legacyTexts(f.scene) : storedTexts(f.text);
  const SceneDescription& d = f.scene;
  db.value("BEGIN");
  const std::string sceneId = legacyExec(
    db.Conn,
    "INSERT INTO scenes (content_hash, description, description_text) VALUES "
    "(sha256(convert_to($1, 'UTF8')), $1::jsonb, $1) ON CONFLICT (content_hash) DO UPDATE SET "
    "description_text = EXCLUDED.description_text RETURNING id",
    { texts.scene });
  std::size_t count = 0;
  for (const auto& t : f.tiles)
    count += t.size();
  const bool complete = f.status == "complete";
  const std::vector<std::string> values = {
    sceneId,
    texts.frame,
    d.name,
    f.label,
    num(d.spacetime.mass),
    num(d.spacetime.spin),
    num(d.spacetime.charge),
    num(d.camera.position.x()),
    num(d.camera.position.y()),
    num(d.camera.position.z()),
    num(d.camera.focalPoint.x()),
    num(d.camera.focalPoint.y()),
    num(d.camera.focalPoint.z()),
    num(d.camera.viewUp.x()),
    num(d.camera.viewUp.y()),
    num(d.camera.viewUp.z()),
    num(d.camera.viewAngle),
    std::to_string(d.camera.width),
    std::to_string(d.camera.height),
    d.integrator.method,
    num(d.integrator.step),
    num(d.integrator.relativeTolerance),
    num(d.integrator.absoluteTolerance),
    std::to_string(f.tiles.size()),
    f.status,
    std::to_string(complete ? count : 0),
  };
  const std::string id = legacyExec(
    db.Conn,
    "INSERT INTO frames (scene_id, frame_hash, effective_text, name, label, mass, spin, charge, "
    "camera_x, camera_y, camera_z, focal_x, focal_y, focal_z, up_x, up_y, up_z, view_angle, "
    "width, height, method, step, relative_tolerance, absolute_tolerance, tile_count, status, "
    "ray_count, write_seconds, trace_seconds, completed_at) VALUES ($1, sha256(convert_to($2, "
    "'UTF8')), $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, "
    "$20, $21, $22, $23, $24, $25, $26, 0.5, 2.5, CASE WHEN $25 = 'complete' THEN now() END) "
    "RETURNING id",
    values);
  for (std::size_t t = 0; t < f.tiles.size(); ++t)
  {
    const std::vector<RayRecord>& tile = f.tiles[t];
    // A tiled frame being written has some of its tiles: here the first one.
    if (!complete && t > 0)
      break;
    insertPartitionedTile(db, id, t, tile, Version4Block, legacyPackedRecord);
  }
  for (std::size_t seq = 0; seq < f.paths.size(); ++seq)
  {
    const RayPath& p = f.paths[seq];
    std::string points;
    for (const asrt::PathPoint& q : p.points)
      for (const double v : { q.x.x(), q.x.y(), q.x.z(), q.lambda, q.r, q.absH })
        for (int m = 7; m >= 0; --m)
          points.push_back(char(bitsOf(v) >> (8 * m)));
    legacyExec(db.Conn,
               "INSERT INTO ray_paths (frame_id, i, j, seq, termination, n, points) VALUES ($1, "
               "$2, $3, $4, $5, $6, $7)",
               { id, std::to_string(p.i), std::to_string(p.j), std::to_string(seq),
                 std::to_string(int(p.termination)), std::to_string(p.points.size()), points },
               { false, false, false, false, false, false, true });
  }
  db.value("COMMIT");
  return std::stoll(id);
}

/// A path of a few points with values that careless storage loses.
RayPath pathOf(int i, int j)
{
  RayPath p;
  p.i = i;
  p.j = j;
  p.termination = asrt::Termination::HitObject;
  for (int k = 0; k < 5; ++k)
    p.points.push_back(
      { asrt::Vec3(k, -0.0, 1e-310 * k), 0.25 * k, fromBits(0x7FF8DEADBEEF0001ull), 1e-15 * k });
  return p;
}

bool samePaths(const std::vector<RayPath>& a, const std::vector<RayPath>& b)
{
  if (a.size() != b.size())
    return false;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    if (a[k].i != b[k].i || a[k].j != b[k].j || a[k].termination != b[k].termination ||
        a[k].points.size() != b[k].points.size())
      return false;
    for (std::size_t m = 0; m < a[k].points.size(); ++m)
    {
      const asrt::PathPoint &p = a[k].points[m], &q = b[k].points[m];
      for (const auto& [x, y] :
           { std::pair(p.x.x(), q.x.x()), std::pair(p.x.y(), q.x.y()), std::pair(p.x.z(), q.x.z()),
             std::pair(p.lambda, q.lambda), std::pair(p.r, q.r), std::pair(p.absH, q.absH) })
        if (bitsOf(x) != bitsOf(y))
          return false;
    }
  }
  return true;
}

/// The first index at which `got` differs from `expected` in any bit of any field, or -1.
long firstDifference(const std::vector<RayRecord>& got, const std::vector<RayRecord>& expected)
{
  for (std::size_t k = 0; k < std::min(got.size(), expected.size()); ++k)
    if (recordBits(got[k]) != recordBits(expected[k]))
      return long(k);
  return got.size() == expected.size() ? -1 : long(std::min(got.size(), expected.size()));
}

/// The first ray of frame `id` in rays_v whose record_bytes are not `pack` of `expected`, or whose
/// rays_per_pixel is not its raysPerPixel (with `pack` the current record), or -1.
template<class Pack>
long firstViewDifference(Db& db, std::int64_t id, const std::vector<RayRecord>& expected, Pack pack,
                         bool current)
{
  const auto r =
    db.binaryRows(std::string("SELECT ray, record_bytes") + (current ? ", rays_per_pixel" : "") +
                  " FROM rays_v WHERE frame_id = " + std::to_string(id) + " ORDER BY ray");
  if (std::size_t(PQntuples(r.get())) != expected.size())
    return long(PQntuples(r.get()));
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    const RayRecord& e = expected[std::size_t(row)];
    const std::string bytes(PQgetvalue(r.get(), row, 1), std::size_t(PQgetlength(r.get(), row, 1)));
    if (resultWord(r.get(), row, 0) != std::uint64_t(row) || bytes != pack(e) ||
        (current && std::int32_t(resultWord(r.get(), row, 2)) != e.raysPerPixel))
      return row;
  }
  return -1;
}

long firstCurrentViewDifference(Db& db, std::int64_t id, const std::vector<RayRecord>& expected)
{
  return firstViewDifference(db, id, expected, packedRecord, true);
}

long firstVersion4ViewDifference(Db& db, std::int64_t id, const std::vector<RayRecord>& expected)
{
  return firstViewDifference(db, id, expected, legacyPackedRecord, false);
}

/// SHA-256 (hex) of `text`, by the server.
std::string sha256Of(Db& db, const std::string& text)
{
  return legacyExec(db.Conn, "SELECT encode(sha256(convert_to($1, 'UTF8')), 'hex')", { text });
}

/// What identifies frames and scenes: every frame's id, label, text and hash, and every scene's.
std::string identities(Db& db)
{
  return db.value("SELECT string_agg(id || '|' || scene_id || '|' || label || '|' || "
                  "effective_text || '|' || encode(frame_hash, 'hex'), E'\\n' ORDER BY id) FROM "
                  "frames") +
         db.value("SELECT string_agg(id || '|' || description_text || '|' || description::text "
                  "|| '|' || encode(content_hash, 'hex'), E'\\n' ORDER BY id) FROM scenes");
}

/// Everything of version 4 that a failed migration must leave as it was: the version, the tables
/// of the store and their constraints, the identities, and every ray as rays_v shows it.
std::string version4State(Db& db)
{
  return db.value("SELECT max(version) FROM schema_version") + "\n" +
         db.value(
           "SELECT string_agg(c.relname || ':' || c.relkind::text, ',' ORDER BY c.relname) FROM "
           "pg_class c WHERE c.relnamespace = 'public'::regnamespace AND c.relkind IN "
           "('r', 'p', 'v')") +
         "\n" +
         db.value("SELECT string_agg(conrelid::regclass::text || ':' || conname || ':' || "
                  "pg_get_constraintdef(oid), ',' ORDER BY conrelid::regclass::text, conname) "
                  "FROM pg_constraint WHERE connamespace = 'public'::regnamespace") +
         "\n" + identities(db) + "\n" +
         db.value("SELECT md5(string_agg(frame_id || ':' || ray || ':' || encode(record_bytes, "
                  "'hex'), ',' ORDER BY frame_id, ray)) FROM rays_v");
}

/// How a tile's table is made (its constraints, indexes, options, storage, partition bound), the
/// frame's id in its names and values replaced by "F", for comparing the tables of two frames.
std::string tileTableShape(Db& db, std::int64_t frame, int tile)
{
  const std::string table = "ray_blocks_" + std::to_string(frame) + "_" + std::to_string(tile);
  const std::string oid = "'" + table + "'::regclass";
  std::string shape =
    db.value("SELECT string_agg(conname || ':' || pg_get_constraintdef(oid), ',' ORDER BY "
             "conname) FROM pg_constraint WHERE conrelid = " +
             oid) +
    "\n" +
    db.value("SELECT string_agg(indexrelid::regclass::text || ':' || pg_get_indexdef(indexrelid), "
             "',') FROM pg_index WHERE indrelid = " +
             oid) +
    "\n" +
    db.value("SELECT coalesce(array_to_string(reloptions, ','), '') || ':' || relispartition || "
             "':' || pg_get_expr(relpartbound, oid) FROM pg_class WHERE oid = " +
             oid) +
    "\n" +
    db.value(
      "SELECT string_agg(attname || ':' || attstorage::text || ':' || attnotnull, ',' ORDER BY "
      "attnum) FROM pg_attribute WHERE attnum > 0 AND attrelid = " +
      oid);
  const std::string id = std::to_string(frame);
  const std::pair<std::string, std::string> names[] = { { "ray_blocks_" + id + "_",
                                                          "ray_blocks_F_" },
                                                        { "frame_id = " + id, "frame_id = F" },
                                                        { "('" + id + "'", "('F'" } };
  for (const auto& [from, to] : names)
    for (std::size_t at = shape.find(from); at != std::string::npos; at = shape.find(from, at))
      shape.replace(at, from.size(), to);
  return shape;
}
}

TEST(RenderingMigration, FrozenSectionIsWhatEffectiveSceneTextWritesForOneRayAPixel)
{
  SceneDescription d = scene(20, 10);
  d.rendering = asrt::singleRayRendering();
  const std::string text = asrt::effectiveSceneText(d);
  EXPECT_NE(text.find(SingleRaySection + ",\"spacetime\":"), std::string::npos) << text;
  // Any other rendering is another text: the section names the frame.
  d.rendering.mode = asrt::AntialiasMode::Filter;
  EXPECT_EQ(asrt::effectiveSceneText(d).find(SingleRaySection), std::string::npos);
}

TEST(RenderingMigration, Version4FramesKeepTheirRaysAndGetTheRenderingTheyWereTracedWith)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(4);
  Db db(ci);
  // A frame of three tiles (the middle one empty) with a path; a frame of a pixel subset; a tiled
  // frame still being written (its first tile written); a frame stored by version 4 with the
  // rendering section already (anti-aliasing "filter"); and a frame of the first one's scene at
  // another mass stored with the section of one ray a pixel, whose scene row is then the one the
  // first frame's scene text becomes.
  const SceneDescription sa = scene(40, 30);
  Version4Frame a{ sa, { rays(1, 0, 500, 40), {}, rays(1, 500, 700, 40) } };
  a.label = "three tiles ✓";
  a.paths = { pathOf(3, 4), pathOf(39, 29) };
  SceneDescription sb = scene(40, 30);
  sb.subset = asrt::pixelSubsetId({ { 1, 2 }, { 3, 4 }, { 5, 6 } });
  const Version4Frame b{ sb, { rays(2, 0, 3, 40) } };
  const SceneDescription sc = scene(41, 30);
  Version4Frame c{ sc, { rays(3, 0, 600, 41), rays(3, 600, 630, 41) } };
  c.status = "writing";
  SceneDescription sd = scene(42, 30);
  sd.rendering.mode = asrt::AntialiasMode::Filter;
  Version4Frame d{ sd, { rays(4, 0, 100, 42) } };
  d.text = textBeforeGrid(asrt::effectiveSceneText(sd));
  const SceneDescription se = scene(40, 30, 1.5);
  Version4Frame e{ se, { rays(5, 0, 50, 40) } };
  e.text = textBeforeGrid(asrt::effectiveSceneText(se));
  // A tiled frame whose second tile a writer of version 4 was loading when the migration came:
  // its table, made LIKE the old layout, is not attached yet.
  Version4Frame g{ scene(43, 30), { rays(7, 0, 40, 43), rays(7, 40, 40, 43) } };
  g.status = "writing";
  const std::int64_t ida = insertVersion4Frame(db, a), idb = insertVersion4Frame(db, b),
                     idc = insertVersion4Frame(db, c), idd = insertVersion4Frame(db, d),
                     ide = insertVersion4Frame(db, e), idg = insertVersion4Frame(db, g);
  const std::string late = "ray_blocks_" + std::to_string(idg) + "_1";
  db.value("CREATE TABLE " + late +
           " (LIKE ray_block_layout INCLUDING ALL, PRIMARY KEY (block), CHECK (frame_id = " +
           std::to_string(idg) + " AND tile = 1))");
  legacyExec(db.Conn,
             "INSERT INTO " + late +
               " (frame_id, tile, block, first_ray, n, data) VALUES ($1, 1, "
               "0, 0, 1, $2)",
             { std::to_string(idg), legacyPackedRecord(g.tiles[1][0]) }, { false, true });
  ASSERT_EQ(firstVersion4ViewDifference(db, ida, joined(a.tiles)), -1);
  ASSERT_EQ(db.value("SELECT count(*) FROM scenes"), "4");

  store.migrate();
  ASSERT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  // The rays: every field as stored, and one ray a pixel.
  using Checked = std::pair<std::int64_t, const Version4Frame*>;
  for (const auto& [id, f] :
       { Checked(ida, &a), Checked(idb, &b), Checked(idd, &d), Checked(ide, &e) })
  {
    const std::vector<RayRecord> expected = singleRay(joined(f->tiles));
    EXPECT_EQ(firstDifference(store.readFrame(id), expected), -1) << "frame " << id;
    EXPECT_EQ(firstCurrentViewDifference(db, id, expected), -1) << "frame " << id;
    EXPECT_EQ(store.frameInfo(id).label, f->label);
    EXPECT_EQ(store.frameInfo(id).tileCount, int(f->tiles.size()));
  }
  EXPECT_TRUE(samePaths(store.readPaths(ida), a.paths));
  EXPECT_EQ(db.value("SELECT min(ray) || '-' || max(ray) FROM rays_v WHERE frame_id = " +
                     std::to_string(ida) + " AND tile = 2"),
            "500-1199");
  EXPECT_EQ(firstDifference(store.readFrame(ida, "rays_per_pixel = 1 AND ray BETWEEN 499 AND 501"),
                            singleRay(rays(1, 499, 3, 40))),
            -1);

  // The texts: what effectiveSceneText() writes for the same descriptions with one ray a pixel,
  // so that the frames are found by them, their hashes follow, and a frame already stored with a
  // section keeps its text.
  for (const auto& [id, s] :
       { std::pair(ida, sa), std::pair(idb, sb), std::pair(idd, sd), std::pair(ide, se) })
  {
    const SceneDescription& lookup = s;
    const std::string text = asrt::effectiveSceneText(lookup);
    EXPECT_EQ(store.frameSceneText(id), text) << "frame " << id;
    EXPECT_EQ(store.findFrame(lookup), id) << "frame " << id;
    EXPECT_EQ(store.frameInfo(id).frameHash, sha256Of(db, text)) << "frame " << id;
    EXPECT_NE(errorOf([&] { store.checkFrameIdentity(lookup, false); }).find("duplicate frame"),
              std::string::npos);
  }
  SceneDescription sa1 = sa;
  sa1.rendering = asrt::singleRayRendering();
  EXPECT_EQ(store.findFrame(sa1), ida);
  EXPECT_NE(store.frameSceneText(ida).find(SingleRaySection), std::string::npos);
  // The same description anti-aliased is another frame.
  sa1.rendering.mode = asrt::AntialiasMode::Adaptive;
  EXPECT_FALSE(store.findFrame(sa1).has_value());
  EXPECT_NE(errorOf([&] { store.writeFrame(sa, "again", joined(a.tiles)); }).find("duplicate"),
            std::string::npos);

  // The scenes: the first frame's scene row became that of the frame stored with the section (one
  // row of one scene), and a new frame of the scene shares it, as frames of one scene do.
  EXPECT_EQ(store.frameInfo(ida).sceneId, store.frameInfo(ide).sceneId);
  EXPECT_EQ(db.value("SELECT count(*) FROM scenes"), "3");
  EXPECT_EQ(store.frameInfo(ida).sceneHash,
            sha256Of(db, storedTexts(store.frameSceneText(ida)).scene));
  const std::int64_t heavier = store.writeFrame(scene(40, 30, 2.0), "new", rays(6, 0, 10, 40));
  EXPECT_EQ(store.frameInfo(heavier).sceneId, store.frameInfo(ida).sceneId);
  EXPECT_EQ(db.value("SELECT count(*) FROM scenes WHERE description <> description_text::jsonb "
                     "OR content_hash <> sha256(convert_to(description_text, 'UTF8'))"),
            "0");

  // The tiled frame being written is found by its ranks again: its last tile completes it.
  EXPECT_EQ(store.beginTiledFrame(sc, "rank 1", 2), idc);
  store.writeTile(idc, 1, c.tiles[1]);
  EXPECT_EQ(firstDifference(store.readFrame(idc), joined({ singleRay(c.tiles[0]), c.tiles[1] })),
            -1);

  // The tables of rays are made as a new frame's are, and take only records of the new layout:
  // a table of version 4's is refused by ray_blocks, and 260-byte records by the new tables.
  EXPECT_EQ(tileTableShape(db, ida, 0), tileTableShape(db, heavier, 0));
  EXPECT_EQ(tileTableShape(db, idc, 0), tileTableShape(db, heavier, 0));
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_class WHERE relname ~ '_v[0-9]'"), "0");
  EXPECT_NE(errorOf(
              [&]
              {
                db.value("ALTER TABLE ray_blocks ATTACH PARTITION " + late + " FOR VALUES FROM (" +
                         std::to_string(idg) + ", 1) TO (" + std::to_string(idg) + ", 2)");
              })
              .find("constraint \"ray_block_"),
            std::string::npos);
  EXPECT_NE(errorOf(
              [&]
              {
                legacyExec(db.Conn,
                           "INSERT INTO ray_blocks_" + std::to_string(heavier) +
                             "_0 (frame_id, tile, block, first_ray, n, data) VALUES ($1, 0, 7, "
                             "210, 1, $2)",
                           { std::to_string(heavier), legacyPackedRecord(RayRecord()) },
                           { false, true });
              })
              .find("ray_block_records_v"),
            std::string::npos);
  store.migrate();
  EXPECT_EQ(store.listFrames().size(), 6u);
}

TEST(RenderingMigration, AFrameStoredTwiceIsRefusedLeavingVersion4AsItWas)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(4);
  Db db(ci);
  // The same frame stored before anti-aliasing and again, by version 4, with the section of one
  // ray a pixel: after the migration they would be one identity.
  const SceneDescription s = scene(30, 20);
  const Version4Frame old{ s, { rays(1, 0, 600, 30) } };
  Version4Frame again{ s, { rays(2, 0, 600, 30) } };
  again.label = "again";
  again.text = textBeforeGrid(asrt::effectiveSceneText(s));
  const std::int64_t ido = insertVersion4Frame(db, old), ida = insertVersion4Frame(db, again);
  const std::string before = version4State(db);

  const std::string error = errorOf([&] { store.migrate(); });
  EXPECT_NE(error.find("migration to schema version 5 failed: frame " + std::to_string(ido)),
            std::string::npos)
    << error;
  EXPECT_NE(error.find("DELETE FROM frames WHERE id = " + std::to_string(ida)), std::string::npos)
    << error;
  EXPECT_EQ(version4State(db), before);
  EXPECT_EQ(firstVersion4ViewDifference(db, ido, old.tiles[0]), -1);

  // The user keeps one of them; the migration then goes through.
  db.value("DELETE FROM frames WHERE id = " + std::to_string(ida));
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(store.findFrame(s), ido);
  EXPECT_EQ(firstDifference(store.readFrame(ido), singleRay(old.tiles[0])), -1);
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_inherits WHERE inhparent = 'ray_blocks'::regclass"),
            "1");
}

TEST(RenderingMigration, AnInterruptedMigrationLeavesVersion4AsItWas)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(4);
  Db db(ci);
  const Version4Frame first{ scene(30, 20), { rays(1, 0, 600, 30), rays(1, 600, 300, 30) } };
  const Version4Frame second{ scene(31, 20), { rays(2, 0, 620, 31) } };
  const std::int64_t id1 = insertVersion4Frame(db, first), id2 = insertVersion4Frame(db, second);
  const std::string before = version4State(db);

  // A reader of the second frame's table holds the migration up once it has re-packed the first
  // frame's tiles (it waits to drop that table), and the migrating backend is then terminated.
  Db reader(ci);
  reader.value("BEGIN");
  reader.value("LOCK TABLE ray_blocks_" + std::to_string(id2) + "_0 IN ACCESS SHARE MODE");
  std::string error;
  std::thread migrator([&] { error = errorOf([&] { store.migrate(); }); });
  const std::string waiting = pollUntil(
    db,
    "SELECT coalesce(max(pid), 0) FROM pg_stat_activity WHERE wait_event_type = 'Lock' AND query "
    "LIKE '%DROP TABLE ray_blocks_" +
      std::to_string(id2) + "_0%'",
    [](const std::string& v) { return v != "0"; }, 30);
  ASSERT_NE(waiting, "0") << "the migration never reached the second frame";
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_class WHERE relname = 'ray_blocks_v5_" +
                     std::to_string(id2) + "_0'"),
            "0")
    << "not visible outside the migration's transaction";
  EXPECT_EQ(db.value("SELECT pg_terminate_backend(" + waiting + ")"), "t");
  migrator.join();
  reader.value("ROLLBACK");
  EXPECT_NE(error, "(no error)");
  EXPECT_EQ(version4State(db), before);
  EXPECT_EQ(firstVersion4ViewDifference(db, id1, joined(first.tiles)), -1);

  // Run again, uninterrupted, it goes through.
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(firstDifference(store.readFrame(id1), singleRay(joined(first.tiles))), -1);
  EXPECT_EQ(firstDifference(store.readFrame(id2), singleRay(second.tiles[0])), -1);
  EXPECT_EQ(store.findFrame(first.scene), id1);
  EXPECT_EQ(store.findFrame(second.scene), id2);
}

// Not a timed test: the time is printed, for the record of what a migration costs.
TEST(RenderingMigration, AFrameOf200By200Migrates)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(4);
  Db db(ci);
  const Version4Frame f{ scene(200, 200), { rays(9, 0, 200 * 200, 200) } };
  const std::int64_t id = insertVersion4Frame(db, f);
  const auto t0 = Clock::now();
  store.migrate();
  const double seconds = secondsSince(t0);
  EXPECT_EQ(firstDifference(store.readFrame(id), singleRay(f.tiles[0])), -1);
  EXPECT_EQ(db.value("SELECT count(*) || ':' || max(n) FROM ray_blocks"),
            std::to_string((200 * 200 + 29) / 30) + ":30");
  SceneDescription lookup = f.scene;
  lookup.rendering = asrt::singleRayRendering();
  EXPECT_EQ(store.findFrame(lookup), id);
  std::printf("[ migration 5 ] a version 4 database with one 200x200 frame (40000 rays) migrated "
              "in %.3f s\n",
              seconds);
}

TEST(RenderingMigration, Version6TextsNameTheLatticeTheirFramesWereTracedWith)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(4);
  Db db(ci);
  const SceneDescription s = scene(30, 20);
  const Version4Frame old{ s, { rays(1, 0, 600, 30) } };
  const std::int64_t id = insertVersion4Frame(db, old);
  store.migrate(6);
  // Versions 5 and 6 wrote no lattice: every frame traced every pixel.
  const std::string before =
    db.value("SELECT effective_text FROM frames WHERE id = " + std::to_string(id));
  EXPECT_NE(before.find(SingleRaySectionV5), std::string::npos) << before;

  store.migrate();
  ASSERT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  // The text now says so, and the frame is found by its description, which names lattice 1...
  const std::string text = asrt::effectiveSceneText(s);
  EXPECT_NE(text.find(SingleRaySection), std::string::npos) << text;
  EXPECT_EQ(store.frameSceneText(id), text);
  EXPECT_EQ(store.frameInfo(id).frameHash, sha256Of(db, text));
  EXPECT_EQ(store.findFrame(s), id);
  EXPECT_EQ(firstDifference(store.readFrame(id), singleRay(old.tiles[0])), -1);
  // ...and not by the same view on the default grid, which it was not traced with.
  SceneDescription onGrid = s;
  onGrid.rendering.gridLattice = asrt::AntialiasOptions().gridLattice;
  ASSERT_GT(onGrid.rendering.gridLattice, 1);
  EXPECT_FALSE(store.findFrame(onGrid).has_value());
  // The scene row followed: the frame's scene text parses back to lattice 1.
  const std::string sceneText = db.value(
    "SELECT s.description_text FROM scenes s JOIN frames f ON f.scene_id = s.id WHERE f.id = " +
    std::to_string(id));
  EXPECT_NE(sceneText.find("\"gridLattice\":1"), std::string::npos) << sceneText;
}
