#include "RayStore.h"

#include <libpq-fe.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>

namespace asrt
{
namespace
{
// ---------------------------------------------------------------------------------------------
// The per-ray fields, in storage order. Each is moved as a 32- or 64-bit word so that doubles
// keep every bit (NaN payloads, −0, denormals).
enum class Kind
{
  I32,
  I64,
  F64
};

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

struct Column
{
  const char* name;
  Kind kind;
  std::uint64_t (*get)(const RayRecord&);
  void (*set)(RayRecord&, std::uint64_t);
};

#define ASRT_F64(n, e)                                                                             \
  Column                                                                                           \
  {                                                                                                \
    n, Kind::F64, [](const RayRecord& r) { return bitsOf(e); },                                    \
      [](RayRecord& r, std::uint64_t w) { e = doubleOf(w); }                                       \
  }
#define ASRT_I32(n, e)                                                                             \
  Column                                                                                           \
  {                                                                                                \
    n, Kind::I32,                                                                                  \
      [](const RayRecord& r) { return std::uint64_t(std::uint32_t(std::int32_t(e))); },            \
      [](RayRecord& r, std::uint64_t w) { e = std::int32_t(std::uint32_t(w)); }                    \
  }

const Column Columns[] = {
  ASRT_I32("i", r.i),
  ASRT_I32("j", r.j),
  ASRT_F64("origin_x", r.origin.x()),
  ASRT_F64("origin_y", r.origin.y()),
  ASRT_F64("origin_z", r.origin.z()),
  ASRT_F64("dir_x", r.direction.x()),
  ASRT_F64("dir_y", r.direction.y()),
  ASRT_F64("dir_z", r.direction.z()),
  ASRT_F64("p_t", r.momentum[0]),
  ASRT_F64("p_x", r.momentum[1]),
  ASRT_F64("p_y", r.momentum[2]),
  ASRT_F64("p_z", r.momentum[3]),
  Column{ "termination", Kind::I32,
          [](const RayRecord& r) { return std::uint64_t(std::uint32_t(r.termination)); },
          [](RayRecord& r, std::uint64_t w) { r.termination = Termination(std::int32_t(w)); } },
  ASRT_I32("object_id", r.objectId),
  ASRT_F64("hit_x", r.hitPoint.x()),
  ASRT_F64("hit_y", r.hitPoint.y()),
  ASRT_F64("hit_z", r.hitPoint.z()),
  ASRT_F64("normal_x", r.hitNormal.x()),
  ASRT_F64("normal_y", r.hitNormal.y()),
  ASRT_F64("normal_z", r.hitNormal.z()),
  ASRT_F64("u", r.u),
  ASRT_F64("v", r.v),
  ASRT_F64("chord_error", r.chordError),
  ASRT_F64("path_length", r.affineLength),
  ASRT_F64("winding", r.winding),
  ASRT_I32("image_order", r.imageOrder),
  Column{ "steps", Kind::I64, [](const RayRecord& r) { return std::uint64_t(r.steps); },
          [](RayRecord& r, std::uint64_t w) { r.steps = std::int64_t(w); } },
  ASRT_F64("max_abs_h", r.maxAbsH),
  ASRT_F64("color_r", r.color.x()),
  ASRT_F64("color_g", r.color.y()),
  ASRT_F64("color_b", r.color.z()),
  ASRT_F64("dudi", r.dudi),
  ASRT_F64("dudj", r.dudj),
  ASRT_F64("dvdi", r.dvdi),
  ASRT_F64("dvdj", r.dvdj),
};
#undef ASRT_F64
#undef ASRT_I32
constexpr int NumColumns = int(sizeof(Columns) / sizeof(Columns[0]));

int wordSize(Kind k)
{
  return k == Kind::I32 ? 4 : 8;
}

// ---------------------------------------------------------------------------------------------
// The schema. Migration N takes version N−1 to N; each runs inside migrate()'s transaction.

std::string columnList(const char* prefix)
{
  std::string s;
  for (const Column& c : Columns)
  {
    s += ", ";
    s += prefix;
    s += c.name;
  }
  return s;
}

// SQL decoding of the stored big-endian words. The double is rebuilt from sign, exponent and
// mantissa with exact operations (products by powers of two); NaN payloads are not kept in SQL,
// only in readFrame. Written out per column rather than as SQL functions: a function whose
// argument is used several times is not inlined, and the call overhead would dominate.
std::string wordExpr(const std::string& bytes, int size)
{
  return "('x' || encode(substr(" + bytes + ", " + std::to_string(size) + " * k + 1, " +
         std::to_string(size) + "), 'hex'))::bit(" + std::to_string(8 * size) +
         ")::" + (size == 4 ? "integer" : "bigint");
}

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

// One row per ray. Each block's values are detoasted once (the OFFSET 0 sub-select) rather than
// once per ray; columns a query does not use are neither detoasted nor decoded. Version 1 is kept
// exactly as it was created, since migration 2 starts from it.
std::string raysView(int version)
{
  std::string s;
  if (version == 1)
  {
    s += "CREATE VIEW rays_v AS SELECT b.frame_id, b.block, b.first_ray + k AS ray";
  }
  else
  {
    // first_ray counts within the tile (a rank does not know the sizes of the other tiles); ray
    // numbers the frame as readFrame() returns it, tile after tile. Only complete frames are
    // shown: the committed tiles of a frame still being written are nobody's business.
    s += "CREATE VIEW rays_v AS SELECT b.frame_id, b.tile, b.block, o.base + b.first_ray + k AS "
         "ray, b.first_ray + k AS tile_ray";
  }
  for (const Column& c : Columns)
  {
    const std::string w = wordExpr("d." + std::string(c.name), wordSize(c.kind));
    s += ",\n  " + (c.kind == Kind::F64 ? float8Expr(w) : w) + " AS " + c.name;
  }
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
  s += raysView(1);
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
)SQL" + raysView(2);
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
    std::vector<const char*> values;
    std::vector<int> lengths;
    for (const std::string& v : this->Values)
    {
      values.push_back(v.data());
      lengths.push_back(int(v.size()));
    }
    Result r(PQexecParams(conn, sql.c_str(), int(values.size()), this->Types.data(), values.data(),
                          lengths.data(), this->Formats.data(), 1));
    const ExecStatusType st = r ? PQresultStatus(r.get()) : PGRES_FATAL_ERROR;
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK)
    {
      fail(what, conn, r.get());
    }
    return r;
  }

