// Whether a record's centre ray was traced or interpolated by the adaptive grid (schema version 7):
// written and read back by RayStore, decoded by rays_v as the SQL the view holds, selected by
// predicates; and migration 7, from a database of version 6 filled through plain SQL in that
// version's layout (264-byte records, written out here with Version6RecordFields), reading every
// record back traced and every other bit as it was.
#include "RayStore.h"
#include "SceneFile.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

using asrt::RayRecord;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
/// Rays per row of ray_blocks in versions 5 and 6.
constexpr std::size_t Version6Block = 30;

std::string freshDatabase()
{
  return databaseNamed("tr_" + currentTestName());
}

std::string num(double x)
{
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

/// Scene `k`: its resolution tells the frames of a test apart.
asrt::SceneDescription scene(int k)
{
  asrt::SceneDescription d;
  d.name = "traced scene";
  d.camera.width = 40 + k;
  d.camera.height = 30;
  return d;
}

/// Rays [first, first + count) of `seed` for a frame `width` pixels wide; ray k is interpolated
/// when k % 3 == 1, so that both values occur whatever the rest of the record.
std::vector<RayRecord> rays(std::uint64_t seed, std::size_t first, std::size_t count, int width)
{
  std::vector<RayRecord> out;
  for (std::size_t k = first; k < first + count; ++k)
  {
    out.push_back(syntheticRecord(seed, k, width));
    out.back().traced = k % 3 != 1;
  }
  return out;
}

/// The first index at which `got` differs from `expected` in any bit of any field (traced
/// included), or -1.
long firstDifference(const std::vector<RayRecord>& got, const std::vector<RayRecord>& expected)
{
  for (std::size_t k = 0; k < std::min(got.size(), expected.size()); ++k)
    if (recordBits(got[k]) != recordBits(expected[k]) || got[k].traced != expected[k].traced)
      return long(k);
  return got.size() == expected.size() ? -1 : long(std::min(got.size(), expected.size()));
}

/// Stores a frame of `tiles` as version 6's RayStore::writeFrame() and writeTile() did, in one
/// transaction: the scene row, the frame row, for each tile that has rays a table made LIKE
/// ray_block_layout, its rows of 30 packed records of 264 bytes, attached to ray_blocks, and the
/// rows of frame_tiles. Returns the frame's id.
std::int64_t insertVersion6Frame(Db& db, const asrt::SceneDescription& d,
                                 const std::vector<std::vector<RayRecord>>& tiles)
{
  const StoredTexts texts = storedTexts(asrt::effectiveSceneText(d));
  db.value("BEGIN");
  const std::string sceneId = legacyExec(
    db.Conn,
    "INSERT INTO scenes (content_hash, description, description_text) VALUES "
    "(sha256(convert_to($1, 'UTF8')), $1::jsonb, $1) ON CONFLICT (content_hash) DO UPDATE SET "
    "description_text = EXCLUDED.description_text RETURNING id",
    { texts.scene });
  std::size_t count = 0;
  for (const auto& t : tiles)
    count += t.size();
  const std::string id = legacyExec(
    db.Conn,
    "INSERT INTO frames (scene_id, frame_hash, effective_text, name, label, mass, spin, charge, "
    "camera_x, camera_y, camera_z, focal_x, focal_y, focal_z, up_x, up_y, up_z, view_angle, "
    "width, height, method, step, relative_tolerance, absolute_tolerance, tile_count, status, "
    "ray_count, write_seconds, trace_seconds, completed_at) VALUES ($1, sha256(convert_to($2, "
    "'UTF8')), $2, $3, 'v6', $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, "
    "$19, $20, $21, $22, $23, 'complete', $24, 0.5, 2.5, now()) RETURNING id",
    { sceneId,
      texts.frame,
      d.name,
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
      std::to_string(tiles.size()),
      std::to_string(count) });
  for (std::size_t t = 0; t < tiles.size(); ++t)
    insertPartitionedTile(db, id, t, tiles[t], Version6Block, version6PackedRecord);
  db.value("COMMIT");
  return std::stoll(id);
}

std::vector<RayRecord> joined(const std::vector<std::vector<RayRecord>>& tiles)
{
  std::vector<RayRecord> all;
  for (const auto& t : tiles)
    all.insert(all.end(), t.begin(), t.end());
  return all;
}

/// The first ray of frame `id` whose rays_v row differs from `expected`: its number, its
/// record_bytes (`pack` of the record), or, when `withTraced`, its traced column; or -1.
template<class Pack>
long firstViewDifference(Db& db, std::int64_t id, const std::vector<RayRecord>& expected, Pack pack,
                         bool withTraced)
{
  const auto r =
    db.binaryRows(std::string("SELECT ray, record_bytes") + (withTraced ? ", traced" : "") +
                  " FROM rays_v WHERE frame_id = " + std::to_string(id) + " ORDER BY ray");
  if (std::size_t(PQntuples(r.get())) != expected.size())
    return long(PQntuples(r.get()));
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    const RayRecord& e = expected[std::size_t(row)];
    const std::string bytes(PQgetvalue(r.get(), row, 1), std::size_t(PQgetlength(r.get(), row, 1)));
    if (resultWord(r.get(), row, 0) != std::uint64_t(row) || bytes != pack(e) ||
        (withTraced && (resultWord(r.get(), row, 2) != 0) != e.traced))
      return row;
  }
  return -1;
}

