// The scene's object hierarchy against brute force over the public API: random scenes of a few
// thousand mixed objects must give, for every random segment, exactly the hit that testing every
// object's own intersection in insertion order gives (ties to the object added first), and for
// every point exactly the least per-object distance bound; a 10,000-sphere scene file traced in
// flat space must hit, pixel by pixel, the sphere the exact pinhole ray meets first.
#include "CameraFixtures.h"
#include "FrameTracer.h"
#include "Scene.h"
#include "SceneFile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using namespace asrt;

namespace
{
const double inf = std::numeric_limits<double>::infinity();

std::shared_ptr<const Texture> solid()
{
  return std::make_shared<SolidTexture>(Color(0.5, 0.5, 0.5));
}

/// A straight segment a → b: with both tangents b − a the Hermite cubic is the chord itself, so
/// testing every object's intersection is the exact answer (no bounding test can matter).
Segment straight(const Vec3& a, const Vec3& b, bool farField = false)
{
  Segment s;
  s.x0 << 0.0, a;
  s.x1 << 1.0, b;
  s.d0 << 1.0, b - a;
  s.d1 = s.d0;
  s.farField = farField;
  return s;
}

/// Random geometry of one object; kept so that some objects can be added twice under new ids.
struct Shape
{
  int kind = 0; // 0 sphere, 1 disk, 2 rectangle, 3 cylinder
  Vec3 center, axis, other;
  double a = 0, b = 0;
};

std::unique_ptr<SceneObject> make(const Shape& s, int id)
{
  switch (s.kind)
  {
    case 0:
      return std::make_unique<Sphere>(id, "s", solid(), s.center, s.a);
    case 1:
      return std::make_unique<Disk>(id, "d", solid(), s.center, s.axis, 0.3 * s.a, s.a);
    case 2:
      return std::make_unique<Rectangle>(id, "r", solid(), s.center, s.axis, s.other, s.a, s.b);
    default:
      return std::make_unique<Cylinder>(id, "c", solid(), s.center, s.axis, s.a, s.b);
  }
}

/// `count` objects of all four bounded kinds in [−20, 20]³, one in twenty a copy of an earlier
/// one under another id, with an infinite plane, an infinite strip and a celestial sphere among
/// them. Ids, from firstId on, are shuffled so that id order is not insertion order.
void fill(Scene& scene, int count, unsigned seed, int firstId = 0)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-20, 20), unit(-1, 1), size(0.05, 1.5), len(0.5, 8);
  std::vector<int> ids(count + 3);
  std::iota(ids.begin(), ids.end(), firstId);
  std::shuffle(ids.begin(), ids.end(), rng);
  std::vector<Shape> shapes;
  std::size_t next = 0;
  for (int k = 0; k < count; ++k)
  {
    if (k == count / 3)
      scene.add(std::make_unique<Rectangle>(ids[next++], "plane", solid(), Vec3(0, 0, -25),
                                            Vec3(1, 0, 0), Vec3(0, 1, 0), inf, inf));
    if (k == count / 2)
      scene.add(std::make_unique<CelestialSphere>(ids[next++], "sky", solid(), 60.0));
    if (k == 2 * count / 3)
      scene.add(std::make_unique<Rectangle>(ids[next++], "strip", solid(), Vec3(0, 22, 0),
                                            Vec3(1, 0, 0), Vec3(0, 0.2, 1), inf, 3.0));
    Shape s;
    if (!shapes.empty() && rng() % 20 == 0)
      s = shapes[rng() % shapes.size()];
    else
    {
      s.kind = static_cast<int>(rng() % 4);
      s.center = Vec3(pos(rng), pos(rng), pos(rng));
      s.axis = Vec3(unit(rng), unit(rng), unit(rng)) + Vec3(0, 0, 0.01);
      s.other = s.axis.cross(Vec3(unit(rng), unit(rng), unit(rng)) + Vec3(0.01, 0, 0));
      s.a = size(rng);
      s.b = s.kind == 3 ? len(rng) : size(rng);
    }
    shapes.push_back(s);
    scene.add(make(s, ids[next++]));
  }
}

bool isSky(const SceneObject& o)
{
  return std::string(o.type()) == "celestialSphere";
}

/// Every object's own intersection in insertion order, the first of the least τ kept; a far-field
/// segment meets only the sky.
bool bruteFirstHit(const Scene& scene, const Segment& seg, SurfaceHit& best)
{
  bool found = false;
  SurfaceHit h;
  for (const auto& o : scene.objects())
  {
    if (seg.farField && !isSky(*o))
      continue;
    if (o->intersect(seg, h) && (!found || h.tau < best.tau))
    {
      best = h;
      found = true;
    }
  }
  return found;
}

