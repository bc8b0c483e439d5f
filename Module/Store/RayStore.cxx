#include "RayStore.h"

#include "SceneFile.h"

#include <libpq-fe.h>
#include <nlohmann/json.hpp>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <set>
#include <thread>
#include <utility>

namespace asrt
{
namespace
{
// ---------------------------------------------------------------------------------------------
// The per-ray fields, in storage order: column name, word kind, record member. Each is moved as a
// 32- or 64-bit word so that doubles keep every bit (NaN payloads, −0, denormals). This one list
// makes the SQL columns, the encoder and the decoder, so that they cannot disagree.
#define ASRT_RAY_FIELDS(X)                                                                         \
  X(i, I32, r.i)                                                                                   \
  X(j, I32, r.j)                                                                                   \
  X(origin_x, F64, r.origin.x())                                                                   \
  X(origin_y, F64, r.origin.y())                                                                   \
  X(origin_z, F64, r.origin.z())                                                                   \
  X(dir_x, F64, r.direction.x())                                                                   \
  X(dir_y, F64, r.direction.y())                                                                   \
  X(dir_z, F64, r.direction.z())                                                                   \
  X(p_t, F64, r.momentum[0])                                                                       \
  X(p_x, F64, r.momentum[1])                                                                       \
  X(p_y, F64, r.momentum[2])                                                                       \
  X(p_z, F64, r.momentum[3])                                                                       \
  X(termination, I32, r.termination)                                                               \
  X(object_id, I32, r.objectId)                                                                    \
  X(hit_x, F64, r.hitPoint.x())                                                                    \
  X(hit_y, F64, r.hitPoint.y())                                                                    \
  X(hit_z, F64, r.hitPoint.z())                                                                    \
  X(normal_x, F64, r.hitNormal.x())                                                                \
  X(normal_y, F64, r.hitNormal.y())                                                                \
  X(normal_z, F64, r.hitNormal.z())                                                                \
  X(u, F64, r.u)                                                                                   \
  X(v, F64, r.v)                                                                                   \
  X(chord_error, F64, r.chordError)                                                                \
  X(path_length, F64, r.affineLength)                                                              \
  X(winding, F64, r.winding)                                                                       \
  X(image_order, I32, r.imageOrder)                                                                \
  X(steps, I64, r.steps)                                                                           \
  X(max_abs_h, F64, r.maxAbsH)                                                                     \
  X(color_r, F64, r.color.x())                                                                     \
  X(color_g, F64, r.color.y())                                                                     \
  X(color_b, F64, r.color.z())                                                                     \
  X(dudi, F64, r.dudi)                                                                             \
  X(dudj, F64, r.dudj)                                                                             \
  X(dvdi, F64, r.dvdi)                                                                             \
  X(dvdj, F64, r.dvdj)

enum class Kind
{
  I32,
  I64,
  F64
};

struct Column
{
  const char* name;
  Kind kind;
};

#define ASRT_COLUMN(name, kind, member) Column{ #name, Kind::kind },
constexpr Column Columns[] = { ASRT_RAY_FIELDS(ASRT_COLUMN) };
#undef ASRT_COLUMN

constexpr int wordSize(Kind k)
{
  return k == Kind::I32 ? 4 : 8;
}

constexpr int recordBytes()
{
  int bytes = 0;
  for (const Column& c : Columns)
  {
    bytes += wordSize(c.kind);
  }
  return bytes;
}
static_assert(recordBytes() == RayStore::kRecordBytes, "kRecordBytes must match the fields");
// A row of ray_blocks: the 24-byte tuple header, frame_id, tile, block, first_ray and n (28
// bytes), the bytea's 4-byte length and the records. PostgreSQL keeps a tuple of at most 8160
// bytes in one 8 kB page; kBlockSize is the most records that fit.
constexpr int rowBytes(int rays)
{
  return 24 + 28 + 4 + RayStore::kRecordBytes * rays;
}
static_assert(rowBytes(RayStore::kBlockSize) <= 8160 && rowBytes(RayStore::kBlockSize + 1) > 8160,
              "kBlockSize must be the most records that fit in one heap page");

std::uint64_t bitsOf(double d)
{
  std::uint64_t w;
  std::memcpy(&w, &d, 8);
  return w;
}
double doubleOf(std::uint64_t w)
{
  double d;
  std::memcpy(&d, &w, 8);
  return d;
}

// Big-endian words, in and out.
template<class T>
char* putI32(char* p, T v)
{
  const std::uint32_t w = __builtin_bswap32(std::uint32_t(std::int32_t(v)));
  std::memcpy(p, &w, 4);
  return p + 4;
}
char* putI64(char* p, std::int64_t v)
{
  const std::uint64_t w = __builtin_bswap64(std::uint64_t(v));
  std::memcpy(p, &w, 8);
  return p + 8;
}
char* putF64(char* p, double v)
{
  return putI64(p, std::int64_t(bitsOf(v)));
}
template<class T>
const char* getI32(const char* p, T& v)
{
  std::uint32_t w;
  std::memcpy(&w, p, 4);
  v = static_cast<T>(std::int32_t(__builtin_bswap32(w)));
  return p + 4;
}
const char* getI64(const char* p, std::int64_t& v)
{
  std::uint64_t w;
  std::memcpy(&w, p, 8);
  v = std::int64_t(__builtin_bswap64(w));
  return p + 8;
}
const char* getF64(const char* p, double& v)
{
  std::int64_t w;
  p = getI64(p, w);
  v = doubleOf(std::uint64_t(w));
  return p;
}

/// Writes the kRecordBytes bytes of a record at p; returns the end.
char* encodeRecord(const RayRecord& r, char* p)
{
#define ASRT_PUT(name, kind, member) p = put##kind(p, member);
  ASRT_RAY_FIELDS(ASRT_PUT)
#undef ASRT_PUT
  return p;
}

/// Reads a record written by encodeRecord.
void decodeRecord(const char* p, RayRecord& r)
{
#define ASRT_GET(name, kind, member) p = get##kind(p, member);
  ASRT_RAY_FIELDS(ASRT_GET)
#undef ASRT_GET
}

/// A path point: x, y, z, λ, r, |H|, as big-endian float64 words.
constexpr Column PathColumns[] = { { "x", Kind::F64 }, { "y", Kind::F64 },
                                   { "z", Kind::F64 }, { "lambda", Kind::F64 },
                                   { "r", Kind::F64 }, { "abs_h", Kind::F64 } };
constexpr int PathPointBytes = 6 * 8;

// ---------------------------------------------------------------------------------------------
// The schema. Migration N takes version N−1 to N; each runs inside migrate()'s transaction.

/// SQL for the big-endian integer of `size` bytes at byte `start` (0-based) of `bytes`.
std::string wordExpr(const std::string& bytes, const std::string& start, int size)
{
  return "('x' || encode(substr(" + bytes + ", " + start + " + 1, " + std::to_string(size) +
         "), 'hex'))::bit(" + std::to_string(8 * size) + ")::" + (size == 4 ? "integer" : "bigint");
}

// SQL decoding of a stored 64-bit word as a double. The double is rebuilt from sign, exponent and
// mantissa with exact operations (products by powers of two). SQL arithmetic has no NaN payloads:
// every NaN comes out as PostgreSQL's one NaN (record_bytes and readFrame keep the bits). Written
// out per column rather than as SQL functions: a function whose argument is used several times is
// not inlined, and the call overhead would dominate.
std::string float8Expr(const std::string& w)
{
  const std::string mant = "(" + w + " & 4503599627370495)";
  const std::string expo = "((" + w + " >> 52) & 2047)";
  const std::string sign = "(CASE WHEN " + w + " < 0 THEN -1 ELSE 1 END)::float8";
  return "CASE " + expo + " WHEN 2047 THEN CASE WHEN " + mant + " <> 0 THEN 'NaN'::float8 WHEN " +
         w + " < 0 THEN '-Infinity'::float8 ELSE 'Infinity'::float8 END WHEN 0 THEN " + sign +
         " * " + mant + "::float8 * (2::float8 ^ (-1074)::float8) ELSE " + sign + " * (" + mant +
         " + 4503599627370496)::float8 * (2::float8 ^ (" + expo + " - 1075)::float8) END";
}

/// The decoded columns of a view, ",\n  <expr> AS <name>" for each of `fields`; word(field,
/// offset) is the SQL of the field's word, `offset` its byte offset in a packed record.
template<class Fields, class Word>
std::string fieldColumns(const Fields& fields, Word word)
{
  std::string s;
  int offset = 0;
  for (const Column& f : fields)
  {
    const std::string w = word(f, offset);
    s += ",\n  " + (f.kind == Kind::F64 ? float8Expr(w) : w) + " AS " + f.name;
    offset += wordSize(f.kind);
  }
  return s;
}

// Versions 1 and 2 kept one bytea column per field, in blocks of up to 4096 rays. Their view is
// kept exactly as it was created, since migrations 2 and 3 start from it. Each block's values are
// detoasted once (the OFFSET 0 sub-select) rather than once per ray.
std::string legacyRaysView(int version)
{
  std::string s;
  if (version == 1)
  {
    s += "CREATE VIEW rays_v AS SELECT b.frame_id, b.block, b.first_ray + k AS ray";
  }
  else
  {
    s += "CREATE VIEW rays_v AS SELECT b.frame_id, b.tile, b.block, o.base + b.first_ray + k AS "
         "ray, b.first_ray + k AS tile_ray";
  }
  s +=
    fieldColumns(Columns,
                 [](const Column& c, int)
                 {
                   const int size = wordSize(c.kind);
                   return wordExpr("d." + std::string(c.name), std::to_string(size) + " * k", size);
                 });
  s += "\nFROM ray_blocks b\n";
  if (version >= 2)
  {
    s += "JOIN frames f ON f.id = b.frame_id AND f.status = 'complete'\n"
         "CROSS JOIN LATERAL (SELECT coalesce(sum(t.ray_count), 0)::bigint AS base FROM "
         "frame_tiles t WHERE t.frame_id = b.frame_id AND t.tile < b.tile) o\n";
  }
  s += "CROSS JOIN LATERAL (SELECT ";
  bool first = true;
  for (const Column& c : Columns)
  {
    s += std::string(first ? "" : ", ") + "b." + c.name + " || ''::bytea AS " + c.name;
    first = false;
  }
  s += " OFFSET 0) d\nCROSS JOIN LATERAL generate_series(0, b.n - 1) AS k;\n";
  return s;
}

std::string migration1()
{
  std::string s = R"SQL(
CREATE TABLE schema_version (
  version integer NOT NULL,
  migrated_at timestamptz NOT NULL DEFAULT now());
-- A scene is the description without the parameters that vary per frame (see frames).
CREATE TABLE scenes (
  id bigserial PRIMARY KEY,
  content_hash bytea NOT NULL UNIQUE,
  description jsonb NOT NULL,
  description_text text NOT NULL,
  created_at timestamptz NOT NULL DEFAULT now());
CREATE TABLE frames (
  id bigserial PRIMARY KEY,
  scene_id bigint NOT NULL REFERENCES scenes (id),
  frame_hash bytea NOT NULL UNIQUE,
  effective_text text NOT NULL,
  name text NOT NULL,
  label text NOT NULL,
  mass float8 NOT NULL, spin float8 NOT NULL, charge float8 NOT NULL,
  camera_x float8 NOT NULL, camera_y float8 NOT NULL, camera_z float8 NOT NULL,
  focal_x float8 NOT NULL, focal_y float8 NOT NULL, focal_z float8 NOT NULL,
  up_x float8 NOT NULL, up_y float8 NOT NULL, up_z float8 NOT NULL,
  view_angle float8 NOT NULL,
  width integer NOT NULL, height integer NOT NULL,
  method text NOT NULL,
  step float8 NOT NULL,
  relative_tolerance float8 NOT NULL, absolute_tolerance float8 NOT NULL,
  status text NOT NULL CHECK (status IN ('writing', 'complete')),
  ray_count bigint NOT NULL DEFAULT 0,
  write_seconds float8,
  trace_seconds float8,
  created_at timestamptz NOT NULL DEFAULT now(),
  completed_at timestamptz);
CREATE INDEX frames_scene_id ON frames (scene_id);
CREATE TABLE ray_blocks (
  frame_id bigint NOT NULL REFERENCES frames (id) ON DELETE CASCADE,
  block integer NOT NULL,
  first_ray bigint NOT NULL,
  n integer NOT NULL CHECK (n > 0 AND n <= 4096),
)SQL";
  for (const Column& c : Columns)
  {
    s += "  " + std::string(c.name) + " bytea NOT NULL CHECK (length(" + c.name +
         ") = " + std::to_string(wordSize(c.kind)) + " * n),\n";
  }
  s += "  PRIMARY KEY (frame_id, block));\n";
  // The words do not compress; trying would only cost time.
  for (const Column& c : Columns)
  {
    s += "ALTER TABLE ray_blocks ALTER COLUMN " + std::string(c.name) + " SET STORAGE EXTERNAL;\n";
  }
  s += legacyRaysView(1);
  return s;
}

// Version 2: tiled frames. Existing frames become frames of one tile (tile 0), so that their
// blocks, ray numbers and readFrame() are unchanged.
std::string migration2()
{
  return R"SQL(
ALTER TABLE frames ADD COLUMN tile_count integer NOT NULL DEFAULT 1 CHECK (tile_count > 0);
CREATE TABLE frame_tiles (
  frame_id bigint NOT NULL REFERENCES frames (id) ON DELETE CASCADE,
  tile integer NOT NULL CHECK (tile >= 0),
  ray_count bigint NOT NULL CHECK (ray_count >= 0),
  written_at timestamptz NOT NULL DEFAULT now(),
  PRIMARY KEY (frame_id, tile));
INSERT INTO frame_tiles (frame_id, tile, ray_count, written_at)
  SELECT id, 0, ray_count, coalesce(completed_at, created_at) FROM frames WHERE status = 'complete';
DROP VIEW rays_v;
ALTER TABLE ray_blocks ADD COLUMN tile integer NOT NULL DEFAULT 0 CHECK (tile >= 0);
ALTER TABLE ray_blocks DROP CONSTRAINT ray_blocks_pkey;
ALTER TABLE ray_blocks ADD PRIMARY KEY (frame_id, tile, block);
)SQL" + legacyRaysView(2);
}

// Version 3: the records of a ray packed together, kBlockSize rays per row kept inline, in a table
// per tile attached to the partitioned ray_blocks (see RayStore.h); the paths of rays.

/// The table holding the rays of one tile of one frame. Made from numbers only: nothing a caller
/// gives reaches this name.
std::string blockTable(std::int64_t frame, std::int32_t tile)
{
  return "ray_blocks_" + std::to_string(frame) + "_" + std::to_string(tile);
}

/// Creates a tile's table. Its CHECK makes ATTACH PARTITION skip scanning it; its rows are never
/// updated and are frozen by COPY FREEZE, so autovacuum has nothing to do there (and would only
/// read it to gather statistics that no query needs).
std::string createBlockTable(std::int64_t frame, std::int32_t tile)
{
  return "CREATE TABLE " + blockTable(frame, tile) +
         " (LIKE ray_block_layout INCLUDING ALL, PRIMARY KEY (block), CHECK (frame_id = " +
         std::to_string(frame) + " AND tile = " + std::to_string(tile) +
         ")) WITH (autovacuum_enabled = false)";
}

std::string attachBlockTable(const std::string& parent, std::int64_t frame, std::int32_t tile)
{
  return "ALTER TABLE " + parent + " ATTACH PARTITION " + blockTable(frame, tile) +
         " FOR VALUES FROM (" + std::to_string(frame) + ", " + std::to_string(tile) + ") TO (" +
         std::to_string(frame) + ", " + std::to_string(std::int64_t(tile) + 1) + ")";
}

/// One row per ray of every complete frame. record_bytes is the packed record itself, every bit
/// of it (NaN payloads included), for clients that decode it and for readFrame's predicates.
std::string raysView()
{
  const std::string rec = std::to_string(RayStore::kRecordBytes);
  std::string s = "CREATE VIEW rays_v AS SELECT b.frame_id, b.tile, b.block, o.base + b.first_ray "
                  "+ k AS ray, b.first_ray + k AS tile_ray";
  s += fieldColumns(
    Columns, [&](const Column& c, int offset)
    { return wordExpr("b.data", rec + " * k + " + std::to_string(offset), wordSize(c.kind)); });
  s += ",\n  substr(b.data, " + rec + " * k + 1, " + rec + ") AS record_bytes\n";
  // first_ray counts within the tile (a rank does not know the sizes of the other tiles); ray
  // numbers the frame as readFrame() returns it, tile after tile. Only complete frames are
  // shown: the committed tiles of a frame still being written are nobody's business, and the
  // tables of deleted frames not yet dropped are nobody's either.
  s += "FROM ray_blocks b\n"
       "JOIN frames f ON f.id = b.frame_id AND f.status = 'complete'\n"
       "CROSS JOIN LATERAL (SELECT coalesce(sum(t.ray_count), 0)::bigint AS base FROM "
       "frame_tiles t WHERE t.frame_id = b.frame_id AND t.tile < b.tile) o\n"
       "CROSS JOIN LATERAL generate_series(0, b.n - 1) AS k;\n";
  return s;
}

/// One row per point of every stored path of a complete frame.
std::string pathPointsView()
{
  std::string s = "CREATE VIEW path_points_v AS SELECT p.frame_id, p.i, p.j, p.seq AS path, k AS "
                  "point";
  s += fieldColumns(PathColumns,
                    [](const Column& c, int offset)
                    {
                      return wordExpr("d.points",
                                      std::to_string(PathPointBytes) + " * k + " +
                                        std::to_string(offset),
                                      wordSize(c.kind));
                    });
  // The points are detoasted once per path (the OFFSET 0 sub-select), not once per point.
  s += "\nFROM ray_paths p\n"
       "JOIN frames f ON f.id = p.frame_id AND f.status = 'complete'\n"
       "CROSS JOIN LATERAL (SELECT p.n, p.points || ''::bytea AS points OFFSET 0) d\n"
       "CROSS JOIN LATERAL generate_series(0, d.n - 1) AS k;\n";
  return s;
}

/// The new tables, before the rays of version 2 move into them.
std::string migration3Tables()
{
  const std::string rays = std::to_string(RayStore::kBlockSize);
  const std::string rec = std::to_string(RayStore::kRecordBytes);
  return R"SQL(
-- The definition of the per-tile tables of ray_blocks (CREATE TABLE ... LIKE it); holds no rows.
CREATE TABLE ray_block_layout (
  frame_id bigint NOT NULL,
  tile integer NOT NULL CHECK (tile >= 0),
  block integer NOT NULL CHECK (block >= 0),
  first_ray bigint NOT NULL CHECK (first_ray = )SQL" +
         rays + R"SQL(::bigint * block),
  n integer NOT NULL CHECK (n BETWEEN 1 AND )SQL" +
         rays + R"SQL(),
  data bytea NOT NULL CHECK (length(data) = )SQL" +
         rec + R"SQL( * n));
-- Inline and uncompressed: a row fills one page, and the words do not compress.
ALTER TABLE ray_block_layout ALTER COLUMN data SET STORAGE PLAIN;
CREATE TABLE ray_blocks_v3 (LIKE ray_block_layout INCLUDING STORAGE)
  PARTITION BY RANGE (frame_id, tile);
)SQL";
}

/// Version 2's rays of one tile, re-packed: each ray's words concatenated, kBlockSize rays a row.
/// The series of rays depends on the detoasted block (d.n, not b.n) so that the planner cannot
/// put it outside, which would detoast the block once per ray; the records are made before the
/// grouping (the outer OFFSET 0), which would otherwise sort whole blocks once per ray.
std::string convertTileV2(std::int64_t frame, std::int32_t tile)
{
  const std::string rays = std::to_string(RayStore::kBlockSize);
  std::string rec, detoast;
  for (const Column& c : Columns)
  {
    const std::string size = std::to_string(wordSize(c.kind));
    rec += std::string(rec.empty() ? "" : " || ") + "substr(d." + c.name + ", " + size +
           " * k + 1, " + size + ")";
    detoast +=
      std::string(detoast.empty() ? "" : ", ") + "b." + c.name + " || ''::bytea AS " + c.name;
  }
  return "INSERT INTO " + blockTable(frame, tile) +
         " (frame_id, tile, block, first_ray, n, data) SELECT " + std::to_string(frame) + ", " +
         std::to_string(tile) + ", (r / " + rays + ")::integer, min(r), count(*)::integer, " +
         "string_agg(rec, ''::bytea ORDER BY r) FROM (SELECT b.first_ray + k AS r, " + rec +
         " AS rec FROM ray_blocks b CROSS JOIN LATERAL (SELECT b.n, " + detoast +
         " OFFSET 0) d CROSS JOIN LATERAL generate_series(0, d.n - 1) AS k WHERE b.frame_id = " +
         std::to_string(frame) + " AND b.tile = " + std::to_string(tile) +
         " OFFSET 0) x GROUP BY r / " + rays;
}

/// After the move: the new table takes the old one's name, and the paths arrive.
std::string migration3Finish()
{
  return R"SQL(
DROP VIEW rays_v;
DROP TABLE ray_blocks;
ALTER TABLE ray_blocks_v3 RENAME TO ray_blocks;
CREATE TABLE ray_paths (
  frame_id bigint NOT NULL REFERENCES frames (id) ON DELETE CASCADE,
  i integer NOT NULL,
  j integer NOT NULL,
  seq integer NOT NULL CHECK (seq >= 0),
  termination integer NOT NULL,
  n integer NOT NULL CHECK (n >= 0),
  points bytea NOT NULL CHECK (length(points) = )SQL" +
         std::to_string(PathPointBytes) + R"SQL( * n),
  PRIMARY KEY (frame_id, i, j),
  UNIQUE (frame_id, seq));
ALTER TABLE ray_paths ALTER COLUMN points SET STORAGE EXTERNAL;
)SQL" + raysView() +
         pathPointsView();
}

