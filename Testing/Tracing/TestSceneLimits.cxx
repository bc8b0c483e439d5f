// The bounds of scene parsing: JSON nested deeper than kMaxSceneNesting is refused while parsing
// (however deep, wherever it sits), scene text and files beyond kMaxSceneBytes are refused (and
// endless files are read only up to the bound), and the values, keys and names quoted in messages
// are cut short.
#include "AddressSpaceLimit.h"
#include "SceneFile.h"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <new>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

using namespace asrt;

namespace
{
/// A valid scene with `spacetimeExtra` (e.g. ", \"spin\": X") added to its spacetime section,
/// the given objects and `sections` (e.g. ", \"integrator\": {...}") added at the top level.
std::string sceneWith(const std::string& spacetimeExtra, const std::string& objects = "[]",
                      const std::string& sections = std::string())
{
  return R"({"spacetime": {"mass": 1)" + spacetimeExtra + R"(},
    "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "resolution": [8, 8]},
    "objects": )" +
         objects + sections + "}";
}

std::string errorOf(const std::string& text)
{
  try
  {
    parseScene(text, "", nullptr);
  }
  catch (const InvalidParameter& e)
  {
    return e.what();
  }
  return "(no error)";
}

std::string nested(std::size_t depth)
{
  return std::string(depth, '[') + std::string(depth, ']');
}

const std::string kTooDeep = "arrays and objects nested more than 64 levels deep";

/// A message quoting a few dozen characters of the value beside its fixed text (the longest, an
/// unknown method's, lists every known method).
constexpr std::size_t kShortMessage = 400;
}

TEST(SceneNesting, SixtyFourLevelsAreParsedSixtyFiveAreNot)
{
  // The document itself: 64 levels reach the object check, 65 stop at the parser.
  EXPECT_EQ(errorOf(nested(64)).find("(document): must be an object, got array"), 0u)
    << errorOf(nested(64));
  EXPECT_EQ(errorOf(nested(65)), "[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]...: " +
                                   kTooDeep + " (a scene needs 6)");
  // Inside the scene: the spacetime object is level 2, so its field may nest 62 more.
  EXPECT_EQ(
    errorOf(sceneWith(", \"spin\": " + nested(62))).find("spacetime.spin: must be a number"), 0u);
  EXPECT_NE(errorOf(sceneWith(", \"spin\": " + nested(63))).find(kTooDeep), std::string::npos);
}

TEST(SceneNesting, HundredThousandLevelsAreRefusedWithoutCrashing)
{
  const std::size_t deep = 100000;
  EXPECT_NE(errorOf(nested(deep)).find(kTooDeep), std::string::npos);
  const std::string inField = errorOf(sceneWith(", \"spin\": " + nested(deep)));
  EXPECT_EQ(inField.find("spacetime.spin[0][0]"), 0u) << inField;
  EXPECT_NE(inField.find(kTooDeep), std::string::npos);
  std::string objects;
  for (std::size_t k = 0; k < deep; ++k)
    objects += "{\"a\": ";
  objects += "1" + std::string(deep, '}');
  const std::string inObjects = errorOf(sceneWith("", objects));
  EXPECT_EQ(inObjects.find("objects.a.a.a"), 0u) << inObjects.substr(0, 200);
  EXPECT_NE(inObjects.find(kTooDeep), std::string::npos);
  EXPECT_LT(inObjects.size(), kShortMessage);
  // Where every scene loader goes: a scene without images takes the same path.
  EXPECT_THROW(parseSceneWithoutImages(nested(deep)), InvalidParameter);
}

