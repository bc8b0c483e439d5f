// The record of which stored frames an interpolated frame was made from: written and read back in
// order, replaced for the same frame and recipe, kept apart per recipe and per frame, refused for a
// key that is no complete frame (nothing written), and created by the migration from version 7.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

using asrt::RayRecord;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
std::string freshDatabase()
{
  return databaseNamed("if_" + currentTestName());
}

/// The frame at this mass of one small synthetic scene.
asrt::SceneDescription scene(double mass)
{
  return syntheticScene("interpolated", mass);
}

using Keys = std::optional<std::vector<std::int64_t>>;
}

TEST(InterpolatedFrames, KeysComeBackInOrderPerFrameAndRecipe)
{
  RayStore store(freshDatabase());
  store.migrate();
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const std::int64_t b = store.writeFrame(scene(0.3), "key", syntheticRecords(2));
  const std::int64_t c = store.writeFrame(scene(0.5), "key", syntheticRecords(3));
  const asrt::SceneDescription between = scene(0.2), other = scene(0.4);

  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=35"), std::nullopt);
  store.recordInterpolatedFrame(between, "quality=35", { c, a, b });
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=35"), (Keys{ { c, a, b } }));
  // Another recipe and another frame are other records.
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=40"), std::nullopt);
  EXPECT_EQ(store.interpolatedFrameKeys(other, "quality=35"), std::nullopt);
  store.recordInterpolatedFrame(between, "quality=40", { a, b });
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=40"), (Keys{ { a, b } }));
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=35"), (Keys{ { c, a, b } }));
  // The same frame and recipe again: replaced.
  store.recordInterpolatedFrame(between, "quality=35", { b, c });
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=35"), (Keys{ { b, c } }));
  // A frame stored whole is no interpolated frame: its own record stays empty.
  EXPECT_EQ(store.interpolatedFrameKeys(scene(0.1), "quality=35"), std::nullopt);
}

TEST(InterpolatedFrames, ABadRecordIsRefusedAndNothingIsWritten)
{
  RayStore store(freshDatabase());
  store.migrate();
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const std::int64_t tiled = store.beginTiledFrame(scene(0.3), "being written", 2);
  const asrt::SceneDescription between = scene(0.2);
  const std::string missing = errorOf(
    [&] {
      store.recordInterpolatedFrame(between, "quality=35", { a, a + tiled + 100 });
    });
  EXPECT_NE(missing.find("is no complete stored frame"), std::string::npos) << missing;
  const std::string incomplete = errorOf(
    [&] {
      store.recordInterpolatedFrame(between, "quality=35", { a, tiled });
    });
  EXPECT_NE(incomplete.find("is no complete stored frame"), std::string::npos) << incomplete;
  const std::string noRecipe = errorOf([&] { store.recordInterpolatedFrame(between, "", { a }); });
  EXPECT_NE(noRecipe.find("the recipe is empty"), std::string::npos) << noRecipe;
  const std::string noKeys = errorOf([&] { store.recordInterpolatedFrame(between, "q", {}); });
  EXPECT_NE(noKeys.find("0 keys (1 to 16)"), std::string::npos) << noKeys;
  const std::string tooMany =
    errorOf([&] { store.recordInterpolatedFrame(between, "q", std::vector<std::int64_t>(17, a)); });
  EXPECT_NE(tooMany.find("17 keys (1 to 16)"), std::string::npos) << tooMany;
  EXPECT_EQ(store.interpolatedFrameKeys(between, "quality=35"), std::nullopt);
  EXPECT_EQ(store.interpolatedFrameKeys(between, "q"), std::nullopt);
}

TEST(InterpolatedFrames, AVersionSevenStoreGainsTheTable)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(7);
  EXPECT_EQ(store.schemaVersion(), 7);
  Db db(ci);
  EXPECT_EQ(db.value("SELECT to_regclass('interpolated_frames') IS NULL"), "t");
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(db.value("SELECT to_regclass('interpolated_frames') IS NULL"), "f");
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  store.recordInterpolatedFrame(scene(0.2), "quality=35", { a });
  EXPECT_EQ(store.interpolatedFrameKeys(scene(0.2), "quality=35"), (Keys{ { a } }));
}