private:
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
  "f.tile_count "
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
  k.mass = getF64(r, row, c++);
  k.spin = getF64(r, row, c++);
  k.charge = getF64(r, row, c++);
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

/// Binary COPY output, streamed to the server in ~1 MB messages.
class CopyWriter
{
public:
  explicit CopyWriter(PGconn* conn)
    : Conn(conn)
  {
    this->Buf.reserve(Flush + (1 << 18));
    this->Buf.append("PGCOPY\n\377\r\n\0", 11);
    this->u32(0);
    this->u32(0);
  }
  void u16(std::uint16_t v) { this->be(v, 2); }
  void u32(std::uint32_t v) { this->be(v, 4); }
  void be(std::uint64_t w, int size)
  {
    char b[8];
    for (int k = 0; k < size; ++k)
    {
      b[k] = char(w >> (8 * (size - 1 - k)));
    }
    this->Buf.append(b, size);
  }
  void block(std::int64_t frameId, std::int32_t tile, std::int32_t block, std::int64_t firstRay,
             const RayRecord* r, int n)
  {
    this->u16(5 + NumColumns);
    this->u32(8);
    this->be(std::uint64_t(frameId), 8);
    this->u32(4);
    this->be(std::uint32_t(tile), 4);
    this->u32(4);
    this->be(std::uint32_t(block), 4);
    this->u32(8);
    this->be(std::uint64_t(firstRay), 8);
    this->u32(4);
    this->be(std::uint32_t(n), 4);
    for (const Column& c : Columns)
    {
      const int size = wordSize(c.kind);
      this->u32(std::uint32_t(size * n));
      const std::size_t at = this->Buf.size();
      this->Buf.resize(at + std::size_t(size) * n);
      char* p = &this->Buf[at];
      for (int m = 0; m < n; ++m, p += size)
      {
        std::uint64_t w = c.get(r[m]);
        if (size == 8)
        {
          w = __builtin_bswap64(w);
          std::memcpy(p, &w, 8);
        }
        else
        {
          const std::uint32_t h = __builtin_bswap32(std::uint32_t(w));
          std::memcpy(p, &h, 4);
        }
      }
    }
    if (this->Buf.size() >= Flush)
    {
      this->send();
    }
  }
  void finish()
  {
    this->u16(0xFFFF);
    this->send();
    if (PQputCopyEnd(this->Conn, nullptr) != 1)
    {
      fail("writing the rays failed", this->Conn, nullptr);
    }
    Result r(PQgetResult(this->Conn));
    if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
    {
      fail("writing the rays failed", this->Conn, r.get());
    }
    while (PGresult* extra = PQgetResult(this->Conn))
    {
      PQclear(extra);
    }
  }

private:
  void send()
  {
    if (!this->Buf.empty() &&
        PQputCopyData(this->Conn, this->Buf.data(), int(this->Buf.size())) != 1)
    {
      fail("writing the rays failed", this->Conn, nullptr);
    }
    this->Buf.clear();
  }
  static constexpr std::size_t Flush = 1 << 20;
  PGconn* Conn;
  std::string Buf;
};

