#include "GeodesicMovie.h"

#include "ErrorEstimate.h"
#include "FrameTracer.h"
#include "GeodesicSceneLoading.h"
#include "LeaveOneOut.h"
#include "PathInterpolation.h"
#include "RayStore.h"
#include "RecordAllocation.h"
#include "RetraceRays.h"
#include "RowBands.h"
#include "SceneFile.h"
#include "SettingsError.h"
#include "vtkGeodesicSource.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <set>
#include <utility>

namespace asrt
{

namespace
{
/// The key of frame k's re-traced subset among those kept in memory: which pixels, and beside
/// which border they were traced.
std::pair<int, std::string> retracedKey(int k, const PixelSubsetId& subset)
{
  return { k, std::to_string(subset.count) + ":" + subset.digest + ":" + subset.border };
}

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
/// completePathFrame's default probe share, the floor of the estimate.
constexpr double kMovieProbeFraction = 0.01;
/// The most bytes of records kept of the frames made from the store alone while planning (a
/// quarter of the memory a read may take, at most 1 GiB): the frames beyond are made again.
double servedBytesKept()
{
  return std::min(double(1 << 30), defaultMemoryLimit() / 4);
}

double raysOf(const std::vector<RayRecord>& records)
{
  double rays = 0;
  for (const RayRecord& r : records)
    rays += r.raysPerPixel;
  return rays;
}

/// A scene text without what a movie's path varies (the hole, the camera, the integrator, the
/// rendering, a subset): two frames whose texts give the same have the same objects and textures.
std::string objectsText(const std::string& sceneText)
{
  nlohmann::json j = nlohmann::json::parse(sceneText);
  for (const char* varied : { "spacetime", "camera", "integrator", "rendering", "subset" })
    j.erase(varied);
  return j.dump();
}

/// What completePathFrame asked of the store alone did not have.
struct NotServed
{
};
}

struct MovieMaker::Internals
{
  std::map<int, std::vector<RayRecord>> whole; ///< whole frames made, in pixel order
  /// When each whole frame kept was last used (a count of uses): the least recent stored ones
  /// leave memory first (MovieMaking::keepWholeWithinBudget).
  std::map<int, std::uint64_t> lastUse;
  std::uint64_t uses = 0;
  /// The rays each whole frame made took: integrated if traced, its records' if read.
  std::map<int, double> wholeRays;
  /// Re-traced pixels kept in memory (MovieSettings::cacheRetraced), by retracedKey.
  std::map<std::pair<int, std::string>, std::vector<RayRecord>> retraced;
  std::optional<SceneDescription> shading; ///< the first frame's scene, textures loaded
  std::string shadingObjects;              ///< its text without what a path varies
  /// Frames the plan made from the store alone between the stored frames, with how: kept when the
  /// plan interpolates them between the same keys, until frame() hands them out (the same records
  /// it would make again).
  std::map<int, std::pair<std::vector<RayRecord>, MovieFrameReport>> served;
  /// The re-trace share estimate: the prior, then what the keys made measured.
  SpacingShareModel share;
  /// Whole frames' own errors against their converged pictures, once measured.
  std::map<int, SettingsError> settings;
  /// The store's id of each whole frame made, read or traced and stored.
  std::map<int, std::int64_t> storedIds;
  /// Interpolated frames the store records as made from keys that are frames of this movie, and
  /// stored: each is made again between exactly those keys, whatever keys the plan has.
  std::map<int, std::vector<int>> recorded;
  bool keysMade = false; ///< makeKeys() done: the plan is final
  /// Whole frames whose rays are counted in the maker's totals (read, traced or served as
  /// pictures): each counted once.
  std::set<int> wholeCounted;
  /// The rays the records of each interpolated frame's re-traced pixels hold, read or traced.
  std::map<int, double> heldRays;
  /// The keys' leave-one-out errors, for the frames between the same keys.
  std::shared_ptr<LeaveOneOutCache> leftOut = std::make_shared<LeaveOneOutCache>();
  /// Each whole frame's matchingFingerprint, once computed: the keys' leave-one-out errors are
  /// looked up by it for every frame between them. A frame's records are the same whenever it is
  /// made or read again.
  std::map<int, std::uint64_t> fingerprints;
  /// The rays each whole frame's records hold (their raysPerPixel), kept or let go.
  std::map<int, double> wholeHeldRays;
  /// Pictures of whole frames traced by this movie, encoded when traced
  /// (MovieSettings::encodePictures), until storedPictures() hands them out.
  std::map<int, std::vector<std::string>> pictures;
  std::deque<int> pictureOrder; ///< the frames of `pictures`, as they were traced
  /// Records of whole frames let go, their memory reused for the next frame traced: fresh memory
  /// costs its first touch (the kernel clears every page), memory used before does not.
  std::vector<RayRecord> spare;
  /// Whole frames made in this run (traced, or anti-aliased again; by this maker, or by the one it
  /// adopted them from, adoptWhole): reported as made, though the store holds them by the time
  /// the plan looks (the rendering's judgement makes the first and last frames before it).
  std::set<int> madeNow;
};

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

namespace
{
/// Stores a frame (whole or a subset). Another writer may have stored it since it was looked up:
/// then its copy stands.
std::int64_t storeFrame(RayStore& store, const MovieSettings& settings,
                        const SceneDescription& identity, const std::vector<RayRecord>& records,
                        double seconds)
{
  std::function<bool()> cancelled = settings.cancelled ? settings.cancelled : [] { return false; };
  try
  {
    return store.writeFrame(identity, settings.label, records,
                            FrameWriteOptions().tracedIn(seconds).cancelledWhen(cancelled));
  }
  catch (const StoreError&)
  {
    if (cancelled())
      throw MovieCancelled();
    const std::optional<std::int64_t> theirs = store.findFrame(identity);
    if (!theirs)
      throw;
    return *theirs;
  }
}

/// How a movie's interpolated frames are made, as recorded with their keys in the store
/// (RayStore::recordInterpolatedFrame): the same keys and recipe make the same frame.
std::string interpolationRecipe(const MovieSettings& settings)
{
  return "asrt movie 1: quality " + formatParameter(settings.quality) + " dB against " +
         (settings.holdToConverged ? "converged" : "traced") + ", probes " +
         formatParameter(kMovieProbeFraction) + ", estimate scaled by its probes' ratio";
}

/// The keys of `keys` (sorted) that interpolating at frame k uses: the two on either side.
std::vector<int> keysAround(const std::vector<int>& keys, int k)
{
  const auto after = std::upper_bound(keys.begin(), keys.end(), k);
  const auto from = after - std::min<std::ptrdiff_t>(2, after - keys.begin());
  const auto to = after + std::min<std::ptrdiff_t>(2, keys.end() - after);
  return std::vector<int>(from, to);
}
}

/// The ways the maker gets records, and the bookkeeping that goes with them.
struct MovieMaking
{
  MovieMaker& maker;
  MovieMaker::Internals& in;