TEST(SceneMessages, LongValuesKeysAndNamesAreCut)
{
  const std::string longText(100000, 'x');
  const std::string quoted = "\"" + longText + "\"";
  std::string manyOnes;
  for (int k = 0; k < 100000; ++k)
    manyOnes += "1,";
  struct Case
  {
    std::string text, start;
  };
  const Case cases[] = {
    { sceneWith(", \"spin\": " + quoted), "spacetime.spin: must be a number, got string \"xxx" },
    { sceneWith(", \"" + longText + "\": 1"), "spacetime.xxxxxxxxxx" },
    { sceneWith(", \"spin\": [" + manyOnes + "1]"),
      "spacetime.spin: must be a number, got array [1,1," },
    { sceneWith(", \"spin\": 1" + std::string(100000, '0')),
      "spacetime.spin: must be finite, got a number that overflows a double ([json.exception" },
    { sceneWith(", \"spin\": " + nested(60)), "spacetime.spin: must be a number, got array [[[[" },
    { sceneWith("", "[{\"type\": " + quoted + "}]"), "objects[0].type: unknown object type \"xxx" },
    { sceneWith("", R"([{"type": "sphere", "id": 1, "center": [0, 5, 0], "radius": 1,
                        "texture": {"image": )" +
                      quoted + "}}]"),
      "objects[0].texture.image: cannot read \"xxx" },
    { sceneWith("", "[]", ", \"integrator\": {\"preset\": " + quoted + "}"),
      "integrator.preset: unknown preset \"xxx" },
    { sceneWith("", "[]", ", \"integrator\": {\"method\": " + quoted + "}"),
      "integrator.method: unknown integration method 'xxx" },
    { "{\"" + longText + "\": 1, \"" + longText + "\": 2}", "xxxxxxxxx" },
    { "[\"" + longText, "(document): malformed JSON" },
  };
  for (const Case& c : cases)
  {
    const std::string message = errorOf(c.text);
    EXPECT_EQ(message.find(c.start), 0u) << message.substr(0, 300);
    EXPECT_LT(message.size(), kShortMessage) << message.substr(0, 300);
  }
  // The cut value ends in "...", and whole values below the cut are shown whole.
  EXPECT_NE(errorOf(sceneWith(", \"spin\": " + quoted)).find("xxx..."), std::string::npos);
  EXPECT_NE(
    errorOf(sceneWith(", \"spin\": [1,[2,{\"k\":\"v\"}]]")).find("got array [1,[2,{\"k\":\"v\"}]]"),
    std::string::npos);
}

TEST(SceneSize, TextBeyondTheCapIsRefused)
{
  // Padding with whitespace keeps the scene valid: at the cap it parses, one byte more it does not.
  const std::string scene = sceneWith("");
  std::string text = scene + std::string(kMaxSceneBytes - scene.size(), ' ');
  EXPECT_NO_THROW(parseScene(text, "", nullptr));
  text += ' ';
  EXPECT_EQ(errorOf(text), "(document): the scene's 67108865 bytes exceed the 64 MiB a scene "
                           "may have");
}

TEST(SceneSize, EndlessFilesAreReadOnlyUpToTheCap)
{
  // Reading /dev/zero whole would exhaust memory: the bound fails the test instead.
  const asrt::testing::AddressSpaceLimit bound(2e9);
  try
  {
    loadSceneFile("/dev/zero", nullptr);
    ADD_FAILURE() << "/dev/zero parsed as a scene";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_STREQ(e.what(), "scene file \"/dev/zero\" is larger than 64 MiB (67108864 bytes), the "
                           "most a scene may hold");
  }
}

TEST(SceneSize, EndlessPipesAreReadOnlyUpToTheCap)
{
  const std::string fifo = ::testing::TempDir() + "asrt-endless-scene";
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // The writer writes until the reader closes its end.
  const auto previous = std::signal(SIGPIPE, SIG_IGN);
  std::atomic<long long> sent{ 0 };
  std::thread writer(
    [&]()
    {
      const int fd = open(fifo.c_str(), O_WRONLY);
      const std::vector<char> block(1 << 16, '[');
      ssize_t n;
      while (fd >= 0 && (n = write(fd, block.data(), block.size())) > 0)
        sent += n;
      if (fd >= 0)
        close(fd);
    });
  std::string message;
  {
    const asrt::testing::AddressSpaceLimit bound(2e9);
    try
    {
      loadSceneFile(fifo, nullptr);
    }
    catch (const InvalidParameter& e)
    {
      message = e.what();
    }
  }
  writer.join();
  std::signal(SIGPIPE, previous);
  std::remove(fifo.c_str());
  EXPECT_NE(message.find("is larger than 64 MiB"), std::string::npos) << message;
  EXPECT_GT(sent.load(), static_cast<long long>(kMaxSceneBytes));
}

TEST(SceneSize, DirectoryIsNotAScene)
{
  const std::string dir = ::testing::TempDir();
  try
  {
    loadSceneFile(dir, nullptr);
    ADD_FAILURE() << "a directory parsed as a scene";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_EQ(std::string(e.what()), "cannot read scene file \"" + dir + "\"");
  }
}

TEST(AddressSpaceLimit, StopsAnAllocationBeyondIt)
{
  // The guard the endless-input tests rely on.
  const asrt::testing::AddressSpaceLimit bound(1e9);
  EXPECT_THROW(std::vector<char>(std::size_t(4) << 30, 'x'), std::bad_alloc);
}

