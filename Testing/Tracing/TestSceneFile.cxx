// Scene files: a valid description is read field by field, every invalid one is refused with the
// offending field's path in the message, and every preset in Data/scenes parses.
#include "SceneFile.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include <unistd.h>

using namespace asrt;
using json = nlohmann::json;

namespace
{
/// Fabricates 8 × 4 pixels for any path ending in "galaxy.png", and fails like a real loader for
/// everything else. Counts calls and records the paths it was given.
struct FakeLoader
{
  int calls = 0;
  std::vector<std::string> paths;
  ImageLoader loader()
  {
    return [this](const std::string& path)
    {
      ++this->calls;
      this->paths.push_back(path);
      const std::string tail = "galaxy.png";
      if (path.size() < tail.size() || path.compare(path.size() - tail.size(), tail.size(), tail))
        throw InvalidParameter("no such file");
      ImagePixels px;
      px.width = 8;
      px.height = 4;
      px.rgb.assign(3 * 8 * 4, 100);
      return px;
    };
  }
};

/// A scene using every object type, texture kind and section.
json validDoc()
{
  return json::parse(R"({
    "name": "test scene",
    "description": "every section and object type",
    "spacetime": {"mass": 1, "spin": 0, "charge": 0},
    "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
               "viewAngle": 30, "resolution": [320, 200], "observer": "static"},
    "integrator": {"method": "auto", "step": 0.02, "timeTransform": false, "omega": 2,
                   "relativeTolerance": 1e-9, "absoluteTolerance": 1e-11},
    "tracing": {"escapeRadius": 900, "maxSteps": 5000, "horizonEpsilon": 0.01,
                "maxHamiltonianError": 0.002},
    "background": [0.1, 0.2, 0.3],
    "horizonColor": [0.5, 0, 0],
    "objects": [
      {"type": "celestialSphere", "id": 0, "name": "galaxy", "radius": 500,
       "texture": {"image": "textures/galaxy.png"}},
      {"type": "cylinder", "id": 1, "name": "x", "base": [-15, 0, 0], "axis": [1, 0, 0],
       "radius": 0.5, "height": 30, "texture": {"checker": [8, 30], "colors": [[1, 0, 0], [1, 1, 1]]}},
      {"type": "sphere", "id": 2, "center": [5, 5, 5], "radius": 1, "texture": {"color": [0, 1, 0]}},
      {"type": "disk", "id": 3, "name": "disk", "center": [0, 0, 0], "normal": [0, 0, 1],
       "innerRadius": 6, "outerRadius": 20, "texture": {"checker": [36, 14]}},
      {"type": "plane", "id": 4, "name": "floor", "center": [0, 0, -10], "uAxis": [1, 0, 0],
       "vAxis": [0, 1, 0], "tile": 4, "texture": {"color": [0.5, 0.5, 0.5]}},
      {"type": "rectangle", "id": 5, "name": "board", "center": [0, 20, 0], "uAxis": [1, 0, 0],
       "vAxis": [0, 0, 1], "halfWidth": 10, "halfHeight": 5, "texture": {"image": "textures/galaxy.png"}}
    ]
  })");
}

SceneDescription parse(const json& doc, FakeLoader* fake = nullptr)
{
  FakeLoader local;
  return parseScene(doc.dump(), "/scenes", (fake ? fake : &local)->loader());
}

/// The message of the InvalidParameter that parsing throws ("" if none: the test then fails).
std::string errorOf(const std::function<void(json&)>& mutate)
{
  json doc = validDoc();
  mutate(doc);
  try
  {
    parse(doc);
  }
  catch (const InvalidParameter& e)
  {
    return e.what();
  }
  catch (const std::exception& e)
  {
    return std::string("unexpected exception type: ") + e.what();
  }
  return "";
}

#define EXPECT_ERROR(mutation, expected)                                                           \
  do                                                                                               \
  {                                                                                                \
    const std::string msg = errorOf([](json& d) { mutation; });                                    \
    EXPECT_NE(msg.find(expected), std::string::npos)                                               \
      << "mutation: " #mutation "\nexpected: " << (expected) << "\ngot: " << msg;                  \
  } while (0)

std::string dataDir()
{
  if (const char* env = std::getenv("ASRT_DATA_DIR"))
    return env;
  // This file is Testing/Tracing/TestSceneFile.cxx; the data is Data/ at the top of the source
  // tree.
  return (std::filesystem::path(__FILE__).parent_path().parent_path().parent_path() / "Data")
    .string();
}