  bool cancelled() const { return maker.Settings.cancelled && maker.Settings.cancelled(); }

  std::function<bool(double)> progress() const
  {
    const MovieSettings& settings = maker.Settings;
    return [&settings](double fraction)
    {
      if (settings.traceProgress)
        settings.traceProgress(fraction);
      return !(settings.cancelled && settings.cancelled());
    };
  }

  /// The frame's scene with its textures: the first frame's objects and textures, read once,
  /// where the frame's text differs from the first's only in what a path varies (the hole, the
  /// camera, the integrator, the rendering); else read from its own text.
  SceneDescription withTextures(const MovieFrame& f) const
  {
    const MovieFrame& first = maker.Frames.front();
    if (!in.shading)
    {
      in.shading =
        loadScene(first.sceneText.c_str(), nullptr, maker.Settings.textureDirectory.c_str());
      in.shadingObjects = objectsText(first.sceneText);
    }
    if (objectsText(f.sceneText) != in.shadingObjects)
      return loadScene(f.sceneText.c_str(), nullptr, maker.Settings.textureDirectory.c_str());
    SceneDescription d = f.identity; // parsed as loadScene parses it, without the images
    d.scene = in.shading->scene;
    return d;
  }

  /// A whole frame's records, in pixel order: kept, read from the store, or traced (and stored).
  const std::vector<RayRecord>& whole(int k)
  {
    in.lastUse[k] = ++in.uses;
    const auto kept = in.whole.find(k);
    if (kept != in.whole.end())
      return kept->second;
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    std::vector<RayRecord> records;
    double rays = 0, held = 0; // rays integrated; rays the records hold (raysOf)
    // Stored before, or traced and stored by this movie and since let go (keepWholeWithinBudget).
    const std::optional<std::int64_t> id = this->storedId(k);
    if (id && maker.Store)
    {
      records = maker.Store->readFrame(*id);
      std::sort(records.begin(), records.end(),
                [](const RayRecord& a, const RayRecord& b)
                { return a.j != b.j ? a.j < b.j : a.i < b.i; });
      if (records.size() != static_cast<std::size_t>(maker.Width) * maker.Height)
        throw StoreError("stored frame " + std::to_string(*id) + " has " +
                         std::to_string(records.size()) + " rays, the movie's frames " +
                         std::to_string(maker.Width * maker.Height) + " pixels");
      rays = held = raysOf(records);
      in.storedIds[k] = *id;
    }
    else
    {
      const FrameTracer tracer(this->withTextures(f));
      const auto t0 = std::chrono::steady_clock::now();
      // A band at a time into records faulted in at once (allocateRecords): tracing the whole
      // frame together would allocate and clear its records several times over (the adaptive
      // grid's, the anti-aliased ones), and clearing fresh pages was a third of what a traced
      // frame cost beyond tracing it. The records are traceRows' bit for bit (RowBands.h).
      const std::size_t pixels = static_cast<std::size_t>(maker.Width) * maker.Height;
      if (in.spare.size() == pixels)
        records = std::move(in.spare); // every record is written below
      else
        records = allocateRecords(pixels);
      in.spare = std::vector<RayRecord>();
      std::size_t filled = 0;
      traceRowsInBands(
        tracer, 0, maker.Height,
        [&records, &filled](const RayRecord* band, std::size_t count)
        {
          std::copy(band, band + count, records.begin() + static_cast<std::ptrdiff_t>(filled));
          filled += count;
        },
        this->progress());
      if (this->cancelled())
        throw MovieCancelled();
      // The tracer's count: on the adaptive grid the records leave out border rays a block traced
      // for a pixel that the block owning it filled (FrameTracer::raysIntegrated).
      return this->keepMade(k, std::move(records), static_cast<double>(tracer.raysIntegrated()),
                            std::chrono::steady_clock::now() - t0);
    }
    return this->keepWhole(k, std::move(records), rays, held);
  }

