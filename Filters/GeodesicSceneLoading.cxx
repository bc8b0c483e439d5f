#include "GeodesicSceneLoading.h"

#include "vtkGeodesicSource.h"

#include <filesystem>

namespace asrt
{
ImageLoader vtkImageFileLoader()
{
  return [](const std::string& path)
  {
    ImagePixels px;
    vtkGeodesicSource::LoadImagePixels(path, px.width, px.height, px.rgb);
    return px;
  };
}

SceneDescription loadScene(const char* text, const char* fileName, const char* textDirectory,
                           ImageLoader loader)
{
  if (!loader)
    loader = vtkImageFileLoader();
  const bool haveFile = fileName && *fileName;
  if (text && *text && haveFile)
  {
    // The file's text, read by the caller its own way: textures beside the file, errors naming it.
    const std::string dir = std::filesystem::path(fileName).parent_path().string();
    try
    {
      return parseScene(text, dir.empty() ? "." : dir, loader);
    }
    catch (const InvalidParameter& e)
    {
      throw InvalidParameter(std::string(fileName) + ": " + e.what());
    }
  }
  if (text && *text)
    return parseScene(text, textDirectory && *textDirectory ? textDirectory : ".", loader);
  if (haveFile)
    return loadSceneFile(fileName, loader);
  throw InvalidParameter("no scene: set SceneFileName or SceneText");
}
}
