// Movies from a sequence of frames: Ogg Theora (.ogv, .ogg) through VTK's vtkOggTheoraWriter,
// always available with Debian's VTK, or H.264 MP4 (.mp4) through the ffmpeg program when it is
// installed (Debian's VTK has no FFMPEG module). The file appears when close() succeeds, whole, or,
// as a member of a set of files, when the set is committed.
#ifndef asrt_tools_MovieWriter_h
#define asrt_tools_MovieWriter_h

#include <memory>
#include <string>

class vtkImageData;

namespace asrt
{
namespace tools
{
class AtomicFileSet;

class MovieWriter
{
public:
  enum class Format
  {
    OggTheora,
    Mp4
  };
  /// The format a file name asks for: .ogv or .ogg → OggTheora, .mp4 → Mp4. Throws
  /// std::invalid_argument for any other extension.
  static Format formatFor(const std::string& path);
  /// Whether the ffmpeg program is on PATH (MP4 needs it).
  static bool mp4Available();

  /// Nothing is written until the first frame. Throws std::invalid_argument for an unknown
  /// extension, a frame rate outside [1, 240], or MP4 without ffmpeg. With `files`, the movie is
  /// a member of that set (added at the first frame), which must outlive the writer: close()
  /// finishes it, and it appears when the set is committed.
  MovieWriter(const std::string& path, int framesPerSecond = 24, AtomicFileSet* files = nullptr);
  /// Without close(), the partial movie is deleted (by its set, for a member of one).
  ~MovieWriter();
  MovieWriter(const MovieWriter&) = delete;
  MovieWriter& operator=(const MovieWriter&) = delete;

  /// Appends a frame: its RGB(A) "Colors" array, else its active unsigned-char scalars. Every
  /// frame must have the size of the first. Throws std::runtime_error on a bad frame or a failed
  /// encoder.
  void addFrame(vtkImageData* frame);
  /// Finishes the movie and moves it into place (a member of a set: ready for the set's commit).
  /// Throws std::runtime_error if there is no frame or the encoder failed (nothing is left behind
  /// then).
  void close();

  int frameCount() const;
  const std::string& path() const;

  struct Backend;

private:
  std::unique_ptr<Backend> Impl;
};
}
}

#endif
