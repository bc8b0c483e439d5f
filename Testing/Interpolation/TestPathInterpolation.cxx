// Per-pixel interpolation along a movie path (PathInterpolation.h) against independent truth:
// polynomials the Lagrange weights must reproduce, synthetic records that are known cubics of s,
// and frames the test traces itself at the interpolated parameter.
#include "FrameTracer.h"
#include "GeodesicMovie.h"
#include "ImageQuality.h"
#include "KdTreeIndex.h"
#include "PathInterpolation.h"
#include "RampScene.h"
#include "SceneFile.h"
#include "Spacetime.h"
#include "TextureFiles.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::rampScene;

namespace
{
/// The options the filters interpolate with: moved edges, matched over the k-d tree.
PathOptions withMovedEdges()
{
  PathOptions options;
  options.pointIndex = kdTreeIndexFactory();
  return options;
}

std::string errorOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return "";
}

double polynomial(const std::vector<double>& c, double x)
{
  double y = 0;
  for (auto it = c.rbegin(); it != c.rend(); ++it)
    y = y * x + *it;
  return y;
}

/// A record of pixel (0, 0) on object 1 whose fields are the given polynomials of s.
RayRecord syntheticRecord(double s, const std::vector<double>& u, const std::vector<double>& v)
{
  RayRecord r;
  r.termination = Termination::HitObject;
  r.objectId = 1;
  const double uu = polynomial(u, s);
  r.u = uu - std::floor(uu);
  r.v = polynomial(v, s);
  r.winding = 1.0 + 0.1 * s;
  r.affineLength = polynomial(u, s) + 40.0;
  r.dudi = polynomial(v, s);
  r.dudj = r.dvdi = 0.0;
  r.dvdj = polynomial(u, s);
  r.hitPoint = Vec3(polynomial(u, s), polynomial(v, s), 2.0);
  return r;
}

/// A scene file of Data/scenes at `side` × `side`, its camera turned about the hole's axis by
/// `degrees` (as asrt movie --orbit turns it).
SceneDescription orbitScene(const SceneDescription& start, int side, double degrees)
{
  SceneDescription d = start;
  d.camera.width = d.camera.height = side;
  const CameraPose pose =
    turnedAboutZ({ d.camera.position, d.camera.focalPoint, d.camera.viewUp }, degrees);
  d.camera.position = pose.position;
  d.camera.focalPoint = pose.focalPoint;
  d.camera.viewUp = pose.viewUp;
  return d;
}

SceneDescription sceneFile(const std::string& name)
{
  return loadSceneFile(std::string(ASRT_SOURCE_DIR) + "/Data/scenes/" + name,
                       [](const std::string& p) { return readPngTexture(p, TextureLimits{}); });
}

std::vector<RayRecord> traceFrame(const SceneDescription& d)
{
  return FrameTracer(d).traceRows(0, d.camera.height);
}

/// Key frames along a path, traced: their parameters and records.
struct TracedKeys
{
  std::vector<double> s;
  std::vector<std::vector<RayRecord>> records;
  std::vector<PathKey> path() const
  {
    std::vector<PathKey> keys;
    for (std::size_t k = 0; k < s.size(); ++k)
      keys.push_back({ s[k], &records[k] });
    return keys;
  }
};

TracedKeys orbitKeys(const SceneDescription& start, int side, std::vector<double> degrees)
{
  TracedKeys keys;
  keys.s = std::move(degrees);
  for (double d : keys.s)
    keys.records.push_back(traceFrame(orbitScene(start, side, d)));
  return keys;
}

/// Four key frames of the mass ramp, `spacing` apart from `first`, traced.
TracedKeys rampKeys(int side, double first, double spacing)
{
  TracedKeys keys;
  for (int k = 0; k < 4; ++k)
  {
    keys.s.push_back(first + spacing * k);
    keys.records.push_back(traceFrame(rampScene(keys.s.back(), side)));
  }
  return keys;
}

/// The mass ramp's frame at t traced (the truth a frame interpolated there is held to), and the
/// frame interpolated there from `keys` with `options`.
struct RampFrameAt
{
  double t;
  int side;
  SceneDescription scene;
  std::vector<RayRecord> truth;
  RampFrameAt(double t, int side)
    : t(t)
    , side(side)
    , scene(rampScene(t, side))
    , truth(traceFrame(scene))
  {
  }
  PathFrame interpolated(const TracedKeys& keys, const PathOptions& options) const
  {
    return interpolateAlongPath(keys.path(), t, side, side, *scene.scene, options);
  }
};

/// Squared colour error summed over the channels, levels² of 255.
double error2(const RayRecord& a, const RayRecord& b)
{
  return (255.0 * (a.color - b.color)).squaredNorm();
}

double psnrOf(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  double sum = 0;
  for (std::size_t p = 0; p < a.size(); ++p)
    sum += error2(a[p], b[p]);
  const double mse = sum / (3.0 * a.size());
  return mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
}

/// Whether a pixel was predicted by moving the keys' scene points (PathEdges.h).
bool movedByPoints(std::uint8_t m)
{
  return m == static_cast<std::uint8_t>(PathMethod::MovedEdge) ||
         m == static_cast<std::uint8_t>(PathMethod::MovedSurface);
}
}

TEST(PathInterpolation, LagrangeWeightsReproducePolynomialsOfTheirDegree)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coefficient(-3.0, 3.0);
  for (int n = 1; n <= 4; ++n)
    for (int trial = 0; trial < 50; ++trial)
    {
      double s[4] = { -0.7, 0.05, 0.3, 1.9 };
      std::vector<double> c(static_cast<std::size_t>(n));
      for (double& x : c)
        x = coefficient(rng);
      const double t = -0.5 + 2.0 * trial / 50.0;
      double w[4];
      lagrangeWeights(s, n, t, w);
      double sum = 0, weights = 0;
      for (int k = 0; k < n; ++k)
      {
        sum += w[k] * polynomial(c, s[k]);
        weights += w[k];
      }
      EXPECT_NEAR(sum, polynomial(c, t), 1e-12 * (1.0 + std::abs(polynomial(c, t))));
      EXPECT_NEAR(weights, 1.0, 1e-13);
    }
}