/// Reads a PNG's size from its IHDR chunk (bytes 16–23) and fabricates that many pixels, so that
/// the presets' textures are checked to exist and be PNGs without decoding them.
ImagePixels pngHeaderLoader(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  unsigned char h[24];
  if (!in.read(reinterpret_cast<char*>(h), sizeof h))
    throw InvalidParameter("cannot open \"" + path + "\"");
  const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' };
  if (!std::equal(sig, sig + 8, h) || std::string(reinterpret_cast<char*>(h + 12), 4) != "IHDR")
    throw InvalidParameter("\"" + path + "\" is not a PNG");
  auto be32 = [&](int k) { return (h[k] << 24) | (h[k + 1] << 16) | (h[k + 2] << 8) | h[k + 3]; };
  ImagePixels px;
  px.width = be32(16);
  px.height = be32(20);
  px.rgb.assign(3 * static_cast<std::size_t>(px.width) * px.height, 0);
  return px;
}
}

TEST(SceneFile, ReadsEveryField)
{
  FakeLoader fake;
  const SceneDescription d = parse(validDoc(), &fake);
  EXPECT_EQ(d.name, "test scene");
  EXPECT_EQ(d.spacetime.mass, 1.0);
  EXPECT_EQ(d.camera.position, Vec3(0, -30, 8));
  EXPECT_EQ(d.camera.width, 320);
  EXPECT_EQ(d.camera.height, 200);
  EXPECT_EQ(d.camera.viewAngle, 30.0);
  EXPECT_EQ(d.camera.observer, ObserverMotion::Static);
  EXPECT_EQ(d.integrator.method, "auto");
  EXPECT_EQ(d.integrator.step, 0.02);
  EXPECT_FALSE(d.integrator.timeTransform);
  EXPECT_EQ(d.integrator.omega, 2.0);
  EXPECT_EQ(d.integrator.relativeTolerance, 1e-9);
  EXPECT_EQ(d.integrator.absoluteTolerance, 1e-11);
  EXPECT_EQ(d.tracing.escapeRadius, 900.0);
  EXPECT_EQ(d.tracing.maxSteps, 5000);
  EXPECT_EQ(d.tracing.horizonEpsilon, 0.01);
  EXPECT_EQ(d.tracing.maxHamiltonianError, 0.002);
  EXPECT_EQ(d.scene->background, Color(0.1, 0.2, 0.3));
  EXPECT_EQ(d.scene->horizonColor, Color(0.5, 0, 0));

  const auto& objs = d.scene->objects();
  ASSERT_EQ(objs.size(), 6u);
  const char* types[] = { "celestialSphere", "cylinder", "sphere", "disk", "plane", "rectangle" };
  for (int k = 0; k < 6; ++k)
  {
    EXPECT_EQ(objs[k]->id(), k);
    EXPECT_STREQ(objs[k]->type(), types[k]);
  }
  EXPECT_EQ(objs[1]->name(), "x");
  EXPECT_EQ(objs[2]->name(), "sphere2"); // the default name: type and id
  EXPECT_EQ(d.scene->celestialRadius(), 500.0);
  // The image is read once, from the path resolved against the base directory, and shared.
  EXPECT_EQ(fake.calls, 1);
  ASSERT_EQ(fake.paths.size(), 1u);
  EXPECT_EQ(fake.paths[0], "/scenes/textures/galaxy.png");
  EXPECT_EQ(&objs[0]->texture(), &objs[5]->texture());
  // The checker's default colours are white and black.
  const auto* checker = dynamic_cast<const CheckerTexture*>(&objs[3]->texture());
  ASSERT_NE(checker, nullptr);
  EXPECT_EQ(checker->sample(0.01, 0.01), Color(1, 1, 1));

  // The geometry arrives: a ray down the y-axis from the camera side meets the board at y = 20
  // only after the cylinder (radius 0.5 about the x-axis) in front of it.
  Segment seg;
  seg.x0 << 0, 0, -10, 0.2;
  seg.x1 << 0, 0, 30, 0.2;
  seg.d0 = seg.d1 = seg.x1 - seg.x0;
  SurfaceHit hit;
  ASSERT_TRUE(d.scene->firstHit(seg, hit));
  EXPECT_EQ(hit.objectId, 1);
  EXPECT_NEAR(hit.point.y(), -std::sqrt(0.25 - 0.04), 1e-14);
}

