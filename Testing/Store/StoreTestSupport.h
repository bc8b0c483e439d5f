// Helpers shared by the store's tests: deterministic synthetic values, bit-exact record
// comparison, plain libpq access behind the store's back, and forked writer processes.
#ifndef asrt_StoreTestSupport_h
#define asrt_StoreTestSupport_h

#include "FrameTracer.h"
#include "RayStore.h"
#include "SceneFile.h"

#include <libpq-fe.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace asrt
{
namespace testing
{
using Clock = std::chrono::steady_clock;

/// SplitMix64: a tiny, well-mixed generator, so that a record is a pure function of its seed.
inline std::uint64_t splitmix(std::uint64_t& s)
{
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

inline double fromBits(std::uint64_t w)
{
  double d;
  std::memcpy(&d, &w, 8);
  return d;
}

inline std::uint64_t bitsOf(double d)
{
  std::uint64_t w;
  std::memcpy(&w, &d, 8);
  return w;
}

/// Every stored field of a record as bits (NaN payloads and −0 included), integers first.
// ---------------------------------------------------------------------------------------------
// Deterministic synthetic records: record k of a seed is a pure function of (seed, k), so that a
// child can stream it and the parent can regenerate it for a bit-exact comparison.

inline RayRecord syntheticRecord(std::uint64_t seed, std::size_t k, int width)
{
  std::uint64_t s = seed * 0x100000001B3ull + k;
  // Values that careless storage loses: NaN payloads, −0, denormals, extremes, infinities.
  const double specials[] = {
    fromBits(0x7FF8DEADBEEF0001ull),           -0.0,
    std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(),
    -std::numeric_limits<double>::infinity(),  1e-310
  };
  auto real = [&]
  {
    const std::uint64_t w = splitmix(s);
    if (w % 13 == 0)
    {
      return specials[(w >> 8) % 6];
    }
    return fromBits((w >> 12) | 0x4000000000000000ull) - 3.0; // in [-1, 1)
  };
  RayRecord r;
  r.i = int(k % std::size_t(width));
  r.j = int(k / std::size_t(width));
  r.origin = asrt::Vec3(real(), real(), real());
  r.direction = asrt::Vec3(real(), real(), real());
  r.momentum = asrt::Vec4(real(), real(), real(), real());
  r.termination = asrt::Termination(splitmix(s) % 6);
  r.objectId = int(splitmix(s) % 5) - 1;
  r.hitPoint = asrt::Vec3(real(), real(), real());
  r.hitNormal = asrt::Vec3(real(), real(), real());
  r.u = real();
  r.v = real();
  r.chordError = real();
  r.affineLength = real();
  r.winding = real();
  r.imageOrder = int(splitmix(s) % 3);
  r.steps = std::int64_t(splitmix(s));
  r.maxAbsH = real();
  r.color = asrt::Vec3(real(), real(), real());
  r.dudi = real();
  r.dudj = real();
  r.dvdi = real();
  r.dvdj = real();
  // One ray, a supersampled grid, the most a pixel may take, and widths a narrower word loses.
  const std::int32_t rays[] = { 1, 9, 1024, 65537, std::numeric_limits<std::int32_t>::max() };
  r.raysPerPixel = rays[splitmix(s) % 5];
  // Interpolated by the adaptive grid one time in three.
  r.traced = splitmix(s) % 3 != 0;
  return r;
}

/// `count` synthetic records of a seed, `width` to a row.
inline std::vector<RayRecord> syntheticRecords(std::uint64_t seed, std::size_t count = 30,
                                               int width = 6)
{
  std::vector<RayRecord> out;
  for (std::size_t k = 0; k < count; ++k)
    out.push_back(syntheticRecord(seed, k, width));
  return out;
}

/// A scene of `width` × `height` pixels, its identity its name and mass: a frame for synthetic
/// records.
inline SceneDescription syntheticScene(const std::string& name, double mass, int width = 6,
                                       int height = 5)
{
  SceneDescription d;
  d.name = name;
  d.spacetime.mass = mass;
  d.camera.width = width;
  d.camera.height = height;
  return d;
}

/// `r` as a store of schema version 6 or earlier kept it, read back by the current version:
/// traced (migration 7).
inline RayRecord tracedRay(RayRecord r)
{
  r.traced = true;
  return r;
}
inline std::vector<RayRecord> tracedRay(std::vector<RayRecord> records)
{
  for (RayRecord& r : records)
    r.traced = true;
  return records;
}

/// `r` as a store of schema version 4 or earlier kept it, read back by the current version: one
/// ray a pixel (migration 5), traced (migration 7).
inline RayRecord singleRay(RayRecord r)
{
  r.raysPerPixel = 1;
  return tracedRay(r);
}
inline std::vector<RayRecord> singleRay(std::vector<RayRecord> records)
{
  for (RayRecord& r : records)
    r = singleRay(r);
  return records;
}

inline std::vector<std::uint64_t> recordBits(const RayRecord& r)
{
  std::vector<std::uint64_t> b = { std::uint64_t(std::uint32_t(r.i)),
                                   std::uint64_t(std::uint32_t(r.j)),
                                   std::uint64_t(r.termination),
                                   std::uint64_t(std::uint32_t(r.objectId)),
                                   std::uint64_t(std::uint32_t(r.imageOrder)),
                                   std::uint64_t(r.steps),
                                   std::uint64_t(std::uint32_t(r.raysPerPixel)),
                                   std::uint64_t(r.traced) };
  const double d[] = { r.origin.x(),
                       r.origin.y(),
                       r.origin.z(),
                       r.direction.x(),
                       r.direction.y(),
                       r.direction.z(),
                       r.momentum[0],
                       r.momentum[1],
                       r.momentum[2],
                       r.momentum[3],
                       r.hitPoint.x(),
                       r.hitPoint.y(),
                       r.hitPoint.z(),
                       r.hitNormal.x(),
                       r.hitNormal.y(),
                       r.hitNormal.z(),
                       r.u,
                       r.v,
                       r.chordError,
                       r.affineLength,
                       r.winding,
                       r.maxAbsH,
                       r.color.x(),
                       r.color.y(),
                       r.color.z(),
                       r.dudi,
                       r.dudj,
                       r.dvdi,
                       r.dvdj };
  for (double x : d)
    b.push_back(bitsOf(x));
  return b;
}

/// The fields of a stored ray, in the order the store documents (the columns of rays_v, the words
/// of its record_bytes), with their size in bytes and their value as a word: written out here
/// independently of RayStore. LegacyRecordFields: those of schema versions 1 to 4 (the bytea
/// columns of versions 1 and 2, the 260-byte records of versions 3 and 4), without
/// rays_per_pixel and traced; Version6RecordFields: those of versions 5 and 6 (264-byte
/// records), without traced.
struct RecordField
{
  const char* name;
  int size;
  std::uint64_t (*word)(const RayRecord&);
};
inline std::uint64_t fieldWord(double d)
{
  return bitsOf(d);
}
inline std::uint64_t fieldWord(std::int32_t v)
{
  return std::uint64_t(std::uint32_t(v));
}
inline std::uint64_t fieldWord(std::int64_t v)
{
  return std::uint64_t(v);
}
#define ASRT_RECORD_FIELD(name, size, e)                                                           \
  RecordField                                                                                      \
  {                                                                                                \
    name, size, [](const RayRecord& r) { return fieldWord(e); }                                    \
  }
inline const RecordField RecordFields[] = {
  ASRT_RECORD_FIELD("i", 4, r.i),
  ASRT_RECORD_FIELD("j", 4, r.j),
  ASRT_RECORD_FIELD("origin_x", 8, r.origin.x()),
  ASRT_RECORD_FIELD("origin_y", 8, r.origin.y()),
  ASRT_RECORD_FIELD("origin_z", 8, r.origin.z()),
  ASRT_RECORD_FIELD("dir_x", 8, r.direction.x()),
  ASRT_RECORD_FIELD("dir_y", 8, r.direction.y()),
  ASRT_RECORD_FIELD("dir_z", 8, r.direction.z()),
  ASRT_RECORD_FIELD("p_t", 8, r.momentum[0]),
  ASRT_RECORD_FIELD("p_x", 8, r.momentum[1]),
  ASRT_RECORD_FIELD("p_y", 8, r.momentum[2]),
  ASRT_RECORD_FIELD("p_z", 8, r.momentum[3]),
  ASRT_RECORD_FIELD("termination", 4, std::int32_t(r.termination)),
  ASRT_RECORD_FIELD("object_id", 4, r.objectId),
  ASRT_RECORD_FIELD("hit_x", 8, r.hitPoint.x()),
  ASRT_RECORD_FIELD("hit_y", 8, r.hitPoint.y()),
  ASRT_RECORD_FIELD("hit_z", 8, r.hitPoint.z()),
  ASRT_RECORD_FIELD("normal_x", 8, r.hitNormal.x()),
  ASRT_RECORD_FIELD("normal_y", 8, r.hitNormal.y()),
  ASRT_RECORD_FIELD("normal_z", 8, r.hitNormal.z()),
  ASRT_RECORD_FIELD("u", 8, r.u),
  ASRT_RECORD_FIELD("v", 8, r.v),
  ASRT_RECORD_FIELD("chord_error", 8, r.chordError),
  ASRT_RECORD_FIELD("path_length", 8, r.affineLength),
  ASRT_RECORD_FIELD("winding", 8, r.winding),
  ASRT_RECORD_FIELD("image_order", 4, r.imageOrder),
  ASRT_RECORD_FIELD("steps", 8, r.steps),
  ASRT_RECORD_FIELD("max_abs_h", 8, r.maxAbsH),
  ASRT_RECORD_FIELD("color_r", 8, r.color.x()),
  ASRT_RECORD_FIELD("color_g", 8, r.color.y()),
  ASRT_RECORD_FIELD("color_b", 8, r.color.z()),
  ASRT_RECORD_FIELD("rays_per_pixel", 4, r.raysPerPixel),
  ASRT_RECORD_FIELD("dudi", 8, r.dudi),
  ASRT_RECORD_FIELD("dudj", 8, r.dudj),
  ASRT_RECORD_FIELD("dvdi", 8, r.dvdi),
  ASRT_RECORD_FIELD("dvdj", 8, r.dvdj),
  ASRT_RECORD_FIELD("traced", 4, std::int32_t(r.traced ? 1 : 0)),
};
#undef ASRT_RECORD_FIELD
inline const std::vector<RecordField> Version6RecordFields = []
{
  std::vector<RecordField> fields;
  for (const RecordField& f : RecordFields)
    if (std::strcmp(f.name, "traced") != 0)
      fields.push_back(f);
  return fields;
}();
inline const std::vector<RecordField> LegacyRecordFields = []
{
  std::vector<RecordField> fields;
  for (const RecordField& f : Version6RecordFields)
    if (std::strcmp(f.name, "rays_per_pixel") != 0)
      fields.push_back(f);
  return fields;
}();

/// A binary result value of a PGresult as a big-endian word (integers and float8 alike).
inline std::uint64_t resultWord(const PGresult* r, int row, int col)
{
  std::uint64_t w = 0;
  for (int k = 0; k < PQgetlength(r, row, col); ++k)
    w = (w << 8) | std::uint8_t(PQgetvalue(r, row, col)[k]);
  return w;
}

/// Whether SQL's double `got` is `expected`, bit for bit, or for a NaN any NaN: SQL arithmetic
/// knows one NaN only (the stored bits keep the payload).
inline bool sameFromSql(double got, double expected)
{
  return std::isnan(expected) ? std::isnan(got) : bitsOf(got) == bitsOf(expected);
}

/// The words of `fields` of `r`, big-endian, concatenated.
template<class Fields>
std::string packedFields(const RayRecord& r, const Fields& fields)
{
  std::string bytes;
  for (const RecordField& f : fields)
  {
    const std::uint64_t w = f.word(r);
    for (int m = f.size - 1; m >= 0; --m)
      bytes.push_back(char(w >> (8 * m)));
  }
  return bytes;
}
/// The packed record of the current schema (rays_v's record_bytes): every field's word.
inline std::string packedRecord(const RayRecord& r)
{
  return packedFields(r, RecordFields);
}
/// The packed record of schema versions 3 and 4 (260 bytes, no rays_per_pixel).
inline std::string legacyPackedRecord(const RayRecord& r)
{
  return packedFields(r, LegacyRecordFields);
}
/// The packed record of schema versions 5 and 6 (264 bytes, no traced).
inline std::string version6PackedRecord(const RayRecord& r)
{
  return packedFields(r, Version6RecordFields);
}

inline double secondsSince(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// What a call throws, as text ("(no error)" if nothing).
template<typename F>
std::string errorOf(F&& f)
{
  try
  {
    f();
  }
  catch (const StoreError& e)
  {
    return e.what();
  }
  catch (const std::exception& e)
  {
    return std::string("(not a StoreError) ") + e.what();
  }
  return "(no error)";
}

/// Plain libpq access, for looking at the database behind the store's back.
struct Db
{
  explicit Db(const std::string& conninfo)
    : Conn(PQconnectdb((conninfo + " connect_timeout=5").c_str()))
  {
    if (PQstatus(this->Conn) != CONNECTION_OK)
    {
      const std::string msg = PQerrorMessage(this->Conn);
      PQfinish(this->Conn);
      throw std::runtime_error(msg);
    }
  }
  ~Db() { PQfinish(this->Conn); }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;
  /// The first value of the first row ("" if none); throws with the server's message.
  std::string value(const std::string& sql)
  {
    PGresult* r = PQexec(this->Conn, sql.c_str());
    const ExecStatusType st = PQresultStatus(r);
    if (st != PGRES_TUPLES_OK && st != PGRES_COMMAND_OK)
    {
      const std::string msg = PQresultErrorMessage(r);
      PQclear(r);
      throw std::runtime_error(sql + ": " + msg);
    }
    std::string v = (st == PGRES_TUPLES_OK && PQntuples(r) > 0) ? PQgetvalue(r, 0, 0) : "";
    PQclear(r);
    return v;
  }
  /// The rows of a query with binary results (integers and doubles as the server holds them);
  /// throws with the server's message.
  std::unique_ptr<PGresult, void (*)(PGresult*)> binaryRows(const std::string& sql)
  {
    std::unique_ptr<PGresult, void (*)(PGresult*)> r(
      PQexecParams(this->Conn, sql.c_str(), 0, nullptr, nullptr, nullptr, nullptr, 1), PQclear);
    if (PQresultStatus(r.get()) != PGRES_TUPLES_OK)
      throw std::runtime_error(sql + ": " + PQresultErrorMessage(r.get()));
    return r;
  }
  PGconn* Conn;
};

/// Polls `sql` (one value) until `done(value)` or the timeout; returns the last value.
template<typename P>
std::string pollUntil(Db& db, const std::string& sql, P&& done, double timeoutSeconds)
{
  const auto t0 = Clock::now();
  std::string v = db.value(sql);
  while (!done(v) && secondsSince(t0) < timeoutSeconds)
  {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    v = db.value(sql);
  }
  return v;
}

// ---------------------------------------------------------------------------------------------
// Databases written by earlier versions. Their layout is written out here (with
// LegacyRecordFields), from what versions 1 and 2 stored, rather than taken from RayStore: one
// bytea column per field, the values of a block of up to 4096 rays as big-endian words; version 2
// added tiles. Their texts had no rendering section.

/// The rendering section that versions 5 and 6 wrote for singleRayRendering(), written out here:
/// what the texts of versions 1 to 4 lacked, and migration 5 gives them.
inline const std::string SingleRaySectionV5 =
  R"("rendering":{"antialias":"none","colorThreshold":1.0,"maxRaysPerPixel":1,"supersample":1})";
/// The section effectiveSceneText() writes for singleRayRendering() since version 7, which also
/// names the lattice (every pixel traced); migration 7 adds it to every text without one.
inline const std::string SingleRaySection =
  R"("rendering":{"antialias":"none","colorThreshold":1.0,)"
  R"("gridLattice":1,"maxRaysPerPixel":1,"supersample":1})";

/// A frame's effective text as versions 5 and 6 wrote it for a frame that traced every pixel:
/// without "gridLattice" (a grid did not exist).
inline std::string textBeforeGrid(const std::string& text)
{
  nlohmann::json j = nlohmann::json::parse(text);
  if (j.contains("rendering"))
  {
    if (j["rendering"].value("gridLattice", 1) != 1)
      throw std::logic_error("textBeforeGrid: the text's frame was traced on the grid");
    j["rendering"].erase("gridLattice");
    j["rendering"].erase("gridTolerance");
  }
  return j.dump();
}

/// The texts a writer of schema version 4 or earlier stored for a frame of `d` (whose rendering
/// must be singleRayRendering(), the only one there was): its effective text, which had no
/// rendering section, and its scene's text, that text without the parameters of frames columns.
struct StoredTexts
{
  std::string frame, scene;
};
/// The texts a writer stored for a frame whose effective text is `frame`: the scene's is the
/// frame's without what the columns of frames hold (spelled out here as the writers of every
/// version made it).
inline StoredTexts storedTexts(const std::string& frame)
{
  nlohmann::json j = nlohmann::json::parse(frame);
  j.erase("spacetime");
  for (const char* k : { "position", "focalPoint", "viewUp", "viewAngle", "resolution" })
    j["camera"].erase(k);
  for (const char* k : { "method", "step", "relativeTolerance", "absoluteTolerance" })
    j["integrator"].erase(k);
  return { frame, j.dump() };
}
inline StoredTexts legacyTexts(asrt::SceneDescription d)
{
  // A frame stored before anti-aliasing was one ray a pixel.
  d.rendering = asrt::singleRayRendering();
  std::string frame = textBeforeGrid(asrt::effectiveSceneText(d));
  // Keys sorted: "spacetime" always follows the section.
  const std::size_t at = frame.find(SingleRaySectionV5 + ",");
  if (at == std::string::npos)
    throw std::logic_error("legacyTexts: the scene's text has no single-ray rendering section");
  frame.erase(at, SingleRaySectionV5.size() + 1);
  return storedTexts(frame);
}

/// Rays per block of ray_blocks in versions 1 and 2.
constexpr std::size_t LegacyBlock = 4096;

/// Runs a statement with text parameters (bytea ones, marked by a leading "\x" in `binary`, in
/// binary) and returns the first value.
inline std::string legacyExec(PGconn* c, const std::string& sql,
                              const std::vector<std::string>& params,
                              const std::vector<bool>& binary = {})
{
  std::vector<const char*> values;
  std::vector<int> lengths, formats;
  for (std::size_t k = 0; k < params.size(); ++k)
  {
    values.push_back(params[k].c_str());
    lengths.push_back(int(params[k].size()));
    formats.push_back(k < binary.size() && binary[k] ? 1 : 0);
  }
  PGresult* r = PQexecParams(c, sql.c_str(), int(params.size()), nullptr, values.data(),
                             lengths.data(), formats.data(), 0);
  const ExecStatusType st = PQresultStatus(r);
  std::string v;
  if (st == PGRES_TUPLES_OK && PQntuples(r) > 0)
    v = PQgetvalue(r, 0, 0);
  const std::string msg = PQresultErrorMessage(r);
  PQclear(r);
  if (st != PGRES_TUPLES_OK && st != PGRES_COMMAND_OK)
    throw std::runtime_error(sql + ": " + msg);
  return v;
}

/// Stores tile `t` of frame `id` as the partitioned schemas (versions 4 to 6) did: its partition of
/// ray_blocks holding the records packed by `pack`, `blockRecords` to a block, and its frame_tiles
/// row. An empty tile has the row alone.
template<typename Pack>
void insertPartitionedTile(Db& db, const std::string& id, std::size_t t,
                           const std::vector<RayRecord>& tile, std::size_t blockRecords,
                           const Pack& pack)
{
  const std::string table = "ray_blocks_" + id + "_" + std::to_string(t);
  if (!tile.empty())
  {
    db.value("CREATE TABLE " + table +
             " (LIKE ray_block_layout INCLUDING ALL, PRIMARY KEY (block), CHECK (frame_id = " + id +
             " AND tile = " + std::to_string(t) + ")) WITH (autovacuum_enabled = false)");
    for (std::size_t first = 0, b = 0; first < tile.size(); first += blockRecords, ++b)
    {
      std::string data;
      const std::size_t n = std::min(blockRecords, tile.size() - first);
      for (std::size_t k = first; k < first + n; ++k)
        data += pack(tile[k]);
      legacyExec(db.Conn,
                 "INSERT INTO " + table +
                   " (frame_id, tile, block, first_ray, n, data) VALUES ($1, $2, $3, $4, $5, $6)",
                 { id, std::to_string(t), std::to_string(b), std::to_string(first),
                   std::to_string(n), data },
                 { false, false, false, false, false, true });
    }
    db.value("ALTER TABLE ray_blocks ATTACH PARTITION " + table + " FOR VALUES FROM (" + id + ", " +
             std::to_string(t) + ") TO (" + id + ", " + std::to_string(t + 1) + ")");
  }
  db.value("INSERT INTO frame_tiles (frame_id, tile, ray_count) VALUES (" + id + ", " +
           std::to_string(t) + ", " + std::to_string(tile.size()) + ")");
}

/// Stores a frame as schema version `version` (1 or 2) did: its row, its tiles' rows (version 2)
/// and the blocks of every tile. Returns the frame's id.
inline std::int64_t insertLegacyFrame(PGconn* c, int version, const asrt::SceneDescription& scene,
                                      const std::vector<std::vector<RayRecord>>& tiles,
                                      const std::string& status = "complete")
{
  std::size_t rays = 0;
  for (const auto& t : tiles)
    rays += t.size();
  const StoredTexts texts = legacyTexts(scene);
  const std::string& effective = texts.frame;
  const std::string sceneId = legacyExec(
    c,
    "INSERT INTO scenes (content_hash, description, description_text) VALUES "
    "(sha256(convert_to($1, 'UTF8')), $1::jsonb, $1) ON CONFLICT (content_hash) DO UPDATE SET "
    "description_text = EXCLUDED.description_text RETURNING id",
    { texts.scene });
  auto num = [](double x)
  {
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", x);
    return std::string(b);
  };
  std::string cols = "scene_id, frame_hash, effective_text, name, label, mass, spin, charge, "
                     "camera_x, camera_y, camera_z, focal_x, focal_y, focal_z, up_x, up_y, up_z, "
                     "view_angle, width, height, method, step, relative_tolerance, "
                     "absolute_tolerance, status, ray_count, write_seconds, completed_at";
  std::string vals = "$1, sha256(convert_to($2, 'UTF8')), $2, $3, 'legacy', $4, $5, 0, 0, -30, "
                     "0, 0, 0, 0, 0, 0, 1, 30, $6, $7, 'auto', 0, 1e-9, 1e-12, $8, $9, 1, "
                     "CASE WHEN $8 = 'complete' THEN now() END";
  if (version >= 2)
  {
    cols += ", tile_count";
    vals += ", " + std::to_string(tiles.size());
  }
  const std::int64_t id = std::stoll(legacyExec(
    c, "INSERT INTO frames (" + cols + ") VALUES (" + vals + ") RETURNING id",
    { sceneId, effective, scene.name, num(scene.spacetime.mass), num(scene.spacetime.spin),
      std::to_string(scene.camera.width), std::to_string(scene.camera.height), status,
      std::to_string(status == "complete" ? rays : 0) }));
  std::string blockCols = "frame_id, block, first_ray, n", blockVals = "$1, $2, $3, $4";
  int next = 5;
  if (version >= 2)
  {
    blockCols += ", tile";
    blockVals += ", $" + std::to_string(next++);
  }
  for (const RecordField& f : LegacyRecordFields)
  {
    blockCols += std::string(", ") + f.name;
    blockVals += ", $" + std::to_string(next++);
  }
  for (std::size_t t = 0; t < tiles.size(); ++t)
  {
    if (version >= 2)
      legacyExec(c, "INSERT INTO frame_tiles (frame_id, tile, ray_count) VALUES ($1, $2, $3)",
                 { std::to_string(id), std::to_string(t), std::to_string(tiles[t].size()) });
    for (std::size_t first = 0, b = 0; first < tiles[t].size(); first += LegacyBlock, ++b)
    {
      const std::size_t n = std::min(LegacyBlock, tiles[t].size() - first);
      std::vector<std::string> params = { std::to_string(id), std::to_string(b),
                                          std::to_string(first), std::to_string(n) };
      if (version >= 2)
        params.push_back(std::to_string(t));
      std::vector<bool> binary(params.size(), false);
      for (const RecordField& f : LegacyRecordFields)
      {
        std::string bytes;
        for (std::size_t k = 0; k < n; ++k)
        {
          const std::uint64_t w = f.word(tiles[t][first + k]);
          for (int m = f.size - 1; m >= 0; --m)
            bytes.push_back(char(w >> (8 * m)));
        }
        params.push_back(bytes);
        binary.push_back(true);
      }
      legacyExec(c, "INSERT INTO ray_blocks (" + blockCols + ") VALUES (" + blockVals + ")", params,
                 binary);
    }
  }
  return id;
}

/// Exit codes of forked children (they must not use gtest assertions).
enum ChildCode
{
  Ok = 0,
  ExpectedError = 10, ///< a StoreError whose message holds the text the test expects
  OtherStoreError = 11,
  OtherException = 12,
  BadReadBack = 13,
};

/// Forks a child that runs `body` (returning its exit code) under an alarm, so that a deadlocked
/// child dies of SIGALRM (128 + 14 to the parent) instead of hanging the test.
template<typename F>
pid_t spawnChild(unsigned alarmSeconds, const char* expectedError, F&& body)
{
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid != 0)
    return pid;
  alarm(alarmSeconds);
  int code = OtherException;
  try
  {
    code = body();
  }
  catch (const StoreError& e)
  {
    std::fprintf(stderr, "[child %d] StoreError: %s\n", int(getpid()), e.what());
    code = std::string(e.what()).find(expectedError) != std::string::npos ? ExpectedError
                                                                          : OtherStoreError;
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "[child %d] exception: %s\n", int(getpid()), e.what());
  }
  catch (...)
  {
  }
  std::fflush(nullptr);
  _exit(code);
}

/// The child's exit code, 128 + signal if a signal ended it, or -1 if it was still running at the
/// deadline (it is then killed).
inline int waitChild(pid_t pid, Clock::time_point deadline)
{
  int status = 0;
  for (;;)
  {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid)
      break;
    if (w < 0)
      return -2;
    if (Clock::now() > deadline)
    {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Makes every child wait on a pipe until the parent closes it, so that they start together.
struct StartGate
{
  int Fd[2] = { -1, -1 };
  StartGate()
  {
    if (pipe(this->Fd) != 0)
      throw std::runtime_error("pipe failed");
  }
  ~StartGate() { this->open(); }
  StartGate(const StartGate&) = delete;
  StartGate& operator=(const StartGate&) = delete;
  /// In a child: blocks until the parent opens the gate.
  void wait()
  {
    close(this->Fd[1]);
    char c;
    while (read(this->Fd[0], &c, 1) < 0 && errno == EINTR)
    {
    }
  }
  /// In the parent.
  void open()
  {
    for (int& fd : this->Fd)
    {
      if (fd >= 0)
      {
        close(fd);
        fd = -1;
      }
    }
  }
};
}
}

#endif