/// Scene::firstHit as documented, one object after another in insertion order: its bounding ball
/// within reach of the chord's ball, its distance from the chord's midpoint within the chord's
/// half-length, then its intersection, the first of the least τ kept.
bool linearFirstHit(const Scene& scene, const Segment& seg, SurfaceHit& best)
{
  const Vec3 a = seg.x0.tail<3>(), b = seg.x1.tail<3>();
  const Vec3 mid = 0.5 * (a + b);
  const double half = 0.5 * (b - a).norm();
  bool found = false;
  SurfaceHit h;
  for (const auto& o : scene.objects())
  {
    if (seg.farField && !isSky(*o))
      continue;
    Vec3 c;
    double r;
    if (o->boundingSphere(c, r))
    {
      const double reach = (r + half) * (1.0 + 1e-9);
      if ((mid - c).squaredNorm() > reach * reach ||
          o->distanceFrom(mid) > half * (1.0 + 1e-9) + 1e-12 * (1.0 + half))
        continue;
    }
    if (o->intersect(seg, h) && (!found || h.tau < best.tau))
    {
      best = h;
      found = true;
    }
  }
  return found;
}

/// The documented bound: the least over the objects but the sky of max(distanceFrom, distance to
/// the bounding ball), the ball's only where there is one.
double bruteObjectDistance(const Scene& scene, const Vec3& x)
{
  double d = inf;
  for (const auto& o : scene.objects())
  {
    if (isSky(*o))
      continue;
    double v = o->distanceFrom(x);
    Vec3 c;
    double r;
    if (o->boundingSphere(c, r))
      v = std::max(v, std::max(0.0, (x - c).norm() - r));
    d = std::min(d, v);
  }
  return d;
}

void expectSameHit(const Scene& scene, const Segment& seg, int& hits, const std::string& what,
                   bool linear = false)
{
  SurfaceHit want, got;
  const bool wanted = linear ? linearFirstHit(scene, seg, want) : bruteFirstHit(scene, seg, want);
  ASSERT_EQ(scene.firstHit(seg, got), wanted) << what;
  if (!wanted)
    return;
  ++hits;
  ASSERT_EQ(got.objectId, want.objectId) << what;
  ASSERT_EQ(got.tau, want.tau) << what;
  ASSERT_EQ(got.point, want.point) << what;
  ASSERT_EQ(got.normal, want.normal) << what;
  ASSERT_EQ(got.u, want.u) << what;
  ASSERT_EQ(got.v, want.v) << what;
}
}

TEST(SceneHierarchy, FirstHitIsTheBruteForceHit)
{
  Scene scene;
  fill(scene, 2000, 7);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> pos(-30, 30), unit(-1, 1), u01(0, 1);
  int hits = 0, skyHits = 0;
  for (int k = 0; k < 3000; ++k)
  {
    const Vec3 a(pos(rng), pos(rng), pos(rng));
    const Vec3 d = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
    // Short steps, middling ones and chords across the whole scene; one in ten a far-field one.
    const double length = k % 3 == 0 ? 0.01 + 0.5 * u01(rng) : k % 3 == 1 ? 5 * u01(rng) : 90;
    const Segment seg = straight(a, a + length * d, k % 10 == 9);
    const int before = hits;
    expectSameHit(scene, seg, hits, "segment " + std::to_string(k));
    if (hits > before && seg.farField)
      ++skyHits;
  }
  EXPECT_GT(hits, 1000); // the test exercised hits, not only misses
  EXPECT_GT(skyHits, 20);
}

TEST(SceneHierarchy, CurvedSegmentsHitAsInALoopOverEveryObject)
{
  // Cubic and quintic segments whose interpolants bow away from their chords by up to about a
  // tenth of their length: the hit, refined on the curve, must be the one-by-one loop's.
  Scene scene;
  fill(scene, 2000, 9);
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> pos(-25, 25), unit(-1, 1), u01(0, 1);
  auto randomVec = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
  int hits = 0, quintic = 0;
  for (int k = 0; k < 3000; ++k)
  {
    const Vec3 a(pos(rng), pos(rng), pos(rng));
    const double length = k % 2 == 0 ? 0.05 + 2 * u01(rng) : 20 * u01(rng);
    const Vec3 b = a + length * randomVec().normalized();
    Segment seg = straight(a, b);
    seg.d0.tail<3>() += 0.4 * length * randomVec();
    seg.d1.tail<3>() += 0.4 * length * randomVec();
    if (k % 3 == 0)
    {
      seg.quintic = true;
      seg.a0.tail<3>() = length * randomVec();
      seg.a1.tail<3>() = length * randomVec();
    }
    const int before = hits;
    expectSameHit(scene, seg, hits, "segment " + std::to_string(k), true);
    quintic += seg.quintic && hits > before;
  }
  EXPECT_GT(hits, 500);
  EXPECT_GT(quintic, 100);
}