TEST(SceneFile, DefaultsAndNormalisedSource)
{
  const std::string minimal = R"({"spacetime": {"mass": 0},
    "camera": {"position": [0, -10, 0], "focalPoint": [0, 0, 0]}, "objects": []})";
  const SceneDescription d = parseScene(minimal, "", nullptr);
  const CameraParameters cam;
  const IntegratorConfig integ;
  const TraceOptions tr;
  EXPECT_EQ(d.name, "");
  EXPECT_EQ(d.spacetime.mass, 0.0);
  EXPECT_EQ(d.spacetime.spin, 0.0);
  EXPECT_EQ(d.camera.width, cam.width);
  EXPECT_EQ(d.camera.viewAngle, cam.viewAngle);
  EXPECT_EQ(d.camera.viewUp, cam.viewUp);
  EXPECT_EQ(d.camera.observer, cam.observer);
  EXPECT_EQ(d.integrator.method, integ.method);
  EXPECT_EQ(d.integrator.step, integ.step);
  EXPECT_EQ(d.tracing.maxSteps, tr.maxSteps);
  EXPECT_EQ(d.tracing.escapeRadius, tr.escapeRadius);
  EXPECT_TRUE(d.scene->objects().empty());
  // The source is stored normalised: the same document written differently gives the same text.
  const std::string reordered = R"({ "objects" : [ ],
    "camera": {"focalPoint": [0, 0, 0], "position": [0, -10, 0]},
    "spacetime": {"mass": 0.0} })";
  EXPECT_EQ(parseScene(reordered, "", nullptr).sourceText, json::parse(reordered).dump());
  EXPECT_EQ(d.sourceText, json::parse(minimal).dump());
  EXPECT_NE(d.sourceText.find("\"camera\""), std::string::npos);
}

