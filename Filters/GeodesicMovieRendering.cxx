// The rendering a movie is made with (GeodesicMovie.h): where no rendering was asked for, the
// default one, judged against the target on the first and last frames (their probes traced
// converged); a cheaper adaptive cap where that still reaches the target, a dearer one where the
// default does not, the accurate preset where neither does.
//
// The caps share the default's centre rays (its grid and integrator): a frame at one is the
// default's anti-aliased again (FrameTracer::antialiasAgain), so what a cap reaches is measured
// on the default frames' probes for a few hundred rays, and the raised movie's first and last
// frames cost the rays of their sampled pixels, not two frames traced again.
#include "GeodesicMovie.h"

#include "vtkGeodesicSource.h"

#include <algorithm>
#include <limits>

namespace asrt
{
bool MovieMaker::judgesRendering() const
{
  return this->Settings.holdToConverged &&
         this->Frames.front().identity.rendering == AntialiasOptions();
}

std::unique_ptr<MovieMaker> MovieMaker::withRenderingForTarget(vtkGeodesicSource* source,
                                                               const MoviePath& path,
                                                               RenderingChoice& choice, bool raise,
                                                               bool lower)
{
  choice = RenderingChoice();
  if (!this->judgesRendering() || (!raise && !lower))
    return nullptr;
  const int last = static_cast<int>(this->Frames.size()) - 1;
  choice.defaultReach = std::min(this->settingsReach(0), this->settingsReach(last));
  // The frames between may score lower than both ends: on the mass ramp at 200 × 200 the
  // default's worst frame lies 1 dB below its lower end against converged frames.
  const double enough = this->Settings.quality + 1.0;
  const bool defaultEnough = choice.defaultReach >= enough;
  if (defaultEnough ? !lower : !raise)
    return nullptr;
  // The movie's frames at the other cap, and what it reaches.
  const int asked = source->GetMaxRaysPerPixel();
  const int cap = defaultEnough ? kLoweredRaysPerPixel : kRaisedRaysPerPixel;
  std::vector<MovieFrame> frames;
  try
  {
    source->SetMaxRaysPerPixel(cap);
    frames = movieFrames(source, path);
    // The lower cap by its bound: on the mass ramp at 200 × 200 its estimate on the ends
    // (37.0 dB) lies 2 dB above what the last frame scores against its converged frame, and
    // frames between score 34.1 dB; its bound, 35.2 dB, leaves the default.
    choice.reach = std::min(this->settingsReachAt(0, frames.front(), defaultEnough),
                            this->settingsReachAt(last, frames.back(), defaultEnough));
  }
  catch (...)
  {
    source->SetMaxRaysPerPixel(asked);
    throw;
  }
  if (choice.reach >= enough)
  {
    auto made =
      std::make_unique<MovieMaker>(std::move(frames), this->Parameter, this->Store, this->Settings);
    if (defaultEnough)
    {
      // The ends made here at the default rendering stay the movie's ends: tracing them again at
      // the lower cap would cost two frames to save a tenth of two.
      choice.change = RenderingChoice::Change::Lowered;
      made->adoptWhole(*this, 0);
      made->adoptWhole(*this, last);
    }
    else
    {
      choice.change = RenderingChoice::Change::Raised;
      made->deriveWhole(*this, 0);
      made->deriveWhole(*this, last);
    }
    return made;
  }
  source->SetMaxRaysPerPixel(asked);
  if (defaultEnough)
    return nullptr;
  // The accurate preset's keys hold 40 dB on the bench's four paths (bench/REPORT.md, "T = 40
  // held on all four paths").
  choice.change = RenderingChoice::Change::Accurate;
  source->SetIntegrationPreset("accurate");
  return std::make_unique<MovieMaker>(movieFrames(source, path), this->Parameter, this->Store,
                                      this->Settings);
}
}
