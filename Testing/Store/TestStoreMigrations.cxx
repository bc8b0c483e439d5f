// Migrations from the frozen schemas of versions 1 and 2: databases built by migrate(1) and
// migrate(2) (the frozen DDL of StoreSchemaHistory.cxx), filled through plain SQL in that
// version's layout (insertLegacyFrame: one bytea column per field), then migrated to the current
// version by RayStore (version 4's layout: TestRenderingMigration.cxx). Every field of every ray
// must come back bit for bit, through readFrame() and through rays_v's record_bytes, and each
// version's tables and views must keep the columns they had.
#include "RayStore.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

using asrt::RayRecord;
using asrt::RayStore;
using asrt::Termination;
using asrt::testing::ThrowawayPostgres;
using namespace asrt::testing;

namespace
{
/// Doubles that careless storage loses, cycled through every field: NaN payloads (quiet and
/// signalling, both signs), ±0, denormals, extremes, infinities, and an ordinary value.
const std::uint64_t SpecialDoubles[] = {
  0x7FF8DEADBEEF0001ull, 0xFFF0000000000001ull, 0x7FF4000000000123ull, 0x8000000000000000ull,
  0x0000000000000000ull, 0x0000000000000001ull, 0x800FFFFFFFFFFFFFull, 0x7FEFFFFFFFFFFFFFull,
  0xFFF0000000000000ull, 0x7FF0000000000000ull, 0x3FF0000000000001ull,
};
constexpr std::size_t SpecialCount = sizeof SpecialDoubles / sizeof SpecialDoubles[0];
const std::int32_t SpecialInts[] = { std::numeric_limits<std::int32_t>::min(), -1, 0, 1,
                                     std::numeric_limits<std::int32_t>::max() };

/// Record k of a frame: field f holds SpecialDoubles[(k + f) % SpecialCount] (doubles) or a value
/// made of k and f (integers), so that every double field sees every special value and no two
/// records or fields are alike; raysPerPixel is 1, all that versions 1 to 4 could store (the
/// migrated records have it).
RayRecord knownRecord(std::size_t k)
{
  std::size_t f = 0;
  auto integer = [&]
  {
    const std::int32_t v = std::int32_t(k * 37 + f++);
    return k % 7 == 0 ? SpecialInts[(k / 7) % 5] : v;
  };
  RayRecord r;
  r.i = integer();
  r.j = integer();
  r.termination = Termination((k + f++) % 6);
  r.objectId = integer();
  r.imageOrder = integer();
  r.steps = k % 5 == 0 ? std::numeric_limits<std::int64_t>::min() + std::int64_t(k)
                       : std::int64_t(k) * 1000003 - (std::int64_t(1) << 40);
  double* const reals[] = { &r.origin.x(),
                            &r.origin.y(),
                            &r.origin.z(),
                            &r.direction.x(),
                            &r.direction.y(),
                            &r.direction.z(),
                            &r.momentum[0],
                            &r.momentum[1],
                            &r.momentum[2],
                            &r.momentum[3],
                            &r.hitPoint.x(),
                            &r.hitPoint.y(),
                            &r.hitPoint.z(),
                            &r.hitNormal.x(),
                            &r.hitNormal.y(),
                            &r.hitNormal.z(),
                            &r.u,
                            &r.v,
                            &r.chordError,
                            &r.affineLength,
                            &r.winding,
                            &r.maxAbsH,
                            &r.color.x(),
                            &r.color.y(),
                            &r.color.z(),
                            &r.dudi,
                            &r.dudj,
                            &r.dvdi,
                            &r.dvdj };
  for (double* x : reals)
    *x = fromBits(SpecialDoubles[(k + f++) % SpecialCount]);
  return r;
}

std::vector<RayRecord> knownRecords(std::size_t first, std::size_t count)
{
  std::vector<RayRecord> out;
  for (std::size_t k = 0; k < count; ++k)
    out.push_back(knownRecord(first + k));
  return out;
}

/// Scene `k`: its resolution tells the frames of a test apart (a frame's identity).
asrt::SceneDescription scene(int k)
{
  asrt::SceneDescription d;
  d.name = "migrated scene";
  d.camera.width = 96 + k;
  d.camera.height = 61;
  return d;
}

/// The first index at which `got` differs from `expected` in any bit of any field, or -1.
long firstDifference(const std::vector<RayRecord>& got, const std::vector<RayRecord>& expected)
{
  for (std::size_t k = 0; k < std::min(got.size(), expected.size()); ++k)
    if (recordBits(got[k]) != recordBits(expected[k]))
      return long(k);
  return got.size() == expected.size() ? -1 : long(std::min(got.size(), expected.size()));
}

/// The first ray of frame `id` whose record_bytes in rays_v differ from `expected`, or -1.
long firstViewDifference(Db& db, std::int64_t id, const std::vector<RayRecord>& expected)
{
  const auto r =
    db.binaryRows("SELECT ray, record_bytes FROM rays_v WHERE frame_id = " + std::to_string(id) +
                  " ORDER BY ray");
  if (std::size_t(PQntuples(r.get())) != expected.size())
    return long(PQntuples(r.get()));
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    const std::string bytes(PQgetvalue(r.get(), row, 1), std::size_t(PQgetlength(r.get(), row, 1)));
    if (resultWord(r.get(), row, 0) != std::uint64_t(row) ||
        bytes != packedRecord(expected[std::size_t(row)]))
      return row;
  }
  return -1;
}

