// validateScene: a description changed after parsing (an override) is refused exactly as the
// scene file holding the same value is. The truth is the parser's own refusal of the file; the
// bounds on lengths are checked against their documented values.
#include "SceneFile.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <limits>
#include <string>

using namespace asrt;
using json = nlohmann::json;

namespace
{
/// A scene with a celestial sphere of radius 500 around a camera at about 31 M.
json validDoc()
{
  return json::parse(R"({
    "spacetime": {"mass": 1, "spin": 0, "charge": 0},
    "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
               "viewAngle": 30, "resolution": [16, 16], "observer": "static"},
    "integrator": {"method": "auto", "step": 0.05},
    "tracing": {"escapeRadius": 1000, "maxSteps": 5000},
    "objects": [
      {"type": "celestialSphere", "id": 0, "radius": 500, "texture": {"color": [0, 0, 1]}},
      {"type": "sphere", "id": 1, "center": [5, 5, 5], "radius": 1, "texture": {"color": [0, 1, 0]}}
    ]
  })");
}

template<class F>
std::string messageOf(F&& f)
{
  try
  {
    f();
  }
  catch (const InvalidParameter& e)
  {
    return e.what();
  }
  return "";
}

/// The parser's message for the scene file with `edit` applied.
std::string fileError(const std::function<void(json&)>& edit)
{
  json doc = validDoc();
  edit(doc);
  return messageOf([&] { parseSceneWithoutImages(doc.dump()); });
}

/// validateScene's message for the valid scene, parsed, then changed by `edit`.
std::string overrideError(const std::function<void(SceneDescription&)>& edit)
{
  SceneDescription d = parseSceneWithoutImages(validDoc().dump());
  edit(d);
  return messageOf([&] { validateScene(d); });
}

struct Case
{
  const char* what;
  std::function<void(json&)> inFile;
  std::function<void(SceneDescription&)> asOverride;
};
}

TEST(DescriptionValidation, TheValidSceneAndItsDescriptionPass)
{
  EXPECT_EQ(fileError([](json&) {}), "");
  EXPECT_EQ(overrideError([](SceneDescription&) {}), "");
  // Tiny and huge holes within the bounds are holes like any other.
  EXPECT_EQ(overrideError([](SceneDescription& d) { d.spacetime = { 1e-6, 1e-7, 0 }; }), "");
}

TEST(DescriptionValidation, AnOverrideIsRefusedAsTheSameValueInTheFile)
{
  const Case cases[] = {
    { "camera outside the celestial sphere",
      [](json& j) {
        j["camera"]["position"] = { 0, -2000, 0 };
      },
      [](SceneDescription& d) { d.camera.position = Vec3(0, -2000, 0); } },
    { "camera at 1e308",
      [](json& j) {
        j["camera"]["position"] = { 1e308, 0, 0 };
      },
      [](SceneDescription& d) { d.camera.position = Vec3(1e308, 0, 0); } },
    { "focal point at -1e200",
      [](json& j) {
        j["camera"]["focalPoint"] = { 0, -1e200, 0 };
      },
      [](SceneDescription& d) { d.camera.focalPoint = Vec3(0, -1e200, 0); } },
    { "mass 1e308", [](json& j) { j["spacetime"]["mass"] = 1e308; },
      [](SceneDescription& d) { d.spacetime.mass = 1e308; } },
    { "mass 1e-80", [](json& j) { j["spacetime"]["mass"] = 1e-80; },
      [](SceneDescription& d) { d.spacetime.mass = 1e-80; } },
    { "negative mass", [](json& j) { j["spacetime"]["mass"] = -1; },
      [](SceneDescription& d) { d.spacetime.mass = -1; } },
    { "spin above the mass", [](json& j) { j["spacetime"]["spin"] = 2; },
      [](SceneDescription& d) { d.spacetime.spin = 2; } },
    { "camera inside the horizon",
      [](json& j) {
        j["camera"]["position"] = { 1.5, 0, 0 };
      },
      [](SceneDescription& d) { d.camera.position = Vec3(1.5, 0, 0); } },
    { "static observer in the ergosphere",
      [](json& j)
      {
        j["spacetime"]["spin"] = 0.99;
        j["camera"]["position"] = { 2.142, 0, 0 };
      },
      [](SceneDescription& d)
      {
        d.spacetime.spin = 0.99;
        d.camera.position = Vec3(2.142, 0, 0);
      } },
    { "focal point at the eye",
      [](json& j) {
        j["camera"]["focalPoint"] = { 0, -30, 8 };
      },
      [](SceneDescription& d) { d.camera.focalPoint = Vec3(0, -30, 8); } },
    { "view-up along the view",
      [](json& j) {
        j["camera"]["viewUp"] = { 0, 30, -8 };
      },
      [](SceneDescription& d) { d.camera.viewUp = Vec3(0, 30, -8); } },
    { "view-up too long",
      [](json& j) {
        j["camera"]["viewUp"] = { 1e200, 0, 0 };
      },
      [](SceneDescription& d) { d.camera.viewUp = Vec3(1e200, 0, 0); } },
    { "view angle 180", [](json& j) { j["camera"]["viewAngle"] = 180; },
      [](SceneDescription& d) { d.camera.viewAngle = 180; } },
    { "view angle -5", [](json& j) { j["camera"]["viewAngle"] = -5; },
      [](SceneDescription& d) { d.camera.viewAngle = -5; } },
    { "too many pixels",
      [](json& j) {
        j["camera"]["resolution"] = { 100000, 100000 };
      },
      [](SceneDescription& d) { d.camera.width = d.camera.height = 100000; } },
    { "unknown method", [](json& j) { j["integrator"]["method"] = "Euler"; },
      [](SceneDescription& d) { d.integrator.method = "Euler"; } },
    { "method that cannot model Kerr",
      [](json& j)
      {
        j["spacetime"]["spin"] = 0.5;
        j["integrator"]["method"] = "SchwarzschildSplit4";
      },
      [](SceneDescription& d)
      {
        d.spacetime.spin = 0.5;
        d.integrator.method = "SchwarzschildSplit4";
      } },
    { "zero step", [](json& j) { j["integrator"]["step"] = 0; },
      [](SceneDescription& d) { d.integrator.step = 0; } },
    { "escape radius 1e300", [](json& j) { j["tracing"]["escapeRadius"] = 1e300; },
      [](SceneDescription& d) { d.tracing.escapeRadius = 1e300; } },
  };
  for (const Case& c : cases)
  {
    const std::string inFile = fileError(c.inFile);
    EXPECT_NE(inFile, "") << c.what << ": the file is not refused";
    EXPECT_EQ(overrideError(c.asOverride), inFile) << c.what;
  }
}