// ---------------------------------------------------------------------------------------------
// libpq helpers.

struct ResultDeleter
{
  void operator()(PGresult* r) const { PQclear(r); }
};
using Result = std::unique_ptr<PGresult, ResultDeleter>;

std::string trimmed(std::string s)
{
  while (!s.empty() && (s.back() == '\n' || s.back() == ' '))
  {
    s.pop_back();
  }
  return s;
}

[[noreturn]] void fail(const std::string& what, PGconn* conn, const PGresult* r)
{
  std::string msg = r ? PQresultErrorMessage(r) : "";
  if (msg.empty())
  {
    msg = PQerrorMessage(conn);
  }
  const char* state = r ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
  throw StoreError(what + ": " + trimmed(msg), state ? state : "");
}

void cancelQuery(PGconn* conn)
{
  if (PGcancel* c = PQgetCancel(conn))
  {
    char why[256];
    PQcancel(c, why, int(sizeof why));
    PQfreeCancel(c);
  }
}

/// Parameters for PQexecParams, all typed, doubles and integers in binary (exact).
class Params
{
public:
  Params& text(const std::string& s) { return this->add(s, 25, 0); }
  Params& bytes(const std::string& s) { return this->add(s, 17, 1); }
  Params& f64(double d) { return this->word(bitsOf(d), 8, 701); }
  Params& i64(std::int64_t v) { return this->word(std::uint64_t(v), 8, 20); }
  Params& i32(std::int32_t v) { return this->word(std::uint32_t(v), 4, 23); }