  /// Whole frame k made by this movie (traced, or anti-aliased again), `rays` integrated in
  /// `took`: checked, counted, stored with its pictures, and kept.
  const std::vector<RayRecord>& keepMade(int k, std::vector<RayRecord> records, double rays,
                                         std::chrono::steady_clock::duration took)
  {
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    // A frame with too many failed rays is no picture of its scene: neither used nor stored.
    if (maker.Settings.checkTraced)
      maker.Settings.checkTraced(records, k);
    const double held = raysOf(records);
    maker.RaysTraced += rays;
    in.madeNow.insert(k);
    if (maker.Store)
    {
      in.storedIds[k] = storeFrame(*maker.Store, maker.Settings, f.identity, records,
                                   std::chrono::duration<double>(took).count());
      if (maker.Settings.encodePictures && !maker.Settings.pictureFormats.empty())
        this->keepPictures(k, maker.Settings.encodePictures(records));
    }
    return this->keepWhole(k, std::move(records), rays, held);
  }

  /// Whole frame k anti-aliased again from `records`, the same frame traced with the rendering
  /// `fromRendering` (FrameTracer::antialiasAgain): checked, counted, stored and kept as a frame
  /// this movie traced, for the rays of its sampled pixels alone.
  const std::vector<RayRecord>& derivedWhole(int k, std::vector<RayRecord> records,
                                             const AntialiasOptions& fromRendering)
  {
    in.lastUse[k] = ++in.uses;
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    const FrameTracer tracer(this->withTextures(f));
    const auto t0 = std::chrono::steady_clock::now();
    tracer.antialiasAgain(records, fromRendering, this->progress());
    if (this->cancelled())
      throw MovieCancelled();
    return this->keepMade(k, std::move(records), static_cast<double>(tracer.raysIntegrated()),
                          std::chrono::steady_clock::now() - t0);
  }

