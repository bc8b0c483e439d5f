// The movie's makers against a real throwaway server: an interpolated frame made again between
// its own keys, pictures stored with the frames and served from them, keys read back when memory
// lets them go, and the pictures encoded as whole frames are traced.
#include "FrameTracer.h"
#include "GeodesicMovie.h"
#include "GeodesicSceneLoading.h"
#include "MoviePlan.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "SharedServer.h"
#include "vtkGeodesicSource.h"

#include "vtkSmartPointer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

// A movie's interpolated frame is made again between the keys it was made between, whatever
// frames are stored since: another user storing a frame beside it whole (a key for free to any
// later plan) changes neither its records nor its cost, nothing is traced for it.
namespace
{
/// The settings of the small ramps below: 35 dB against the frames traced at their parameters.
/// The mass ramp's scene (Figs. 4-5) at 48x48: the small movies' source.
vtkSmartPointer<vtkGeodesicSource> smallRampSource()
{
  auto source = vtkSmartPointer<vtkGeodesicSource>::New();
  source->SetSceneFileName(
    (std::string(ASRT_SOURCE_DIR) + "/Data/scenes/fig4-mass-start.json").c_str());
  source->SetResolution(48, 48);
  return source;
}

/// The small ramp's movie of `frames` frames, M = 0.65 to 0.8 (smallRampSource), and a migrated
/// store on the shared server to accumulate it in.
struct RampMovies
{
  explicit RampMovies(int frames)
    : path(asrt::rampMoviePath("mass", 0.65, 0.8, frames))
  {
    this->store.migrate();
  }
  /// A maker of the movie with `settings`, accumulating in the store unless `stored` is false.
  asrt::MovieMaker movie(const asrt::MovieSettings& settings, bool stored = true)
  {
    return asrt::MovieMaker(asrt::movieFrames(this->source, this->path), "mass",
                            stored ? &this->store : nullptr, settings);
  }
  asrt::RayStore store{ asrt::testing::sharedServer().conninfo() };
  vtkSmartPointer<vtkGeodesicSource> source = smallRampSource();
  asrt::MoviePath path;
};

asrt::MovieSettings rampSettings()
{
  asrt::MovieSettings settings;
  settings.quality = 35;
  settings.holdToConverged = false;
  settings.textureDirectory = std::string(ASRT_SOURCE_DIR) + "/Data/scenes";
  return settings;
}
}

TEST(StorePipeline, ARecordedMovieFrameIsMadeAgainBetweenItsOwnKeys)
{
  RampMovies ramp(13);
  asrt::RayStore& store = ramp.store;
  asrt::MovieSettings settings = rampSettings();
  settings.label = "first";
  asrt::MovieMaker first = ramp.movie(settings);
  std::vector<std::vector<asrt::RayRecord>> made;
  for (int k = 0; k < 13; ++k)
  {
    asrt::MovieFrameReport report;
    made.push_back(first.frame(k, report));
  }
  // Two interpolated frames side by side: the second user stores the first of them whole.
  const asrt::MoviePlan& plan = first.plan();
  int other = -1;
  for (int k = 1; k + 1 < 13 && other < 0; ++k)
    if (plan.frames[k].method == asrt::FrameMethod::Interpolated &&
        plan.frames[k + 1].method == asrt::FrameMethod::Interpolated)
      other = k;
  ASSERT_GE(other, 0) << "the movie interpolates no two frames side by side: nothing to check";
  const asrt::MovieFrame& f = first.frames()[static_cast<std::size_t>(other)];
  const asrt::SceneDescription whole =
    asrt::loadScene(f.sceneText.c_str(), nullptr, settings.textureDirectory.c_str());
  store.writeFrame(f.identity, "another user",
                   asrt::FrameTracer(whole).traceRows(0, whole.camera.height));

  settings.label = "again";
  asrt::MovieMaker again = ramp.movie(settings);
  EXPECT_EQ(again.plan().frames[other].method, asrt::FrameMethod::Reused);
  for (int k = 0; k < 13; ++k)
  {
    if (k == other || plan.frames[k].method != asrt::FrameMethod::Interpolated)
      continue;
    EXPECT_EQ(again.plan().frames[k].method, asrt::FrameMethod::Interpolated) << "frame " << k;
    EXPECT_EQ(again.plan().frames[k].keyBefore, plan.frames[k].keyBefore) << "frame " << k;
    EXPECT_EQ(again.plan().frames[k].keyAfter, plan.frames[k].keyAfter) << "frame " << k;
    asrt::MovieFrameReport report;
    const std::vector<asrt::RayRecord> records = again.frame(k, report);
    EXPECT_EQ(report.raysTraced, 0) << "frame " << k;
    ASSERT_EQ(records.size(), made[k].size());
    for (std::size_t p = 0; p < records.size(); ++p)
      ASSERT_TRUE(records[p].color == made[k][p].color) << "frame " << k << ", pixel " << p;
  }
  EXPECT_EQ(again.raysTraced(), 0);
}