  Result exec(PGconn* conn, const std::string& sql, const std::string& what) const
  {
    const Arrays a(*this);
    Result r(PQexecParams(conn, sql.c_str(), int(a.Values.size()), this->Types.data(),
                          a.Values.data(), a.Lengths.data(), this->Formats.data(), 1));
    const ExecStatusType st = r ? PQresultStatus(r.get()) : PGRES_FATAL_ERROR;
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK)
    {
      fail(what, conn, r.get());
    }
    return r;
  }

  /// Runs a query whose rows come one at a time (single-row mode: the client never holds more
  /// than one row), calling row(result) for each, binary.
  template<class Row>
  void stream(PGconn* conn, const std::string& sql, const std::string& what, Row row) const
  {
    const Arrays a(*this);
    if (!PQsendQueryParams(conn, sql.c_str(), int(a.Values.size()), this->Types.data(),
                           a.Values.data(), a.Lengths.data(), this->Formats.data(), 1) ||
        !PQsetSingleRowMode(conn))
    {
      fail(what, conn, nullptr);
    }
    // Every result is consumed, even after an error, so that the connection is ready again.
    std::string error, state;
    while (PGresult* raw = PQgetResult(conn))
    {
      Result r(raw);
      const ExecStatusType st = PQresultStatus(raw);
      if (st == PGRES_SINGLE_TUPLE && error.empty())
      {
        try
        {
          row(raw);
        }
        catch (const StoreError& e)
        {
          // Stop asking for rows; the rest are read and dropped.
          error = e.what();
          state = e.sqlState();
          cancelQuery(conn);
        }
      }
      else if (st != PGRES_SINGLE_TUPLE && st != PGRES_TUPLES_OK && error.empty())
      {
        const char* s = PQresultErrorField(raw, PG_DIAG_SQLSTATE);
        error = what + ": " + trimmed(PQresultErrorMessage(raw));
        state = s ? s : "";
      }
    }
    if (!error.empty())
    {
      throw StoreError(error, state);
    }
    if (PQstatus(conn) != CONNECTION_OK)
    {
      fail(what, conn, nullptr);
    }
  }

private:
  struct Arrays
  {
    explicit Arrays(const Params& p)
    {
      for (const std::string& v : p.Values)
      {
        this->Values.push_back(v.data());
        this->Lengths.push_back(int(v.size()));
      }
    }
    std::vector<const char*> Values;
    std::vector<int> Lengths;
  };
  Params& add(const std::string& s, Oid type, int format)
  {
    this->Values.push_back(s);
    this->Types.push_back(type);
    this->Formats.push_back(format);
    return *this;
  }
  Params& word(std::uint64_t w, int size, Oid type)
  {
    char b[8];
    for (int k = 0; k < size; ++k)
    {
      b[k] = char(w >> (8 * (size - 1 - k)));
    }
    return this->add(std::string(b, size), type, 1);
  }
  std::vector<std::string> Values;
  std::vector<Oid> Types;
  std::vector<int> Formats;
};

Result exec(PGconn* conn, const std::string& sql, const std::string& what)
{
  return Params().exec(conn, sql, what);
}

std::uint64_t readBE(const char* p, int size)
{
  std::uint64_t w = 0;
  for (int k = 0; k < size; ++k)
  {
    w = (w << 8) | std::uint8_t(p[k]);
  }
  return w;
}

// Readers of binary-format result values.
std::int64_t getI64(const PGresult* r, int row, int col)
{
  return std::int64_t(readBE(PQgetvalue(r, row, col), 8));
}
std::int32_t getI32(const PGresult* r, int row, int col)
{
  return std::int32_t(readBE(PQgetvalue(r, row, col), 4));
}
double getF64(const PGresult* r, int row, int col)
{
  return doubleOf(readBE(PQgetvalue(r, row, col), 8));
}
std::string getText(const PGresult* r, int row, int col)
{
  return std::string(PQgetvalue(r, row, col), std::size_t(PQgetlength(r, row, col)));
}

/// Refuses what PostgreSQL's text cannot hold exactly: invalid UTF-8 and NUL bytes.
void requireText(const std::string& s, const char* what)
{
  std::size_t k = 0;
  while (k < s.size())
  {
    const unsigned char c = static_cast<unsigned char>(s[k]);
    int len = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
    bool ok = len > 0 && c != 0 && k + len <= s.size() && c != 0xC0 && c != 0xC1 && c <= 0xF4;
    for (int m = 1; ok && m < len; ++m)
    {
      ok = (static_cast<unsigned char>(s[k + m]) & 0xC0) == 0x80;
    }
    if (ok && len > 1)
    {
      // Overlong forms, surrogates and code points above U+10FFFF.
      const unsigned char d = static_cast<unsigned char>(s[k + 1]);
      ok = !(c == 0xE0 && d < 0xA0) && !(c == 0xED && d >= 0xA0) && !(c == 0xF0 && d < 0x90) &&
           !(c == 0xF4 && d >= 0x90);
    }
    if (!ok)
    {
      throw StoreError(std::string(what) + " is not valid UTF-8 text (byte " + std::to_string(k) +
                       (c == 0 ? " is NUL" : " starts an invalid sequence") +
                       "); it was not stored");
    }
    k += len;
  }
}

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

/// The scene's identity texts: the whole effective description (the frame), and the description
/// without the parameters stored as frame columns (the scene shared by the frames of a movie).
struct SceneTexts
{
  std::string frame;
  std::string scene;
};

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
  requireText(t.frame, "the scene description");
  // JSON may escape a NUL as \u0000, which the text check cannot see and jsonb refuses: refuse it
  // here, before the database, like a NUL anywhere else.
  if (t.frame.find("\\u0000") != std::string::npos)
    throw StoreError("the scene description contains a NUL character (\\u0000); it was not stored");
  return t;
}

/// Binary COPY input, streamed to the server in ~1 MB messages.
class CopyWriter
{
public:
  CopyWriter(PGconn* conn, const std::string& copySql, const char* what)
    : Conn(conn)
    , What(what)
  {
    Result copy(PQexec(conn, copySql.c_str()));
    if (!copy || PQresultStatus(copy.get()) != PGRES_COPY_IN)
    {
      fail(std::string("starting to write ") + what + " failed", conn, copy.get());
    }
    this->Buf.reserve(Flush + (1 << 16));
    this->Buf.append("PGCOPY\n\377\r\n\0", 11);
    this->u32(0);
    this->u32(0);
  }
  /// Starts a row of `fields` fields.
  void row(std::uint16_t fields)
  {
    if (this->Buf.size() >= Flush)
    {
      this->send();
    }
    this->u16(fields);
  }
  void i32(std::int32_t v)
  {
    this->u32(4);
    putI32(this->grow(4), v);
  }
  void i64(std::int64_t v)
  {
    this->u32(8);
    putI64(this->grow(8), v);
  }
  /// A bytea field of `size` bytes; returns where to write them.
  char* bytes(std::size_t size)
  {
    this->u32(std::uint32_t(size));
    return this->grow(size);
  }
  void finish()
  {
    this->u16(0xFFFF);
    this->send();
    if (PQputCopyEnd(this->Conn, nullptr) != 1)
    {
      fail(this->failure(), this->Conn, nullptr);
    }
    Result r(PQgetResult(this->Conn));
    if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
    {
      fail(this->failure(), this->Conn, r.get());
    }
    while (PGresult* extra = PQgetResult(this->Conn))
    {
      PQclear(extra);
    }
  }

private:
  void u16(std::uint16_t v)
  {
    const std::uint16_t w = __builtin_bswap16(v);
    std::memcpy(this->grow(2), &w, 2);
  }
  void u32(std::uint32_t v) { putI32(this->grow(4), v); }
  char* grow(std::size_t size)
  {
    const std::size_t at = this->Buf.size();
    this->Buf.resize(at + size);
    return &this->Buf[at];
  }
  std::string failure() const { return std::string("writing ") + this->What + " failed"; }
  void send()
  {
    if (!this->Buf.empty() &&
        PQputCopyData(this->Conn, this->Buf.data(), int(this->Buf.size())) != 1)
    {
      fail(this->failure(), this->Conn, nullptr);
    }
    this->Buf.clear();
  }
  static constexpr std::size_t Flush = 1 << 20;
  PGconn* Conn;
  const char* What;
  std::string Buf;
};

