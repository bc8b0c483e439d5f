// The camera path of asrt movie --cameras: the key file's refusals, and the spline against what
// it must be (through every key, C¹ across them, a straight line through collinear keys spaced
// evenly).
#include "CameraPath.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace
{
using asrt::Vec3;
using asrt::tools::CameraPose;

const char* const kThreeKeys = R"({"keys": [
  {"position": [0, -30, 5], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]},
  {"position": [20, -20, 8], "focalPoint": [1, 0, 0], "viewUp": [0, 0, 1]},
  {"position": [30, 0, 2], "focalPoint": [0, 1, 0], "viewUp": [0, 0.6, 0.8]}]})";

void expectRefused(const std::string& text, const std::string& message)
{
  try
  {
    asrt::tools::parseCameraKeys(text, "cams.json");
    ADD_FAILURE() << "accepted: " << text;
  }
  catch (const asrt::InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(CameraPath, KeyFileRefusalsNameTheField)
{
  expectRefused(R"({"keys": [{"position": [0, -30, 5], "focalPoint": [0, 0, 0],
    "viewUp": [0, 0, 1]}]})",
                "cams.json: keys: a path needs at least 2 key cameras, got 1");
  expectRefused(R"({"keys": [{"position": [0, -30, 5], "focalPoint": [0, 0, 0],
    "viewUp": [0, 0, 1]}, {"position": [0, 1e999, 5], "focalPoint": [0, 0, 0],
    "viewUp": [0, 0, 1]}]})",
                "cams.json: not valid JSON ([json.exception.out_of_range.406] number overflow "
                "parsing '1e999')");
  expectRefused(R"({"keys": [{"position": [0, NaN, 5]}]})", "cams.json: not valid JSON");
  expectRefused(R"({"keys": [{"position": [0, -30], "focalPoint": [0, 0, 0],
    "viewUp": [0, 0, 1]}, {}]})",
                "keys[0].position must be an array of 3 numbers");
  expectRefused(R"({"keys": [{"position": [0, -30, 1], "focalPoint": [0, 0, 0],
    "viewUp": [0, 0, 1]}, {"position": [0, -30, 1], "viewUp": [0, 0, 1]}]})",
                "keys[1].focalPoint is missing");
  expectRefused(R"({"keys": [], "speed": 1})", "unknown field \"speed\"");
  expectRefused(R"([1, 2])", "expected {\"keys\"");
}

TEST(CameraPath, PassesThroughEveryKeyAndIsSmoothAcrossThem)
{
  const std::vector<CameraPose> keys = asrt::tools::parseCameraKeys(kThreeKeys, "k");
  ASSERT_EQ(keys.size(), 3u);
  for (int k = 0; k < 3; ++k)
  {
    const CameraPose at = asrt::tools::cameraOnPath(keys, k);
    EXPECT_EQ(at.position, keys[static_cast<std::size_t>(k)].position) << "key " << k;
    EXPECT_EQ(at.focalPoint, keys[static_cast<std::size_t>(k)].focalPoint) << "key " << k;
    EXPECT_NEAR((at.viewUp - keys[static_cast<std::size_t>(k)].viewUp).norm(), 0, 1e-15);
  }
  // C¹ at the inner key: the difference quotients on both sides agree to O(h).
  const double h = 1e-5;
  const Vec3 left = (asrt::tools::cameraOnPath(keys, 1).position -
                     asrt::tools::cameraOnPath(keys, 1 - h).position) /
                    h;
  const Vec3 right = (asrt::tools::cameraOnPath(keys, 1 + h).position -
                      asrt::tools::cameraOnPath(keys, 1).position) /
                     h;
  EXPECT_NEAR((left - right).norm(), 0, 1e-3);
  // The Catmull-Rom tangent at an inner key is half the chord between its neighbours.
  EXPECT_NEAR((left - 0.5 * (keys[2].position - keys[0].position)).norm(), 0, 1e-3);
}

TEST(CameraPath, EvenlySpacedCollinearKeysGiveAStraightEvenFlight)
{
  std::vector<CameraPose> keys;
  for (int k = 0; k < 4; ++k)
    keys.push_back({ Vec3(10.0 * k, -30, 0), Vec3(0, 0, 0), Vec3(0, 0, 1) });
  for (double u : { 0.25, 0.5, 1.7, 2.9 })
  {
    const CameraPose p = asrt::tools::cameraOnPath(keys, u);
    EXPECT_NEAR((p.position - Vec3(10.0 * u, -30, 0)).norm(), 0, 1e-12) << "u = " << u;
  }
}
}
