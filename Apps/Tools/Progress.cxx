#include "Progress.h"

#include "vtkAlgorithm.h"
#include "vtkCommand.h"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <string>

namespace asrt
{
namespace tools
{
namespace
{
volatile std::sig_atomic_t interrupted = 0;
volatile std::time_t interruptedAt = 0;

extern "C" void onInterrupt(int signal)
{
  // A second Ctrl-C a moment later stops at once, should the work not be polling (e.g. waiting
  // for a server). One signal delivered twice (as timeout(1) sends it, to the process and to its
  // group) is still one request.
  timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now); // async-signal-safe
  if (interrupted && now.tv_sec - interruptedAt >= 1)
  {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
  if (!interrupted)
    interruptedAt = now.tv_sec;
  interrupted = 1;
}

constexpr int kBarWidth = 30;
}

void installInterruptHandler()
{
  struct sigaction action = {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  // No SA_RESTART: a blocking open or read (a FIFO, a slow device) returns EINTR, so that the
  // reader can see the request.
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  // Over the file-size limit (ulimit -f), a write then fails with EFBIG, an error the writer
  // reports and rolls back, instead of killing the process half-way through a set of files.
  std::signal(SIGXFSZ, SIG_IGN);
}

bool interruptRequested()
{
  return interrupted != 0;
}

class ProgressCommand : public vtkCommand
{
public:
  static ProgressCommand* New() { return new ProgressCommand; }
  void Execute(vtkObject* caller, unsigned long, void* data) override
  {
    if (data)
      this->Bar->update(*static_cast<double*>(data));
    if (interruptRequested())
      if (auto* algorithm = vtkAlgorithm::SafeDownCast(caller))
        algorithm->SetAbortExecute(1);
  }
  ProgressBar* Bar = nullptr;
};

ProgressBar::ProgressBar(std::string label, Style style)
  : Label(std::move(label))
  , Mode(style)
  , Start(std::chrono::steady_clock::now())
{
  if (this->Mode == Style::Automatic)
    this->Mode = isatty(STDERR_FILENO) ? Style::Bar : Style::Lines;
  auto command = vtkSmartPointer<ProgressCommand>::New();
  command->Bar = this;
  this->Command = command;
}

ProgressBar::~ProgressBar()
{
  for (auto& [algorithm, tag] : this->Observed)
    algorithm->RemoveObserver(tag);
  // A bar left unfinished (an error) must not leave the cursor mid-line.
  if (this->Mode == Style::Bar && this->Drawn && !this->Finished)
    std::fputc('\n', stderr);
}

double ProgressBar::elapsedSeconds() const
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - this->Start).count();
}

void ProgressBar::watch(vtkAlgorithm* algorithm)
{
  this->Observed.emplace_back(algorithm,
                              algorithm->AddObserver(vtkCommand::ProgressEvent, this->Command));
}

std::function<bool(double)> ProgressBar::callback()
{
  return [this](double fraction)
  {
    this->update(fraction);
    return !interruptRequested();
  };
}

void ProgressBar::update(double fraction)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  if (this->Finished || this->Mode == Style::Silent)
    return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const auto now = std::chrono::steady_clock::now();
  if (this->Mode == Style::Bar)
  {
    if (this->Drawn && now - this->LastDraw < std::chrono::milliseconds(100))
      return;
    this->LastDraw = now;
    this->draw(fraction, false);
  }
  else
  {
    const int quarter = static_cast<int>(fraction * 4.0);
    if (quarter > this->LastQuarter && quarter > 0 && quarter < 4)
      this->draw(fraction, false);
    this->LastQuarter = std::max(this->LastQuarter, quarter);
  }
}

void ProgressBar::finish(const std::string& note)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  if (this->Finished || this->Mode == Style::Silent)
  {
    this->Finished = true;
    return;
  }
  this->draw(1.0, true);
  if (!note.empty())
    std::fprintf(stderr, "  %s", note.c_str());
  std::fputc('\n', stderr);
  this->Finished = true;
}

void ProgressBar::draw(double fraction, bool final)
{
  const double seconds = this->elapsedSeconds();
  if (this->Mode == Style::Bar)
  {
    const int filled = static_cast<int>(fraction * kBarWidth + 0.5);
    std::fprintf(stderr, "\r%s [%s%s] %3d%%  %.1f s", this->Label.c_str(),
                 std::string(filled, '#').c_str(), std::string(kBarWidth - filled, '.').c_str(),
                 static_cast<int>(fraction * 100.0 + 0.5), seconds);
    if (!final)
      std::fflush(stderr);
  }
  else if (final)
    std::fprintf(stderr, "%s: done in %.1f s", this->Label.c_str(), seconds);
  else
    std::fprintf(stderr, "%s: %d%% (%.1f s)\n", this->Label.c_str(),
                 static_cast<int>(fraction * 100.0 + 0.5), seconds);
  this->Drawn = true;
}

FrameCount::FrameCount(int frames)
{
  if (frames < 1)
    throw std::invalid_argument("FrameCount: a movie has at least one frame, got " +
                                std::to_string(frames));
  this->Made.assign(static_cast<std::size_t>(frames), 0);
}

double FrameCount::made(int k)
{
  if (k < 0 || static_cast<std::size_t>(k) >= this->Made.size())
    throw std::out_of_range("FrameCount: frame " + std::to_string(k) + " outside [0, " +
                            std::to_string(this->Made.size()) + ")");
  unsigned char& seen = this->Made[static_cast<std::size_t>(k)];
  if (!seen)
  {
    seen = 1;
    ++this->Count;
  }
  return this->share();
}

double FrameCount::share() const
{
  return static_cast<double>(this->Count) / static_cast<double>(this->Made.size());
}
}
}