/// Leaves a COPY IN or OUT that an error interrupted, so that the connection can roll back.
void abandonCopy(PGconn* conn, const char* why)
{
  const PGTransactionStatusType ts = PQtransactionStatus(conn);
  if (ts != PQTRANS_ACTIVE)
  {
    return;
  }
  // The state of an interrupted COPY is only visible through the results still to come.
  PQputCopyEnd(conn, why);
  while (PGresult* r = PQgetResult(conn))
  {
    const ExecStatusType st = PQresultStatus(r);
    PQclear(r);
    if (st == PGRES_COPY_OUT)
    {
      char* buf = nullptr;
      while (PQgetCopyData(conn, &buf, 0) > 0)
      {
        PQfreemem(buf);
      }
    }
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

/// Streams the records of one tile (a whole frame is tile 0) into ray_blocks in one COPY.
void copyTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t count,
              const std::function<void(std::size_t, RayRecord&)>& next)
{
  // Tests find a writer's backend by this statement's beginning ("COPY ray_blocks").
  Result copy(PQexec(conn, ("COPY ray_blocks (frame_id, tile, block, first_ray, n" +
                            columnList("") + ") FROM STDIN (FORMAT binary)")
                             .c_str()));
  if (!copy || PQresultStatus(copy.get()) != PGRES_COPY_IN)
  {
    fail("starting to write the rays failed", conn, copy.get());
  }
  constexpr std::size_t blockSize = RayStore::kBlockSize;
  CopyWriter writer(conn);
  std::vector<RayRecord> block(std::min(count, blockSize));
  for (std::size_t first = 0, b = 0; first < count; first += blockSize, ++b)
  {
    const int n = int(std::min(blockSize, count - first));
    for (int m = 0; m < n; ++m)
    {
      next(first + std::size_t(m), block[std::size_t(m)]);
    }
    writer.block(frameId, tile, std::int32_t(b), std::int64_t(first), block.data(), n);
  }
  writer.finish();
}

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
  ins.f64(scene.mass).f64(scene.spin).f64(scene.charge);
  for (const Vec3* v : { &cam.position, &cam.focalPoint, &cam.viewUp })
  {
    ins.f64(v->x()).f64(v->y()).f64(v->z());
  }
  ins.f64(cam.viewAngle).i32(cam.width).i32(cam.height).text(ic.method).f64(ic.step);
  ins.f64(ic.relativeTolerance).f64(ic.absoluteTolerance).i32(tileCount);
  return ins.exec(conn,
                  std::string("INSERT INTO frames (scene_id, frame_hash, effective_text, name, "
                              "label, mass, spin, charge, camera_x, camera_y, camera_z, focal_x, "
                              "focal_y, focal_z, up_x, up_y, up_z, view_angle, width, height, "
                              "method, step, relative_tolerance, absolute_tolerance, tile_count, "
                              "status) VALUES ($1, sha256($2), $3, $4, $5, $6, $7, $8, $9, $10, "
                              "$11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22, $23, "
                              "$24, $25, 'writing')") +
                    (ifAbsent ? " ON CONFLICT (frame_hash) DO NOTHING" : "") + " RETURNING id",
                  "creating the frame failed");
}
}

// -----------------------------------------------------------------------------------------------

