#include "GeodesicMovieMaking.h"

#include "ErrorEstimate.h"
#include "RayStore.h"
#include "RecordAllocation.h"
#include "SceneFile.h"
#include "SettingsError.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

namespace asrt
{

namespace
{
/// The prior of the re-trace share (SpacingShareModel), until the first keys are measured: a
/// quarter of a frame re-traced, beyond the probes, between keys a quarter of the path apart. The
/// paper's mass ramp re-traced 23 % in exact mode with keys ΔM = 0.2 apart on M 0.1 → 1.2 (README,
/// "Interpolated movies").
constexpr double kPriorSlope = 1.0;
/// A movie's costs before any is measured, for frames of `pixels` pixels, in rays: a whole frame
/// traces the adaptive grid's centre rays, in proportion to its area, and anti-aliasing samples
/// and edge midpoints along its edges, in proportion to its side (√pixels); a re-trace, beyond
/// its pixels' own centre rays, its edge neighbours, edge midpoints and samples (RetraceRays.h),
/// along the edges too; interpolating a frame (without its re-trace) takes CPU in proportion to
/// its pixels. Fitted to the mass ramp of Figs. 4–5 at 35 dB: whole frames 40 289 rays on average
/// at 200 × 200 (31 frames; 47 364 on the 90° orbit of Fig. 1) and 6 650 at 48 × 48 (7 frames);
/// a re-trace's edges 17 000 to 29 000 rays at 200 × 200 with keys two frames apart (about
/// 22 000 on the orbit) and about 5 000 at 48 × 48; interpolating a frame took the CPU time of
/// 0.125 (ramp) and 0.15 (orbit) rays a pixel at 200 × 200. The last is never measured while
/// planning (a time would make the plan differ from run to run): where rays cost more (Kerr), it
/// overstates interpolating.
MovieCostPrior movieCostPrior(double pixels)
{
  const double side = std::sqrt(pixels);
  MovieCostPrior prior;
  prior.wholeRaysPerPixel = 0.41 + 118 / side;
  prior.edgeRaysPerPixel = 110 / side;
  prior.interpolationRaysPerPixel = 0.15;
  return prior;
}
/// The most bytes of records kept of the frames made from the store alone while planning (a
/// quarter of the memory a read may take, at most 1 GiB): the frames beyond are made again.
double servedBytesKept()
{
  return std::min(double(1 << 30), defaultMemoryLimit() / 4);
}
}

MovieMaker::MovieMaker(std::vector<MovieFrame> frames, std::string parameter, RayStore* store,
                       MovieSettings settings)
  : Frames(std::move(frames))
  , Parameter(std::move(parameter))
  , Store(store)
  , Settings(std::move(settings))
  , Impl(new Internals)
{
  if (this->Frames.size() < 2)
    throw InvalidParameter("frames: a movie has at least 2 frames, got " +
                           std::to_string(this->Frames.size()));
  if (!(this->Settings.quality > 0.0 && this->Settings.quality <= kMaxQualityTargetDb))
    throw InvalidParameter("quality: the target must lie in (0, " +
                           formatParameter(kMaxQualityTargetDb) + "] dB, got " +
                           formatParameter(this->Settings.quality));
  if (!(this->Settings.keptFrameBytes >= 0.0))
    throw InvalidParameter("keptFrameBytes: the bytes of frames kept must be 0 or more, got " +
                           formatParameter(this->Settings.keptFrameBytes));
  if (!(this->Settings.unstoredFrameBytes >= 0.0))
    throw InvalidParameter(
      "unstoredFrameBytes: the bytes of frames kept unstored must be 0 or more, got " +
      formatParameter(this->Settings.unstoredFrameBytes));
  this->Width = this->Frames.front().identity.camera.width;
  this->Height = this->Frames.front().identity.camera.height;
  for (const MovieFrame& f : this->Frames)
    if (f.identity.camera.width != this->Width || f.identity.camera.height != this->Height)
      throw InvalidParameter("frames: " + f.describe + " is " +
                             std::to_string(f.identity.camera.width) + "x" +
                             std::to_string(f.identity.camera.height) + ", the first frame " +
                             std::to_string(this->Width) + "x" + std::to_string(this->Height));
}

MovieMaker::~MovieMaker() = default;

const SpacingShareModel& MovieMaker::shareModel() const
{
  return this->Impl->share;
}

namespace
{
/// The plan of the frames `open` (a plan of open.size() frames, indices into `open`) as the plan
/// of the whole movie of n frames: the frames not open are the recorded ones, interpolated
/// between their recorded keys at no cost.
MoviePlan wholeMoviePlan(const MoviePlan& planned, const std::vector<int>& open, std::size_t n,
                         const std::map<int, std::vector<int>>& recorded)
{
  MoviePlan plan = planned;
  plan.frames.assign(n, FramePlan());
  for (std::size_t i = 0; i < open.size(); ++i)
  {
    FramePlan f = planned.frames[i];
    if (f.keyBefore >= 0)
      f.keyBefore = open[static_cast<std::size_t>(f.keyBefore)];
    if (f.keyAfter >= 0)
      f.keyAfter = open[static_cast<std::size_t>(f.keyAfter)];
    plan.frames[static_cast<std::size_t>(open[i])] = f;
  }
  for (const auto& [k, keys] : recorded)
  {
    FramePlan& f = plan.frames[static_cast<std::size_t>(k)];
    f.method = FrameMethod::Interpolated;
    const auto after = std::upper_bound(keys.begin(), keys.end(), k);
    f.keyBefore = *(after - 1);
    f.keyAfter = *after;
    plan.directRays += planned.frameRays;
    plan.tracedAllRays += planned.frameRays;
  }
  return plan;
}

/// The frames a plan plans (of a movie of n frames): every frame not recorded, in order.
std::vector<int> openFrames(std::size_t n, const std::map<int, std::vector<int>>& recorded)
{
  std::vector<int> open;
  for (int k = 0; k < static_cast<int>(n); ++k)
    if (!recorded.count(k))
      open.push_back(k);
  return open;
}

/// The open frames' path parameters and whether each is stored whole: what a plan plans over.
void openPath(const std::vector<MovieFrame>& frames, const std::vector<int>& open,
              std::vector<double>& s, std::vector<bool>& stored)
{
  s.clear();
  stored.clear();
  for (int k : open)
  {
    s.push_back(frames[static_cast<std::size_t>(k)].s);
    stored.push_back(frames[static_cast<std::size_t>(k)].storedId.has_value());
  }
}
}

void MovieMaker::findRecorded()
{
  std::map<std::int64_t, int> frameOfId;
  for (std::size_t k = 0; k < this->Frames.size(); ++k)
    if (this->Frames[k].storedId)
      frameOfId[*this->Frames[k].storedId] = static_cast<int>(k);
  const std::string plain = interpolationRecipe(this->Settings),
                    chained = interpolationRecipe(this->Settings, true);
  for (std::size_t k = 0; k < this->Frames.size() && this->Store; ++k)
  {
    if (this->Frames[k].storedId)
      continue;
    // Made between its keys alone, else through the chains too.
    bool isChained = false;
    auto ids = this->Store->interpolatedFrameKeys(this->Frames[k].identity, plain);
    if (!ids)
    {
      ids = this->Store->interpolatedFrameKeys(this->Frames[k].identity, chained);
      isChained = true;
    }
    if (!ids)
      continue;
    std::vector<int> keys;
    for (std::int64_t id : *ids)
    {
      const auto key = frameOfId.find(id);
      if (key == frameOfId.end())
        break;
      keys.push_back(key->second);
    }
    // Keys of another movie (another frame count, another path) are not this movie's to read.
    const bool bracketed = keys.size() == ids->size() && std::is_sorted(keys.begin(), keys.end()) &&
                           keys.front() < static_cast<int>(k) && keys.back() > static_cast<int>(k);
    if (bracketed)
    {
      this->Impl->recorded[static_cast<int>(k)] = keys;
      (isChained ? this->Impl->recordedChained : this->Impl->chainSources)
        .insert(static_cast<int>(k));
    }
  }
}

const MoviePlan& MovieMaker::plan()
{
  if (this->Plan)
    return *this->Plan;
  const std::size_t n = this->Frames.size();
  for (MovieFrame& f : this->Frames)
    if (this->Store)
      f.storedId = this->Store->findFrame(f.identity);
  // Frames made before between keys stored now are made again between those (findRecorded); the
  // plan is of the others, the open frames (indices into `open` below).
  this->findRecorded();
  const std::vector<int> open = openFrames(n, this->Impl->recorded);
  std::vector<double> s;
  std::vector<bool> stored;
  openPath(this->Frames, open, s, stored);
  const std::size_t m = open.size();
  SpacingShareModel& share = this->Impl->share;
  share.pathLength = std::abs(s.back() - s.front());
  share.floor =
    std::min(1.0, std::max(kMovieProbeFraction, 64.0 / (static_cast<double>(this->Width) *
                                                        static_cast<double>(this->Height))));
  share.slope = kPriorSlope;
  const double pixels = static_cast<double>(this->Width) * this->Height;
  const MovieCostModel model = movieCostPrior(pixels).model(pixels, share.function());
  MoviePlan bisected = planMovie(s, stored, model);
  std::vector<int> storedKeys, plannedKeys;
  for (std::size_t i = 0; i < m; ++i)
    if (stored[i])
      storedKeys.push_back(open[i]);
  for (int i : bisected.keys())
    plannedKeys.push_back(open[static_cast<std::size_t>(i)]);
  // The other candidate, the stored frames as the only keys, is worth a look only when the
  // bisection wants keys of its own and the store has both ends (planBetweenStored).
  if (plannedKeys != storedKeys && stored.front() && stored.back())
  {
    MovieMaking making{ *this, *this->Impl };
    std::vector<bool> served(m, false);
    double kept = 0;
    for (std::size_t i = 0; i < m; ++i)
    {
      // A frame of which no pixel was traced before cannot be served (every completion traces
      // its probes at least): asking the store says so without interpolating it.
      if (stored[i] ||
          !this->Store->hasSubsetFrames(this->Frames[static_cast<std::size_t>(open[i])].identity))
        continue;
      MovieFrameReport dry;
      try
      {
        std::vector<RayRecord> records = making.interpolated(open[i], storedKeys, dry, true);
        served[i] = true;
        const double bytes = static_cast<double>(records.size() * sizeof(RayRecord));
        if (kept + bytes <= servedBytesKept())
        {
          kept += bytes;
          this->Impl->served.emplace(open[i], std::make_pair(std::move(records), dry));
        }
      }
      catch (const NotServed&)
      {
      }
    }
    const std::optional<MoviePlan> between = planBetweenStored(s, stored, served, model);
    if (between && between->estimatedRays < bisected.estimatedRays)
      bisected = *between;
    else // other keys: the frames made between the stored ones are not the plan's
      this->Impl->served.clear();
  }
  this->Plan = wholeMoviePlan(bisected, open, n, this->Impl->recorded);
  return *this->Plan;
}

void MovieMaker::makeKeys(const std::function<void(int frame)>& afterEach)
{
  if (this->Impl->keysMade)
    return;
  MovieMaking making{ *this, *this->Impl };
  const MoviePlan& first = this->plan();
  const bool traces =
    std::any_of(first.frames.begin(), first.frames.end(),
                [](const FramePlan& f)
                { return f.method == FrameMethod::Key || f.method == FrameMethod::Traced; });
  if (traces)
  {
    // Keys to trace: made coarse first, each measured against an interpolation of itself, and
    // the rest planned again with what was learnt (planProgressively), over the open frames.
    const std::vector<int> open = openFrames(this->Frames.size(), this->Impl->recorded);
    std::vector<double> s;
    std::vector<bool> stored;
    openPath(this->Frames, open, s, stored);
    std::vector<bool> whole = stored;
    KeyMaking keyMaking;
    keyMaking.makeWhole = [&](int i)
    {
      whole[static_cast<std::size_t>(i)] = true;
      const int k = open[static_cast<std::size_t>(i)];
      making.keepWholeWithinBudget({});
      making.whole(k);
      const double rays = this->Impl->wholeRays.at(k);
      if (afterEach)
        afterEach(k);
      return rays;
    };
    keyMaking.measureShare = [&](int i, int, int)
    {
      std::vector<int> around;
      for (std::size_t w = 0; w < whole.size(); ++w)
        if (whole[w] && static_cast<int>(w) != i)
          around.push_back(open[w]);
      return making.measuredShare(open[static_cast<std::size_t>(i)], around);
    };
    const double pixels = static_cast<double>(this->Width) * this->Height;
    const MoviePlan planned =
      planProgressively(s, stored, pixels, this->Impl->share, keyMaking, movieCostPrior(pixels));
    this->Plan = wholeMoviePlan(planned, open, this->Frames.size(), this->Impl->recorded);
  }
  // Every key traced; those stored are read when a frame needs them, and those made and let go
  // without a store traced again then.
  for (int k : this->plan().keys())
  {
    if (this->Impl->whole.count(k) > 0 || making.storedId(k) || this->Impl->wholeRays.count(k))
      continue;
    making.keepWholeWithinBudget({});
    making.whole(k);
    if (afterEach)
      afterEach(k);
  }
  this->Impl->keysMade = true;
}

void MovieMaker::lookUpStored(int k)
{
  MovieFrame& f = this->Frames[static_cast<std::size_t>(k)];
  if (this->Store && !this->Plan && !f.storedId && !this->Impl->storedIds.count(k))
    f.storedId = this->Store->findFrame(f.identity);
}

double MovieMaker::settingsReach(int k)
{
  // Not the plan: a movie made at another rendering would leave it unused, and planning a
  // movie over stored frames makes the frames the store serves.
  this->lookUpStored(k);
  MovieMaking making{ *this, *this->Impl };
  return psnrOfMse(making.settingsOf(k, false).mse());
}

double MovieMaker::settingsReachAt(int k, const MovieFrame& other, bool bound)
{
  this->lookUpStored(k);
  MovieMaking making{ *this, *this->Impl };
  const SettingsError error = making.settingsAt(k, other);
  return bound ? error.psnr() : psnrOfMse(error.mse());
}

void MovieMaker::deriveWhole(MovieMaker& from, int k)
{
  const std::size_t at = static_cast<std::size_t>(k);
  if (k < 0 || at >= this->Frames.size() || at >= from.Frames.size() || from.Width != this->Width ||
      from.Height != this->Height)
    throw InvalidParameter("frame " + std::to_string(k) + " cannot be derived: the movies differ");
  if (this->Impl->whole.count(k))
    return;
  // Stored before (this movie made again): read when it is needed, as any stored frame.
  if (this->Store)
    if (const std::optional<std::int64_t> id = this->Store->findFrame(this->Frames[at].identity))
    {
      this->Frames[at].storedId = id;
      return;
    }
  MovieMaking source{ from, *from.Impl };
  source.whole(k);
  // Moved, not copied: at 1920×1080 a frame's records take about 550 MB.
  std::vector<RayRecord> records = std::move(from.Impl->whole.at(k));
  from.Impl->whole.erase(k);
  MovieMaking making{ *this, *this->Impl };
  making.derivedWhole(k, std::move(records), from.Frames[at].identity.rendering);
}

void MovieMaker::adoptWhole(MovieMaker& from, int k)
{
  const std::size_t at = static_cast<std::size_t>(k);
  if (k < 0 || at >= this->Frames.size() || at >= from.Frames.size() || from.Width != this->Width ||
      from.Height != this->Height)
    throw InvalidParameter("frame " + std::to_string(k) + " cannot be adopted: the movies differ");
  Internals &a = *from.Impl, &b = *this->Impl;
  MovieMaking making{ from, a };
  making.whole(k); // kept, read or traced, as from would make it
  if (a.madeNow.count(k))
    b.madeNow.insert(k);
  this->Frames[at] = from.Frames[at];
  b.whole[k] = std::move(a.whole.at(k)); // moved: at 1920×1080 about 550 MB
  a.whole.erase(k);
  b.lastUse[k] = ++b.uses;
  const double rays = a.wholeRays.at(k);
  b.wholeRays[k] = rays;
  b.wholeHeldRays[k] = a.wholeHeldRays.at(k);
  if (const auto id = a.storedIds.find(k); id != a.storedIds.end())
    b.storedIds[k] = id->second;
  if (const auto settings = a.settings.find(k); settings != a.settings.end())
    b.settings[k] = settings->second;
  if (const auto fingerprint = a.fingerprints.find(k); fingerprint != a.fingerprints.end())
    b.fingerprints[k] = fingerprint->second;
  if (const auto pictures = a.pictures.find(k); pictures != a.pictures.end())
  {
    b.pictures[k] = pictures->second;
    b.pictureOrder.push_back(k);
  }
  if (b.wholeCounted.insert(k).second)
  {
    this->RaysOfMovie += rays;
    this->RaysOfKeys += rays;
    ++this->WholeCount;
  }
}

std::vector<RayRecord> MovieMaker::frame(int k, MovieFrameReport& report)
{
  std::vector<RayRecord> made;
  const std::vector<RayRecord>& records = this->madeFrame(k, report, made);
  if (&records == &made)
    return made;
  return records;
}

void MovieMaker::useFrame(int k, MovieFrameReport& report,
                          const std::function<void(const std::vector<RayRecord>&)>& use)
{
  std::vector<RayRecord> made;
  use(this->madeFrame(k, report, made));
}

const std::vector<RayRecord>& MovieMaker::madeFrame(int k, MovieFrameReport& report,
                                                    std::vector<RayRecord>& made)
{
  if (k < 0 || k >= static_cast<int>(this->Frames.size()))
    throw InvalidParameter("frame " + std::to_string(k) + " of a movie of " +
                           std::to_string(this->Frames.size()) + " frames");
  this->makeKeys(); // the plan is final once its keys are made
  const MoviePlan& plan = this->plan();
  MovieMaking making{ *this, *this->Impl };
  {
    const auto recorded = this->Impl->recorded.find(k);
    const std::vector<int> around =
      keysAround(recorded != this->Impl->recorded.end() ? recorded->second : plan.keys(), k);
    std::set<int> inUse(around.begin(), around.end());
    inUse.insert(k);
    making.keepWholeWithinBudget(inUse);
  }
  report = MovieFrameReport();
  report.method = plan.frames[static_cast<std::size_t>(k)].method;
  const auto served = report.method == FrameMethod::Interpolated ? this->Impl->served.find(k)
                                                                 : this->Impl->served.end();
  if (served != this->Impl->served.end())
  {
    // Made while planning, between the same keys: nothing traced, its re-traced pixels read.
    std::vector<RayRecord> records = std::move(served->second.first);
    report = served->second.second;
    this->RaysOfMovie += report.raysReused;
    this->Impl->served.erase(served);
    making.recordKeys(k, plan.keys(), false); // made from the store alone, its keys alone
    made = std::move(records);
    return made;
  }
  if (report.method == FrameMethod::Interpolated)
  {
    const auto recorded = this->Impl->recorded.find(k);
    made = making.interpolated(
      k, recorded != this->Impl->recorded.end() ? recorded->second : plan.keys(), report, false);
    return made;
  }
  const std::vector<RayRecord>& records = making.whole(k);
  this->reportWhole(k, report);
  return records;
}

std::size_t MovieMaker::wholeFramesKept() const
{
  return this->Impl->whole.size();
}

void MovieMaker::reportWhole(int k, MovieFrameReport& report) const
{
  const double rays = this->Impl->wholeRays.at(k);
  const auto settings = this->Impl->settings.find(k);
  if (settings != this->Impl->settings.end())
    report.settingsPsnr = report.estimatedPsnr = settings->second.psnr();
  if (this->Frames[static_cast<std::size_t>(k)].storedId && !this->Impl->madeNow.count(k))
    report.raysReused = rays;
  else
  {
    report.raysTraced = rays;
    report.shareRetraced = 1;
    if (report.method == FrameMethod::Reused) // stored by now, but made in this run
      report.method = FrameMethod::Key;
  }
}

std::optional<std::vector<std::string>> MovieMaker::storedPictures(
  int k, const std::vector<std::string>& formats, MovieFrameReport& report)
{
  if (k < 0 || k >= static_cast<int>(this->Frames.size()))
    throw InvalidParameter("frame " + std::to_string(k) + " of a movie of " +
                           std::to_string(this->Frames.size()) + " frames");
  if (formats.empty())
    return std::nullopt;
  const MoviePlan& plan = this->plan(); // the stored and the recorded frames looked up
  const auto early =
    this->Impl->keysMade ? this->Impl->pictures.find(k) : this->Impl->pictures.end();
  if (early != this->Impl->pictures.end() && formats == this->Settings.pictureFormats &&
      plan.frames[static_cast<std::size_t>(k)].method != FrameMethod::Interpolated)
  {
    // Encoded when this movie traced the frame: the report frame() gives, and stored as a frame
    // made now is.
    std::vector<std::string> bytes = std::move(early->second);
    this->Impl->pictures.erase(early);
    report = MovieFrameReport();
    report.method = plan.frames[static_cast<std::size_t>(k)].method;
    this->reportWhole(k, report);
    this->storePictures(k, formats, bytes, report);
    return bytes;
  }
  if (!this->Store)
    return std::nullopt;
  const MovieMaking making{ *this, *this->Impl };
  const std::optional<PictureOrigin> origin = making.pictureOrigin(k);
  if (!origin)
    return std::nullopt;
  std::vector<std::string> bytes;
  FramePicture facts;
  for (const std::string& format : formats)
  {
    std::optional<FramePicture> picture = this->Store->readPicture(*origin, format);
    if (!picture)
      return std::nullopt;
    bytes.push_back(std::move(picture->bytes));
    facts = std::move(*picture);
  }
  report = MovieFrameReport();
  report.raysReused = facts.rays;
  if (origin->wholeFrame)
  {
    report.method = plan.frames[static_cast<std::size_t>(k)].method;
    report.settingsPsnr = report.estimatedPsnr = facts.settingsPsnr;
    if (this->Impl->whole.count(k) == 0 && this->Impl->wholeCounted.insert(k).second)
    {
      this->RaysOfMovie += facts.rays;
      this->RaysOfKeys += facts.rays;
      ++this->WholeCount;
    }
  }
  else
  {
    report.method = FrameMethod::Interpolated;
    report.estimatedPsnr = facts.estimatedPsnr;
    report.settingsPsnr = facts.settingsPsnr;
    report.shareRetraced = facts.shareRetraced;
    this->RaysOfMovie += facts.rays;
  }
  return bytes;
}

void MovieMaker::storePictures(int k, const std::vector<std::string>& formats,
                               const std::vector<std::string>& bytes,
                               const MovieFrameReport& report)
{
  if (formats.size() != bytes.size())
    throw InvalidParameter("pictures: " + std::to_string(formats.size()) + " formats for " +
                           std::to_string(bytes.size()) + " pictures");
  const MovieMaking making{ *this, *this->Impl };
  const std::optional<PictureOrigin> origin = making.pictureOrigin(k);
  if (!origin)
    return;
  FramePicture picture;
  picture.method = static_cast<int>(report.method);
  picture.estimatedPsnr = report.estimatedPsnr;
  picture.settingsPsnr = report.settingsPsnr;
  picture.shareRetraced = std::min(1.0, std::max(0.0, report.shareRetraced));
  const auto held = this->Impl->heldRays.find(k);
  const auto wholeHeld = this->Impl->wholeHeldRays.find(k);
  // The rays its records hold, as a run that reads the frame counts them.
  picture.rays =
    origin->wholeFrame
      ? (wholeHeld != this->Impl->wholeHeldRays.end() ? wholeHeld->second
                                                      : report.raysReused + report.raysTraced)
      : (held != this->Impl->heldRays.end() ? held->second : report.raysReused);
  for (std::size_t f = 0; f < formats.size(); ++f)
  {
    picture.format = formats[f];
    picture.bytes = bytes[f];
    try
    {
      this->Store->storePicture(*origin, picture);
    }
    catch (const StoreError& e)
    {
      // What the picture was made from changed since (another movie recorded the frame between
      // other keys, or a key was deleted): the picture would serve nothing, and the movie stands.
      if (!e.sqlState().empty() || std::string(e.what()).rfind(kPictureRefused, 0) != 0)
        throw;
      return;
    }
  }
}
}
