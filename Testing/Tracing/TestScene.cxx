// Scene objects against geometry worked out by hand: chord crossings of lines with spheres,
// cylinders, planes and annuli, surface coordinates at known points, textures, the scene's choice
// of the nearest hit, and the refinement of a hit on a curved segment, whose error must fall from
// the chord's O(h²) to the interpolant's O(h⁴).
#include "RayFixtures.h"
#include "Scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace asrt;

namespace
{
std::shared_ptr<const Texture> solid(double r = 0.5, double g = 0.5, double b = 0.5)
{
  return std::make_shared<SolidTexture>(Color(r, g, b));
}

/// A straight segment a → b: with both tangents b − a the Hermite cubic is the chord itself.
Segment straight(const Vec3& a, const Vec3& b)
{
  Segment s;
  s.x0 << 0.0, a;
  s.x1 << 1.0, b;
  s.d0 << 1.0, b - a;
  s.d1 = s.d0;
  return s;
}

/// The Hermite segment of a circular arc of radius R about the origin in the xy-plane, from angle
/// α0 to α0 + h: ends on the circle, tangents dx/dτ = h × (the circle's dx/dα). Its interpolant
/// leaves the circle by O(h⁴) R; the chord by O(h²) R.
Segment arc(double R, double alpha0, double h)
{
  const double a1 = alpha0 + h;
  Segment s;
  s.x0 << 0.0, R * std::cos(alpha0), R * std::sin(alpha0), 0.0;
  s.x1 << h * R, R * std::cos(a1), R * std::sin(a1), 0.0;
  s.d0 << h * R, -h * R * std::sin(alpha0), h * R * std::cos(alpha0), 0.0;
  s.d1 << h * R, -h * R * std::sin(a1), h * R * std::cos(a1), 0.0;
  return s;
}

const double inf = std::numeric_limits<double>::infinity();
}

// ---- chord tests --------------------------------------------------------------------------------
TEST(SceneChord, SphereAgainstLineSphereGeometry)
{
  const Vec3 c(1, 2, 3);
  const Sphere s(7, "ball", solid(), c, 2.0);
  SurfaceHit hit;

  // Through the centre along +x: enters at c − (2, 0, 0), 8 of the 20 units along.
  ASSERT_TRUE(s.intersect(straight(c - Vec3(10, 0, 0), c + Vec3(10, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 7);
  EXPECT_NEAR(hit.tau, 0.4, 1e-15);
  EXPECT_LT((hit.point - (c - Vec3(2, 0, 0))).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(-1, 0, 0)).norm(), 1e-14);

  // Impact parameter 1.2 in y: enters at x = −√(R² − b²) = −1.6 from the centre.
  ASSERT_TRUE(s.intersect(straight(c + Vec3(-10, 1.2, 0), c + Vec3(10, 1.2, 0)), hit));
  EXPECT_LT((hit.point - (c + Vec3(-1.6, 1.2, 0))).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(-0.8, 0.6, 0)).norm(), 1e-14);

  // Impact parameter above R misses; a segment that stops short misses.
  EXPECT_FALSE(s.intersect(straight(c + Vec3(-10, 2.01, 0), c + Vec3(10, 2.01, 0)), hit));
  EXPECT_FALSE(s.intersect(straight(c - Vec3(10, 0, 0), c - Vec3(2.1, 0, 0)), hit));

  // Starting inside: the exit point, with the normal facing back inwards (towards the ray).
  ASSERT_TRUE(s.intersect(straight(c, c + Vec3(0, 0, 4)), hit));
  EXPECT_NEAR(hit.tau, 0.5, 1e-15);
  EXPECT_LT((hit.point - (c + Vec3(0, 0, 2))).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(0, 0, -1)).norm(), 1e-14);
}

TEST(SceneChord, CylinderAgainstLineCylinderGeometry)
{
  // Axis along z (given unnormalised) from z = −5 to 5, radius 1.
  const Cylinder cyl(1, "pipe", solid(), Vec3(0, 0, -5), Vec3(0, 0, 2), 1.0, 10.0);
  SurfaceHit hit;

  // A line along x at y = 0.5, z = 1: meets x² + y² = 1 at x = −√0.75.
  const double x = -std::sqrt(0.75);
  ASSERT_TRUE(cyl.intersect(straight(Vec3(-10, 0.5, 1), Vec3(10, 0.5, 1)), hit));
  EXPECT_NEAR(hit.tau, (10 + x) / 20, 1e-15);
  EXPECT_LT((hit.point - Vec3(x, 0.5, 1)).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(x, 0.5, 0)).norm(), 1e-14);
  // u = φ/2π about +z from +x (φ = 150°), v = height fraction (1 + 5)/10.
  EXPECT_NEAR(hit.u, 150.0 / 360.0, 1e-14);
  EXPECT_NEAR(hit.v, 0.6, 1e-14);

  // Above the top end (z = 6) the infinite cylinder is crossed but not this one.
  EXPECT_FALSE(cyl.intersect(straight(Vec3(-10, 0.5, 6), Vec3(10, 0.5, 6)), hit));

  // Through the open top onto the inner wall: x = 3τ, z = 7 − 12τ meets x = 1 at τ = 1/3, z = 3.
  ASSERT_TRUE(cyl.intersect(straight(Vec3(0, 0, 7), Vec3(3, 0, -5)), hit));
  EXPECT_NEAR(hit.tau, 1.0 / 3.0, 1e-15);
  EXPECT_LT((hit.point - Vec3(1, 0, 3)).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(-1, 0, 0)).norm(), 1e-14); // the inner side faces the ray

  // Parallel to the axis, inside: never meets the wall.
  EXPECT_FALSE(cyl.intersect(straight(Vec3(0.3, 0, -20), Vec3(0.3, 0, 20)), hit));
  // A line passing beside it.
  EXPECT_FALSE(cyl.intersect(straight(Vec3(-10, 1.01, 0), Vec3(10, 1.01, 0)), hit));
}