// A number that underflows a double is refused naming its field (nlohmann would read 1e-400 as 0:
// flat space for a mass), while zeros written as such and normal small numbers are taken as they
// are; strtod's ERANGE is the truth each case is judged by.
TEST(SceneNumbers, UnderflowingNumbersAreRefusedNamingTheirField)
{
  const std::string tiny = "1e-400";
  errno = 0;
  std::strtod(tiny.c_str(), nullptr);
  ASSERT_EQ(errno, ERANGE) << "the case must underflow";
  EXPECT_EQ(errorOf(sceneWith(", \"spin\": " + tiny)).find("spacetime.spin: a number too small"),
            0u)
    << errorOf(sceneWith(", \"spin\": " + tiny));
  // After legal zeros and tiny normal numbers elsewhere, the underflowing one is still the one
  // named: zeros written "0.0" and "-0e5" come first in the document.
  const std::string objects =
    R"([{"type": "sphere", "id": 1, "center": [0.0, -0e5, 1e-300], "radius": 1,
        "texture": {"color": [0.0, 0.5, 1e-320]}}])";
  const std::string message = errorOf(sceneWith(", \"spin\": 0.0", objects));
  EXPECT_EQ(message.find("objects[0].texture.color[2]: a number too small"), 0u) << message;
  // The same scene with a normal number there parses, every zero and 1e-300 kept.
  const std::string fine =
    R"([{"type": "sphere", "id": 1, "center": [0.0, -0e5, 1e-300], "radius": 1,
        "texture": {"color": [0.0, 0.5, 0.25]}}])";
  const SceneDescription d = parseScene(sceneWith(", \"spin\": 0.0", fine), "", nullptr);
  EXPECT_EQ(d.spacetime.spin, 0.0);
  // A zero in a string, a key or a name is text, not a number.
  EXPECT_NO_THROW(parseScene(R"({"name": "1e-400", "spacetime": {"mass": 1},
    "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "resolution": [8, 8]},
    "objects": []})",
                             "", nullptr));
}

// The tracing margins are bounded: a capture margin of 1e300 would call every ray captured.
TEST(SceneNumbers, TracingMarginsAreBounded)
{
  const auto tracing = [](const std::string& fields)
  { return errorOf(sceneWith("", "[]", ", \"tracing\": {" + fields + "}")); };
  EXPECT_EQ(tracing("\"horizonEpsilon\": 1e300").find("tracing.horizonEpsilon: must lie in (0, 1]"),
            0u);
  EXPECT_EQ(tracing("\"maxHamiltonianError\": 1").find("tracing.maxHamiltonianError: must lie"),
            0u);
  EXPECT_EQ(tracing("\"horizonEpsilon\": 1, \"maxHamiltonianError\": 0.5"), "(no error)");
}

// A NUL in a texture's file name is refused, and the message shows it escaped and goes on past it.
TEST(SceneMessages, NulInATextureNameIsShownAndRefused)
{
  const std::string message =
    errorOf(sceneWith("", R"([{"type": "sphere", "id": 1, "center": [0, 5, 0], "radius": 1,
                              "texture": {"image": "galaxy.png\u0000/etc/passwd"}}])"));
  EXPECT_EQ(message.find("objects[0].texture.image: a file name cannot hold a NUL character"), 0u)
    << message;
  EXPECT_EQ(message.find('\0'), std::string::npos) << "the message holds the NUL itself";
  EXPECT_NE(message.find("\\u0000/etc/passwd"), std::string::npos) << message;
}

// The object count is bounded, and the bound is exact: kMaxSceneObjects spheres parse, one more
// is refused naming the field, before any object is built.
TEST(SceneSize, ObjectCountIsBounded)
{
  auto spheres = [](std::size_t n)
  {
    std::string objects = "[";
    for (std::size_t k = 0; k < n; ++k)
      objects += (k ? "," : "") + std::string(R"({"type": "sphere", "id": )") +
                 std::to_string(k + 1) + R"(, "center": [0, 20, 0], "radius": 0.5,
                  "texture": {"color": [1, 1, 1]}})";
    return objects + "]";
  };
  EXPECT_EQ(
    parseScene(sceneWith("", spheres(kMaxSceneObjects)), "", nullptr).scene->objects().size(),
    kMaxSceneObjects);
  EXPECT_EQ(errorOf(sceneWith("", spheres(kMaxSceneObjects + 1))),
            "objects: holds 20001 objects; a scene may have at most 20000");
}