/// Leaves a COPY that an error interrupted, so that the connection can roll back.
void abandonCopy(PGconn* conn, const char* why)
{
  if (PQtransactionStatus(conn) != PQTRANS_ACTIVE)
  {
    return;
  }
  // The state of an interrupted COPY is only visible through the results still to come.
  PQputCopyEnd(conn, why);
  while (PGresult* r = PQgetResult(conn))
  {
    PQclear(r);
    if (PQstatus(conn) == CONNECTION_BAD)
    {
      break;
    }
  }
}

void rollback(PGconn* conn)
{
  if (PQstatus(conn) != CONNECTION_OK)
  {
    return;
  }
  abandonCopy(conn, "aborted by the client");
  if (PQtransactionStatus(conn) != PQTRANS_IDLE)
  {
    PQclear(PQexec(conn, "ROLLBACK"));
  }
}

/// Writes the records of one tile into a table of its own, created here and loaded in one COPY
/// FREEZE, records [first, first + count) of `next`; not attached to ray_blocks (see copyTile).
/// The caller's transaction must be READ COMMITTED (COPY FREEZE refuses a transaction that holds a
/// snapshot). An empty tile has no table.
void loadTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t first0,
              std::size_t count, const std::function<void(std::size_t, RayRecord&)>& next)
{
  if (count == 0)
  {
    return;
  }
  exec(conn, createBlockTable(frameId, tile), "creating the table of the rays failed");
  // The table is fsynced at commit (wal_level = minimal) or at the next checkpoint: asking the
  // kernel to start writing its pages back every 2 MB keeps that fsync from writing the whole
  // table after the COPY, alone (bench/REPORT.md: the write took about a third less).
  exec(conn, "SET LOCAL backend_flush_after = 256", "setting backend_flush_after failed");
  // Tests find a writer's backend by this statement's beginning ("COPY ray_blocks").
  CopyWriter writer(conn,
                    "COPY " + blockTable(frameId, tile) +
                      " (frame_id, tile, block, first_ray, n, data) FROM STDIN (FORMAT binary, "
                      "FREEZE)",
                    "the rays");
  constexpr std::size_t blockSize = RayStore::kBlockSize;
  RayRecord block[blockSize];
  for (std::size_t first = 0, b = 0; first < count; first += blockSize, ++b)
  {
    const int n = int(std::min(blockSize, count - first));
    for (int m = 0; m < n; ++m)
    {
      next(first0 + first + std::size_t(m), block[m]);
    }
    writer.row(6);
    writer.i64(frameId);
    writer.i32(tile);
    writer.i32(std::int32_t(b));
    writer.i64(std::int64_t(first));
    writer.i32(n);
    char* p = writer.bytes(std::size_t(RayStore::kRecordBytes) * std::size_t(n));
    for (int m = 0; m < n; ++m)
    {
      p = encodeRecord(block[m], p);
    }
  }
  writer.finish();
}

/// loadTile() and the attachment of its table to ray_blocks, in the caller's transaction.
void copyTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t count,
              const std::function<void(std::size_t, RayRecord&)>& next)
{
  if (count > 0)
  {
    loadTile(conn, frameId, tile, 0, count, next);
    exec(conn, attachBlockTable("ray_blocks", frameId, tile), "attaching the rays failed");
  }
}

/// Refuses paths that the frame cannot hold: a pixel outside it, two paths of one pixel, more
/// points than a bytea holds.
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
    if (p.points.size() > (std::size_t(1) << 30) / PathPointBytes - 1)
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
  CopyWriter writer(conn,
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
    char* p = writer.bytes(path.points.size() * PathPointBytes);
    for (const PathPoint& q : path.points)
    {
      for (const double v : { q.x.x(), q.x.y(), q.x.z(), q.lambda, q.r, q.absH })
      {
        p = putF64(p, v);
      }
    }
  }
  writer.finish();
}

/// The complete frame `old` (labelled `label`) has the identity of the one being written: a
/// duplicate, refused unless `replace`, which deletes its row (its paths and tiles go with it).
/// Its tables of rays are dropped after the commit (see dropOrphanBlocks: dropping them here would
/// lock ray_blocks for the whole write); until then nothing shows them.
void deleteReplaced(PGconn* conn, std::int64_t old, const std::string& label, bool replace)
{
  if (!replace)
  {
    throw StoreError("duplicate frame: this scene with these parameters is already stored as "
                     "frame " +
                     std::to_string(old) + " (label \"" + label +
                     "\"); pass replace = true to replace it");
  }
  Params().i64(old).exec(conn, "DELETE FROM frames WHERE id = $1",
                         "deleting the frame to be replaced failed");
}

/// The scene row a frame was to use disappeared before the frame's row referenced it (an unused
/// scene row is removed after a failed write or the deletion of its last frame): look it up again.
struct SceneVanished
{
};

/// Inserts the row of a frame being written. With `ifAbsent`, a frame of the same identity makes
/// the result empty instead of an error (the caller then looks at that frame).
Result insertFrame(PGconn* conn, std::int64_t sceneId, const SceneTexts& texts,
                   const SceneDescription& scene, const std::string& label, int tileCount,
                   bool ifAbsent)
{
  const CameraParameters& cam = scene.camera;
  const IntegratorConfig& ic = scene.integrator;
  Params ins;
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
    return ins.exec(
      conn,
      std::string("INSERT INTO frames (scene_id, frame_hash, effective_text, name, label, mass, "
                  "spin, charge, camera_x, camera_y, camera_z, focal_x, focal_y, focal_z, up_x, "
                  "up_y, up_z, view_angle, width, height, method, step, relative_tolerance, "
                  "absolute_tolerance, tile_count, status) VALUES ($1, sha256($2), $3, $4, $5, $6, "
                  "$7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22, "
                  "$23, $24, $25, 'writing')") +
        (ifAbsent ? " ON CONFLICT (frame_hash) DO NOTHING" : "") + " RETURNING id",
      "creating the frame failed");
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

/// Decodes a path's points (the bytes of ray_paths.points).
void decodePoints(const char* p, std::size_t count, std::vector<PathPoint>& points)
{
  points.resize(count);
  for (PathPoint& q : points)
  {
    for (double* v : { &q.x.x(), &q.x.y(), &q.x.z(), &q.lambda, &q.r, &q.absH })
    {
      p = getF64(p, *v);
    }
  }
}
}

std::vector<RayRecord> allocateRecords(std::size_t count, int threads)
{
  std::vector<RayRecord> records;
  records.reserve(count);
#ifdef MADV_POPULATE_WRITE
  if (threads <= 0)
  {
    threads = int(std::max(1u, std::thread::hardware_concurrency()));
  }
  // Only whole pages inside the reserved block; the kernel may refuse (older kernels: EINVAL),
  // and then construction faults the pages in as usual.
  const std::uintptr_t page = std::uintptr_t(sysconf(_SC_PAGESIZE));
  const std::uintptr_t begin = (std::uintptr_t(records.data()) + page - 1) / page * page;
  const std::uintptr_t end = (std::uintptr_t(records.data() + count)) / page * page;
  constexpr std::uintptr_t minSlice = std::uintptr_t(16) << 20;
  if (end > begin)
  {
    const std::uintptr_t pages = (end - begin) / page;
    const std::uintptr_t slices = std::max<std::uintptr_t>(
      1, std::min<std::uintptr_t>(std::uintptr_t(threads), (end - begin) / minSlice));
    auto populate = [&](std::uintptr_t k)
    {
      const std::uintptr_t a = begin + pages * k / slices * page;
      const std::uintptr_t b = begin + pages * (k + 1) / slices * page;
      madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_WRITE);
    };
    std::vector<std::thread> others;
    for (std::uintptr_t k = 1; k < slices; ++k)
    {
      others.emplace_back(populate, k);
    }
    populate(0);
    for (std::thread& t : others)
    {
      t.join();
    }
  }
#else
  (void)threads;
#endif
  records.resize(count);
  return records;
}

namespace
{
/// A connection set up as every connection of the store is (UTF8, notices silenced), or null
/// with libpq's reason in `error`.
PGconn* openConnection(const std::string& conninfo, std::string& error)
{
  // Keywords before "dbname" are overridden by what the expanded conninfo sets itself.
  std::vector<const char*> keys, values;
  if (!std::getenv("PGCONNECT_TIMEOUT"))
  {
    keys.push_back("connect_timeout");
    values.push_back("10");
  }
  keys.push_back("fallback_application_name");
  values.push_back("asrt");
  keys.push_back("dbname");
  values.push_back(conninfo.c_str());
  keys.push_back(nullptr);
  values.push_back(nullptr);
  PGconn* conn = PQconnectdbParams(keys.data(), values.data(), 1);
  if (!conn || PQstatus(conn) != CONNECTION_OK)
  {
    error =
      "cannot connect to PostgreSQL: " + (conn ? trimmed(PQerrorMessage(conn)) : "out of memory");
    PQfinish(conn);
    return nullptr;
  }
  if (PQsetClientEncoding(conn, "UTF8") != 0)
  {
    error = "cannot set the client encoding to UTF8: " + trimmed(PQerrorMessage(conn));
    PQfinish(conn);
    return nullptr;
  }
  // The server's notices ("table does not exist, skipping", ...) are not the caller's business;
  // libpq would print them on stderr.
  PQsetNoticeProcessor(
    conn, [](void*, const char*) {}, nullptr);
  return conn;
}
}

// -----------------------------------------------------------------------------------------------

