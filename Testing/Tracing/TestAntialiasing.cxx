// Anti-aliasing against independent truth: a head-on checker in flat space against its exact area
// average over each pixel, adaptive sampling against a fixed 8 × 8 supersample the test traces
// itself, footprints that bend settled by their corner cells where the colour cannot show it (and
// within their spread of the supersample), the same frame at any thread count and in any split into
// pieces, and the rendering options refused by name.
#include "CameraFixtures.h"
#include "FrameTracer.h"
#include "RowBands.h"
#include "SceneFile.h"
#include "TextureFiles.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::looking;

namespace
{
/// The integral of the ±1 square wave s(x) = (−1)^⌊x⌋ from 0 to x: a triangle wave.
double squareWaveIntegral(double x)
{
  const double f = x - 2.0 * std::floor(0.5 * x); // x mod 2, in [0, 2)
  return f <= 1.0 ? f : 2.0 - f;
}

/// The mean of s over [a, b].
double squareWaveMean(double a, double b)
{
  return (squareWaveIntegral(b) - squareWaveIntegral(a)) / (b - a);
}

SceneDescription checkerWall(double mass, int w, int h)
{
  SceneDescription d;
  d.spacetime.mass = mass;
  d.camera = looking(Vec3(0, -30, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), 40, w, h);
  d.scene = std::make_shared<Scene>();
  d.scene->add(std::make_unique<Rectangle>(
    1, "wall", std::make_shared<CheckerTexture>(12, 12, Color(0.9, 0.2, 0.1), Color(0.1, 0.3, 0.9)),
    Vec3(0, 10, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), 20.0, 20.0));
  d.scene->add(std::make_unique<CelestialSphere>(
    0, "sky", std::make_shared<CheckerTexture>(24, 12, Color(1, 1, 1), Color(0, 0, 0)), 200.0));
  return d;
}

/// Where the head-on checkerWall(0, w, h) seen from (0, −30, 0) puts pixel edges, in checks
/// from the wall's corner (u = 0 at x = −20): the pinhole projects screen position i onto the wall
/// 40 units away, whose 40 units a side hold 12 checks.
struct HeadOnWallChecks
{
  int w, h;
  double x(double i) const
  {
    return ((2.0 * i + 1.0 - w) / w * tanHalf() * double(w) / h * 40.0 + 20.0) / 40.0 * 12.0;
  }
  double z(double j) const
  {
    return ((2.0 * j + 1.0 - h) / h * tanHalf() * 40.0 + 20.0) / 40.0 * 12.0;
  }
  static double tanHalf() { return std::tan(0.5 * 40.0 * M_PI / 180.0); }
};

double rmsDifference(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  double s = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    s += (a[k].color - b[k].color).squaredNorm();
  return std::sqrt(s / (3.0 * a.size()));
}

std::vector<RayRecord> traceFrame(SceneDescription d, const AntialiasOptions& o)
{
  d.rendering = o;
  FrameTracer tracer(d);
  return tracer.traceRows(0, d.camera.height);
}

std::string dataDir()
{
  if (const char* env = std::getenv("ASRT_DATA_DIR"))
    return env;
  return (std::filesystem::path(__FILE__).parent_path().parent_path().parent_path() / "Data")
    .string();
}

/// Fig. 1's scene (strongly lensed: its edges are where anti-aliasing works), its textures read,
/// at w × h.
SceneDescription fig1At(int w, int h)
{
  SceneDescription d = loadSceneFile(dataDir() + "/scenes/fig1-cylinders.json",
                                     [](const std::string& path) { return readPngTexture(path); });
  d.camera.width = w;
  d.camera.height = h;
  return d;
}

AntialiasOptions options(AntialiasMode mode, int cap = 16, int supersample = 1)
{
  AntialiasOptions o;
  o.mode = mode;
  o.maxRaysPerPixel = cap;
  o.supersample = supersample;
  // The anti-aliasing of every pixel's own centre ray; the grid's records are TestAdaptiveGrid's.
  o.gridLattice = 1;
  return o;
}
}

