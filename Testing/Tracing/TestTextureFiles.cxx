// The PNG texture decoder against PNGs this test encodes itself (zlib and the chunk layout of the
// PNG specification, no libpng): every colour type comes back as the RGB it encodes, bottom row
// first; truncated, CRC-broken, garbage and huge-header files are refused with a message, and
// the size caps hold before any pixel is decoded.
#include "AddressSpaceLimit.h"
#include "TextureFiles.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

using namespace asrt;

namespace
{
void put32(std::string& s, std::uint32_t v)
{
  for (int shift = 24; shift >= 0; shift -= 8)
    s += static_cast<char>((v >> shift) & 0xff);
}

std::string chunk(const std::string& type, const std::string& data)
{
  std::string c;
  put32(c, static_cast<std::uint32_t>(data.size()));
  const std::string body = type + data;
  c += body;
  put32(c, static_cast<std::uint32_t>(
             crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size())));
  return c;
}

std::string ihdr(std::uint32_t w, std::uint32_t h, int depth, int colorType)
{
  std::string d;
  put32(d, w);
  put32(d, h);
  d += static_cast<char>(depth);
  d += static_cast<char>(colorType);
  d += std::string(3, '\0'); // deflate, adaptive filtering, no interlace
  return chunk("IHDR", d);
}

std::string deflated(const std::string& raw)
{
  uLongf size = compressBound(raw.size());
  std::string out(size, '\0');
  compress(reinterpret_cast<Bytef*>(&out[0]), &size, reinterpret_cast<const Bytef*>(raw.data()),
           raw.size());
  out.resize(size);
  return out;
}

const std::string kSignature = "\x89PNG\r\n\x1a\n";

/// A PNG of `rows` (packed samples, top row first), each prefixed with filter type 0 (none).
std::string png(int w, int depth, int colorType, const std::vector<std::string>& rows,
                const std::string& extraChunks = std::string())
{
  std::string raw;
  for (const std::string& r : rows)
    raw += '\0' + r;
  return kSignature + ihdr(w, static_cast<std::uint32_t>(rows.size()), depth, colorType) +
         extraChunks + chunk("IDAT", deflated(raw)) + chunk("IEND", "");
}

std::string tempPath(const std::string& name)
{
  return ::testing::TempDir() + "asrt-texture-" + name;
}