TEST(SceneFile, ErrorsNameTheField)
{
  // The brief's examples, verbatim.
  EXPECT_ERROR(d["camera"]["resolution"][0] = 0,
               "camera.resolution[0]: must be a positive integer, got 0");
  EXPECT_ERROR(
    d["objects"][3]["type"] = "cone",
    "objects[3].type: unknown object type \"cone\" (known: celestialSphere, plane, rectangle, "
    "cylinder, sphere, disk)");
  EXPECT_ERROR(d["objects"][1]["texture"] = json::parse(R"({"image": "textures/missing.png"})"),
               "objects[1].texture.image: cannot read \"textures/missing.png\"");

  // Unknown keys, with a hint for a likely typo.
  EXPECT_ERROR(d["objects"][2]["raduis"] = 1,
               "objects[2].raduis: unknown field (did you mean \"radius\"?)");
  EXPECT_ERROR(
    {
      d["objects"][2].erase("radius");
      d["objects"][2]["raduis"] = 1;
    },
    "objects[2].raduis: unknown field"); // the typo, not "radius: missing"
  EXPECT_ERROR(d["backgroud"] = json::array({ 0, 0, 0 }), "backgroud: unknown field");
  EXPECT_ERROR(d["camera"]["fov"] = 30, "camera.fov: unknown field");
  EXPECT_ERROR(d["tracing"]["maxstep"] = 30,
               "tracing.maxstep: unknown field (did you mean \"maxSteps\"?)");
  EXPECT_ERROR(d["objects"][1]["texture"]["colour"] = json::array({ 0, 0, 0 }),
               "objects[1].texture.colour: unknown field");
  // A field of another object type is unknown here.
  EXPECT_ERROR(d["objects"][2]["height"] = 3, "objects[2].height: unknown field");

  // Wrong JSON types, "nan" and friends.
  EXPECT_ERROR(d["camera"]["viewAngle"] = "nan",
               "camera.viewAngle: must be a number, got string \"nan\"");
  EXPECT_ERROR(d["tracing"]["escapeRadius"] = "1000", "tracing.escapeRadius: must be a number");
  EXPECT_ERROR(d["spacetime"]["mass"] = "inf", "spacetime.mass: must be a number");
  EXPECT_ERROR(d["camera"]["position"] = json::array({ 0, "x", 1 }),
               "camera.position[1]: must be a number");
  EXPECT_ERROR(d["camera"]["position"] = json::array({ 0, 1 }),
               "camera.position: must be an array of 3 numbers");
  EXPECT_ERROR(d["integrator"]["timeTransform"] = "yes",
               "integrator.timeTransform: must be true or false");
  EXPECT_ERROR(d["objects"][1]["name"] = 5, "objects[1].name: must be a string");
  EXPECT_ERROR(d["camera"] = 3, "camera: must be an object");
  EXPECT_ERROR(d["objects"] = json::object(), "objects: must be an array");
  EXPECT_ERROR(d["objects"][2] = 7, "objects[2]: must be an object");

  // Missing required fields.
  EXPECT_ERROR(d.erase("spacetime"), "spacetime: required field is missing");
  EXPECT_ERROR(d.erase("objects"), "objects: required field is missing");
  EXPECT_ERROR(d["camera"].erase("position"), "camera.position: required field is missing");
  EXPECT_ERROR(d["spacetime"].erase("mass"), "spacetime.mass: required field is missing");
  EXPECT_ERROR(d["objects"][1].erase("radius"), "objects[1].radius: required field is missing");
  EXPECT_ERROR(d["objects"][3].erase("type"), "objects[3].type: required field is missing");
  EXPECT_ERROR(d["objects"][3].erase("id"), "objects[3].id: required field is missing");
  EXPECT_ERROR(d["objects"][3].erase("texture"), "objects[3].texture: required field is missing");

  // Values out of range.
  EXPECT_ERROR(d["spacetime"]["mass"] = -1, "spacetime.mass: must be non-negative, got -1");
  EXPECT_ERROR(d["spacetime"]["spin"] = 2, "spacetime: ");
  EXPECT_ERROR(d["objects"][2]["radius"] = -1, "objects[2].radius: must be positive, got -1");
  EXPECT_ERROR(d["objects"][1]["height"] = 0, "objects[1].height: must be positive, got 0");
  EXPECT_ERROR(d["objects"][1]["axis"] = json::array({ 0, 0, 0 }),
               "objects[1].axis: must be a nonzero vector");
  EXPECT_ERROR(d["objects"][3]["innerRadius"] = 25,
               "objects[3].outerRadius: must exceed innerRadius (25)");
  EXPECT_ERROR(d["objects"][3]["innerRadius"] = -1, "objects[3].innerRadius: must be non-negative");
  EXPECT_ERROR(d["objects"][4]["vAxis"] = json::array({ 2, 0, 0 }),
               "objects[4].vAxis: must not be parallel to uAxis");
  EXPECT_ERROR(d["objects"][4]["tile"] = 0, "objects[4].tile: must be positive");
  EXPECT_ERROR(d["objects"][5]["halfWidth"] = -2, "objects[5].halfWidth: must be positive");
  EXPECT_ERROR(d["objects"][0]["radius"] = 20,
               "objects[0].radius: the celestial sphere is seen from inside");
  EXPECT_ERROR(d["objects"][1]["id"] = 0,
               "objects[1].id: duplicate id 0 (already used by objects[0])");
  EXPECT_ERROR(d["objects"][1]["id"] = -1, "objects[1].id: must be a non-negative integer, got -1");
  EXPECT_ERROR(d["objects"][1]["id"] = 1.5,
               "objects[1].id: must be a non-negative integer, got 1.5");
  EXPECT_ERROR(d["camera"]["resolution"] = json::array({ 200 }),
               "camera.resolution: must be [width, height]");
  EXPECT_ERROR(d["camera"]["resolution"][1] = 200.5,
               "camera.resolution[1]: must be a positive integer, got 200.5");
  EXPECT_ERROR(d["camera"]["resolution"][0] = 3000000000LL,
               "camera.resolution[0]: must be a positive integer");
  EXPECT_ERROR(d["camera"]["resolution"] = json::array({ 100000, 100000 }),
               "camera.resolution: 100000 x 100000 pixels exceed the budget of 268435456 pixels");
  EXPECT_ERROR(d["camera"]["viewAngle"] = 180,
               "camera.viewAngle: must lie in (0, 180) degrees, got 180");
  EXPECT_ERROR(d["camera"]["viewAngle"] = 0, "camera.viewAngle: must lie in (0, 180)");
  EXPECT_ERROR(d["camera"]["observer"] = "moving",
               "camera.observer: must be \"static\" or \"zamo\", got \"moving\"");
  EXPECT_ERROR(d["camera"]["focalPoint"] = json::array({ 0, -30, 8 }),
               "camera.focalPoint: coincides with camera.position");
  EXPECT_ERROR(d["camera"]["viewUp"] = json::array({ 0, 30, -8 }),
               "camera.viewUp: is parallel to the direction of view");
  EXPECT_ERROR(d["camera"]["viewUp"] = json::array({ 0, 0, 0 }),
               "camera.viewUp: must be a nonzero vector");
  EXPECT_ERROR(d["camera"]["position"] = json::array({ 1.5, 0, 0 }),
               "camera.position: is inside the horizon");
  EXPECT_ERROR(d["integrator"]["method"] = "Euler",
               "integrator.method: unknown integration method 'Euler'");
  EXPECT_ERROR(d["integrator"]["method"] = "Analytic",
               "integrator.method: method Analytic traces straight lines");
  EXPECT_ERROR(d["integrator"]["method"] = "", "integrator.method: must not be empty");
  EXPECT_ERROR(d["integrator"]["step"] = 0, "integrator.step: must be positive, got 0");
  EXPECT_ERROR(d["integrator"]["omega"] = -1, "integrator.omega: must be positive");
  EXPECT_ERROR(d["tracing"]["maxSteps"] = -5,
               "tracing.maxSteps: must be a positive integer, got -5");
  EXPECT_ERROR(d["tracing"]["horizonEpsilon"] = 0, "tracing.horizonEpsilon: must be positive");
  EXPECT_ERROR(d["background"] = json::array({ 1, 2, 0 }),
               "background[1]: must lie in [0, 1], got 2");
  EXPECT_ERROR(d["horizonColor"] = "black", "horizonColor: must be an RGB array");

  // Textures.
  EXPECT_ERROR(d["objects"][2]["texture"]["checker"] = json::array({ 2, 2 }),
               "objects[2].texture: give exactly one of \"color\", \"checker\" or \"image\"");
  EXPECT_ERROR(d["objects"][2]["texture"] = json::object(),
               "objects[2].texture: give exactly one of");
  EXPECT_ERROR(d["objects"][1]["texture"]["checker"] = json::array({ 0, 4 }),
               "objects[1].texture.checker[0]: must be a positive integer, got 0");
  EXPECT_ERROR(d["objects"][1]["texture"]["colors"] = json::array({ json::array({ 1, 0, 0 }) }),
               "objects[1].texture.colors: must be two RGB colours");
  EXPECT_ERROR(d["objects"][1]["texture"]["colors"][1][2] = 1.5,
               "objects[1].texture.colors[1][2]: must lie in [0, 1], got 1.5");
  EXPECT_ERROR(d["objects"][2]["texture"]["colors"] = json::array(),
               "objects[2].texture.colors: belongs to a \"checker\" texture");
  EXPECT_ERROR(d["objects"][0]["texture"]["image"] = "",
               "objects[0].texture.image: must not be empty");
}