TEST(Antialiasing, HeadOnCheckerIsItsExactAreaAverageOverEachPixel)
{
  // Flat space, the wall perpendicular to the line of sight: a pixel's footprint is the square of
  // the wall that the pinhole projects it onto, and the checker's average over it is a product of
  // square-wave means.
  const int W = 48, H = 36;
  SceneDescription d = checkerWall(0.0, W, H);
  const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::Filter));
  const HeadOnWallChecks checks{ W, H };
  const Color a(0.9, 0.2, 0.1), b(0.1, 0.3, 0.9);
  double worst = 0;
  for (const RayRecord& r : frame)
  {
    ASSERT_EQ(r.objectId, 1) << "pixel " << r.i << ", " << r.j;
    EXPECT_EQ(r.raysPerPixel, 1);
    const double mean = squareWaveMean(checks.x(r.i - 0.5), checks.x(r.i + 0.5)) *
                        squareWaveMean(checks.z(r.j - 0.5), checks.z(r.j + 0.5));
    const Color exact = 0.5 * (a + b) + 0.5 * (a - b) * mean;
    worst = std::max(worst, (r.color - exact).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1.0 / 255.0);
  // One ray a pixel point-samples, and is far from the average where a check edge crosses.
  const std::vector<RayRecord> point = traceFrame(d, options(AntialiasMode::None));
  EXPECT_GT(rmsDifference(point, frame), 0.05);
}

TEST(Antialiasing, SamplePatternResolvesAnEdgeAlongAPixelAxisInNinthsOfThePixel)
{
  // The same head-on wall, point-sampled by the 3 × 3 pattern: each of the 9 samples lies in its
  // own ninth of the pixel's width and of its height, so where one check edge crosses the pixel
  // (along a pixel axis) the colour is the area average to within half a ninth of the contrast.
  // A plain 3 × 3 grid resolves such an edge in thirds only, up to three times further off.
  const int W = 48, H = 36;
  SceneDescription d = checkerWall(0.0, W, H);
  const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::None, 1, 3));
  const HeadOnWallChecks checks{ W, H };
  auto crosses = [](double a, double b) { return std::floor(a) != std::floor(b); };
  const Color a(0.9, 0.2, 0.1), b(0.1, 0.3, 0.9);
  const double contrast = (a - b).cwiseAbs().maxCoeff();
  double worst = 0;
  long edgePixels = 0;
  for (const RayRecord& r : frame)
  {
    EXPECT_EQ(r.raysPerPixel, 9);
    const double x0 = checks.x(r.i - 0.5), x1 = checks.x(r.i + 0.5);
    const double z0 = checks.z(r.j - 0.5), z1 = checks.z(r.j + 0.5);
    if (crosses(x0, x1) == crosses(z0, z1))
      continue; // no edge, or a corner of four checks
    ++edgePixels;
    const Color exact =
      0.5 * (a + b) + 0.5 * (a - b) * squareWaveMean(x0, x1) * squareWaveMean(z0, z1);
    worst = std::max(worst, (r.color - exact).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(edgePixels, W * H / 4);
  EXPECT_LE(worst, contrast / 18.0 + 1e-6);
  EXPECT_GT(worst, contrast / 30.0) << "the edges should fall between the samples somewhere";
}

TEST(Antialiasing, AdaptiveSamplingConvergesToTheFixedSupersampleAsItsCapGrows)
{
  const int W = 24, H = 24;
  SceneDescription d = checkerWall(1.0, W, H);
  d.camera.position = Vec3(0, -60, 0);
  d.camera.viewAngle = 30;
  // The samples' own tolerance for the whole frame: the supersample's samples (traced as the
  // centre rays are) and the adaptive pattern's are then the same rays.
  d.integrator.relativeTolerance = kSampleRelativeTolerance;
  d.integrator.absoluteTolerance = 1e-2 * kSampleRelativeTolerance;
  const std::vector<RayRecord> reference = traceFrame(d, options(AntialiasMode::Filter, 1, 8));
  for (const RayRecord& r : reference)
    ASSERT_EQ(r.raysPerPixel, 65); // 64 samples and the centre ray
  double previous = rmsDifference(traceFrame(d, options(AntialiasMode::None)), reference);
  const double none = previous;
  double last = 0;
  for (int cap : { 5, 10, 17, 37, 65 })
  {
    const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::Adaptive, cap));
    const double e = rmsDifference(frame, reference);
    EXPECT_LT(e, previous) << "cap " << cap;
    previous = e;
    last = e;
    long sampled = 0;
    for (std::size_t k = 0; k < frame.size(); ++k)
    {
      // A pixel takes its centre ray or its n × n grid, or, settled by its corner cells, those
      // 4 rays and its centre ray; and up to two of the rays through the midpoints between its
      // centre and a disagreeing neighbour's (its right and upper ones).
      const int n = adaptivePatternSide(cap);
      const int rays = frame[k].raysPerPixel;
      if (rays <= 3)
        continue;
      ++sampled;
      const bool settled = n >= 3 && rays <= 5 + 2;
      EXPECT_GE(rays, settled ? 5 : patternRays(n));
      EXPECT_LE(rays, patternRays(n) + 2);
      EXPECT_LE(rays, cap + 2);
      // At the reference's grid the pixels sampled in full are the reference's pixels.
      if (cap == 65 && !settled)
      {
        EXPECT_EQ((frame[k].color - reference[k].color).norm(), 0.0);
      }
    }
    EXPECT_GT(sampled, 0);
    EXPECT_LT(sampled, static_cast<long>(frame.size()) / 2)
      << "adaptive sampling samples everything";
  }
  EXPECT_LT(last, 0.25 * none);
}

