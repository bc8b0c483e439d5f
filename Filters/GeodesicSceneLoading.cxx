#include "GeodesicSceneLoading.h"

#include "vtkGeodesicSource.h"

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
  if (text && *text)
    return parseScene(text, textDirectory && *textDirectory ? textDirectory : ".",
                      vtkImageFileLoader());
  if (fileName && *fileName)
    return loadSceneFile(fileName, vtkImageFileLoader());
  throw InvalidParameter("no scene: set SceneFileName or SceneText");
}
}