TEST(SceneChord, PlaneAndRectangleAgainstLinePlaneGeometry)
{
  const Rectangle plane(2, "floor", solid(), Vec3(0, 0, -2), Vec3(1, 0, 0), Vec3(0, 1, 0), inf, inf,
                        2.0);
  EXPECT_STREQ(plane.type(), "plane");
  SurfaceHit hit;
  ASSERT_TRUE(plane.intersect(straight(Vec3(3, 4.5, 10), Vec3(3, 4.5, -10)), hit));
  EXPECT_NEAR(hit.tau, 0.6, 1e-15);
  EXPECT_LT((hit.point - Vec3(3, 4.5, -2)).norm(), 1e-14);
  EXPECT_LT((hit.normal - Vec3(0, 0, 1)).norm(), 1e-15);
  // Tiles of 2 M from the centre: u = frac(3/2), v = frac(4.5/2).
  EXPECT_NEAR(hit.u, 0.5, 1e-14);
  EXPECT_NEAR(hit.v, 0.25, 1e-14);
  // Negative coordinates wrap into [0, 1).
  ASSERT_TRUE(plane.intersect(straight(Vec3(-0.5, -3.5, 1), Vec3(-0.5, -3.5, -3)), hit));
  EXPECT_NEAR(hit.u, 0.75, 1e-14);
  EXPECT_NEAR(hit.v, 0.25, 1e-14);

  // Far out it still counts: the plane is infinite.
  EXPECT_TRUE(plane.intersect(straight(Vec3(1e5, -3e5, 1), Vec3(1e5, -3e5, -3)), hit));
  // Parallel, and stopping short.
  EXPECT_FALSE(plane.intersect(straight(Vec3(0, 0, -1), Vec3(10, 0, -1)), hit));
  EXPECT_FALSE(plane.intersect(straight(Vec3(0, 0, 10), Vec3(0, 0, -1.9)), hit));

  // A rectangle in a tilted plane; vAxis is given with a part along uAxis, which must be removed.
  const Vec3 c(1, 1, 1);
  const Vec3 eu = Vec3(1, 1, 0).normalized(), ev(0, 0, 1);
  const Vec3 n = eu.cross(ev);
  const Rectangle rect(3, "board", solid(), c, Vec3(1, 1, 0), Vec3(2, 2, 1), 2.0, 1.0);
  EXPECT_STREQ(rect.type(), "rectangle");
  const double in = 1 - 1e-9, out = 1 + 1e-9;
  for (const int su : { -1, 1 })
  {
    for (const int sv : { -1, 1 })
    {
      const Vec3 corner = c + su * 2.0 * eu + sv * 1.0 * ev;
      const Vec3 inside = c + in * (su * 2.0 * eu + sv * 1.0 * ev);
      ASSERT_TRUE(rect.intersect(straight(inside + 5 * n, inside - 5 * n), hit));
      EXPECT_LT((hit.point - corner).norm(), 1e-8);
      EXPECT_NEAR(hit.u, su > 0 ? 1.0 : 0.0, 1e-8);
      EXPECT_NEAR(hit.v, sv > 0 ? 1.0 : 0.0, 1e-8);
      EXPECT_LT((hit.normal - n).norm(), 1e-14); // n faces the ray, which runs along −n
      const Vec3 outside = c + out * (su * 2.0 * eu + sv * 1.0 * ev);
      EXPECT_FALSE(rect.intersect(straight(outside + 5 * n, outside - 5 * n), hit));
    }
  }
  // The centre is (½, ½).
  ASSERT_TRUE(rect.intersect(straight(c - 3 * n, c + 3 * n), hit));
  EXPECT_NEAR(hit.u, 0.5, 1e-14);
  EXPECT_NEAR(hit.v, 0.5, 1e-14);
  EXPECT_LT((hit.normal + n).norm(), 1e-14); // from the other side the normal flips
}

