#include "VtkMessages.h"

#include "vtkAlgorithm.h"
#include "vtkCommand.h"
#include "vtkExecutive.h"

namespace asrt
{
namespace tools
{
std::string plainVtkMessage(const std::string& eventText)
{
  std::string text = eventText;
  // vtkOutputWindowDisplayErrorText frames the message as
  // "ERROR: In <file>, line <n>\n<Class> (<address>): <message>\n\n".
  if (text.rfind("ERROR: In ", 0) == 0 || text.rfind("Warning: In ", 0) == 0)
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
{
  auto command = vtkSmartPointer<VtkMessageCommand>::New();
  command->Owner = this;
  this->Command = command;
}

VtkMessageCatcher::~VtkMessageCatcher()
{
  for (auto& [object, tag] : this->Observed)
    object->RemoveObserver(tag);
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
}
}
}
