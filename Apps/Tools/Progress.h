// Progress of long work on stderr: a bar redrawn in place when stderr is a terminal, otherwise a
// line at each quarter (logs and CI stay readable). Ctrl-C asks the work to stop cleanly: the
// algorithms watched are told to abort, core callbacks return false.
#ifndef asrt_tools_Progress_h
#define asrt_tools_Progress_h

#include "vtkSmartPointer.h"

#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

class vtkAlgorithm;
class vtkCommand;

namespace asrt
{
namespace tools
{
/// Installs a SIGINT/SIGTERM handler that only records the request (the work polls it; blocking
/// calls return EINTR), and ignores SIGXFSZ (a write over the file-size limit fails instead).
void installInterruptHandler();
/// Whether Ctrl-C (or SIGTERM) arrived since installInterruptHandler().
bool interruptRequested();

class ProgressBar
{
public:
  enum class Style
  {
    Automatic, ///< a bar on a terminal, quarter lines otherwise
    Bar,
    Lines,
    Silent
  };
  explicit ProgressBar(std::string label, Style style = Style::Automatic);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// The fraction done, in [0, 1]. Cheap to call often: drawing is throttled.
  void update(double fraction);
  /// Ends the bar with the elapsed time and an optional note ("-> fig1.png").
  void finish(const std::string& note = std::string());
  double elapsedSeconds() const;

  /// Follows an algorithm's ProgressEvents, and sets its AbortExecute on an interrupt.
  void watch(vtkAlgorithm* algorithm);
  /// For the core's progress callbacks: updates the bar, returns false on an interrupt.
  std::function<bool(double)> callback();

private:
  void draw(double fraction, bool final);
  std::string Label;
  Style Mode;
  std::chrono::steady_clock::time_point Start;
  std::chrono::steady_clock::time_point LastDraw;
  int LastQuarter = -1;
  bool Finished = false;
  bool Drawn = false;
  std::mutex Mutex;
  vtkSmartPointer<vtkCommand> Command;
  std::vector<std::pair<vtkSmartPointer<vtkAlgorithm>, unsigned long>> Observed;
};

/// The share of a movie's frames made, for its progress bar: each frame counts once, when it is
/// made, whether it is traced whole while the plan makes its keys or interpolated (or written from
/// its stored pictures) when its turn comes; writing a frame made before adds nothing. Counting
/// each frame's writing as a step of its own put half of the bar after the last ray where the plan
/// traces every frame, as it does at high resolution: the bar stood at 50 % when the last frame
/// was traced.
class FrameCount
{
public:
  /// Throws std::invalid_argument for fewer than one frame.
  explicit FrameCount(int frames);
  /// Counts frame k, unless it was counted before, and returns the share made. Throws
  /// std::out_of_range for a frame outside [0, frames).
  double made(int k);
  double share() const;

private:
  std::vector<unsigned char> Made;
  int Count = 0;
};
}
}

#endif