TEST(DescriptionValidation, MagnitudesAreRefusedByNameAndBoundBeforeWhatTheyBreak)
{
  // Not "r+ = inf" nor "view-up parallel to the view": the overflowing value itself.
  const std::string mass = overrideError([](SceneDescription& d) { d.spacetime.mass = 1e308; });
  EXPECT_EQ(mass.rfind("spacetime.mass: must be at most 1e+75 in magnitude", 0), 0u) << mass;
  EXPECT_NE(mass.find("got 1e+308"), std::string::npos) << mass;
  EXPECT_EQ(mass.find("inf"), std::string::npos) << mass;
  const std::string eye =
    overrideError([](SceneDescription& d) { d.camera.position = Vec3(1e308, 0, 0); });
  EXPECT_EQ(eye.rfind("camera.position: coordinates must be at most 1e+75", 0), 0u) << eye;
  EXPECT_EQ(eye.find("parallel"), std::string::npos) << eye;
  const std::string tiny = overrideError([](SceneDescription& d) { d.spacetime.mass = 1e-80; });
  EXPECT_EQ(tiny.rfind("spacetime.mass: must be 0 or at least 1e-75", 0), 0u) << tiny;
  // At the bounds themselves, and zero mass, all is well.
  EXPECT_EQ(overrideError([](SceneDescription& d) { d.spacetime = { kMinSceneMass, 0, 0 }; }), "");
  EXPECT_EQ(overrideError([](SceneDescription& d) { d.spacetime = { 0, 0, 0 }; }), "");
  EXPECT_EQ(kMaxSceneLength, 1e75);
  EXPECT_EQ(kMinSceneMass, 1e-75);
}

TEST(DescriptionValidation, NonFiniteValuesAreNamed)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(overrideError([&](SceneDescription& d) { d.camera.position = Vec3(0, nan, 0); })
              .rfind("camera.position: must be finite", 0),
            0u);
  EXPECT_EQ(overrideError([&](SceneDescription& d) { d.spacetime.spin = inf; })
              .rfind("spacetime.spin: must be finite", 0),
            0u);
  EXPECT_EQ(overrideError([&](SceneDescription& d) { d.integrator.step = inf; })
              .rfind("integrator.step: must be finite", 0),
            0u);
  EXPECT_EQ(overrideError([&](SceneDescription& d) { d.camera.width = 0; }),
            "camera.resolution: must be positive, got 0 x 16");
}