namespace
{
/// Stand-in bytes of a frame's picture: its colours, as an encoder would read them.
std::string colourBytes(const std::vector<asrt::RayRecord>& records)
{
  std::string bytes;
  for (const asrt::RayRecord& r : records)
    bytes.append(reinterpret_cast<const char*>(&r.color), sizeof r.color);
  return bytes;
}

/// An encoder of one picture, a frame's colourBytes, that counts the frames it encodes.
auto countedColourBytes(int& encoded)
{
  return [&encoded](const std::vector<asrt::RayRecord>& records)
  {
    ++encoded;
    return std::vector<std::string>{ colourBytes(records) };
  };
}
}

TEST(StorePipeline, AMoviesStoredPicturesServeTheNextMakerAndAStalePictureIsLeftOut)
{
  RampMovies ramp(7);
  asrt::RayStore& store = ramp.store;
  asrt::MovieSettings settings = rampSettings();
  const std::vector<std::string> formats{ "test.1" };
  asrt::MovieMaker first = ramp.movie(settings);
  std::vector<std::string> pictures;
  std::vector<asrt::MovieFrameReport> reports(7);
  int interpolated = 0;
  for (int k = 0; k < 7; ++k)
  {
    // Nothing stored yet: the frame must be made.
    EXPECT_EQ(first.storedPictures(k, formats, reports[k]), std::nullopt) << "frame " << k;
    pictures.push_back(colourBytes(first.frame(k, reports[k])));
    first.storePictures(k, formats, { pictures.back() }, reports[k]);
    interpolated += reports[k].method == asrt::FrameMethod::Interpolated;
  }
  ASSERT_GT(interpolated, 0) << "the movie interpolates no frame: nothing to check";

  // The next maker of the movie is served every frame's picture, with what the first reported,
  // and reads no key: it traces nothing and counts the rays the frames' records hold.
  asrt::MovieMaker again = ramp.movie(settings);
  for (int k = 0; k < 7; ++k)
  {
    asrt::MovieFrameReport report;
    const auto served = again.storedPictures(k, formats, report);
    ASSERT_TRUE(served.has_value()) << "frame " << k;
    EXPECT_TRUE(served->at(0) == pictures[k]) << "frame " << k;
    EXPECT_EQ(report.raysTraced, 0) << "frame " << k;
    if (reports[k].method == asrt::FrameMethod::Interpolated)
    {
      EXPECT_EQ(report.method, asrt::FrameMethod::Interpolated) << "frame " << k;
      EXPECT_EQ(report.estimatedPsnr, reports[k].estimatedPsnr) << "frame " << k;
      EXPECT_EQ(report.shareRetraced, reports[k].shareRetraced) << "frame " << k;
      EXPECT_GT(report.raysReused, 0) << "frame " << k;
    }
    else
      EXPECT_EQ(report.method, asrt::FrameMethod::Reused) << "frame " << k;
  }
  EXPECT_EQ(again.raysTraced(), 0);
  EXPECT_EQ(again.wholeCount(), 7 - interpolated);
  // The whole frames' rays as their stored records hold them.
  double held = 0;
  for (int k = 0; k < 7; ++k)
    if (reports[k].method != asrt::FrameMethod::Interpolated)
      for (const asrt::RayRecord& r : store.readFrame(*store.findFrame(again.frames()[k].identity)))
        held += r.raysPerPixel;
  EXPECT_DOUBLE_EQ(again.raysOfKeys(), held);

  // A key deleted after its frame was made and before its picture is stored: the picture would
  // serve nothing and is left out, the movie stands; the frames made from it are made again.
  asrt::MovieMaker third = ramp.movie(settings);
  asrt::MovieFrameReport report;
  const std::vector<asrt::RayRecord> records = third.frame(0, report);
  const auto id = store.findFrame(third.frames()[0].identity);
  ASSERT_TRUE(id.has_value());
  store.deleteFrame(*id);
  EXPECT_NO_THROW(third.storePictures(0, formats, { colourBytes(records) }, report));
  asrt::PictureOrigin origin;
  origin.wholeFrame = *id;
  EXPECT_EQ(store.readPicture(origin, "test.1"), std::nullopt);
  asrt::MovieMaker fourth = ramp.movie(settings);
  for (int k = 0; k < 7; ++k)
  {
    if (reports[k].method == asrt::FrameMethod::Interpolated &&
        first.plan().frames[k].keyBefore == 0)
    {
      EXPECT_EQ(fourth.storedPictures(k, formats, report), std::nullopt) << "frame " << k;
    }
  }
}