// (u, v) are cubics of s, and u crosses the seam between the nodes: 4 nodes give them exactly, and
// the quadratic one order lower misses by exactly what the cubic's estimate measures.
TEST(PathInterpolation, FourNodesAreExactForCubicsAndTheLowerOrderMissesByItsOwnError)
{
  const std::vector<double> u = { 0.93, 0.2, -0.05, 0.03 }, v = { 0.2, 0.3, 0.1, -0.08 };
  const double s[4] = { 0.0, 0.4, 0.9, 1.3 };
  RayRecord keys[4];
  const RayRecord* nodes[4];
  for (int k = 0; k < 4; ++k)
  {
    keys[k] = syntheticRecord(s[k], u, v);
    nodes[k] = &keys[k];
  }
  for (double t : { 0.45, 0.6, 0.85 })
  {
    const RayRecord cubic = predictRecord(nodes, s, 4, t);
    const double exactU = polynomial(u, t) - std::floor(polynomial(u, t));
    EXPECT_NEAR(cubic.u, exactU, 1e-12) << t;
    EXPECT_NEAR(cubic.v, polynomial(v, t), 1e-12) << t;
    EXPECT_NEAR(cubic.dvdj, polynomial(u, t), 1e-12) << t;
    EXPECT_NEAR(cubic.hitPoint.x(), polynomial(u, t), 1e-12) << t;
    // The quadratic through three of the nodes misses by the cubic term's share, which is exactly
    // the difference of the two predictions: the estimate's measure.
    const RayRecord quadratic = predictRecord(nodes, s, 3, t);
    double w[3];
    lagrangeWeights(s, 3, t, w);
    double quadraticV = 0;
    for (int k = 0; k < 3; ++k)
      quadraticV += w[k] * polynomial(v, s[k]);
    EXPECT_NEAR(quadratic.v, quadraticV, 1e-12);
    EXPECT_NEAR(cubic.v - quadratic.v, polynomial(v, t) - quadraticV, 1e-12);
    EXPECT_GT(std::abs(cubic.v - quadratic.v), 1e-4) << "the cubic term must show at " << t;
  }
  // A quadratic path: the two orders agree, so the estimate is zero.
  const std::vector<double> q = { 0.1, 0.5, -0.2 };
  for (int k = 0; k < 4; ++k)
    keys[k] = syntheticRecord(s[k], q, q);
  const RayRecord a = predictRecord(nodes, s, 4, 0.7), b = predictRecord(nodes, s, 3, 0.7);
  EXPECT_NEAR(a.v, b.v, 1e-13);
  EXPECT_NEAR(a.v, polynomial(q, 0.7), 1e-13);
}

TEST(PathInterpolation, RecordsEndAlikeOnlyOnTheSameObjectTerminationAndImage)
{
  RayRecord a;
  a.termination = Termination::HitObject;
  a.objectId = 2;
  a.winding = 3.0;
  RayRecord b = a;
  EXPECT_TRUE(endAlike(a, b));
  b.winding = 3.0 + 0.9 * kWindingJump;
  EXPECT_TRUE(endAlike(a, b));
  b.winding = 3.0 + kWindingJump;
  EXPECT_FALSE(endAlike(a, b)) << "a jump of the winding is another image";
  b = a;
  b.objectId = 3;
  EXPECT_FALSE(endAlike(a, b));
  b = a;
  b.termination = Termination::Escaped;
  EXPECT_FALSE(endAlike(a, b));
  a.termination = b.termination = Termination::StepBudget;
  a.objectId = b.objectId = -1;
  EXPECT_FALSE(endAlike(a, b)) << "a ray that did not end cleanly vouches for nothing";
}

TEST(PathInterpolation, BadKeysAndTargetsAreRefusedByName)
{
  const SceneDescription d = rampScene(0.5, 4);
  std::vector<RayRecord> r(16);
  for (int p = 0; p < 16; ++p)
  {
    r[p].i = p % 4;
    r[p].j = p / 4;
  }
  const Scene& scene = *d.scene;
  EXPECT_NE(errorOf(
              [&] {
                interpolateAlongPath({ { 0.0, &r } }, 0.0, 4, 4, scene, withMovedEdges());
              })
              .find("at least 2 key frames"),
            std::string::npos);
  EXPECT_NE(
    errorOf(
      [&] {
        interpolateAlongPath({ { 0.5, &r }, { 0.5, &r } }, 0.5, 4, 4, scene, withMovedEdges());
      })
      .find("strictly increasing"),
    std::string::npos);
  EXPECT_NE(
    errorOf(
      [&] {
        interpolateAlongPath({ { 0.0, &r }, { 1.0, &r } }, 1.5, 4, 4, scene, withMovedEdges());
      })
      .find("outside the keys' range"),
    std::string::npos);
  EXPECT_NE(
    errorOf(
      [&] {
        interpolateAlongPath({ { 0.0, &r }, { 1.0, &r } }, 0.5, 5, 4, scene, withMovedEdges());
      })
      .find("has 16 records"),
    std::string::npos);
  EXPECT_NE(errorOf(
              [&] {
                interpolateAlongPath({ { 0.0, &r }, { 1.0, &r } }, 0.5, 4, 4, scene, PathOptions{});
              })
              .find("PathOptions::pointIndex"),
            std::string::npos);
  for (double bad : { -0.1, 1.5, std::nan("") })
  {
    PathOptions o = withMovedEdges();
    o.keyResidualShare = bad;
    EXPECT_NE(errorOf(
                [&] {
                  interpolateAlongPath({ { 0.0, &r }, { 1.0, &r } }, 0.5, 4, 4, scene, o);
                })
                .find("PathOptions::keyResidualShare"),
              std::string::npos)
      << bad;
  }
  PathFrame f =
    interpolateAlongPath({ { 0.0, &r }, { 1.0, &r } }, 0.5, 4, 4, scene, withMovedEdges());
  const FrameTracer tracer(d);
  for (double bad : { 0.0, -3.0, std::nan(""), 100.5 })
    EXPECT_NE(errorOf([&] { completePathFrame(f, tracer, bad); }).find("quality target"),
              std::string::npos)
      << bad;
}

// The mass ramp of Figs. 4–5, four key frames h = 0.1 apart, the frame between the middle two
// against the frame the test traces there itself.
class PathInterpolationRamp : public ::testing::Test
{
protected:
  static constexpr int Side = 96;
  static void SetUpTestSuite()
  {
    for (int k = 0; k < 4; ++k)
      keys().push_back(traceFrame(rampScene(0.65 + 0.05 * k, Side)));
    truth() = traceFrame(rampScene(T, Side));
  }
  static std::vector<std::vector<RayRecord>>& keys()
  {
    static std::vector<std::vector<RayRecord>> k;
    return k;
  }
  static std::vector<RayRecord>& truth()
  {
    static std::vector<RayRecord> t;
    return t;
  }
  static PathFrame interpolated()
  {
    std::vector<PathKey> path;
    for (int k = 0; k < 4; ++k)
      path.push_back({ 0.65 + 0.05 * k, &keys()[static_cast<std::size_t>(k)] });
    return interpolateAlongPath(path, T, Side, Side, *rampScene(T, Side).scene, withMovedEdges());
  }
  static constexpr double T = 0.72;
};