TEST(SceneFile, StaticObserverInsideAnErgosphereIsRefused)
{
  // Kerr a = 0.99: on the equator x² = r² + a², so x = 2.142 is r = 1.90, between r₊ = 1.14 and
  // the ergosphere's 2 M.
  const std::string msg = errorOf(
    [](json& d)
    {
      d["spacetime"]["spin"] = 0.99;
      d["camera"]["position"] = json::array({ 2.142, 0, 0 });
    });
  EXPECT_NE(msg.find("camera.observer: a static observer cannot exist"), std::string::npos) << msg;
  EXPECT_EQ(errorOf(
              [](json& d)
              {
                d["spacetime"]["spin"] = 0.99;
                d["camera"]["position"] = json::array({ 2.142, 0, 0 });
                d["camera"]["observer"] = "zamo";
              }),
            "");
}

TEST(SceneFile, DuplicateKeysAndMalformedJson)
{
  auto error = [](const std::string& text)
  {
    try
    {
      parseScene(text, "", nullptr);
    }
    catch (const InvalidParameter& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string head = R"({"spacetime": {"mass": 1}, "camera": {"position": [0, -30, 8],
    "focalPoint": [0, 0, 0]}, )";
  std::string msg = error(head + R"("objects": [], "objects": []})");
  EXPECT_NE(msg.find("objects: duplicate field"), std::string::npos) << msg;
  msg = error(head + R"("objects": [{"type": "sphere", "id": 0, "center": [0, 0, 0], "radius": 1,
    "texture": {"color": [1, 1, 1]}}, {"type": "sphere", "id": 1, "center": [0, 0, 0],
    "radius": 1, "radius": 2, "texture": {"color": [1, 1, 1]}}]})");
  EXPECT_NE(msg.find("objects[1].radius: duplicate field"), std::string::npos) << msg;
  msg = error(head + R"("objects": [)");
  EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << msg;
  msg = error("[1, 2]");
  EXPECT_NE(msg.find("must be an object"), std::string::npos) << msg;
  msg = error("");
  EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << msg;
  // JSON has no NaN or infinity, but a number can overflow a double.
  msg = error(head + R"("objects": [{"type": "sphere", "id": 0, "center": [0, 0, 1e400],
    "radius": 1, "texture": {"color": [1, 1, 1]}}]})");
  EXPECT_NE(msg.find("objects[0].center[2]: must be finite"), std::string::npos) << msg;
}

TEST(SceneFile, ImagesThroughTheLoader)
{
  json doc = validDoc();
  // An absolute path is used as it is; a relative one is resolved against the base directory.
  doc["objects"][5]["texture"]["image"] = "/elsewhere/galaxy.png";
  FakeLoader fake;
  parseScene(doc.dump(), "/data/scenes/../scenes", fake.loader());
  ASSERT_EQ(fake.paths.size(), 2u);
  EXPECT_EQ(fake.paths[0], "/data/scenes/textures/galaxy.png");
  EXPECT_EQ(fake.paths[1], "/elsewhere/galaxy.png");

  // No loader, or a loader that returns inconsistent pixels: refused, naming the field.
  try
  {
    parseScene(validDoc().dump(), "/scenes", nullptr);
    ADD_FAILURE() << "accepted an image without a loader";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("objects[0].texture.image: cannot read"),
              std::string::npos)
      << e.what();
  }
  const ImageLoader bad = [](const std::string&)
  {
    ImagePixels px;
    px.width = 4;
    px.height = 4;
    px.rgb.resize(10);
    return px;
  };
  try
  {
    parseScene(validDoc().dump(), "/scenes", bad);
    ADD_FAILURE() << "accepted inconsistent pixels";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("objects[0].texture.image: cannot read"),
              std::string::npos)
      << e.what();
    EXPECT_NE(std::string(e.what()).find("48"), std::string::npos) << e.what();
  }
}

