#include "DataFiles.h"

#include "AtomicFile.h"
#include "VtkMessages.h"

#include "vtkAbstractArray.h"
#include "vtkCellData.h"
#include "vtkErrorCode.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkXMLImageDataWriter.h"
#include "vtkXMLPolyDataWriter.h"

#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <vector>

namespace asrt
{
namespace tools
{
namespace
{
/// `message` with the name the writer was given replaced by the file's own.
std::string naming(std::string message, const std::string& given, const std::string& path)
{
  if (given.empty())
    return message;
  for (std::size_t at = message.find(given); at != std::string::npos;
       at = message.find(given, at + path.size()))
    message.replace(at, given.size(), path);
  return message;
}

/// Throws for a writer that failed: its error code when it names the system's reason (VTK's
/// writers keep errno to themselves otherwise: a full disk or the file-size limit is only a code),
/// else its message.
void checkWriter(unsigned long code, const VtkMessageCatcher& messages, const std::string& given,
                 const std::string& path)
{
  const std::string failed = "cannot write \"" + path + "\": ";
  if (code == vtkErrorCode::OutOfDiskSpaceError)
    throw std::runtime_error(failed + "out of disk space (or over the file-size limit)");
  if (code != vtkErrorCode::NoError && code < vtkErrorCode::FirstVTKErrorCode)
    throw std::runtime_error(failed + vtkErrorCode::GetStringFromErrorCode(code));
  if (messages.failed())
    throw std::runtime_error(failed + naming(messages.firstError(), given, path));
  if (code != vtkErrorCode::NoError)
    throw std::runtime_error(failed + vtkErrorCode::GetStringFromErrorCode(code));
}

/// The arrays of `data` (its field, point and cell data, and its points) whose information holds
/// no key.
std::vector<vtkSmartPointer<vtkAbstractArray>> arraysWithoutInformation(vtkDataObject* data)
{
  std::vector<vtkSmartPointer<vtkAbstractArray>> arrays;
  auto add = [&arrays](vtkAbstractArray* a)
  {
    if (a && (!a->HasInformation() || a->GetInformation()->GetNumberOfKeys() == 0))
      arrays.emplace_back(a);
  };
  std::vector<vtkFieldData*> groups = { data->GetFieldData() };
  if (auto* set = vtkDataSet::SafeDownCast(data))
  {
    groups.push_back(set->GetPointData());
    groups.push_back(set->GetCellData());
  }
  for (vtkFieldData* fd : groups)
    for (int k = 0; fd && k < fd->GetNumberOfArrays(); ++k)
      add(fd->GetAbstractArray(k));
  if (auto* set = vtkPointSet::SafeDownCast(data))
    if (set->GetPoints())
      add(set->GetPoints()->GetData());
  return arrays;
}

/// Runs a VTK writer into the file's temporary (through the descriptor created for it, never by
/// its name) and checks that it wrote the whole file.
template<class Writer>
void writeWith(Writer* writer, vtkDataObject* data, TemporaryFile& file)
{
  const std::string& path = file.path();
  if (!data)
    throw std::runtime_error("cannot write \"" + path + "\": no data");
  VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  writer->SetInputData(data);
  const std::string name = file.openName();
  writer->SetFileName(name.c_str());
  // VTK's XML writers cache each array's range in its information, and write an array with
  // information keys in a longer form (the same data, other bytes): the arrays leave as they came,
  // so that a file is the same whatever was written before from arrays it shares (a frame's image
  // and hit points share four).
  const auto untouched = arraysWithoutInformation(data);
  writer->Write();
  for (vtkAbstractArray* a : untouched)
    if (a->HasInformation())
      a->GetInformation()->Clear();
  writer->SetFileName(nullptr);
  checkWriter(writer->GetErrorCode(), messages, name, path);
  struct stat st;
  if (fstat(file.descriptor(), &st) != 0 || st.st_size == 0)
    throw std::runtime_error("cannot write \"" + path + "\"");
  file.finish();
}

/// One file written alone, atomically.
template<class Write>
void writeOne(const std::string& path, Write write)
{
  AtomicFileSet files;
  write(files.add(path));
  files.commit();
}
}

void writePng(vtkImageData* image, const std::string& path)
{
  writeOne(path, [image](TemporaryFile& file) { writePng(image, file); });
}

void writeVti(vtkImageData* image, const std::string& path)
{
  writeOne(path, [image](TemporaryFile& file) { writeVti(image, file); });
}

void writeVtp(vtkPolyData* data, const std::string& path)
{
  writeOne(path, [data](TemporaryFile& file) { writeVtp(data, file); });
}

void writePng(vtkImageData* image, TemporaryFile& file)
{
  const std::string& path = file.path();
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
  // Encoded in memory and written here: libpng would report a failed write on stderr itself.
  vtkNew<vtkPNGWriter> writer;
  VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  writer->WriteToMemoryOn();
  writer->SetInputData(picture);
  writer->Write();
  checkWriter(writer->GetErrorCode(), messages, std::string(), path);
  vtkUnsignedCharArray* bytes = writer->GetResult();
  if (!bytes || bytes->GetNumberOfValues() == 0)
    throw std::runtime_error("cannot write \"" + path + "\"");
  file.write(reinterpret_cast<const char*>(bytes->GetPointer(0)),
             static_cast<std::size_t>(bytes->GetNumberOfValues()));
  file.finish();
}

void writeVti(vtkImageData* image, TemporaryFile& file)
{
  vtkNew<vtkXMLImageDataWriter> writer;
  writer->SetCompressorTypeToZLib();
  writeWith(writer.Get(), image, file);
}

void writeVtp(vtkPolyData* data, TemporaryFile& file)
{
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetCompressorTypeToZLib();
  writeWith(writer.Get(), data, file);
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