namespace
{
/// Writes begin READ COMMITTED whatever the server's default: the frame-identity checks rely on
/// its row locking, and COPY FREEZE refuses a transaction that holds a snapshot.
const char* const WriteBegin = "BEGIN ISOLATION LEVEL READ COMMITTED";
const char* const ReadBegin = "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY";

/// The advisory lock (two-key form: this class, the frame id's low 31 bits) that a parallel
/// write's main transaction holds from its frame's insertion to its end. The tables that its
/// helper connections commit are not attached until the main transaction attaches them just
/// before its commit; until then the lock tells dropUnattachedTiles() that they are not orphans.
constexpr int WriterLockClass = 1095979605;

std::string writerLock(const char* function)
{
  return std::string("SELECT ") + function + "(" + std::to_string(WriterLockClass) +
         ", ($1::bigint & 2147483647)::integer)";
}

/// Drops the tables of tiles that a parallel write's helper connection committed but whose frame
/// never committed (the writer failed or died): tables ray_blocks_<frame>_<tile> that are not
/// partitions, whose writer's lock is free and whose frame does not exist. The lock is taken
/// before the frame is looked for, in separate statements, so that the look sees a writer's
/// commit that came before the lock. Those tables are no partitions of ray_blocks, so dropping
/// them waits for nobody's reads. `ownFrame` >= 0: only that frame's, by its own writer after a
/// failure, waiting a moment for its main backend to let go (a terminated backend may still be
/// exiting). Best effort: never throws (left for a later call).
void dropUnattachedTiles(PGconn* conn, std::int64_t ownFrame = -1) noexcept
{
  if (PQstatus(conn) != CONNECTION_OK || PQtransactionStatus(conn) != PQTRANS_IDLE)
  {
    return;
  }
  try
  {
    Result r = Params().i64(ownFrame).exec(
      conn,
      "SELECT m[1]::bigint, m[2]::integer FROM pg_class c CROSS JOIN LATERAL "
      "regexp_match(c.relname::text, '^ray_blocks_([0-9]+)_([0-9]+)$') AS m WHERE c.relkind = "
      "'r' AND NOT c.relispartition AND pg_table_is_visible(c.oid) AND ($1 < 0 OR m[1]::bigint = "
      "$1)",
      "looking for the rays of failed writes failed");
    if (PQntuples(r.get()) == 0)
    {
      return;
    }
    exec(conn, WriteBegin, "starting a transaction failed");
    if (ownFrame >= 0)
    {
      exec(conn, "SET LOCAL lock_timeout = '2s'", "setting a lock timeout failed");
    }
    for (int row = 0; row < PQntuples(r.get()); ++row)
    {
      const std::int64_t frame = getI64(r.get(), row, 0);
      const std::string table = blockTable(frame, getI32(r.get(), row, 1));
      if (ownFrame >= 0)
      {
        Params().i64(frame).exec(conn, writerLock("pg_advisory_xact_lock"), "locking failed");
      }
      else if (Result locked = Params().i64(frame).exec(
                 conn, writerLock("pg_try_advisory_xact_lock"), "locking failed");
               PQgetvalue(locked.get(), 0, 0)[0] == 0)
      {
        continue; // its writer is still at work
      }
      Result orphan = Params().i64(frame).text(table).exec(
        conn,
        "SELECT NOT EXISTS (SELECT 1 FROM frames WHERE id = $1) AND EXISTS (SELECT 1 FROM "
        "pg_class WHERE oid = to_regclass($2) AND NOT relispartition)",
        "looking for the frame failed");
      if (PQgetvalue(orphan.get(), 0, 0)[0] != 0)
      {
        exec(conn, "DROP TABLE IF EXISTS " + table, "dropping the rays of a failed write failed");
      }
    }
    exec(conn, "COMMIT", "committing failed");
  }
  catch (const StoreError&)
  {
    rollback(conn);
  }
}

/// The tiles of a parallel write other than the main connection's: each loaded and committed by
/// a helper connection on a thread of its own, not attached (the main transaction attaches them).
/// Any failure stops the others (and the main connection's load, through failed()).
class HelperLoads
{
public:
  HelperLoads(const std::vector<PGconn*>& conns, std::int64_t frameId,
              const std::vector<std::size_t>& bounds,
              const std::function<void(std::size_t, RayRecord&)>& next)
    : Errors(conns.size())
  {
    for (std::size_t k = 0; k < conns.size(); ++k)
    {
      const auto tile = std::int32_t(k + 1);
      this->Threads.emplace_back(
        [this, k, tile, frameId, &bounds, &next, conn = conns[k]]
        {
          try
          {
            exec(conn, WriteBegin, "starting a transaction failed");
            loadTile(conn, frameId, tile, bounds[k + 1], bounds[k + 2] - bounds[k + 1],
                     this->checked(next));
            exec(conn, "COMMIT", "committing the rays failed");
          }
          catch (...)
          {
            rollback(conn);
            this->Errors[k] = std::current_exception();
            this->Failed = true;
          }
        });
    }
  }
  ~HelperLoads()
  {
    this->fail();
    this->join();
  }
  HelperLoads(const HelperLoads&) = delete;
  HelperLoads& operator=(const HelperLoads&) = delete;

  /// `next`, stopped (by an exception) once any load has failed.
  std::function<void(std::size_t, RayRecord&)> checked(
    const std::function<void(std::size_t, RayRecord&)>& next)
  {
    return [this, &next](std::size_t k, RayRecord& r)
    {
      if (this->Failed.load(std::memory_order_relaxed))
      {
        throw StoreError("writing the rays failed: another connection of the write failed");
      }
      next(k, r);
    };
  }
  void fail() { this->Failed = true; }
  void join()
  {
    for (std::thread& t : this->Threads)
    {
      if (t.joinable())
      {
        t.join();
      }
    }
  }
  /// After join(): rethrows the first helper's error, if any.
  void rethrow()
  {
    for (const std::exception_ptr& e : this->Errors)
    {
      if (e)
      {
        std::rethrow_exception(e);
      }
    }
  }

private:
  std::atomic<bool> Failed{ false };
  std::vector<std::exception_ptr> Errors;
  std::vector<std::thread> Threads;
};
}

struct RayStore::Impl
{
  PGconn* Conn = nullptr;
  bool SchemaChecked = false;
  std::string Conninfo;
  /// The other connections of a parallel write (see writeFrameTiles), opened when first needed.
  std::vector<PGconn*> Helpers;
  int WriteConnections = RayStore::kDefaultWriteConnections;

  /// Up to `wanted` helper connections, connected; fewer if the server refuses more (e.g. at
  /// max_connections): a parallel write then uses the ones it got.
  std::vector<PGconn*> helpers(int wanted)
  {
    std::vector<PGconn*> out;
    for (std::size_t k = 0; int(out.size()) < wanted; ++k)
    {
      if (k == this->Helpers.size())
      {
        std::string error;
        PGconn* c = openConnection(this->Conninfo, error);
        if (!c)
        {
          break;
        }
        this->Helpers.push_back(c);
      }
      PGconn* c = this->Helpers[k];
      if (PQstatus(c) != CONNECTION_OK)
      {
        PQreset(c);
        if (PQstatus(c) != CONNECTION_OK)
        {
          break;
        }
        PQsetClientEncoding(c, "UTF8");
      }
      out.push_back(c);
    }
    return out;
  }

  /// Reconnects once after the connection broke (server restart, terminated backend).
  void ensureConnected()
  {
    if (PQstatus(this->Conn) != CONNECTION_OK)
    {
      PQreset(this->Conn);
      this->SchemaChecked = false;
      if (PQstatus(this->Conn) != CONNECTION_OK)
      {
        throw StoreError("lost the connection to PostgreSQL and could not reconnect: " +
                         trimmed(PQerrorMessage(this->Conn)));
      }
      PQsetClientEncoding(this->Conn, "UTF8");
    }
  }

  int readVersion()
  {
    Result r = exec(this->Conn, "SELECT to_regclass('schema_version') IS NOT NULL",
                    "reading the schema version failed");
    if (PQgetvalue(r.get(), 0, 0)[0] == 0)
    {
      return 0;
    }
    r = exec(this->Conn, "SELECT coalesce(max(version), 0) FROM schema_version",
             "reading the schema version failed");
    return getI32(r.get(), 0, 0);
  }

  void requireSchema()
  {
    this->ensureConnected();
    if (this->SchemaChecked)
    {
      return;
    }
    const int v = this->readVersion();
    if (v == 0)
    {
      throw StoreError("the database has no ASRT schema (schema version 0); call migrate() first");
    }
    if (v != kSchemaVersion)
    {
      throw StoreError("schema version mismatch: found " + std::to_string(v) +
                       ", this build knows " + std::to_string(kSchemaVersion) +
                       (v < kSchemaVersion ? "; call migrate() to upgrade the database"
                                           : "; the database was written by a newer ASRT"));
    }
    this->SchemaChecked = true;
  }

  /// Runs `body` in a transaction begun with `begin`, rolling back if it throws.
  template<typename F>
  auto transaction(const char* begin, F&& body)
  {
    exec(this->Conn, begin, "starting a transaction failed");
    try
    {
      return body();
    }
    catch (...)
    {
      rollback(this->Conn);
      throw;
    }
  }