TEST(SceneFile, LoadSceneFileNamesTheFile)
{
  EXPECT_THROW(loadSceneFile("/nonexistent/scene.json", nullptr), InvalidParameter);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("asrt-scenefile-" + std::to_string(::getpid()) + ".json"))
                             .string();
  {
    json doc = validDoc();
    doc["objects"][2]["radius"] = -3;
    std::ofstream(path) << doc.dump(2);
  }
  try
  {
    FakeLoader fake;
    loadSceneFile(path, fake.loader());
    ADD_FAILURE() << "accepted a negative radius";
  }
  catch (const InvalidParameter& e)
  {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": objects[2].radius: must be positive, got -3", 0), 0u) << msg;
  }
  std::remove(path.c_str());
}

// ---- the presets --------------------------------------------------------------------------------
namespace
{
SceneDescription preset(const std::string& name)
{
  return loadSceneFile(dataDir() + "/scenes/" + name, pngHeaderLoader);
}
}

TEST(SceneFilePresets, EveryPresetParses)
{
  const std::filesystem::path dir = dataDir() + "/scenes";
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
  {
    if (entry.path().extension() != ".json")
      continue;
    ++n;
    SCOPED_TRACE(entry.path().string());
    SceneDescription d;
    ASSERT_NO_THROW(d = loadSceneFile(entry.path().string(), pngHeaderLoader));
    EXPECT_FALSE(d.name.empty());
    EXPECT_FALSE(d.scene->objects().empty());
    // Each builds its spacetime and propagator (the parser checked the method against it).
    EXPECT_NO_THROW(makePropagator(*makeSpacetime(d.spacetime), d.integrator));
  }
  EXPECT_GE(n, 6);
}

TEST(SceneFilePresets, PaperFiguresAreOneSceneAtDifferentMasses)
{
  const SceneDescription fig1 = preset("fig1-cylinders.json");
  EXPECT_EQ(fig1.spacetime.mass, 1.0);
  EXPECT_EQ(fig1.camera.width, 200);
  EXPECT_EQ(fig1.camera.height, 200);
  int cylinders = 0, skies = 0, planes = 0;
  for (const auto& o : fig1.scene->objects())
  {
    const std::string t = o->type();
    cylinders += t == "cylinder";
    skies += t == "celestialSphere";
    planes += t == "rectangle" || t == "plane";
  }
  EXPECT_EQ(cylinders, 3);
  EXPECT_EQ(skies, 1);
  EXPECT_EQ(planes, 1);
  // The galaxy texture is the generated 1024 × 512 equirectangular image.
  const auto* sky = dynamic_cast<const ImageTexture*>(&fig1.scene->find(0)->texture());
  ASSERT_NE(sky, nullptr);
  EXPECT_EQ(sky->width(), 1024);
  EXPECT_EQ(sky->height(), 512);
  // The three cylinders cross at the hole: a straight line along each axis hits each one there.
  for (int id = 1; id <= 3; ++id)
  {
    const Vec3 axisPoint = Vec3::Unit(id - 1) * 3.0;
    Segment seg;
    seg.x0 << 0, axisPoint + Vec3(0.1, 0.1, 0.1) + 5 * Vec3::Unit(id % 3);
    seg.x1 << 0, axisPoint + Vec3(0.1, 0.1, 0.1);
    seg.d0 = seg.d1 = seg.x1 - seg.x0;
    SurfaceHit hit;
    EXPECT_TRUE(fig1.scene->find(id)->intersect(seg, hit)) << id;
  }

  // Figs. 2, 4 and 5 are fig. 1's scene with another mass: everything else is identical.
  auto withoutMass = [](const SceneDescription& d)
  {
    json j = json::parse(d.sourceText);
    j.erase("name");
    j.erase("description");
    j["spacetime"].erase("mass");
    return j;
  };
  const struct
  {
    const char* file;
    double mass;
  } others[] = { { "fig2-no-hole.json", 0.0 },
                 { "fig4-mass-start.json", 0.1 },
                 { "fig5-mass-end.json", 1.2 } };
  for (const auto& o : others)
  {
    const SceneDescription d = preset(o.file);
    EXPECT_EQ(d.spacetime.mass, o.mass) << o.file;
    EXPECT_EQ(withoutMass(d), withoutMass(fig1)) << o.file;
  }
}

