#include "GeodesicMovieMaking.h"

#include "ErrorEstimate.h"
#include "GeodesicSceneLoading.h"
#include "RecordAllocation.h"
#include "RetraceRays.h"
#include "RowBands.h"
#include "SceneFile.h"
#include "vtkGeodesicSource.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

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

/// Stores a frame (whole or a subset) by `write`, given the options that cancel it with the movie.
/// Another writer may have stored it since it was looked up: then its copy stands.
std::int64_t storeOrFind(RayStore& store, const MovieSettings& settings,
                         const SceneDescription& identity,
                         const std::function<std::int64_t(FrameWriteOptions)>& write)
{
  std::function<bool()> cancelled = settings.cancelled ? settings.cancelled : [] { return false; };
  try
  {
    return write(FrameWriteOptions().cancelledWhen(cancelled));
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

/// Stores a frame's records, traced in `seconds` (storeOrFind).
std::int64_t storeFrame(RayStore& store, const MovieSettings& settings,
                        const SceneDescription& identity, const std::vector<RayRecord>& records,
                        double seconds)
{
  return storeOrFind(
    store, settings, identity,
    [&](FrameWriteOptions options)
    { return store.writeFrame(identity, settings.label, records, options.tracedIn(seconds)); });
}
}

std::string interpolationRecipe(const MovieSettings& settings, bool chained)
{
  return "asrt movie 1: quality " + formatParameter(settings.quality) + " dB against " +
         (settings.holdToConverged ? "converged" : "traced") + ", probes " +
         formatParameter(kMovieProbeFraction) + ", estimate scaled by its probes' ratio" +
         (chained ? ", chained through the pixels the frames between its keys re-traced" : "");
}

bool MovieMaking::cancelled() const
{
  return maker.Settings.cancelled && maker.Settings.cancelled();
}

std::function<bool(double)> MovieMaking::progress() const
{
  const MovieSettings& settings = maker.Settings;
  return [&settings](double fraction)
  {
    if (settings.traceProgress)
      settings.traceProgress(fraction);
    return !(settings.cancelled && settings.cancelled());
  };
}

SceneDescription MovieMaking::withTextures(const MovieFrame& f) const
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

const std::vector<RayRecord>& MovieMaking::whole(int k)
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
    if (maker.Store)
    {
      const std::int64_t stored = this->traceStreamed(k, tracer, records);
      return this->keepMade(k, std::move(records), static_cast<double>(tracer.raysIntegrated()),
                            std::chrono::steady_clock::now() - t0, stored);
    }
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

std::int64_t MovieMaking::traceStreamed(int k, const FrameTracer& tracer,
                                        std::vector<RayRecord>& records)
{
  const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
  const std::size_t total = records.size();
  const std::size_t lastRow = total - static_cast<std::size_t>(maker.Width);
  const auto t0 = std::chrono::steady_clock::now();
  // The write runs on a thread of its own and takes the rows as they are finished: the store's
  // work and the server's overlap the tracing of the rows after them. The tracing stays on this
  // thread, with its progress (a filter's progress events) and its OpenMP threads. The last row
  // waits for the frame's check, so that the write cannot commit a frame the check refuses.
  std::mutex mutex;
  std::condition_variable ready;
  std::size_t visible = 0;
  bool done = false;
  const auto next = [&](std::size_t index, RayRecord& out)
  {
    std::unique_lock<std::mutex> lock(mutex);
    ready.wait(lock, [&] { return visible > index || done; });
    if (visible <= index)
      throw std::runtime_error("the frame's tracing stopped before its rays were stored");
    lock.unlock();
    out = records[index];
  };
  double seconds = 0; // the tracing's, stored with the frame once it is known
  std::optional<std::int64_t> id;
  std::exception_ptr storeFailure;
  std::thread writing(
    [&]
    {
      try
      {
        id = storeOrFind(*maker.Store, maker.Settings, f.identity,
                         [&](FrameWriteOptions options)
                         {
                           return maker.Store->writeFrame(
                             f.identity, maker.Settings.label, total, next,
                             options.fromConcurrentProducer().tracedSecondsWhenDone(
                               [&seconds] { return seconds; }));
                         });
      }
      catch (...)
      {
        storeFailure = std::current_exception();
      }
    });
  std::size_t filled = 0;
  bool complete = false;
  std::exception_ptr failure;
  try
  {
    complete = traceRowsInBands(
      tracer, 0, maker.Height,
      [&](const RayRecord* band, std::size_t count)
      {
        std::copy(band, band + count, records.begin() + static_cast<std::ptrdiff_t>(filled));
        filled += count;
        const std::lock_guard<std::mutex> lock(mutex);
        visible = std::min(filled, lastRow);
        ready.notify_all();
      },
      this->progress());
    complete = complete && filled == total && !this->cancelled();
    // A frame with too many failed rays is no picture of its scene: neither used nor stored.
    if (complete && maker.Settings.checkTraced)
      maker.Settings.checkTraced(records, k);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  catch (...)
  {
    failure = std::current_exception();
    complete = false;
  }
  {
    const std::lock_guard<std::mutex> lock(mutex);
    done = true;
    if (complete)
      visible = total;
    ready.notify_all();
  }
  writing.join();
  if (failure)
    std::rethrow_exception(failure); // the tracer's, or the check's refusal
  if (!complete || this->cancelled())
    throw MovieCancelled();
  if (storeFailure)
    std::rethrow_exception(storeFailure);
  return *id;
}

const std::vector<RayRecord>& MovieMaking::keepMade(int k, std::vector<RayRecord> records,
                                                    double rays,
                                                    std::chrono::steady_clock::duration took,
                                                    std::optional<std::int64_t> stored)
{
  const MovieFrame& f = maker.Frames[static_cast<std::size_t>(k)];
  // A frame with too many failed rays is no picture of its scene: neither used nor stored (one
  // stored as traced was checked before its last row went).
  if (maker.Settings.checkTraced && !stored)
    maker.Settings.checkTraced(records, k);
  const double held = raysOf(records);
  maker.RaysTraced += rays;
  in.madeNow.insert(k);
  if (stored)
    in.storedIds[k] = *stored;
  else if (maker.Store)
    in.storedIds[k] = storeFrame(*maker.Store, maker.Settings, f.identity, records,
                                 std::chrono::duration<double>(took).count());
  // Made once: a frame traced again after it was let go (no store) has its pictures already.
  if (maker.Settings.encodePictures && !maker.Settings.pictureFormats.empty() &&
      in.encoded.insert(k).second)
    this->keepPictures(k, maker.Settings.encodePictures(records));
  return this->keepWhole(k, std::move(records), rays, held);
}

const std::vector<RayRecord>& MovieMaking::derivedWhole(int k, std::vector<RayRecord> records,
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

const std::vector<RayRecord>& MovieMaking::keepWhole(int k, std::vector<RayRecord> records,
                                                     double rays, double held)
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

void MovieMaking::keepPictures(int k, std::vector<std::string> bytes)
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

double MovieMaking::frameBytes() const
{
  return static_cast<double>(maker.Width) * maker.Height * static_cast<double>(sizeof(RayRecord));
}

double MovieMaking::wholeBytes() const
{
  double bytes = 0;
  for (const auto& kept : in.whole)
    bytes += static_cast<double>(kept.second.size() * sizeof(RayRecord));
  return bytes;
}

std::set<int> MovieMaking::keysOfInterpolated() const
{
  std::set<int> keys;
  if (!in.keysMade)
    return keys;
  const MoviePlan& plan = maker.plan();
  for (std::size_t k = 0; k < plan.frames.size(); ++k)
  {
    if (plan.frames[k].method != FrameMethod::Interpolated)
      continue;
    const auto recorded = in.recorded.find(static_cast<int>(k));
    for (int key : keysAround(recorded != in.recorded.end() ? recorded->second : plan.keys(),
                              static_cast<int>(k)))
      keys.insert(key);
  }
  return keys;
}

void MovieMaking::keepWholeWithinBudget(const std::set<int>& inUse)
{
  double bytes = this->wholeBytes();
  // By default at most a quarter of the memory a read may take, and at most 4 frames beyond the
  // first GiB: what a frame being made uses (its keys, the frames around a frame measured), with
  // room to spare. More costs memory a frame is not read back for (the pictures of a whole frame
  // are made as it is traced), and fresh memory costs its first touch.
  const double budget =
    maker.Settings.keptFrameBytes > 0
      ? maker.Settings.keptFrameBytes
      : std::min(defaultMemoryLimit() / 4, std::max(double(1 << 30), 4 * this->frameBytes()));
  // Frames not stored cannot be read back: one let go is traced again if it is needed again. So
  // they get more room by default: 2 GiB or 8 frames, at most half the memory a read may take.
  const double unstoredBudget =
    maker.Settings.unstoredFrameBytes > 0
      ? maker.Settings.unstoredFrameBytes
      : std::min(defaultMemoryLimit() / 2, std::max(2.0 * (1 << 30), 8 * this->frameBytes()));
  // The least recently used frame that may go: stored ones while above the budget; then, above
  // the unstored budget, those not stored, the frames no interpolated frame needs first.
  std::optional<std::set<int>> keys; // looked up once a frame not stored must go
  const auto leastRecent = [&](bool stored, bool spareKeys)
  {
    if (spareKeys && !keys)
      keys = this->keysOfInterpolated();
    int oldest = -1;
    for (const auto& [k, records] : in.whole)
      if (!inUse.count(k) && this->storedId(k).has_value() == stored &&
          !(spareKeys && keys->count(k)) && (oldest < 0 || in.lastUse[k] < in.lastUse[oldest]))
        oldest = k;
    return oldest;
  };
  while (bytes > std::min(budget, unstoredBudget))
  {
    int oldest = bytes > budget ? leastRecent(true, false) : -1;
    if (oldest < 0 && bytes > unstoredBudget)
      oldest = leastRecent(false, true);
    if (oldest < 0 && bytes > unstoredBudget)
      oldest = leastRecent(false, false);
    if (oldest < 0)
      return;
    bytes -= static_cast<double>(in.whole[oldest].size() * sizeof(RayRecord));
    in.spare = std::move(in.whole[oldest]);
    in.whole.erase(oldest);
  }
}

std::optional<std::vector<RayRecord>> MovieMaking::known(
  int k, const SceneDescription& subset, const std::vector<std::pair<int, int>>& pixels)
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

TracedPixels MovieMaking::tracedSubset(const FrameTracer& tracer,
                                       const std::vector<std::pair<int, int>>& pixels,
                                       const SceneDescription& subset, CentreRays* kept,
                                       const std::vector<JacobianSample>& border)
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

PixelTracer MovieMaking::retracedPixels(int k, const std::function<const FrameTracer&()>& tracer,
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

std::vector<RayRecord> MovieMaking::convergedProbes(int k, const std::vector<std::int32_t>& probes,
                                                    bool storeOnly, int side)
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

const SettingsError& MovieMaking::settingsOf(int k, bool storeOnly)
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

SettingsError MovieMaking::settingsAt(int k, const MovieFrame& lowered)
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

std::vector<std::shared_ptr<const PathSamples>> MovieMaking::samplesFor(
  int k, const std::vector<int>& keys)
{
  std::vector<std::shared_ptr<const PathSamples>> out;
  const auto after = std::upper_bound(keys.begin(), keys.end(), k);
  if (!maker.Store || after == keys.begin() || after == keys.end())
    return out;
  const int lo = *(after - 1), hi = *after;
  for (auto it = in.samples.begin(); it != in.samples.end();)
    it = it->first > lo && it->first < hi ? std::next(it) : in.samples.erase(it);
  const double direction = maker.Frames.back().s > maker.Frames.front().s ? 1.0 : -1.0;
  for (auto j = in.chainSources.upper_bound(lo); j != in.chainSources.end() && *j < hi; ++j)
  {
    if (*j == k)
      continue;
    auto kept = in.samples.find(*j);
    if (kept == in.samples.end())
    {
      // The frame's re-traced lists: its subsets at the rendering it re-traces pixels with.
      const MovieFrame& f = maker.Frames[static_cast<std::size_t>(*j)];
      SceneDescription retraced = f.identity;
      retraced.rendering = scatteredPixelRendering(retraced.rendering);
      auto samples = std::make_shared<PathSamples>();
      samples->s = direction * f.s;
      for (RayRecord& r : maker.Store->readSubsetRecords(retraced))
        if (r.i >= 0 && r.i < maker.Width && r.j >= 0 && r.j < maker.Height)
        {
          samples->pixels.push_back(r.j * maker.Width + r.i);
          samples->records.push_back(std::move(r));
        }
      kept = in.samples.emplace(*j, std::move(samples)).first;
    }
    if (!kept->second->pixels.empty())
      out.push_back(kept->second);
  }
  return out;
}

PathCompletion MovieMaking::interpolatedWith(int k, const std::vector<int>& keys,
                                             const PixelTracer& retrace,
                                             std::vector<RayRecord>& records, bool storeOnly,
                                             SettingsError& settings, bool* chained)
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
    pathKeys.push_back(
      { direction * maker.Frames[static_cast<std::size_t>(key)].s, &records, fingerprint->second });
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
  // The pixels the frames recorded between the inner keys re-traced: nearer t than the keys, they
  // vouch for pixels an edge crossed between the keys (PathInterpolation.h, Chains). On the
  // 200×200 movies of 61 frames, the 60 frames a run of 121 adds re-traced 10.7 % fewer rays
  // with them on the mass ramp, 5.3 % fewer on Fig. 1's orbit.
  if (chained)
  {
    options.samples = this->samplesFor(k, keys);
    *chained = !options.samples.empty();
  }
  PathFrame frame = interpolateAlongPath(pathKeys, direction * f.s, maker.Width, maker.Height,
                                         *in.shading->scene, options);
  const auto after = std::upper_bound(keys.begin(), keys.end(), k);
  if (after == keys.begin() || after == keys.end())
    throw InvalidParameter("frame " + std::to_string(k) + " lies outside its keys");
  settings = pooled(this->settingsOf(*(after - 1), storeOnly), this->settingsOf(*after, storeOnly));
  const PathCompletion done = completePathFrame(frame, retrace, maker.Settings.quality,
                                                kMovieProbeFraction, settings.mseBound());
  records = std::move(frame.records);
  return done;
}

std::vector<RayRecord> MovieMaking::interpolated(int k, const std::vector<int>& keys,
                                                 MovieFrameReport& report, bool storeOnly)
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
  // A frame recorded by the plain recipe is made again as it was made, from its keys alone.
  bool chained = false;
  const bool withSamples = !storeOnly && !in.chainSources.count(k);
  const PathCompletion done =
    this->interpolatedWith(k, keys, this->retracedPixels(k, tracer, report, storeOnly), records,
                           storeOnly, settings, withSamples ? &chained : nullptr);
  if (!storeOnly) // made while planning, from its keys alone: recorded when frame() hands it out
    this->recordKeys(k, keys, chained);
  report.method = FrameMethod::Interpolated;
  report.estimatedPsnr = done.estimatedPsnr;
  report.settingsPsnr = settings.psnr();
  report.shareRetraced = static_cast<double>(done.retraced) / static_cast<double>(maker.Width) /
                         static_cast<double>(maker.Height);
  return records;
}

void MovieMaking::recordKeys(int k, const std::vector<int>& keys, bool chained)
{
  if (!maker.Store)
    return;
  const std::vector<int> used = keysAround(keys, k);
  const auto before = in.recorded.find(k);
  if (before != in.recorded.end() && before->second == used &&
      (in.recordedChained.count(k) > 0) == chained)
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
                                       interpolationRecipe(maker.Settings, chained), ids);
  in.recorded[k] = used;
  if (chained)
    in.recordedChained.insert(k);
  else
    in.recordedChained.erase(k);
}

std::optional<std::int64_t> MovieMaking::storedId(int k) const
{
  const auto made = in.storedIds.find(k);
  if (made != in.storedIds.end())
    return made->second;
  return maker.Frames[static_cast<std::size_t>(k)].storedId;
}

std::optional<PictureOrigin> MovieMaking::pictureOrigin(int k) const
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
  origin.recipe = interpolationRecipe(maker.Settings, in.recordedChained.count(k) > 0);
  for (int key : recorded->second)
  {
    const std::optional<std::int64_t> id = this->storedId(key);
    if (!id)
      return std::nullopt;
    origin.keys.push_back(*id);
  }
  return origin;
}

ShareMeasurement MovieMaking::measuredShare(int k, const std::vector<int>& wholeFrames)
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

}