std::string written(const std::string& name, const std::string& bytes)
{
  const std::string path = tempPath(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

/// The RGB of pixel (x, row) of decoded pixels, row 0 at the bottom.
std::vector<int> at(const ImagePixels& px, int x, int row)
{
  const std::uint8_t* p = &px.rgb[3 * (static_cast<std::size_t>(row) * px.width + x)];
  return { p[0], p[1], p[2] };
}

std::string errorOf(const std::string& path, const TextureLimits& limits = TextureLimits())
{
  try
  {
    readPngTexture(path, limits);
  }
  catch (const InvalidParameter& e)
  {
    return e.what();
  }
  return "(no error)";
}

/// 5 × 3 RGB pixels, distinct in every channel: pixel (x, fileRow) = (10x + fileRow, 100 + x,
/// 200 + fileRow).
std::vector<std::string> rgbRows()
{
  std::vector<std::string> rows(3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x)
      rows[y] +=
        { static_cast<char>(10 * x + y), static_cast<char>(100 + x), static_cast<char>(200 + y) };
  return rows;
}
}

TEST(PngTexture, RgbComesBackBottomRowFirst)
{
  const ImagePixels px = readPngTexture(written("rgb.png", png(5, 8, 2, rgbRows())));
  ASSERT_EQ(px.width, 5);
  ASSERT_EQ(px.height, 3);
  ASSERT_EQ(px.rgb.size(), 45u);
  for (int row = 0; row < 3; ++row)
    for (int x = 0; x < 5; ++x)
    {
      const int fileRow = 2 - row;
      EXPECT_EQ(at(px, x, row), (std::vector<int>{ 10 * x + fileRow, 100 + x, 200 + fileRow }))
        << "pixel " << x << ", row " << row << " from the bottom";
    }
}

TEST(PngTexture, AlphaIsDroppedNotComposited)
{
  // RGBA with alpha 0, 1 and 128: the colour channels come back as stored.
  std::vector<std::string> rows{ std::string("\x10\x20\x30\x00\x40\x50\x60\x01", 8),
                                 std::string("\x70\x80\x90\x80\xa0\xb0\xc0\xff", 8) };
  const ImagePixels px = readPngTexture(written("rgba.png", png(2, 8, 6, rows)));
  ASSERT_EQ(px.rgb.size(), 12u);
  EXPECT_EQ(at(px, 0, 1), (std::vector<int>{ 0x10, 0x20, 0x30 }));
  EXPECT_EQ(at(px, 1, 1), (std::vector<int>{ 0x40, 0x50, 0x60 }));
  EXPECT_EQ(at(px, 0, 0), (std::vector<int>{ 0x70, 0x80, 0x90 }));
  EXPECT_EQ(at(px, 1, 0), (std::vector<int>{ 0xa0, 0xb0, 0xc0 }));
}

TEST(PngTexture, GreyAndGreyAlphaBecomeRgb)
{
  const ImagePixels grey =
    readPngTexture(written("grey.png", png(3, 8, 0, { std::string("\x00\x7f\xff", 3) })));
  EXPECT_EQ(at(grey, 0, 0), (std::vector<int>{ 0, 0, 0 }));
  EXPECT_EQ(at(grey, 1, 0), (std::vector<int>{ 127, 127, 127 }));
  EXPECT_EQ(at(grey, 2, 0), (std::vector<int>{ 255, 255, 255 }));
  const ImagePixels ga =
    readPngTexture(written("grey-alpha.png", png(2, 8, 4, { std::string("\x33\x00\xcc\x80", 4) })));
  EXPECT_EQ(at(ga, 0, 0), (std::vector<int>{ 0x33, 0x33, 0x33 }));
  EXPECT_EQ(at(ga, 1, 0), (std::vector<int>{ 0xcc, 0xcc, 0xcc }));
}

TEST(PngTexture, OneBitGreyIsExpanded)
{
  // 10 pixels of 1 bit: 1011001110 (then padding).
  const ImagePixels px =
    readPngTexture(written("one-bit.png", png(10, 1, 0, { std::string("\xb3\x80", 2) })));
  const int bits[10] = { 1, 0, 1, 1, 0, 0, 1, 1, 1, 0 };
  for (int x = 0; x < 10; ++x)
    EXPECT_EQ(at(px, x, 0), std::vector<int>(3, bits[x] ? 255 : 0)) << "pixel " << x;
}

TEST(PngTexture, PaletteWithTransparencyIsExpanded)
{
  const std::string plte = chunk("PLTE", std::string("\x01\x02\x03\xfa\xfb\xfc\x80\x40\x20", 9));
  const std::string trns = chunk("tRNS", std::string("\x00\x80", 2)); // entries 0 and 1 translucent
  const ImagePixels px = readPngTexture(
    written("palette.png", png(4, 8, 3, { std::string("\x02\x00\x01\x02", 4) }, plte + trns)));
  EXPECT_EQ(at(px, 0, 0), (std::vector<int>{ 0x80, 0x40, 0x20 }));
  EXPECT_EQ(at(px, 1, 0), (std::vector<int>{ 1, 2, 3 }));
  EXPECT_EQ(at(px, 2, 0), (std::vector<int>{ 0xfa, 0xfb, 0xfc }));
  EXPECT_EQ(at(px, 3, 0), (std::vector<int>{ 0x80, 0x40, 0x20 }));
}

TEST(PngTexture, SixteenBitSamplesAreRescaled)
{
  // Without gamma information: v → round(255 v / 65535), as for VTK's readers.
  const std::vector<int> samples = { 0, 128, 129, 32767, 32768, 65407, 65408, 65535, 257, 1000 };
  std::string row;
  for (std::size_t k = 0; k + 2 < samples.size(); k += 3)
    for (std::size_t c = 0; c < 3; ++c)
      row += { static_cast<char>(samples[k + c] >> 8), static_cast<char>(samples[k + c] & 0xff) };
  const ImagePixels px = readPngTexture(written("sixteen.png", png(3, 16, 2, { row })));
  for (std::size_t k = 0; k < 9; ++k)
    EXPECT_EQ(px.rgb[k], std::lround(255.0 * samples[k] / 65535.0)) << "sample " << samples[k];
}

TEST(PngTexture, EveryTruncationIsAnError)
{
  const std::string whole = png(5, 8, 2, rgbRows());
  const std::size_t iend = whole.size() - 12;
  for (std::size_t n = 0; n < iend; ++n)
  {
    const std::string message = errorOf(written("cut.png", whole.substr(0, n)));
    EXPECT_TRUE(message.find("is not a readable PNG file") == 0 ||
                message.find("holds corrupt or truncated PNG data") == 0)
      << "the first " << n << " bytes: " << message;
  }
}

TEST(PngTexture, BrokenCrcIsAnError)
{
  std::string bytes = png(5, 8, 2, rgbRows());
  const std::size_t idat = bytes.find("IDAT");
  const std::uint32_t length = (std::uint8_t(bytes[idat - 4]) << 24) |
                               (std::uint8_t(bytes[idat - 3]) << 16) |
                               (std::uint8_t(bytes[idat - 2]) << 8) | std::uint8_t(bytes[idat - 1]);
  bytes[idat + 4 + length] ^= 0x01;
  EXPECT_EQ(errorOf(written("crc.png", bytes)),
            "holds corrupt or truncated PNG data (libpng: IDAT: CRC error)");
  std::string header = png(5, 8, 2, rgbRows());
  header[8 + 8 + 13] ^= 0x01; // IHDR's CRC
  EXPECT_EQ(errorOf(written("crc-ihdr.png", header)).find("is not a readable PNG file"), 0u);
}

TEST(PngTexture, GarbageDataIsAnError)
{
  std::mt19937 random(15);
  std::string garbage(300, '\0');
  for (char& c : garbage)
    c = static_cast<char>(random());
  const std::string bytes =
    kSignature + ihdr(5, 3, 8, 2) + chunk("IDAT", garbage) + chunk("IEND", "");
  EXPECT_EQ(errorOf(written("garbage.png", bytes)).find("holds corrupt or truncated PNG data"), 0u);
  // Too little data for the rows the header declares.
  const std::string shortData = kSignature + ihdr(5, 300, 8, 2) +
                                chunk("IDAT", deflated(std::string(16, '\0'))) + chunk("IEND", "");
  EXPECT_EQ(errorOf(written("short.png", shortData)).find("holds corrupt or truncated PNG data"),
            0u);
}

TEST(PngTexture, HugeHeaderIsRefusedBeforeDecoding)
{
  const std::string bytes = kSignature + ihdr(60000, 60000, 8, 2) +
                            chunk("IDAT", deflated(std::string(1000, '\0'))) + chunk("IEND", "");
  // 60000² RGB pixels would need 10 GB: refused from the header, within 1 GB.
  const asrt::testing::AddressSpaceLimit bound(1e9);
  EXPECT_EQ(errorOf(written("huge.png", bytes)),
            "declares 60000 x 60000 pixels; image textures may have at most 16384 pixels a side");
}

TEST(PngTexture, SideCapIsInclusive)
{
  std::string row(3 * 16384, '\x11');
  const ImagePixels px = readPngTexture(written("wide.png", png(16384, 8, 2, { row })));
  EXPECT_EQ(px.width, 16384);
  EXPECT_EQ(at(px, 16383, 0), (std::vector<int>{ 0x11, 0x11, 0x11 }));
  row += "\x11\x11\x11";
  EXPECT_EQ(errorOf(written("wider.png", png(16385, 8, 2, { row }))),
            "declares 16385 x 1 pixels; image textures may have at most 16384 pixels a side");
}

TEST(PngTexture, MemoryBudgetIsCheckedBeforeDecoding)
{
  const std::string path = written("budget.png", png(5, 8, 2, rgbRows())); // 45 RGB bytes
  TextureLimits limits;
  limits.maxBytes = 45;
  EXPECT_EQ(readPngTexture(path, limits).rgb.size(), 45u);
  limits.maxBytes = 44;
  EXPECT_NE(errorOf(path, limits).find("declares 5 x 3 pixels, which need"), std::string::npos);
  EXPECT_NE(errorOf(path, limits).find("more than the"), std::string::npos);
}

TEST(PngTexture, NotAPngFile)
{
  EXPECT_EQ(errorOf(written("text.png", "just text, no PNG\n")).find("is not a readable PNG file"),
            0u);
  EXPECT_EQ(errorOf(written("empty.png", "")).find("is not a readable PNG file"), 0u);
  EXPECT_EQ(errorOf(tempPath("no-such-file.png")), "does not exist");
  EXPECT_EQ(errorOf(::testing::TempDir()), "is not a regular file");
  // A device would never end: refused before it is opened.
  EXPECT_EQ(errorOf("/dev/zero"), "is not a regular file");
}

TEST(TextureSize, LimitsAreNamed)
{
  EXPECT_NO_THROW(checkTextureSize(16384, 16384, 3.0));
  EXPECT_THROW(checkTextureSize(0, 10, 3.0), InvalidParameter);
  EXPECT_THROW(checkTextureSize(10, 16385, 3.0), InvalidParameter);
  TextureLimits small;
  small.maxSide = 8;
  small.maxBytes = 1e6;
  try
  {
    checkTextureSize(9, 2, 3.0, small);
    ADD_FAILURE() << "a side of 9 passed a cap of 8";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_STREQ(e.what(),
                 "declares 9 x 2 pixels; image textures may have at most 8 pixels a side");
  }
  small.maxSide = 100000;
  small.maxBytes = 1024.0 * 1024.0;
  try
  {
    checkTextureSize(1024, 1024, 3.0, small);
    ADD_FAILURE() << "3 MiB passed a budget of 1 MiB";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_STREQ(e.what(), "declares 1024 x 1024 pixels, which need 3 MiB to decode, more than the "
                           "1 MiB a texture may take");
  }
}