TEST(SceneFilePresets, DiskScenesMatchTheirSpecification)
{
  const SceneDescription kerr = preset("kerr-disk.json");
  EXPECT_EQ(kerr.spacetime.spin, 0.9);
  // Prograde ISCO (Bardeen, Press & Teukolsky 1972) for a = 0.9: r = 2.32 M in Boyer–Lindquist r;
  // the disk is given in Cartesian (Kerr–Schild) radius ρ = √(r² + a²) on the equator.
  const double a = 0.9;
  const double z1 = 1 + std::cbrt(1 - a * a) * (std::cbrt(1 + a) + std::cbrt(1 - a));
  const double z2 = std::sqrt(3 * a * a + z1 * z1);
  const double isco = 3 + z2 - std::sqrt((3 - z1) * (3 + z1 + 2 * z2));
  EXPECT_NEAR(isco, 2.32, 0.005);
  const json kj = json::parse(kerr.sourceText);
  const json* disk = nullptr;
  for (const json& o : kj["objects"])
    if (o["type"] == "disk")
      disk = &o;
  ASSERT_NE(disk, nullptr);
  const double rho = (*disk)["innerRadius"].get<double>();
  EXPECT_NEAR(std::sqrt(rho * rho - a * a), isco, 0.02);
  EXPECT_EQ((*disk)["outerRadius"].get<double>(), 15.0);
  const double r = kerr.camera.position.norm();
  EXPECT_NEAR(r, 40.0, 1e-12);
  EXPECT_NEAR(std::acos(kerr.camera.position.z() / r) * 180 / M_PI, 75.0, 1e-9);

  const SceneDescription gyoto = preset("gyoto-disk.json");
  EXPECT_EQ(gyoto.spacetime.mass, 1.0);
  EXPECT_EQ(gyoto.spacetime.spin, 0.0);
  const double th = 80 * M_PI / 180;
  EXPECT_LT((gyoto.camera.position - Vec3(0, -50 * std::sin(th), 50 * std::cos(th))).norm(), 1e-13);
  EXPECT_NEAR(gyoto.camera.viewAngle * M_PI / 180, 0.9, 1e-15);
  EXPECT_EQ(gyoto.camera.observer, ObserverMotion::Static);
  EXPECT_EQ(gyoto.camera.width, 200);
  EXPECT_EQ(gyoto.camera.height, 200);
  ASSERT_EQ(gyoto.scene->objects().size(), 1u);
  const SceneObject& g = *gyoto.scene->objects()[0];
  EXPECT_STREQ(g.type(), "disk");
  // Opaque from 6 to 20 M in the equatorial plane: straight probes just inside and outside.
  auto probe = [&](double x)
  {
    Segment seg;
    seg.x0 << 0, x, 0, 1;
    seg.x1 << 0, x, 0, -1;
    seg.d0 = seg.d1 = seg.x1 - seg.x0;
    SurfaceHit hit;
    return g.intersect(seg, hit);
  };
  EXPECT_FALSE(probe(5.99));
  EXPECT_TRUE(probe(6.01));
  EXPECT_TRUE(probe(19.99));
  EXPECT_FALSE(probe(20.01));
}

TEST(SceneFile, IntegratorPresetsSetTolerancesAndAreRefinedByFields)
{
  const ImageLoader none = [](const std::string& path) -> ImagePixels
  { throw InvalidParameter("no images in this test: " + path); };
  auto parse = [&](const std::string& integrator)
  {
    return parseScene(
      R"({"spacetime": {"mass": 1}, "camera": {"position": [0, -30, 0], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
        "viewAngle": 30, "resolution": [8, 8]}, "objects": [],
      "integrator": )" +
        integrator + "}",
      ".", none);
  };
  EXPECT_EQ(parse(R"({"preset": "fast"})").integrator.relativeTolerance, 1e-8);
  EXPECT_EQ(parse(R"({"preset": "accurate"})").integrator.relativeTolerance, 1e-12);
  EXPECT_EQ(parse(R"({"preset": "accurate"})").integrator.absoluteTolerance, 1e-14);
  const SceneDescription refined = parse(R"({"preset": "fast", "method": "RK4", "step": 0.01})");
  EXPECT_EQ(refined.integrator.method, "RK4");
  EXPECT_EQ(refined.integrator.relativeTolerance, 1e-8);
  try
  {
    parse(R"({"preset": "ludicrous"})");
    FAIL();
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("integrator.preset"), std::string::npos) << e.what();
  }
}

TEST(SceneFile, EffectiveSceneTextCarriesOverridesAndParsesBack)
{
  // What is stored with a frame must be the scene as traced, overrides included, and must parse
  // back to the same description.
  const ImageLoader none = [](const std::string& path) -> ImagePixels
  { throw InvalidParameter("no images in this test: " + path); };
  SceneDescription d = parseScene(R"({"spacetime": {"mass": 1},
      "camera": {"position": [0, -30, 0], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
                 "viewAngle": 30, "resolution": [8, 8]},
      "objects": [{"type": "sphere", "id": 3, "center": [0, 20, 0], "radius": 2,
                   "texture": {"color": [1, 0, 0]}}]})",
                                  ".", none);
  d.spacetime.mass = 0.5;
  d.camera.position = Vec3(1, -25, 2);
  d.camera.width = 16;
  d.integrator.method = "RK4";
  d.integrator.step = 0.02;
  const SceneDescription back = parseScene(effectiveSceneText(d), ".", none);
  EXPECT_EQ(back.spacetime.mass, 0.5);
  EXPECT_EQ(back.camera.position, Vec3(1, -25, 2));
  EXPECT_EQ(back.camera.width, 16);
  EXPECT_EQ(back.integrator.method, "RK4");
  EXPECT_EQ(back.integrator.step, 0.02);
  ASSERT_EQ(back.scene->objects().size(), 1u);
  EXPECT_EQ(back.scene->objects()[0]->id(), 3);
  EXPECT_EQ(effectiveSceneText(back), effectiveSceneText(d)); // a fixed point: stable for hashing
}

