// VTK algorithms report failures through vtkErrorMacro, which reaches an observer (or the output
// window) and never a return value. A command-line tool needs the message itself, without VTK's
// "ERROR: In <file>, line <n>" framing or the executive's dump of the failed request.
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

/// Collects the errors (and warnings) of the objects it watches.
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
  void clear();

private:
  friend class VtkMessageCommand;
  std::vector<std::string> Errors;
  std::vector<std::string> Warnings;
  vtkSmartPointer<vtkCommand> Command;
  std::vector<std::pair<vtkSmartPointer<vtkObject>, unsigned long>> Observed;
};
}
}

#endif
