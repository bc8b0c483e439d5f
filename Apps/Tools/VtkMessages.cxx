#include "VtkMessages.h"

#include "vtkAlgorithm.h"
#include "vtkCommand.h"
#include "vtkExecutive.h"
#include "vtkLogger.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOutputWindow.h"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <mutex>

namespace asrt
{
namespace tools
{
std::string plainVtkMessage(const std::string& eventText)
{
  std::string text = eventText;
  // vtkOutputWindowDisplayErrorText frames the message as
  // "ERROR: In <file>, line <n>\n<Class> (<address>): <message>\n\n" (warnings, generic warnings
  // and debug messages alike).
  if (text.rfind("ERROR: In ", 0) == 0 || text.rfind("Warning: In ", 0) == 0 ||
      text.rfind("Generic Warning: In ", 0) == 0 || text.rfind("Debug: In ", 0) == 0)
  {
    const std::size_t nl = text.find('\n');
    text = nl == std::string::npos ? std::string() : text.substr(nl + 1);
  }
  const std::size_t tag = text.find("): ");
  const std::size_t firstLine = text.find('\n');
  if (tag != std::string::npos && (firstLine == std::string::npos || tag < firstLine))
    text = text.substr(tag + 3);
  // The executive appends the whole failed request; its first line says enough.
  if (text.rfind("Algorithm ", 0) == 0)
    text = text.substr(0, text.find('\n'));
  while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
    text.pop_back();
  return text;
}

void addStrayVtkMessage(bool error, const std::string& text);

namespace
{
/// The catchers alive, in the order they were made.
std::mutex registryLock;
std::vector<VtkMessageCatcher*> liveCatchers;

std::string firstLine(const std::string& text)
{
  return text.substr(0, text.find('\n'));
}

void printStray(bool error, const std::string& text)
{
  std::fprintf(stderr, "asrt: VTK %s: %s\n", error ? "error" : "warning", text.c_str());
}

/// The output window that hands VTK's own printing to addStrayVtkMessage.
class RoutingOutputWindow : public vtkOutputWindow
{
public:
  static RoutingOutputWindow* New();
  vtkTypeMacro(RoutingOutputWindow, vtkOutputWindow);
  // vtkOutputWindow's Display*Text set the message type and call this.
  void DisplayText(const char* text) override
  {
    addStrayVtkMessage(this->GetCurrentMessageType() == MESSAGE_TYPE_ERROR, text ? text : "");
  }

protected:
  RoutingOutputWindow() = default;
  ~RoutingOutputWindow() override = default;
};
vtkStandardNewMacro(RoutingOutputWindow);
}

void addStrayVtkMessage(bool error, const std::string& text)
{
  const std::string plain = firstLine(plainVtkMessage(text));
  if (plain.empty())
    return;
  std::lock_guard<std::mutex> lock(registryLock);
  if (liveCatchers.empty())
    printStray(error, plain);
  else
    liveCatchers.back()->Strays.push_back({ error, plain });
}

void routeVtkMessages()
{
  static std::once_flag once;
  std::call_once(once,
                 []
                 {
                   // The logger would print its own copy of every message (in colour, on a
                   // terminal-like TERM), whatever the output window does.
                   vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
                   vtkNew<RoutingOutputWindow> window;
                   vtkOutputWindow::SetInstance(window);
                 });
}

class VtkMessageCommand : public vtkCommand
{
public:
  static VtkMessageCommand* New() { return new VtkMessageCommand; }
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    const std::string text = plainVtkMessage(data ? static_cast<const char*>(data) : "");
    (event == vtkCommand::ErrorEvent ? this->Owner->Errors : this->Owner->Warnings).push_back(text);
  }
  VtkMessageCatcher* Owner = nullptr;
};

VtkMessageCatcher::VtkMessageCatcher()
  : UncaughtAtStart(std::uncaught_exceptions())
{
  auto command = vtkSmartPointer<VtkMessageCommand>::New();
  command->Owner = this;
  this->Command = command;
  std::lock_guard<std::mutex> lock(registryLock);
  liveCatchers.push_back(this);
}

VtkMessageCatcher::~VtkMessageCatcher()
{
  for (auto& [object, tag] : this->Observed)
    object->RemoveObserver(tag);
  std::vector<StrayVtkMessage> strays;
  {
    std::lock_guard<std::mutex> lock(registryLock);
    liveCatchers.erase(std::find(liveCatchers.begin(), liveCatchers.end(), this));
    strays.swap(this->Strays);
  }
  // Ended by an exception, the work failed and its error says why; the strays (a reader the
  // image factory tried, say) would only bury that line.
  if (std::uncaught_exceptions() > this->UncaughtAtStart)
    return;
  for (const StrayVtkMessage& m : strays)
    printStray(m.error, m.text);
}

std::vector<StrayVtkMessage> VtkMessageCatcher::strays() const
{
  std::lock_guard<std::mutex> lock(registryLock);
  return this->Strays;
}

void VtkMessageCatcher::watch(vtkObject* object)
{
  this->Observed.emplace_back(object, object->AddObserver(vtkCommand::ErrorEvent, this->Command));
  this->Observed.emplace_back(object, object->AddObserver(vtkCommand::WarningEvent, this->Command));
}

void VtkMessageCatcher::watchAlgorithm(vtkAlgorithm* algorithm)
{
  this->watch(algorithm);
  this->watch(algorithm->GetExecutive());
}

std::string VtkMessageCatcher::firstError() const
{
  return this->Errors.empty() ? std::string() : this->Errors.front();
}

void VtkMessageCatcher::clear()
{
  this->Errors.clear();
  this->Warnings.clear();
  std::lock_guard<std::mutex> lock(registryLock);
  this->Strays.clear();
}
}
}
