// A movie without a store keeps its whole frames' records within a budget: beyond it, the least
// recently used are let go and traced again where needed. The frames it makes are the same bit
// for bit as those of a movie that keeps them all.
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
