// The mass ramp of Figs. 4–5 for the path tests: Data/scenes/fig4-mass-start.json at another mass
// and frame size.
#ifndef asrt_RampScene_h
#define asrt_RampScene_h

#include "SceneFile.h"
#include "TextureFiles.h"

#include <string>

namespace asrt
{
namespace testing
{
inline SceneDescription rampScene(double mass, int side)
{
  const std::string path = std::string(ASRT_SOURCE_DIR) + "/Data/scenes/fig4-mass-start.json";
  SceneDescription d =
    loadSceneFile(path, [](const std::string& p) { return readPngTexture(p, TextureLimits{}); });
  d.spacetime.mass = mass;
  d.camera.width = d.camera.height = side;
  return d;
}
}
}

#endif
