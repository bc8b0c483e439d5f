#include "AtomicFile.h"

#include <vtksys/SystemTools.hxx>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace asrt
{
namespace tools
{
std::string temporaryNameFor(const std::string& path)
{
  const std::string dir = vtksys::SystemTools::GetFilenamePath(path);
  const std::string name = vtksys::SystemTools::GetFilenameName(path);
  return (dir.empty() ? std::string() : dir + "/") + "." + name + "." + std::to_string(getpid()) +
         ".part";
}

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
  const std::string tmp = temporaryNameFor(path);
  try
  {
    write(tmp);
    if (!vtksys::SystemTools::FileExists(tmp, true))
      throw std::runtime_error("cannot write \"" + path + "\"");
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      throw std::runtime_error("cannot write \"" + path + "\": " + std::strerror(errno));
  }
  catch (...)
  {
    std::remove(tmp.c_str());
    throw;
  }
}

void writeFileAtomically(const std::string& path, const std::string& content)
{
  writeAtomically(path,
                  [&](const std::string& tmp)
                  {
                    std::ofstream out(tmp, std::ios::binary);
                    out << content;
                    out.close();
                    if (!out)
                      throw std::runtime_error("cannot write \"" + path +
                                               "\": " + std::strerror(errno));
                  });
}
}
}
