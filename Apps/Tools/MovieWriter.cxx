#include "MovieWriter.h"

#include "AtomicFile.h"
#include "VtkMessages.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkOggTheoraWriter.h"
#include "vtkPointData.h"
#include "vtkUnsignedCharArray.h"
#include "vtk_ogg.h"

#include <vtksys/SystemTools.hxx>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace asrt
{
namespace tools
{
namespace
{
/// The frame as a tightly packed RGB image, rows from the bottom (VTK's order).
vtkSmartPointer<vtkImageData> rgbFrame(vtkImageData* frame)
{
  vtkDataArray* colors = frame ? frame->GetPointData()->GetArray("Colors") : nullptr;
  if (!colors && frame)
    colors = frame->GetPointData()->GetScalars();
  const int nc = colors ? colors->GetNumberOfComponents() : 0;
  if (!colors || colors->GetDataType() != VTK_UNSIGNED_CHAR || (nc != 3 && nc != 4))
    throw std::runtime_error("movie frame has no RGB colours (unsigned char, 3 or 4 components)");
  int dims[3];
  frame->GetDimensions(dims);
  auto rgb = vtkSmartPointer<vtkImageData>::New();
  rgb->SetDimensions(dims[0], dims[1], 1);
  rgb->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(rgb->GetScalarPointer());
  auto* in = vtkUnsignedCharArray::SafeDownCast(colors);
  const vtkIdType n = static_cast<vtkIdType>(dims[0]) * dims[1];
  for (vtkIdType k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c)
      out[3 * k + c] = in->GetValue(k * nc + c);
  return rgb;
}

/// The serial number of the movie's one logical stream ("ASRT").
constexpr std::uint32_t kOggSerial = 0x41535254;

/// vtkOggTheoraWriter numbers its stream with rand() seeded by the clock's second, so the same
/// frames made other bytes a second later. Every page of the file open at `fd` gets kOggSerial
/// instead, its checksum computed again (libogg's); the pages keep their sizes, so the file is
/// patched in place. A file that is not a plain sequence of pages is left as it is.
void numberOggStream(int fd, const std::string& path)
{
  struct stat st;
  if (fstat(fd, &st) != 0)
    throw std::runtime_error("cannot write the movie \"" + path + "\": " + std::strerror(errno));
  std::vector<unsigned char> bytes(static_cast<std::size_t>(st.st_size));
  for (std::size_t got = 0; got < bytes.size();)
  {
    const ssize_t n = pread(fd, bytes.data() + got, bytes.size() - got, static_cast<off_t>(got));
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      throw std::runtime_error("cannot read back the movie \"" + path +
                               "\": " + std::strerror(n < 0 ? errno : EIO));
    got += static_cast<std::size_t>(n);
  }
  std::vector<ogg_page> pages;
  for (std::size_t at = 0; at < bytes.size();)
  {
    // RFC 3533: "OggS", version, flags, granule position (8), serial (4), sequence (4), checksum
    // (4), the segment count, then the segments' lengths, then the body.
    if (bytes.size() - at < 27 || std::memcmp(bytes.data() + at, "OggS", 4) != 0)
      return;
    const std::size_t headerLength = 27 + bytes[at + 26];
    if (bytes.size() - at < headerLength)
      return;
    std::size_t bodyLength = 0;
    for (std::size_t k = 27; k < headerLength; ++k)
      bodyLength += bytes[at + k];
    if (bytes.size() - at - headerLength < bodyLength)
      return;
    ogg_page page;
    page.header = bytes.data() + at;
    page.header_len = static_cast<long>(headerLength);
    page.body = bytes.data() + at + headerLength;
    page.body_len = static_cast<long>(bodyLength);
    pages.push_back(page);
    at += headerLength + bodyLength;
  }
  for (ogg_page& page : pages)
  {
    for (int b = 0; b < 4; ++b)
      page.header[14 + b] = static_cast<unsigned char>(kOggSerial >> (8 * b));
    ogg_page_checksum_set(&page);
  }
  for (std::size_t put = 0; put < bytes.size();)
  {
    const ssize_t n = pwrite(fd, bytes.data() + put, bytes.size() - put, static_cast<off_t>(put));
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      throw std::runtime_error("cannot write the movie \"" + path +
                               "\": " + std::strerror(n < 0 ? errno : EIO));
    put += static_cast<std::size_t>(n);
  }
}
}

struct MovieWriter::Backend
{
  std::string Path;
  /// The set the movie is a member of, when the caller gave one.
  AtomicFileSet* External = nullptr;
  /// The movie's temporary, created with the first frame (in a set of its own, or External).
  std::unique_ptr<AtomicFileSet> Files;
  TemporaryFile* File = nullptr;
  int Rate = 24;
  int Frames = 0;
  int Width = 0, Height = 0;
  bool Closed = false;

  Backend(std::string path, int rate)
    : Path(std::move(path))
    , Rate(rate)
  {
  }
  void create()
  {
    if (!this->External)
      this->Files = std::make_unique<AtomicFileSet>();
    this->File = &(this->External ? *this->External : *this->Files).add(this->Path);
  }
  /// Removes the temporary, if any (an External set removes it unless it is committed).
  void discard()
  {
    this->File = nullptr;
    this->Files.reset();
  }
  virtual ~Backend() = default;
  virtual void start() = 0;
  virtual void write(vtkImageData* rgb) = 0;
  virtual void finish() = 0;
  virtual void abandon() = 0;
};

namespace
{
class OggBackend : public MovieWriter::Backend
{
public:
  using Backend::Backend;
  void start() override
  {
    this->Messages.watchAlgorithm(this->Writer);
    this->Writer->SetRate(this->Rate);
    this->Writer->SetQuality(2);
    this->Writer->SetSubsampling(1); // 4:2:0, what players expect
  }
  void write(vtkImageData* rgb) override
  {
    this->Writer->SetInputData(rgb);
    if (!this->Started)
    {
      this->Writer->SetFileName(this->File->openName().c_str());
      this->Writer->Start();
      this->Started = true;
    }
    this->Writer->Write();
    this->check();
  }
  void finish() override
  {
    this->Started = false;
    this->Writer->End();
    this->check();
    // The temporary is open for writing only: read and patched through a descriptor of its own.
    const int fd = open(this->File->openName().c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0)
      throw std::runtime_error("cannot write the movie \"" + this->Path +
                               "\": " + std::strerror(errno));
    try
    {
      numberOggStream(fd, this->Path);
    }
    catch (...)
    {
      close(fd);
      throw;
    }
    close(fd);
  }
  void abandon() override
  {
    if (this->Started)
      this->Writer->End();
    this->Started = false;
    this->discard();
  }

private:
  void check()
  {
    if (this->Messages.failed() || this->Writer->GetErrorCode() != 0)
      throw std::runtime_error(
        "cannot write the movie \"" + this->Path + "\"" +
        (this->Messages.failed() ? ": " + this->Messages.firstError() : std::string()));
  }
  vtkNew<vtkOggTheoraWriter> Writer;
  VtkMessageCatcher Messages;
  bool Started = false;
};

/// Feeds raw RGB frames to an ffmpeg process through a pipe.
class FfmpegBackend : public MovieWriter::Backend
{
public:
  using Backend::Backend;
  ~FfmpegBackend() override { this->stop(); }
  void start() override {}
  void write(vtkImageData* rgb) override
  {
    if (this->Pid < 0)
      this->spawn();
    // ffmpeg's raw video is top row first; VTK's images start at the bottom.
    const auto* px = static_cast<const unsigned char*>(rgb->GetScalarPointer());
    const std::size_t row = 3 * static_cast<std::size_t>(this->Width);
    for (int j = this->Height - 1; j >= 0; --j)
      this->put(px + j * row, row);
  }
  void finish() override
  {
    if (this->stop() != 0)
      throw std::runtime_error("ffmpeg failed to write \"" + this->Path + "\"");
  }
  void abandon() override
  {
    this->stop();
    this->discard();
  }

private:
  void spawn()
  {
    int fds[2];
    if (pipe(fds) != 0)
      throw std::runtime_error(std::string("cannot start ffmpeg: ") + std::strerror(errno));
    const std::string size = std::to_string(this->Width) + "x" + std::to_string(this->Height);
    const std::string rate = std::to_string(this->Rate);
    std::vector<std::string> args = { "ffmpeg", "-nostdin", "-hide_banner", "-loglevel", "error",
                                      "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", size, "-r",
                                      rate, "-i", "pipe:0",
                                      // H.264 in yuv420p needs even sizes.
                                      "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
                                      "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4",
                                      // The temporary created for it, as ffmpeg's descriptor 3
                                      // (seekable, as +faststart needs; never opened by name).
                                      "file:/proc/self/fd/3" };
    std::vector<char*> argv;
    for (std::string& a : args)
      argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
    // dup2 onto itself would keep the close-on-exec flag: move a descriptor 3 out of the way.
    int movie = this->File->descriptor();
    const int spare = movie == 3 ? fcntl(movie, F_DUPFD_CLOEXEC, 4) : -1;
    if (spare >= 0)
      movie = spare;
    posix_spawn_file_actions_adddup2(&actions, movie, 3);
    pid_t pid = -1;
    const int rc = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[0]);
    if (spare >= 0)
      close(spare);
    if (rc != 0)
    {
      close(fds[1]);
      throw std::runtime_error(std::string("cannot start ffmpeg: ") + std::strerror(rc));
    }
    this->Pid = pid;
    this->Pipe = fds[1];
  }
  void put(const unsigned char* data, std::size_t n)
  {
    // A dead ffmpeg must give an error here, not kill this process with SIGPIPE: block the
    // signal around the write and consume it if it came.
    sigset_t pipeSignal, old;
    sigemptyset(&pipeSignal);
    sigaddset(&pipeSignal, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipeSignal, &old);
    bool broken = false;
    while (n > 0 && !broken)
    {
      const ssize_t w = ::write(this->Pipe, data, n);
      if (w < 0 && errno == EINTR)
        continue;
      if (w <= 0)
      {
        broken = true;
        const timespec zero = { 0, 0 };
        sigtimedwait(&pipeSignal, nullptr, &zero);
        break;
      }
      data += w;
      n -= static_cast<std::size_t>(w);
    }
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
    if (broken)
      throw std::runtime_error("ffmpeg stopped while writing \"" + this->Path + "\"");
  }
  int stop()
  {
    if (this->Pipe >= 0)
      close(this->Pipe);
    this->Pipe = -1;
    int status = -1;
    if (this->Pid > 0)
      while (waitpid(this->Pid, &status, 0) < 0 && errno == EINTR)
        ;
    this->Pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  pid_t Pid = -1;
  int Pipe = -1;
};
}

MovieWriter::Format MovieWriter::formatFor(const std::string& path)
{
  const std::string ext =
    vtksys::SystemTools::LowerCase(vtksys::SystemTools::GetFilenameLastExtension(path));
  if (ext == ".ogv" || ext == ".ogg")
    return Format::OggTheora;
  if (ext == ".mp4")
    return Format::Mp4;
  throw std::invalid_argument("\"" + path +
                              "\": movies are .ogv (Ogg Theora) or .mp4 (needs ffmpeg)");
}

bool MovieWriter::mp4Available()
{
  std::string found = vtksys::SystemTools::FindProgram("ffmpeg");
  return !found.empty();
}

MovieWriter::MovieWriter(const std::string& path, int framesPerSecond, AtomicFileSet* files)
{
  if (framesPerSecond < 1 || framesPerSecond > 240)
    throw std::invalid_argument("frame rate must be 1 to 240 frames/s, got " +
                                std::to_string(framesPerSecond));
  if (formatFor(path) == Format::Mp4)
  {
    if (!mp4Available())
      throw std::invalid_argument("\"" + path +
                                  "\": MP4 needs the ffmpeg program (apt-get install ffmpeg); "
                                  "write .ogv instead");
    this->Impl = std::make_unique<FfmpegBackend>(path, framesPerSecond);
  }
  else
    this->Impl = std::make_unique<OggBackend>(path, framesPerSecond);
  this->Impl->External = files;
  this->Impl->start();
}

MovieWriter::~MovieWriter()
{
  if (!this->Impl->Closed)
    this->Impl->abandon();
}

void MovieWriter::addFrame(vtkImageData* frame)
{
  if (this->Impl->Closed)
    throw std::runtime_error("movie \"" + this->Impl->Path + "\" is already closed");
  vtkSmartPointer<vtkImageData> rgb = rgbFrame(frame);
  int dims[3];
  rgb->GetDimensions(dims);
  if (this->Impl->Frames == 0)
  {
    if (!this->Impl->File)
      this->Impl->create();
    this->Impl->Width = dims[0];
    this->Impl->Height = dims[1];
  }
  else if (dims[0] != this->Impl->Width || dims[1] != this->Impl->Height)
    throw std::runtime_error("movie frame " + std::to_string(this->Impl->Frames) + " is " +
                             std::to_string(dims[0]) + "x" + std::to_string(dims[1]) +
                             ", the movie is " + std::to_string(this->Impl->Width) + "x" +
                             std::to_string(this->Impl->Height));
  this->Impl->write(rgb);
  ++this->Impl->Frames;
}

void MovieWriter::close()
{
  Backend& b = *this->Impl;
  if (b.Closed)
    return;
  if (b.Frames == 0)
    throw std::runtime_error("movie \"" + b.Path + "\" has no frames");
  b.finish();
  if (b.Files)
    b.Files->commit();
  else
    b.File->finish();
  b.Closed = true;
}

int MovieWriter::frameCount() const
{
  return this->Impl->Frames;
}

const std::string& MovieWriter::path() const
{
  return this->Impl->Path;
}
}
}
