// The stored form of a ray and of a path point: RayRecord packed into the kRecordBytes bytes of
// ray_blocks.data (and rays_v's record_bytes), PathPoint into the words of ray_paths.points.
// Every field is a big-endian 32- or 64-bit word, so that SQL can decode it with bit(n) casts and
// doubles keep every bit (NaN payloads, −0, denormals). Internal to ASRT::Store.
#ifndef asrt_StoreRecordCodec_h
#define asrt_StoreRecordCodec_h

#include "RayRecord.h"

#include <cstdint>
#include <cstring>
#include <vector>

namespace asrt
{
namespace storage
{
/// Bytes of one packed path point: x, y, z, λ, r, |H|, as big-endian float64 words.
constexpr int kPathPointBytes = 6 * 8;

inline std::uint64_t bitsOf(double d)
{
  std::uint64_t w;
  std::memcpy(&w, &d, 8);
  return w;
}
inline double doubleOf(std::uint64_t w)
{
  double d;
  std::memcpy(&d, &w, 8);
  return d;
}

// Big-endian words, in and out; each returns the position after the word.
template<class T>
char* putI32(char* p, T v)
{
  const std::uint32_t w = __builtin_bswap32(std::uint32_t(std::int32_t(v)));
  std::memcpy(p, &w, 4);
  return p + 4;
}
inline char* putI64(char* p, std::int64_t v)
{
  const std::uint64_t w = __builtin_bswap64(std::uint64_t(v));
  std::memcpy(p, &w, 8);
  return p + 8;
}
inline char* putF64(char* p, double v)
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
inline const char* getI64(const char* p, std::int64_t& v)
{
  std::uint64_t w;
  std::memcpy(&w, p, 8);
  v = std::int64_t(__builtin_bswap64(w));
  return p + 8;
}
inline const char* getF64(const char* p, double& v)
{
  std::int64_t w;
  p = getI64(p, w);
  v = doubleOf(std::uint64_t(w));
  return p;
}

/// Packs `count` records at `out` (kRecordBytes bytes each); returns the end.
char* encodeRecords(const RayRecord* records, std::size_t count, char* out);
/// Unpacks `count` records packed by encodeRecords().
void decodeRecords(const char* in, std::size_t count, RayRecord* records);

/// Packs a path's points at `out` (kPathPointBytes bytes each); returns the end.
char* encodePathPoints(const std::vector<PathPoint>& points, char* out);
/// Unpacks `count` points packed by encodePathPoints().
void decodePathPoints(const char* in, std::size_t count, std::vector<PathPoint>& points);
}
}

#endif
