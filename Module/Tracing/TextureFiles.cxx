#include "TextureFiles.h"

#include <png.h>

#include <unistd.h>

#include <filesystem>
#include <sstream>
#include <system_error>

namespace asrt
{
namespace
{
double physicalMemory()
{
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? static_cast<double>(pages) * size : 8e9;
}

std::string megabytes(double bytes)
{
  std::ostringstream os;
  os.precision(bytes < 1e10 ? 3 : 4);
  os << bytes / (1024.0 * 1024.0) << " MiB";
  return os.str();
}

/// libpng's state of one read, freed however the read ends (png_image_free is a no-op once
/// png_image_finish_read has freed it).
class PngRead
{
public:
  PngRead() { this->Image.version = PNG_IMAGE_VERSION; }
  ~PngRead() { png_image_free(&this->Image); }
  PngRead(const PngRead&) = delete;
  PngRead& operator=(const PngRead&) = delete;

  png_image& image() { return this->Image; }
  /// libpng's message for the failed step, in a sentence.
  [[noreturn]] void fail(const char* what) const
  {
    std::string message = what;
    if (this->Image.message[0] != '\0')
      message += std::string(" (libpng: ") + this->Image.message + ")";
    throw InvalidParameter(message);
  }

private:
  png_image Image{};
};
}

void requireTextureFile(const std::string& path)
{
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status))
    throw InvalidParameter("does not exist");
  if (!std::filesystem::is_regular_file(status))
    throw InvalidParameter("is not a regular file");
}

void checkTextureSize(long long width, long long height, double bytesPerPixel,
                      const TextureLimits& limits)
{
  std::ostringstream os;
  os << "declares " << width << " x " << height << " pixels";
  if (width < 1 || height < 1)
    throw InvalidParameter(os.str() + "; an image texture needs at least one pixel");
  if (width > limits.maxSide || height > limits.maxSide)
  {
    os << "; image textures may have at most " << limits.maxSide << " pixels a side";
    throw InvalidParameter(os.str());
  }
  const double budget = limits.maxBytes > 0.0 ? limits.maxBytes : 0.25 * physicalMemory();
  const double bytes = static_cast<double>(width) * static_cast<double>(height) * bytesPerPixel;
  if (bytes > budget)
  {
    os << ", which need " << megabytes(bytes) << " to decode, more than the " << megabytes(budget)
       << " a texture may take"
       << (limits.maxBytes > 0.0 ? std::string() : " (a quarter of this machine's memory)");
    throw InvalidParameter(os.str());
  }
}

ImagePixels readPngTexture(const std::string& path, const TextureLimits& limits)
{
  requireTextureFile(path);
  PngRead read;
  png_image& image = read.image();
  if (!png_image_begin_read_from_file(&image, path.c_str()))
    read.fail("is not a readable PNG file");
  // The colour channels as stored: alpha is read (so that libpng does not composite it onto a
  // background) and dropped below. 16-bit samples without gamma information are sRGB-encoded
  // like 8-bit ones, so that they are only rescaled, not converted from linear.
  const bool alpha = (image.format & PNG_FORMAT_FLAG_ALPHA) != 0;
  image.format = alpha ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  image.flags |= PNG_IMAGE_FLAG_16BIT_sRGB;
  const int channels = alpha ? 4 : 3;
  // Peak: the decoded buffer, plus the RGB copy when alpha is dropped.
  checkTextureSize(image.width, image.height, alpha ? 4.0 + 3.0 : 3.0, limits);

  ImagePixels px;
  px.width = static_cast<int>(image.width);
  px.height = static_cast<int>(image.height);
  const std::size_t pixels = static_cast<std::size_t>(px.width) * px.height;
  px.rgb.resize(channels * pixels);
  // A negative stride stores the bottom row first.
  const png_int_32 stride = -static_cast<png_int_32>(channels * image.width);
  if (!png_image_finish_read(&image, nullptr, px.rgb.data(), stride, nullptr))
    read.fail("holds corrupt or truncated PNG data");
  if (alpha)
  {
    for (std::size_t k = 0; k < pixels; ++k)
      for (std::size_t c = 0; c < 3; ++c)
        px.rgb[3 * k + c] = px.rgb[4 * k + c];
    px.rgb.resize(3 * pixels);
    px.rgb.shrink_to_fit();
  }
  return px;
}
}