struct RayStore::Impl
{
  PGconn* Conn = nullptr;
  bool SchemaChecked = false;

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
  /// would hold its row lock for the whole COPY and serialise every other writer of the scene. A
  /// failed frame may leave an unused scene row.
  std::int64_t sceneRow(const SceneTexts& texts)
  {
    return this->transaction(
      "BEGIN",
      [&]
      {
        Params()
          .bytes(texts.scene)
          .text(texts.scene)
          .exec(this->Conn,
                "INSERT INTO scenes (content_hash, description, description_text) "
                "VALUES (sha256($1), $2::jsonb, $2) ON CONFLICT (content_hash) DO NOTHING",
                "storing the scene failed");
        Result found = Params()
                         .bytes(texts.scene)
                         .exec(this->Conn, "SELECT id FROM scenes WHERE content_hash = sha256($1)",
                               "finding the scene failed");
        const std::int64_t id = getI64(found.get(), 0, 0);
        exec(this->Conn, "COMMIT", "committing the scene failed");
        return id;
      });
  }
};

RayStore::RayStore(const std::string& conninfo)
  : P(new Impl)
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
  this->P->Conn = PQconnectdbParams(keys.data(), values.data(), 1);
  if (!this->P->Conn || PQstatus(this->P->Conn) != CONNECTION_OK)
  {
    const std::string msg =
      this->P->Conn ? trimmed(PQerrorMessage(this->P->Conn)) : "out of memory";
    PQfinish(this->P->Conn);
    delete this->P;
    throw StoreError("cannot connect to PostgreSQL: " + msg);
  }
  if (PQsetClientEncoding(this->P->Conn, "UTF8") != 0)
  {
    const std::string msg = trimmed(PQerrorMessage(this->P->Conn));
    PQfinish(this->P->Conn);
    delete this->P;
    throw StoreError("cannot set the client encoding to UTF8: " + msg);
  }
}

