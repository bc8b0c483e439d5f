// The paper's Fig. 1 traced by vtkGeodesicSource: three cylinders crossing where a Schwarzschild
// hole sits, a checkered plane and a galaxy behind, with the default (adaptive) anti-aliasing. The
// baseline was inspected: the shadow is centred, the cylinders bend round it into Einstein-ring
// arcs, the sky is lensed into a ring; check edges are smooth and the thin arcs along the shadow
// continuous, where TestFig1ImageSingleRay's are jagged and broken into dots.
#include "RenderingTestUtilities.h"
#include "vtkGeodesicSource.h"

int TestFig1Image(int argc, char* argv[])
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(asrt::testing::scenePath("fig1-cylinders.json").c_str());
  source->Update();
  return asrt::testing::compareFrame(source->GetImageOutput(), argc, argv);
}
