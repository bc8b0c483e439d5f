// The interpolation core on frames whose truth is known in closed form: a colour ramp translated
// by a sub-pixel amount (linear interpolation of a linear function is exact), a magnified frame
// (coverage from the Jacobian), objects passing in front of each other (visibility), and the
// parameters between two frames (linear, orbit). Also the image-quality measures and push-pull.
#include "FrameInterpolation.h"
#include "FrameTracer.h"
#include "ImageQuality.h"
#include "SceneFile.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>

using namespace asrt;

namespace
{
/// A frame whose pixel (i, j) saw a flat object at path length `length`, colour by `color`.
FrameSamples flatFrame(int w, int h, const std::function<Color(int, int)>& color,
                       const std::function<int(int, int)>& object = nullptr,
                       const std::function<double(int, int)>& length = nullptr)
{
  FrameSamples f;
  f.width = w;
  f.height = h;
  f.pixels.resize(static_cast<std::size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
    {
      PixelSample& s = f.pixels[static_cast<std::size_t>(j) * w + i];
      s.termination = Termination::HitObject;
      s.objectId = object ? object(i, j) : 1;
      s.pathLength = length ? length(i, j) : 10.0;
      s.point = Vec3(i, j, 0);
      s.rgb = imageColor(color(i, j));
    }
  return f;
}

/// Every pixel matched to (i, j) + d with Jacobian J.
std::vector<PixelMatch> uniformMatch(int w, int h, const std::function<Vec3(int, int)>& target,
                                     double jacobianScale = 1.0)
{
  std::vector<PixelMatch> m(static_cast<std::size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
    {
      PixelMatch& x = m[static_cast<std::size_t>(j) * w + i];
      const Vec3 p = target(i, j);
      x.x = static_cast<float>(p.x());
      x.y = static_cast<float>(p.y());
      x.kind = MatchKind::Matched;
      x.jacobian = { { static_cast<float>(jacobianScale), 0, 0,
                       static_cast<float>(jacobianScale) } };
    }
  return m;
}

Correspondence correspondence(int w, int h, std::vector<PixelMatch> ab, std::vector<PixelMatch> ba)
{
  Correspondence c;
  c.width = w;
  c.height = h;
  c.aToB = std::move(ab);
  c.bToA = std::move(ba);
  return c;
}

std::uint8_t channel(const InterpolatedFrame& f, int i, int j, int c)
{
  return f.rgb[3 * (static_cast<std::size_t>(j) * f.width + i) + c];
}
}

TEST(FrameInterpolation, TranslatedRampIsExactUpToRounding)
{
  // B is A moved 3.4 px right and 1.3 px up; the red channel is a ramp along i, so the frame at
  // t is the ramp moved by t·(3.4, 1.3): red(i) = 4 (i − 3.4 t) + 20 exactly.
  const int w = 48, h = 32;
  const double dx = 3.4, dy = 1.3;
  auto ramp = [](double x) { return (4.0 * x + 20.0) / 255.0; };
  const FrameSamples a = flatFrame(w, h, [&](int i, int) { return Color(ramp(i), 0.5, 0.5); });
  const FrameSamples b = flatFrame(w, h, [&](int i, int) { return Color(ramp(i - dx), 0.5, 0.5); });
  const Correspondence c =
    correspondence(w, h, uniformMatch(w, h, [&](int i, int j) { return Vec3(i + dx, j + dy, 0); }),
                   uniformMatch(w, h, [&](int i, int j) { return Vec3(i - dx, j - dy, 0); }));
  const SplatSet set = buildSplats(a, b, c);
  InterpolationWorkspace ws;
  InterpolatedFrame f;
  for (double t : { 0.2, 0.5, 0.7 })
  {
    renderFrame(set, t, f, ws);
    EXPECT_EQ(f.holes, 0);
    // Away from the borders, where pixels enter and leave the view.
    for (int j = 3; j < h - 3; ++j)
      for (int i = 5; i < w - 5; ++i)
      {
        const double expected = 255.0 * ramp(i - t * dx);
        EXPECT_NEAR(channel(f, i, j, 0), expected, 1.01) << "t " << t << " at " << i << ", " << j;
        EXPECT_EQ(channel(f, i, j, 1), 128);
      }
  }
}

TEST(FrameInterpolation, EndsAreTheFramesThemselves)
{
  const int w = 20, h = 16;
  const FrameSamples a =
    flatFrame(w, h, [](int i, int j) { return Color((i * 13 % 256) / 255.0, j / 15.0, 0.2); });
  const FrameSamples b =
    flatFrame(w, h, [](int i, int j) { return Color(0.1, (i * 7 % 256) / 255.0, j / 15.0); });
  const Correspondence c = correspondence(
    w, h, uniformMatch(w, h, [](int i, int j) { return Vec3(i + 0.37, j - 0.61, 0); }),
    uniformMatch(w, h, [](int i, int j) { return Vec3(i - 0.37, j + 0.61, 0); }));
  const SplatSet set = buildSplats(a, b, c);
  InterpolationWorkspace ws;
  InterpolatedFrame f;
  renderFrame(set, 0.0, f, ws);
  for (std::size_t p = 0; p < a.pixels.size(); ++p)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(f.rgb[3 * p + k], a.pixels[p].rgb[k]) << "pixel " << p;
  renderFrame(set, 1.0, f, ws);
  for (std::size_t p = 0; p < b.pixels.size(); ++p)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(f.rgb[3 * p + k], b.pixels[p].rgb[k]) << "pixel " << p;
}

TEST(FrameInterpolation, MagnifiedFrameIsCoveredThroughItsJacobian)
{
  // B is A magnified 5× about the centre: at t = ½ A's splats lie 3 px apart. Footprints that
  // follow (1 − t) I + t D cover every pixel; bilinear splats (support ±1 px) leave holes,
  // which are counted and filled.
  const int w = 60, h = 60;
  const double cx = 29.5, cy = 29.5, k = 5.0;
  const FrameSamples a = flatFrame(w, h, [](int i, int) { return Color(i / 59.0, 0.3, 0.3); });
  const FrameSamples b =
    flatFrame(w, h, [&](int i, int) { return Color((cx + (i - cx) / k) / 59.0, 0.3, 0.3); });
  // Only A's splats: B's own pixels map back densely and would hide the effect.
  std::vector<PixelMatch> ab = uniformMatch(
    w, h, [&](int i, int j) { return Vec3(cx + k * (i - cx), cy + k * (j - cy), 0); }, k);
  std::vector<PixelMatch> ba(static_cast<std::size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
    {
      PixelMatch& m = ba[static_cast<std::size_t>(j) * w + i];
      m.x = -1000; // far outside: B's splats never reach the frame
      m.y = -1000;
    }
  const Correspondence c = correspondence(w, h, ab, ba);
  InterpolationWorkspace ws;
  InterpolatedFrame f;
  const SplatSet covered = buildSplats(a, b, c);
  renderFrame(covered, 0.5, f, ws, SplatSides::AOnly);
  EXPECT_EQ(f.holes, 0);
  InterpolationOptions narrow;
  narrow.maxMagnification = 1.0f;
  const SplatSet pointlike = buildSplats(a, b, c, narrow);
  renderFrame(pointlike, 0.5, f, ws, SplatSides::AOnly);
  EXPECT_GT(f.holes, w * h / 10);
  // Filled holes lie between their neighbours' values (the red ramp is monotonic in i).
  for (int j = 20; j < 40; ++j)
    for (int i = 21; i < 39; ++i)
    {
      EXPECT_GE(channel(f, i, j, 0) + 3, channel(f, i - 1, j, 0)) << i << ", " << j;
      EXPECT_EQ(channel(f, i, j, 1), 77);
    }
}

TEST(FrameInterpolation, NearerSurfacesAndLowerImageOrdersHideTheRest)
{
  // A red object (path length 10) moves 6 px right over a static blue one (path length 100).
  const int w = 40, h = 10;
  auto isRed = [](int i) { return i < 15; };
  const FrameSamples a = flatFrame(
    w, h, [&](int i, int) { return isRed(i) ? Color(1, 0, 0) : Color(0, 0, 1); },
    [&](int i, int) { return isRed(i) ? 1 : 2; },
    [&](int i, int) { return isRed(i) ? 10.0 : 100.0; });
  auto build = [&](int redOrder)
  {
    FrameSamples fa = a, fb = a;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i)
      {
        PixelSample& s = fb.pixels[static_cast<std::size_t>(j) * w + i];
        const bool red = i >= 6 && i < 21;
        s.rgb =
          red ? std::array<std::uint8_t, 3>{ 255, 0, 0 } : std::array<std::uint8_t, 3>{ 0, 0, 255 };
        s.objectId = red ? 1 : 2;
        s.pathLength = red ? 10.0 : 100.0;
        s.imageOrder = red ? redOrder : 0;
        fa.pixels[static_cast<std::size_t>(j) * w + i].imageOrder = isRed(i) ? redOrder : 0;
      }
    std::vector<PixelMatch> ab =
      uniformMatch(w, h, [&](int i, int j) { return Vec3(isRed(i) ? i + 6 : i, j, 0); });
    std::vector<PixelMatch> ba =
      uniformMatch(w, h, [&](int i, int j) { return Vec3(i >= 6 && i < 21 ? i - 6 : i, j, 0); });
    // Blue pixels covered in B (15 … 20) are seen in A only; those uncovered (0 … 5) in B only.
    for (int j = 0; j < h; ++j)
    {
      for (int i = 15; i < 21; ++i)
        ab[static_cast<std::size_t>(j) * w + i].kind = MatchKind::OneSided;
      for (int i = 0; i < 6; ++i)
        ba[static_cast<std::size_t>(j) * w + i].kind = MatchKind::OneSided;
    }
    return buildSplats(fa, fb, correspondence(w, h, ab, ba));
  };
  InterpolationWorkspace ws;
  InterpolatedFrame f;
  renderFrame(build(0), 0.5, f, ws);
  // At t = ½ the red object spans 3 … 17: the nearer surface covers the blue one there.
  for (int i = 4; i <= 16; ++i)
    EXPECT_EQ(channel(f, i, 5, 0), 255) << i;
  for (int i = 19; i < w; ++i)
    EXPECT_EQ(channel(f, i, 5, 2), 255) << i;
  // With the red object seen after a half-turn (image order 1), the primary image of the blue
  // one comes first wherever both land, whatever their path lengths.
  renderFrame(build(1), 0.5, f, ws);
  for (int i = 15; i <= 16; ++i)
    EXPECT_EQ(channel(f, i, 5, 2), 255) << i;
}

TEST(FrameInterpolation, DisagreementFlagsInconsistentFrames)
{
  const int w = 32, h = 16;
  const FrameSamples a = flatFrame(w, h, [](int i, int) { return Color(i / 31.0, 0.5, 0.5); });
  FrameSamples b = flatFrame(w, h, [](int i, int) { return Color((i - 2) / 31.0, 0.5, 0.5); });
  // Consistent: B is A moved 2 px.
  const Correspondence c =
    correspondence(w, h, uniformMatch(w, h, [](int i, int j) { return Vec3(i + 2, j, 0); }),
                   uniformMatch(w, h, [](int i, int j) { return Vec3(i - 2, j, 0); }));
  InterpolationWorkspace ws;
  std::vector<std::uint8_t> d;
  renderDisagreement(buildSplats(a, b, c), 0.5, d, ws);
  for (int i = 4; i < w - 4; ++i)
    EXPECT_LE(d[static_cast<std::size_t>(8) * w + i], 2) << i;
  // Inconsistent: B sees other colours where the motion puts A's points.
  for (PixelSample& s : b.pixels)
    s.rgb[1] = 20;
  renderDisagreement(buildSplats(a, b, c), 0.5, d, ws);
  for (int i = 4; i < w - 4; ++i)
    EXPECT_GE(d[static_cast<std::size_t>(8) * w + i], 100) << i;
}

namespace
{
/// High-contrast noise in [0, 1] per pixel and salt (a touch left out or added then shows; a
/// smooth ramp would hide it in the neighbours' mean).
double noise(int i, int j, int salt)
{
  const unsigned x = static_cast<unsigned>(i) * 73856093u ^ static_cast<unsigned>(j) * 19349663u ^
                     static_cast<unsigned>(salt) * 83492791u;
  return static_cast<double>((x * 2654435761u) >> 24) / 255.0;
}
}

TEST(FrameInterpolation, BandsDoNotChangeTheFrame)
{
  // The renderer cuts the frame into bands of rows, lists each splat in the bands it can reach
  // (per slice of t when it travels far) and skips those that cannot reach a band at t. None of
  // that may change a pixel: splats travelling across many narrow bands, bilinear and with
  // footprints, against the same frame drawn as one band.
  const int w = 40, h = 160;
  const double dx = 0.3, dy = 70.6;
  const FrameSamples a = flatFrame(
    w, h, [&](int i, int j) { return Color(noise(i, j, 1), noise(i, j, 2), noise(i, j, 3)); });
  const FrameSamples b = flatFrame(
    w, h, [&](int i, int j) { return Color(noise(i, j, 4), noise(i, j, 5), noise(i, j, 6)); });
  const Correspondence moved =
    correspondence(w, h, uniformMatch(w, h, [&](int i, int j) { return Vec3(i + dx, j + dy, 0); }),
                   uniformMatch(w, h, [&](int i, int j) { return Vec3(i - dx, j - dy, 0); }));
  // A magnified 3× about a point low in the frame: A's splats spread over several rows and
  // travel up to ~190 rows; B's never reach the frame.
  std::vector<PixelMatch> ab = uniformMatch(
    w, h, [&](int i, int j) { return Vec3(20 + 3.0 * (i - 20), 30 + 3.0 * (j - 30), 0); }, 3.0);
  std::vector<PixelMatch> away(static_cast<std::size_t>(w) * h);
  for (PixelMatch& m : away)
    m.x = m.y = -1000;
  const Correspondence magnified = correspondence(w, h, ab, away);
  InterpolationOptions narrow, whole;
  narrow.bandRows = 8;
  whole.bandRows = h;
  InterpolationWorkspace ws;
  InterpolatedFrame banded, single;
  for (const Correspondence* c : { &moved, &magnified })
  {
    const SplatSet setNarrow = buildSplats(a, b, *c, narrow),
                   setWhole = buildSplats(a, b, *c, whole);
    for (const SplatSides sides : { SplatSides::Both, SplatSides::AOnly, SplatSides::BOnly })
      for (const double t : { 0.13, 0.5, 0.77 })
      {
        renderFrame(setNarrow, t, banded, ws, sides);
        renderFrame(setWhole, t, single, ws, sides);
        ASSERT_EQ(banded.holes, single.holes) << "t " << t;
        for (std::size_t p = 0; p < banded.pixelClass.size(); ++p)
        {
          ASSERT_EQ(banded.pixelClass[p], single.pixelClass[p]) << "t " << t << " pixel " << p;
          for (int k = 0; k < 3; ++k)
            ASSERT_NEAR(banded.rgb[3 * p + k], single.rgb[3 * p + k], 1)
              << "t " << t << " pixel " << p;
        }
      }
  }
}

TEST(FrameInterpolation, ThreadCountDoesNotChangeTheFrame)
{
  // Bands are handed to threads dynamically and each thread keeps its own accumulators between
  // bands and frames: none of that may show in a pixel. Large enough to be drawn in parallel,
  // with depths that blend and hide, footprints, holes, and frames drawn one after another (so
  // that accumulators left over from one render meet the next).
  const int w = 200, h = 120;
  auto color = [&](int salt)
  {
    return [&, salt](int i, int j)
    { return Color(noise(i, j, salt), noise(i, j, salt + 1), noise(i, j, salt + 2)); };
  };
  auto length = [&](int salt)
  { return [&, salt](int i, int j) { return 10.0 + noise(i, j, salt); }; };
  const FrameSamples a = flatFrame(w, h, color(1), nullptr, length(7));
  const FrameSamples b = flatFrame(w, h, color(4), nullptr, length(8));
  // Rows that travel 1.5 px per row towards the bottom, and a 5× magnification (beyond
  // maxMagnification: holes) of the top.
  const Correspondence sheared = correspondence(
    w, h, uniformMatch(w, h, [&](int i, int j) { return Vec3(i + 0.37, j + 1.5 * j - 40.2, 0); }),
    uniformMatch(w, h, [&](int i, int j) { return Vec3(i - 0.37, (j + 40.2) / 2.5, 0); }));
  const Correspondence magnified = correspondence(
    w, h,
    uniformMatch(
      w, h, [&](int i, int j) { return Vec3(100 + 5.0 * (i - 100), 90 + 5.0 * (j - 90), 0); }, 5.0),
    uniformMatch(
      w, h, [&](int i, int j) { return Vec3(100 + 0.2 * (i - 100), 90 + 0.2 * (j - 90), 0); },
      0.2));
  const int saved = omp_get_max_threads();
  std::int64_t holes = 0;
  for (const Correspondence* c : { &sheared, &magnified })
  {
    const SplatSet set = buildSplats(a, b, *c);
    for (const SplatSides sides : { SplatSides::Both, SplatSides::AOnly })
    {
      InterpolationWorkspace ws;
      std::vector<InterpolatedFrame> one;
      omp_set_num_threads(1);
      for (const double t : { 0.13, 0.5, 0.77 })
      {
        one.emplace_back();
        renderFrame(set, t, one.back(), ws, sides);
        holes += one.back().holes;
      }
      for (const int threads : { 2, 3 })
      {
        omp_set_num_threads(threads);
        InterpolatedFrame f;
        for (std::size_t k = 0; k < one.size(); ++k)
        {
          renderFrame(set, one[k].t, f, ws, sides);
          EXPECT_EQ(f.holes, one[k].holes) << threads << " threads, t " << one[k].t;
          EXPECT_TRUE(f.rgb == one[k].rgb) << threads << " threads, t " << one[k].t;
          EXPECT_TRUE(f.pixelClass == one[k].pixelClass) << threads << " threads, t " << one[k].t;
          EXPECT_TRUE(f.source == one[k].source) << threads << " threads, t " << one[k].t;
        }
      }
    }
  }
  omp_set_num_threads(saved);
  EXPECT_GT(holes, 0); // the hole filling was exercised too
}

TEST(FrameInterpolation, PushPullKeepsKnownPixelsAndFillsFromThem)
{
  const int w = 37, h = 23;
  std::vector<float> v(static_cast<std::size_t>(w) * h), weight(v.size(), 0.0f);
  EXPECT_FALSE(pushPullFill(w, h, 1, v.data(), weight.data()));
  // One known pixel: everything takes its value.
  weight[5 * w + 7] = 1;
  v[5 * w + 7] = 42;
  ASSERT_TRUE(pushPullFill(w, h, 1, v.data(), weight.data()));
  for (float x : v)
    EXPECT_NEAR(x, 42.0f, 1e-4f);
  // Known columns at i = 0 and i = w − 1 of values 0 and 100: the fill stays within them and
  // grows from left to right along every row.
  std::fill(weight.begin(), weight.end(), 0.0f);
  for (int j = 0; j < h; ++j)
  {
    weight[static_cast<std::size_t>(j) * w] = weight[static_cast<std::size_t>(j) * w + w - 1] = 1;
    v[static_cast<std::size_t>(j) * w] = 0;
    v[static_cast<std::size_t>(j) * w + w - 1] = 100;
  }
  ASSERT_TRUE(pushPullFill(w, h, 1, v.data(), weight.data()));
  for (int j = 0; j < h; ++j)
  {
    EXPECT_EQ(v[static_cast<std::size_t>(j) * w], 0.0f);
    EXPECT_EQ(v[static_cast<std::size_t>(j) * w + w - 1], 100.0f);
    for (int i = 1; i < w; ++i)
      EXPECT_GE(v[static_cast<std::size_t>(j) * w + i] + 1e-3f,
                v[static_cast<std::size_t>(j) * w + i - 1]);
  }
}

TEST(FrameParameters, MassSpinAndCameraBetweenTwoFrames)
{
  FrameParameters a, b;
  a.spacetime.mass = 0.1;
  b.spacetime.mass = 1.2;
  a.spacetime.spin = 0.0;
  b.spacetime.spin = 0.6;
  a.position = Vec3(30, 0, 0);
  b.position = Vec3(0, 40, 0);
  const FrameParameters m = interpolateParameters(a, b, 0.5, CameraPath::Orbit);
  EXPECT_DOUBLE_EQ(m.spacetime.mass, 0.65);
  EXPECT_DOUBLE_EQ(m.spacetime.spin, 0.3);
  // Radius 35 on the bisector of the quarter turn.
  EXPECT_NEAR(m.position.norm(), 35.0, 1e-12);
  EXPECT_NEAR(m.position.x(), 35.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(m.position.y(), 35.0 / std::sqrt(2.0), 1e-12);
  // A third of the way: 30° round, radius 33⅓.
  const FrameParameters third = interpolateParameters(a, b, 1.0 / 3, CameraPath::Orbit);
  EXPECT_NEAR(std::atan2(third.position.y(), third.position.x()), M_PI / 6, 1e-12);
  EXPECT_NEAR(third.position.norm(), 100.0 / 3, 1e-12);
  // Linear: the chord's midpoint. Automatic: an orbit with a hole, a line in flat space.
  const FrameParameters line = interpolateParameters(a, b, 0.5, CameraPath::Linear);
  EXPECT_NEAR((line.position - Vec3(15, 20, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(
    (interpolateParameters(a, b, 0.5, CameraPath::Automatic).position - m.position).norm(), 0,
    1e-12);
  FrameParameters fa = a, fb = b;
  fa.spacetime.mass = fb.spacetime.mass = 0;
  EXPECT_NEAR(
    (interpolateParameters(fa, fb, 0.5, CameraPath::Automatic).position - line.position).norm(), 0,
    1e-12);
  // The ends are the frames' own values, to the bit.
  EXPECT_EQ(interpolateParameters(a, b, 0.0, CameraPath::Orbit).position, a.position);
  EXPECT_EQ(interpolateParameters(a, b, 1.0, CameraPath::Orbit).position, b.position);
  // No orbit between opposite directions.
  FrameParameters c = a;
  c.position = Vec3(-30, 0, 0);
  EXPECT_THROW(interpolateParameters(a, c, 0.5, CameraPath::Orbit), InvalidParameter);
}

TEST(ImageQuality, PsnrAndSsimAgainstClosedForms)
{
  const int w = 32, h = 24;
  std::vector<std::uint8_t> x(3 * w * h), y(3 * w * h);
  for (std::size_t k = 0; k < x.size(); ++k)
  {
    x[k] = static_cast<std::uint8_t>(100 + (k * 37) % 50);
    y[k] = static_cast<std::uint8_t>(x[k] + 5);
  }
  const RgbView vx{ w, h, x.data() }, vy{ w, h, y.data() };
  EXPECT_TRUE(std::isinf(psnr(vx, vx)));
  EXPECT_DOUBLE_EQ(ssim(vx, vx), 1.0);
  // A constant offset d: MSE = d².
  EXPECT_NEAR(psnr(vx, vy), 20.0 * std::log10(255.0 / 5.0), 1e-12);
  // Constant images μ and μ + d: only the luminance term of SSIM differs from 1.
  std::fill(x.begin(), x.end(), 80);
  std::fill(y.begin(), y.end(), 120);
  const double C1 = std::pow(0.01 * 255, 2);
  const double expected = (2.0 * 80 * 120 + C1) / (80.0 * 80 + 120.0 * 120 + C1);
  EXPECT_NEAR(ssim(vx, vy), expected, 1e-9);
  EXPECT_NEAR(ssim(vy, vx), expected, 1e-9);
  // A mask restricts both.
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(w) * h, 0);
  mask[static_cast<std::size_t>(10) * w + 10] = 1;
  EXPECT_NEAR(psnr(vx, vy, &mask), 20.0 * std::log10(255.0 / 40.0), 1e-12);
  std::vector<std::uint8_t> none(mask.size(), 0);
  EXPECT_THROW(psnr(vx, vy, &none), InvalidParameter);
  const RgbView small{ 8, 8, x.data() };
  EXPECT_THROW(ssim(small, small), InvalidParameter);
}

// Spearman's rank correlation against its closed form for distinct values,
// 1 − 6 Σ d² / (n (n² − 1)), and against ranks worked by hand where values tie.
TEST(ImageQuality, SpearmanAgainstItsClosedFormAndTies)
{
  const std::vector<double> x = { 3.0, 1.0, 4.0, 1.5, 5.0, 9.0, 2.0, 6.0 };
  const std::vector<double> y = { 2.0, 7.0, 1.0, 8.0, 2.5, 3.0, 9.0, 4.0 };
  auto rankOf = [](const std::vector<double>& v, std::size_t k)
  {
    double below = 0;
    for (double w : v)
      below += w < v[k];
    return below + 1;
  };
  double d2 = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
    d2 += std::pow(rankOf(x, k) - rankOf(y, k), 2);
  const double n = static_cast<double>(x.size());
  EXPECT_NEAR(spearman(x, y), 1.0 - 6.0 * d2 / (n * (n * n - 1.0)), 1e-12);
  // Monotone maps of either series leave it unchanged; reversing one negates it.
  std::vector<double> cubed = x, reversed = y;
  for (double& v : cubed)
    v = v * v * v;
  for (double& v : reversed)
    v = -v;
  EXPECT_NEAR(spearman(cubed, y), spearman(x, y), 1e-12);
  EXPECT_NEAR(spearman(x, reversed), -spearman(x, y), 1e-12);
  EXPECT_NEAR(spearman(x, x), 1.0, 1e-12);
  // Ties share their mean rank: x ranks 1, 2.5, 2.5, 4 and y ranks 1, 2, 3, 4, whose Pearson
  // correlation is 4.5 / sqrt(4.5 · 5) = 3 / sqrt(10).
  EXPECT_NEAR(spearman({ 0, 1, 1, 2 }, { 10, 20, 30, 40 }), 3.0 / std::sqrt(10.0), 1e-12);
  EXPECT_TRUE(std::isnan(spearman({ 1, 1, 1 }, { 1, 2, 3 })));
  EXPECT_THROW(spearman({ 1, 2 }, { 1, 2, 3 }), InvalidParameter);
  EXPECT_THROW(spearman({ 1 }, { 1 }), InvalidParameter);
}

TEST(FrameTracerSubpixel, TraceAtIsTracePixelAtPixelCentresAndMovesInBetween)
{
  // Sub-pixel rays check where an interpolated point should be: at integer positions they are
  // the pixels' own rays, and in flat space the hit point of a fronto-parallel plane moves
  // linearly with the position.
  const ImageLoader none = [](const std::string& path) -> ImagePixels
  { throw InvalidParameter("no images: " + path); };
  const SceneDescription d = parseScene(R"({"spacetime": {"mass": 0},
      "camera": {"position": [0, -10, 0], "focalPoint": [0, 0, 0], "resolution": [16, 16]},
      "objects": [{"type": "plane", "id": 0, "center": [0, 0, 0], "uAxis": [1, 0, 0],
                   "vAxis": [0, 0, 1], "texture": {"color": [1, 1, 1]}}]})",
                                        ".", none);
  const FrameTracer tracer(d);
  const RayRecord a = tracer.tracePixel(5, 7), b = tracer.traceAt(5.0, 7.0);
  EXPECT_EQ(a.hitPoint, b.hitPoint);
  EXPECT_EQ(a.affineLength, b.affineLength);
  EXPECT_EQ(a.i, b.i);
  EXPECT_EQ(a.j, b.j);
  const RayRecord c = tracer.traceAt(5.5, 7.0), e = tracer.tracePixel(6, 7);
  EXPECT_NEAR(c.hitPoint.x(), 0.5 * (a.hitPoint.x() + e.hitPoint.x()), 1e-12);
  EXPECT_NEAR(c.hitPoint.z(), a.hitPoint.z(), 1e-12);
}