TEST(StorePipeline, AMovieKeepingNoSpareFrameInMemoryReadsItsKeysAgainAndMakesTheSameFrames)
{
  RampMovies ramp(9);
  asrt::MovieSettings settings = rampSettings();
  // Without a store every frame stays; with one and a budget of a byte, only the frames in use.
  asrt::MovieMaker kept = ramp.movie(settings, false);
  settings.keptFrameBytes = 1;
  asrt::MovieMaker tight = ramp.movie(settings);
  int interpolated = 0;
  for (int k = 0; k < 9; ++k)
  {
    asrt::MovieFrameReport a, b;
    const std::vector<asrt::RayRecord> x = kept.frame(k, a), y = tight.frame(k, b);
    EXPECT_EQ(a.method, b.method) << "frame " << k;
    interpolated += a.method == asrt::FrameMethod::Interpolated;
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t p = 0; p < x.size(); ++p)
      ASSERT_TRUE(x[p].color == y[p].color && x[p].objectId == y[p].objectId)
        << "frame " << k << ", pixel " << p;
  }
  ASSERT_GT(interpolated, 0) << "the movie interpolates no frame: nothing to check";
  // Read again, never traced again.
  EXPECT_EQ(tight.raysTraced(), kept.raysTraced());
  settings.keptFrameBytes = -1;
  EXPECT_THROW(ramp.movie(settings), asrt::InvalidParameter);
}

TEST(StorePipeline, MakingTheKeysAnnouncesEachFrameItTracesOnce)
{
  // What a progress bar counts: the frames the plan traces whole while it makes its keys.
  RampMovies ramp(9);
  const asrt::MovieSettings settings = rampSettings();
  asrt::MovieMaker movie = ramp.movie(settings);
  std::vector<int> announced;
  movie.makeKeys([&announced](int k) { announced.push_back(k); });
  // The truth: the frames each report says were traced whole.
  std::vector<int> whole;
  for (int k = 0; k < 9; ++k)
  {
    asrt::MovieFrameReport report;
    movie.frame(k, report);
    if (report.method == asrt::FrameMethod::Key || report.method == asrt::FrameMethod::Traced)
      whole.push_back(k);
  }
  ASSERT_GT(whole.size(), 1u);
  ASSERT_LT(whole.size(), 9u) << "the movie interpolates no frame: nothing tells them apart";
  std::vector<int> sorted = announced;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end())
    << "a frame announced twice";
  EXPECT_EQ(sorted, whole);
  // The same movie over the store: its keys are read, none traced, none announced.
  asrt::MovieMaker again = ramp.movie(settings);
  int announcedAgain = 0;
  again.makeKeys([&announcedAgain](int) { ++announcedAgain; });
  EXPECT_EQ(announcedAgain, 0);
  EXPECT_EQ(again.raysTraced(), 0.0);
}