  /// The id of the scene row, created if missing. The scene row is shared by every frame of the
  /// scene (a movie's frames differ only in their parameters). It is created in its own short
  /// transaction and never locked by a frame's write: an upsert inside the frame's transaction
  /// would hold its row lock for the whole COPY and serialise every other writer of the scene.
  /// The row may be removed again (see dropUnusedScenes) before the frame's row refers to it:
  /// insertFrame() then throws SceneVanished and the writer asks again.
  std::int64_t sceneRow(const SceneTexts& texts)
  {
    for (int attempt = 0; attempt < 5; ++attempt)
    {
      const std::int64_t id = this->transaction(
        WriteBegin,
        [&]
        {
          Params()
            .bytes(texts.scene)
            .text(texts.scene)
            .exec(this->Conn,
                  "INSERT INTO scenes (content_hash, description, description_text) "
                  "VALUES (sha256($1), $2::jsonb, $2) ON CONFLICT (content_hash) DO NOTHING",
                  "storing the scene failed");
          Result found =
            Params()
              .bytes(texts.scene)
              .exec(this->Conn, "SELECT id FROM scenes WHERE content_hash = sha256($1)",
                    "finding the scene failed");
          const std::int64_t sceneId = PQntuples(found.get()) ? getI64(found.get(), 0, 0) : -1;
          exec(this->Conn, "COMMIT", "committing the scene failed");
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

  /// Removes scene rows that no frame uses: `sceneId`'s, or all of them when it is negative.
  /// They are left by a failed write (the scene row is committed before the frame's transaction)
  /// or by the deletion of a scene's last frame. A row that a frame being written refers to is
  /// locked by that writer and skipped; a writer that looked the row up but has not referred to it
  /// yet looks it up again (SceneVanished). Best effort and never throws: the caller may be
  /// handling another error, and an unused scene row is only a few kB of description that the
  /// next write of the scene reuses.
  void dropUnusedScenes(std::int64_t sceneId) noexcept
  {
    if (PQstatus(this->Conn) != CONNECTION_OK || PQtransactionStatus(this->Conn) != PQTRANS_IDLE)
    {
      return;
    }
    try
    {
      Params().i64(sceneId).exec(
        this->Conn,
        "DELETE FROM scenes WHERE id IN (SELECT s.id FROM scenes s WHERE ($1 < 0 OR s.id = $1) "
        "AND NOT EXISTS (SELECT 1 FROM frames f WHERE f.scene_id = s.id) FOR UPDATE SKIP LOCKED)",
        "removing an unused scene failed");
    }
    catch (const StoreError&)
    {
      // A frame committed in the meantime refers to it (foreign key): it stays, as it should.
    }
  }

  /// Drops the tables of rays whose frame is gone: those of a replaced frame, or of frames
  /// deleted with plain SQL. Dropping a table of ray_blocks locks ray_blocks exclusively, so this
  /// waits at most a moment for reads under way and otherwise leaves the tables for a later call
  /// (rays_v and readFrame never show them). Never throws.
  void dropOrphanBlocks() noexcept
  {
    if (PQstatus(this->Conn) != CONNECTION_OK || PQtransactionStatus(this->Conn) != PQTRANS_IDLE)
    {
      return;
    }
    dropUnattachedTiles(this->Conn);
    try
    {
      this->transaction(
        WriteBegin,
        [&]
        {
          Result r = exec(this->Conn,
                          "SELECT m[1]::bigint, m[2]::integer FROM pg_inherits i JOIN pg_class c "
                          "ON c.oid = i.inhrelid CROSS JOIN LATERAL regexp_match(c.relname::text, "
                          "'^ray_blocks_([0-9]+)_([0-9]+)$') AS m WHERE i.inhparent = "
                          "'ray_blocks'::regclass AND NOT EXISTS (SELECT 1 FROM frames f WHERE "
                          "f.id = m[1]::bigint)",
                          "looking for the rays of deleted frames failed");
          std::string tables;
          for (int row = 0; row < PQntuples(r.get()); ++row)
          {
            tables += (tables.empty() ? "" : ", ") +
                      blockTable(getI64(r.get(), row, 0), getI32(r.get(), row, 1));
          }
          if (!tables.empty())
          {
            exec(this->Conn, "SET LOCAL lock_timeout = '2s'", "setting a lock timeout failed");
            exec(this->Conn, "DROP TABLE IF EXISTS " + tables,
                 "dropping the rays of deleted frames failed");
          }
          exec(this->Conn, "COMMIT", "committing failed");
        });
    }
    catch (const StoreError&)
    {
      // Left for a later call.
    }
  }
};

namespace
{
/// Runs a script of several statements (the migrations).
void execScript(PGconn* conn, const std::string& sql, const std::string& what)
{
  Result r(PQexec(conn, sql.c_str()));
  if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
  {
    fail(what, conn, r.get());
  }
}

void runMigration(PGconn* conn, int version)
{
  const std::string what = "migration to schema version " + std::to_string(version) + " failed";
  if (version == 1)
  {
    execScript(conn, migration1(), what);
  }
  else if (version == 2)
  {
    execScript(conn, migration2(), what);
  }
  else
  {
    execScript(conn, migration3Tables(), what);
    Result tiles =
      exec(conn, "SELECT DISTINCT frame_id, tile FROM ray_blocks ORDER BY frame_id, tile", what);
    for (int row = 0; row < PQntuples(tiles.get()); ++row)
    {
      const std::int64_t frame = getI64(tiles.get(), row, 0);
      const std::int32_t tile = getI32(tiles.get(), row, 1);
      exec(conn, createBlockTable(frame, tile), what);
      exec(conn, convertTileV2(frame, tile), what);
      exec(conn, attachBlockTable("ray_blocks_v3", frame, tile), what);
    }
    execScript(conn, migration3Finish(), what);
  }
}
}

RayStore::RayStore(const std::string& conninfo)
  : P(new Impl)
{
  std::string error;
  this->P->Conn = openConnection(conninfo, error);
  if (!this->P->Conn)
  {
    delete this->P;
    throw StoreError(error);
  }
  this->P->Conninfo = conninfo;
}

RayStore::~RayStore()
{
  PQfinish(this->P->Conn);
  for (PGconn* c : this->P->Helpers)
  {
    PQfinish(c);
  }
  delete this->P;
}

int RayStore::backendPid() const
{
  return PQbackendPID(this->P->Conn);
}

int RayStore::schemaVersion()
{
  this->P->ensureConnected();
  return this->P->readVersion();
}

void RayStore::migrate(int targetVersion)
{
  if (targetVersion < 1 || targetVersion > kSchemaVersion)
  {
    throw StoreError("cannot migrate to schema version " + std::to_string(targetVersion) +
                     ": this build knows versions 1 to " + std::to_string(kSchemaVersion));
  }
  this->P->ensureConnected();
  this->P->SchemaChecked = false;
  PGconn* conn = this->P->Conn;
  this->P->transaction(
    WriteBegin,
    [&]
    {
      // Concurrent migrators wait for each other instead of failing on each other's tables.
      exec(conn, "SELECT pg_advisory_xact_lock(1095979604)", "locking the schema failed");
      const int v = this->P->readVersion();
      if (v > kSchemaVersion)
      {
        throw StoreError("schema version mismatch: found " + std::to_string(v) +
                         ", this build knows " + std::to_string(kSchemaVersion) +
                         "; refusing to touch a database written by a newer ASRT");
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
        exec(conn, "DELETE FROM schema_version", "recording the schema version failed");
        Params()
          .i32(targetVersion)
          .exec(conn, "INSERT INTO schema_version (version) VALUES ($1)",
                "recording the schema version failed");
      }
      exec(conn, "COMMIT", "committing the migration failed");
    });
  if (targetVersion == kSchemaVersion)
  {
    this->P->dropOrphanBlocks();
    this->P->dropUnusedScenes(-1);
  }
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  const std::vector<RayRecord>& records, bool replace,
                                  double traceSeconds)
{
  return this->writeFrame(scene, label, records, std::vector<RayPath>(), replace, traceSeconds);
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  const std::vector<RayRecord>& records,
                                  const std::vector<RayPath>& paths, bool replace,
                                  double traceSeconds)
{
  return this->writeFrame(
    scene, label, records.size(), [&records](std::size_t k, RayRecord& r) { r = records[k]; },
    replace, traceSeconds, paths, true);
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  std::size_t count,
                                  const std::function<void(std::size_t, RayRecord&)>& next,
                                  bool replace, double traceSeconds,
                                  const std::vector<RayPath>& paths, bool concurrentProducer)
{
  const auto start = std::chrono::steady_clock::now();
  requireText(label, "the label");
  requireText(scene.name, "the scene name");
  const SceneTexts texts = sceneTexts(scene);
  checkPaths(scene, paths);
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  // A large frame from a producer that any thread may call goes in as several tiles, each over a
  // connection of its own: one backend alone is the bottleneck of a write (bench/REPORT.md).
  std::vector<PGconn*> helpers;
  if (concurrentProducer && count >= kParallelMinRays)
  {
    helpers = this->P->helpers(
      int(std::min<std::size_t>(std::size_t(this->P->WriteConnections), count / kParallelMinRays)) -
      1);
  }
  std::vector<std::size_t> bounds;
  for (std::size_t k = 0; k <= helpers.size(); ++k)
  {
    // Whole rows of kBlockSize rays in every tile but the last.
    bounds.push_back(count * k / (helpers.size() + 1) / kBlockSize * kBlockSize);
  }
  bounds.push_back(count);
  const int tiles = int(helpers.size()) + 1;
  for (int attempt = 0;; ++attempt)
  {
    const std::int64_t sceneId = this->P->sceneRow(texts);
    bool replaced = false;
    std::int64_t writingId = -1; // the frame of a parallel write, once it has an id
    try
    {
      const std::int64_t frameId = this->P->transaction(
        WriteBegin,
        [&]
        {
          Result r =
            Params()
              .bytes(texts.frame)
              .exec(conn,
                    "SELECT id, label, status FROM frames WHERE frame_hash = sha256($1) FOR UPDATE",
                    "looking for an existing frame failed");
          if (PQntuples(r.get()) > 0)
          {
            const std::int64_t old = getI64(r.get(), 0, 0);
            if (getText(r.get(), 0, 2) != "complete")
            {
              // Replacing it would pull the frame from under the ranks writing its tiles.
              throw StoreError("duplicate frame: this scene with these parameters is being "
                               "written as tiled frame " +
                               std::to_string(old) + " (label \"" + getText(r.get(), 0, 1) +
                               "\"); delete it first if its writers are gone");
            }
            deleteReplaced(conn, old, getText(r.get(), 0, 1), replace);
            replaced = true;
          }

          try
          {
            r = insertFrame(conn, sceneId, texts, scene, label, tiles, false);
          }
          catch (const StoreError& e)
          {
            if (e.sqlState() == "23505")
            {
              // Another writer stored the same frame between our check and our insert.
              throw StoreError("duplicate frame: this scene with these parameters was just "
                               "stored by another writer; pass replace = true to replace it",
                               e.sqlState());
            }
            throw;
          }
          const std::int64_t id = getI64(r.get(), 0, 0);
          if (tiles > 1)
          {
            writingId = id;
          }

          if (tiles == 1)
          {
            copyTile(conn, id, 0, count, next);
          }
          else
          {
            Params().i64(id).exec(conn, writerLock("pg_advisory_xact_lock"),
                                  "locking the frame failed");
            {
              HelperLoads others(helpers, id, bounds, next);
              try
              {
                loadTile(conn, id, 0, 0, bounds[1], others.checked(next));
              }
              catch (...)
              {
                others.fail();
                throw;
              }
              others.join();
              others.rethrow();
            }
            // Attached together at the end: ATTACH PARTITION locks ray_blocks against other
            // writers' attachments, so it waits for no COPY.
            for (int tile = 0; tile < tiles; ++tile)
            {
              if (bounds[std::size_t(tile) + 1] > bounds[std::size_t(tile)])
              {
                exec(conn, attachBlockTable("ray_blocks", id, tile), "attaching the rays failed");
              }
            }
          }
          copyPaths(conn, id, paths);
          for (int tile = 0; tile < tiles; ++tile)
          {
            Params()
              .i64(id)
              .i32(tile)
              .i64(std::int64_t(bounds[std::size_t(tile) + 1] - bounds[std::size_t(tile)]))
              .exec(conn,
                    "INSERT INTO frame_tiles (frame_id, tile, ray_count, written_at) VALUES ($1, "
                    "$2, $3, clock_timestamp())",
                    "recording the frame's rays failed");
          }

          const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          Params()
            .i64(id)
            .i64(std::int64_t(count))
            .f64(seconds)
            .f64(traceSeconds)
            .exec(conn,
                  "UPDATE frames SET status = 'complete', ray_count = $2, write_seconds = $3, "
                  "trace_seconds = nullif($4, 'NaN'), completed_at = clock_timestamp() WHERE id "
                  "= $1",
                  "completing the frame failed");
          exec(conn, "COMMIT", "committing the frame failed");
          return id;
        });
      if (replaced)
      {
        this->P->dropOrphanBlocks();
      }
      return frameId;
    }
    catch (const SceneVanished&)
    {
      if (attempt == 4)
      {
        throw StoreError("writing the frame failed: its scene row kept disappearing under "
                         "concurrent deletions");
      }
    }
    catch (...)
    {
      if (writingId >= 0)
      {
        // What the helpers committed (the main connection may be the one that broke).
        dropUnattachedTiles(PQstatus(conn) == CONNECTION_OK ? conn : helpers.front(), writingId);
      }
      this->P->dropUnusedScenes(sceneId);
      throw;
    }
  }
}

void RayStore::setWriteConnections(int n)
{
  if (n < 1)
  {
    throw StoreError("a write needs at least one connection (got " + std::to_string(n) + ")");
  }
  this->P->WriteConnections = n;
}

int RayStore::writeConnections() const
{
  return this->P->WriteConnections;
}

std::int64_t RayStore::beginTiledFrame(const SceneDescription& scene, const std::string& label,
                                       int tileCount, bool replace)
{
  if (tileCount < 1)
  {
    throw StoreError("a tiled frame needs at least one tile (got " + std::to_string(tileCount) +
                     ")");
  }
  requireText(label, "the label");
  requireText(scene.name, "the scene name");
  const SceneTexts texts = sceneTexts(scene);
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  // Every rank runs this at about the same time. INSERT ... ON CONFLICT DO NOTHING waits for a
  // concurrent inserter of the same identity and then yields to it, so that all agree on its row.
  // The row can still vanish between that and the SELECT (a concurrent replace or delete), and so
  // can the scene's row before the frame's refers to it: then try again.
  for (int attempt = 0; attempt < 10; ++attempt)
  {
    const std::int64_t sceneId = this->P->sceneRow(texts);
    bool replaced = false;
    std::optional<std::int64_t> id;
    try
    {
      id = this->P->transaction(
        WriteBegin,
        [&]() -> std::optional<std::int64_t>
        {
          Result r = insertFrame(conn, sceneId, texts, scene, label, tileCount, true);
          if (PQntuples(r.get()) == 0)
          {
            r = Params()
                  .bytes(texts.frame)
                  .exec(conn,
                        "SELECT id, status, tile_count, label FROM frames WHERE frame_hash = "
                        "sha256($1) FOR UPDATE",
                        "looking for the frame failed");
            if (PQntuples(r.get()) == 0)
            {
              exec(conn, "ROLLBACK", "ending the transaction failed");
              return std::nullopt;
            }
            const std::int64_t old = getI64(r.get(), 0, 0);
            const std::string status = getText(r.get(), 0, 1);
            const int oldTiles = getI32(r.get(), 0, 2);
            if (status == "writing")
            {
              if (oldTiles != tileCount)
              {
                throw StoreError("frame " + std::to_string(old) +
                                 " of this scene is being written as " + std::to_string(oldTiles) +
                                 " tiles, not " + std::to_string(tileCount));
              }
              exec(conn, "COMMIT", "committing the frame failed");
              return old;
            }
            deleteReplaced(conn, old, getText(r.get(), 0, 3), replace);
            replaced = true;
            // No conflict is possible any more: the old row is deleted and locked by us.
            r = insertFrame(conn, sceneId, texts, scene, label, tileCount, false);
          }
          const std::int64_t frameId = getI64(r.get(), 0, 0);
          exec(conn, "COMMIT", "committing the frame failed");
          return frameId;
        });
    }
    catch (const SceneVanished&)
    {
      continue;
    }
    catch (...)
    {
      this->P->dropUnusedScenes(sceneId);
      throw;
    }
    if (replaced)
    {
      this->P->dropOrphanBlocks();
    }
    if (id)
    {
      return *id;
    }
  }
  throw StoreError("starting the tiled frame failed: its row kept disappearing under concurrent "
                   "replacements or deletions");
}
void RayStore::writeTile(std::int64_t frameId, int tile, const std::vector<RayRecord>& records)
{
  this->writeTile(frameId, tile, records.size(),
                  [&records](std::size_t k, RayRecord& r) { r = records[k]; });
}

void RayStore::writeTile(std::int64_t frameId, int tile, std::size_t count,
                         const std::function<void(std::size_t, RayRecord&)>& next)
{
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  const std::string which = "tile " + std::to_string(tile) + " of frame " + std::to_string(frameId);
  this->P->transaction(
    WriteBegin,
    [&]
    {
      // FOR KEY SHARE keeps the frame from being deleted under the COPY without blocking the
      // other tiles' writers (the foreign keys take the same lock anyway).
      Result r = Params().i64(frameId).i32(tile).exec(
        conn,
        "SELECT f.status, f.tile_count, EXISTS (SELECT 1 FROM frame_tiles t WHERE t.frame_id = "
        "f.id AND t.tile = $2) FROM frames f WHERE f.id = $1 FOR KEY SHARE OF f",
        "looking for the frame failed");
      if (PQntuples(r.get()) == 0)
      {
        throw StoreError("writing " + which + " failed: there is no such frame");
      }
      const int tileCount = getI32(r.get(), 0, 1);
      if (PQgetvalue(r.get(), 0, 2)[0] != 0)
      {
        throw StoreError("writing " + which + " failed: the tile is already written");
      }
      if (getText(r.get(), 0, 0) != "writing")
      {
        throw StoreError("writing " + which + " failed: the frame is complete");
      }
      if (tile < 0 || tile >= tileCount)
      {
        throw StoreError("writing " + which + " failed: the frame has tiles 0 to " +
                         std::to_string(tileCount - 1));
      }
      try
      {
        copyTile(conn, frameId, tile, count, next);
        Params()
          .i64(frameId)
          .i32(tile)
          .i64(std::int64_t(count))
          .exec(conn,
                "INSERT INTO frame_tiles (frame_id, tile, ray_count, written_at) VALUES ($1, $2, "
                "$3, clock_timestamp())",
                "recording the tile failed");
      }
      catch (const StoreError& e)
      {
        if (e.sqlState() == "23505" || e.sqlState() == "42P07")
        {
          // A concurrent writer of the same tile committed first (its row of frame_tiles, or its
          // table of rays, exists).
          throw StoreError("writing " + which + " failed: the tile is already written",
                           e.sqlState());
        }
        throw;
      }
      // Only now, after the COPY, is the frame row locked, so tiles are written in parallel and
      // only this short step is serialised. Under the lock, the count (a fresh snapshot) sees
      // every tile committed before and this one: of two last tiles committing together, the
      // second to get the lock sees the first's row and completes the frame. FOR NO KEY UPDATE,
      // not FOR UPDATE, which would conflict with the other writers' key-share locks and
      // deadlock two of them.
      Params().i64(frameId).exec(conn, "SELECT 1 FROM frames WHERE id = $1 FOR NO KEY UPDATE",
                                 "locking the frame failed");
      r = Params().i64(frameId).exec(
        conn,
        "SELECT count(*), coalesce(sum(ray_count), 0)::bigint FROM frame_tiles WHERE frame_id = $1",
        "counting the tiles failed");
      if (getI64(r.get(), 0, 0) == tileCount)
      {
        Params()
          .i64(frameId)
          .i64(getI64(r.get(), 0, 1))
          .exec(conn,
                "UPDATE frames SET status = 'complete', ray_count = $2, write_seconds = "
                "extract(epoch FROM clock_timestamp() - created_at), completed_at = "
                "clock_timestamp() WHERE id = $1",
                "completing the frame failed");
      }
      exec(conn, "COMMIT", "committing the tile failed");
    });
}

std::vector<std::int64_t> RayStore::abandonedFrames(std::chrono::seconds olderThan)
{
  this->P->requireSchema();
  Result r = Params()
               .i64(std::int64_t(olderThan.count()))
               .exec(this->P->Conn,
                     "SELECT f.id FROM frames f WHERE f.status = 'writing' AND coalesce((SELECT "
                     "max(t.written_at) FROM frame_tiles t WHERE t.frame_id = f.id), f.created_at) "
                     "< clock_timestamp() - $1::float8 * interval '1 second' ORDER BY f.id",
                     "looking for abandoned frames failed");
  std::vector<std::int64_t> ids;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    ids.push_back(getI64(r.get(), row, 0));
  }
  return ids;
}

std::vector<FrameInfo> RayStore::listFrames()
{
  this->P->requireSchema();
  Result r = exec(this->P->Conn, std::string("SELECT ") + FrameColumns + " ORDER BY f.id",
                  "listing the frames failed");
  std::vector<FrameInfo> frames;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    frames.push_back(frameFromRow(r.get(), row));
  }
  return frames;
}

FrameInfo RayStore::frameInfo(std::int64_t id)
{
  this->P->requireSchema();
  Result r =
    Params().i64(id).exec(this->P->Conn, std::string("SELECT ") + FrameColumns + " AND f.id = $1",
                          "reading the frame failed");
  if (PQntuples(r.get()) == 0)
  {
    throw StoreError("there is no frame " + std::to_string(id));
  }
  return frameFromRow(r.get(), 0);
}

std::string RayStore::frameSceneText(std::int64_t id)
{
  this->P->requireSchema();
  Result r = Params().i64(id).exec(
    this->P->Conn, "SELECT effective_text FROM frames WHERE id = $1 AND status = 'complete'",
    "reading the frame's scene failed");
  if (PQntuples(r.get()) == 0)
  {
    throw StoreError("there is no frame " + std::to_string(id));
  }
  return std::string(PQgetvalue(r.get(), 0, 0), static_cast<size_t>(PQgetlength(r.get(), 0, 0)));
}

std::optional<std::int64_t> RayStore::findFrame(const SceneDescription& scene)
{
  const SceneTexts texts = sceneTexts(scene);
  this->P->requireSchema();
  Result r = Params()
               .bytes(texts.frame)
               .exec(this->P->Conn,
                     "SELECT id FROM frames WHERE frame_hash = sha256($1) AND status = 'complete'",
                     "looking for the frame failed");
  if (PQntuples(r.get()) == 0)
  {
    return std::nullopt;
  }
  return getI64(r.get(), 0, 0);
}

void RayStore::deleteFrame(std::int64_t id)
{
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  const std::int64_t sceneId = this->P->transaction(
    WriteBegin,
    [&]
    {
      // The row lock waits for the writers of its tiles (they hold it in key-share mode), so that
      // no table of rays is attached after the ones dropped here.
      Result r = Params().i64(id).exec(conn, "SELECT scene_id FROM frames WHERE id = $1 FOR UPDATE",
                                       "deleting the frame failed");
      if (PQntuples(r.get()) == 0)
      {
        throw StoreError("there is no frame " + std::to_string(id) + " to delete");
      }
      const std::int64_t scene = getI64(r.get(), 0, 0);
      Result tiles = Params().i64(id).exec(
        conn, "SELECT tile FROM frame_tiles WHERE frame_id = $1 AND ray_count > 0 ORDER BY tile",
        "deleting the frame failed");
      Params().i64(id).exec(conn, "DELETE FROM frames WHERE id = $1", "deleting the frame failed");
      std::string tables;
      for (int row = 0; row < PQntuples(tiles.get()); ++row)
      {
        tables += (tables.empty() ? "" : ", ") + blockTable(id, getI32(tiles.get(), row, 0));
      }
      if (!tables.empty())
      {
        exec(conn, "DROP TABLE " + tables, "deleting the frame's rays failed");
      }
      exec(conn, "COMMIT", "committing the deletion failed");
      return scene;
    });
  this->P->dropUnusedScenes(sceneId);
}

std::vector<RayRecord> RayStore::readFrame(std::int64_t id, const std::string& predicate)
{
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  // REPEATABLE READ: the frame row, its tiles and its rays come from one snapshot. Always rolled
  // back, so that nothing a predicate might have done (set_config, ...) outlives the read.
  return this->P->transaction(
    ReadBegin,
    [&]
    {
      Result r = Params().i64(id).exec(
        conn, "SELECT ray_count FROM frames WHERE id = $1 AND status = 'complete'",
        "reading the frame failed");
      if (PQntuples(r.get()) == 0)
      {
        throw StoreError("there is no frame " + std::to_string(id));
      }
      const std::int64_t rayCount = getI64(r.get(), 0, 0);
      const std::string frame = "frame " + std::to_string(id);
      std::vector<RayRecord> records;
      if (predicate.empty())
      {
        // Where each tile's rays start in the frame, and how many it has.
        struct TileRays
        {
          std::int64_t base, count;
        };
        std::vector<std::pair<std::int32_t, TileRays>> tiles;
        r = Params().i64(id).exec(
          conn, "SELECT tile, ray_count FROM frame_tiles WHERE frame_id = $1 ORDER BY tile",
          "reading the frame's tiles failed");
        std::int64_t base = 0;
        for (int row = 0; row < PQntuples(r.get()); ++row)
        {
          const std::int64_t count = getI64(r.get(), row, 1);
          tiles.push_back({ getI32(r.get(), row, 0), { base, count } });
          base += count;
        }
        if (base != rayCount)
        {
          throw StoreError(frame + " is inconsistent: it says " + std::to_string(rayCount) +
                           " rays, its tiles " + std::to_string(base));
        }
        // Tiles of a large frame are read over several connections at once, from one snapshot
        // (exported by this transaction), each decoded on a thread of its own; the tiles are
        // shared out by their rays.
        std::vector<PGconn*> helpers;
        if (tiles.size() > 1 && rayCount >= std::int64_t(2 * kParallelMinRays))
        {
          helpers = this->P->helpers(
            int(std::min<std::size_t>(std::size_t(this->P->WriteConnections), tiles.size())) - 1);
        }
        records = allocateRecords(std::size_t(rayCount));
        std::vector<std::string> groups(helpers.size() + 1);
        {
          std::vector<std::int64_t> load(groups.size(), 0);
          for (const auto& t : tiles)
          {
            const std::size_t g =
              std::size_t(std::min_element(load.begin(), load.end()) - load.begin());
            groups[g] += (groups[g].empty() ? "" : ",") + std::to_string(t.first);
            load[g] += t.second.count;
          }
        }
        std::string snapshot;
        if (!helpers.empty())
        {
          r = exec(conn, "SELECT pg_export_snapshot()", "reading the rays failed");
          snapshot = getText(r.get(), 0, 0);
          // The server's name for it; checked all the same before it goes into SQL.
          if (snapshot.empty() ||
              snapshot.find_first_not_of("0123456789ABCDEFabcdef-") != std::string::npos)
          {
            throw StoreError("reading the rays failed: unexpected snapshot name \"" + snapshot +
                             "\"");
          }
        }
        // Rows come in whatever order the server finds them; each says where its rays go. The
        // table's keys and checks (one row per block, first_ray = kBlockSize × block, n ≤
        // kBlockSize) make the rows' ranges disjoint, so a count that adds up covers every ray
        // exactly once.
        auto readTiles = [&](PGconn* c, const std::string& group) -> std::int64_t
        {
          // A parallel plan would only copy the rows once more, between processes.
          exec(c, "SELECT set_config('max_parallel_workers_per_gather', '0', true)",
               "reading the rays failed");
          std::int64_t got = 0;
          Params()
            .i64(id)
            .text("{" + group + "}")
            .stream(
              c,
              "SELECT tile, first_ray, n, data FROM ray_blocks WHERE frame_id = $1 AND tile = "
              "ANY($2::integer[])",
              "reading the rays failed",
              [&](const PGresult* row)
              {
                const std::int32_t tile = getI32(row, 0, 0);
                const std::int64_t first = getI64(row, 0, 1);
                const std::int32_t n = getI32(row, 0, 2);
                const auto t = std::find_if(tiles.begin(), tiles.end(),
                                            [&](const auto& x) { return x.first == tile; });
                if (t == tiles.end() || n < 1 || n > kBlockSize || first < 0 ||
                    first + n > t->second.count ||
                    PQgetlength(row, 0, 3) != std::int64_t(n) * kRecordBytes)
                {
                  throw StoreError("reading the rays of " + frame +
                                   " failed: a stored block (tile " + std::to_string(tile) +
                                   ", first ray " + std::to_string(first) +
                                   ") does not fit the frame");
                }
                const char* p = PQgetvalue(row, 0, 3);
                RayRecord* out = &records[std::size_t(t->second.base + first)];
                for (int m = 0; m < n; ++m, p += kRecordBytes)
                {
                  decodeRecord(p, out[m]);
                }
                got += n;
              });
          return got;
        };
        std::vector<std::int64_t> gots(helpers.size(), 0);
        std::vector<std::exception_ptr> errors(helpers.size());
        std::vector<std::thread> threads;
        for (std::size_t k = 0; k < helpers.size(); ++k)
        {
          threads.emplace_back(
            [&, k]
            {
              PGconn* c = helpers[k];
              try
              {
                exec(c, ReadBegin, "starting a transaction failed");
                exec(c, "SET TRANSACTION SNAPSHOT '" + snapshot + "'", "reading the rays failed");
                gots[k] = readTiles(c, groups[k + 1]);
                exec(c, "ROLLBACK", "ending the read failed");
              }
              catch (...)
              {
                rollback(c);
                errors[k] = std::current_exception();
              }
            });
        }
        std::int64_t got = 0;
        std::exception_ptr mainError;
        try
        {
          got = readTiles(conn, groups[0]);
        }
        catch (...)
        {
          mainError = std::current_exception();
        }
        for (std::thread& t : threads)
        {
          t.join();
        }
        if (mainError)
        {
          std::rethrow_exception(mainError);
        }
        for (std::size_t k = 0; k < helpers.size(); ++k)
        {
          if (errors[k])
          {
            std::rethrow_exception(errors[k]);
          }
          got += gots[k];
        }
        if (got != rayCount)
        {
          throw StoreError(frame + " is inconsistent: it says " + std::to_string(rayCount) +
                           " rays, its blocks hold " + std::to_string(got));
        }
      }
      else
      {
        Params()
          .text(std::to_string(this->PredicateTimeout.count()) + "ms")
          .exec(conn, "SELECT set_config('statement_timeout', $1, true)",
                "setting the predicate's time limit failed");
        // The predicate is the one deliberate splice (see the header). The frame restriction is
        // inside the sub-select, so text that closes the parentheses still sees only this frame;
        // the extended protocol refuses a second statement; READ ONLY refuses writes. The server
        // evaluates it and sends the selected records only, in any order.
        std::vector<std::pair<std::int64_t, RayRecord>> selected;
        Params().i64(id).stream(
          conn,
          "SELECT r.ray, r.record_bytes FROM (SELECT * FROM rays_v WHERE frame_id = $1) r "
          "WHERE (" +
            predicate + "\n)",
          "the ray predicate failed",
          [&](const PGresult* row)
          {
            const std::int64_t ray = getI64(row, 0, 0);
            if (PQgetisnull(row, 0, 0) || ray < 0 || ray >= rayCount ||
                PQgetlength(row, 0, 1) != kRecordBytes)
            {
              throw StoreError("the ray predicate failed: its query gave a row that is no ray of " +
                               frame);
            }
            selected.emplace_back(ray, RayRecord());
            decodeRecord(PQgetvalue(row, 0, 1), selected.back().second);
          });
        std::sort(selected.begin(), selected.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        records.reserve(selected.size());
        for (std::size_t k = 0; k < selected.size(); ++k)
        {
          if (k > 0 && selected[k].first == selected[k - 1].first)
          {
            throw StoreError("the ray predicate failed: its query gave ray " +
                             std::to_string(selected[k].first) + " twice");
          }
          records.push_back(selected[k].second);
        }
      }
      exec(conn, "ROLLBACK", "ending the read failed");
      return records;
    });
}

std::vector<RayPath> RayStore::readPaths(std::int64_t id)
{
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  return this->P->transaction(
    ReadBegin,
    [&]
    {
      Result r =
        Params().i64(id).exec(conn, "SELECT 1 FROM frames WHERE id = $1 AND status = 'complete'",
                              "reading the frame failed");
      if (PQntuples(r.get()) == 0)
      {
        throw StoreError("there is no frame " + std::to_string(id));
      }
      std::vector<RayPath> paths;
      Params().i64(id).stream(
        conn, "SELECT i, j, termination, n, points FROM ray_paths WHERE frame_id = $1 ORDER BY seq",
        "reading the paths failed",
        [&](const PGresult* row)
        {
          RayPath p;
          p.i = getI32(row, 0, 0);
          p.j = getI32(row, 0, 1);
          p.termination = Termination(getI32(row, 0, 2));
          const std::int32_t n = getI32(row, 0, 3);
          if (n < 0 || PQgetlength(row, 0, 4) != std::int64_t(n) * PathPointBytes)
          {
            throw StoreError("reading the paths of frame " + std::to_string(id) +
                             " failed: the path of pixel (" + std::to_string(p.i) + ", " +
                             std::to_string(p.j) + ") is malformed");
          }
          decodePoints(PQgetvalue(row, 0, 4), std::size_t(n), p.points);
          paths.push_back(std::move(p));
        });
      exec(conn, "ROLLBACK", "ending the read failed");
      return paths;
    });
}
}
