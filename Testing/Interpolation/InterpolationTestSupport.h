// Shared helpers of the interpolation tests: frames traced by vtkGeodesicSource (deep copies, so
// that each test owns its inputs), the interpolator run at a time, the RGB bytes of an image, and
// PNGs of what the tests compared, written when ASRT_INTERPOLATION_DUMP names a directory.
#ifndef asrt_InterpolationTestSupport_h
#define asrt_InterpolationTestSupport_h

#include "FiltersTestUtilities.h"
#include "ImageQuality.h"
#include "vtkGeodesicFrameInterpolator.h"
#include "vtkGeodesicSource.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTrivialProducer.h"
#include "vtkUnsignedCharArray.h"

#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

namespace asrt
{
namespace testing
{
/// One traced frame: its image (port 0) and hit points (port 1), owned.
struct TracedFrame
{
  vtkSmartPointer<vtkImageData> image;
  vtkSmartPointer<vtkPolyData> hits;
};

inline TracedFrame traceWith(const std::function<void(vtkGeodesicSource*)>& configure)
{
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  watch(source, catcher);
  // Every pixel its own ray, as the interpolators re-trace pixels: the tests hold re-traced pixels
  // to frames traced here. A test may still ask for the grid.
  source->SetGridLattice(1);
  configure(source);
  source->Update();
  EXPECT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  TracedFrame f;
  f.image = vtkSmartPointer<vtkImageData>::New();
  f.image->DeepCopy(source->GetImageOutput());
  f.hits = vtkSmartPointer<vtkPolyData>::New();
  f.hits->DeepCopy(source->GetHitsOutput());
  return f;
}

/// The RGB bytes of an image's "Colors", row-major from the bottom-left.
inline std::vector<std::uint8_t> rgbOf(vtkImageData* image)
{
  auto* colors = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetArray("Colors"));
  if (!colors || colors->GetNumberOfComponents() != 3)
  {
    ADD_FAILURE() << "the image has no RGB Colors";
    return {};
  }
  return std::vector<std::uint8_t>(colors->GetPointer(0),
                                   colors->GetPointer(0) + 3 * colors->GetNumberOfTuples());
}

inline RgbView view(const std::vector<std::uint8_t>& rgb, int w, int h)
{
  return RgbView{ w, h, rgb.data() };
}

/// A pipeline producing a given data object (the frames as an interpolator's inputs).
inline vtkSmartPointer<vtkTrivialProducer> producerOf(vtkDataObject* data)
{
  auto p = vtkSmartPointer<vtkTrivialProducer>::New();
  p->SetOutput(data);
  return p;
}

/// Writes the image (its RGB Colors) as <ASRT_INTERPOLATION_DUMP>/<name>.png, if set.
inline void dump(vtkImageData* image, const std::string& name)
{
  const char* dir = std::getenv("ASRT_INTERPOLATION_DUMP");
  if (!dir || !*dir)
    return;
  vtkNew<vtkImageData> copy;
  copy->ShallowCopy(image);
  copy->GetPointData()->SetActiveScalars("Colors");
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(copy);
  writer->SetFileName((std::string(dir) + "/" + name + ".png").c_str());
  writer->Write();
}

inline double fieldValue(vtkDataObject* data, const char* name, int component = 0)
{
  vtkDataArray* a = data->GetFieldData()->GetArray(name);
  if (!a)
  {
    ADD_FAILURE() << "no field data \"" << name << "\"";
    return 0;
  }
  return a->GetComponent(0, component);
}
}
}

#endif