TEST(SceneChord, DiskAnnulusHoleAndOutside)
{
  const Disk disk(4, "disk", solid(), Vec3(0, 0, 1), Vec3(0, 0, 3), 2.0, 5.0);
  SurfaceHit hit;
  auto down = [](double x, double y) { return straight(Vec3(x, y, 11), Vec3(x, y, -9)); };
  // Through the hole, outside the rim: no hit.
  EXPECT_FALSE(disk.intersect(down(1, 0), hit));
  EXPECT_FALSE(disk.intersect(down(0, 1.99), hit));
  EXPECT_FALSE(disk.intersect(down(6, 0), hit));
  EXPECT_FALSE(disk.intersect(down(3.6, 3.6), hit)); // ρ = 5.09
  // On the annulus: τ = 0.5 at z = 1; u = angle/2π from +x about +z, v = (ρ − 2)/3.
  ASSERT_TRUE(disk.intersect(down(3, 0), hit));
  EXPECT_NEAR(hit.tau, 0.5, 1e-15);
  EXPECT_LT((hit.point - Vec3(3, 0, 1)).norm(), 1e-14);
  EXPECT_NEAR(hit.u, 0.0, 1e-15);
  EXPECT_NEAR(hit.v, 1.0 / 3.0, 1e-14);
  EXPECT_LT((hit.normal - Vec3(0, 0, 1)).norm(), 1e-15);
  ASSERT_TRUE(disk.intersect(down(0, -4), hit));
  EXPECT_NEAR(hit.u, 0.75, 1e-14);
  EXPECT_NEAR(hit.v, 2.0 / 3.0, 1e-14);
  ASSERT_TRUE(disk.intersect(down(-2.4, 3.2), hit)); // ρ = 4 at 126.87°
  EXPECT_NEAR(hit.u, std::atan2(3.2, -2.4) / (2 * M_PI), 1e-14);
  EXPECT_NEAR(hit.v, 2.0 / 3.0, 1e-14);
  // Edges: just inside each rim hits, just outside misses.
  EXPECT_TRUE(disk.intersect(down(2.000001, 0), hit));
  EXPECT_TRUE(disk.intersect(down(4.999999, 0), hit));
  EXPECT_FALSE(disk.intersect(down(1.999999, 0), hit));
  EXPECT_FALSE(disk.intersect(down(5.000001, 0), hit));
  // A chord lying in the disk's plane does not cross it.
  EXPECT_FALSE(disk.intersect(straight(Vec3(-10, 3, 1), Vec3(10, 3, 1)), hit));
}

TEST(SceneChord, CelestialSphereSeenFromInside)
{
  const CelestialSphere sky(0, "sky", solid(), 100.0);
  SurfaceHit hit;
  // From the centre straight up: the north pole at τ = ½, v = 1.
  ASSERT_TRUE(sky.intersect(straight(Vec3::Zero(), Vec3(0, 0, 200)), hit));
  EXPECT_NEAR(hit.tau, 0.5, 1e-15);
  EXPECT_LT((hit.point - Vec3(0, 0, 100)).norm(), 1e-12);
  EXPECT_NEAR(hit.v, 1.0, 1e-15);
  EXPECT_LT((hit.normal - Vec3(0, 0, -1)).norm(), 1e-15); // facing inwards, towards the ray
  // From an off-centre start inside, down to the south pole.
  ASSERT_TRUE(sky.intersect(straight(Vec3(0, 0, 30), Vec3(0, 0, -170)), hit));
  EXPECT_NEAR(hit.tau, 0.65, 1e-15);
  EXPECT_NEAR(hit.v, 0.0, 1e-15);
  // A chord through the whole sphere from outside counts only where it leaves.
  ASSERT_TRUE(sky.intersect(straight(Vec3(-200, 0, 0), Vec3(200, 0, 0)), hit));
  EXPECT_NEAR(hit.tau, 0.75, 1e-15);
  EXPECT_NEAR(hit.u, 0.0, 1e-15);
  EXPECT_NEAR(hit.v, 0.5, 1e-15);
  // A ray at 30° from +y in the plane z = 0, from a point inside: line–sphere by hand,
  // |p + s d|² = R² with p = (10, 0, 0), d = (−sin 30°, cos 30°, 0): s = −p·d + √((p·d)² − |p|² +
  // R²).
  const Vec3 p(10, 0, 0), d(-0.5, std::sqrt(3.0) / 2, 0);
  const double pd = p.dot(d);
  const double s = -pd + std::sqrt(pd * pd - p.squaredNorm() + 100.0 * 100.0);
  ASSERT_TRUE(sky.intersect(straight(p, p + 150 * d), hit));
  EXPECT_NEAR(hit.tau, s / 150, 1e-14);
  EXPECT_LT((hit.point - (p + s * d)).norm(), 1e-12);
  EXPECT_NEAR(hit.u, std::atan2((p + s * d).y(), (p + s * d).x()) / (2 * M_PI), 1e-14);
  // Inside throughout, or moving inwards from outside: nothing.
  EXPECT_FALSE(sky.intersect(straight(Vec3(0, 0, -50), Vec3(0, 0, 50)), hit));
  EXPECT_FALSE(sky.intersect(straight(Vec3(0, 0, 300), Vec3(0, 0, 0)), hit));
}

// ---- surface coordinates ------------------------------------------------------------------------
TEST(SceneSurface, SpherePolesAndEquator)
{
  const Vec3 c(-3, 4, 2);
  const Sphere s(1, "ball", solid(), c, 1.5);
  SurfaceHit hit;
  auto from = [&](const Vec3& dir)
  {
    EXPECT_TRUE(s.intersect(straight(c + 10 * dir, c), hit));
    return std::make_pair(hit.u, hit.v);
  };
  EXPECT_NEAR(from(Vec3(0, 0, 1)).second, 1.0, 1e-15);  // north pole
  EXPECT_NEAR(from(Vec3(0, 0, -1)).second, 0.0, 1e-15); // south pole
  const double quarter[4][3] = { { 1, 0, 0 }, { 0, 1, 0 }, { -1, 0, 0 }, { 0, -1, 0 } };
  for (int k = 0; k < 4; ++k)
  {
    const auto uv = from(Vec3(quarter[k][0], quarter[k][1], quarter[k][2]));
    EXPECT_NEAR(uv.first, 0.25 * k, 1e-15) << k;
    EXPECT_NEAR(uv.second, 0.5, 1e-15) << k;
  }
  // 30° above the equator at φ = 45°: v = 1 − 60°/180°.
  const Vec3 dir(std::cos(M_PI / 6) * std::sqrt(0.5), std::cos(M_PI / 6) * std::sqrt(0.5), 0.5);
  const auto uv = from(dir);
  EXPECT_NEAR(uv.first, 0.125, 1e-14);
  EXPECT_NEAR(uv.second, 2.0 / 3.0, 1e-14);
}

