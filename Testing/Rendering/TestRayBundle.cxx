// The 3D ray bundle around the hole: a fan of traced rays (port 2) of the Fig. 1 scene's camera,
// with the horizon and the scene's objects. The baseline was inspected: rays leave the eye as a
// fan, those aimed inside the shadow end on the black horizon sphere, the others bend round it.
#include "RenderingTestUtilities.h"
#include "vtkActor.h"
#include "vtkGeodesicSceneGeometry.h"
#include "vtkGeodesicSource.h"
#include "vtkIntArray.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"

int TestRayBundle(int argc, char* argv[])
{
  const std::string scene = asrt::testing::scenePath("fig1-cylinders.json");
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene.c_str());
  source->SetResolution(40, 40);
  source->GeneratePolylinesOn();
  // The middle row and column of pixels: two fans through the hole.
  vtkNew<vtkIntArray> fan;
  fan->SetNumberOfComponents(2);
  for (int k = 0; k < 40; k += 2)
  {
    const int a[2] = { k, 20 }, b[2] = { 20, k };
    fan->InsertNextTypedTuple(a);
    fan->InsertNextTypedTuple(b);
  }
  source->SetPolylinePixels(fan);
  source->SetPixelSubset(fan); // trace only those for the frame too: the test is about paths
  source->Update();

  vtkNew<vtkPolyDataMapper> rayMapper;
  rayMapper->SetInputConnection(source->GetOutputPort(2));
  rayMapper->SetScalarModeToUsePointFieldData();
  rayMapper->SelectColorArray("R");
  rayMapper->SetScalarRange(2.0, 32.0);
  vtkNew<vtkActor> rays;
  rays->SetMapper(rayMapper);
  rays->GetProperty()->SetLineWidth(1.5);

  vtkNew<vtkGeodesicSceneGeometry> geometry;
  geometry->SetSceneFileName(scene.c_str());
  geometry->SetIncludeCelestialSphere(false);
  vtkNew<vtkPolyDataMapper> objectMapper;
  objectMapper->SetInputConnection(geometry->GetOutputPort());
  objectMapper->SetScalarModeToUsePointFieldData();
  objectMapper->SelectColorArray("Colors");
  vtkNew<vtkActor> objects;
  objects->SetMapper(objectMapper);
  objects->GetProperty()->SetOpacity(0.6);

  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(rays);
  renderer->AddActor(objects);
  renderer->SetBackground(0.1, 0.1, 0.15);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(300, 300);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(window);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(30, -14, 22);
  camera->SetFocalPoint(0, -9, 0);
  camera->SetViewUp(0, 0, 1);
  renderer->ResetCameraClippingRange();
  camera->SetViewAngle(40);
  window->Render();
  const int result = vtkRegressionTestImage(window);
  if (result == vtkRegressionTester::DO_INTERACTOR)
    interactor->Start();
  return !result;
}
