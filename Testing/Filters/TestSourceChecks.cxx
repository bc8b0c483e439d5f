// vtkGeodesicSource's checks of what it traces: overrides are refused (vtkErrorMacro, outputs
// emptied) as the scene file's values would be, and CountRayEnds counts how the traced rays
// ended. The truths: the scene file's refusal of the same values, and the per-ray records of
// port 1, which reach the hits through another path than the image's Termination array.
#include "FiltersTestUtilities.h"
#include "SceneFile.h"

#include "vtkGeodesicSource.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <string>

using asrt::testing::MessageCatcher;
using asrt::testing::pixelList;
using asrt::testing::readFile;
using asrt::testing::scenePath;

namespace
{
/// Traces fig1 at 8 × 8 with `set` applied; returns the filter's first error ("" if none).
std::string traceError(vtkGeodesicSource* s, const std::function<void(vtkGeodesicSource*)>& set)
{
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(8, 8);
  set(s);
  s->Update();
  return catcher->Errors.empty() ? std::string() : catcher->Errors.front();
}

/// The error of the scene file fig1 with `edit` applied to its JSON.
std::string fileError(const std::function<void(nlohmann::json&)>& edit)
{
  nlohmann::json doc = nlohmann::json::parse(readFile(scenePath("fig1-cylinders.json")));
  edit(doc);
  try
  {
    asrt::parseSceneWithoutImages(doc.dump());
  }
  catch (const asrt::InvalidParameter& e)
  {
    return e.what();
  }
  return "";
}

/// Termination counts of the hits (port 1), one record per traced ray.
std::array<vtkIdType, 3> countsOfRecords(vtkPolyData* hits)
{
  std::array<vtkIdType, 3> c{ 0, 0, 0 };
  vtkDataArray* t = hits->GetPointData()->GetArray("Termination");
  for (vtkIdType k = 0; t && k < t->GetNumberOfTuples(); ++k)
  {
    const auto end = static_cast<asrt::Termination>(static_cast<int>(t->GetComponent(k, 0)));
    ++c[0];
    c[1] += end == asrt::Termination::NumericalFailure;
    c[2] += end == asrt::Termination::StepBudget;
  }
  return c;
}

void expectCountsOfRecords(vtkGeodesicSource* s)
{
  vtkIdType counts[3] = { -1, -1, -1 };
  ASSERT_TRUE(vtkGeodesicSource::CountRayEnds(s->GetImageOutput(), counts));
  const std::array<vtkIdType, 3> truth = countsOfRecords(s->GetHitsOutput());
  EXPECT_EQ(counts[0], truth[0]);
  EXPECT_EQ(counts[1], truth[1]);
  EXPECT_EQ(counts[2], truth[2]);
}
}