TEST(SceneSurface, CylinderAngleFromTheDocumentedReference)
{
  // perpendicularBasis: for an axis along x the reference is y, then z a quarter turn on.
  Vec3 e1, e2;
  perpendicularBasis(Vec3(1, 0, 0), e1, e2);
  EXPECT_EQ(e1, Vec3(0, 1, 0));
  EXPECT_EQ(e2, Vec3(0, 0, 1));
  perpendicularBasis(Vec3(0, 0, 1), e1, e2);
  EXPECT_EQ(e1, Vec3(1, 0, 0));
  EXPECT_EQ(e2, Vec3(0, 1, 0));
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (int k = 0; k < 100; ++k)
  {
    const Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    perpendicularBasis(n, e1, e2);
    EXPECT_NEAR(e1.norm(), 1.0, 1e-15);
    EXPECT_NEAR(e1.dot(n), 0.0, 1e-14);
    EXPECT_LT((e1.cross(e2) - n).norm(), 1e-14);
  }

  const Cylinder cyl(1, "x", solid(), Vec3(-15, 0, 0), Vec3(1, 0, 0), 0.5, 30.0);
  SurfaceHit hit;
  // At x = 0 (the middle, v = ½), on +y (u = 0), +z (¼), −y (½), −z (¾).
  const Vec3 radial[4] = { Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(0, 0, -1) };
  for (int k = 0; k < 4; ++k)
  {
    ASSERT_TRUE(cyl.intersect(straight(5 * radial[k], Vec3::Zero()), hit));
    EXPECT_LT((hit.point - 0.5 * radial[k]).norm(), 1e-15);
    EXPECT_NEAR(hit.u, 0.25 * k, 1e-15) << k;
    EXPECT_NEAR(hit.v, 0.5, 1e-15) << k;
  }
  // The ends: v = 0 at the base, 1 at the top.
  ASSERT_TRUE(cyl.intersect(straight(Vec3(-15, 5, 0), Vec3(-15, 0, 0)), hit));
  EXPECT_NEAR(hit.v, 0.0, 1e-15);
  ASSERT_TRUE(cyl.intersect(straight(Vec3(15, 5, 0), Vec3(15, 0, 0)), hit));
  EXPECT_NEAR(hit.v, 1.0, 1e-15);
}

// ---- refinement on the Hermite interpolant ------------------------------------------------------
namespace
{
struct ArcErrors
{
  double chord, refined;
  bool wasRefined;
};

/// The arc of radius 10 crossing the plane through the z-axis at angle β = α0 + 0.37 h: the true
/// crossing is exactly 10 (cos β, sin β, 0).
ArcErrors planeArcErrors(double h)
{
  const double R = 10, alpha0 = 0.3, beta = alpha0 + 0.37 * h;
  const Rectangle plane(1, "p", solid(), Vec3::Zero(), Vec3(std::cos(beta), std::sin(beta), 0),
                        Vec3(0, 0, 1), inf, inf);
  SurfaceHit hit;
  EXPECT_TRUE(plane.intersect(arc(R, alpha0, h), hit));
  const Vec3 truth(R * std::cos(beta), R * std::sin(beta), 0);
  return { (hit.chordPoint - truth).norm(), (hit.point - truth).norm(), hit.refined };
}

/// The same arc leaving a sphere of radius 5 about (12, 0, 0): the circles |x| = 10 and
/// |x − (12, 0, 0)| = 5 meet where cos α* = (10² + 12² − 5²)/(2·10·12).
ArcErrors sphereArcErrors(double h)
{
  const double R = 10, alphaStar = std::acos(219.0 / 240.0);
  const Sphere ball(1, "b", solid(), Vec3(12, 0, 0), 5.0);
  SurfaceHit hit;
  EXPECT_TRUE(ball.intersect(arc(R, alphaStar - 0.6 * h, h), hit));
  const Vec3 truth(R * std::cos(alphaStar), R * std::sin(alphaStar), 0);
  return { (hit.chordPoint - truth).norm(), (hit.point - truth).norm(), hit.refined };
}
}

TEST(SceneRefine, CurvedSegmentHitIsFourthOrderAgainstTheChordsSecond)
{
  for (auto errors : { planeArcErrors, sphereArcErrors })
  {
    const double hs[] = { 0.2, 0.1, 0.05 };
    ArcErrors e[3];
    for (int k = 0; k < 3; ++k)
    {
      e[k] = errors(hs[k]);
      EXPECT_TRUE(e[k].wasRefined);
      std::cout << "[ info ] h = " << hs[k] << ": chord error " << e[k].chord << ", refined error "
                << e[k].refined << "\n";
    }
    for (int k = 0; k < 2; ++k)
    {
      // Halving h: the chord's error falls 4×, the refined point's 16×.
      EXPECT_NEAR(std::log2(e[k].chord / e[k + 1].chord), 2.0, 0.15) << k;
      EXPECT_NEAR(std::log2(e[k].refined / e[k + 1].refined), 4.0, 0.3) << k;
    }
    // At h = 0.1 (a 1 M step on this 10 M circle) refinement gains three orders of magnitude.
    EXPECT_LT(e[1].refined, 1e-3 * e[1].chord);
  }
}