  /// Keeps whole frame k, counted once among the movie's whole frames.
  const std::vector<RayRecord>& keepWhole(int k, std::vector<RayRecord> records, double rays,
                                          double held)
  {
    if (in.wholeCounted.insert(k).second)
    {
      maker.RaysOfMovie += rays;
      maker.RaysOfKeys += rays;
      ++maker.WholeCount;
    }
    in.wholeRays.emplace(k, rays); // a frame read again keeps the count it was made with
    in.wholeHeldRays[k] = held;
    return in.whole.emplace(k, std::move(records)).first->second;
  }

  /// Keeps frame k's pictures until storedPictures() hands them out, those of the frames traced
  /// earliest let go beyond a quarter of the memory a read may take (their frames are then made
  /// from their records at their turn, read back from the store).
  void keepPictures(int k, std::vector<std::string> bytes)
  {
    double kept = 0;
    for (const std::string& b : bytes)
      kept += static_cast<double>(b.size());
    for (const auto& [frame, pictures] : in.pictures)
      for (const std::string& b : pictures)
        kept += static_cast<double>(b.size());
    while (kept > defaultMemoryLimit() / 4 && !in.pictureOrder.empty())
    {
      const auto oldest = in.pictures.find(in.pictureOrder.front());
      in.pictureOrder.pop_front();
      if (oldest == in.pictures.end())
        continue;
      for (const std::string& b : oldest->second)
        kept -= static_cast<double>(b.size());
      in.pictures.erase(oldest);
    }
    in.pictures[k] = std::move(bytes);
    in.pictureOrder.push_back(k);
  }

  /// Lets go of the least recently used whole frames that are stored, but not of `inUse`, until
  /// those kept fit in MovieSettings::keptFrameBytes (a movie's keys at 1920×1080 would not fit
  /// in memory together). Called where no reference to a kept frame is held.
  void keepWholeWithinBudget(const std::set<int>& inUse)
  {
    double bytes = 0;
    for (const auto& [k, records] : in.whole)
      bytes += static_cast<double>(records.size() * sizeof(RayRecord));
    // By default at most a quarter of the memory a read may take, and at most 4 frames beyond the
    // first GiB: what a frame being made uses (its keys, the frames around a frame measured), with
    // room to spare. More costs memory a frame is not read back for (the pictures of a whole frame
    // are made as it is traced), and fresh memory costs its first touch.
    const double frameBytes =
      static_cast<double>(maker.Width) * maker.Height * static_cast<double>(sizeof(RayRecord));
    const double budget =
      maker.Settings.keptFrameBytes > 0
        ? maker.Settings.keptFrameBytes
        : std::min(defaultMemoryLimit() / 4, std::max(double(1 << 30), 4 * frameBytes));
    while (bytes > budget)
    {
      int oldest = -1;
      for (const auto& [k, records] : in.whole)
        if (!inUse.count(k) && this->storedId(k) &&
            (oldest < 0 || in.lastUse[k] < in.lastUse[oldest]))
          oldest = k;
      if (oldest < 0)
        return;
      bytes -= static_cast<double>(in.whole[oldest].size() * sizeof(RayRecord));
      in.spare = std::move(in.whole[oldest]);
      in.whole.erase(oldest);
    }
  }

