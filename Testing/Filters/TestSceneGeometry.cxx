// vtkGeodesicSceneGeometry: every preset tessellates into coloured polygons, the horizon lies on
// the Kerr–Schild horizon (r₊ computed here, independently of the spacetime classes), and vertex
// colours follow the objects' textures.
#include "FiltersTestUtilities.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkGeodesicSceneGeometry.h"
#include "vtkIdList.h"

#include <cmath>
#include <set>

using asrt::testing::MessageCatcher;
using asrt::testing::scenePath;

namespace
{
struct Preset
{
  const char* file;
  std::set<int> objectIds; ///< ids of the objects other than the celestial sphere
  bool hole;               ///< M > 0, so a horizon is drawn
  bool sky;                ///< has a celestial sphere (id 0)
};

const Preset kPresets[] = {
  { "fig1-cylinders.json", { 1, 2, 3, 4 }, true, true },
  { "fig2-no-hole.json", { 1, 2, 3, 4 }, false, true },
  { "fig4-mass-start.json", { 1, 2, 3, 4 }, true, true },
  { "fig5-mass-end.json", { 1, 2, 3, 4 }, true, true },
  { "gyoto-disk.json", { 1 }, true, false },
  { "kerr-disk.json", { 1 }, true, true },
};

double outerHorizon(double m, double a)
{
  return m > 0 ? m + std::sqrt(m * m - a * a) : 0.0;
}

/// The ids of the points of the cells whose ObjectId is `id`.
std::set<vtkIdType> pointsOfObject(vtkPolyData* pd, int id)
{
  std::set<vtkIdType> out;
  vtkDataArray* ids = pd->GetCellData()->GetArray("ObjectId");
  vtkNew<vtkIdList> cell;
  for (vtkIdType c = 0; c < pd->GetNumberOfCells(); ++c)
    if (static_cast<int>(ids->GetComponent(c, 0)) == id)
    {
      pd->GetCellPoints(c, cell);
      for (vtkIdType k = 0; k < cell->GetNumberOfIds(); ++k)
        out.insert(cell->GetId(k));
    }
  return out;
}
}

TEST(SceneGeometry, EveryPresetGivesColouredPolygons)
{
  for (const Preset& preset : kPresets)
  {
    SCOPED_TRACE(preset.file);
    vtkNew<vtkGeodesicSceneGeometry> g;
    vtkNew<MessageCatcher> catcher;
    asrt::testing::watch(g, catcher);
    g->SetSceneFileName(scenePath(preset.file).c_str());
    g->SetResolution(16);
    g->Update();
    ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
    vtkPolyData* pd = g->GetOutput();
    ASSERT_GT(pd->GetNumberOfPolys(), 0);
    EXPECT_EQ(pd->GetNumberOfCells(), pd->GetNumberOfPolys()) << "only polygons expected";
    vtkDataArray* colors = pd->GetPointData()->GetArray("Colors");
    ASSERT_NE(colors, nullptr);
    EXPECT_EQ(colors->GetDataType(), VTK_UNSIGNED_CHAR);
    EXPECT_EQ(colors->GetNumberOfComponents(), 3);
    EXPECT_EQ(colors->GetNumberOfTuples(), pd->GetNumberOfPoints());
    vtkDataArray* ids = pd->GetCellData()->GetArray("ObjectId");
    ASSERT_NE(ids, nullptr);
    ASSERT_EQ(ids->GetNumberOfTuples(), pd->GetNumberOfCells());
    std::set<int> seen;
    for (vtkIdType c = 0; c < ids->GetNumberOfTuples(); ++c)
      seen.insert(static_cast<int>(ids->GetComponent(c, 0)));
    std::set<int> expected = preset.objectIds;
    if (preset.hole)
      expected.insert(-1); // the horizon
    EXPECT_EQ(seen, expected) << "celestial sphere off by default, horizon iff M > 0";
    // Texture colours are not all black: the objects are checkered in colour.
    double sum = 0;
    for (vtkIdType k = 0; k < colors->GetNumberOfTuples(); ++k)
      sum += colors->GetComponent(k, 0) + colors->GetComponent(k, 1) + colors->GetComponent(k, 2);
    EXPECT_GT(sum, 0.0);

    if (!preset.sky)
      continue;
    g->IncludeCelestialSphereOn();
    g->Update();
    std::set<vtkIdType> sky = pointsOfObject(g->GetOutput(), 0);
    ASSERT_FALSE(sky.empty()) << "no celestial sphere when asked for";
    double x[3];
    for (vtkIdType k : sky)
    {
      g->GetOutput()->GetPoint(k, x);
      EXPECT_NEAR(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), 500.0, 1e-9);
    }
  }
}