TEST_F(PathInterpolationRamp, KeysAreReturnedAsTheyAre)
{
  std::vector<PathKey> path;
  for (int k = 0; k < 4; ++k)
    path.push_back({ 0.65 + 0.05 * k, &keys()[static_cast<std::size_t>(k)] });
  const PathFrame f = interpolateAlongPath(path, path[1].s, Side, Side,
                                           *rampScene(path[1].s, Side).scene, withMovedEdges());
  ASSERT_EQ(f.records.size(), keys()[1].size());
  for (std::size_t p = 0; p < f.records.size(); ++p)
    ASSERT_EQ(f.records[p].color, keys()[1][p].color) << p;
  EXPECT_EQ(f.counts()[static_cast<int>(PathMethod::Key)], f.records.size());
}

// Frames along the ramp with the moved edges' correspondences kept between them (PathMatchCache):
// the same frames, bit for bit, as matching afresh each time, and each pair of keys matched once:
// three frames between the middle keys match keys 0-1, 1-2 and 2-3, and the frames of the pairs
// either side need no other pair. A key whose records change is matched again.
TEST_F(PathInterpolationRamp, KeptCorrespondencesGiveTheSameFramesMatchingEachPairOnce)
{
  std::vector<PathKey> path;
  for (int k = 0; k < 4; ++k)
    path.push_back({ 0.65 + 0.05 * k, &keys()[static_cast<std::size_t>(k)] });
  PathOptions kept = withMovedEdges();
  kept.matchCache = std::make_shared<PathMatchCache>();
  const SceneDescription shading = rampScene(T, Side);
  const asrt::Scene& scene = *shading.scene;
  for (const double t : { 0.71, 0.72, 0.74, 0.78, 0.66 })
  {
    const PathFrame a = interpolateAlongPath(path, t, Side, Side, scene, kept);
    const PathFrame b = interpolateAlongPath(path, t, Side, Side, scene, withMovedEdges());
    ASSERT_EQ(a.method, b.method) << "t = " << t;
    ASSERT_EQ(a.estimate, b.estimate) << "t = " << t;
    for (std::size_t p = 0; p < a.records.size(); ++p)
      ASSERT_EQ(a.records[p].color, b.records[p].color) << "t = " << t << ", pixel " << p;
  }
  EXPECT_EQ(kept.matchCache->made(), 3u);
  // The keys' fingerprints given by the caller find the same kept pairs: nothing matched again.
  std::vector<PathKey> printed = path;
  for (PathKey& key : printed)
    key.fingerprint = matchingFingerprint(*key.records);
  const PathFrame given = interpolateAlongPath(printed, 0.73, Side, Side, scene, kept);
  EXPECT_EQ(kept.matchCache->made(), 3u);
  ASSERT_EQ(given.estimate, interpolateAlongPath(path, 0.73, Side, Side, scene, kept).estimate);
  // Another key 2 (one surface coordinate a little off): the pairs it is in are matched again.
  std::vector<RayRecord> changed = keys()[2];
  changed[changed.size() / 2].u = std::nextafter(changed[changed.size() / 2].u, 2.0);
  path[2].records = &changed;
  interpolateAlongPath(path, 0.72, Side, Side, scene, kept);
  EXPECT_EQ(kept.matchCache->made(), 5u);
}

// The colours alone (what the keys left out read) are the frame's colours bit for bit, with or
// without its estimates, between every pair of keys, at an end of the keys and on a key; and the
// frames compared hold every way of making a pixel that has a colour without moved edges.
TEST_F(PathInterpolationRamp, TheColoursAloneAreTheFramesColoursBitForBit)
{
  std::vector<PathKey> path;
  for (int k = 0; k < 4; ++k)
    path.push_back({ 0.65 + 0.05 * k, &keys()[static_cast<std::size_t>(k)] });
  const SceneDescription shading = rampScene(T, Side);
  std::array<std::size_t, kPathMethodCount> seen{};
  for (const double t : { 0.66, path[1].s, 0.72, 0.74, 0.79 })
  {
    const std::vector<Color> alone = interpolatedColours(path, t, Side, Side, *shading.scene);
    for (const bool estimates : { false, true })
    {
      PathOptions options;
      options.movedEdges = false;
      options.estimates = estimates;
      options.leaveOneOut = false;
      const PathFrame f = interpolateAlongPath(path, t, Side, Side, *shading.scene, options);
      ASSERT_EQ(alone.size(), f.records.size());
      for (std::size_t p = 0; p < alone.size(); ++p)
        ASSERT_EQ(alone[p], f.records[p].color) << "t = " << t << ", pixel " << p;
      for (std::size_t p = 0; p < f.method.size(); ++p)
        ++seen[f.method[p]];
    }
  }
  for (const PathMethod m : { PathMethod::Key, PathMethod::Cubic, PathMethod::Quadratic,
                              PathMethod::Linear, PathMethod::EdgeBlend, PathMethod::Retrace })
    EXPECT_GT(seen[static_cast<int>(m)], 0u) << toString(m);
  EXPECT_THROW(interpolatedColours(path, 0.6, Side, Side, *shading.scene), InvalidParameter);
}

TEST_F(PathInterpolationRamp, PredictedPixelsAreCloseAndTheEstimateFindsTheWorst)
{
  const PathFrame f = interpolated();
  const std::vector<std::size_t> c = f.counts();
  std::printf("[ path ] %d x %d at M = %.2f: cubic %zu, quadratic %zu, linear %zu, moved edge "
              "%zu, must re-trace %zu\n",
              Side, Side, T, c[1], c[2], c[3], c[7], c[4]);
  EXPECT_GT(c[static_cast<int>(PathMethod::Cubic)], f.records.size() / 2);
  // The pixels predicted from their own records (the moved edges, where the keys disagree, are
  // held to the truth in TestPathEdges).
  std::vector<std::size_t> predicted;
  double sum = 0;
  for (std::size_t p = 0; p < f.records.size(); ++p)
    if (f.method[p] != static_cast<std::uint8_t>(PathMethod::Retrace) &&
        f.method[p] != static_cast<std::uint8_t>(PathMethod::MovedEdge))
    {
      predicted.push_back(p);
      sum += error2(f.records[p], truth()[p]);
      // Off the pixels the keys cannot vouch for, no pixel changes object.
      EXPECT_EQ(f.records[p].objectId, truth()[p].objectId) << p;
    }
  const double mse = sum / (3.0 * predicted.size());
  const double psnr = 10.0 * std::log10(255.0 * 255.0 / mse);
  std::printf("[ path ] predicted pixels against the traced frame: %.1f dB\n", psnr);
  EXPECT_GT(psnr, 30.0);
  // The tenth of the predicted pixels the estimate ranks worst carries far more of the true error
  // than a tenth drawn at random would (which carries a tenth of it).
  std::vector<std::size_t> ranked = predicted;
  std::stable_sort(ranked.begin(), ranked.end(),
                   [&](std::size_t a, std::size_t b) { return f.estimate[a] > f.estimate[b]; });
  double worst = 0;
  for (std::size_t k = 0; k < ranked.size() / 10; ++k)
    worst += error2(f.records[ranked[k]], truth()[ranked[k]]);
  std::printf("[ path ] the estimate's worst tenth holds %.0f %% of the true error\n",
              100.0 * worst / sum);
  EXPECT_GT(worst, 0.4 * sum);
}

