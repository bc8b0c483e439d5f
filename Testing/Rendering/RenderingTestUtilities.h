// Shared set-up of the regression image tests: a fixed-size window under Xvfb, and the scene
// presets found relative to the source tree.
#ifndef asrt_RenderingTestUtilities_h
#define asrt_RenderingTestUtilities_h

#include "vtkCamera.h"
#include "vtkImageActor.h"
#include "vtkImageData.h"
#include "vtkImageMapper3D.h"
#include "vtkNew.h"
#include "vtkRegressionTestImage.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"

#include <string>

namespace asrt
{
namespace testing
{
inline std::string scenePath(const char* name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/scenes/" + name;
}

/// Shows a traced frame pixel for pixel: one image pixel per window pixel.
inline int compareFrame(vtkImageData* frame, int argc, char* argv[])
{
  int dims[3];
  frame->GetDimensions(dims);
  vtkNew<vtkImageActor> actor;
  actor->GetMapper()->SetInputData(frame);
  actor->InterpolateOff();
  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(dims[0], dims[1]);
  window->AddRenderer(renderer);
  window->SetMultiSamples(0);
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(window);
  renderer->ResetCamera();
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->ParallelProjectionOn();
  camera->SetParallelScale(0.5 * dims[1]);
  window->Render();
  int result = vtkRegressionTestImage(window);
  if (result == vtkRegressionTester::DO_INTERACTOR)
  {
    interactor->Start();
  }
  return !result;
}
}
}

#endif