RayStore::~RayStore()
{
  PQfinish(this->P->Conn);
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

void RayStore::migrate()
{
  this->P->ensureConnected();
  this->P->SchemaChecked = false;
  this->P->transaction(
    "BEGIN",
    [&]
    {
      // Concurrent migrators wait for each other instead of failing on each other's tables.
      exec(this->P->Conn, "SELECT pg_advisory_xact_lock(1095979604)", "locking the schema failed");
      const int v = this->P->readVersion();
      if (v > kSchemaVersion)
      {
        throw StoreError("schema version mismatch: found " + std::to_string(v) +
                         ", this build knows " + std::to_string(kSchemaVersion) +
                         "; refusing to touch a database written by a newer ASRT");
      }
      const std::vector<std::string> migrations = { migration1(), migration2() };
      for (int m = v; m < kSchemaVersion; ++m)
      {
        Result r(PQexec(this->P->Conn, migrations[std::size_t(m)].c_str()));
        if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
        {
          fail("migration to schema version " + std::to_string(m + 1) + " failed", this->P->Conn,
               r.get());
        }
      }
      if (v != kSchemaVersion)
      {
        exec(this->P->Conn, "DELETE FROM schema_version", "recording the schema version failed");
        Params()
          .i32(kSchemaVersion)
          .exec(this->P->Conn, "INSERT INTO schema_version (version) VALUES ($1)",
                "recording the schema version failed");
      }
      exec(this->P->Conn, "COMMIT", "committing the migration failed");
    });
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  const std::vector<RayRecord>& records, bool replace,
                                  double traceSeconds)
{
  return this->writeFrame(
    scene, label, records.size(), [&records](std::size_t k, RayRecord& r) { r = records[k]; },
    replace, traceSeconds);
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  std::size_t count,
                                  const std::function<void(std::size_t, RayRecord&)>& next,
                                  bool replace, double traceSeconds)
{
  const auto start = std::chrono::steady_clock::now();
  requireText(label, "the label");
  requireText(scene.name, "the scene name");
  const SceneTexts texts = sceneTexts(scene);
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  const std::int64_t sceneId = this->P->sceneRow(texts);
  return this->P->transaction(
    "BEGIN",
    [&]
    {
      Result r;

      r = Params()
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
          throw StoreError("duplicate frame: this scene with these parameters is being written "
                           "as tiled frame " +
                           std::to_string(old) + " (label \"" + getText(r.get(), 0, 1) +
                           "\"); delete it first if its writers are gone");
        }
        if (!replace)
        {
          throw StoreError("duplicate frame: this scene with these parameters is already stored as "
                           "frame " +
                           std::to_string(old) + " (label \"" + getText(r.get(), 0, 1) +
                           "\"); pass replace = true to replace it");
        }
        Params().i64(old).exec(conn, "DELETE FROM frames WHERE id = $1",
                               "deleting the frame to be replaced failed");
      }

      try
      {
        r = insertFrame(conn, sceneId, texts, scene, label, 1, false);
      }
      catch (const StoreError& e)
      {
        if (e.sqlState() == "23505")
        {
          // Another writer stored the same frame between our check and our insert.
          throw StoreError("duplicate frame: this scene with these parameters was just stored by "
                           "another writer; pass replace = true to replace it",
                           e.sqlState());
        }
        throw;
      }
      const std::int64_t frameId = getI64(r.get(), 0, 0);

      copyTile(conn, frameId, 0, count, next);
      Params()
        .i64(frameId)
        .i64(std::int64_t(count))
        .exec(conn,
              "INSERT INTO frame_tiles (frame_id, tile, ray_count, written_at) VALUES ($1, 0, $2, "
              "clock_timestamp())",
              "recording the frame's rays failed");

      const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      Params()
        .i64(frameId)
        .i64(std::int64_t(count))
        .f64(seconds)
        .f64(traceSeconds)
        .exec(conn,
              "UPDATE frames SET status = 'complete', ray_count = $2, write_seconds = $3, "
              "trace_seconds = nullif($4, 'NaN'), completed_at = clock_timestamp() WHERE id = $1",
              "completing the frame failed");
      exec(conn, "COMMIT", "committing the frame failed");
      return frameId;
    });
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
  const std::int64_t sceneId = this->P->sceneRow(texts);
  // Every rank runs this at about the same time. INSERT ... ON CONFLICT DO NOTHING waits for a
  // concurrent inserter of the same identity and then yields to it, so that all agree on its row.
  // The row can still vanish between that and the SELECT (a concurrent replace or delete):
  // then try again.
  for (int attempt = 0; attempt < 10; ++attempt)
  {
    const std::optional<std::int64_t> id = this->P->transaction(
      "BEGIN",
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
          if (!replace)
          {
            throw StoreError("duplicate frame: this scene with these parameters is already stored "
                             "as frame " +
                             std::to_string(old) + " (label \"" + getText(r.get(), 0, 3) +
                             "\"); pass replace = true to replace it");
          }
          Params().i64(old).exec(conn, "DELETE FROM frames WHERE id = $1",
                                 "deleting the frame to be replaced failed");
          // No conflict is possible any more: the old row is deleted and locked by us.
          r = insertFrame(conn, sceneId, texts, scene, label, tileCount, false);
        }
        const std::int64_t frameId = getI64(r.get(), 0, 0);
        exec(conn, "COMMIT", "committing the frame failed");
        return frameId;
      });
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
    "BEGIN",
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
        if (e.sqlState() == "23505")
        {
          // A concurrent writer of the same tile committed first.
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
  Result r = Params().i64(id).exec(this->P->Conn, "DELETE FROM frames WHERE id = $1",
                                   "deleting the frame failed");
  if (std::string(PQcmdTuples(r.get())) == "0")
  {
    throw StoreError("there is no frame " + std::to_string(id) + " to delete");
  }
}

