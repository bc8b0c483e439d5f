#include "DataFiles.h"

#include "AtomicFile.h"
#include "VtkMessages.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkXMLImageDataWriter.h"
#include "vtkXMLPolyDataWriter.h"

#include <filesystem>
#include <stdexcept>

namespace asrt
{
namespace tools
{
namespace
{
/// Runs a VTK writer into a temporary file and renames it into place.
template<class Writer>
void writeWith(Writer* writer, vtkDataObject* data, const std::string& path)
{
  if (!data)
    throw std::runtime_error("cannot write \"" + path + "\": no data");
  VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  writer->SetInputData(data);
  writeAtomically(path,
                  [&](const std::string& tmp)
                  {
                    writer->SetFileName(tmp.c_str());
                    writer->Write();
                    if (messages.failed() || writer->GetErrorCode() != 0)
                      throw std::runtime_error(
                        "cannot write \"" + path + "\"" +
                        (messages.failed() ? ": " + messages.firstError() : std::string()));
                  });
}
}

void writePng(vtkImageData* image, const std::string& path)
{
  vtkDataArray* colors = image ? image->GetPointData()->GetArray("Colors") : nullptr;
  if (!colors && image)
    colors = image->GetPointData()->GetScalars();
  if (!colors || colors->GetDataType() != VTK_UNSIGNED_CHAR ||
      (colors->GetNumberOfComponents() != 3 && colors->GetNumberOfComponents() != 4))
    throw std::runtime_error("cannot write \"" + path + "\": the image has no RGB colours");
  // The PNG writer takes the active scalars: make them the colours on a shallow copy, so that the
  // caller's image keeps its own active array.
  vtkNew<vtkImageData> picture;
  picture->ShallowCopy(image);
  picture->GetPointData()->SetScalars(colors);
  vtkNew<vtkPNGWriter> writer;
  writeWith(writer.Get(), picture, path);
}

void writeVti(vtkImageData* image, const std::string& path)
{
  vtkNew<vtkXMLImageDataWriter> writer;
  writer->SetCompressorTypeToZLib();
  writeWith(writer.Get(), image, path);
}

void writeVtp(vtkPolyData* data, const std::string& path)
{
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetCompressorTypeToZLib();
  writeWith(writer.Get(), data, path);
}

std::string dataDirectory()
{
  // The install puts the data at a fixed path relative to the program (bin/../share/asrt), so an
  // installed tree can be moved (cmake --install --prefix, a package's /usr). /proc/self/exe is
  // the running program with symbolic links resolved.
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error)
  {
    const std::filesystem::path installed =
      (program.parent_path() / ASRT_INSTALLED_DATA_DIR_FROM_PROGRAM).lexically_normal();
    if (std::filesystem::is_directory(installed / "scenes", error))
      return installed.string();
  }
  return ASRT_SOURCE_DATA_DIR;
}
}
}