/// The fields of a ray, comma-separated, in their stored order.
template<class Fields>
std::string fieldNames(const Fields& fields)
{
  std::string s;
  for (const RecordField& f : fields)
    s += std::string(s.empty() ? "" : ",") + f.name;
  return s;
}

/// The columns of table or view `relation`, comma-separated, in order.
std::string columnsOf(Db& db, const std::string& relation)
{
  return db.value("SELECT string_agg(attname, ',' ORDER BY attnum) FROM pg_attribute WHERE "
                  "attrelid = '" +
                  relation + "'::regclass AND attnum > 0 AND NOT attisdropped");
}

/// Every frame comes back from the migrated database bit for bit, by readFrame() and by rays_v,
/// with its ray count and one tile per tile written.
void expectFramesIntact(RayStore& store, Db& db,
                        const std::vector<std::pair<std::int64_t, std::vector<RayRecord>>>& frames,
                        const std::vector<int>& tileCounts)
{
  ASSERT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  ASSERT_EQ(store.listFrames().size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    const auto& [id, expected] = frames[k];
    EXPECT_EQ(firstDifference(store.readFrame(id), expected), -1) << "frame " << id;
    EXPECT_EQ(firstViewDifference(db, id, expected), -1) << "frame " << id;
    const asrt::FrameInfo info = store.frameInfo(id);
    EXPECT_EQ(info.rayCount, std::int64_t(expected.size())) << "frame " << id;
    EXPECT_EQ(info.tileCount, tileCounts[k]) << "frame " << id;
  }
}
}

