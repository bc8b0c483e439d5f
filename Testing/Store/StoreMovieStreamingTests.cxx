// A movie with a store streams each frame it traces whole into the store as its rows are traced:
// what is stored is the frame FrameTracer traces, bit for bit, over one connection or several;
// a frame the movie's check refuses, or a movie stopped mid-frame, leaves nothing stored.
#include "FrameTracer.h"
#include "GeodesicMovie.h"
#include "GeodesicSceneLoading.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "SharedServer.h"
#include "vtkGeodesicSource.h"

#include "vtkNew.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace
{
const std::string kScenes = std::string(ASRT_SOURCE_DIR) + "/Data/scenes";

/// Figs. 4-5's mass ramp, M = 0.65 to 0.8 in 2 frames (both traced whole) at width × height,
/// held to the frames traced at their parameters.
asrt::MovieMaker twoFrames(int width, int height, asrt::RayStore& store,
                           const asrt::MovieSettings& settings)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName((kScenes + "/fig4-mass-start.json").c_str());
  source->SetResolution(width, height);
  return asrt::MovieMaker(asrt::movieFrames(source, asrt::rampMoviePath("mass", 0.65, 0.8, 2)),
                          "mass", &store, settings);
}

asrt::MovieSettings rampSettings()
{
  asrt::MovieSettings settings;
  settings.quality = 35;
  settings.holdToConverged = false;
  settings.textureDirectory = kScenes;
  return settings;
}

/// A record's fields as bit patterns (a RayRecord may hold padding).
std::vector<std::uint64_t> bits(const asrt::RayRecord& r)
{
  std::vector<std::uint64_t> out;
  auto add = [&out](double d)
  {
    std::uint64_t w;
    std::memcpy(&w, &d, 8);
    out.push_back(w);
  };
  for (int c = 0; c < 3; ++c)
    for (double d : { r.origin[c], r.direction[c], r.hitPoint[c], r.hitNormal[c], r.color[c] })
      add(d);
  for (int c = 0; c < 4; ++c)
    add(r.momentum[c]);
  for (double d : { r.u, r.v, r.chordError, r.affineLength, r.winding, r.maxAbsH, r.dudi, r.dudj,
                    r.dvdi, r.dvdj })
    add(d);
  for (std::int64_t v : { std::int64_t(r.i), std::int64_t(r.j), std::int64_t(r.termination),
                          std::int64_t(r.objectId), std::int64_t(r.imageOrder), r.steps,
                          std::int64_t(r.raysPerPixel), std::int64_t(r.traced) })
    out.push_back(static_cast<std::uint64_t>(v));
  return out;
}

void expectStoredAsTraced(int width, int height, int tiles)
{
  asrt::RayStore store(asrt::testing::databaseNamed("stored_" + std::to_string(width)));
  store.migrate();
  asrt::MovieMaker movie = twoFrames(width, height, store, rampSettings());
  movie.makeKeys();
  for (int k = 0; k < 2; ++k)
  {
    const asrt::MovieFrame& f = movie.frames()[static_cast<std::size_t>(k)];
    const std::optional<std::int64_t> id = store.findFrame(f.identity);
    ASSERT_TRUE(id.has_value()) << "frame " << k << " was not stored";
    const asrt::FrameInfo info = store.frameInfo(*id);
    EXPECT_EQ(info.tileCount, tiles) << "frame " << k;
    EXPECT_TRUE(std::isfinite(info.traceSeconds) && info.traceSeconds > 0) << "frame " << k;
    std::vector<asrt::RayRecord> stored = store.readFrame(*id);
    const asrt::SceneDescription d = asrt::loadScene(f.sceneText.c_str(), nullptr, kScenes.c_str());
    const std::vector<asrt::RayRecord> traced = asrt::FrameTracer(d).traceRows(0, height);
    ASSERT_EQ(stored.size(), traced.size()) << "frame " << k;
    for (std::size_t p = 0; p < traced.size(); ++p)
      ASSERT_EQ(bits(stored[p]), bits(traced[p])) << "frame " << k << ", record " << p;
  }
}

/// Stops the movie with `settings` once its first frame is half traced, or refuses that frame
/// in the check, and expects nothing stored.
void expectNothingStored(int width, int height, bool refuse)
{
  // A database of its own: no frame of another test's in it.
  asrt::RayStore store(
    asrt::testing::databaseNamed((refuse ? "refused_" : "stopped_") + std::to_string(width)));
  store.migrate();
  asrt::MovieSettings settings = rampSettings();
  std::atomic<bool> stop{ false }; // read by the write's cancellation thread too
  if (refuse)
    settings.checkTraced = [](const std::vector<asrt::RayRecord>&, int k)
    {
      // Time for a write that did not wait for the check to commit: this one must not.
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      throw std::runtime_error("refused frame " + std::to_string(k));
    };
  else
  {
    settings.traceProgress = [&stop](double fraction)
    {
      if (fraction > 0.5)
        stop = true;
    };
    settings.cancelled = [&stop] { return stop.load(); };
  }
  asrt::MovieMaker movie = twoFrames(width, height, store, settings);
  if (refuse)
    EXPECT_THROW(movie.makeKeys(), std::runtime_error);
  else
    EXPECT_THROW(movie.makeKeys(), asrt::MovieCancelled);
  EXPECT_TRUE(store.listFrames().empty()) << store.listFrames().size() << " frames stored";
}
}

TEST(StoreMovieStreaming, AWholeFrameStoredAsItIsTracedIsTheTracedFrame)
{
  expectStoredAsTraced(48, 40, 1);
}

TEST(StoreMovieStreaming, AWholeFrameStreamedOverTwoConnectionsIsTheTracedFrame)
{
  // At least 2 × RayStore::kParallelMinRays rays: two tiles, each connection waiting for its rows.
  expectStoredAsTraced(384, 352, 2);
}

TEST(StoreMovieStreaming, AFrameTheCheckRefusesIsNotStored)
{
  expectNothingStored(48, 40, true);
  expectNothingStored(384, 352, true);
}

TEST(StoreMovieStreaming, AMovieStoppedMidFrameStoresNothing)
{
  expectNothingStored(48, 40, false);
  expectNothingStored(384, 352, false);
}