TEST(SceneFile, SubsetFramesHaveAnIdentityOfTheirOwn)
{
  // A frame of only some pixels must never share its identity (its effective text) with the
  // whole frame at the same parameters, nor with another subset; whole frames keep their text.
  const ImageLoader none = [](const std::string& path) -> ImagePixels
  { throw InvalidParameter("no images in this test: " + path); };
  const SceneDescription whole = parseScene(R"({"spacetime": {"mass": 1},
      "camera": {"position": [0, -30, 0], "focalPoint": [0, 0, 0], "resolution": [8, 8]},
      "objects": []})",
                                            ".", none);
  const std::string wholeText = effectiveSceneText(whole);
  EXPECT_EQ(json::parse(wholeText).count("subset"), 0u);
  EXPECT_EQ(whole.subset.count, 0);

  const PixelSubsetId id = pixelSubsetId({ { 3, 4 }, { 1, 2 }, { 3, 4 } });
  EXPECT_EQ(id.count, 2); // distinct pixels
  EXPECT_EQ(id.digest.size(), 16u);
  EXPECT_EQ(pixelSubsetId({ { 1, 2 }, { 3, 4 } }), id); // order and repetition do not matter
  EXPECT_NE(pixelSubsetId({ { 1, 2 }, { 3, 5 } }).digest, id.digest);
  EXPECT_NE(pixelSubsetId({ { 2, 1 }, { 4, 3 } }).digest, id.digest); // i and j are not swapped
  EXPECT_EQ(pixelSubsetId({}).count, 0);

  SceneDescription part = whole;
  part.subset = id;
  const std::string partText = effectiveSceneText(part);
  EXPECT_NE(partText, wholeText);
  const SceneDescription back = parseScene(partText, ".", none, SceneOrigin::Program);
  EXPECT_EQ(back.subset, id);
  EXPECT_EQ(effectiveSceneText(back), partText);
  // Pixels traced beside given neighbour samples are a subset of their own, by those samples.
  JacobianSample given;
  given.i = 2;
  given.j = 2;
  given.u = 0.25;
  given.termination = Termination::Escaped;
  SceneDescription beside = part;
  beside.subset.border = borderDigest({ given });
  EXPECT_EQ(beside.subset.border.size(), 16u);
  EXPECT_EQ(borderDigest({}), "");
  JacobianSample moved = given;
  moved.u = std::nextafter(0.25, 1.0);
  EXPECT_NE(borderDigest({ moved }), beside.subset.border); // every bit of u counts
  JacobianSample other = given;
  other.i = 1;
  EXPECT_EQ(borderDigest({ given, other }), borderDigest({ other, given })); // in pixel order
  const std::string besideText = effectiveSceneText(beside);
  EXPECT_NE(besideText, partText);
  const SceneDescription besideBack = parseScene(besideText, ".", none, SceneOrigin::Program);
  EXPECT_EQ(besideBack.subset, beside.subset);
  EXPECT_FALSE(besideBack.subset == part.subset);
  EXPECT_EQ(effectiveSceneText(besideBack), besideText);
  // Clearing it gives the whole frame's text back.
  SceneDescription cleared = back;
  cleared.subset = PixelSubsetId();
  EXPECT_EQ(effectiveSceneText(cleared), wholeText);

  // A user's scene may not say it is a subset: a scene claiming 3 pixels that traces the whole
  // frame would be stored as that subset (the program's own text, read back, may).
  try
  {
    parseScene(partText, ".", none);
    ADD_FAILURE() << "a hand-written subset was accepted";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_EQ(std::string(e.what()).find("subset: is written by the program"), 0u) << e.what();
  }
  EXPECT_EQ(parseSceneWithoutImages(partText).subset, id);

  for (const char* bad :
       { R"({"pixels": 0, "digest": "0123456789abcdef"})", R"({"pixels": 3, "digest": "xyz"})",
         R"({"pixels": 3})", R"({"pixels": 3, "digest": "0123456789abcdef", "border": "12"})" })
  {
    json doc = json::parse(wholeText);
    doc["subset"] = json::parse(bad);
    try
    {
      parseScene(doc.dump(), ".", none, SceneOrigin::Program);
      ADD_FAILURE() << bad;
    }
    catch (const InvalidParameter& e)
    {
      EXPECT_NE(std::string(e.what()).find("subset"), std::string::npos) << e.what();
    }
  }
}
