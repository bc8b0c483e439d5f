#include "DataFiles.h"

#include "AtomicFile.h"
#include "CompressedBlocks.h"
#include "VtkMessages.h"

#include "vtkAbstractArray.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkErrorCode.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPNGReader.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkXMLImageDataWriter.h"
#include "vtkXMLPolyDataWriter.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <streambuf>
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

/// A stream buffer into a TemporaryFile that never tells its stream of a failed write. VTK's XML
/// writers, in inline mode, free memory they never allocated when a write fails
/// (vtkXMLUnstructuredDataWriter::WriteAPiece deletes appended mode's position arrays): so the
/// first error is kept here, the rest of the output is dropped, and the error is thrown once the
/// writer has returned.
class TemporaryFileBuffer : public std::streambuf
{
public:
  explicit TemporaryFileBuffer(TemporaryFile& file)
    : File(file)
  {
    this->setp(this->Buffer, this->Buffer + sizeof(this->Buffer));
  }
  /// Writes what is buffered; the first error's message, or empty.
  const std::string& finish()
  {
    this->flushBuffer();
    return this->Error;
  }

protected:
  int_type overflow(int_type c) override
  {
    this->flushBuffer();
    if (!traits_type::eq_int_type(c, traits_type::eof()))
    {
      *this->pptr() = traits_type::to_char_type(c);
      this->pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* data, std::streamsize n) override
  {
    if (n > this->epptr() - this->pptr())
    {
      this->flushBuffer();
      if (n >= static_cast<std::streamsize>(sizeof(this->Buffer)))
      {
        this->writeThrough(data, static_cast<std::size_t>(n));
        return n;
      }
    }
    std::memcpy(this->pptr(), data, static_cast<std::size_t>(n));
    this->pbump(static_cast<int>(n));
    return n;
  }
  int sync() override
  {
    this->flushBuffer();
    return 0;
  }
  // Positions: the writers rewind to 0 before they start, and go back to rewrite a compressed
  // array's header once its blocks are written, then forward again.
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override
  {
    const off_type here = this->Position + (this->pptr() - this->pbase());
    if (off == 0 && dir == std::ios_base::cur)
      return pos_type(here);
    if (dir != std::ios_base::beg || off < 0)
      return pos_type(off_type(-1));
    this->flushBuffer();
    if (off != this->Position)
    {
      if (lseek(this->File.descriptor(), off, SEEK_SET) < 0 && this->Error.empty())
        this->Error = "cannot write \"" + this->File.path() + "\": " + std::strerror(errno);
      this->Position = off;
    }
    return pos_type(off);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override
  {
    return this->seekoff(off_type(pos), std::ios_base::beg, which);
  }

private:
  void flushBuffer()
  {
    this->writeThrough(this->pbase(), static_cast<std::size_t>(this->pptr() - this->pbase()));
    this->setp(this->Buffer, this->Buffer + sizeof(this->Buffer));
  }
  void writeThrough(const char* data, std::size_t size)
  {
    this->Position += static_cast<off_type>(size);
    if (!this->Error.empty() || size == 0)
      return;
    try
    {
      this->File.write(data, size);
    }
    catch (const std::exception& e)
    {
      this->Error = e.what();
    }
  }

  TemporaryFile& File;
  char Buffer[1 << 16];
  off_type Position = 0; ///< the file offset that the buffer's first byte goes to
  std::string Error;
};

/// A VTK XML writer that writes into a stream of ours (vtkXMLWriter's protected Stream, which its
/// OpenStream uses instead of opening a file when it is set), and compresses an array's blocks on
/// every thread (the bytes vtkXMLWriter would write one block after another).
template<class Base>
class StreamXMLWriter : public Base
{
public:
  static StreamXMLWriter* New()
  {
    auto* writer = new StreamXMLWriter;
    writer->InitializeObjectBase();
    return writer;
  }
  void SetOutputStream(std::ostream* stream) { this->Stream = stream; }

protected:
  void WriteInlineData(vtkAbstractArray* a, vtkIndent indent) override
  {
    const std::size_t size = this->plainBytes(a);
    if (size == 0)
    {
      Base::WriteInlineData(a, indent);
      return;
    }
    std::ostream& os = *this->Stream;
    os << indent;
    if (!writeCompressedBase64(os, static_cast<const unsigned char*>(a->GetVoidPointer(0)), size,
                               this->Compressor, this->BlockSize,
                               this->HeaderType == vtkXMLWriter::UInt64))
    {
      vtkErrorWithObjectMacro(this, "cannot compress array \"" << (a->GetName() ? a->GetName() : "")
                                                               << "\"");
      this->SetErrorCode(vtkErrorCode::FileFormatError);
    }
    os << "\n";
  }

private:
  /// Arrays of fewer blocks are compressed by vtkXMLWriter itself: for them starting threads
  /// costs more than it saves (a sequence of small frames writes thousands of arrays).
  static constexpr std::size_t kParallelBlocks = 16;

  /// The size in bytes of an array written as it lies in memory (compressed binary data of a
  /// numeric array in contiguous memory, its words as wide in the file, in the machine's byte
  /// order, whole words to a block, at least kParallelBlocks blocks), else 0: vtkXMLWriter
  /// converts or swaps the others itself.
  std::size_t plainBytes(vtkAbstractArray* a)
  {
#ifdef VTK_WORDS_BIGENDIAN
    const bool native = this->ByteOrder == vtkXMLWriter::BigEndian;
#else
    const bool native = this->ByteOrder == vtkXMLWriter::LittleEndian;
#endif
    auto* numbers = vtkDataArray::SafeDownCast(a);
    if (this->DataMode != vtkXMLWriter::Binary || !this->Compressor || !native || !numbers ||
        !numbers->HasStandardMemoryLayout() || numbers->GetDataType() == VTK_BIT ||
        numbers->GetNumberOfValues() == 0)
      return 0;
    const std::size_t word = this->GetOutputWordTypeSize(numbers->GetDataType());
    const std::size_t size = word * static_cast<std::size_t>(numbers->GetNumberOfValues());
    if (word != static_cast<std::size_t>(numbers->GetDataTypeSize()) ||
        this->BlockSize % word != 0 || size < kParallelBlocks * this->BlockSize)
      return 0;
    return size;
  }
};

/// The `size` bytes written to the file open at `fd` (read back from the start).
std::string bytesOf(int fd, std::size_t size, const std::string& path)
{
  std::string bytes(size, '\0');
  std::size_t done = 0;
  while (done < size)
  {
    const ssize_t n = pread(fd, &bytes[done], size - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      throw std::runtime_error("cannot read back \"" + path + "\": " +
                               (n < 0 ? std::strerror(errno) : "it is shorter than written"));
    done += static_cast<std::size_t>(n);
  }
  return bytes;
}

/// Runs a VTK XML writer of `data` into `stream`; `name` only satisfies the writer's check that
/// it has somewhere to write.
template<class Writer>
void writeInto(Writer* writer, vtkDataObject* data, const std::string& name, std::ostream& stream)
{
  writer->SetInputData(data);
  writer->SetFileName(name.c_str());
  writer->SetOutputStream(&stream);
  // VTK's XML writers cache each array's range in its information, and write an array with
  // information keys in a longer form (the same data, other bytes): the arrays leave as they came,
  // so that a file is the same whatever was written before from arrays it shares (a frame's image
  // and hit points share four).
  const auto untouched = arraysWithoutInformation(data);
  writer->Write();
  writer->SetOutputStream(nullptr);
  for (vtkAbstractArray* a : untouched)
    if (a->HasInformation())
      a->GetInformation()->Clear();
  writer->SetFileName(nullptr);
}

/// Runs a VTK writer into the file's temporary (through the descriptor created for it, never by
/// its name) and checks that it wrote the whole file.
template<class Writer>
void writeWith(Writer* writer, vtkDataObject* data, TemporaryFile& file, std::string* copy)
{
  const std::string& path = file.path();
  if (!data)
    throw std::runtime_error("cannot write \"" + path + "\": no data");
  VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  const std::string name = file.openName();
  TemporaryFileBuffer buffer(file);
  std::ostream stream(&buffer);
  writeInto(writer, data, name, stream);
  const std::string error = buffer.finish();
  if (!error.empty())
    throw std::runtime_error(error);
  checkWriter(writer->GetErrorCode(), messages, name, path);
  struct stat st;
  if (fstat(file.descriptor(), &st) != 0 || st.st_size == 0)
    throw std::runtime_error("cannot write \"" + path + "\"");
  if (copy)
    *copy = bytesOf(file.descriptor(), static_cast<std::size_t>(st.st_size), path);
  file.finish();
}

void setCompression(vtkXMLWriter* writer, XmlCompression compression)
{
  switch (compression)
  {
    case XmlCompression::LZ4:
      writer->SetCompressorTypeToLZ4();
      break;
    case XmlCompression::ZLib:
      writer->SetCompressorTypeToZLib();
      break;
    case XmlCompression::ZLibFastest:
      writer->SetCompressorTypeToZLib();
      writer->SetCompressionLevel(1);
      break;
    case XmlCompression::None:
      writer->SetCompressorTypeToNone();
      break;
  }
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

void writeSideBySide(const std::vector<std::function<void()>>& writes)
{
  std::vector<std::exception_ptr> errors(writes.size());
  const int n = static_cast<int>(writes.size());
#pragma omp parallel for num_threads(2) schedule(dynamic, 1) if (n > 1)
  for (int k = 0; k < n; ++k)
  {
    try
    {
      writes[static_cast<std::size_t>(k)]();
    }
    catch (...)
    {
      errors[static_cast<std::size_t>(k)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e)
      std::rethrow_exception(e);
}

void writePng(vtkImageData* image, const std::string& path)
{
  writeOne(path, [image](TemporaryFile& file) { writePng(image, file); });
}

void writeVti(vtkImageData* image, const std::string& path, XmlCompression compression)
{
  writeOne(path, [=](TemporaryFile& file) { writeVti(image, file, compression); });
}

void writeVtp(vtkPolyData* data, const std::string& path, XmlCompression compression)
{
  writeOne(path, [=](TemporaryFile& file) { writeVtp(data, file, compression); });
}

namespace
{
/// The PNG of the image's colours; errors name `path`.
std::string pngBytes(vtkImageData* image, const std::string& path)
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
  // Encoded in memory and written by the caller: libpng would report a failed write on stderr
  // itself.
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
  return std::string(reinterpret_cast<const char*>(bytes->GetPointer(0)),
                     static_cast<std::size_t>(bytes->GetNumberOfValues()));
}
}

void writePng(vtkImageData* image, TemporaryFile& file, std::string* copy)
{
  const std::string bytes = pngBytes(image, file.path());
  file.write(bytes.data(), bytes.size());
  if (copy)
    *copy = bytes;
  file.finish();
}

std::string encodePng(vtkImageData* image)
{
  return pngBytes(image, "a PNG in memory");
}

void writeBytes(const std::string& bytes, TemporaryFile& file)
{
  file.write(bytes.data(), bytes.size());
  file.finish();
}

vtkSmartPointer<vtkImageData> readPng(const std::string& bytes)
{
  vtkNew<vtkPNGReader> reader;
  VtkMessageCatcher messages;
  messages.watchAlgorithm(reader);
  reader->SetMemoryBuffer(bytes.data());
  reader->SetMemoryBufferLength(static_cast<vtkIdType>(bytes.size()));
  reader->Update();
  vtkSmartPointer<vtkImageData> image = reader->GetOutput();
  vtkDataArray* scalars = image ? image->GetPointData()->GetScalars() : nullptr;
  if (reader->GetErrorCode() != vtkErrorCode::NoError || messages.failed() || !scalars ||
      scalars->GetDataType() != VTK_UNSIGNED_CHAR ||
      (scalars->GetNumberOfComponents() != 3 && scalars->GetNumberOfComponents() != 4))
    throw std::runtime_error("cannot decode a PNG picture of " + std::to_string(bytes.size()) +
                             " bytes" +
                             (messages.failed() ? ": " + messages.firstError() : std::string()));
  return image;
}

// Inline binary (base64 in the XML), never VTK's default appended data: ParaView 5.11's bundled VTK
// cannot parse appended data with the current libexpat (2.5.0-1+deb12u5 and later), so files with
// it open with 0 points in Debian's ParaView. Inline data parses with every expat.
void writeVti(vtkImageData* image, TemporaryFile& file, XmlCompression compression,
              std::string* copy)
{
  vtkNew<StreamXMLWriter<vtkXMLImageDataWriter>> writer;
  writer->SetDataModeToBinary();
  setCompression(writer, compression);
  writeWith(writer.Get(), image, file, copy);
}

std::string encodeVti(vtkImageData* image, XmlCompression compression)
{
  const std::string name = "a VTI in memory";
  if (!image)
    throw std::runtime_error("cannot write " + name + ": no data");
  vtkNew<StreamXMLWriter<vtkXMLImageDataWriter>> writer;
  writer->SetDataModeToBinary();
  setCompression(writer, compression);
  VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  std::ostringstream stream;
  writeInto(writer.Get(), image, name, stream);
  checkWriter(writer->GetErrorCode(), messages, name, name);
  std::string bytes = stream.str();
  if (!stream || bytes.empty())
    throw std::runtime_error("cannot write " + name);
  return bytes;
}

void writeVtp(vtkPolyData* data, TemporaryFile& file, XmlCompression compression)
{
  vtkNew<StreamXMLWriter<vtkXMLPolyDataWriter>> writer;
  writer->SetDataModeToBinary();
  setCompression(writer, compression);
  writeWith(writer.Get(), data, file, nullptr);
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