TEST(Antialiasing, SamplesAtTheirToleranceLandWithinAFewHundredthsOfAPixel)
{
  // The rays an adaptive pattern adds are traced at kSampleRelativeTolerance. Where they land,
  // against rays traced at 1e-12, in pixels of the screen: the surface displacement mapped back
  // through the tight frame's Jacobian ∂(u, v)/∂(i, j). The view is Fig. 1's, strongly lensed:
  // the floor and the cylinders near the shadow, where an integration error grows fastest.
  const int W = 96, H = 64;
  SceneDescription d = fig1At(W, H);
  d.camera.viewAngle = 12; // the shadow and the photon ring fill the frame
  AntialiasOptions one = options(AntialiasMode::None);
  SceneDescription tight = d, loose = d;
  tight.integrator.relativeTolerance = 1e-12;
  tight.integrator.absoluteTolerance = 1e-14;
  loose.integrator.relativeTolerance = kSampleRelativeTolerance;
  loose.integrator.absoluteTolerance = 1e-2 * kSampleRelativeTolerance;
  const std::vector<RayRecord> exact = traceFrame(tight, one), sampled = traceFrame(loose, one);
  ASSERT_EQ(exact.size(), sampled.size());
  std::vector<double> shift;
  for (std::size_t k = 0; k < exact.size(); ++k)
  {
    const RayRecord &a = exact[k], &b = sampled[k];
    if (a.objectId < 0 || a.objectId != b.objectId || a.imageOrder != b.imageOrder ||
        !std::isfinite(a.dudi + a.dudj + a.dvdi + a.dvdj))
      continue;
    Eigen::Matrix2d jacobian;
    jacobian << a.dudi, a.dudj, a.dvdi, a.dvdj;
    const Eigen::Vector2d du(std::remainder(b.u - a.u, 1.0), b.v - a.v);
    shift.push_back((jacobian.inverse() * du).norm());
  }
  ASSERT_GT(shift.size(), exact.size() / 8);
  std::sort(shift.begin(), shift.end());
  // Most within a thousandth of a pixel; the farthest in the secondary images, whose map nearly
  // folds (∂(u, v)/∂(i, j) almost singular), within a few hundredths.
  EXPECT_LT(shift[shift.size() * 99 / 100], 2e-3);
  EXPECT_LT(shift.back(), 0.05);
}

