// VTK algorithms report failures through vtkErrorMacro, which reaches an observer (or the output
// window) and never a return value. A command-line tool needs the message itself, without VTK's
// "ERROR: In <file>, line <n>" framing or the executive's dump of the failed request. Messages of
// objects nobody observes (the readers an image factory tries, say) would reach the output
// window, and VTK's logger would copy them to stderr in ANSI colours: routeVtkMessages sends them
// to the catcher at work instead.
#ifndef asrt_tools_VtkMessages_h
#define asrt_tools_VtkMessages_h

#include "vtkSmartPointer.h"

#include <string>
#include <vector>

class vtkAlgorithm;
class vtkCommand;
class vtkObject;

namespace asrt
{
namespace tools
{
/// The message of an ErrorEvent's or WarningEvent's text, as the user should read it: the part
/// after "<Class> (<address>): ", first line of an executive's report only.
std::string plainVtkMessage(const std::string& eventText);

/// Makes every message VTK would print on its own (of objects no catcher watches) go to the
/// VtkMessageCatcher constructed last among those alive, as a stray; with none alive, to stderr
/// as one plain line ("asrt: VTK warning: ..."). VTK's logger no longer writes to stderr, so no
/// coloured copy appears. Call once, at start-up; later calls change nothing.
void routeVtkMessages();

/// A message VTK printed for an object nobody watched, while a catcher was alive.
struct StrayVtkMessage
{
  bool error = false;
  std::string text; ///< plainVtkMessage's, its first line
};

/// Collects the errors (and warnings) of the objects it watches, and, once routeVtkMessages is in
/// force, the strays: what unwatched objects report meanwhile. Strays are side notes, never the
/// error: when the catcher ends by an exception (the work failed, and its one-line error says
/// why) they are dropped, otherwise printed on stderr, one plain line each.
class VtkMessageCatcher
{
public:
  VtkMessageCatcher();
  ~VtkMessageCatcher();
  VtkMessageCatcher(const VtkMessageCatcher&) = delete;
  VtkMessageCatcher& operator=(const VtkMessageCatcher&) = delete;

  /// Watches an object's ErrorEvent and WarningEvent.
  void watch(vtkObject* object);
  /// Watches an algorithm and its executive (which reports a failed request on its own object).
  void watchAlgorithm(vtkAlgorithm* algorithm);

  bool failed() const { return !this->Errors.empty(); }
  /// The first error: the cause (later ones are usually its consequences). Empty if none.
  std::string firstError() const;
  const std::vector<std::string>& errors() const { return this->Errors; }
  const std::vector<std::string>& warnings() const { return this->Warnings; }
  /// The strays so far (a copy: they may arrive from any thread).
  std::vector<StrayVtkMessage> strays() const;
  void clear();

private:
  friend class VtkMessageCommand;
  friend void addStrayVtkMessage(bool error, const std::string& text);
  std::vector<std::string> Errors;
  std::vector<std::string> Warnings;
  std::vector<StrayVtkMessage> Strays; ///< guarded by the catchers' registry lock
  int UncaughtAtStart = 0;             ///< std::uncaught_exceptions() when constructed
  vtkSmartPointer<vtkCommand> Command;
  std::vector<std::pair<vtkSmartPointer<vtkObject>, unsigned long>> Observed;
};
}
}

#endif
