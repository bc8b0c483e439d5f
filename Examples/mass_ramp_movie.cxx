// The paper's movie of a growing hole (Figs. 4 and 5, M = 0.1 to 1.2), made the accumulative
// way: six key frames along the ramp (M = 0.1, 0.32, ..., 1.2; Data/scenes/fig4-mass-start.json
// with the mass set) are traced, and the 5 frames between each pair are interpolated by
// vtkGeodesicFrameInterpolator, which matches the rays of the two key frames that hit the same
// scene point instead of tracing again. Key frames along the ramp rather than its two ends alone:
// the ends lie too far apart for matching (bench/REPORT.md). Writes mass-ramp-000.png ...
// mass-ramp-030.png and the movie mass-ramp.ogv.
//
// Usage: asrt_example_mass_ramp_movie OUTPUT_DIR [SIZE]   (default: the scene's 200 x 200)
#include "vtkGeodesicFrameInterpolator.h"
#include "vtkGeodesicSource.h"

#include "DataFiles.h"
#include "MovieWriter.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkSmartPointer.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR [SIZE]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int size = argc > 2 ? std::atoi(argv[2]) : 0;
  const std::string scene = std::string(ASRT_DATA_DIR) + "/scenes/fig4-mass-start.json";
  constexpr int keyFrames = 6, between = 5;
  constexpr double firstMass = 0.1, lastMass = 1.2;

  // The key frames, traced. Their hit points (port 1) carry each ray's record: what the
  // interpolator matches.
  std::vector<vtkSmartPointer<vtkGeodesicSource>> keys;
  for (int k = 0; k < keyFrames; ++k)
  {
    auto key = vtkSmartPointer<vtkGeodesicSource>::New();
    key->SetSceneFileName(scene.c_str());
    key->SetMass(firstMass + (lastMass - firstMass) * k / (keyFrames - 1));
    if (size > 0)
      key->SetResolution(size, size);
    keys.push_back(key);
  }
  // One interpolator per consecutive pair; each declares the time steps k / (5 + 1).
  std::vector<vtkSmartPointer<vtkGeodesicFrameInterpolator>> pairs;
  for (int k = 0; k + 1 < keyFrames; ++k)
  {
    auto pair = vtkSmartPointer<vtkGeodesicFrameInterpolator>::New();
    pair->SetFrameAConnection(keys[k]->GetOutputPort(1));
    pair->SetFrameBConnection(keys[k + 1]->GetOutputPort(1));
    pair->SetNumberOfIntermediateFrames(between);
    pairs.push_back(pair);
  }
  try
  {
    asrt::tools::MovieWriter movie(out + "/mass-ramp.ogv", 10);
    const int frames = (keyFrames - 1) * (between + 1) + 1;
    for (int k = 0; k < frames; ++k)
    {
      // A key frame between two pairs is the end of one and the start of the next: made once.
      const int pair = k == frames - 1 ? keyFrames - 2 : k / (between + 1);
      const double t = double(k - pair * (between + 1)) / (between + 1);
      pairs[pair]->UpdateTimeStep(t);
      vtkImageData* frame = pairs[pair]->GetOutput();
      if (frame->GetNumberOfPoints() == 0)
        return 1; // a source or the interpolator has said why on stderr
      char name[64];
      std::snprintf(name, sizeof name, "/mass-ramp-%03d.png", k);
      asrt::tools::writePng(frame, out + name); // whole or not at all, never through a link
      movie.addFrame(frame);
      // Field data: the mass at t, and the shares of pixels matched, one-sided, holes, ...
      vtkFieldData* about = frame->GetFieldData();
      std::printf("%s  pair %d, t = %.3f  M = %.3f  matched %.1f%%\n", (out + name).c_str(), pair,
                  t, about->GetArray("Mass")->GetComponent(0, 0),
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
