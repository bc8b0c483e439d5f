// Reads an Ogg Theora file's structure without decoding it, to check what a movie writer made
// against the specifications (RFC 3533 for Ogg pages, the Theora I specification for the
// identification header and granule positions): every page's CRC, the picture size, the frame
// rate and the number of frames.
#ifndef asrt_testing_OggTheoraFile_h
#define asrt_testing_OggTheoraFile_h

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace asrt
{
namespace testing
{
struct OggTheoraInfo
{
  std::string error; ///< empty if the file is a well-formed Ogg Theora stream
  int pages = 0;
  int width = 0, height = 0;              ///< the picture region (PICW, PICH)
  std::uint32_t rateNum = 0, rateDen = 0; ///< frames per second = num / den
  long long frames = 0;                   ///< from the last page's granule position
};

/// Ogg's CRC-32: polynomial 0x04c11db7, not reflected, initial value 0, no final xor (RFC 3533).
inline std::uint32_t oggCrc(const unsigned char* data, std::size_t n)
{
  std::uint32_t crc = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    crc ^= static_cast<std::uint32_t>(data[k]) << 24;
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 0x80000000u) ? (crc << 1) ^ 0x04c11db7u : crc << 1;
  }
  return crc;
}

inline OggTheoraInfo inspectOggTheora(const std::string& path)
{
  OggTheoraInfo info;
  std::ifstream in(path, std::ios::binary);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
  auto be = [&bytes](std::size_t at, int n)
  {
    std::uint64_t v = 0;
    for (int k = 0; k < n; ++k)
      v = (v << 8) | bytes[at + k];
    return v;
  };
  std::size_t at = 0;
  std::uint64_t lastGranule = 0;
  int shift = 0, revision = 0;
  std::uint32_t theoraSerial = 0;
  while (at < bytes.size())
  {
    if (at + 27 > bytes.size() || std::string(bytes.begin() + at, bytes.begin() + at + 4) != "OggS")
    {
      info.error = "no Ogg page at byte " + std::to_string(at);
      return info;
    }
    const int segments = bytes[at + 26];
    std::size_t body = 0;
    for (int s = 0; s < segments; ++s)
      body += bytes[at + 27 + s];
    const std::size_t size = 27 + segments + body;
    if (at + size > bytes.size())
    {
      info.error = "page " + std::to_string(info.pages) + " is cut short";
      return info;
    }
    std::vector<unsigned char> page(bytes.begin() + at, bytes.begin() + at + size);
    const std::uint32_t stored =
      page[22] | (page[23] << 8) | (page[24] << 16) | (static_cast<std::uint32_t>(page[25]) << 24);
    page[22] = page[23] = page[24] = page[25] = 0;
    if (oggCrc(page.data(), page.size()) != stored)
    {
      info.error = "page " + std::to_string(info.pages) + " fails its CRC";
      return info;
    }
    std::uint64_t granule = 0;
    for (int k = 7; k >= 0; --k)
      granule = (granule << 8) | bytes[at + 6 + k];
    const std::uint32_t serial = static_cast<std::uint32_t>(
      bytes[at + 14] | (bytes[at + 15] << 8) | (bytes[at + 16] << 16) | (bytes[at + 17] << 24));
    const std::size_t packet = at + 27 + segments;
    if (info.pages == 0)
    {
      if (body < 42 || bytes[packet] != 0x80 ||
          std::string(bytes.begin() + packet + 1, bytes.begin() + packet + 7) != "theora")
      {
        info.error = "the first packet is not a Theora identification header";
        return info;
      }
      revision = bytes[packet + 9];
      info.width = static_cast<int>(be(packet + 14, 3));
      info.height = static_cast<int>(be(packet + 17, 3));
      info.rateNum = static_cast<std::uint32_t>(be(packet + 22, 4));
      info.rateDen = static_cast<std::uint32_t>(be(packet + 26, 4));
      shift = ((bytes[packet + 40] & 0x03) << 3) | (bytes[packet + 41] >> 5);
      theoraSerial = serial;
    }
    if (serial == theoraSerial && granule != ~std::uint64_t(0))
      lastGranule = granule;
    ++info.pages;
    at += size;
  }
  if (info.pages == 0)
  {
    info.error = "empty file";
    return info;
  }
  // The granule position of a frame is (keyframe number << shift) + frames since it; from
  // bitstream version 3.2.1 on it counts frames from 1, so for the last frame it is the count.
  const std::uint64_t mask = (std::uint64_t(1) << shift) - 1;
  info.frames =
    static_cast<long long>((lastGranule >> shift) + (lastGranule & mask)) + (revision >= 1 ? 0 : 1);
  return info;
}
}
}

#endif