  /// Records of a subset that was traced before: in memory, or in the store.
  std::optional<std::vector<RayRecord>> known(int k, const SceneDescription& subset,
                                              const std::vector<std::pair<int, int>>& pixels)
  {
    const auto cached = in.retraced.find(retracedKey(k, subset.subset));
    if (cached != in.retraced.end())
      return cached->second;
    if (!maker.Store)
      return std::nullopt;
    const auto id = maker.Store->findFrame(subset);
    if (!id)
      return std::nullopt;
    // Each pixel's record found through the frame's pixel grid: the subset is a few pixels of
    // it, at most all of them.
    const std::vector<RayRecord> stored = maker.Store->readFrame(*id);
    std::vector<std::int32_t> at(static_cast<std::size_t>(maker.Width) * maker.Height, -1);
    for (std::size_t r = 0; r < stored.size(); ++r)
    {
      const RayRecord& ray = stored[r];
      if (ray.i >= 0 && ray.i < maker.Width && ray.j >= 0 && ray.j < maker.Height)
      {
        std::int32_t& slot = at[static_cast<std::size_t>(ray.j) * maker.Width + ray.i];
        if (slot < 0) // a pixel stored twice: its first record stands
          slot = static_cast<std::int32_t>(r);
      }
    }
    std::vector<RayRecord> records;
    records.reserve(pixels.size());
    for (const auto& ij : pixels)
    {
      const bool inside =
        ij.first >= 0 && ij.first < maker.Width && ij.second >= 0 && ij.second < maker.Height;
      const std::int32_t r =
        inside ? at[static_cast<std::size_t>(ij.second) * maker.Width + ij.first] : -1;
      if (r < 0)
        throw StoreError("stored subset frame " + std::to_string(*id) + " lacks pixel (" +
                         std::to_string(ij.first) + ", " + std::to_string(ij.second) +
                         ") that its digest names");
      records.push_back(stored[static_cast<std::size_t>(r)]);
    }
    return records;
  }

  /// `pixels` traced by `tracer` and stored as `subset` (a subset frame of their frame's scene):
  /// the tracer's count of rays, not the records' (these leave out the edge neighbours it traces
  /// and drops, FrameTracer::raysIntegrated), counted as the movie's.
  TracedPixels tracedSubset(const FrameTracer& tracer,
                            const std::vector<std::pair<int, int>>& pixels,
                            const SceneDescription& subset, CentreRays* kept = nullptr,
                            const std::vector<JacobianSample>& border = {})
  {
    const auto t0 = std::chrono::steady_clock::now();
    const std::int64_t before = tracer.raysIntegrated();
    TracedPixels out;
    out.records = tracer.tracePixelsBeside(pixels, border, kept, this->progress());
    out.rays = static_cast<double>(tracer.raysIntegrated() - before);
    if (this->cancelled())
      throw MovieCancelled();
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    maker.RaysTraced += out.rays;
    maker.RaysOfMovie += out.rays;
    if (maker.Store)
      storeFrame(*maker.Store, maker.Settings, subset, out.records, seconds);
    return out;
  }

  /// The re-traced pixels of interpolated frame k: known ones read, else traced (and stored).
  /// With `storeOnly`, a subset not known is NotServed, and nothing is counted or kept.
  PixelTracer retracedPixels(int k, const std::function<const FrameTracer&()>& tracer,
                             MovieFrameReport& report, bool storeOnly)
  {
    // The frame's lists border each other: their centre rays are traced once (CentreRays).
    auto kept = std::make_shared<CentreRays>();
    return
      [this, k, &tracer, &report, storeOnly, kept](const std::vector<std::pair<int, int>>& pixels,
                                                   const std::vector<JacobianSample>& border)
    {
      TracedPixels out;
      if (pixels.empty())
        return out;
      SceneDescription subset = maker.Frames[static_cast<std::size_t>(k)].identity;
      subset.subset = pixelSubsetId(pixels);
      subset.subset.border = borderDigest(border); // the records' Jacobians and colours read it
      subset.rendering = scatteredPixelRendering(subset.rendering); // as the tracer traces them
      const std::pair<int, std::string> cacheKey = retracedKey(k, subset.subset);
      if (auto found = this->known(k, subset, pixels))
      {
        in.heldRays[k] += raysOf(*found);
        report.raysReused += raysOf(*found);
        if (!storeOnly)
        {
          maker.RaysOfMovie += raysOf(*found);
          if (maker.Settings.cacheRetraced)
            in.retraced.emplace(cacheKey, *found);
        }
        out.records = std::move(*found);
        return out;
      }
      if (storeOnly)
        throw NotServed();
      out = this->tracedSubset(tracer(), pixels, subset, kept.get(), border); // this frame's alone
      in.heldRays[k] += raysOf(out.records);
      report.raysTraced += out.rays;
      if (maker.Settings.cacheRetraced)
        in.retraced.emplace(cacheKey, out.records);
      return out;
    };
  }

