// Loading a scene in the VTK layer: textures through vtkGeodesicSource::LoadImagePixels.
#ifndef asrt_GeodesicSceneLoading_h
#define asrt_GeodesicSceneLoading_h

#include "SceneFile.h"

namespace asrt
{
/// An ImageLoader on vtkGeodesicSource::LoadImagePixels (libpng for PNG, VTK's readers for other
/// formats, sizes checked before decoding); throws InvalidParameter for missing or unreadable
/// files.
ImageLoader vtkImageFileLoader();
/// The scene from JSON text if given (relative texture paths against `textDirectory`, the working
/// directory if null or empty), else from the file; throws InvalidParameter if neither is set or
/// the scene is invalid. Given both, the text is the file's content as the caller read it: its
/// textures are found beside the file and errors name the file. Textures are read through
/// `loader` (vtkImageFileLoader() if empty).
SceneDescription loadScene(const char* text, const char* fileName,
                           const char* textDirectory = nullptr, ImageLoader loader = {});
}

#endif