TEST(Antialiasing, EachTargetIsJudgedByAConvergedPictureWellBelowItsError)
{
  // convergedSideFor picks, for a quality target, the converged picture that judges it: one whose
  // own error lies at least 6 dB below the target's at 200 × 200. Here the truth is the picture
  // at 16 × 16 samples a pixel, traced by the test, of Fig. 1 (strongly lensed, its edges where
  // the error lies) at 96 × 96: about twice the share of edge pixels, so the margin held is half,
  // 3 dB.
  EXPECT_EQ(convergedSideFor(35.0), kConvergedSide); // the default target keeps its picture
  EXPECT_GT(convergedSideFor(40.0), convergedSideFor(35.0));
  EXPECT_GE(convergedSideFor(60.0), convergedSideFor(40.0));
  EXPECT_LE(convergedSideFor(100.0), 32); // the most a rendering may take
  const int N = 96;
  SceneDescription d = fig1At(N, N);
  const std::vector<RayRecord> truth = traceFrame(d, convergedRendering(16));
  auto psnrOf = [&](int side)
  { return -20.0 * std::log10(rmsDifference(traceFrame(d, convergedRendering(side)), truth)); };
  const double coarse = psnrOf(convergedSideFor(35.0)), fine = psnrOf(convergedSideFor(40.0));
  EXPECT_GE(coarse, 35.0 + 3.0);
  EXPECT_GE(fine, 40.0 + 3.0);
  // And the coarser picture could not judge the higher target: its own error is too near it.
  EXPECT_LT(coarse, 40.0 + 3.0);
}

TEST(Antialiasing, BendingFootprintsOverOneColourAreSettledByTheirCornerCells)
{
  // A long floor of one colour seen from just above it, past a hole: towards its far edge the
  // perspective bends its map within a pixel, which samples the pixel, but the bend cannot show
  // in one colour. Every such pixel inside an image of the floor is settled, by the local
  // quadratic map and two of the pattern's corners or by its 4 corner cells and its centre, to
  // the floor's colour.
  const int W = 40, H = 40;
  SceneDescription d = checkerWall(1.0, W, H);
  const Color wall(0.7, 0.4, 0.2);
  d.camera = looking(Vec3(0, -30, 1), Vec3(0, 0, 0.5), Vec3(0, 0, 1), 40, W, H);
  d.scene = std::make_shared<Scene>();
  d.scene->add(std::make_unique<Rectangle>(1, "floor", std::make_shared<SolidTexture>(wall),
                                           Vec3(0, 60, -1), Vec3(1, 0, 0), Vec3(0, 1, 0), 100.0,
                                           150.0));
  d.scene->add(std::make_unique<CelestialSphere>(
    0, "sky", std::make_shared<CheckerTexture>(24, 12, Color(1, 1, 1), Color(0, 0, 0)), 200.0));
  const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::Adaptive, 9));
  // Inside one image of the wall: the pixel and its 8 neighbours hit it in the same image order.
  auto onImage = [&](int i, int j, int order)
  {
    if (i < 0 || i >= W || j < 0 || j >= H)
      return false;
    const RayRecord& r = frame[std::size_t(j * W + i)];
    return r.objectId == 1 && r.imageOrder == order;
  };
  long settled = 0, interior = 0;
  for (const RayRecord& r : frame)
  {
    bool inside = true;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di)
        inside = inside && onImage(r.i + di, r.j + dj, r.imageOrder);
    if (!inside)
      continue;
    ++interior;
    EXPECT_LT(r.raysPerPixel, 8) << "pixel " << r.i << ", " << r.j << " took its whole pattern";
    if (r.raysPerPixel >= 3) // its centre and two corners at least
    {
      ++settled;
      EXPECT_LT((r.color - wall).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
  EXPECT_GT(interior, W * H / 20);
  EXPECT_GT(settled, 0) << "no footprint bends: the test sees nothing";
}

TEST(Antialiasing, SettledPixelsStayWithinTheirSpreadOfTheSupersample)
{
  // The lensed checker wall: where a bending footprint's corner cells agree, the pixel's colour
  // is their mean, and where its local quadratic map predicts a corner, the map places the other
  // samples; against the 8 × 8 supersample the test traces, those pixels are off by no more than
  // the spread that settled them, in the mean square.
  const int W = 32, H = 32;
  SceneDescription d = checkerWall(1.0, W, H);
  const std::vector<RayRecord> reference = traceFrame(d, options(AntialiasMode::Filter, 1, 8));
  const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::Adaptive, 9));
  double sum = 0;
  long settled = 0, byMap = 0;
  for (std::size_t k = 0; k < frame.size(); ++k)
  {
    // Sampled pixels that took fewer rays than the pattern's 9: the map's (the centre and two
    // corners, and no midpoint ray: its edge neighbours end as it does) or the corners' (5, and
    // up to two midpoint rays).
    const RayRecord& r = frame[k];
    bool inside = r.i > 0 && r.i + 1 < W && r.j > 0 && r.j + 1 < H;
    for (const auto& [di, dj] :
         { std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1) })
      inside = inside && frame[k + di + dj * W].objectId == r.objectId &&
               frame[k + di + dj * W].imageOrder == r.imageOrder;
    const bool mapped = inside && r.raysPerPixel == 3;
    if (mapped || (r.raysPerPixel >= 5 && r.raysPerPixel <= 7))
    {
      ++settled;
      byMap += mapped;
      sum += (r.color - reference[k].color).squaredNorm() / 3.0;
    }
  }
  ASSERT_GT(settled, 0) << "no pixel was settled: the test sees nothing";
  EXPECT_GT(byMap, 0) << "no pixel was settled by its quadratic map";
  EXPECT_LE(std::sqrt(sum / settled), kSettledColorSpread);
}