TEST(GeodesicSourceOverrides, AreRefusedAsTheSameValuesInTheSceneFile)
{
  struct Case
  {
    const char* what;
    std::function<void(vtkGeodesicSource*)> set;
    std::function<void(nlohmann::json&)> edit;
  };
  const Case cases[] = {
    { "camera outside the celestial sphere",
      [](vtkGeodesicSource* s) { s->SetCameraPosition(0, -2000, 0); },
      [](nlohmann::json& j) {
        j["camera"]["position"] = { 0, -2000, 0 };
      } },
    { "mass 1e308", [](vtkGeodesicSource* s) { s->SetMass(1e308); },
      [](nlohmann::json& j) { j["spacetime"]["mass"] = 1e308; } },
    { "camera at 1e308", [](vtkGeodesicSource* s) { s->SetCameraPosition(1e308, 0, 0); },
      [](nlohmann::json& j) {
        j["camera"]["position"] = { 1e308, 0, 0 };
      } },
    { "view-up along the view", [](vtkGeodesicSource* s) { s->SetViewUp(0, 30, -8); },
      [](nlohmann::json& j) {
        j["camera"]["viewUp"] = { 0, 30, -8 };
      } },
    { "view angle 200", [](vtkGeodesicSource* s) { s->SetViewAngle(200); },
      [](nlohmann::json& j) { j["camera"]["viewAngle"] = 200; } },
    { "spin above the mass", [](vtkGeodesicSource* s) { s->SetSpin(1.5); },
      [](nlohmann::json& j) { j["spacetime"]["spin"] = 1.5; } },
    { "focal point at 1e300", [](vtkGeodesicSource* s) { s->SetFocalPoint(0, 0, 1e300); },
      [](nlohmann::json& j) {
        j["camera"]["focalPoint"] = { 0, 0, 1e300 };
      } },
  };
  for (const Case& c : cases)
  {
    vtkNew<vtkGeodesicSource> s;
    const std::string expected = fileError(c.edit);
    ASSERT_NE(expected, "") << c.what;
    // The file's message is prefixed with its path; the override's is the field's.
    const std::string got = traceError(s, c.set);
    EXPECT_NE(got.find(expected.substr(expected.find(": ") + 2)), std::string::npos)
      << c.what << "\n got: " << got << "\n file: " << expected;
    EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0) << c.what;
    EXPECT_EQ(s->GetHitsOutput()->GetNumberOfPoints(), 0) << c.what;
  }
}

TEST(GeodesicSourceOverrides, FrameSceneTextIsRefusedToo)
{
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetCameraPosition(0, -2000, 0);
  EXPECT_EQ(s->GetFrameSceneText(), "");
  EXPECT_TRUE(catcher->Mentions("celestial sphere")) << catcher->AllErrors();
}

TEST(GeodesicSourceOverrides, FrameSceneTextWithoutImagesIsTheTextWithoutReadingATexture)
{
  vtkNew<vtkGeodesicSource> s;
  s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  s->SetMass(0.7);
  s->SetCameraPosition(3, -29, 8);
  const std::string withImages = s->GetFrameSceneText();
  ASSERT_FALSE(withImages.empty());
  EXPECT_EQ(s->GetFrameSceneTextWithoutImages(), withImages);

  // A texture that is not there: the scene text with images is refused for it, the one without
  // them never reads it and names it as the scene does.
  nlohmann::json doc = nlohmann::json::parse(readFile(scenePath("fig4-mass-start.json")));
  doc["objects"][0]["texture"]["image"] = "no-such-texture.png";
  vtkNew<vtkGeodesicSource> t;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(t, catcher);
  t->SetSceneText(doc.dump().c_str());
  EXPECT_EQ(t->GetFrameSceneText(), "");
  EXPECT_TRUE(catcher->Mentions("no-such-texture.png")) << catcher->AllErrors();
  const std::string withoutImages = t->GetFrameSceneTextWithoutImages();
  ASSERT_FALSE(withoutImages.empty()) << catcher->AllErrors();
  EXPECT_EQ(nlohmann::json::parse(withoutImages)["objects"][0]["texture"]["image"],
            "no-such-texture.png");
}

TEST(GeodesicSourceRayEnds, CountsMatchTheRecordsOfAGoodFrame)
{
  vtkNew<vtkGeodesicSource> s;
  ASSERT_EQ(traceError(s, [](vtkGeodesicSource*) {}), "");
  expectCountsOfRecords(s);
  vtkIdType counts[3];
  vtkGeodesicSource::CountRayEnds(s->GetImageOutput(), counts);
  EXPECT_EQ(counts[0], 64);
}

TEST(GeodesicSourceRayEnds, AHugeStepFailsEveryRay)
{
  vtkNew<vtkGeodesicSource> s;
  // Dormand–Prince starts from the given step; PlanarOrbit, the default here, picks its own.
  ASSERT_EQ(traceError(s,
                       [](vtkGeodesicSource* f)
                       {
                         f->SetIntegrationMethod("DormandPrince54");
                         f->SetIntegrationStep(1e300);
                       }),
            "");
  expectCountsOfRecords(s);
  vtkIdType counts[3];
  vtkGeodesicSource::CountRayEnds(s->GetImageOutput(), counts);
  EXPECT_EQ(counts[0], 64);
  EXPECT_EQ(counts[1], 64) << "a step of 1e300 M cannot trace a ray";
}