std::vector<RayRecord> RayStore::readFrame(std::int64_t id, const std::string& predicate)
{
  this->P->requireSchema();
  PGconn* conn = this->P->Conn;
  // REPEATABLE READ: the frame row, the selection and the blocks come from one snapshot. Always
  // rolled back, so that nothing a predicate might have done (set_config, ...) outlives the read.
  return this->P->transaction(
    "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY",
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

      // COPY takes no parameters: the frame id reaches it bound, through a transaction-local
      // setting.
      Params()
        .text(std::to_string(id))
        .exec(conn, "SELECT set_config('asrt.frame', $1, true)", "reading the frame failed");
      Result copy(PQexec(conn, ("COPY (SELECT n" + columnList("") +
                                " FROM ray_blocks WHERE frame_id = "
                                "current_setting('asrt.frame')::bigint ORDER BY tile, block) "
                                "TO STDOUT (FORMAT binary)")
                                 .c_str()));
      if (!copy || PQresultStatus(copy.get()) != PGRES_COPY_OUT)
      {
        fail("reading the rays failed", conn, copy.get());
      }
      std::vector<RayRecord> records;
      records.reserve(std::size_t(rayCount));
      std::vector<RayRecord> block(kBlockSize);
      std::int64_t ray = 0;
      bool header = true;
      auto corrupt = [&](const char* what)
      {
        throw StoreError(std::string("reading the rays of frame ") + std::to_string(id) +
                         " failed: malformed COPY data (" + what + ")");
      };
      for (;;)
      {
        char* buf = nullptr;
        const int len = PQgetCopyData(conn, &buf, 0);
        if (len == -1)
        {
          break;
        }
        if (len < 0)
        {
          fail("reading the rays failed", conn, nullptr);
        }
        std::unique_ptr<char, void (*)(void*)> hold(buf, PQfreemem);
        const char* p = buf;
        const char* end = buf + len;
        if (header)
        {
          if (len < 19 || std::memcmp(p, "PGCOPY\n\377\r\n\0", 11) != 0)
          {
            corrupt("header");
          }
          p += 15;
          p += 4 + readBE(p, 4);
          header = false;
        }
        if (end - p < 2)
        {
          corrupt("short row");
        }
        const std::uint16_t fields = std::uint16_t(readBE(p, 2));
        p += 2;
        if (fields == 0xFFFF)
        {
          continue;
        }
        if (fields != 1 + NumColumns || end - p < 8 || readBE(p, 4) != 4)
        {
          corrupt("row shape");
        }
        const int n = int(std::int32_t(readBE(p + 4, 4)));
        p += 8;
        if (n <= 0 || n > kBlockSize)
        {
          corrupt("block size");
        }
        for (const Column& c : Columns)
        {
          const int size = wordSize(c.kind);
          if (end - p < 4 || std::int64_t(readBE(p, 4)) != std::int64_t(size) * n ||
              end - p < 4 + std::int64_t(size) * n)
          {
            corrupt(c.name);
          }
          p += 4;
          for (int m = 0; m < n; ++m, p += size)
          {
            std::uint64_t w;
            if (size == 8)
            {
              std::memcpy(&w, p, 8);
              w = __builtin_bswap64(w);
            }
            else
            {
              std::uint32_t h;
              std::memcpy(&h, p, 4);
              w = __builtin_bswap32(h);
            }
            c.set(block[std::size_t(m)], w);
          }
        }
        records.insert(records.end(), block.begin(), block.begin() + n);
        ray += n;
      }
      Result done(PQgetResult(conn));
      if (!done || PQresultStatus(done.get()) != PGRES_COMMAND_OK)
      {
        fail("reading the rays failed", conn, done.get());
      }
      while (PGresult* extra = PQgetResult(conn))
      {
        PQclear(extra);
      }
      if (ray != rayCount)
      {
        throw StoreError("frame " + std::to_string(id) + " is inconsistent: it says " +
                         std::to_string(rayCount) + " rays, its blocks hold " +
                         std::to_string(ray));
      }
      // The predicate runs last, so that settings it may change (search_path, ...) cannot affect
      // the store's own statements; the rollback then undoes them.
      if (!predicate.empty())
      {
        Params()
          .text(std::to_string(this->PredicateTimeout.count()) + "ms")
          .exec(conn, "SELECT set_config('statement_timeout', $1, true)",
                "setting the predicate's time limit failed");
        // The predicate is the one deliberate splice (see the header). The frame restriction is
        // inside the sub-select, so text that closes the parentheses still sees only this frame;
        // the extended protocol refuses a second statement; READ ONLY refuses writes.
        r = Params().i64(id).exec(conn,
                                  "SELECT r.ray FROM (SELECT * FROM rays_v WHERE frame_id = $1) r "
                                  "WHERE (" +
                                    predicate + "\n)",
                                  "the ray predicate failed");
        std::vector<char> selected(std::size_t(rayCount), 0);
        for (int row = 0; row < PQntuples(r.get()); ++row)
        {
          const std::int64_t k = getI64(r.get(), row, 0);
          if (k >= 0 && k < rayCount)
          {
            selected[std::size_t(k)] = 1;
          }
        }
        std::size_t kept = 0;
        for (std::size_t k = 0; k < records.size(); ++k)
        {
          if (selected[k])
          {
            records[kept++] = records[k];
          }
        }
        records.resize(kept);
      }
      exec(conn, "ROLLBACK", "ending the read failed");
      return records;
    });
}
}
