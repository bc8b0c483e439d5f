// The words the interpolation's kept results are found by: a double's bits, mixed into a running
// 64-bit hash. Private to ASRT::Interpolation.
#ifndef asrt_RecordHashing_h
#define asrt_RecordHashing_h

#include <cstdint>
#include <cstring>

namespace asrt
{
/// Mixes a 64-bit word into a running hash (the multiply-xorshift step of MurmurHash3's
/// finalizer, applied per word).
inline std::uint64_t mixWord(std::uint64_t h, std::uint64_t w)
{
  w *= 0xff51afd7ed558ccdULL;
  w ^= w >> 33;
  h ^= w;
  h *= 0xc4ceb9fe1a85ec53ULL;
  return h ^ (h >> 29);
}

/// The bits of a double, as a word to hash: equal doubles, equal words.
inline std::uint64_t bitsOf(double x)
{
  std::uint64_t w = 0;
  std::memcpy(&w, &x, sizeof w);
  return w;
}
}

#endif
