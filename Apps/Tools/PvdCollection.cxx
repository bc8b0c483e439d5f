#include "PvdCollection.h"

#include "AtomicFile.h"

#include <vtksys/SystemTools.hxx>

#include <cstdio>
#include <sstream>

namespace asrt
{
namespace tools
{
namespace
{
/// XML attribute text: the five characters with a meaning in markup become entities.
std::string xmlAttribute(const std::string& text)
{
  std::string out;
  for (char c : text)
  {
    switch (c)
    {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}
}

void PvdCollection::add(double timestep, const std::string& file, int part)
{
  this->Entries.push_back({ timestep, part, file });
}

void PvdCollection::write(const std::string& pvdPath) const
{
  AtomicFileSet files;
  this->write(files.add(pvdPath));
  files.commit();
}

void PvdCollection::write(TemporaryFile& file) const
{
  const std::string& pvdPath = file.path();
  const std::string dir =
    vtksys::SystemTools::GetFilenamePath(vtksys::SystemTools::CollapseFullPath(pvdPath));
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  for (const Entry& e : this->Entries)
  {
    const std::string full = vtksys::SystemTools::CollapseFullPath(e.file);
    const std::string relative = vtksys::SystemTools::RelativePath(dir, full);
    const bool inside = !relative.empty() && relative.rfind("../", 0) != 0;
    char step[32];
    std::snprintf(step, sizeof step, "%.17g", e.timestep); // round-trips every double
    xml << "    <DataSet timestep=\"" << step << "\" group=\"\" part=\"" << e.part << "\" file=\""
        << xmlAttribute(inside ? relative : e.file) << "\"/>\n";
  }
  xml << "  </Collection>\n</VTKFile>\n";
  const std::string text = xml.str();
  file.write(text.data(), text.size());
}
}
}