TEST(SceneHierarchy, EqualTausGoToTheObjectAddedFirst)
{
  // Two identical spheres among many: every chord meets both at the same τ, bit for bit, and the
  // one added first must win whatever its id. (The random scenes' copies test the rule where the
  // hierarchy happens to visit the later copy first.)
  for (const bool lowIdFirst : { true, false })
  {
    Scene scene;
    fill(scene, 500, 3);
    const Vec3 c(1.5, -2.0, 0.5);
    const int first = lowIdFirst ? 10001 : 10002, second = lowIdFirst ? 10002 : 10001;
    scene.add(std::make_unique<Sphere>(first, "twin", solid(), c, 0.75));
    fill(scene, 500, 4, 1000);
    scene.add(std::make_unique<Sphere>(second, "twin", solid(), c, 0.75));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(-1, 1);
    int hits = 0;
    for (int k = 0; k < 200; ++k)
    {
      const Vec3 d = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
      const Vec3 a = c - 0.9 * d;
      SurfaceHit hit;
      ASSERT_TRUE(scene.firstHit(straight(a, a + 0.2 * d), hit)) << k;
      EXPECT_EQ(hit.objectId, first) << k;
      expectSameHit(scene, straight(a, a + 0.2 * d), hits, "twin " + std::to_string(k));
    }
  }
}

TEST(SceneHierarchy, ObjectDistanceIsTheLeastBoundAndABound)
{
  Scene scene;
  fill(scene, 2000, 11);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> pos(-30, 30), u01(0, 1);
  const auto& objects = scene.objects();
  for (int k = 0; k < 2000; ++k)
  {
    const double spread = k % 4 == 0 ? 100.0 : 1.0; // a quarter far outside the objects
    const Vec3 x = spread * Vec3(pos(rng), pos(rng), pos(rng));
    const double d = scene.objectDistance(x);
    ASSERT_EQ(d, bruteObjectDistance(scene, x)) << k;
    // A lower bound on the distance to every surface: no object's point is nearer.
    for (int m = 0; m < 20; ++m)
    {
      const SceneObject& o = *objects[rng() % objects.size()];
      if (isSky(o))
        continue;
      const Vec3 p = o.surfacePoint(u01(rng), u01(rng));
      ASSERT_LE(d, (x - p).norm() * (1 + 1e-12) + 1e-12) << k << " " << o.type();
    }
  }
}

TEST(SceneHierarchy, CylinderBoundIsTightenedByItsBall)
{
  // On the axis at s beyond an end, the cylinder's own bound (to the axis segment, less the
  // radius) is s − R; the bounding ball's, s + h/2 − √(R² + h²/4), is larger and still below the
  // true distance √(s² + R²) to the rim.
  Scene scene;
  const double R = 0.5, h = 10.0, s = 3.0;
  scene.add(std::make_unique<Cylinder>(1, "c", solid(), Vec3::Zero(), Vec3(0, 0, 1), R, h));
  const Vec3 x(0, 0, h + s);
  EXPECT_DOUBLE_EQ(scene.objects()[0]->distanceFrom(x), s - R);
  const double ball = s + 0.5 * h - std::hypot(R, 0.5 * h);
  EXPECT_DOUBLE_EQ(scene.objectDistance(x), ball);
  EXPECT_GT(ball, s - R);
  EXPECT_LT(ball, std::hypot(s, R)); // the nearest point of the wall is the rim
}