TEST(GeodesicSourceRayEnds, ATinyStepBudgetEndsRaysOnTheBudget)
{
  nlohmann::json doc = nlohmann::json::parse(readFile(scenePath("fig1-cylinders.json")));
  doc["tracing"]["maxSteps"] = 3;
  for (nlohmann::json& object : doc["objects"]) // SceneText has no directory to find textures in
    if (object["texture"].contains("image"))
      object["texture"] = { { "color", { 0, 0, 1 } } };
  vtkNew<vtkGeodesicSource> s;
  ASSERT_EQ(traceError(s, [&](vtkGeodesicSource* f) { f->SetSceneText(doc.dump().c_str()); }), "");
  expectCountsOfRecords(s);
  vtkIdType counts[3];
  vtkGeodesicSource::CountRayEnds(s->GetImageOutput(), counts);
  EXPECT_GT(counts[2], 32) << "three steps cannot take most rays from 31 M to the sky";
}

TEST(GeodesicSourceRayEnds, PixelsOutsideASubsetAreNotCounted)
{
  vtkNew<vtkGeodesicSource> s;
  ASSERT_EQ(traceError(s,
                       [](vtkGeodesicSource* f) {
                         f->SetPixelSubset(pixelList({ { 0, 0 }, { 3, 4 }, { 7, 7 } }));
                       }),
            "");
  vtkIdType counts[3];
  ASSERT_TRUE(vtkGeodesicSource::CountRayEnds(s->GetImageOutput(), counts));
  EXPECT_EQ(counts[0], 3);
  expectCountsOfRecords(s);
}

TEST(GeodesicSourceRayEnds, AnImageWithoutTerminationIsNotCounted)
{
  vtkNew<vtkImageData> image;
  image->SetDimensions(2, 2, 1);
  vtkIdType counts[3] = { 5, 5, 5 };
  EXPECT_FALSE(vtkGeodesicSource::CountRayEnds(image, counts));
  EXPECT_EQ(counts[0] + counts[1] + counts[2], 0);
  EXPECT_FALSE(vtkGeodesicSource::CountRayEnds(nullptr, counts));
}

TEST(GeodesicSourceOverrides, GridOptionsOutOfRangeAreRefusedNamingTheField)
{
  const std::pair<std::function<void(vtkGeodesicSource*)>, const char*> cases[] = {
    { [](vtkGeodesicSource* s) { s->SetGridLattice(257); }, "rendering.gridLattice" },
    { [](vtkGeodesicSource* s) { s->SetGridLattice(-3); }, "rendering.gridLattice" },
    { [](vtkGeodesicSource* s) { s->SetGridTolerance(-1e-3); }, "rendering.gridTolerance" },
  };
  for (const auto& [set, field] : cases)
  {
    vtkNew<vtkGeodesicSource> s;
    const std::string got = traceError(s, set);
    EXPECT_NE(got.find(field), std::string::npos) << got;
    EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0) << field;
  }
  // In range, the frame's scene says how it was traced.
  vtkNew<vtkGeodesicSource> s;
  EXPECT_EQ(traceError(s,
                       [](vtkGeodesicSource* g)
                       {
                         g->SetGridLattice(4);
                         g->SetGridTolerance(2e-3);
                       }),
            "");
  const nlohmann::json text = nlohmann::json::parse(s->GetFrameSceneText());
  EXPECT_EQ(text["rendering"]["gridLattice"], 4);
  EXPECT_EQ(text["rendering"]["gridTolerance"], 2e-3);
}
