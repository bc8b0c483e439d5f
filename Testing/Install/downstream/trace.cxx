// Traces a scene file at a small resolution through vtkGeodesicSource and writes the frame as a
// PNG: what a project linking ASRT::Filters from an installed ASRT does first.
// Usage: downstream_trace SCENE.json OUT.png WIDTH HEIGHT
#include "vtkGeodesicSource.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"

#include <cstdio>
#include <cstdlib>

int main(int argc, char* argv[])
{
  if (argc != 5)
  {
    std::fprintf(stderr, "usage: %s SCENE.json OUT.png WIDTH HEIGHT\n", argv[0]);
    return 2;
  }
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(argv[1]);
  const int width = std::atoi(argv[3]), height = std::atoi(argv[4]);
  source->SetResolution(width, height);
  source->Update();
  // A scene that fails to load leaves an empty frame (and VTK's error on stderr).
  vtkImageData* frame = source->GetImageOutput();
  int dims[3] = { 0, 0, 0 };
  frame->GetDimensions(dims);
  if (dims[0] != width || dims[1] != height || !frame->GetPointData()->GetArray("Colors"))
  {
    std::fprintf(stderr, "downstream_trace: tracing %s failed\n", argv[1]);
    return 1;
  }
  frame->GetPointData()->SetActiveScalars("Colors");
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(frame);
  writer->SetFileName(argv[2]);
  writer->Write();
  return writer->GetErrorCode() == 0 ? 0 : 1;
}