TEST(SceneHierarchy, QueriesFollowObjectsAddedLaterAndMoves)
{
  Scene scene;
  SurfaceHit hit;
  EXPECT_FALSE(scene.firstHit(straight(Vec3(-5, 0, 0), Vec3(5, 0, 0)), hit));
  EXPECT_EQ(scene.objectDistance(Vec3::Zero()), inf);
  scene.add(std::make_unique<Sphere>(1, "a", solid(), Vec3(3, 0, 0), 1.0));
  ASSERT_TRUE(scene.firstHit(straight(Vec3(-5, 0, 0), Vec3(5, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 1);
  EXPECT_EQ(scene.objectDistance(Vec3::Zero()), 2.0);
  // Added after the hierarchy was built: the next query sees it.
  scene.add(std::make_unique<Sphere>(2, "b", solid(), Vec3(-2, 0, 0), 0.5));
  ASSERT_TRUE(scene.firstHit(straight(Vec3(-5, 0, 0), Vec3(5, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 2);
  EXPECT_EQ(scene.objectDistance(Vec3::Zero()), 1.5);
  Scene moved(std::move(scene));
  ASSERT_TRUE(moved.firstHit(straight(Vec3(-5, 0, 0), Vec3(5, 0, 0)), hit));
  EXPECT_EQ(hit.objectId, 2);
  EXPECT_TRUE(scene.objects().empty()); // the moved-from scene is documented as empty
  EXPECT_FALSE(scene.firstHit(straight(Vec3(-5, 0, 0), Vec3(5, 0, 0)), hit));
  scene = std::move(moved);
  EXPECT_EQ(scene.objectDistance(Vec3::Zero()), 1.5);
}

TEST(SceneHierarchy, TenThousandSpheresTraceToTheExactPinholeRender)
{
  // Flat space: each pixel's ray is the straight half-line of the pinhole, and its first hit is
  // the nearest root over all spheres and the sky, found here by brute force.
  const int W = 40, H = 30, count = 10000;
  const double skyR = 200.0;
  const Vec3 eye(0, -60, 0);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> pos(-12, 12), size(0.05, 0.4);
  std::vector<Vec3> centers;
  std::vector<double> radii;
  std::string objects = R"([{"type": "celestialSphere", "id": 0, "radius": 200,
                             "texture": {"color": [0, 0, 1]}})";
  for (int k = 0; k < count; ++k)
  {
    centers.emplace_back(pos(rng), pos(rng), pos(rng));
    radii.push_back(size(rng));
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  R"(, {"type": "sphere", "id": %d, "center": [%.17g, %.17g, %.17g],
                        "radius": %.17g, "texture": {"color": [1, 1, 1]}})",
                  k + 1, centers[k].x(), centers[k].y(), centers[k].z(), radii[k]);
    objects += buf;
  }
  objects += "]";
  const std::string text = R"({"spacetime": {"mass": 0},
    "camera": {"position": [0, -60, 0], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
               "viewAngle": 30, "resolution": [40, 30]},
    "rendering": {"gridLattice": 1},
    "objects": )" + objects +
                           "}";
  const SceneDescription d = parseScene(text, "", nullptr);
  ASSERT_EQ(d.scene->objects().size(), static_cast<std::size_t>(count + 1));
  const std::vector<RayRecord> recs = FrameTracer(d).traceRows(0, H);
  ASSERT_EQ(recs.size(), static_cast<std::size_t>(W * H));

  const CameraParameters& cam = d.camera;
  const Vec3 F = (cam.focalPoint - eye).normalized();
  const Vec3 U = (cam.viewUp - cam.viewUp.dot(F) * F).normalized();
  const Vec3 R = F.cross(U);
  int spheres = 0;
  for (const RayRecord& rec : recs)
  {
    const Vec3 n = rec.direction;
    const Vec3 dir = n.x() * R + n.y() * U + n.z() * F;
    int id = 0;
    double tBest = -eye.dot(dir) + std::sqrt(std::pow(eye.dot(dir), 2) - eye.squaredNorm() +
                                             skyR * skyR); // the sky, seen from inside
    for (int k = 0; k < count; ++k)
    {
      const Vec3 w = eye - centers[k];
      const double bq = w.dot(dir), disc = bq * bq - (w.squaredNorm() - radii[k] * radii[k]);
      if (disc < 0.0)
        continue;
      const double t = -bq - std::sqrt(disc);
      if (t > 0.0 && t < tBest)
      {
        tBest = t;
        id = k + 1;
      }
    }
    ASSERT_EQ(rec.objectId, id) << "pixel " << rec.i << "," << rec.j;
    EXPECT_LT((rec.hitPoint - (eye + tBest * dir)).norm(), 1e-9) << rec.i << "," << rec.j;
    spheres += id > 0;
  }
  // Both spheres and the sky between them are in the frame.
  EXPECT_GT(spheres, W * H / 4);
  EXPECT_LT(spheres, W * H);
}
