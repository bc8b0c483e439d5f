// Image textures from files, bounded: the size a texture may declare (a cap on each side and a
// memory budget, both checked against the file's header before any pixel is decoded), and a PNG
// decoder on libpng's simplified API, which reports every corrupt, truncated or hostile file as
// an error instead of crashing (VTK's vtkPNGReader does not survive a truncated file).
#ifndef asrt_TextureFiles_h
#define asrt_TextureFiles_h

#include "SceneFile.h"
#include "asrtTracingModule.h"

#include <string>

namespace asrt
{
/// The largest width or height of an image texture, in pixels. 16384 is also the largest texture
/// side common GPUs (and Mesa's llvmpipe) accept; an RGB texture of 16384 × 16384 takes 768 MiB.
constexpr int kMaxTextureSide = 16384;

/// What a texture file may declare.
struct TextureLimits
{
  int maxSide = kMaxTextureSide;
  /// Bytes the decoding may take at its peak; 0 (default): a quarter of this machine's memory, as
  /// a scene holds several textures beside its frame.
  double maxBytes = 0.0;
};

/// Throws InvalidParameter unless an image of width × height pixels, needing `bytesPerPixel` at
/// the peak of its decoding, fits `limits`; the message names the limit that is exceeded.
ASRTTRACING_EXPORT void checkTextureSize(long long width, long long height, double bytesPerPixel,
                                         const TextureLimits& limits = TextureLimits());

/// Throws InvalidParameter ("does not exist", "is not a regular file") unless `path` names a
/// regular file: a texture that is a FIFO or a device would block the reading or never end.
ASRTTRACING_EXPORT void requireTextureFile(const std::string& path);

/// Decodes a PNG file into RGB bytes, bottom row first (VTK's order, ImagePixels'). Every colour
/// type and bit depth is read: grey becomes RGB, palettes are expanded, an alpha channel is
/// dropped (the colour channels are kept as stored, not composited), 16-bit samples are scaled
/// to 8 bits. Samples come out sRGB-encoded: 16-bit samples without gamma information are taken
/// as sRGB-encoded (rescaled only), a file whose gAMA chunk declares another gamma is converted.
/// The declared size is checked against `limits` before decoding. Throws InvalidParameter with a
/// message that starts with a verb and leaves the path out ("holds corrupt or truncated PNG data
/// (libpng: Read Error)"; the caller names the file) for a missing or non-regular file, a file
/// that is not a PNG, and corrupt (bad CRC, bad compressed data) or truncated data.
ASRTTRACING_EXPORT ImagePixels readPngTexture(const std::string& path,
                                              const TextureLimits& limits = TextureLimits());
}

#endif
