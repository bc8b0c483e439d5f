#include "CompressedBlocks.h"

#include "vtkBase64Utilities.h"
#include "vtkDataCompressor.h"
#include "vtkSmartPointer.h"

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace asrt
{
namespace tools
{
namespace
{
/// Blocks compressed between two writes: enough work for every thread, little memory (a batch of
/// 32 KiB blocks is 8 MiB before compression).
constexpr std::size_t kBatchBlocks = 256;

/// Base64 of `size` bytes (a multiple of 3, except for the last piece of a stream), in parallel:
/// every 3 bytes give 4 characters on their own, so the pieces' encodings join up.
std::vector<unsigned char> encode(const unsigned char* bytes, std::size_t size)
{
  constexpr std::size_t kPiece = 3 * (1 << 16);
  std::vector<unsigned char> text((size + 2) / 3 * 4);
  const long pieces = static_cast<long>((size + kPiece - 1) / kPiece);
#pragma omp parallel for schedule(static)
  for (long p = 0; p < pieces; ++p)
  {
    const std::size_t from = static_cast<std::size_t>(p) * kPiece;
    const std::size_t n = std::min(kPiece, size - from);
    vtkBase64Utilities::Encode(bytes + from, static_cast<unsigned long>(n),
                               text.data() + from / 3 * 4);
  }
  return text;
}

/// The header's words in the machine's byte order, 4 or 8 bytes each.
std::vector<unsigned char> headerBytes(const std::vector<std::uint64_t>& words, bool header64)
{
  const std::size_t width = header64 ? 8 : 4;
  std::vector<unsigned char> bytes(words.size() * width);
  for (std::size_t k = 0; k < words.size(); ++k)
  {
    if (header64)
      std::memcpy(bytes.data() + k * width, &words[k], width);
    else
    {
      const auto word = static_cast<std::uint32_t>(words[k]);
      std::memcpy(bytes.data() + k * width, &word, width);
    }
  }
  return bytes;
}

void put(std::ostream& os, const std::vector<unsigned char>& text)
{
  os.write(reinterpret_cast<const char*>(text.data()), static_cast<std::streamsize>(text.size()));
}
}

bool writeCompressedBase64(std::ostream& os, const unsigned char* data, std::size_t size,
                           vtkDataCompressor* compressor, std::size_t blockSize, bool header64)
{
  if (!compressor || blockSize == 0)
    return false;
  const std::size_t blocks = size / blockSize + (size % blockSize ? 1 : 0);
  std::vector<std::uint64_t> header(3 + blocks, 0);
  header[0] = blocks;
  header[1] = blockSize;
  header[2] = size % blockSize;
  // A compressed block may be larger than the block: the bound for the check is the compressor's.
  const std::size_t space = compressor->GetMaximumCompressionSpace(blockSize);
  if (!header64 &&
      std::max({ blocks, blockSize, space }) > std::numeric_limits<std::uint32_t>::max())
    return false;

  const std::streampos headerAt = os.tellp();
  put(os, encode(headerBytes(header, header64).data(), header.size() * (header64 ? 8 : 4)));

  // One compressor per thread, made here: the threads only compress.
  std::vector<vtkSmartPointer<vtkDataCompressor>> compressors(
    static_cast<std::size_t>(omp_get_max_threads()));
  for (auto& c : compressors)
  {
    c = vtkSmartPointer<vtkDataCompressor>::Take(compressor->NewInstance());
    c->SetCompressionLevel(compressor->GetCompressionLevel());
  }
  std::vector<std::vector<unsigned char>> packed(std::min(blocks, kBatchBlocks));
  std::vector<unsigned char> stream; // the batch's compressed bytes after the previous' carry
  bool failed = false;
  for (std::size_t first = 0; first < blocks && !failed; first += kBatchBlocks)
  {
    const long n = static_cast<long>(std::min(kBatchBlocks, blocks - first));
#pragma omp parallel for schedule(dynamic, 4) reduction(|| : failed)
    for (long k = 0; k < n; ++k)
    {
      vtkDataCompressor* mine =
        compressors[static_cast<std::size_t>(omp_get_thread_num()) % compressors.size()];
      const std::size_t at = (first + static_cast<std::size_t>(k)) * blockSize;
      const std::size_t length = std::min(blockSize, size - at);
      std::vector<unsigned char>& out = packed[static_cast<std::size_t>(k)];
      out.resize(space);
      const std::size_t got = mine->Compress(data + at, length, out.data(), space);
      out.resize(got);
      failed = failed || got == 0;
    }
    for (long k = 0; k < n; ++k)
    {
      const std::vector<unsigned char>& out = packed[static_cast<std::size_t>(k)];
      header[3 + first + static_cast<std::size_t>(k)] = out.size();
      stream.insert(stream.end(), out.begin(), out.end());
    }
    // Whole triplets now; the 0 to 2 bytes left over start the next batch's.
    const std::size_t whole = stream.size() / 3 * 3;
    put(os, encode(stream.data(), whole));
    stream.erase(stream.begin(), stream.begin() + static_cast<std::ptrdiff_t>(whole));
  }
  if (failed)
    return false;
  put(os, encode(stream.data(), stream.size()));

  const std::streampos end = os.tellp();
  os.seekp(headerAt);
  put(os, encode(headerBytes(header, header64).data(), header.size() * (header64 ? 8 : 4)));
  os.seekp(end);
  return static_cast<bool>(os);
}
}
}
