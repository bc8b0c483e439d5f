// A bundle of rays around the hole in 3D: the rays of the middle row and column of the Fig. 1
// camera's image, traced as polylines (vtkGeodesicSource's port 2) and drawn with the scene's
// objects and the horizon, coloured by how each ray ended. Rendered off screen to a PNG (Debian's
// VTK renders through X: run it under xvfb-run -a on a machine without a display).
//
// Usage: asrt_example_ray_bundle OUTPUT_DIR [SIZE]   (the traced image's SIZE x SIZE; default 41)
#include "vtkGeodesicSource.h"

#include "RayBundleView.h"

#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
#include "vtkRenderer.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR [SIZE]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int size = argc > 2 ? std::atoi(argv[2]) : 41;
  try
  {
    vtkNew<vtkGeodesicSource> source;
    source->SetSceneFileName((std::string(ASRT_DATA_DIR) + "/scenes/fig1-cylinders.json").c_str());
    source->SetResolution(size, size);
    // Two fans through the hole; tracing only their pixels keeps it quick.
    vtkSmartPointer<vtkIntArray> fan = asrt::tools::crossPixels(size, size, 2);
    source->GeneratePolylinesOn();
    source->SetPolylinePixels(fan);
    source->SetPixelSubset(fan);
    source->Update();
    if (source->GetHitsOutput()->GetNumberOfPoints() == 0)
      return 1; // the source has said why on stderr

    asrt::tools::RayBundleStyle style;
    style.coloring = asrt::tools::RayColoring::Termination;
    style.title = "Fig. 1 scene: rays of the middle row and column";
    vtkSmartPointer<vtkRenderer> view = asrt::tools::makeRayBundleRenderer(source, style);
    asrt::tools::renderToPng(view, 800, 600, out + "/ray-bundle.png");
    std::printf("%s/ray-bundle.png\n", out.c_str());
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
  return 0;
}