TEST(Antialiasing, QuadraticMapsPlaceTheSamplesOfABendingFootprint)
{
  // A floor seen from just above it, past a hole, its texture a ramp in u and v (red and green):
  // a sample's filtered colour tells where it landed. Where a bending footprint was settled by
  // its local quadratic map (its centre, two corners and no midpoint ray), the pixel's colour
  // against the 8 × 8 supersample the test traces is as good as that of the pixels whose 9
  // samples were traced.
  const int W = 64, H = 64, T = 256;
  SceneDescription d = checkerWall(1.0, W, H);
  std::vector<std::uint8_t> ramp(3 * T * T);
  for (int y = 0; y < T; ++y)
    for (int x = 0; x < T; ++x)
    {
      ramp[3 * (y * T + x)] = static_cast<std::uint8_t>(x);
      ramp[3 * (y * T + x) + 1] = static_cast<std::uint8_t>(y);
      ramp[3 * (y * T + x) + 2] = 128;
    }
  d.camera = looking(Vec3(0, -30, 1), Vec3(0, 0, 0.5), Vec3(0, 0, 1), 40, W, H);
  d.scene = std::make_shared<Scene>();
  d.scene->add(std::make_unique<Rectangle>(1, "floor", std::make_shared<ImageTexture>(T, T, ramp),
                                           Vec3(0, 60, -1), Vec3(1, 0, 0), Vec3(0, 1, 0), 100.0,
                                           150.0));
  d.scene->add(std::make_unique<CelestialSphere>(
    0, "sky", std::make_shared<SolidTexture>(Color(0, 0, 0)), 200.0));
  const std::vector<RayRecord> reference = traceFrame(d, options(AntialiasMode::Filter, 1, 8));
  const std::vector<RayRecord> frame = traceFrame(d, options(AntialiasMode::Adaptive, 9));
  double mapped = 0, full = 0;
  long nMapped = 0, nFull = 0;
  for (std::size_t k = 0; k < frame.size(); ++k)
  {
    const RayRecord& r = frame[k];
    bool inside = r.objectId == 1 && r.i > 0 && r.i + 1 < W && r.j > 0 && r.j + 1 < H &&
                  r.u > 0.05 && r.u < 0.95 && r.v > 0.05 && r.v < 0.95;
    for (const auto& [di, dj] :
         { std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1) })
      inside = inside && frame[k + di + dj * W].objectId == r.objectId &&
               frame[k + di + dj * W].imageOrder == r.imageOrder;
    if (!inside)
      continue;
    const double e = (r.color - reference[k].color).squaredNorm() / 3.0;
    if (r.raysPerPixel == 3)
    {
      mapped += e;
      ++nMapped;
    }
    else if (r.raysPerPixel == 9)
    {
      full += e;
      ++nFull;
    }
  }
  // The ramp is linear in (u, v), so a pixel's error is where its samples were placed: the traced
  // ones land within a few tenths of a level of the supersample, the mapped ones far closer (a
  // map without its cross term misplaces them by a quarter of a level).
  ASSERT_GT(nMapped, 5) << "no bending footprint was settled by its quadratic map";
  ASSERT_GT(nFull, 5);
  EXPECT_LE(std::sqrt(mapped / nMapped), 0.05 / 255);
  EXPECT_LE(std::sqrt(mapped / nMapped), std::sqrt(full / nFull));
}

