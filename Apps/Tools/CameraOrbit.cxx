#include "CameraOrbit.h"

#include "SceneFile.h"

#include <fstream>
#include <sstream>

namespace asrt
{
namespace tools
{
CameraPose sceneCamera(const std::string& scenePath)
{
  std::ifstream in(scenePath, std::ios::binary);
  if (!in)
    throw InvalidParameter("cannot read scene file \"" + scenePath + "\"");
  std::ostringstream text;
  text << in.rdbuf();
  return sceneCameraOfText(text.str());
}
}
}