// In the first interval of the keys there is no key before the inner pair: the pixels are
// predicted through the first 3 keys (quadratic) as before, and the fourth, the second beyond,
// measures their error (the difference to the cubic through all 4, not to the line through the
// inner pair). On the Kerr disk's spin ramp at 64 × 64 (keys 0.198 apart from a = 0, the frame at
// a = 0.099) the colours are those of the first 3 keys alone, and the estimate ranks their true
// error, against the frame traced there, better than without the fourth key.
TEST(PathInterpolation, AtAnEndOfTheKeysTheSecondKeyBeyondMeasuresTheError)
{
  constexpr int side = 64;
  auto spinScene = [](double spin)
  {
    SceneDescription d =
      loadSceneFile(std::string(ASRT_SOURCE_DIR) + "/Data/scenes/kerr-disk.json",
                    [](const std::string& p) { return readPngTexture(p, TextureLimits{}); });
    d.spacetime.spin = spin;
    d.camera.width = d.camera.height = side;
    return d;
  };
  TracedKeys four, three;
  for (int k = 0; k < 4; ++k)
  {
    four.s.push_back(0.198 * k);
    four.records.push_back(traceFrame(spinScene(four.s.back())));
  }
  three = four;
  three.s.pop_back();
  three.records.pop_back();
  const double t = 0.099;
  const SceneDescription atT = spinScene(t);
  const std::vector<RayRecord> truth = traceFrame(atT);
  PathOptions options;
  options.movedEdges = false;
  options.leaveOneOut = false; // the estimates as predicted
  const PathFrame withFour = interpolateAlongPath(four.path(), t, side, side, *atT.scene, options);
  const PathFrame withThree =
    interpolateAlongPath(three.path(), t, side, side, *atT.scene, options);
  EXPECT_EQ(withFour.counts()[static_cast<std::size_t>(PathMethod::Cubic)], 0u);
  std::vector<double> estimate[2], error;
  for (std::size_t p = 0; p < truth.size(); ++p)
  {
    ASSERT_EQ(withFour.method[p], withThree.method[p]) << p;
    ASSERT_EQ(withFour.records[p].color, withThree.records[p].color) << p;
    if (withFour.method[p] != static_cast<std::uint8_t>(PathMethod::Quadratic))
      continue;
    estimate[0].push_back(withThree.estimate[p]);
    estimate[1].push_back(withFour.estimate[p]);
    error.push_back(error2(withFour.records[p], truth[p]));
  }
  ASSERT_GT(estimate[0].size(), truth.size() / 2);
  const double rank[2] = { spearman(estimate[0], error), spearman(estimate[1], error) };
  std::printf("[ path ] %zu pixels predicted through 3 keys: the estimate's rank correlation with "
              "their error %.3f, with the fourth key %.3f\n",
              error.size(), rank[0], rank[1]);
  EXPECT_GT(rank[1], rank[0] + 0.05);
}

TEST_F(PathInterpolationRamp, AQualityTargetIsMetByReTracingTheWorstPixels)
{
  const SceneDescription atT = rampScene(T, Side);
  const FrameTracer tracer(atT);
  for (double target : { 30.0, 40.0 })
  {
    PathFrame f = interpolated();
    const std::size_t must = f.counts()[static_cast<int>(PathMethod::Retrace)];
    const std::int64_t before = tracer.raysIntegrated();
    const PathCompletion done = completePathFrame(f, tracer, target);
    const double psnr = psnrOf(f.records, truth());
    // The rays counted are all the tracer integrated (TestFrameTracer holds its count to the
    // rays of whole frames), more than the re-traced records hold: their edge neighbours too.
    double charged = 0;
    for (std::size_t p = 0; p < f.records.size(); ++p)
      if (f.method[p] == static_cast<std::uint8_t>(PathMethod::Retraced))
        charged += f.records[p].raysPerPixel;
    std::printf("[ path ] target %.0f dB: %.1f dB, %zu re-traced (%zu must, %zu probes) of %zu, "
                "%.0f rays (%.0f in their records)\n",
                target, psnr, done.retraced, done.mustRetrace, done.probes, f.records.size(),
                done.raysTraced, charged);
    EXPECT_EQ(done.raysTraced, static_cast<double>(tracer.raysIntegrated() - before));
    EXPECT_GT(done.raysTraced, charged);
    EXPECT_EQ(done.mustRetrace, must);
    EXPECT_GE(psnr, target - 1.0);
    EXPECT_LT(done.retraced, f.records.size());
    // Re-traced pixels' rays are the traced frame's, to the bit. Their colours read the
    // neighbours as the frame held them (predicted ones too): the same, or within the error of
    // predictions the keys agree on.
    std::size_t differing = 0;
    double worstColour = 0;
    for (std::size_t p = 0; p < f.records.size(); ++p)
      if (f.method[p] == static_cast<std::uint8_t>(PathMethod::Retraced))
      {
        const RayRecord &a = f.records[p], &b = truth()[p];
        ASSERT_TRUE(a.objectId == b.objectId && a.termination == b.termination && a.u == b.u &&
                    a.v == b.v && a.winding == b.winding)
          << p;
        const double d =
          std::max({ std::abs(a.color[0] - b.color[0]), std::abs(a.color[1] - b.color[1]),
                     std::abs(a.color[2] - b.color[2]) });
        differing += d > 0;
        worstColour = std::max(worstColour, d);
      }
    std::printf("[ path ] target %.0f dB: %zu of %zu re-traced colours differ, at most %.5f\n",
                target, differing, done.retraced, worstColour);
    EXPECT_LE(worstColour, 2.0 / 255.0); // the given neighbours' level, and the 8-bit rounding
  }
}