namespace
{
/// An arc of radius 10 crossing the plane through the z-axis along `eu`, and where its chord
/// crosses that plane: at a radius below the arc's, by the step's sagitta.
struct ArcThroughPlane
{
  double R = 10, alpha0 = 0.3, h = 0.2, beta = alpha0 + 0.37 * h;
  Vec3 eu{ std::cos(beta), std::sin(beta), 0 };
  Segment seg = arc(R, alpha0, h);
  double rhoChord = 0;
  ArcThroughPlane()
  {
    SurfaceHit full;
    EXPECT_TRUE(
      Rectangle(1, "p", solid(), Vec3::Zero(), eu, Vec3(0, 0, 1), inf, inf).intersect(seg, full));
    rhoChord = full.chordPoint.norm();
  }
  /// The strip of the plane between radii lo and hi along eu.
  Rectangle strip(double lo, double hi) const
  {
    return Rectangle(1, "s", solid(), 0.5 * (lo + hi) * eu, eu, Vec3(0, 0, 1), 0.5 * (hi - lo),
                     1.0);
  }
};
}

TEST(SceneRefine, MissesWhereTheCurveCrossesBeyondTheEdgeThoughTheChordCrossesInside)
{
  const ArcThroughPlane a;
  ASSERT_LT(a.rhoChord, a.R - 0.01);
  // The ray itself crosses the plane at radius R; the strip ends halfway between the chord's
  // crossing and R, so the ray passes beyond its edge.
  SurfaceHit hit;
  EXPECT_FALSE(a.strip(0.0, 0.5 * (a.rhoChord + a.R)).intersect(a.seg, hit));
}

TEST(SceneRefine, HitsWhereTheCurveCrossesInsideThoughTheChordCrossesBeyondTheEdge)
{
  const ArcThroughPlane a;
  ASSERT_LT(a.rhoChord, a.R - 0.01);
  SurfaceHit hit;
  ASSERT_TRUE(a.strip(0.5 * (a.rhoChord + a.R), a.R + 1.0).intersect(a.seg, hit));
  EXPECT_TRUE(hit.refined);
  // The hit is the ray's own crossing, exactly R along eu.
  EXPECT_LT((hit.point - a.R * a.eu).norm(), 1e-2 * (a.R - a.rhoChord));
}

TEST(SceneRefine, FallsBackToBisectionWhereNewtonCannotStep)
{
  // x(τ) = τ and z(τ) = −8τ³ + 10τ² − 4τ + 1 (the Hermite cubic of these ends and tangents): the
  // chord crosses z = 0 at τ = ½, where z' = −4(2τ − 1)(3τ − 1) vanishes, so Newton has no step.
  // z > 0 on [0, ½] (its minimum is 13/27 at τ = ⅓), so the curve's one crossing lies in (½, 1).
  Segment seg;
  seg.x0 << 0, 0, 0, 1;
  seg.x1 << 0, 1, 0, -1;
  seg.d0 << 0, 1, 0, -4;
  seg.d1 << 0, 1, 0, -8;
  auto z = [](double t) { return ((-8 * t + 10) * t - 4) * t + 1; };
  ASSERT_NEAR(seg.position(0.3)[3], z(0.3), 1e-15);
  const Rectangle plane(1, "z=0", solid(), Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), inf, inf);
  SurfaceHit hit;
  ASSERT_TRUE(plane.intersect(seg, hit));
  EXPECT_LT((hit.chordPoint - Vec3(0.5, 0, 0)).norm(), 1e-15);
  EXPECT_TRUE(hit.refined);
  EXPECT_GT(hit.tau, 0.5);
  EXPECT_LT(std::abs(z(hit.tau)), 1e-14);
  EXPECT_LT((hit.point - Vec3(hit.tau, 0, 0)).norm(), 1e-14);
}

TEST(SceneRefine, IntegratedRayCrossingAPlane)
{
  // A Schwarzschild ray bending around the hole (b = 6 M from 8 M) crosses the plane x = 0. The
  // step that crosses it, refined, against the same crossing found on steps 64 times shorter.
  const SchwarzschildSpacetime st(1.0);
  const PhasePoint z = asrt::testing::equatorialRay(st, 8.0, 6.0);
  const Rectangle plane(1, "x=0", solid(), Vec3::Zero(), Vec3(0, 1, 0), Vec3(0, 0, 1), inf, inf);
  auto crossing = [&](double h, SurfaceHit& hit)
  {
    GeneralPropagator prop(st, std::make_unique<GaussLegendre>(3), h, true);
    prop.start(z);
    Segment seg;
    for (int k = 0; k < 100000; ++k)
    {
      if (!prop.advance(seg))
        return false;
      if (plane.intersect(seg, hit))
        return true;
    }
    return false;
  };
  SurfaceHit coarse, fine;
  ASSERT_TRUE(crossing(0.2, coarse));
  ASSERT_TRUE(crossing(0.2 / 64, fine));
  EXPECT_TRUE(coarse.refined);
  const double chordErr = (coarse.chordPoint - fine.point).norm();
  const double refinedErr = (coarse.point - fine.point).norm();
  std::cout << "[ info ] integrated ray, h = 0.2: chord error " << chordErr << ", refined error "
            << refinedErr << "\n";
  EXPECT_GT(chordErr, 1e-4); // the step is coarse enough for the chord to be visibly off
  EXPECT_LT(refinedErr, 1e-2 * chordErr);
}

