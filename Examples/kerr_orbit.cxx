// A camera orbiting a Kerr hole (a = 0.9 M) with a thin accretion disk
// (Data/scenes/kerr-disk.json): a few frames along a full orbit about the spin axis, each written
// as a PNG and as VTK image data, with a .pvd collection that ParaView opens as a time series, and
// an Ogg Theora movie. The eye keeps its distance and height, so the hole and the disk look the
// same from every side while the sky turns behind them.
//
// Usage: asrt_example_kerr_orbit OUTPUT_DIR [SIZE] [FRAMES]   (default: the scene's size, 8 frames)
#include "vtkGeodesicSource.h"

#include "CameraOrbit.h"
#include "DataFiles.h"
#include "MovieWriter.h"
#include "PvdCollection.h"

#include "vtkImageData.h"
#include "vtkNew.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR [SIZE] [FRAMES]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int size = argc > 2 ? std::atoi(argv[2]) : 0;
  const int frames = argc > 3 ? std::atoi(argv[3]) : 8;
  const std::string scene = std::string(ASRT_DATA_DIR) + "/scenes/kerr-disk.json";
  try
  {
    const asrt::tools::CameraPose start = asrt::tools::sceneCamera(scene);
    vtkNew<vtkGeodesicSource> source;
    source->SetSceneFileName(scene.c_str());
    if (size > 0)
      source->SetResolution(size, size);

    asrt::tools::PvdCollection series;
    asrt::tools::MovieWriter movie(out + "/kerr-orbit.ogv", 4);
    for (int k = 0; k < frames; ++k)
    {
      const double degrees = asrt::tools::orbitAngle(k, frames, 360.0);
      asrt::tools::setCamera(source, asrt::tools::turnedAboutZ(start, degrees));
      source->Update();
      if (source->GetImageOutput()->GetNumberOfPoints() == 0)
        return 1; // the source has said why on stderr

      char name[64];
      std::snprintf(name, sizeof name, "/kerr-orbit-%03d", k);
      // VTK's PNG and XML writers, each frame's two files appearing together (a set of
      // temporaries renamed into place); the .vti has every per-pixel array, for ParaView.
      asrt::tools::AtomicFileSet files;
      asrt::tools::writePng(source->GetImageOutput(), files.add(out + name + ".png"));
      asrt::tools::writeVti(source->GetImageOutput(), files.add(out + name + ".vti"));
      files.commit();
      series.add(degrees, out + name + ".vti"); // time = the camera's angle in degrees
      movie.addFrame(source->GetImageOutput());
      std::printf("%s.png (%g deg)\n", (out + name).c_str(), degrees);
    }
    series.write(out + "/kerr-orbit.pvd");
    movie.close();
    std::printf("%s/kerr-orbit.pvd\n%s/kerr-orbit.ogv\n", out.c_str(), out.c_str());
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
  return 0;
}
