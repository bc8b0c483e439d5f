// Frames' encoded pictures: every byte and fact back as stored (infinite PSNRs, zero bytes); one
// picture per origin and format, replaced; a whole frame's gone with its frame; an interpolated
// frame's served only while its frame is recorded between exactly its keys and each key is
// stored; refusals name the field and write nothing; created by the migration from version 8.
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

using asrt::FramePicture;
using asrt::PictureOrigin;
using asrt::RayStore;
using namespace asrt::testing;

namespace
{
std::string freshDatabase()
{
  return databaseNamed("fp_" + currentTestName());
}

asrt::SceneDescription scene(double mass)
{
  return syntheticScene("pictures", mass);
}

/// Bytes of every value, zeros among them, as an encoder may write.
std::string arbitraryBytes(std::size_t n, unsigned seed)
{
  std::mt19937 random(seed);
  std::string bytes(n, '\0');
  for (char& c : bytes)
    c = static_cast<char>(random() & 0xff);
  bytes[n / 2] = '\0';
  return bytes;
}

FramePicture picture(const std::string& format, unsigned seed)
{
  FramePicture p;
  p.format = format;
  p.bytes = arbitraryBytes(70000 + seed, seed);
  p.method = 3;
  p.estimatedPsnr = 35.25 + seed;
  p.settingsPsnr = std::numeric_limits<double>::infinity();
  p.shareRetraced = 0.125;
  p.rays = 27307.5;
  return p;
}

PictureOrigin whole(std::int64_t id)
{
  PictureOrigin o;
  o.wholeFrame = id;
  return o;
}

PictureOrigin interpolated(double mass, const std::string& recipe,
                           const std::vector<std::int64_t>& keys)
{
  PictureOrigin o;
  o.scene = scene(mass);
  o.recipe = recipe;
  o.keys = keys;
  return o;
}

void expectSame(const std::optional<FramePicture>& got, const FramePicture& want)
{
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->format, want.format);
  EXPECT_TRUE(got->bytes == want.bytes) << "the picture's bytes differ";
  EXPECT_EQ(got->method, want.method);
  EXPECT_EQ(got->estimatedPsnr, want.estimatedPsnr);
  EXPECT_EQ(got->settingsPsnr, want.settingsPsnr);
  EXPECT_EQ(got->shareRetraced, want.shareRetraced);
  EXPECT_EQ(got->rays, want.rays);
}
}

TEST(FramePictures, AWholeFramesPicturesComeBackPerFormatAndGoWithTheFrame)
{
  RayStore store(freshDatabase());
  store.migrate();
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const std::int64_t b = store.writeFrame(scene(0.3), "key", syntheticRecords(2));
  EXPECT_EQ(store.readPicture(whole(a), "png.1"), std::nullopt);
  const FramePicture png = picture("png.1", 1), vti = picture("vti.1", 2);
  store.storePicture(whole(a), png);
  store.storePicture(whole(a), vti);
  expectSame(store.readPicture(whole(a), "png.1"), png);
  expectSame(store.readPicture(whole(a), "vti.1"), vti);
  EXPECT_EQ(store.readPicture(whole(b), "png.1"), std::nullopt);
  // The same origin and format again: replaced.
  const FramePicture again = picture("png.1", 3);
  store.storePicture(whole(a), again);
  expectSame(store.readPicture(whole(a), "png.1"), again);
  // Deleted with its frame; the same scene stored again is another frame, with no picture.
  store.deleteFrame(a);
  EXPECT_EQ(store.readPicture(whole(a), "png.1"), std::nullopt);
  const std::int64_t a2 = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  EXPECT_EQ(store.readPicture(whole(a2), "png.1"), std::nullopt);
  const std::string gone = errorOf([&] { store.storePicture(whole(a), png); });
  EXPECT_NE(gone.find("frame " + std::to_string(a) + " is no complete stored frame"),
            std::string::npos)
    << gone;
}

