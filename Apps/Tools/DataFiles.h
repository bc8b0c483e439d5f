// Writing frames and rays to files with VTK's writers: PNG for the picture, VTK XML (.vti, .vtp)
// for ParaView. Every file appears whole or not at all; a failure throws std::runtime_error naming
// the file and VTK's reason.
#ifndef asrt_tools_DataFiles_h
#define asrt_tools_DataFiles_h

#include <string>

class vtkImageData;
class vtkPolyData;

namespace asrt
{
namespace tools
{
/// The image's RGB(A) "Colors" (else its unsigned-char active scalars) as a PNG (row 0 of the image
/// at the bottom of the picture).
void writePng(vtkImageData* image, const std::string& path);
/// The image with every array, as VTK XML image data (zlib-compressed, appended binary).
void writeVti(vtkImageData* image, const std::string& path);
/// Polygonal data (hit points, ray polylines) as VTK XML poly data.
void writeVtp(vtkPolyData* data, const std::string& path);
}
}

#endif