// The mass ramp with keys 0.11 M apart, where the lensed edges move far and not evenly between
// keys: the ways of moving the keys' scene points disagree on where an edge now lies, and the
// mean of the ways (hedged, the default) comes closer to the frame the test traces there than
// the points of both keys alone.
TEST(PathInterpolationMovedEdges, HedgingTheWaysOfMovingComesCloserToTheTracedFrame)
{
  constexpr int side = 96;
  constexpr double t = 0.76;
  const TracedKeys keys = rampKeys(side, 0.595, 0.11);
  const RampFrameAt at(t, side);
  const std::vector<RayRecord>& truth = at.truth;
  PathOptions single = withMovedEdges();
  single.hedgeMovedEdges = false;
  const PathFrame a = at.interpolated(keys, withMovedEdges());
  const PathFrame b = at.interpolated(keys, single);
  double errorHedged = 0, errorSingle = 0;
  std::size_t moved = 0, changed = 0;
  for (std::size_t p = 0; p < truth.size(); ++p)
  {
    // Both frames choose their ways of predicting alike: hedging changes colours alone.
    ASSERT_EQ(a.method[p], b.method[p]) << p;
    if (a.method[p] != static_cast<std::uint8_t>(PathMethod::MovedEdge))
      continue;
    ++moved;
    changed += a.records[p].color != b.records[p].color;
    errorHedged += error2(a.records[p], truth[p]);
    errorSingle += error2(b.records[p], truth[p]);
  }
  std::printf("[ path ] moved edges at M = %.2f, keys 0.11 apart: %zu pixels, %zu hedged; mean "
              "squared error %.0f hedged, %.0f from both keys' points alone\n",
              t, moved, changed, errorHedged / moved, errorSingle / moved);
  EXPECT_GT(moved, side * side / 20u);
  EXPECT_GT(changed, moved / 10);
  EXPECT_LT(errorHedged, 0.9 * errorSingle);
}

// The mass ramp, keys 0.11 M apart, where the shadow grows between them and swallows the images
// near its rim: moved points of a surface and of the hole both cover spots there, and the frame
// shown as predicted (hedgeNearShadow) takes the mean of the two. It comes closer to the frame the
// test traces at t, and only moved-edge pixels change.
TEST(PathInterpolationMovedEdges, HedgingTheShadowsRimComesCloserToTheTracedFrame)
{
  constexpr int side = 96;
  constexpr double t = 0.6225;
  const TracedKeys keys = rampKeys(side, 0.45, 0.11);
  const RampFrameAt at(t, side);
  const std::vector<RayRecord>& truth = at.truth;
  PathOptions hedged = withMovedEdges();
  hedged.hedgeNearShadow = true;
  const PathFrame a = at.interpolated(keys, hedged);
  const PathFrame b = at.interpolated(keys, withMovedEdges());
  double errorHedged = 0, errorPlain = 0;
  std::size_t changed = 0;
  for (std::size_t p = 0; p < truth.size(); ++p)
  {
    ASSERT_EQ(a.method[p], b.method[p]) << p;
    errorHedged += error2(a.records[p], truth[p]);
    errorPlain += error2(b.records[p], truth[p]);
    if (a.records[p].color == b.records[p].color)
      continue;
    ++changed;
    EXPECT_TRUE(movedByPoints(a.method[p])) << p;
  }
  std::printf("[ path ] the shadow's rim at M = %.4f, keys 0.11 apart: %zu pixels hedged; squared "
              "error %.0f hedged, %.0f not\n",
              t, changed, errorHedged, errorPlain);
  EXPECT_GT(changed, 20u);
  EXPECT_LT(errorHedged, 0.8 * errorPlain);
}

// The mass ramp, keys 0.11 M apart: Fig. 4's cylinders run through the hole, and as it grows
// between the keys its horizon swallows the parts of them that reach into it. Those parts, seen by
// the earlier key and gone at the later, move only as matching extrapolates them, and without the
// spacetime at t they are shown where the frame the test traces at t shows the hole. Given it
// (PathOptions::spacetimeAt), no pixel shows a scene point inside the horizon at t, far fewer show
// a surface where the traced frame shows the hole, and the frame comes closer to the traced one;
// only pixels predicted by moving the keys' points change.
TEST(PathInterpolationMovedEdges, AGrowingHorizonSwallowsTheSurfacesReachingIntoIt)
{
  constexpr int side = 96;
  const TracedKeys keys = rampKeys(side, 0.45, 0.11);
  for (const double t : { 0.5875, 0.6225 })
  {
    const RampFrameAt at(t, side);
    const std::vector<RayRecord>& truth = at.truth;
    PathOptions known = withMovedEdges();
    known.spacetimeAt = [hole = at.scene.spacetime](double m)
    {
      SpacetimeParameters p = hole;
      p.mass = m;
      return std::shared_ptr<const Spacetime>(makeSpacetime(p));
    };
    const PathFrame a = at.interpolated(keys, known);
    const PathFrame b = at.interpolated(keys, withMovedEdges());
    double errorKnown = 0, errorNot = 0;
    std::size_t changed = 0, swallowedKnown = 0, swallowedNot = 0, inside = 0;
    for (std::size_t p = 0; p < truth.size(); ++p)
    {
      // A surface given way to the hole may class a pixel as on an edge or off one.
      ASSERT_TRUE(a.method[p] == b.method[p] ||
                  (movedByPoints(a.method[p]) && movedByPoints(b.method[p])))
        << p;
      errorKnown += error2(a.records[p], truth[p]);
      errorNot += error2(b.records[p], truth[p]);
      const bool hole = truth[p].termination == Termination::Captured;
      swallowedKnown += hole && a.records[p].termination == Termination::HitObject;
      swallowedNot += hole && b.records[p].termination == Termination::HitObject;
      inside += a.records[p].termination == Termination::HitObject &&
                a.records[p].hitPoint.norm() <= 2.0 * t;
      if (a.records[p].color == b.records[p].color)
        continue;
      ++changed;
      EXPECT_TRUE(movedByPoints(a.method[p])) << p;
    }
    std::printf("[ path ] the horizon at M = %.4f, keys 0.11 apart: %zu pixels changed; a surface "
                "where the traced frame shows the hole at %zu pixels, %zu without the spacetime; "
                "squared error %.0f, %.0f without\n",
                t, changed, swallowedKnown, swallowedNot, errorKnown, errorNot);
    EXPECT_EQ(inside, 0u);
    EXPECT_GT(swallowedNot, 20u);
    EXPECT_LT(swallowedKnown, swallowedNot);
    EXPECT_LT(errorKnown, 0.9 * errorNot);
    if (t == 0.6225) // midway, where the extrapolated points have moved furthest
    {
      EXPECT_LT(swallowedKnown, swallowedNot / 2);
      EXPECT_LT(errorKnown, 0.8 * errorNot);
    }
  }
}

