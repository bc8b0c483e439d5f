// The paper's Fig. 2: the Fig. 1 scene with no hole (M = 0), traced as exact straight lines. The
// baseline (default anti-aliasing) was inspected: straight cylinders through the centre, an
// undistorted plane and sky, smooth check edges on the floor and no moiré on the far cylinder.
#include "RenderingTestUtilities.h"
#include "vtkGeodesicSource.h"

int TestFig2Image(int argc, char* argv[])
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(asrt::testing::scenePath("fig2-no-hole.json").c_str());
  source->Update();
  return asrt::testing::compareFrame(source->GetImageOutput(), argc, argv);
}