namespace
{
/// Hands out every frame of `early` (encoding whole frames as traced, into `encoded`) against
/// `truth`'s, made from its records: a whole frame's picture once, then again from the store
/// (`stored`) or not at all; an interpolated frame's none. Returns the whole frames.
int expectPicturesAsTraced(asrt::MovieMaker& truth, asrt::MovieMaker& early, int frames,
                           const std::vector<std::string>& formats, bool stored)
{
  early.makeKeys();
  int whole = 0;
  for (int k = 0; k < frames; ++k)
  {
    asrt::MovieFrameReport expected, report;
    const std::string picture = colourBytes(truth.frame(k, expected));
    std::optional<std::vector<std::string>> served = early.storedPictures(k, formats, report);
    if (expected.method == asrt::FrameMethod::Interpolated)
    {
      EXPECT_FALSE(served.has_value()) << "frame " << k << " is interpolated, not traced whole";
      EXPECT_TRUE(colourBytes(early.frame(k, report)) == picture) << "frame " << k;
      continue;
    }
    ++whole;
    EXPECT_TRUE(served.has_value() && served->at(0) == picture)
      << "whole frame " << k << ": its picture was not made, or not its own";
    EXPECT_EQ(report.method, expected.method) << "frame " << k;
    EXPECT_EQ(report.shareRetraced, 1.0) << "frame " << k;
    // Stored as they were handed out: served again, from the store. Without one, handed out
    // once: asked again, the frame is made from its records.
    served = early.storedPictures(k, formats, report);
    if (stored)
      EXPECT_TRUE(served.has_value() && served->at(0) == picture) << "frame " << k;
    else
      EXPECT_FALSE(served.has_value()) << "frame " << k;
  }
  EXPECT_GT(whole, 1);
  EXPECT_LT(whole, frames) << "the movie interpolates no frame: the mixture is not checked";
  return whole;
}
}

TEST(StorePipeline, AMovieEncodingWholeFramesWhenTracedHandsOutTheSamePicturesAndStoresThem)
{
  RampMovies ramp(7);
  asrt::MovieSettings settings = rampSettings();
  const std::vector<std::string> formats{ "test.1" };
  // The truth: every frame made from its records, nothing stored, nothing encoded early.
  asrt::MovieMaker truth = ramp.movie(settings, false);
  // Encoding each whole frame as it is traced, and keeping no frame it need not (a budget of a
  // byte): the records of a whole frame are let go once its pictures are made.
  settings.label = "early";
  settings.keptFrameBytes = 1;
  settings.pictureFormats = formats;
  int encoded = 0;
  settings.encodePictures = countedColourBytes(encoded);
  asrt::MovieMaker early = ramp.movie(settings);
  EXPECT_EQ(expectPicturesAsTraced(truth, early, 7, formats, true), encoded);
  EXPECT_EQ(early.raysTraced(), truth.raysTraced());

  // Stored with the frames: the next maker is served them from the store, tracing nothing.
  asrt::MovieMaker again = ramp.movie(settings);
  for (int k = 0; k < 7; ++k)
  {
    asrt::MovieFrameReport expected, report;
    const std::string picture = colourBytes(truth.frame(k, expected));
    if (expected.method == asrt::FrameMethod::Interpolated)
      continue;
    const auto served = again.storedPictures(k, formats, report);
    ASSERT_TRUE(served.has_value()) << "frame " << k;
    EXPECT_TRUE(served->at(0) == picture) << "frame " << k;
  }
  EXPECT_EQ(again.raysTraced(), 0);
}

TEST(StorePipeline, AMovieWithoutAStoreHandsOutThePicturesEncodedAsTracedOnce)
{
  RampMovies ramp(9);
  asrt::MovieSettings settings = rampSettings();
  const std::vector<std::string> formats{ "test.1" };
  asrt::MovieMaker truth = ramp.movie(settings, false);
  // Room for no frame beyond those in use: a whole frame's records go once its pictures are
  // made, and the keys are traced again where interpolated frames need them.
  settings.unstoredFrameBytes = 1;
  settings.pictureFormats = formats;
  int encoded = 0;
  settings.encodePictures = countedColourBytes(encoded);
  asrt::MovieMaker early = ramp.movie(settings, false);
  // Each whole frame encoded once, though its records were let go and traced again.
  EXPECT_EQ(expectPicturesAsTraced(truth, early, 9, formats, false), encoded);
  EXPECT_GT(early.raysTraced(), truth.raysTraced()) << "no key was let go and traced again";
}