// The mass ramp, keys 0.11 M apart: among the moved-edge pixels, those whose centre shows
// another surface than the frame the test traces at t (the errors of a whole contrast) rank above
// the others by the estimate. An edge that every way of moving puts in the same place counts a
// sixteenth of the contrast across it, one the ways dispute a quarter (PathEdges.h).
TEST(PathInterpolationMovedEdges, PixelsShowingAnotherSurfaceRankAboveTheOtherMovedEdges)
{
  constexpr int side = 96;
  const TracedKeys keys = rampKeys(side, 0.45, 0.11);
  for (const double t : { 0.5875, 0.6225 })
  {
    const RampFrameAt at(t, side);
    const std::vector<RayRecord>& truth = at.truth;
    const PathFrame f = at.interpolated(keys, withMovedEdges());
    std::vector<std::pair<float, bool>> moved; // estimate, shows another surface
    for (std::size_t p = 0; p < truth.size(); ++p)
      if (f.method[p] == static_cast<std::uint8_t>(PathMethod::MovedEdge))
        moved.emplace_back(f.estimate[p], f.records[p].objectId != truth[p].objectId ||
                                            f.records[p].termination != truth[p].termination);
    // Mean rank (average ranks for ties, scaled to (0, 1]) of the pixels showing another surface.
    std::sort(moved.begin(), moved.end());
    double rankSum = 0;
    std::size_t another = 0;
    for (std::size_t k = 0; k < moved.size();)
    {
      std::size_t end = k;
      while (end < moved.size() && moved[end].first == moved[k].first)
        ++end;
      const double rank = 0.5 * static_cast<double>(k + 1 + end) / moved.size();
      for (; k < end; ++k)
        if (moved[k].second)
        {
          rankSum += rank;
          ++another;
        }
    }
    const double meanRank = another > 0 ? rankSum / another : 0.0;
    std::printf("[ path ] moved edges at M = %.4f: %zu pixels, %zu showing another surface, their "
                "mean rank by the estimate %.2f\n",
                t, moved.size(), another, meanRank);
    EXPECT_GT(another, 10u);
    EXPECT_GT(meanRank, 0.65);
  }
}

// The whole mass ramp with key frames a quarter of it apart, where the orders of prediction
// disagree little while the texture under a pixel changes a lot between keys: every frame between
// them, completed to a target, meets it within 1 dB against the frame the test traces there, and
// a completed frame is reported exact only when it is.
TEST(PathInterpolationFarKeys, EveryFrameMeetsItsTargetAgainstTheTracedFrame)
{
  constexpr int side = 64;
  constexpr double target = 35.0;
  std::vector<double> s;
  std::vector<std::vector<RayRecord>> records;
  for (int k = 0; k < 5; ++k)
  {
    s.push_back(0.1 + 0.275 * k);
    records.push_back(traceFrame(rampScene(s.back(), side)));
  }
  std::vector<PathKey> path;
  for (std::size_t k = 0; k < s.size(); ++k)
    path.push_back({ s[k], &records[k] });
  double worst = std::numeric_limits<double>::infinity();
  for (int f = 1; f < 9; ++f)
  {
    const double t = 0.1 + 1.1 * f / 9.0;
    const SceneDescription atT = rampScene(t, side);
    const FrameTracer tracer(atT);
    const std::vector<RayRecord> truth = tracer.traceRows(0, side);
    PathFrame frame = interpolateAlongPath(path, t, side, side, *atT.scene, withMovedEdges());
    const PathCompletion done = completePathFrame(frame, tracer, target);
    const double psnr = psnrOf(frame.records, truth);
    std::printf("[ path ] far keys, M = %.3f: estimated %.1f dB, %.1f dB against the traced frame, "
                "%.0f %% re-traced\n",
                t, done.estimatedPsnr, psnr, 100.0 * done.retraced / truth.size());
    worst = std::min(worst, psnr);
    EXPECT_GE(psnr, target - 1.0) << "M = " << t;
    if (std::isinf(done.estimatedPsnr))
    {
      EXPECT_TRUE(std::isinf(psnr)) << "M = " << t << ": reported exact, " << psnr << " dB";
    }
    EXPECT_LT(done.retraced, truth.size()) << "M = " << t;
  }
  std::printf("[ path ] far keys: the worst frame %.1f dB against its traced frame\n", worst);
}

// Fig. 1's camera orbit between keys 6° apart (72° and 78°, with 66° and 84° outside), 100 × 100:
// the tip of the x cylinder's silhouette sweeps across pixels where every key shows the galaxy
// behind it, so their records agree and predict the galaxy there. The frames between, completed
// to a target, still meet it within 1 dB against the frames the test traces there.
TEST(PathInterpolationOrbit, ASilhouetteSweepingAcrossPixelsTheKeysAgreeOnIsTraced)
{
  constexpr int side = 100;
  constexpr double target = 35.0;
  const SceneDescription start = sceneFile("fig1-cylinders.json");
  auto sceneAt = [&start](double degrees) { return orbitScene(start, side, degrees); };
  const TracedKeys keys = orbitKeys(start, side, { 66.0, 72.0, 78.0, 84.0 });
  const std::vector<PathKey> path = keys.path();
  const std::vector<std::vector<RayRecord>>& records = keys.records;
  PathOptions options;
  options.movedEdges = false; // as asrt movie interpolates
  std::size_t swept = 0;
  for (int degrees = 73; degrees < 78; ++degrees)
  {
    const double t = degrees;
    const SceneDescription atT = sceneAt(t);
    const FrameTracer tracer(atT);
    const std::vector<RayRecord> truth = tracer.traceRows(0, side);
    PathFrame frame = interpolateAlongPath(path, t, side, side, *atT.scene, options);
    // The pixels whose keys all agree on one surface while the frame traced at t shows another
    // object: what sweeps across them between the keys.
    for (std::size_t p = 0; p < truth.size(); ++p)
    {
      bool agree = true;
      for (const std::vector<RayRecord>& key : records)
        agree = agree && key[p].objectId == records[1][p].objectId;
      swept += agree && truth[p].objectId >= 0 && truth[p].objectId != records[1][p].objectId;
    }
    const PathCompletion done = completePathFrame(frame, tracer, target);
    const double psnr = psnrOf(frame.records, truth);
    std::printf("[ path ] orbit, %.0f°: estimated %.1f dB, %.1f dB against the traced frame, "
                "%.1f %% re-traced (%zu following traced edges)\n",
                t, done.estimatedPsnr, psnr, 100.0 * done.retraced / truth.size(), done.followed);
    EXPECT_GE(psnr, target - 1.0) << t << "°";
    EXPECT_LT(done.retraced, truth.size()) << t << "°";
  }
  std::printf("[ path ] orbit: %zu pixels show an object that all four keys show elsewhere\n",
              swept);
  EXPECT_GT(swept, 0u) << "the path no longer has an object sweeping between its keys";
}