  /// The converged records of whole frame k's probes `probes` (settingsProbes of its records):
  /// traced with the converged rendering, or read where they were traced before, and stored as a
  /// subset of the frame's scene at that rendering. With `storeOnly`, probes not known are
  /// NotServed.
  std::vector<RayRecord> convergedProbes(int k, const std::vector<std::int32_t>& probes,
                                         bool storeOnly, int side = kConvergedSide)
  {
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    std::vector<std::pair<int, int>> pixels;
    for (std::int32_t p : probes)
      pixels.emplace_back(p % maker.Width, p / maker.Width);
    SceneDescription subset = f.identity;
    subset.subset = pixelSubsetId(pixels);
    subset.rendering = convergedRendering(side);
    if (auto found = this->known(k, subset, pixels))
      return std::move(*found);
    if (storeOnly)
      throw NotServed();
    SceneDescription d = this->withTextures(f);
    d.rendering = convergedRendering(side);
    return this->tracedSubset(FrameTracer(d), pixels, subset).records;
  }

  /// Whole frame k's own error against its converged picture: its probes (settingsProbes) against
  /// their converged records (convergedProbes). With `storeOnly`, probes not known are NotServed.
  const SettingsError& settingsOf(int k, bool storeOnly)
  {
    const auto kept = in.settings.find(k);
    if (kept != in.settings.end())
      return kept->second;
    const std::vector<RayRecord>& records = this->whole(k);
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    if (!maker.Settings.holdToConverged || isConvergedRendering(f.identity.rendering))
      return in.settings.emplace(k, SettingsError{}).first->second;
    const std::vector<std::int32_t> probes = settingsProbes(records);
    const std::vector<RayRecord> converged =
      this->convergedProbes(k, probes, storeOnly, settingsReferenceSide(f.identity.rendering));
    return in.settings.emplace(k, settingsError(records, probes, converged)).first->second;
  }