// ---- textures -----------------------------------------------------------------------------------
TEST(SceneTexture, CheckerParity)
{
  const Color a(1, 0, 0), b(0, 0, 1);
  const CheckerTexture t(4, 2, a, b);
  EXPECT_EQ(t.sample(0.125, 0.25), a); // check (0, 0)
  EXPECT_EQ(t.sample(0.375, 0.25), b); // (1, 0)
  EXPECT_EQ(t.sample(0.375, 0.75), a); // (1, 1)
  EXPECT_EQ(t.sample(0.875, 0.75), a); // (3, 1)
  EXPECT_EQ(t.sample(0.875, 0.25), b); // (3, 0)
  // Periodic: one period on, or negative, lands on the same check.
  EXPECT_EQ(t.sample(1.375, 0.25), b);
  EXPECT_EQ(t.sample(-0.625, 0.25), b);
  EXPECT_EQ(t.sample(0.125, -0.75), a);
  // The last check's far edge wraps to the first.
  EXPECT_EQ(t.sample(1.0, 0.25), a);
  EXPECT_THROW(CheckerTexture(0, 2, a, b), InvalidParameter);
  EXPECT_THROW(CheckerTexture(2, 2, a, Color(0, 2, 0)), InvalidParameter);
  EXPECT_THROW(SolidTexture(Color(0, std::nan(""), 0)), InvalidParameter);
}

TEST(SceneTexture, ImageBilinearPeriodicInUClampedInV)
{
  // 4 × 2 pixels; red = 10 × column + 100 × row, green = 255 − red, blue = 7.
  const int W = 4, H = 2;
  std::vector<std::uint8_t> rgb;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
    {
      const int r = 10 * i + 100 * j;
      rgb.insert(rgb.end(), { std::uint8_t(r), std::uint8_t(255 - r), 7 });
    }
  const ImageTexture t(W, H, rgb);
  auto red = [&](double u, double v) { return 255.0 * t.sample(u, v)[0]; };
  // At pixel centres: the pixel itself.
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
    {
      const Color c = t.sample((i + 0.5) / W, (j + 0.5) / H);
      EXPECT_NEAR(255.0 * c[0], 10 * i + 100 * j, 1e-12);
      EXPECT_NEAR(255.0 * c[1], 255 - (10 * i + 100 * j), 1e-12);
      EXPECT_NEAR(255.0 * c[2], 7, 1e-12);
    }
  // Halfway between centres: the mean; at a quarter: the weighted mean.
  EXPECT_NEAR(red(1.0 / W, 0.25), 5.0, 1e-12);
  EXPECT_NEAR(red(2.0 / W, 0.5), 0.25 * (10 + 20 + 110 + 120), 1e-12); // four centres around it
  EXPECT_NEAR(red(1.5 / W, 0.5), 0.5 * (10 + 110), 1e-12);             // on column 1
  EXPECT_NEAR(red(0.875 / W, 0.25), 3.75, 1e-12);
  // u = 0 lies between the last column and the first: periodic.
  EXPECT_NEAR(red(0.0, 0.25), 0.5 * (30 + 0), 1e-12);
  EXPECT_NEAR(red(1.0, 0.25), red(0.0, 0.25), 1e-12);
  for (double u : { 0.1, 0.37, 0.93 })
  {
    EXPECT_NEAR(red(u + 1, 0.6), red(u, 0.6), 1e-9);
    EXPECT_NEAR(red(u - 3, 0.6), red(u, 0.6), 1e-9);
  }
  // v is clamped: beyond the outer centres, the edge row.
  EXPECT_NEAR(red(0.625, 0.0), 20.0, 1e-12);
  EXPECT_NEAR(red(0.625, -2.0), 20.0, 1e-12);
  EXPECT_NEAR(red(0.625, 1.0), 120.0, 1e-12);
  EXPECT_THROW(ImageTexture(4, 2, std::vector<std::uint8_t>(23)), InvalidParameter);
  EXPECT_THROW(ImageTexture(0, 2, {}), InvalidParameter);
}

