#include "StoreRecordCodec.h"

#include "RayStore.h"

namespace asrt
{
namespace storage
{
namespace
{
// The per-ray fields, in storage order: column name, word kind, record member. This one list
// makes the encoder and the decoder, so that they cannot disagree; the columns of rays_v (schema
// version 7, StoreSchemaHistory.cxx) name the same fields in the same order. Versions 3 and 4
// stored the same words without rays_per_pixel, versions 5 and 6 without traced. traced is a
// whole word, 1 or 0 (a bool written as an int32 is 1 or 0, and any non-zero word reads as true).
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
  X(rays_per_pixel, I32, r.raysPerPixel)                                                           \
  X(dudi, F64, r.dudi)                                                                             \
  X(dudj, F64, r.dudj)                                                                             \
  X(dvdi, F64, r.dvdi)                                                                             \
  X(dvdj, F64, r.dvdj)                                                                             \
  X(traced, I32, r.traced)

constexpr int wordBytesI32 = 4;
constexpr int wordBytesI64 = 8;
constexpr int wordBytesF64 = 8;
#define ASRT_WORD_BYTES(name, kind, member) +wordBytes##kind
static_assert(0 ASRT_RAY_FIELDS(ASRT_WORD_BYTES) == RayStore::kRecordBytes,
              "kRecordBytes must match the fields");
#undef ASRT_WORD_BYTES

// A row of ray_blocks: the 24-byte tuple header, frame_id, tile, block, first_ray and n (28
// bytes), the bytea's 4-byte length and the records. PostgreSQL keeps a tuple of at most 8160
// bytes in one 8 kB page; kBlockSize is the most records that fit.
constexpr int rowBytes(int rays)
{
  return 24 + 28 + 4 + RayStore::kRecordBytes * rays;
}
static_assert(rowBytes(RayStore::kBlockSize) <= 8160 && rowBytes(RayStore::kBlockSize + 1) > 8160,
              "kBlockSize must be the most records that fit in one heap page");

char* encodeRecord(const RayRecord& r, char* p)
{
#define ASRT_PUT(name, kind, member) p = put##kind(p, member);
  ASRT_RAY_FIELDS(ASRT_PUT)
#undef ASRT_PUT
  return p;
}

void decodeRecord(const char* p, RayRecord& r)
{
#define ASRT_GET(name, kind, member) p = get##kind(p, member);
  ASRT_RAY_FIELDS(ASRT_GET)
#undef ASRT_GET
}
}

char* encodeRecords(const RayRecord* records, std::size_t count, char* out)
{
  for (std::size_t k = 0; k < count; ++k)
  {
    out = encodeRecord(records[k], out);
  }
  return out;
}

void decodeRecords(const char* in, std::size_t count, RayRecord* records)
{
  for (std::size_t k = 0; k < count; ++k, in += RayStore::kRecordBytes)
  {
    decodeRecord(in, records[k]);
  }
}

char* encodePathPoints(const std::vector<PathPoint>& points, char* out)
{
  for (const PathPoint& q : points)
  {
    for (const double v : { q.x.x(), q.x.y(), q.x.z(), q.lambda, q.r, q.absH })
    {
      out = putF64(out, v);
    }
  }
  return out;
}

void decodePathPoints(const char* in, std::size_t count, std::vector<PathPoint>& points)
{
  points.resize(count);
  for (PathPoint& q : points)
  {
    for (double* v : { &q.x.x(), &q.x.y(), &q.x.z(), &q.lambda, &q.r, &q.absH })
    {
      in = getF64(in, *v);
    }
  }
}
}
}