TEST(SceneGeometry, KerrHorizonLiesOnTheKerrSchildSpheroid)
{
  for (double spinOverride : { std::nan(""), 0.5, 0.0 })
  {
    SCOPED_TRACE("spin override " + std::to_string(spinOverride));
    vtkNew<vtkGeodesicSceneGeometry> g;
    vtkNew<MessageCatcher> catcher;
    asrt::testing::watch(g, catcher);
    g->SetSceneFileName(scenePath("kerr-disk.json").c_str());
    g->SetSpin(spinOverride);
    g->SetResolution(24);
    g->Update();
    ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
    const double m = 1.0, a = std::isnan(spinOverride) ? 0.9 : spinOverride;
    const double rPlus = outerHorizon(m, a);
    const std::set<vtkIdType> horizon = pointsOfObject(g->GetOutput(), -1);
    ASSERT_GT(horizon.size(), 50u);
    double x[3], zMin = 1e300, zMax = -1e300, rhoMax = 0;
    for (vtkIdType k : horizon)
    {
      g->GetOutput()->GetPoint(k, x);
      // z = r₊ cos θ and x² + y² = (r₊² + a²) sin²θ, with sin²θ = 1 − (z / r₊)².
      const double cosTheta = x[2] / rPlus;
      ASSERT_LE(std::abs(cosTheta), 1.0 + 1e-12);
      const double rho2 = x[0] * x[0] + x[1] * x[1];
      EXPECT_NEAR(rho2, (rPlus * rPlus + a * a) * (1.0 - cosTheta * cosTheta), 1e-9);
      zMin = std::min(zMin, x[2]);
      zMax = std::max(zMax, x[2]);
      rhoMax = std::max(rhoMax, std::sqrt(rho2));
    }
    // The poles and the equator are on the surface, so the spheroid's axes are reached.
    EXPECT_NEAR(zMax, rPlus, 1e-9);
    EXPECT_NEAR(zMin, -rPlus, 1e-9);
    // The grid's rows of θ need not include the equator: allow the gap of half a row.
    EXPECT_NEAR(rhoMax, std::sqrt(rPlus * rPlus + a * a), 2e-2 * std::sqrt(rPlus * rPlus + a * a));
    // All horizon vertices are black.
    vtkDataArray* colors = g->GetOutput()->GetPointData()->GetArray("Colors");
    for (vtkIdType k : horizon)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(colors->GetComponent(k, c), 0.0);
  }
}

TEST(SceneGeometry, SchwarzschildHorizonIsTheSphereOfRadiusTwoM)
{
  vtkNew<vtkGeodesicSceneGeometry> g;
  g->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  g->SetMass(1.5); // the override, so that r₊ = 3 differs from the file's 2
  g->Update();
  const std::set<vtkIdType> horizon = pointsOfObject(g->GetOutput(), -1);
  ASSERT_FALSE(horizon.empty());
  double x[3];
  for (vtkIdType k : horizon)
  {
    g->GetOutput()->GetPoint(k, x);
    EXPECT_NEAR(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), 3.0, 1e-9);
  }
}