// ---- the scene ----------------------------------------------------------------------------------
TEST(SceneFirstHit, PicksTheNearestObject)
{
  Scene scene;
  // Added far to near, so that insertion order cannot explain the answer.
  scene.add(std::make_unique<CelestialSphere>(0, "sky", solid(0, 0, 1), 100.0));
  scene.add(std::make_unique<Sphere>(2, "far", solid(0, 1, 0), Vec3(20, 0, 0), 1.0));
  scene.add(std::make_unique<Sphere>(1, "near", solid(1, 0, 0), Vec3(10, 0, 0), 1.0));
  SurfaceHit hit;
  ASSERT_TRUE(scene.firstHit(straight(Vec3::Zero(), Vec3(200, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 1);
  EXPECT_NEAR(hit.tau, 9.0 / 200, 1e-15);
  EXPECT_EQ(scene.shade(hit), Color(1, 0, 0));
  // Starting past the near one.
  ASSERT_TRUE(scene.firstHit(straight(Vec3(12, 0, 0), Vec3(200, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 2);
  // Missing both spheres: the sky.
  ASSERT_TRUE(scene.firstHit(straight(Vec3(0, 5, 0), Vec3(200, 5, 0)), hit));
  EXPECT_EQ(hit.objectId, 0);
  EXPECT_EQ(scene.shade(hit), Color(0, 0, 1));
  // Nothing at all inside the sky.
  EXPECT_FALSE(scene.firstHit(straight(Vec3(0, 5, 0), Vec3(50, 5, 0)), hit));
  EXPECT_EQ(scene.celestialRadius(), 100.0);
  EXPECT_EQ(scene.find(2)->name(), "far");
  EXPECT_EQ(scene.find(5), nullptr);
  SurfaceHit unknown;
  unknown.objectId = 5;
  scene.background = Color(0.1, 0.2, 0.3);
  EXPECT_EQ(scene.shade(unknown), scene.background);
}

TEST(SceneFirstHit, BoundingRejectionNeverLosesAHit)
{
  // Random segments through a cluttered scene: firstHit (with its bounding-ball rejection) must
  // find exactly the nearest of the objects' own intersections.
  Scene scene;
  scene.add(std::make_unique<Sphere>(1, "s", solid(), Vec3(1, 2, 0), 1.5));
  scene.add(std::make_unique<Cylinder>(2, "c", solid(), Vec3(-3, -3, -3), Vec3(1, 1, 2), 0.7, 6));
  scene.add(std::make_unique<Disk>(3, "d", solid(), Vec3(0, -2, 1), Vec3(0, 1, 1), 1.0, 3.0));
  scene.add(std::make_unique<Rectangle>(4, "r", solid(), Vec3(2, -1, 2), Vec3(1, 0, 0),
                                        Vec3(0, 1, 0), 1.0, 2.5));
  scene.add(std::make_unique<Rectangle>(5, "p", solid(), Vec3(0, 0, -4), Vec3(1, 0, 0),
                                        Vec3(0, 1, 0), inf, inf));
  scene.add(std::make_unique<CelestialSphere>(6, "sky", solid(), 8.0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(-7, 7), len(0.01, 4);
  int hits = 0;
  for (int k = 0; k < 20000; ++k)
  {
    const Vec3 a(x(rng), x(rng), x(rng));
    const Vec3 d = Vec3(x(rng), x(rng), x(rng)).normalized();
    const Segment seg = straight(a, a + len(rng) * d);
    bool want = false;
    SurfaceHit best, h;
    for (const auto& o : scene.objects())
    {
      if (o->intersect(seg, h) && (!want || h.tau < best.tau))
      {
        best = h;
        want = true;
      }
    }
    SurfaceHit got;
    ASSERT_EQ(scene.firstHit(seg, got), want) << k;
    if (want)
    {
      ++hits;
      EXPECT_EQ(got.objectId, best.objectId) << k;
      EXPECT_EQ(got.tau, best.tau) << k;
    }
  }
  EXPECT_GT(hits, 2000); // the test exercised hits, not only misses
}

TEST(SceneFirstHit, RejectsDuplicateIdsAndNull)
{
  Scene scene;
  scene.add(std::make_unique<Sphere>(3, "a", solid(), Vec3::Zero(), 1.0));
  try
  {
    scene.add(std::make_unique<Sphere>(3, "b", solid(), Vec3(5, 0, 0), 1.0));
    FAIL() << "duplicate id accepted";
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("id 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(scene.add(nullptr), InvalidParameter);
  EXPECT_EQ(scene.objects().size(), 1u);
}

TEST(SceneValidation, ConstructorsRefuseDegenerateGeometry)
{
  const double nan = std::nan("");
  const Vec3 o = Vec3::Zero(), z(0, 0, 1), x(1, 0, 0);
  EXPECT_THROW(Sphere(1, "s", solid(), o, -1.0), InvalidParameter);
  EXPECT_THROW(Sphere(1, "s", solid(), o, 0.0), InvalidParameter);
  EXPECT_THROW(Sphere(1, "s", solid(), Vec3(nan, 0, 0), 1.0), InvalidParameter);
  EXPECT_THROW(Sphere(-2, "s", solid(), o, 1.0), InvalidParameter);
  EXPECT_THROW(Sphere(1, "s", nullptr, o, 1.0), InvalidParameter);
  EXPECT_THROW(CelestialSphere(0, "sky", solid(), inf), InvalidParameter);
  EXPECT_THROW(Cylinder(1, "c", solid(), o, Vec3::Zero(), 1.0, 1.0), InvalidParameter);
  EXPECT_THROW(Cylinder(1, "c", solid(), o, Vec3(inf, 0, 0), 1.0, 1.0), InvalidParameter);
  EXPECT_THROW(Cylinder(1, "c", solid(), o, z, 1.0, -1.0), InvalidParameter);
  EXPECT_THROW(Cylinder(1, "c", solid(), o, z, nan, 1.0), InvalidParameter);
  EXPECT_THROW(Disk(1, "d", solid(), o, z, 3.0, 3.0), InvalidParameter);
  EXPECT_THROW(Disk(1, "d", solid(), o, z, 4.0, 3.0), InvalidParameter);
  EXPECT_THROW(Disk(1, "d", solid(), o, z, -1.0, 3.0), InvalidParameter);
  EXPECT_THROW(Disk(1, "d", solid(), o, Vec3::Zero(), 1.0, 3.0), InvalidParameter);
  EXPECT_NO_THROW(Disk(1, "d", solid(), o, z, 0.0, 3.0)); // a full disk
  EXPECT_THROW(Rectangle(1, "r", solid(), o, x, 2 * x, 1, 1), InvalidParameter);
  EXPECT_THROW(Rectangle(1, "r", solid(), o, x, z, 0, 1), InvalidParameter);
  EXPECT_THROW(Rectangle(1, "r", solid(), o, x, z, nan, 1), InvalidParameter);
  EXPECT_THROW(Rectangle(1, "r", solid(), o, x, z, inf, inf, 0.0), InvalidParameter);
  try
  {
    Disk(1, "d", solid(), o, z, 4.0, 3.0);
  }
  catch (const InvalidParameter& e)
  {
    EXPECT_NE(std::string(e.what()).find("outer radius"), std::string::npos) << e.what();
  }
}

namespace
{
/// (u, v) of the object at x, read through the public path: a short straight segment crossing
/// the surface there along its normal (from the tangents of surfacePoint), in either direction.
bool uvThrough(const SceneObject& o, double u, double v, double& uu, double& vv)
{
  const double d = 1e-4;
  const Vec3 x = o.surfacePoint(u, v);
  const Vec3 n = (o.surfacePoint(u + d, v) - o.surfacePoint(u - d, v))
                   .cross(o.surfacePoint(u, v + d) - o.surfacePoint(u, v - d))
                   .normalized();
  const double reach = 1e-3 * std::max(1.0, x.norm());
  SurfaceHit hit;
  if (!o.intersect(straight(x + reach * n, x - reach * n), hit) &&
      !o.intersect(straight(x - reach * n, x + reach * n), hit))
    return false;
  uu = hit.u;
  vv = hit.v;
  return true;
}
}

TEST(SceneGeometry, SurfacePointInvertsSurfaceCoordinates)
{
  // Drawing an object samples surfacePoint(u, v); a hit's (u, v) comes from surfaceCoordinates.
  // They must be inverse maps, or drawn textures would not line up with traced ones.
  const auto t = std::make_shared<SolidTexture>(Color(1, 1, 1));
  const CelestialSphere sky(0, "sky", t, 500.0);
  const Rectangle rect(1, "rect", t, Vec3(1, 2, 3), Vec3(1, 0, 0), Vec3(0, 0.6, 0.8), 4.0, 2.0);
  const Rectangle plane(2, "plane", t, Vec3(0, 0, -5), Vec3(1, 0, 0), Vec3(0, 1, 0), INFINITY,
                        INFINITY, 3.0);
  const Cylinder cyl(3, "cyl", t, Vec3(0, 0, -10), Vec3(0, 1, 1), 0.5, 20.0);
  const Sphere ball(4, "ball", t, Vec3(3, -2, 1), 2.0);
  const Disk disk(5, "disk", t, Vec3(0, 0, 0), Vec3(0.2, 0, 1), 6.0, 20.0);
  EXPECT_TRUE(plane.isInfinite());
  EXPECT_FALSE(rect.isInfinite());
  for (double u : { 0.1, 0.37, 0.8 })
    for (double v : { 0.2, 0.5, 0.9 })
      for (const SceneObject* o :
           std::initializer_list<const SceneObject*>{ &sky, &rect, &plane, &cyl, &ball, &disk })
      {
        double uu = -1, vv = -1;
        ASSERT_TRUE(uvThrough(*o, u, v, uu, vv)) << o->type() << " " << u << "," << v;
        EXPECT_NEAR(uu, u, 1e-9) << o->type();
        EXPECT_NEAR(vv, v, 1e-9) << o->type();
      }
  // The drawn points lie on the surfaces themselves.
  EXPECT_NEAR(sky.surfacePoint(0.3, 0.7).norm(), 500.0, 1e-10);
  EXPECT_NEAR((ball.surfacePoint(0.3, 0.7) - Vec3(3, -2, 1)).norm(), 2.0, 1e-12);
}

TEST(SceneRefine, AGrazingRayWhoseChordCutsIntoASphereMissesIt)
{
  // A step along the circle of radius 10 about the centre of a sphere of radius 9.9: the ray stays
  // 0.1 outside it, while the step's chord dips to 10 cos 0.2 = 9.80, inside.
  const Sphere ball(1, "b", solid(), Vec3::Zero(), 9.9);
  const Segment seg = arc(10.0, 0.3, 0.4);
  SurfaceHit hit;
  ASSERT_TRUE(ball.intersect(straight(seg.x0.tail<3>(), seg.x1.tail<3>()), hit))
    << "the chord itself enters the sphere";
  for (double tau = 0.0; tau <= 1.0; tau += 1.0 / 64)
    ASSERT_GT(seg.position(tau).tail<3>().norm(), 9.9) << "the ray must stay outside";
  EXPECT_FALSE(ball.intersect(seg, hit));
  // The same step through a sphere it does enter is hit on its surface.
  const Vec3 centre(10.0 * std::cos(0.5), 10.0 * std::sin(0.5), 0);
  const Sphere inner(2, "c", solid(), centre, 0.3);
  ASSERT_TRUE(inner.intersect(seg, hit));
  EXPECT_NEAR((hit.point - centre).norm(), 0.3, 1e-9);
}
