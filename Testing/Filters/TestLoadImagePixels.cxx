// vtkGeodesicSource::LoadImagePixels against an independent reading of the same PNG: the size
// from the IHDR bytes, every pixel from a small decoder (zlib inflate and PNG unfiltering, enough
// for 8-bit RGB without interlace), and a few pixels against the checker pattern that
// scripts/make-textures draws. Orientation matters: rows come back bottom first (VTK's order).
#include "FiltersTestUtilities.h"

#include "AsrtTypes.h"

#include "vtkImageData.h"
#include "vtkJPEGWriter.h"
#include "vtkNew.h"

#include <zlib.h>

#include <cstdio>
#include <cstdlib>

using asrt::testing::readFile;
using asrt::testing::texturePath;

namespace
{
std::uint32_t bigEndian32(const std::string& s, size_t at)
{
  return (std::uint32_t(std::uint8_t(s[at])) << 24) |
         (std::uint32_t(std::uint8_t(s[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(s[at + 2])) << 8) | std::uint32_t(std::uint8_t(s[at + 3]));
}

struct Png
{
  int width = 0, height = 0, bitDepth = 0, colorType = 0, interlace = 0;
  std::vector<std::uint8_t> rgb; ///< top row first, as stored in the file
};

int paeth(int a, int b, int c)
{
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
}

/// Decodes 8-bit RGB non-interlaced PNGs; anything else leaves rgb empty.
Png decodePng(const std::string& file)
{
  Png png;
  if (file.size() < 33 || file.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 ||
      file.compare(12, 4, "IHDR") != 0)
    return png;
  png.width = static_cast<int>(bigEndian32(file, 16));
  png.height = static_cast<int>(bigEndian32(file, 20));
  png.bitDepth = std::uint8_t(file[24]);
  png.colorType = std::uint8_t(file[25]);
  png.interlace = std::uint8_t(file[28]);
  if (png.bitDepth != 8 || png.colorType != 2 || png.interlace != 0)
    return png;
  std::string idat;
  for (size_t at = 8; at + 12 <= file.size();)
  {
    const std::uint32_t length = bigEndian32(file, at);
    const std::string type = file.substr(at + 4, 4);
    if (type == "IDAT")
      idat += file.substr(at + 8, length);
    at += 12 + length;
  }
  const size_t stride = 3 * static_cast<size_t>(png.width);
  std::vector<std::uint8_t> raw((stride + 1) * png.height);
  uLongf rawSize = raw.size();
  if (uncompress(raw.data(), &rawSize, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) !=
        Z_OK ||
      rawSize != raw.size())
    return png;
  png.rgb.resize(stride * png.height);
  for (int y = 0; y < png.height; ++y)
  {
    const std::uint8_t filter = raw[y * (stride + 1)];
    const std::uint8_t* in = &raw[y * (stride + 1) + 1];
    std::uint8_t* out = &png.rgb[y * stride];
    const std::uint8_t* up = y > 0 ? &png.rgb[(y - 1) * stride] : nullptr;
    for (size_t x = 0; x < stride; ++x)
    {
      const int a = x >= 3 ? out[x - 3] : 0, b = up ? up[x] : 0, c = (up && x >= 3) ? up[x - 3] : 0;
      int predictor = 0;
      switch (filter)
      {
        case 1:
          predictor = a;
          break;
        case 2:
          predictor = b;
          break;
        case 3:
          predictor = (a + b) / 2;
          break;
        case 4:
          predictor = paeth(a, b, c);
          break;
        default:
          predictor = 0;
      }
      out[x] = static_cast<std::uint8_t>(in[x] + predictor);
    }
  }
  return png;
}
}

TEST(LoadImagePixels, CheckerPngMatchesAnIndependentDecoding)
{
  const std::string path = texturePath("checker.png");
  const Png png = decodePng(readFile(path));
  ASSERT_EQ(png.bitDepth, 8);
  ASSERT_EQ(png.colorType, 2) << "the decoder here handles RGB only";
  ASSERT_FALSE(png.rgb.empty()) << "independent decoding failed";

  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  vtkGeodesicSource::LoadImagePixels(path, width, height, rgb);
  EXPECT_EQ(width, png.width);
  EXPECT_EQ(height, png.height);
  ASSERT_EQ(rgb.size(), 3u * png.width * png.height);
  int differing = 0;
  for (int row = 0; row < height; ++row) // row 0 = bottom = last row of the file
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        if (rgb[3 * (static_cast<size_t>(row) * width + x) + c] !=
            png.rgb[3 * (static_cast<size_t>(height - 1 - row) * width + x) + c])
          ++differing;
  EXPECT_EQ(differing, 0) << "channel values differing from the file read bottom row first";
}

TEST(LoadImagePixels, CheckerPatternAndOrientationMarks)
{
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  vtkGeodesicSource::LoadImagePixels(texturePath("checker.png"), width, height, rgb);
  ASSERT_EQ(width, 256);
  ASSERT_EQ(height, 256);
  auto pixel = [&](int x, int row)
  {
    const unsigned char* p = &rgb[3 * (static_cast<size_t>(row) * width + x)];
    return std::vector<int>{ p[0], p[1], p[2] };
  };
  const std::vector<int> cream = { 232, 226, 208 }, slate = { 46, 66, 98 };
  // 8 × 8 checks of 32 pixels, cream where column + row (from the bottom) is even.
  EXPECT_EQ(pixel(0, 0), cream);
  EXPECT_EQ(pixel(40, 0), slate);
  EXPECT_EQ(pixel(0, 40), slate);
  EXPECT_EQ(pixel(255, 255), cream);
  EXPECT_EQ(pixel(100, 200), slate); // check (3, 6)
  // The red dot marks the bottom-left check, the green one the bottom-right: centres at
  // (16, 240) and (240, 240) in file rows, i.e. row 15 from the bottom.
  EXPECT_EQ(pixel(16, 15), (std::vector<int>{ 200, 30, 30 }));
  EXPECT_EQ(pixel(240, 15), (std::vector<int>{ 30, 160, 50 }));
  EXPECT_EQ(pixel(16, 240), slate) << "the red dot must not be at the top: rows are flipped";
}

TEST(LoadImagePixels, MissingFileThrows)
{
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  EXPECT_THROW(
    vtkGeodesicSource::LoadImagePixels(texturePath("no-such-file.png"), width, height, rgb),
    asrt::InvalidParameter);
}

TEST(LoadImagePixels, TextFileIsNotAnImage)
{
  // The textures' README is Markdown; a scene naming it as a texture must get an error, not a
  // blank picture (the scene format promises an error for an unreadable image).
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  EXPECT_THROW(vtkGeodesicSource::LoadImagePixels(texturePath("README.md"), width, height, rgb),
               asrt::InvalidParameter)
    << "read as a " << width << " x " << height << " image";
}

TEST(LoadImagePixels, JpegOfOneColourComesBackThatColour)
{
  // JPEG is lossy, but an image of one colour has no detail to lose: its 8 x 8 blocks keep only
  // their mean, which comes back within a level or two (the colour conversion's rounding).
  const std::string path = ::testing::TempDir() + "asrt-flat.jpg";
  vtkNew<vtkImageData> flat;
  flat->SetDimensions(16, 16, 1);
  flat->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* bytes = static_cast<unsigned char*>(flat->GetScalarPointer());
  for (int k = 0; k < 16 * 16; ++k)
  {
    bytes[3 * k] = 200;
    bytes[3 * k + 1] = 100;
    bytes[3 * k + 2] = 50;
  }
  vtkNew<vtkJPEGWriter> writer;
  writer->SetInputData(flat);
  writer->SetQuality(100);
  writer->SetFileName(path.c_str());
  writer->Write();
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  vtkGeodesicSource::LoadImagePixels(path, width, height, rgb);
  std::remove(path.c_str());
  ASSERT_EQ(width, 16);
  ASSERT_EQ(height, 16);
  ASSERT_EQ(rgb.size(), 16u * 16u * 3u);
  const int expected[3] = { 200, 100, 50 };
  for (std::size_t k = 0; k < rgb.size(); ++k)
    ASSERT_NEAR(rgb[k], expected[k % 3], 2) << "byte " << k;
}
