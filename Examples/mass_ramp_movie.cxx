// The paper's 30-frame movie of a growing hole (Figs. 4 and 5): the first frame (M = 0.1,
// Data/scenes/fig4-mass-start.json) and the last (M = 1.2, fig5-mass-end.json) are traced; the 28
// between them are interpolated by vtkGeodesicFrameInterpolator, which matches the rays of the
// two ends that hit the same scene point instead of tracing again. Writes mass-ramp-000.png ...
// mass-ramp-029.png and the movie mass-ramp.ogv.
//
// Usage: asrt_example_mass_ramp_movie OUTPUT_DIR [SIZE]   (default: the scenes' 200 x 200)
#include "vtkGeodesicFrameInterpolator.h"
#include "vtkGeodesicSource.h"

#include "MovieWriter.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"

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
  const int size = argc > 2 ? std::atoi(argv[2]) : 0;
  const std::string scenes = std::string(ASRT_DATA_DIR) + "/scenes/";

  // The two ends, traced. Their hit points (port 1) carry each ray's record: what the
  // interpolator matches.
  vtkNew<vtkGeodesicSource> start, end;
  start->SetSceneFileName((scenes + "fig4-mass-start.json").c_str());
  end->SetSceneFileName((scenes + "fig5-mass-end.json").c_str());
  if (size > 0)
  {
    start->SetResolution(size, size);
    end->SetResolution(size, size);
  }

  vtkNew<vtkGeodesicFrameInterpolator> interpolator;
  interpolator->SetFrameAConnection(start->GetOutputPort(1));
  interpolator->SetFrameBConnection(end->GetOutputPort(1));
  interpolator->SetNumberOfIntermediateFrames(28);
  try
  {
    asrt::tools::MovieWriter movie(out + "/mass-ramp.ogv", 10);
    for (int k = 0; k < 30; ++k)
    {
      const double t = k / 29.0; // the time steps the interpolator declares: k / (28 + 1)
      interpolator->UpdateTimeStep(t);
      vtkImageData* frame = interpolator->GetOutput();
      if (frame->GetNumberOfPoints() == 0)
        return 1; // a source or the interpolator has said why on stderr
      char name[64];
      std::snprintf(name, sizeof name, "/mass-ramp-%03d.png", k);
      vtkNew<vtkPNGWriter> png;
      png->SetInputData(frame);
      png->SetFileName((out + name).c_str());
      png->Write();
      if (png->GetErrorCode() != 0)
        return 1;
      movie.addFrame(frame);
      // Field data: the mass at t, and the shares of pixels matched, one-sided, holes, ...
      vtkFieldData* about = frame->GetFieldData();
      std::printf("%s  t = %.3f  M = %.3f  matched %.1f%%\n", (out + name).c_str(), t,
                  about->GetArray("Mass")->GetComponent(0, 0),
                  100 * about->GetArray("InterpolationFractions")->GetComponent(0, 0));
    }
    movie.close();
    std::printf("%s/mass-ramp.ogv\n", out.c_str());
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
  return 0;
}