TEST(InterpolatedFrames, SubsetFramesAreFoundByTheFramesIdentityAtAnyRendering)
{
  RayStore store(freshDatabase());
  store.migrate();
  auto subsetOf = [](asrt::SceneDescription d)
  {
    d.subset = asrt::pixelSubsetId({ { 1, 2 }, { 3, 4 }, { 5, 0 } });
    return d;
  };
  EXPECT_FALSE(store.hasSubsetFrames(scene(0.2)));
  // A frame stored whole is no subset of itself.
  store.writeFrame(scene(0.2), "whole", syntheticRecords(1));
  EXPECT_FALSE(store.hasSubsetFrames(scene(0.2)));
  // Three pixels of the frame at 0.4, traced with another rendering than the frame's.
  asrt::SceneDescription scattered = subsetOf(scene(0.4));
  scattered.rendering.mode = asrt::AntialiasMode::Filter;
  store.writeFrame(scattered, "subset", syntheticRecords(2, 3));
  EXPECT_TRUE(store.hasSubsetFrames(scene(0.4)));
  EXPECT_TRUE(store.hasSubsetFrames(subsetOf(scene(0.4)))); // its own subset named: the same frame
  EXPECT_TRUE(store.hasSubsetFrames(scattered));
  // Another mass, eye, size or tolerance: another frame.
  EXPECT_FALSE(store.hasSubsetFrames(scene(0.2)));
  EXPECT_FALSE(store.hasSubsetFrames(scene(0.5)));
  asrt::SceneDescription moved = scene(0.4);
  moved.camera.position.x() += 1e-9;
  EXPECT_FALSE(store.hasSubsetFrames(moved));
  EXPECT_FALSE(store.hasSubsetFrames(syntheticScene("interpolated", 0.4, 7, 5)));
  // The name is no part of a frame's identity: findFrame finds the subset under another too.
  asrt::SceneDescription renamed = scattered;
  renamed.name = "another";
  ASSERT_TRUE(store.findFrame(renamed).has_value());
  EXPECT_TRUE(store.hasSubsetFrames(syntheticScene("another", 0.4)));
  asrt::SceneDescription nearer = scene(0.4);
  nearer.tracing.escapeRadius = 500;
  EXPECT_FALSE(store.hasSubsetFrames(nearer));
  // A subset frame still being written is visible to nobody.
  store.beginTiledFrame(subsetOf(scene(0.6)), "being written", 2);
  EXPECT_FALSE(store.hasSubsetFrames(scene(0.6)));
}

TEST(InterpolatedFrames, SubsetRecordsComeBackByPixelTheFirstStoredStanding)
{
  RayStore store(freshDatabase());
  store.migrate();
  // Pixels k of a 6-wide frame: the records of pixels k0 .. k0 + count − 1 of seed `seed`.
  auto pixels = [](std::uint64_t seed, std::size_t k0, std::size_t count)
  {
    std::vector<RayRecord> all = syntheticRecords(seed, k0 + count);
    return std::vector<RayRecord>(all.begin() + static_cast<std::ptrdiff_t>(k0), all.end());
  };
  auto subsetOf = [](asrt::SceneDescription d, const std::vector<RayRecord>& records)
  {
    std::vector<std::pair<int, int>> ij;
    for (const RayRecord& r : records)
      ij.emplace_back(r.i, r.j);
    d.subset = asrt::pixelSubsetId(ij);
    return d;
  };
  EXPECT_TRUE(store.readSubsetRecords(scene(0.4)).empty());
  // Pixels 20–25 stored first, then 8–21 (newer records of 20 and 21), written in reverse order.
  const std::vector<RayRecord> first = pixels(1, 20, 6);
  std::vector<RayRecord> second = pixels(2, 8, 14);
  std::reverse(second.begin(), second.end());
  store.writeFrame(subsetOf(scene(0.4), first), "first", first);
  store.writeFrame(subsetOf(scene(0.4), second), "second", second);
  // Not the frame's: its pixels at another rendering, another frame's, the frame stored whole.
  asrt::SceneDescription other = subsetOf(scene(0.4), pixels(3, 0, 8));
  other.rendering.mode = asrt::AntialiasMode::Filter;
  store.writeFrame(other, "another rendering", pixels(3, 0, 8));
  store.writeFrame(subsetOf(scene(0.5), pixels(4, 0, 8)), "another frame", pixels(4, 0, 8));
  store.writeFrame(scene(0.4), "whole", syntheticRecords(5));

  const std::vector<RayRecord> read = store.readSubsetRecords(scene(0.4));
  ASSERT_EQ(read.size(), 18u); // pixels 8 .. 25
  for (std::size_t k = 0; k < read.size(); ++k)
  {
    const int pixel = static_cast<int>(k) + 8;
    EXPECT_EQ(read[k].i, pixel % 6);
    EXPECT_EQ(read[k].j, pixel / 6);
    // The first stored stands where both hold the pixel.
    const RayRecord& expected = pixel >= 20
                                  ? first[static_cast<std::size_t>(pixel - 20)]
                                  : second[second.size() - 1 - static_cast<std::size_t>(pixel - 8)];
    EXPECT_EQ(recordBits(read[k]), recordBits(expected)) << pixel;
  }
  // The frame's subset named, or none: the same frame. Its pixels at the other rendering alone.
  EXPECT_EQ(store.readSubsetRecords(subsetOf(scene(0.4), first)).size(), 18u);
  EXPECT_EQ(store.readSubsetRecords(other).size(), 8u);
}
