// Writing frames and rays to files with VTK's writers: PNG for the picture, VTK XML (.vti, .vtp)
// for ParaView. Every file appears whole or not at all, alone (the path overloads) or as a member
// of an AtomicFileSet (the TemporaryFile overloads: the file appears when the set is committed); a
// failure throws std::runtime_error naming the file and VTK's or the system's reason. And where
// the program's own data (the scene presets) lies.
#ifndef asrt_tools_DataFiles_h
#define asrt_tools_DataFiles_h

#include "AtomicFile.h"

#include "vtkSmartPointer.h"

#include <functional>
#include <string>
#include <vector>

class vtkImageData;
class vtkPolyData;

namespace asrt
{
namespace tools
{
/// How the arrays of a VTK XML file are compressed (VTK's compressors; ParaView reads each). The
/// blocks of an array are compressed on every OpenMP thread, into the same bytes at any count.
enum class XmlCompression
{
  LZ4,         ///< vtkLZ4DataCompressor: the fastest, files up to half larger than zlib's
  ZLib,        ///< vtkZLibDataCompressor at vtkXMLWriter's default level
  ZLibFastest, ///< vtkZLibDataCompressor at level 1
  None         ///< uncompressed
};
/// What the programs write: LZ4 (see the README's section on outputs).
constexpr XmlCompression kXmlCompression = XmlCompression::LZ4;

/// The image's RGB(A) "Colors" (else its unsigned-char active scalars) as a PNG (row 0 of the image
/// at the bottom of the picture).
void writePng(vtkImageData* image, const std::string& path);
/// The image with every array, as VTK XML image data (inline binary, compressed).
void writeVti(vtkImageData* image, const std::string& path,
              XmlCompression compression = kXmlCompression);
/// Polygonal data (hit points, ray polylines) as VTK XML poly data (inline binary, compressed).
void writeVtp(vtkPolyData* data, const std::string& path,
              XmlCompression compression = kXmlCompression);
/// `copy`, where given, gets the file's bytes.
void writePng(vtkImageData* image, TemporaryFile& file, std::string* copy = nullptr);
void writeVti(vtkImageData* image, TemporaryFile& file,
              XmlCompression compression = kXmlCompression, std::string* copy = nullptr);
/// writePng's bytes, in memory.
std::string encodePng(vtkImageData* image);
/// writeVti's bytes, in memory.
std::string encodeVti(vtkImageData* image, XmlCompression compression = kXmlCompression);
/// Bytes encoded before (a picture stored with its frame) as the file.
void writeBytes(const std::string& bytes, TemporaryFile& file);
/// A PNG's picture: its RGB(A) as the image's unsigned-char scalars. Throws std::runtime_error
/// for bytes that are no such PNG.
vtkSmartPointer<vtkImageData> readPng(const std::string& bytes);
void writeVtp(vtkPolyData* data, TemporaryFile& file, XmlCompression compression = kXmlCompression);

/// Runs the writes on up to two threads and rethrows the first one's exception after all have
/// ended. Writes that run side by side must not share an array that either writer changes: the
/// XML writers compute each array's range and cache it on the array, so two XML files sharing
/// arrays go in one write, one after the other. A frame's PNG is encoded while its VTI is
/// compressed.
void writeSideBySide(const std::vector<std::function<void()>>& writes);

/// The directory holding the example data (scenes/, textures/): <prefix>/share/asrt when the
/// running program is an installed one (<prefix>/bin/asrt, in whatever prefix it was installed
/// to), else the source tree's Data/ that the program was built from.
std::string dataDirectory();
}
}

#endif
