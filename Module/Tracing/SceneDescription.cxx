#include "SceneDescription.h"

#include <algorithm>
#include <cstdio>

namespace asrt
{
PixelSubsetId pixelSubsetId(std::vector<std::pair<int, int>> pixels)
{
  std::sort(pixels.begin(), pixels.end());
  pixels.erase(std::unique(pixels.begin(), pixels.end()), pixels.end());
  PixelSubsetId id;
  id.count = static_cast<std::int64_t>(pixels.size());
  if (pixels.empty())
    return id;
  // FNV-1a, 64 bits, over the little-endian bytes of each (i, j) as two int32.
  std::uint64_t h = 14695981039346656037ULL;
  auto feed = [&h](std::int32_t v)
  {
    const auto u = static_cast<std::uint32_t>(v);
    for (int b = 0; b < 4; ++b)
    {
      h ^= (u >> (8 * b)) & 0xffu;
      h *= 1099511628211ULL;
    }
  };
  for (const auto& [i, j] : pixels)
  {
    feed(i);
    feed(j);
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  id.digest = hex;
  return id;
}
}