// The Kerr disk orbited about its axis: the edges (the disk's rims, the shadow) stay in place
// while the disk's texture turns under them. An edge pixel's centre ray is predicted like any
// pixel's, and only what the keys' colours add to their centre rays' shades is interpolated: the
// edge pixels then come far closer to the frame traced there than the keys' colours interpolated
// alone (the same Lagrange weights), which is what interpolating whole colours gave.
TEST(PathInterpolationOrbit, EdgePixelsFollowATextureTurningUnderEdgesThatStay)
{
  constexpr int side = 96;
  const SceneDescription start = sceneFile("kerr-disk.json");
  auto sceneAt = [&start](double degrees) { return orbitScene(start, side, degrees); };
  const TracedKeys keys = orbitKeys(start, side, { 20.0, 30.0, 40.0, 50.0 });
  const std::vector<PathKey> path = keys.path();
  const std::vector<double>& s = keys.s;
  const std::vector<std::vector<RayRecord>>& records = keys.records;
  PathOptions options;
  options.movedEdges = false;
  const double t = 35.0;
  const SceneDescription atT = sceneAt(t);
  const std::vector<RayRecord> truth = traceFrame(atT);
  const PathFrame f = interpolateAlongPath(path, t, side, side, *atT.scene, options);
  double w[4];
  lagrangeWeights(s.data(), 4, t, w);
  double predicted = 0, colours = 0;
  std::size_t edges = 0;
  for (std::size_t p = 0; p < f.records.size(); ++p)
  {
    if (f.method[p] != static_cast<std::uint8_t>(PathMethod::EdgeBlend))
      continue;
    ++edges;
    predicted += error2(f.records[p], truth[p]);
    // The keys' colours alone, through the same 4 keys where they all vouch for the pixel.
    Color blend = Color::Zero();
    for (int k = 0; k < 4; ++k)
      blend += w[k] * records[static_cast<std::size_t>(k)][p].color;
    RayRecord alone = truth[p];
    alone.color = blend.cwiseMax(0.0).cwiseMin(1.0);
    colours += error2(alone, truth[p]);
  }
  std::printf("[ path ] Kerr disk at %.0f degrees: %zu edge pixels, squared error %.0f (keys' "
              "colours alone: %.0f)\n",
              t, edges, predicted, colours);
  ASSERT_GT(edges, 100u) << "no edge pixels: this test checks nothing";
  EXPECT_LT(predicted, 0.25 * colours);
}

namespace
{
/// Pixel (i, j)'s record on object 1 whose fields are the given polynomials of s (syntheticRecord),
/// or its ray escaped where `escaped`.
RayRecord syntheticPixel(int i, int j, double s, bool escaped)
{
  const std::vector<double> u = { 0.93, 0.2, -0.05, 0.03 }, v = { 0.2, 0.3, 0.1, -0.08 };
  RayRecord r = syntheticRecord(s + 0.01 * (i + 4 * j), u, v);
  r.i = i;
  r.j = j;
  if (escaped)
  {
    r.termination = Termination::Escaped;
    r.objectId = -1;
  }
  return r;
}

/// A side × side frame of syntheticPixel records at s.
std::vector<RayRecord> syntheticFrame(int side, double s, bool escaped)
{
  std::vector<RayRecord> f;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      f.push_back(syntheticPixel(i, j, s, escaped));
  return f;
}

/// Every pixel of a side × side frame at s, as a frame traced in part.
std::shared_ptr<PathSamples> wholeSamples(int side, double s)
{
  auto f = std::make_shared<PathSamples>();
  f->s = s;
  f->records = syntheticFrame(side, s, false);
  for (int p = 0; p < side * side; ++p)
    f->pixels.push_back(p);
  return f;
}
}

// Keys whose inner pair disagrees everywhere (the surface at s = 0, the rays escaped at s = 1):
// the keys vouch for no pixel. Frames traced in part between them hold the surface nearer t,
// and each pixel's chain through them and the keys that end alike is exact for a cubic in s.
TEST(PathInterpolationChains, ChainsThroughFramesTracedInPartAreExactForCubics)
{
  constexpr int side = 5;
  const SceneDescription d = rampScene(0.5, 8);
  std::vector<std::vector<RayRecord>> keyRecords = { syntheticFrame(side, -1.0, false),
                                                     syntheticFrame(side, 0.0, false),
                                                     syntheticFrame(side, 1.0, true),
                                                     syntheticFrame(side, 2.0, true) };
  std::vector<PathKey> keys;
  for (std::size_t k = 0; k < 4; ++k)
    keys.push_back({ static_cast<double>(k) - 1.0, &keyRecords[k] });
  PathOptions options;
  options.movedEdges = false;
  options.leaveOneOut = false;
  const double t = 0.45;
  const PathFrame plain = interpolateAlongPath(keys, t, side, side, *d.scene, options);
  EXPECT_EQ(plain.counts()[static_cast<std::size_t>(PathMethod::Retrace)],
            static_cast<std::size_t>(side * side));
  options.samples = { wholeSamples(side, 0.3), wholeSamples(side, 0.5), wholeSamples(side, 0.6) };
  const PathFrame chained = interpolateAlongPath(keys, t, side, side, *d.scene, options);
  ASSERT_EQ(chained.counts()[static_cast<std::size_t>(PathMethod::Cubic)],
            static_cast<std::size_t>(side * side));
  for (std::size_t p = 0; p < chained.records.size(); ++p)
  {
    // Nodes 0, 0.3, 0.5 and 0.6: the key at 1 ends otherwise and the one at −1 lies beyond.
    const RayRecord exact =
      syntheticPixel(static_cast<int>(p % side), static_cast<int>(p / side), t, false);
    EXPECT_NEAR(chained.records[p].u, exact.u, 1e-12) << p;
    EXPECT_NEAR(chained.records[p].v, exact.v, 1e-12) << p;
    EXPECT_NEAR(chained.records[p].dvdj, exact.dvdj, 1e-12) << p;
    EXPECT_NEAR(chained.records[p].hitPoint.x(), exact.hitPoint.x(), 1e-12) << p;
    EXPECT_EQ(chained.records[p].color, shadePrediction(*d.scene, chained.records[p])) << p;
    // The estimate is the quadratic's error (the node farther from t, at 0, dropped): at least
    // the colour difference to the quadratic through the records at 0.3, 0.5 and 0.6, which is
    // not zero for a cubic.
    const int i = static_cast<int>(p % side), j = static_cast<int>(p / side);
    const RayRecord at[3] = { syntheticPixel(i, j, 0.3, false), syntheticPixel(i, j, 0.5, false),
                              syntheticPixel(i, j, 0.6, false) };
    const RayRecord* three[3] = { &at[0], &at[1], &at[2] };
    const double s3[3] = { 0.3, 0.5, 0.6 };
    const RayRecord quadratic = predictRecord(three, s3, 3, t);
    EXPECT_NE(quadratic.v, exact.v) << p;
    const float lower = colorError2(chained.records[p].color, shadePrediction(*d.scene, quadratic));
    EXPECT_GT(lower, 0.0f) << p;
    EXPECT_GE(chained.estimate[p], lower) << p;
  }
  // A frame traced in part at t itself is not a node (it would be the frame), nor one outside
  // the inner keys.
  auto atT = std::make_shared<PathSamples>(*wholeSamples(side, t));
  for (RayRecord& r : atT->records)
    r.objectId = 2;
  auto outside = std::make_shared<PathSamples>(*wholeSamples(side, -0.5));
  for (RayRecord& r : outside->records)
    r.objectId = 3;
  PathOptions more = options;
  more.samples.push_back(atT);
  more.samples.push_back(outside);
  const PathFrame same = interpolateAlongPath(keys, t, side, side, *d.scene, more);
  for (std::size_t p = 0; p < same.records.size(); ++p)
    ASSERT_EQ(same.records[p].color, chained.records[p].color) << p;

  // The surface gone at pixel (1, 1) by s = 0.5: the inner pair there disagrees, and an edge
  // between the two frames may cross its 8 neighbours at t too. The pixels beyond are vouched for.
  auto edge = std::make_shared<PathSamples>(*wholeSamples(side, 0.5));
  edge->records[static_cast<std::size_t>(1 + side)] = syntheticPixel(1, 1, 0.5, true);
  options.samples = { wholeSamples(side, 0.3), edge, wholeSamples(side, 0.6) };
  const PathFrame guarded = interpolateAlongPath(keys, t, side, side, *d.scene, options);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
    {
      const bool near = i <= 2 && j <= 2;
      EXPECT_EQ(guarded.method[static_cast<std::size_t>(i + side * j)] ==
                  static_cast<std::uint8_t>(PathMethod::Retrace),
                near)
        << i << ", " << j;
    }
}