// With OverrideSpacetime off, Mass is ignored (ParaView's panel always holds a number): the horizon
// is the scene's, r₊ = 2M = 2; switched back on, the override's r₊ = 3.
TEST(SceneGeometry, OverrideSpacetimeOffKeepsTheScenesHole)
{
  for (bool override : { false, true })
  {
    SCOPED_TRACE(override ? "override on" : "override off");
    vtkNew<vtkGeodesicSceneGeometry> g;
    g->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
    g->SetMass(1.5);
    g->SetOverrideSpacetime(override);
    g->Update();
    const std::set<vtkIdType> horizon = pointsOfObject(g->GetOutput(), -1);
    ASSERT_FALSE(horizon.empty());
    double x[3];
    for (vtkIdType k : horizon)
    {
      g->GetOutput()->GetPoint(k, x);
      ASSERT_NEAR(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), override ? 3.0 : 2.0, 1e-9);
    }
  }
}

TEST(SceneGeometry, FloorVertexColoursFollowTheCheckerImage)
{
  // Fig. 1's floor is a rectangle centred at (0, 5, −10), 40 × 40 M, textured with checker.png:
  // 8 × 8 checks of 32 pixels, cream at the bottom-left check (0, 0), slate at odd i + j
  // (scripts/make-textures). With the default Resolution 64, vertices sit at u, v = k/64.
  // Probe vertices in the middle of checks, away from the orientation dots: u = 3/16 lies in
  // check column 1, and v = 0 (bottom row), v = 1/2 (check row 4) and v = 1 (top row, check
  // row 7: the image is clamped in v, so the top edge shows the top row of the image).
  const unsigned char cream[3] = { 232, 226, 208 }, slate[3] = { 46, 66, 98 };
  struct Probe
  {
    double u, v;
    const unsigned char* rgb;
  };
  const Probe probes[] = {
    { 3.0 / 16, 0.0, slate },      // check (1, 0): odd
    { 3.0 / 16, 9.0 / 16, slate }, // check (1, 4): odd
    { 5.0 / 16, 9.0 / 16, cream }, // check (2, 4): even
    { 3.0 / 16, 1.0, cream },      // check (1, 7): even, the top edge
    { 5.0 / 16, 1.0, slate },      // check (2, 7): odd, the top edge
  };
  vtkNew<vtkGeodesicSceneGeometry> g;
  g->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  g->Update();
  vtkPolyData* pd = g->GetOutput();
  const std::set<vtkIdType> floor = pointsOfObject(pd, 4);
  ASSERT_FALSE(floor.empty());
  vtkDataArray* colors = pd->GetPointData()->GetArray("Colors");
  for (const Probe& probe : probes)
  {
    const double target[3] = { -20.0 + 40.0 * probe.u, -15.0 + 40.0 * probe.v, -10.0 };
    vtkIdType found = -1;
    double x[3];
    for (vtkIdType k : floor)
    {
      pd->GetPoint(k, x);
      if (std::abs(x[0] - target[0]) < 1e-9 && std::abs(x[1] - target[1]) < 1e-9 &&
          std::abs(x[2] - target[2]) < 1e-9)
        found = k;
    }
    ASSERT_GE(found, 0) << "no floor vertex at u = " << probe.u << ", v = " << probe.v;
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(colors->GetComponent(found, c), probe.rgb[c])
        << "channel " << c << " of the vertex at u = " << probe.u << ", v = " << probe.v;
  }
}

TEST(SceneGeometry, BadSceneIsAnError)
{
  vtkNew<vtkGeodesicSceneGeometry> g;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(g, catcher);
  g->SetSceneFileName(scenePath("kerr-disk.json").c_str());
  g->SetSpin(2.0); // |a| > M: no horizon, a naked singularity
  g->Update();
  EXPECT_TRUE(catcher->Mentions("spin")) << catcher->AllErrors();
  EXPECT_EQ(g->GetOutput()->GetNumberOfPoints(), 0);
}