TEST(FramePictures, AnInterpolatedFramesPictureServesOnlyBetweenItsRecordedKeys)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const std::int64_t b = store.writeFrame(scene(0.3), "key", syntheticRecords(2));
  const std::int64_t c = store.writeFrame(scene(0.5), "key", syntheticRecords(3));
  const FramePicture png = picture("png.1", 4);
  // Not recorded as interpolated: refused, nothing written.
  const std::string unrecorded = errorOf(
    [&] {
      store.storePicture(interpolated(0.2, "q35", { a, b }), png);
    });
  EXPECT_NE(unrecorded.find("is not recorded as interpolated by \"q35\" between the complete "
                            "frames {" +
                            std::to_string(a) + "," + std::to_string(b) + "}"),
            std::string::npos)
    << unrecorded;
  Db db(ci);
  EXPECT_EQ(db.value("SELECT count(*) FROM frame_pictures"), "0");

  store.recordInterpolatedFrame(scene(0.2), "q35", { a, b });
  store.storePicture(interpolated(0.2, "q35", { a, b }), png);
  expectSame(store.readPicture(interpolated(0.2, "q35", { a, b }), "png.1"), png);
  // Other keys, another recipe, another frame: none.
  EXPECT_EQ(store.readPicture(interpolated(0.2, "q35", { a, c }), "png.1"), std::nullopt);
  EXPECT_EQ(store.readPicture(interpolated(0.2, "q40", { a, b }), "png.1"), std::nullopt);
  EXPECT_EQ(store.readPicture(interpolated(0.4, "q35", { a, b }), "png.1"), std::nullopt);
  // The frame recorded again between other keys: the picture made between the old ones no longer
  // serves, not even asked for by them.
  store.recordInterpolatedFrame(scene(0.2), "q35", { a, c });
  EXPECT_EQ(store.readPicture(interpolated(0.2, "q35", { a, b }), "png.1"), std::nullopt);
  EXPECT_EQ(store.readPicture(interpolated(0.2, "q35", { a, c }), "png.1"), std::nullopt);
  store.recordInterpolatedFrame(scene(0.2), "q35", { a, b });
  expectSame(store.readPicture(interpolated(0.2, "q35", { a, b }), "png.1"), png);
  // A key deleted: the picture serves no more.
  store.deleteFrame(b);
  EXPECT_EQ(store.readPicture(interpolated(0.2, "q35", { a, b }), "png.1"), std::nullopt);
}

TEST(FramePictures, ABadPictureIsRefusedByNameAndNothingIsWritten)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate();
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const auto refusal = [&](FramePicture p)
  { return errorOf([&] { store.storePicture(whole(a), p); }); };
  FramePicture p = picture("png.1", 5);
  p.format = "PNG; DROP TABLE frames";
  EXPECT_NE(refusal(p).find("is not 1 to 32 of a-z, 0-9 and '.'"), std::string::npos);
  p = picture("", 5);
  EXPECT_NE(refusal(p).find("picture format \"\""), std::string::npos);
  p = picture("png.1", 5);
  p.method = 256;
  EXPECT_NE(refusal(p).find("picture method 256 is outside 0..255"), std::string::npos);
  p = picture("png.1", 5);
  p.shareRetraced = 1.5;
  EXPECT_NE(refusal(p).find("picture share re-traced"), std::string::npos);
  p = picture("png.1", 5);
  p.rays = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(p).find("picture rays"), std::string::npos);
  p = picture("png.1", 5);
  p.estimatedPsnr = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(p).find("picture PSNR is NaN"), std::string::npos);
  const std::string format = errorOf([&] { store.readPicture(whole(a), "a b"); });
  EXPECT_NE(format.find("picture format \"a b\""), std::string::npos) << format;
  Db db(ci);
  EXPECT_EQ(db.value("SELECT count(*) FROM frame_pictures"), "0");
}

TEST(FramePictures, AVersionEightStoreGainsTheTable)
{
  const std::string ci = freshDatabase();
  RayStore store(ci);
  store.migrate(8);
  Db db(ci);
  EXPECT_EQ(db.value("SELECT to_regclass('frame_pictures') IS NULL"), "t");
  store.migrate();
  EXPECT_EQ(store.schemaVersion(), RayStore::kSchemaVersion);
  EXPECT_EQ(db.value("SELECT to_regclass('frame_pictures') IS NULL"), "f");
  const std::int64_t a = store.writeFrame(scene(0.1), "key", syntheticRecords(1));
  const FramePicture png = picture("png.1", 6);
  store.storePicture(whole(a), png);
  expectSame(store.readPicture(whole(a), "png.1"), png);
}