TEST(PathInterpolationChains, BadFramesTracedInPartAreRefusedByName)
{
  constexpr int side = 3;
  const SceneDescription d = rampScene(0.5, 8);
  std::vector<std::vector<RayRecord>> keyRecords = { syntheticFrame(side, 0.0, false),
                                                     syntheticFrame(side, 1.0, true) };
  const std::vector<PathKey> keys = { { 0.0, &keyRecords[0] }, { 1.0, &keyRecords[1] } };
  PathOptions options;
  options.movedEdges = false;
  options.leaveOneOut = false;
  auto refused = [&](const std::shared_ptr<PathSamples>& f)
  {
    PathOptions o = options;
    o.samples = { wholeSamples(side, 0.25), f };
    return errorOf([&] { interpolateAlongPath(keys, 0.5, side, side, *d.scene, o); });
  };
  auto f = wholeSamples(side, 0.75);
  EXPECT_EQ(refused(f), "");
  auto unsorted = wholeSamples(side, 0.75);
  std::swap(unsorted->pixels[2], unsorted->pixels[3]);
  std::swap(unsorted->records[2], unsorted->records[3]);
  EXPECT_NE(refused(unsorted).find("sample frame 1: its pixels must be strictly ascending"),
            std::string::npos)
    << refused(unsorted);
  auto outside = wholeSamples(side, 0.75);
  outside->pixels.back() = side * side;
  EXPECT_NE(refused(outside).find("sample frame 1: its pixels"), std::string::npos);
  auto misplaced = wholeSamples(side, 0.75);
  misplaced->records[4].i = 0;
  EXPECT_NE(refused(misplaced).find("sample frame 1: record 4 is pixel (0, 1)"), std::string::npos)
    << refused(misplaced);
  auto short_ = wholeSamples(side, 0.75);
  short_->records.pop_back();
  EXPECT_NE(refused(short_).find("sample frame 1 has 8 records for 9 pixels"), std::string::npos);
  auto nan = wholeSamples(side, std::nan(""));
  EXPECT_NE(refused(nan).find("sample frame 1: its parameter s must be finite"), std::string::npos);
  EXPECT_NE(refused(nullptr).find("sample frame 1 is null"), std::string::npos);
}

// The mass ramp: the frame at T between keys 0.05 apart, completed to a target against the frame
// the test traces there, once from the keys alone and once with the pixels a frame nearer the
// next key re-traced (completed first, as a movie makes its frames). Those hold edges nearer T:
// fewer pixels must be re-traced, and the pixels they let it predict are close to the truth.
TEST_F(PathInterpolationRamp, PixelsAnotherFrameReTracedLetTheFramePredictMore)
{
  const double target = 35.0;
  const double nearer = 0.735;
  std::vector<PathKey> path;
  for (int k = 0; k < 4; ++k)
    path.push_back({ 0.65 + 0.05 * k, &keys()[static_cast<std::size_t>(k)] });
  auto retracer = [](double s)
  {
    SceneDescription d = rampScene(s, Side);
    d.rendering = scatteredPixelRendering(d.rendering);
    return d;
  };
  PathOptions options;
  options.movedEdges = false;
  PathFrame first =
    interpolateAlongPath(path, nearer, Side, Side, *rampScene(nearer, Side).scene, options);
  completePathFrame(first, FrameTracer(retracer(nearer)), target);
  auto samples = std::make_shared<PathSamples>();
  samples->s = nearer;
  for (std::size_t p = 0; p < first.records.size(); ++p)
    if (first.method[p] == static_cast<std::uint8_t>(PathMethod::Retraced))
    {
      samples->pixels.push_back(static_cast<std::int32_t>(p));
      samples->records.push_back(first.records[p]);
    }
  const SceneDescription atT = rampScene(T, Side);
  const Scene& scene = *atT.scene;
  const PathFrame alone = interpolateAlongPath(path, T, Side, Side, scene, options);
  PathOptions chained = options;
  chained.samples = { samples };
  PathFrame with = interpolateAlongPath(path, T, Side, Side, scene, chained);
  const std::size_t retrace = static_cast<std::size_t>(PathMethod::Retrace);
  double sum = 0;
  std::size_t gained = 0;
  for (std::size_t p = 0; p < with.records.size(); ++p)
    if (alone.method[p] == retrace && with.method[p] != retrace)
    {
      ++gained;
      sum += error2(with.records[p], truth()[p]);
    }
  const double gainedPsnr = 10.0 * std::log10(255.0 * 255.0 * 3.0 * gained / sum);
  std::printf("[ path ] %zu pixels to re-trace from the keys alone, %zu with %zu pixels re-traced "
              "at %.3f; the %zu predicted instead score %.1f dB against the traced frame\n",
              alone.counts()[retrace], with.counts()[retrace], samples->pixels.size(), nearer,
              gained, gainedPsnr);
  EXPECT_LT(with.counts()[retrace] * 20, alone.counts()[retrace] * 19); // 5 % fewer at least
  EXPECT_GT(gainedPsnr, target + 3.0);
  const FrameTracer tracer(retracer(T));
  const PathCompletion done = completePathFrame(with, tracer, target);
  const double psnr = psnrOf(with.records, truth());
  std::printf("[ path ] completed to %.0f dB with them: %.1f dB, %zu re-traced\n", target, psnr,
              done.retraced);
  EXPECT_GE(psnr, target - 1.0);
}