TEST(Antialiasing, FramesAreTheSameAtAnyThreadCountAndInAnySplit)
{
  const int W = 20, H = 17;
  SceneDescription d = checkerWall(1.0, W, H);
  d.rendering = options(AntialiasMode::Adaptive, 9);
  FrameTracer tracer(d);
  const int threads = omp_get_max_threads();
  std::vector<std::vector<RayRecord>> frames;
  for (int n : { 1, 2, 3 })
  {
    omp_set_num_threads(n);
    frames.push_back(tracer.traceRows(0, H));
  }
  omp_set_num_threads(threads);
  // Pieces: two calls of traceRows, row bands of 3 rows, and tracePixels of the whole frame.
  std::vector<RayRecord> pieces = tracer.traceRows(0, 7), upper = tracer.traceRows(7, H);
  pieces.insert(pieces.end(), upper.begin(), upper.end());
  frames.push_back(pieces);
  std::vector<RayRecord> banded;
  ASSERT_TRUE(traceRowsInBands(
    tracer, 0, H, [&](const RayRecord* r, std::size_t n) { banded.insert(banded.end(), r, r + n); },
    nullptr, 3 * W));
  frames.push_back(banded);
  std::vector<std::pair<int, int>> all;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
      all.emplace_back(i, j);
  frames.push_back(tracer.tracePixels(all));
  long sampled = 0;
  for (const RayRecord& r : frames[0])
    sampled += r.raysPerPixel > 1;
  EXPECT_GT(sampled, 0);
  for (std::size_t f = 1; f < frames.size(); ++f)
  {
    ASSERT_EQ(frames[f].size(), frames[0].size()) << "frame " << f;
    for (std::size_t k = 0; k < frames[0].size(); ++k)
    {
      const RayRecord &a = frames[0][k], &b = frames[f][k];
      ASSERT_EQ(a.i, b.i);
      ASSERT_EQ(a.j, b.j);
      EXPECT_EQ(a.raysPerPixel, b.raysPerPixel) << "frame " << f << " pixel " << a.i << ", " << a.j;
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(a.color[c], b.color[c]) << "frame " << f << " pixel " << a.i << ", " << a.j;
    }
  }
}

