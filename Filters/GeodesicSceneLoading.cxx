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

SceneDescription loadScene(const char* text, const char* fileName, const char* textDirectory)
{
  const bool haveFile = fileName && *fileName;
  if (text && *text && haveFile)
  {
    // The file's text, read by the caller its own way: textures beside the file, errors naming it.
    const std::string dir = std::filesystem::path(fileName).parent_path().string();
    try
    {
      return parseScene(text, dir.empty() ? "." : dir, vtkImageFileLoader());
    }
    catch (const InvalidParameter& e)
    {
      throw InvalidParameter(std::string(fileName) + ": " + e.what());
    }
  }
  if (text && *text)
    return parseScene(text, textDirectory && *textDirectory ? textDirectory : ".",
                      vtkImageFileLoader());
  if (haveFile)
    return loadSceneFile(fileName, vtkImageFileLoader());
  throw InvalidParameter("no scene: set SceneFileName or SceneText");
}
}
