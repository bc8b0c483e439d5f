// A movie without a store keeps its whole frames' records within a budget: beyond it, the least
// recently used are let go and traced again where needed. The frames it makes are the same bit
// for bit as those of a movie that keeps them all, and the pictures encoded as each frame is
// traced serve its whole frames without their records.
#include "FiltersTestUtilities.h"

#include "GeodesicMovie.h"
#include "MoviePlan.h"

#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <vector>

using namespace asrt::testing;

namespace
{
constexpr int kSide = 48;

/// Figs. 4-5's scene at 48×48, the mass from 0.65 to 0.8 in `frames` frames, held to the frames
/// traced at their parameters; nothing stored.
asrt::MovieMaker rampMovie(int frames, const asrt::MovieSettings& settings)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  source->SetResolution(kSide, kSide);
  return asrt::MovieMaker(asrt::movieFrames(source, asrt::rampMoviePath("mass", 0.65, 0.8, frames)),
                          "mass", nullptr, settings);
}

asrt::MovieSettings rampSettings()
{
  asrt::MovieSettings settings;
  settings.quality = 35;
  settings.holdToConverged = false;
  settings.textureDirectory = std::string(ASRT_SOURCE_DIR) + "/Data/scenes";
  return settings;
}

/// A frame's colours, as an encoder would read them.
std::string colourBytes(const std::vector<asrt::RayRecord>& records)
{
  std::string bytes;
  for (const asrt::RayRecord& r : records)
    bytes.append(reinterpret_cast<const char*>(&r.color), sizeof r.color);
  return bytes;
}

constexpr double kFrameBytes = double(kSide) * kSide * sizeof(asrt::RayRecord);
}

TEST(MovieMemory, WithoutAStoreWholeFramesStayWithinTheirBudgetAndTheFramesAreTheSame)
{
  constexpr int n = 13;
  // The truth: every whole frame kept (room for all of them).
  asrt::MovieSettings settings = rampSettings();
  settings.unstoredFrameBytes = 100 * kFrameBytes;
  asrt::MovieMaker roomy = rampMovie(n, settings);
  std::size_t roomyMost = 0;
  roomy.makeKeys([&](int) { roomyMost = std::max(roomyMost, roomy.wholeFramesKept()); });
  std::vector<std::string> truth;
  for (int k = 0; k < n; ++k)
  {
    asrt::MovieFrameReport report;
    truth.push_back(colourBytes(roomy.frame(k, report)));
  }
  ASSERT_GE(roomyMost, 4u) << "the plan traces too few frames whole to fill the room";
  ASSERT_LT(roomy.wholeCount(), n) << "the movie interpolates no frame: no key is needed again";

  // Room for two and a half frames: at most two kept and the one being made, whatever the plan.
  settings.unstoredFrameBytes = 2.5 * kFrameBytes;
  std::map<int, int> traced;
  settings.checkTraced = [&traced](const std::vector<asrt::RayRecord>&, int k) { ++traced[k]; };
  asrt::MovieMaker cramped = rampMovie(n, settings);
  std::size_t most = 0;
  cramped.makeKeys([&](int) { most = std::max(most, cramped.wholeFramesKept()); });
  EXPECT_LE(most, 3u);
  for (int k = 0; k < n; ++k)
  {
    asrt::MovieFrameReport report;
    EXPECT_TRUE(colourBytes(cramped.frame(k, report)) == truth[static_cast<std::size_t>(k)])
      << "frame " << k;
    // A frame in the making uses its four keys and itself.
    EXPECT_LE(cramped.wholeFramesKept(), 6u) << "frame " << k;
  }
  // The keys let go were traced again where an interpolated frame needed them.
  int again = 0;
  for (const auto& [k, times] : traced)
    again += times - 1;
  EXPECT_GT(again, 0) << "no frame was let go and needed again: the budget is not exercised";
  EXPECT_GT(cramped.raysTraced(), roomy.raysTraced());
}

TEST(MovieMemory, WithoutAStorePicturesEncodedAsTracedServeTheWholeFramesOnce)
{
  constexpr int n = 9;
  const std::vector<std::string> formats{ "test.1" };
  asrt::MovieSettings settings = rampSettings();
  asrt::MovieMaker truth = rampMovie(n, settings);
  // Room for no frame beyond those in use: a whole frame's records go once its pictures are made.
  settings.unstoredFrameBytes = 1;
  settings.pictureFormats = formats;
  int encodings = 0;
  settings.encodePictures = [&encodings](const std::vector<asrt::RayRecord>& records)
  {
    ++encodings;
    return std::vector<std::string>{ colourBytes(records) };
  };
  asrt::MovieMaker early = rampMovie(n, settings);
  early.makeKeys();
  int whole = 0;
  for (int k = 0; k < n; ++k)
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
    ASSERT_TRUE(served.has_value()) << "whole frame " << k << ": its picture was not made";
    EXPECT_TRUE(served->at(0) == picture) << "frame " << k;
    EXPECT_EQ(report.method, expected.method) << "frame " << k;
    EXPECT_EQ(report.shareRetraced, 1.0) << "frame " << k;
    // Handed out once: asked again, the frame is made from its records.
    EXPECT_FALSE(early.storedPictures(k, formats, report).has_value()) << "frame " << k;
  }
  ASSERT_GT(whole, 1);
  ASSERT_LT(whole, n) << "the movie interpolates no frame: the mixture is not checked";
  // Each whole frame encoded once, though the keys were let go and traced again.
  EXPECT_EQ(encodings, whole);
}
