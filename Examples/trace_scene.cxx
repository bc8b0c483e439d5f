// Traces a scene file to a PNG image (and the hit records to a VTK XML file if asked).
// Usage: asrt_trace_scene scene.json out.png [width height] [hits.vtp]
#include "vtkGeodesicSource.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkXMLPolyDataWriter.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char* argv[])
{
  if (argc < 3)
  {
    std::fprintf(stderr, "usage: %s scene.json out.png [width height] [hits.vtp]\n", argv[0]);
    return 2;
  }
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(argv[1]);
  if (argc >= 5)
    source->SetResolution(std::atoi(argv[3]), std::atoi(argv[4]));
  const auto t0 = std::chrono::steady_clock::now();
  source->Update();
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (source->GetImageOutput()->GetNumberOfPoints() == 0)
    return 1; // the source has reported why
  vtkNew<vtkPNGWriter> png;
  png->SetInputConnection(source->GetOutputPort(0));
  png->SetFileName(argv[2]);
  png->Write();
  if (argc >= 6)
  {
    vtkNew<vtkXMLPolyDataWriter> hits;
    hits->SetInputConnection(source->GetOutputPort(1));
    hits->SetFileName(argv[5]);
    hits->Write();
  }
  int dims[3];
  source->GetImageOutput()->GetDimensions(dims);
  std::printf("%s: %d x %d in %.2f s -> %s\n", argv[1], dims[0], dims[1], seconds, argv[2]);
  return 0;
}