TEST(StoreMigrations, FrozenLayoutsKeepTheirColumns)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  Db db(ci);
  const std::string fields = fieldNames(LegacyRecordFields);
  store.migrate(1);
  EXPECT_EQ(columnsOf(db, "ray_blocks"), "frame_id,block,first_ray,n," + fields);
  EXPECT_EQ(columnsOf(db, "rays_v"), "frame_id,block,ray," + fields);
  store.migrate(2);
  EXPECT_EQ(columnsOf(db, "ray_blocks"), "frame_id,block,first_ray,n," + fields + ",tile");
  EXPECT_EQ(columnsOf(db, "rays_v"), "frame_id,tile,block,ray,tile_ray," + fields);
  EXPECT_EQ(columnsOf(db, "frame_tiles"), "frame_id,tile,ray_count,written_at");
  store.migrate(3);
  EXPECT_EQ(columnsOf(db, "ray_blocks"), "frame_id,tile,block,first_ray,n,data");
  EXPECT_EQ(columnsOf(db, "rays_v"),
            "frame_id,tile,block,ray,tile_ray," + fields + ",record_bytes");
  EXPECT_EQ(columnsOf(db, "path_points_v"), "frame_id,i,j,path,point,x,y,z,lambda,r,abs_h");
  EXPECT_EQ(columnsOf(db, "ray_paths"), "frame_id,i,j,seq,termination,n,points");
  store.migrate(4);
  EXPECT_EQ(columnsOf(db, "rays_v"),
            "frame_id,tile,block,ray,tile_ray," + fields + ",record_bytes");
  store.migrate(5);
  EXPECT_EQ(columnsOf(db, "ray_blocks"), "frame_id,tile,block,first_ray,n,data");
  EXPECT_EQ(columnsOf(db, "rays_v"), "frame_id,tile,block,ray,tile_ray," +
                                       fieldNames(Version6RecordFields) + ",record_bytes");
  EXPECT_EQ(columnsOf(db, "path_points_v"), "frame_id,i,j,path,point,x,y,z,lambda,r,abs_h");
  // Version 6 changes the function that evaluates predicates only.
  store.migrate(6);
  EXPECT_EQ(columnsOf(db, "rays_v"), "frame_id,tile,block,ray,tile_ray," +
                                       fieldNames(Version6RecordFields) + ",record_bytes");
  store.migrate(7);
  EXPECT_EQ(columnsOf(db, "ray_blocks"), "frame_id,tile,block,first_ray,n,data");
  EXPECT_EQ(columnsOf(db, "rays_v"),
            "frame_id,tile,block,ray,tile_ray," + fieldNames(RecordFields) + ",record_bytes");
  EXPECT_EQ(columnsOf(db, "path_points_v"), "frame_id,i,j,path,point,x,y,z,lambda,r,abs_h");
  store.migrate(8);
  EXPECT_EQ(columnsOf(db, "interpolated_frames"), "frame_hash,recipe,key_frame_ids,created_at");
  EXPECT_EQ(columnsOf(db, "rays_v"),
            "frame_id,tile,block,ray,tile_ray," + fieldNames(RecordFields) + ",record_bytes");
  store.migrate(9);
  EXPECT_EQ(columnsOf(db, "frame_pictures"),
            "id,frame_id,frame_hash,recipe,key_frame_ids,format,method,estimated_psnr,"
            "settings_psnr,share_retraced,rays,bytes,created_at");
}

TEST(StoreMigrations, VersionOneRaysComeBackBitExact)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate(1);
  Db db(ci);
  // Several blocks of version 1 (the last one partial), a single ray, and a frame of whole
  // blocks: the re-packing into rows of kBlockSize must not depend on where blocks end.
  const std::vector<RayRecord> large = knownRecords(0, 2 * LegacyBlock + 45);
  const std::vector<RayRecord> single = knownRecords(100000, 1);
  const std::vector<RayRecord> whole = knownRecords(200000, LegacyBlock);
  const std::int64_t a = insertLegacyFrame(db.Conn, 1, scene(1), { large });
  const std::int64_t b = insertLegacyFrame(db.Conn, 1, scene(2), { single });
  const std::int64_t c = insertLegacyFrame(db.Conn, 1, scene(3), { whole });
  // The rows are what version 1's own view decodes (the test's layout is version 1's).
  EXPECT_EQ(db.value("SELECT count(*) FROM rays_v WHERE frame_id = " + std::to_string(a)),
            std::to_string(large.size()));
  EXPECT_EQ(
    db.value("SELECT steps FROM rays_v WHERE frame_id = " + std::to_string(a) + " AND ray = 4100"),
    std::to_string(large[4100].steps));

  store.migrate();
  expectFramesIntact(store, db, { { a, large }, { b, single }, { c, whole } }, { 1, 1, 1 });
  EXPECT_EQ(db.value("SELECT count(*) FROM schema_version"), "1");
}

