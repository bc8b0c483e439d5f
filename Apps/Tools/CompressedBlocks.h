// The compressed, base64-encoded data of one array of a VTK XML file in inline binary mode, made
// on every OpenMP thread: the bytes vtkXMLWriter writes one block after another, the same at any
// thread count.
#ifndef asrt_tools_CompressedBlocks_h
#define asrt_tools_CompressedBlocks_h

#include <cstddef>
#include <ostream>

class vtkDataCompressor;

namespace asrt
{
namespace tools
{
/// Writes `size` bytes of `data` to `os` as vtkXMLWriter writes compressed inline data: the base64
/// of the header (number of blocks, block size, size of the last block, each block's compressed
/// size: 32- or 64-bit words in the machine's byte order), then the base64 of the compressed
/// blocks one after another. The header is written as a placeholder first and rewritten in place
/// (`os` must seek). Blocks are compressed in batches, each batch on every thread with a compressor
/// of `compressor`'s class and level per thread. Returns false if the compressor fails or a header
/// word does not fit in 32 bits (with `header64` false); `os` then holds part of the data.
bool writeCompressedBase64(std::ostream& os, const unsigned char* data, std::size_t size,
                           vtkDataCompressor* compressor, std::size_t blockSize, bool header64);
}
}

#endif
