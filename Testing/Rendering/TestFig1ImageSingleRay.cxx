// The paper's Fig. 1 traced one ray a pixel, point-sampled (antialias "none"), as before
// anti-aliasing existed. The baseline was inspected: the shadow is centred, the cylinders bend
// round it into Einstein-ring arcs, the sky is lensed into a ring; edges and checks are jagged.
#include "RenderingTestUtilities.h"
#include "vtkGeodesicSource.h"

int TestFig1ImageSingleRay(int argc, char* argv[])
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(asrt::testing::scenePath("fig1-cylinders.json").c_str());
  source->SetAntialias("none");
  source->Update();
  return asrt::testing::compareFrame(source->GetImageOutput(), argc, argv);
}