  /// Whole frame k's own error against its converged picture at the rendering of `lowered` (the
  /// same frame at another adaptive cap): its probes anti-aliased again from the frame's records
  /// (FrameTracer::antialiasAgain; read where that was done before, else done and stored as a
  /// subset of `lowered`'s scene) against their converged records.
  SettingsError settingsAt(int k, const MovieFrame& lowered)
  {
    const std::vector<RayRecord>& records = this->whole(k);
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    const std::vector<std::int32_t> probes = settingsProbes(records);
    const std::vector<RayRecord> converged =
      this->convergedProbes(k, probes, false, settingsReferenceSide(lowered.identity.rendering));
    std::vector<std::pair<int, int>> pixels;
    for (std::int32_t p : probes)
      pixels.emplace_back(p % maker.Width, p / maker.Width);
    // The probes' records read their edge neighbours' centre rays, the frame's own.
    SceneDescription subset = lowered.identity;
    subset.subset = pixelSubsetId(pixels);
    subset.subset.border =
      borderDigest(edgeNeighbourSamples(records, maker.Width, maker.Height, pixels));
    std::vector<RayRecord> probed;
    if (auto found = this->known(k, subset, pixels))
      probed = std::move(*found);
    else
    {
      const auto t0 = std::chrono::steady_clock::now();
      const FrameTracer tracer(this->withTextures(lowered));
      probed = tracer.antialiasAgain(records, f.identity.rendering, probes);
      const double rays = static_cast<double>(tracer.raysIntegrated());
      maker.RaysTraced += rays;
      maker.RaysOfMovie += rays;
      if (maker.Store)
        storeFrame(*maker.Store, maker.Settings, subset, probed,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return settingsError(records, probes, probed, converged);
  }

  /// Frame k interpolated between `keys` (the nearest of them around it), completed to the target
  /// with the pixels `retrace` gives, held to the converged picture through the inner keys' own
  /// errors (settingsOf, with `storeOnly`).
  PathCompletion interpolatedWith(int k, const std::vector<int>& keys, const PixelTracer& retrace,
                                  std::vector<RayRecord>& records, bool storeOnly,
                                  SettingsError& settings)
  {
    const double direction = maker.Frames.back().s > maker.Frames.front().s ? 1.0 : -1.0;
    // Frame order is the order of direction · s: the keys go in as they are.
    std::vector<PathKey> pathKeys;
    for (int key : keysAround(keys, k))
    {
      const std::vector<RayRecord>& records = this->whole(key);
      auto fingerprint = in.fingerprints.find(key);
      if (fingerprint == in.fingerprints.end())
        fingerprint = in.fingerprints.emplace(key, matchingFingerprint(records)).first;
      pathKeys.push_back({ direction * maker.Frames[static_cast<std::size_t>(key)].s, &records,
                           fingerprint->second });
    }
    if (!in.shading)
      this->withTextures(maker.Frames.front());
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    // Without moved edges: on whole movies (bench/REPORT.md, "Movies") predicting them cost more
    // CPU than the rays they saved (the mass ramp's first run 1.73 of direct with them, 1.05
    // without; the same movie again, nothing traced, 0.77 against 0.08), and its worst frame
    // fell from 33.1 to 29.6 dB against the converged one.
    PathOptions options;
    options.movedEdges = false;
    // The keys' leave-one-out errors rank the edge blends, whose scale then has no floor; each
    // key's are kept for the frames on either side of it, and made without estimates (their
    // colours alone). Paired first runs at 200×200 (bench/movie-paired, bench/REPORT.md): the
    // Kerr orbit 0.67 → 0.45 of direct's CPU, the spin ramp 0.74 → 0.71, the mass ramp and
    // Fig. 1's orbit 3 % more (the plan measures frames between many sets of keys, each set's
    // keys left out made afresh).
    options.leaveOneOutCache = in.leftOut;
    PathFrame frame = interpolateAlongPath(pathKeys, direction * f.s, maker.Width, maker.Height,
                                           *in.shading->scene, options);
    const auto after = std::upper_bound(keys.begin(), keys.end(), k);
    if (after == keys.begin() || after == keys.end())
      throw InvalidParameter("frame " + std::to_string(k) + " lies outside its keys");
    settings =
      pooled(this->settingsOf(*(after - 1), storeOnly), this->settingsOf(*after, storeOnly));
    const PathCompletion done = completePathFrame(frame, retrace, maker.Settings.quality,
                                                  kMovieProbeFraction, settings.mseBound());
    records = std::move(frame.records);
    return done;
  }

  /// Frame k interpolated between `keys` (the nearest of the plan's keys), completed to the target.
  std::vector<RayRecord> interpolated(int k, const std::vector<int>& keys, MovieFrameReport& report,
                                      bool storeOnly)
  {
    const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
    // The tracer (the frame's scene, its textures loaded) only once a pixel must be traced: a
    // frame the store serves whole needs none.
    std::unique_ptr<FrameTracer> made;
    const std::function<const FrameTracer&()> tracer = [this, &made, &f]() -> const FrameTracer&
    {
      if (!made)
      {
        SceneDescription retrace = this->withTextures(f);
        retrace.rendering = scatteredPixelRendering(retrace.rendering);
        made = std::make_unique<FrameTracer>(retrace);
      }
      return *made;
    };
    std::vector<RayRecord> records;
    SettingsError settings;
    in.heldRays[k] = 0;
    const PathCompletion done = this->interpolatedWith(
      k, keys, this->retracedPixels(k, tracer, report, storeOnly), records, storeOnly, settings);
    if (!storeOnly) // made while planning: recorded when frame() hands it out
      this->recordKeys(k, keys);
    report.method = FrameMethod::Interpolated;
    report.estimatedPsnr = done.estimatedPsnr;
    report.settingsPsnr = settings.psnr();
    report.shareRetraced = static_cast<double>(done.retraced) / static_cast<double>(maker.Width) /
                           static_cast<double>(maker.Height);
    return records;
  }

  /// Records in the store that frame k was made between the keys of `keys` around it, unless it
  /// was recorded so before; nothing without a store, or with a key it did not store.
  void recordKeys(int k, const std::vector<int>& keys)
  {
    if (!maker.Store)
      return;
    const std::vector<int> used = keysAround(keys, k);
    const auto before = in.recorded.find(k);
    if (before != in.recorded.end() && before->second == used)
      return;
    std::vector<std::int64_t> ids;
    for (int key : used)
    {
      const auto id = in.storedIds.find(key);
      if (id == in.storedIds.end())
        return;
      ids.push_back(id->second);
    }
    maker.Store->recordInterpolatedFrame(maker.Frames[static_cast<std::size_t>(k)].identity,
                                         interpolationRecipe(maker.Settings), ids);
    in.recorded[k] = used;
  }

  /// The store's id of whole frame k, if it is stored.
  std::optional<std::int64_t> storedId(int k) const
  {
    const auto made = in.storedIds.find(k);
    if (made != in.storedIds.end())
      return made->second;
    return maker.Frames[static_cast<std::size_t>(k)].storedId;
  }

  /// What frame k's pictures are of, where the store holds it: the frame stored whole, or the
  /// frame recorded as interpolated between stored keys by this movie's recipe.
  std::optional<PictureOrigin> pictureOrigin(int k) const
  {
    if (!maker.Store)
      return std::nullopt;
    PictureOrigin origin;
    const auto recorded = in.recorded.find(k);
    if (maker.Frames[static_cast<std::size_t>(k)].storedId || recorded == in.recorded.end())
    {
      origin.wholeFrame = this->storedId(k);
      return origin.wholeFrame ? std::optional<PictureOrigin>(origin) : std::nullopt;
    }
    origin.scene = maker.Frames[static_cast<std::size_t>(k)].identity;
    origin.recipe = interpolationRecipe(maker.Settings);
    for (int key : recorded->second)
    {
      const std::optional<std::int64_t> id = this->storedId(key);
      if (!id)
        return std::nullopt;
      origin.keys.push_back(*id);
    }
    return origin;
  }

  /// Whole frame k interpolated between the whole frames `wholeFrames` around it (k not among
  /// them) and completed to the target from its own records: the share the target needed there,
  /// and the rays re-tracing those pixels would have taken, nothing traced or stored.
  ShareMeasurement measuredShare(int k, const std::vector<int>& wholeFrames)
  {
    const std::vector<RayRecord>& truth = this->whole(k);
    const int width = maker.Width, height = maker.Height;
    RetraceRays rays;
    const PixelTracer fromTruth =
      [&truth, &rays, width, height](const std::vector<std::pair<int, int>>& ij,
                                     const std::vector<JacobianSample>& border)
    {
      TracedPixels out;
      out.records.reserve(ij.size());
      for (const auto& p : ij)
        out.records.push_back(truth[static_cast<std::size_t>(p.second) * width + p.first]);
      // What tracing the list at k would integrate (RetraceRays.h).
      const RetraceRays list = predictRetraceRays(truth, width, height, ij, border);
      rays += list;
      out.rays = list.total();
      return out;
    };
    std::vector<RayRecord> records;
    SettingsError settings;
    const PathCompletion done =
      this->interpolatedWith(k, wholeFrames, fromTruth, records, false, settings);
    ShareMeasurement m;
    m.share = static_cast<double>(done.retraced) / static_cast<double>(maker.Width) /
              static_cast<double>(maker.Height);
    m.raysPerPixel = rays.centres > 0 ? rays.centres / static_cast<double>(done.retraced) : 0.0;
    m.neighbourRays = rays.neighbours;
    m.edgeRays = rays.midpoints + rays.samples;
    return m;
  }
};

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
  const std::string recipe = interpolationRecipe(this->Settings);
  for (std::size_t k = 0; k < this->Frames.size() && this->Store; ++k)
  {
    if (this->Frames[k].storedId)
      continue;
    const auto ids = this->Store->interpolatedFrameKeys(this->Frames[k].identity, recipe);
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
      this->Impl->recorded[static_cast<int>(k)] = keys;
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

void MovieMaker::makeKeys(const std::function<void()>& afterEach)
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
        afterEach();
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
  // Every key traced; those stored are read when a frame needs them.
  for (int k : this->plan().keys())
  {
    if (this->Impl->whole.count(k) > 0 || making.storedId(k))
      continue;
    making.keepWholeWithinBudget({});
    making.whole(k);
    if (afterEach)
      afterEach();
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
    making.recordKeys(k, plan.keys());
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
  if (!this->Store || formats.empty())
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