/// The records of `records` whose traced flag is `traced`.
std::vector<RayRecord> withTraced(const std::vector<RayRecord>& records, bool traced)
{
  std::vector<RayRecord> out;
  for (const RayRecord& r : records)
    if (r.traced == traced)
      out.push_back(r);
  return out;
}
}

TEST(TracedRecords, TheFlagComesBackThroughReadFrameTheViewAndPredicates)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  // Several rows of kBlockSize, the last one partial, so that the flag's offset in every record
  // of a row counts.
  const std::vector<RayRecord> records = rays(7, 0, 3 * RayStore::kBlockSize + 11, 40);
  ASSERT_FALSE(withTraced(records, true).empty());
  ASSERT_FALSE(withTraced(records, false).empty());
  const std::int64_t id = store.writeFrame(scene(1), "traced", records);

  // The C++ decoder.
  const std::vector<RayRecord> read = store.readFrame(id);
  EXPECT_EQ(firstDifference(read, records), -1);

  // The view's SQL, against the records written and against the C++ decoder alike.
  Db db(ci);
  EXPECT_EQ(firstViewDifference(db, id, records, packedRecord, true), -1);
  const auto r = db.binaryRows(
    "SELECT ray, traced FROM rays_v WHERE frame_id = " + std::to_string(id) + " ORDER BY ray");
  ASSERT_EQ(std::size_t(PQntuples(r.get())), read.size());
  for (int row = 0; row < PQntuples(r.get()); ++row)
    ASSERT_EQ(resultWord(r.get(), row, 1) != 0, read[std::size_t(row)].traced) << "ray " << row;
  EXPECT_EQ(db.value("SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = "
                     "'rays_v'::regclass AND attname = 'traced'"),
            "boolean");
  // The word after dvdj, big-endian: bytes 265 to 268 of the record.
  EXPECT_EQ(db.value("SELECT string_agg(encode(substr(record_bytes, 265, 4), 'hex'), ',' ORDER BY "
                     "ray) FROM rays_v WHERE frame_id = " +
                     std::to_string(id) + " AND ray < 4"),
            "00000001,00000000,00000001,00000001");

  // Predicates name it, on the client's grammar and the server's tokens alike.
  EXPECT_EQ(firstDifference(store.readFrame(id, "NOT traced"), withTraced(records, false)), -1);
  EXPECT_EQ(firstDifference(store.readFrame(id, "traced = true"), withTraced(records, true)), -1);
}