TEST(Antialiasing, AFrameAntialiasedAgainAtALowerEvenCapIsThatCapsFrameBitForBit)
{
  // Fig. 1 on the adaptive grid (the default lattice): its cylinders' edges are sampled, and most
  // centre rays interpolated. Traced at the default cap of 9 rays and anti-aliased again at 5 (a
  // 2 × 2 pattern), the frame is the one traced at 5, every record, for the rays of its sampled
  // pixels and edge midpoints alone.
  const int W = 128, H = 96;
  SceneDescription d = fig1At(W, H);
  SceneDescription lower = d;
  lower.rendering.maxRaysPerPixel = 5;
  const FrameTracer traced(d), direct(lower);
  const std::vector<RayRecord> before = traced.traceRows(0, H);
  const std::vector<RayRecord> truth = direct.traceRows(0, H);
  std::vector<RayRecord> again = before;
  long sampled = 0, interpolated = 0, extraRays = 0;
  for (const RayRecord& r : truth)
  {
    sampled += r.raysPerPixel > 2; // more than the centre ray and the midpoints charged to it
    interpolated += !r.traced;
    extraRays += r.raysPerPixel - (r.traced ? 1 : 0);
  }
  EXPECT_GT(sampled, 50);
  EXPECT_GT(interpolated, W * H / 4);
  const FrameTracer antialiasing(lower);
  ASSERT_TRUE(antialiasing.antialiasAgain(again, d.rendering));
  // The sampled pixels' rays and the edge midpoints, and no centre ray.
  EXPECT_EQ(antialiasing.raysIntegrated(), extraRays);
  EXPECT_LT(antialiasing.raysIntegrated(), direct.raysIntegrated() / 2);
  ASSERT_EQ(again.size(), truth.size());
  long changed = 0;
  auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (std::size_t k = 0; k < truth.size(); ++k)
  {
    const RayRecord &a = truth[k], &b = again[k];
    ASSERT_EQ(a.i, b.i);
    ASSERT_EQ(a.j, b.j);
    EXPECT_EQ(a.raysPerPixel, b.raysPerPixel) << "pixel " << a.i << ", " << a.j;
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(a.color[c], b.color[c]) << "pixel " << a.i << ", " << a.j;
    EXPECT_TRUE(same(a.u, b.u) && same(a.dudi, b.dudi) && same(a.dvdj, b.dvdj));
    changed += before[k].color != b.color;
  }
  EXPECT_GT(changed, sampled / 2); // the two caps do give other colours where they sample

  // Scattered pixels alone, judged against their neighbours in the frame: the same records.
  std::vector<std::int32_t> some;
  for (std::int32_t p = 5; p < W * H; p += 7)
    some.push_back(p);
  const std::vector<RayRecord> piece = FrameTracer(lower).antialiasAgain(before, d.rendering, some);
  ASSERT_EQ(piece.size(), some.size());
  std::vector<std::pair<int, int>> someIJ;
  for (std::int32_t p : some)
    someIJ.emplace_back(p % W, p / W);
  EXPECT_FALSE(edgeNeighbourSamples(before, W, H, someIJ).empty());
  for (std::size_t q = 0; q < some.size(); ++q)
  {
    const RayRecord &a = truth[static_cast<std::size_t>(some[q])], &b = piece[q];
    ASSERT_EQ(a.i, b.i);
    ASSERT_EQ(a.j, b.j);
    EXPECT_EQ(a.raysPerPixel, b.raysPerPixel) << "pixel " << a.i << ", " << a.j;
    EXPECT_EQ(a.color, b.color) << "pixel " << a.i << ", " << a.j;
  }

  // Renderings it cannot derive are refused by name.
  auto refusal = [&](const AntialiasOptions& to, const AntialiasOptions& from)
  {
    SceneDescription t = d;
    t.rendering = to;
    std::vector<RayRecord> frame = truth;
    try
    {
      FrameTracer(t).antialiasAgain(frame, from);
    }
    catch (const InvalidParameter& e)
    {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  AntialiasOptions other = lower.rendering, single = d.rendering;
  other.gridLattice = 1;
  EXPECT_NE(refusal(other, d.rendering).find("more than maxRaysPerPixel"), std::string::npos);
  EXPECT_NE(refusal(d.rendering, lower.rendering).find("not an even side"), std::string::npos);
  single.maxRaysPerPixel = 1;
  EXPECT_NE(refusal(lower.rendering, single).find("samples no pixel"), std::string::npos);
  EXPECT_THROW(FrameTracer(lower).antialiasAgain(before, d.rendering, { 3, 3 }), InvalidParameter);
  EXPECT_THROW(FrameTracer(lower).antialiasAgain(before, d.rendering, { W * H }), InvalidParameter);
}

TEST(Antialiasing, ARenderingSampledOnTheConvergedPatternIsMeasuredAgainstAnother)
{
  // At 17 rays a pixel adaptive sampling takes a 4 x 4 pattern, the converged rendering's own:
  // its sampled pixels are the reference's samples, and their error against it all but vanishes,
  // though against 16 x 16 samples (the truth, traced here) it does not. Against 8 x 8, the
  // reference settingsReferenceSide gives it, the error is seen.
  const int W = 64, H = 48;
  SceneDescription d = fig1At(W, H);
  AntialiasOptions cap17 = d.rendering;
  cap17.maxRaysPerPixel = 17;
  EXPECT_EQ(settingsReferenceSide(cap17), 2 * kConvergedSide);
  EXPECT_EQ(settingsReferenceSide(d.rendering), kConvergedSide); // 3 x 3
  AntialiasOptions cap5 = d.rendering;
  cap5.maxRaysPerPixel = 5;
  EXPECT_EQ(settingsReferenceSide(cap5), kConvergedSide); // 2 x 2
  const std::vector<RayRecord> frame = traceFrame(d, cap17);
  const std::vector<RayRecord> four = traceFrame(d, convergedRendering(kConvergedSide));
  const std::vector<RayRecord> eight =
    traceFrame(d, convergedRendering(settingsReferenceSide(cap17)));
  const std::vector<RayRecord> truth = traceFrame(d, convergedRendering(16));
  double against4 = 0, against8 = 0, againstTruth = 0;
  long sampled = 0;
  for (std::size_t k = 0; k < frame.size(); ++k)
  {
    if (frame[k].raysPerPixel < 16)
      continue;
    ++sampled;
    against4 += (frame[k].color - four[k].color).squaredNorm();
    against8 += (frame[k].color - eight[k].color).squaredNorm();
    againstTruth += (frame[k].color - truth[k].color).squaredNorm();
  }
  ASSERT_GT(sampled, 50);
  EXPECT_LT(against4, 0.25 * againstTruth);
  EXPECT_GT(against8, 0.5 * againstTruth);
}

TEST(Antialiasing, BadRenderingOptionsAreRefusedNamingTheField)
{
  const std::string head =
    R"({"spacetime": {"mass": 1}, "camera": {"position": [0, -30, 0], "focalPoint": [0, 0, 0], "resolution": [%R%]},
        "objects": [], "rendering": {)";
  auto parse = [&](const std::string& rendering, const std::string& resolution = "20, 20")
  {
    std::string text = head + rendering + "}}";
    text.replace(text.find("%R%"), 3, resolution);
    parseScene(text, ".", nullptr);
  };
  auto refused = [&](const std::string& rendering, const std::string& field,
                     const std::string& resolution = "20, 20")
  {
    try
    {
      parse(rendering, resolution);
      ADD_FAILURE() << rendering << " was accepted";
    }
    catch (const InvalidParameter& e)
    {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(parse(R"("antialias": "adaptive", "maxRaysPerPixel": 1024, "supersample": 32)"));
  refused(R"("maxRaysPerPixel": 0)", "rendering.maxRaysPerPixel");
  refused(R"("maxRaysPerPixel": 1025)", "rendering.maxRaysPerPixel");
  refused(R"("antialias": "supersample")", "rendering.antialias");
  refused(R"("antialias": 3)", "rendering.antialias");
  refused(R"("supersample": 0)", "rendering.supersample");
  refused(R"("supersample": 33)", "rendering.supersample");
  refused(R"("colorThreshold": -0.1)", "rendering.colorThreshold");
  refused(R"("colorThreshold": 2)", "rendering.colorThreshold");
  refused(R"("gridLattice": 0)", "rendering.gridLattice");
  refused(R"("gridLattice": 257)", "rendering.gridLattice");
  refused(R"("gridLattice": 2.5)", "rendering.gridLattice");
  refused(R"("gridTolerance": -1e-3)", "rendering.gridTolerance");
  EXPECT_NO_THROW(parse(R"("gridLattice": 256, "gridTolerance": 0)"));
  refused(R"("preset": "fastest")", "rendering.preset");
  refused(R"("supersamples": 2)", "rendering.supersamples");
  // 2²⁸ pixels are a frame's most; supersampled 2 × 2 they are four times the rays a frame may
  // take.
  refused(R"("supersample": 2)", "rendering.supersample", "16384, 16384");
  // A description changed after parsing is refused by the same rule.
  SceneDescription d = checkerWall(1.0, 10, 10);
  d.rendering.maxRaysPerPixel = 0;
  EXPECT_THROW(validateScene(d), InvalidParameter);
  d.rendering.maxRaysPerPixel = 9;
  d.rendering.gridLattice = 0;
  EXPECT_THROW(validateScene(d), InvalidParameter);
  d.rendering.gridLattice = 8;
  d.rendering.gridTolerance = -1.0;
  EXPECT_THROW(validateScene(d), InvalidParameter);
}