TEST(StoreMigrations, VersionTwoTiledRaysComeBackBitExact)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate(2);
  Db db(ci);
  // Tiles of unequal sizes (one empty, one of a single ray, one over a block of version 2), so
  // that each tile's offset in the frame matters.
  const std::vector<std::size_t> sizes = { LegacyBlock + 31, 0, 1, 62 };
  std::vector<std::vector<RayRecord>> tiles;
  std::vector<RayRecord> all;
  for (std::size_t t = 0, first = 0; t < sizes.size(); first += sizes[t++])
  {
    tiles.push_back(knownRecords(first, sizes[t]));
    all.insert(all.end(), tiles.back().begin(), tiles.back().end());
  }
  const std::int64_t tiled = insertLegacyFrame(db.Conn, 2, scene(1), tiles);
  const std::vector<RayRecord> plain = knownRecords(50000, 777);
  const std::int64_t one = insertLegacyFrame(db.Conn, 2, scene(2), { plain });
  EXPECT_EQ(db.value("SELECT min(ray) || '-' || max(ray) FROM rays_v WHERE frame_id = " +
                     std::to_string(tiled) + " AND tile = 3"),
            std::to_string(LegacyBlock + 32) + "-" + std::to_string(LegacyBlock + 93));

  store.migrate();
  expectFramesIntact(store, db, { { tiled, all }, { one, plain } }, { 4, 1 });
}

TEST(StoreMigrations, StepByStepFromVersionOneKeepsEveryRay)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate(1);
  Db db(ci);
  const std::vector<RayRecord> first = knownRecords(7, LegacyBlock + 3);
  const std::int64_t a = insertLegacyFrame(db.Conn, 1, scene(1), { first });
  store.migrate(2);
  EXPECT_EQ(store.schemaVersion(), 2);
  // Version 2 made the frame one of one tile.
  EXPECT_EQ(db.value("SELECT tile || ':' || ray_count FROM frame_tiles WHERE frame_id = " +
                     std::to_string(a)),
            "0:" + std::to_string(first.size()));
  const std::vector<RayRecord> second = knownRecords(90000, 40);
  const std::int64_t b =
    insertLegacyFrame(db.Conn, 2, scene(2), { knownRecords(90000, 25), knownRecords(90025, 15) });

  store.migrate(3);
  EXPECT_EQ(store.schemaVersion(), 3);
  store.migrate(4);
  EXPECT_EQ(store.schemaVersion(), 4);
  store.migrate(5);
  EXPECT_EQ(store.schemaVersion(), 5);
  store.migrate(6);
  EXPECT_EQ(store.schemaVersion(), 6);
  store.migrate(7);
  EXPECT_EQ(store.schemaVersion(), 7);
  // Version 8 adds the table of interpolated frames' keys only.
  store.migrate(8);
  // Version 9 adds the table of frames' pictures only.
  store.migrate(9);
  expectFramesIntact(store, db, { { a, first }, { b, second } }, { 1, 2 });
}

TEST(StoreMigrations, VersionThreeGetsTheRoleThatEvaluatesPredicates)
{
  ThrowawayPostgres pg;
  const std::string ci = pg.conninfo();
  RayStore store(ci);
  store.migrate(2);
  Db db(ci);
  const std::vector<RayRecord> rays = knownRecords(300, 100);
  const std::int64_t id = insertLegacyFrame(db.Conn, 2, scene(1), { rays });
  store.migrate(3);
  EXPECT_EQ(db.value("SELECT to_regprocedure('asrt_selected_rays(bigint,text)') IS NULL"), "t");
  EXPECT_EQ(db.value("SELECT count(*) FROM pg_roles WHERE rolname = 'asrt_predicate'"), "0");

  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(db.value("SELECT proowner::regrole::text FROM pg_proc WHERE oid = "
                     "'asrt_selected_rays(bigint,text)'::regprocedure"),
            "asrt_predicate");
  EXPECT_EQ(db.value("SELECT has_table_privilege('asrt_predicate', 'rays_v', 'SELECT')::text || "
                     "has_table_privilege('asrt_predicate', 'frames', 'SELECT')::text"),
            "truefalse");
  EXPECT_EQ(firstDifference(store.readFrame(id, "ray < 10"),
                            std::vector<RayRecord>(rays.begin(), rays.begin() + 10)),
            -1);
  // The function it got checks the predicate's tokens on the server too (version 6).
  EXPECT_NE(db.value("SELECT prosrc FROM pg_proc WHERE oid = "
                     "'asrt_selected_rays(bigint,text)'::regprocedure")
              .find("the predicate may not use"),
            std::string::npos);
  expectFramesIntact(store, db, { { id, rays } }, { 1 });
}
