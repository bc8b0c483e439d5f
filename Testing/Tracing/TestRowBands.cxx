// Tracing rows a band at a time (traceRowsInBands) against the rows traced together
// (FrameTracer::traceRows): the same records bit for bit, Jacobians across the bands' seams
// included, for bands of every height and row ranges touching the frame's edges; whole rows at a
// time; and progress and stopping.
#include "CameraFixtures.h"
#include "FrameTracer.h"
#include "RowBands.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::looking;

namespace
{
constexpr int kW = 16, kH = 12;

/// A Schwarzschild scene whose rays hit a disk, a ball and the sky: Jacobians of several objects,
/// defined and undefined, on every row.
SceneDescription diskScene()
{
  SceneDescription d;
  d.spacetime.mass = 1.0;
  d.camera = looking(Vec3(0, -20, 3), Vec3(0, 0, 0), Vec3(0, 0, 1), 40, kW, kH);
  d.scene = std::make_shared<Scene>();
  // Bands of any number of rows: on the grid they would end on its lattice (TestAdaptiveGrid).
  d.rendering.gridLattice = 1;
  d.scene->add(std::make_unique<CelestialSphere>(
    0, "sky", std::make_shared<SolidTexture>(Color(0.1, 0.1, 0.3)), 500.0));
  d.scene->add(std::make_unique<Disk>(1, "disk",
                                      std::make_shared<SolidTexture>(Color(0.9, 0.6, 0.2)),
                                      Vec3(0, 0, 0), Vec3(0, 0, 1), 3.0, 12.0));
  d.scene->add(std::make_unique<Sphere>(
    2, "ball", std::make_shared<SolidTexture>(Color(0.2, 0.8, 0.2)), Vec3(4, 8, 2), 1.5));
  return d;
}

const FrameTracer& tracer()
{
  static const FrameTracer t(diskScene());
  return t;
}

/// Every field bit for bit (NaN equals NaN); the first that differs, or "".
std::string firstDifference(const RayRecord& a, const RayRecord& b)
{
  auto same = [](const auto& x, const auto& y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  const std::vector<std::pair<const char*, bool>> fields = {
    { "pixel", a.i == b.i && a.j == b.j },
    { "origin", same(a.origin, b.origin) },
    { "direction", same(a.direction, b.direction) },
    { "momentum", same(a.momentum, b.momentum) },
    { "termination", a.termination == b.termination },
    { "objectId", a.objectId == b.objectId },
    { "hitPoint", same(a.hitPoint, b.hitPoint) },
    { "hitNormal", same(a.hitNormal, b.hitNormal) },
    { "uv", same(a.u, b.u) && same(a.v, b.v) },
    { "chordError", same(a.chordError, b.chordError) },
    { "affineLength", same(a.affineLength, b.affineLength) },
    { "winding", same(a.winding, b.winding) },
    { "imageOrder", a.imageOrder == b.imageOrder },
    { "steps", a.steps == b.steps },
    { "maxAbsH", same(a.maxAbsH, b.maxAbsH) },
    { "color", same(a.color, b.color) },
    { "dudi", same(a.dudi, b.dudi) },
    { "dudj", same(a.dudj, b.dudj) },
    { "dvdi", same(a.dvdi, b.dvdi) },
    { "dvdj", same(a.dvdj, b.dvdj) },
  };
  for (const auto& [name, equal] : fields)
    if (!equal)
      return name;
  return "";
}

struct Banded
{
  std::vector<RayRecord> records;
  std::vector<std::size_t> runs; ///< the sizes the sink was handed
  bool finished = false;
};

Banded traceInBands(int rowBegin, int rowEnd, std::size_t bandPixels,
                    const std::function<bool(double)>& progress = nullptr)
{
  Banded out;
  out.finished = traceRowsInBands(
    tracer(), rowBegin, rowEnd,
    [&](const RayRecord* records, std::size_t count)
    {
      out.records.insert(out.records.end(), records, records + count);
      out.runs.push_back(count);
    },
    progress, bandPixels);
  return out;
}
}

TEST(RowBands, RecordsAreThoseOfTheRowsTracedTogether)
{
  const std::vector<std::pair<int, int>> ranges = { { 0, kH },      { 3, 7 }, { 0, 1 },
                                                    { kH - 1, kH }, { 5, 6 }, { 2, kH } };
  // One row, two, three, five, and more than the frame.
  const std::vector<std::size_t> bands = { 1, kW, 2 * kW + 3, 3 * kW, 5 * kW, 1000 * kW };
  for (const auto& [rowBegin, rowEnd] : ranges)
  {
    const std::vector<RayRecord> together = tracer().traceRows(rowBegin, rowEnd);
    for (std::size_t bandPixels : bands)
    {
      SCOPED_TRACE("rows [" + std::to_string(rowBegin) + ", " + std::to_string(rowEnd) +
                   "), bands of " + std::to_string(bandPixels) + " pixels");
      const Banded banded = traceInBands(rowBegin, rowEnd, bandPixels);
      EXPECT_TRUE(banded.finished);
      ASSERT_EQ(banded.records.size(), together.size());
      for (std::size_t k = 0; k < together.size(); ++k)
        ASSERT_EQ(firstDifference(banded.records[k], together[k]), "")
          << "record " << k << ", pixel (" << together[k].i << ", " << together[k].j << ")";
      // Whole rows at a time, never more than a band's.
      const std::size_t bandRows = std::max<std::size_t>(1, bandPixels / kW);
      for (std::size_t run : banded.runs)
      {
        EXPECT_EQ(run % kW, 0u) << "a run of " << run << " records is not whole rows";
        EXPECT_LE(run, bandRows * kW);
      }
    }
  }
}

TEST(RowBands, TheSeamsNeedTheNeighbouringBand)
{
  // Bands traced alone differ from the frame at their seams (else the comparison above would not
  // show that the seams are joined): the vertical Jacobians of a band's edge rows need the rows
  // across the seam.
  const std::vector<RayRecord> whole = tracer().traceRows(0, kH);
  int differing = 0;
  for (int b = 0; b < kH; b += 3)
  {
    std::vector<std::pair<int, int>> pixels;
    for (int j = b; j < b + 3; ++j)
      for (int i = 0; i < kW; ++i)
        pixels.emplace_back(i, j);
    const std::vector<RayRecord> alone = tracer().traceCentres(pixels);
    for (std::size_t k = 0; k < alone.size(); ++k)
      differing += firstDifference(alone[k], whole[static_cast<std::size_t>(b) * kW + k]) != "";
  }
  EXPECT_GT(differing, kW) << "the scene's Jacobians hardly depend on the next row";
}

TEST(RowBands, ProgressGrowsToOneAndStoppingEndsTheTrace)
{
  std::vector<double> seen;
  const Banded all = traceInBands(0, kH, 2 * kW,
                                  [&](double f)
                                  {
                                    seen.push_back(f);
                                    return true;
                                  });
  EXPECT_TRUE(all.finished);
  ASSERT_GE(seen.size(), 3u);
  for (std::size_t k = 1; k < seen.size(); ++k)
    EXPECT_GE(seen[k], seen[k - 1]) << "progress went back at " << k;
  EXPECT_GT(seen.front(), 0.0);
  // The end is reported as 1 by the calling thread, whichever threads traced the last rays.
  EXPECT_EQ(seen.back(), 1.0);

  // Stopped at the first report: the sink has had at most the rows before that band, and those
  // as traced together.
  int calls = 0;
  const Banded stopped = traceInBands(0, kH, 2 * kW, [&](double) { return ++calls > 1; });
  EXPECT_FALSE(stopped.finished);
  EXPECT_EQ(calls, 1);
  EXPECT_LT(stopped.records.size(), static_cast<std::size_t>(kW * kH));
  const std::vector<RayRecord> together = tracer().traceRows(0, kH);
  for (std::size_t k = 0; k < stopped.records.size(); ++k)
    EXPECT_EQ(firstDifference(stopped.records[k], together[k]), "") << "record " << k;

  // Stopped in a later band: what came before is kept.
  const Banded later = traceInBands(0, kH, 2 * kW, [&](double f) { return f < 0.5; });
  EXPECT_FALSE(later.finished);
  EXPECT_GT(later.records.size(), 0u);
  EXPECT_LT(later.records.size(), static_cast<std::size_t>(kW * kH));
  for (std::size_t k = 0; k < later.records.size(); ++k)
    EXPECT_EQ(firstDifference(later.records[k], together[k]), "") << "record " << k;
}

TEST(RowBands, EmptyAndOutOfFrameRangesTraceNothingOrTheFramesRows)
{
  EXPECT_TRUE(traceInBands(4, 4, kW).records.empty());
  EXPECT_TRUE(traceInBands(7, 3, kW).records.empty());
  const Banded clamped = traceInBands(-5, kH + 5, 3 * kW);
  const std::vector<RayRecord> together = tracer().traceRows(0, kH);
  ASSERT_EQ(clamped.records.size(), together.size());
  for (std::size_t k = 0; k < together.size(); ++k)
    EXPECT_EQ(firstDifference(clamped.records[k], together[k]), "") << "record " << k;
}