TEST(TracedRecords, Version6FramesMigrateTracedWithEveryOtherBitKept)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(6);
  Db db(ci);
  // Tiles of unequal sizes (one empty, one of a single ray, one of whole rows), and a frame of
  // one tile: the re-packing must keep every row's block, first ray and count.
  const std::vector<std::size_t> sizes = { 2 * Version6Block + 7, 0, 1, Version6Block };
  std::vector<std::vector<RayRecord>> tiles;
  for (std::size_t t = 0, first = 0; t < sizes.size(); first += sizes[t++])
    tiles.push_back(rays(11, first, sizes[t], 41));
  const std::int64_t tiled = insertVersion6Frame(db, scene(1), tiles);
  const std::vector<RayRecord> plain = rays(12, 0, 95, 42);
  const std::int64_t one = insertVersion6Frame(db, scene(2), { plain });
  // The rows are version 6's layout, as its own view decodes them.
  ASSERT_EQ(firstViewDifference(db, tiled, joined(tiles), version6PackedRecord, false), -1);
  ASSERT_EQ(firstViewDifference(db, one, plain, version6PackedRecord, false), -1);
  const std::string blocksBefore =
    db.value("SELECT string_agg(frame_id || ':' || tile || ':' || block || ':' || first_ray || ':' "
             "|| n, ',' ORDER BY frame_id, tile, block) FROM ray_blocks");

  store.migrate();
  ASSERT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  // Every record traced, every other bit as stored.
  EXPECT_EQ(firstDifference(store.readFrame(tiled), tracedRay(joined(tiles))), -1);
  EXPECT_EQ(firstDifference(store.readFrame(one), tracedRay(plain)), -1);
  EXPECT_EQ(firstViewDifference(db, tiled, tracedRay(joined(tiles)), packedRecord, true), -1);
  EXPECT_EQ(firstViewDifference(db, one, tracedRay(plain), packedRecord, true), -1);
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v WHERE NOT traced"), "0");
  EXPECT_EQ(store.frameInfo(tiled).tileCount, 4);
  EXPECT_EQ(store.frameInfo(tiled).rayCount, std::int64_t(joined(tiles).size()));
  EXPECT_EQ(db.value("SELECT string_agg(frame_id || ':' || tile || ':' || block || ':' || "
                     "first_ray || ':' || n, ',' ORDER BY frame_id, tile, block) FROM ray_blocks"),
            blocksBefore);
  // Nothing of the old layout is left, and the predicate function knows the new column.
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_class WHERE relname LIKE 'ray\\_blocks\\_v%' OR "
                     "relname LIKE 'ray\\_block\\_layout\\_v%'"),
            "0");
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_constraint WHERE conname = 'ray_block_records_v7' "
                     "AND conrelid = 'ray_blocks'::regclass"),
            "1");
  EXPECT_EQ(firstDifference(store.readFrame(one, "traced AND ray < 5"),
                            tracedRay(std::vector<RayRecord>(plain.begin(), plain.begin() + 5))),
            -1);
  EXPECT_TRUE(store.readFrame(one, "NOT traced").empty());

  // A frame written after the migration keeps its interpolated records beside the old ones.
  const std::vector<RayRecord> fresh = rays(13, 0, 50, 43);
  const std::int64_t after = store.writeFrame(scene(3), "after", fresh);
  EXPECT_EQ(firstDifference(store.readFrame(after), fresh), -1);
  EXPECT_EQ(firstDifference(store.readFrame(after, "NOT traced"), withTraced(fresh, false)), -1);
}

TEST(TracedRecords, AVersion6TableIsRefusedByTheNewLayout)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  Db db(ci);
  // A table of 264-byte records, as a writer of version 6 would make it, cannot join ray_blocks:
  // the parent's check on the records' length is a constraint it lacks.
  db.value("CREATE TABLE ray_blocks_999_0 (frame_id bigint NOT NULL, tile integer NOT NULL "
           "CONSTRAINT ray_block_tile CHECK (tile >= 0), block integer NOT NULL CONSTRAINT "
           "ray_block_number CHECK (block >= 0), first_ray bigint NOT NULL CONSTRAINT "
           "ray_block_first_ray CHECK (first_ray = 30::bigint * block), n integer NOT NULL "
           "CONSTRAINT ray_block_rays CHECK (n BETWEEN 1 AND 30), data bytea NOT NULL CONSTRAINT "
           "ray_block_records_v5 CHECK (length(data) = 264 * n))");
  EXPECT_NE(errorOf(
              [&]
              {
                db.value("ALTER TABLE ray_blocks ATTACH PARTITION ray_blocks_999_0 FOR VALUES "
                         "FROM (999, 0) TO (999, 1)");
              })
              .find("constraint \"ray_block_records_v7\""),
            std::string::npos);
  // Nor does a record of 264 bytes fit a table made as writes make theirs.
  db.value("CREATE TABLE ray_blocks_998_0 (LIKE ray_block_layout INCLUDING ALL)");
  EXPECT_NE(errorOf(
              [&]
              {
                legacyExec(db.Conn,
                           "INSERT INTO ray_blocks_998_0 (frame_id, tile, block, first_ray, n, "
                           "data) VALUES (998, 0, 0, 0, 1, $1)",
                           { std::string(264, '\0') }, { true });
              })
              .find("ray_block_records_v7"),
            std::string::npos);
}
