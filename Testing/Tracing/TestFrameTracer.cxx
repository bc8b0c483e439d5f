// Frame tracing against independent truth: a flat-space render against the exact pinhole, sky hits
// against Darwin's deflection, a plane hit against a fine RK4 integration of Binet's orbit
// equation, an Einstein ring against the analytic lens solution, the image's symmetries, and the
// bookkeeping of the records (threads, subsets, image order, screen-space Jacobians).
#include "CameraFixtures.h"
#include "FrameTracer.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace asrt;
using asrt::testing::looking;

namespace
{
const double inf = std::numeric_limits<double>::infinity();

std::shared_ptr<const Texture> solid(double r = 0.5, double g = 0.5, double b = 0.5)
{
  return std::make_shared<SolidTexture>(Color(r, g, b));
}

SceneDescription describe(double mass, const CameraParameters& cam)
{
  SceneDescription d;
  d.spacetime.mass = mass;
  d.camera = cam;
  d.scene = std::make_shared<Scene>();
  // Every pixel's own ray: these tests hold each ray to an exact formula.
  d.rendering.gridLattice = 1;
  return d;
}

/// The pinhole's image-plane coordinates of pixel (i, j) at unit distance, as Camera.h documents
/// them (centres at (i + ½, j + ½), vertical half-angle from the view angle).
Vec3 pinholeDirection(const CameraParameters& c, int i, int j)
{
  const double t = std::tan(0.5 * c.viewAngle * M_PI / 180.0);
  const double aspect = static_cast<double>(c.width) / c.height;
  return Vec3((2.0 * (i + 0.5) / c.width - 1.0) * t * aspect,
              (2.0 * (j + 0.5) / c.height - 1.0) * t, 1.0);
}

/// Angle of pixel (i, j) from the camera's forward axis, in the observer's frame.
double pixelAngle(const CameraParameters& c, int i, int j)
{
  const Vec3 d = pinholeDirection(c, i, j);
  return std::atan(std::hypot(d.x(), d.y()));
}

/// Conserved quantities of a Schwarzschild ray from its initial covariant momentum (Kerr–Schild,
/// a = 0): E = |p_t| (traced backwards, so p_t > 0), L = x × p (normal to the ray's plane).
struct RayInvariants
{
  double E;
  Vec3 L;
  double b() const { return this->L.norm() / this->E; }
};

RayInvariants invariants(const RayRecord& r)
{
  return { std::abs(r.momentum[0]), r.origin.cross(r.momentum.tail<3>()) };
}

/// dr/dλ at x for covariant p, from g^{μν} = η^{μν} − f l^μ l^ν with l^μ = (−1, x/r), f = 2M/r
/// (physics.md): x̂·ẋ = (1 − f) p_r + f p_t.
double radialVelocity(const Vec3& x, const Vec4& p, double M)
{
  const double r = x.norm(), f = 2.0 * M / r;
  return (1.0 - f) * x.dot(p.tail<3>()) / r + f * p[0];
}

/// Angle swept from the eye at r_o to radius r on the outgoing branch: π + α̂ − tail(r_o) − tail(r)
/// past periapsis (sweepToInfinity added to the finite sweep gives π + α̂), tail(r_o) − tail(r)
/// for a ray moving outwards from the start.
double sweptAngle(double b, double M, double ro, double r, bool passesPeriapsis)
{
  if (passesPeriapsis)
    return M_PI + analytic::darwinDeflection(analytic::closestApproach(b, M), M) -
           analytic::sweepToInfinity(b, M, ro) - analytic::sweepToInfinity(b, M, r);
  return analytic::sweepToInfinity(b, M, ro) - analytic::sweepToInfinity(b, M, r);
}

double angleBetween(const Vec3& a, const Vec3& b)
{
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The first field in which two records differ bit for bit (NaN equals NaN, −0 differs from +0),
/// or "" if none does.
std::string firstDifference(const RayRecord& a, const RayRecord& b, bool jacobians = true)
{
  auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  auto sameV = [&](const auto& x, const auto& y)
  {
    for (int k = 0; k < x.size(); ++k)
      if (!same(x[k], y[k]))
        return false;
    return true;
  };
  if (a.i != b.i || a.j != b.j)
    return "pixel";
  if (!sameV(a.origin, b.origin))
    return "origin";
  if (!sameV(a.direction, b.direction))
    return "direction";
  if (!sameV(a.momentum, b.momentum))
    return "momentum";
  if (a.termination != b.termination)
    return "termination";
  if (a.objectId != b.objectId)
    return "objectId";
  if (!sameV(a.hitPoint, b.hitPoint))
    return "hitPoint";
  if (!sameV(a.hitNormal, b.hitNormal))
    return "hitNormal";
  if (!same(a.u, b.u) || !same(a.v, b.v))
    return "uv";
  if (!same(a.chordError, b.chordError))
    return "chordError";
  if (!same(a.affineLength, b.affineLength))
    return "affineLength";
  if (!same(a.winding, b.winding))
    return "winding";
  if (a.imageOrder != b.imageOrder)
    return "imageOrder";
  if (a.steps != b.steps)
    return "steps";
  if (!same(a.maxAbsH, b.maxAbsH))
    return "maxAbsH";
  if (!sameV(a.color, b.color))
    return "color";
  if (jacobians && (!same(a.dudi, b.dudi) || !same(a.dudj, b.dudj) || !same(a.dvdi, b.dvdi) ||
                    !same(a.dvdj, b.dvdj)))
    return "jacobian";
  return "";
}

/// A Schwarzschild scene with rays near the photon sphere: a disk, a ball and the sky.
SceneDescription photonSphereScene(int w, int h)
{
  SceneDescription d =
    describe(1.0, looking(Vec3(0, -20, 3), Vec3(0, 0, 0), Vec3(0, 0, 1), 40, w, h));
  d.scene->add(std::make_unique<CelestialSphere>(0, "sky", solid(0.1, 0.1, 0.3), 500.0));
  d.scene->add(std::make_unique<Disk>(1, "disk", solid(0.9, 0.6, 0.2), Vec3(0, 0, 0), Vec3(0, 0, 1),
                                      3.0, 12.0));
  d.scene->add(std::make_unique<Sphere>(2, "ball", solid(0.2, 0.8, 0.2), Vec3(4, 8, 2), 1.5));
  return d;
}
}

// ---- 1. flat space ------------------------------------------------------------------------------
TEST(FrameTracerFlat, MatchesTheExactPinholeRender)
{
  const CameraParameters cam = looking(Vec3(1, -20, 4), Vec3(0, 0, 0), Vec3(0, 0, 1), 50, 40, 30);
  SceneDescription d = describe(0.0, cam);
  const Vec3 planeC(0, 0, -3), planeN(0, 0, 1);
  const Vec3 ballC(3, 2, 0);
  const double ballR = 2.5;
  const Vec3 cylB(-5, -2, -3), cylA(0, 0, 1);
  const double cylR = 1.2, cylH = 7.0, skyR = 100.0;
  d.scene->add(std::make_unique<Rectangle>(0, "floor", solid(), planeC, Vec3(1, 0, 0),
                                           Vec3(0, 1, 0), inf, inf, 2.0));
  d.scene->add(std::make_unique<Sphere>(1, "ball", solid(), ballC, ballR));
  d.scene->add(std::make_unique<Cylinder>(2, "pillar", solid(), cylB, cylA, cylR, cylH));
  d.scene->add(std::make_unique<CelestialSphere>(3, "sky", solid(), skyR));
  const FrameTracer tracer(d);
  const std::vector<RayRecord> recs = tracer.traceRows(0, cam.height);

  // The static observer of flat space has u = ∂_t and the Euclidean Gram–Schmidt of the camera
  // axes as its legs.
  const Vec3 eye = cam.position;
  const Vec3 F = (cam.focalPoint - eye).normalized();
  const Vec3 U = (cam.viewUp - cam.viewUp.dot(F) * F).normalized();
  const Vec3 R = F.cross(U);

  int counts[4] = { 0, 0, 0, 0 };
  double worstPoint = 0, worstLength = 0, worstNormal = 0;
  for (const RayRecord& rec : recs)
  {
    const Vec3 n = pinholeDirection(cam, rec.i, rec.j).normalized();
    EXPECT_LT((rec.direction - n).norm(), 1e-15) << rec.i << "," << rec.j;
    const Vec3 dir = n.x() * R + n.y() * U + n.z() * F;

    // The exact first intersection of the half-line eye + t dir, t > 0.
    int id = -1;
    double tBest = inf;
    Vec3 normal = Vec3::Zero();
    auto offer = [&](int k, double t, const Vec3& nrm)
    {
      if (t > 0.0 && t < tBest)
      {
        tBest = t;
        id = k;
        normal = nrm;
      }
    };
    offer(0, planeN.dot(planeC - eye) / planeN.dot(dir), planeN);
    {
      const Vec3 w = eye - ballC;
      const double bq = w.dot(dir), c = w.squaredNorm() - ballR * ballR, disc = bq * bq - c;
      if (disc >= 0.0)
      {
        const double t = -bq - std::sqrt(disc);
        offer(1, t, (eye + t * dir - ballC) / ballR);
      }
    }
    {
      const Vec3 w = eye - cylB;
      const Vec3 wp = w - w.dot(cylA) * cylA, dp = dir - dir.dot(cylA) * cylA;
      const double A = dp.squaredNorm(), B = wp.dot(dp), C = wp.squaredNorm() - cylR * cylR;
      const double disc = B * B - A * C;
      if (disc >= 0.0)
      {
        for (const double t : { (-B - std::sqrt(disc)) / A, (-B + std::sqrt(disc)) / A })
        {
          const double h = w.dot(cylA) + t * dir.dot(cylA);
          const Vec3 x = eye + t * dir - cylB;
          if (h >= 0.0 && h <= cylH && t > 0.0)
          {
            offer(2, t, (x - x.dot(cylA) * cylA) / cylR);
            break;
          }
        }
      }
    }
    {
      const double bq = eye.dot(dir), c = eye.squaredNorm() - skyR * skyR;
      const double t = -bq + std::sqrt(bq * bq - c); // seen from inside: the far root
      offer(3, t, (eye + t * dir) / skyR);
    }
    if (normal.dot(dir) > 0.0)
      normal = -normal;

    ASSERT_EQ(rec.objectId, id) << "pixel " << rec.i << "," << rec.j;
    ++counts[id];
    EXPECT_EQ(rec.termination, Termination::HitObject);
    const Vec3 expected = eye + tBest * dir;
    worstPoint = std::max(worstPoint, (rec.hitPoint - expected).norm());
    // dx/dλ = η p and the spatial p is the unit direction (E_local = 1), so λ is the distance.
    worstLength = std::max(worstLength, std::abs(rec.affineLength - tBest));
    worstNormal = std::max(worstNormal, (rec.hitNormal - normal).norm());
    EXPECT_LT((rec.hitPoint - expected).norm(), 1e-10) << rec.i << "," << rec.j;
    EXPECT_LT(std::abs(rec.affineLength - tBest), 1e-10) << rec.i << "," << rec.j;
    EXPECT_LT((rec.hitNormal - normal).norm(), 1e-10) << rec.i << "," << rec.j;
    EXPECT_EQ(rec.imageOrder, 0);
  }
  std::printf("[ measured ] flat pinhole: |hit error| <= %.3g M, |lambda error| <= %.3g M, "
              "|normal error| <= %.3g; pixels on floor/ball/pillar/sky = %d/%d/%d/%d\n",
              worstPoint, worstLength, worstNormal, counts[0], counts[1], counts[2], counts[3]);
  for (int k = 0; k < 4; ++k)
    EXPECT_GT(counts[k], 20) << "object " << k << " is barely in the frame: the test is weak";
}

// ---- 2. Schwarzschild sky against Darwin's deflection -------------------------------------------
TEST(FrameTracerSchwarzschild, SkyHitsFollowDarwinsDeflection)
{
  const double M = 1.0, ro = 30.0, skyR = 1000.0;
  struct Case
  {
    const char* what;
    Vec3 focal;
    bool inwards;
  };
  // Looking at the hole every ray starts inwards and passes periapsis; looking away every ray
  // starts outwards.
  for (const Case& c : { Case{ "towards the hole", Vec3(0, 0, 0), true },
                         Case{ "away from the hole", Vec3(100, 0, 0), false } })
  {
    SceneDescription d = describe(M, looking(Vec3(ro, 0, 0), c.focal, Vec3(0, 0, 1), 50, 20, 20));
    d.scene->add(std::make_unique<CelestialSphere>(0, "sky", solid(), skyR));
    const FrameTracer tracer(d);
    const std::vector<RayRecord> recs = tracer.traceRows(0, 20);
    int used = 0;
    double worst = 0, worstB = 0, worstRadius = 0;
    for (const RayRecord& rec : recs)
    {
      const RayInvariants inv = invariants(rec);
      const double b = inv.b();
      const bool inwards = radialVelocity(rec.origin, rec.momentum, M) < 0.0;
      ASSERT_EQ(inwards, c.inwards) << rec.i << "," << rec.j;
      if (rec.objectId != 0)
      {
        // Only rays below the critical impact parameter may miss the sky.
        EXPECT_LT(b, 3.0 * std::sqrt(3.0) * M) << rec.i << "," << rec.j;
        EXPECT_EQ(rec.termination, Termination::Captured);
        continue;
      }
      // Darwin's sweep needs both ends well outside periapsis (the tails' quadrature).
      if (c.inwards && analytic::closestApproach(b, M) > ro / 3.0)
        continue;
      ++used;
      const double r = rec.hitPoint.norm();
      worstRadius = std::max(worstRadius, std::abs(r - skyR));
      const double psi = sweptAngle(b, M, ro, r, c.inwards);
      const Vec3 e0 = rec.origin.normalized();
      const Vec3 e1 = inv.L.normalized().cross(e0);
      const Vec3 predicted = std::cos(psi) * e0 + std::sin(psi) * e1;
      const double err = angleBetween(predicted, rec.hitPoint);
      if (err > worst)
      {
        worst = err;
        worstB = b;
      }
      EXPECT_LT(err, 1e-7) << "pixel " << rec.i << "," << rec.j << " b = " << b;
      // The record's winding is the same sweep.
      EXPECT_NEAR(rec.winding, psi, 1e-7) << "pixel " << rec.i << "," << rec.j;
    }
    std::printf("[ measured ] sky hits looking %s: %d rays, worst direction error %.3g rad "
                "(b = %.6g M), |r - R| <= %.3g M\n",
                c.what, used, worst, worstB, worstRadius);
    EXPECT_GT(used, 150) << c.what;
  }
}

// ---- 3. a plane hit against Binet's orbit equation ----------------------------------------------
namespace
{
/// Where a planar Schwarzschild orbit first crosses the line r cos φ = c.
struct OrbitCrossing
{
  Vec3 point;    ///< in the plane z = 0
  double psi;    ///< angle swept from the start
  double lambda; ///< affine parameter from the start
};

/// u'' + u = 3Mu² (u = 1/r, ' = d/dψ, ψ the angle swept) by classic RK4 with a fixed tiny step in
/// long double, from (u0, w0 = du/dψ) at polar angle φ0, sweeping in the sense s = ±1; with it the
/// affine parameter, dλ/dψ = r²/|L| (dφ/dλ = L/r²). Finds the first ψ where r cos φ = c, i.e.
/// where cos φ − c u turns positive, refined by bisection on a single RK4 substep. Returns false
/// if the orbit falls in (u > 1/2M) or escapes (u < uEscape) first.
bool binetCrossing(double M, double L, double u0, double w0, double phi0, int s, double c,
                   double uEscape, OrbitCrossing& out)
{
  using LD = long double;
  struct State
  {
    LD u, w, lambda;
  };
  const LD h = 2e-4L;
  auto rate = [&](const State& z) {
    return State{ z.w, 3.0L * M * z.u * z.u - z.u, 1.0L / (std::abs(L) * z.u * z.u) };
  };
  auto rk4 = [&](const State& z, LD dt)
  {
    auto add = [](const State& a, const State& k, LD f) {
      return State{ a.u + f * k.u, a.w + f * k.w, a.lambda + f * k.lambda };
    };
    const State k1 = rate(z), k2 = rate(add(z, k1, 0.5L * dt)), k3 = rate(add(z, k2, 0.5L * dt)),
                k4 = rate(add(z, k3, dt));
    return State{ z.u + dt / 6 * (k1.u + 2 * k2.u + 2 * k3.u + k4.u),
                  z.w + dt / 6 * (k1.w + 2 * k2.w + 2 * k3.w + k4.w),
                  z.lambda + dt / 6 * (k1.lambda + 2 * k2.lambda + 2 * k3.lambda + k4.lambda) };
  };
  auto F = [&](LD psi, LD u) { return std::cos(phi0 + s * psi) - c * u; };
  State z{ u0, w0, 0.0L };
  LD psi = 0;
  if (!(F(psi, z.u) < 0))
    return false;
  for (long k = 0; k < 200000; ++k)
  {
    const State next = rk4(z, h);
    if (next.u > 1.0L / (2.0L * M) || next.u < uEscape)
      return false;
    if (F(psi + h, next.u) >= 0)
    {
      LD lo = 0, hi = h;
      for (int it = 0; it < 80; ++it)
      {
        const LD mid = 0.5L * (lo + hi);
        (F(psi + mid, rk4(z, mid).u) < 0 ? lo : hi) = mid;
      }
      const State at = rk4(z, 0.5L * (lo + hi));
      const LD phi = phi0 + s * (psi + 0.5L * (lo + hi));
      out.point = Vec3(static_cast<double>(std::cos(phi) / at.u),
                       static_cast<double>(std::sin(phi) / at.u), 0.0);
      out.psi = static_cast<double>(psi + 0.5L * (lo + hi));
      out.lambda = static_cast<double>(at.lambda);
      return true;
    }
    z = next;
    psi += h;
  }
  return false;
}
}

namespace
{
/// The centre row of a camera at (−30, 0, 0) looking across the hole at the wall x = c: each ray
/// lies in the plane z = 0, and its crossing of the wall is found independently from Binet's
/// equation started at the eye's (u, du/dψ).
struct WallRay
{
  RayRecord rec;
  double b = 0;
  bool radial = false;
  bool crosses = false;
  OrbitCrossing truth{ Vec3::Zero(), 0.0, 0.0 };
};

std::vector<WallRay> wallRowAgainstBinet(double M, double c)
{
  const int W = 41;
  SceneDescription d =
    describe(M, looking(Vec3(-30, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), 60, W, W));
  // At the default tolerances (relative 1e-8 of a state whose coordinates are ~30 M) the
  // integration itself is off by ~1e-6 M at the wall (1.4e-5 M on the near-critical ray, measured):
  // tightened, what remains is the hit's refinement.
  d.integrator.relativeTolerance = 1e-11;
  d.integrator.absoluteTolerance = 1e-13;
  d.scene->add(std::make_unique<Rectangle>(0, "wall", solid(), Vec3(c, 0, 0), Vec3(0, 1, 0),
                                           Vec3(0, 0, 1), inf, inf, 1.0));
  const FrameTracer tracer(d);
  std::vector<std::pair<int, int>> row;
  for (int i = 0; i < W; ++i)
    row.emplace_back(i, W / 2);
  std::vector<WallRay> out;
  for (const RayRecord& rec : tracer.tracePixels(row))
  {
    WallRay ray;
    ray.rec = rec;
    // The centre row's direction has no up component, and the up leg is +z exactly here.
    EXPECT_EQ(rec.momentum[3], 0.0) << "centre-row ray leaves the plane z = 0";
    const RayInvariants inv = invariants(rec);
    const double Lz = inv.L.z();
    ray.b = inv.b();
    ray.radial = Lz == 0.0;
    if (!ray.radial)
    {
      const double u0 = 1.0 / rec.origin.norm();
      const double rdot = radialVelocity(rec.origin, rec.momentum, M);
      // (du/dφ)² = 1/b² − u² + 2Mu³ (physics.md) with the sign of −dr/dλ; du/dψ = −ṙ/|L| too.
      const double w0 =
        -std::copysign(std::sqrt(1.0 / (ray.b * ray.b) - u0 * u0 + 2.0 * M * u0 * u0 * u0), rdot);
      EXPECT_NEAR(w0, -rdot / std::abs(Lz), 1e-12 * std::abs(w0) + 1e-15);
      const double phi0 = std::atan2(rec.origin.y(), rec.origin.x());
      ray.crosses = binetCrossing(M, Lz, u0, w0, phi0, Lz > 0 ? 1 : -1, c,
                                  1.0 / tracer.escapeRadius(), ray.truth);
    }
    out.push_back(ray);
  }
  return out;
}
}

TEST(FrameTracerSchwarzschild, PlaneHitMatchesBinetOrbit)
{
  const double c = 15.0;
  int hits = 0;
  double worst = 0, worstWinding = 0, minChord = inf, maxChord = 0, minRatio = inf;
  for (const WallRay& ray : wallRowAgainstBinet(1.0, c))
  {
    const RayRecord& rec = ray.rec;
    if (ray.radial)
    {
      EXPECT_EQ(rec.termination, Termination::Captured); // falls straight in
      continue;
    }
    ASSERT_EQ(rec.objectId == 0, ray.crosses) << "pixel " << rec.i << " b = " << ray.b;
    if (!ray.crosses)
      continue;
    ++hits;
    const double err = (rec.hitPoint - ray.truth.point).norm();
    worst = std::max(worst, err);
    worstWinding = std::max(worstWinding, std::abs(rec.winding - ray.truth.psi));
    minChord = std::min(minChord, rec.chordError);
    maxChord = std::max(maxChord, rec.chordError);
    minRatio = std::min(minRatio, rec.chordError / err);
    EXPECT_LT(err, 1e-7) << "pixel " << rec.i << " b = " << ray.b;
    // A planar orbit sweeps its polar angle monotonically: the winding is ψ.
    EXPECT_NEAR(rec.winding, ray.truth.psi, 1e-8) << "pixel " << rec.i << " b = " << ray.b;
    // Refinement must have corrected far more than what remains of the error.
    EXPECT_GT(rec.chordError, 10.0 * err) << "pixel " << rec.i << " b = " << ray.b;
  }
  std::printf("[ measured ] plane x = %g: %d hits, |hit - Binet| <= %.3g M, |winding - psi| <= "
              "%.3g rad, chord error in [%.3g, %.3g] M, chord error / hit error >= %.3g\n",
              c, hits, worst, worstWinding, minChord, maxChord, minRatio);
  EXPECT_GT(hits, 20);
}

TEST(FrameTracerSchwarzschild, AffineLengthAtAHitMatchesBinet)
{
  // λ from the eye to the wall, dλ/dψ = r²/|L| along Binet's orbit. At this tolerance the
  // integration's own λ is good to ~3e-8 M at the step ends (measured on the traced polylines).
  int hits = 0, worstPixel = -1;
  double worst = 0, worstRelative = 0, worstLambda = 0;
  for (const WallRay& ray : wallRowAgainstBinet(1.0, 15.0))
  {
    if (!ray.crosses || ray.rec.objectId != 0)
      continue;
    ++hits;
    const double err = std::abs(ray.rec.affineLength - ray.truth.lambda);
    if (err > worst)
    {
      worst = err;
      worstPixel = ray.rec.i;
      worstLambda = ray.truth.lambda;
    }
    worstRelative = std::max(worstRelative, err / ray.truth.lambda);
  }
  std::printf("[ measured ] affine length at the wall: |lambda - Binet| <= %.3g M (relative "
              "%.3g)\n",
              worst, worstRelative);
  EXPECT_LT(worst, 1e-6) << "worst at pixel " << worstPixel << " (lambda " << worstLambda << " M)";
  EXPECT_GT(hits, 20);
}

// ---- 4. symmetry --------------------------------------------------------------------------------
TEST(FrameTracerSymmetry, AxisymmetricSceneGivesASymmetricImage)
{
  // Looking down the z axis at a scene symmetric about it, the image must be invariant under the
  // square's quarter turn and mirror, which are rotations and reflections of the scene about z.
  const int W = 41;
  SceneDescription d =
    describe(1.0, looking(Vec3(0, 0, 30), Vec3(0, 0, 0), Vec3(1, 0, 0), 40, W, W));
  d.scene->add(std::make_unique<CelestialSphere>(0, "sky", solid(), 500.0));
  d.scene->add(std::make_unique<Disk>(1, "disk", solid(), Vec3(0, 0, 0), Vec3(0, 0, 1), 6.0, 15.0));
  d.scene->add(std::make_unique<Sphere>(2, "ball", solid(), Vec3(0, 0, -12), 2.0));
  const FrameTracer tracer(d);
  const std::vector<RayRecord> recs = tracer.traceRows(0, W);
  auto at = [&](int i, int j) -> const RayRecord& { return recs[static_cast<size_t>(j) * W + i]; };

  // Legs: forward −z, up +x, right = forward × up = −y. Pixel (j, W − 1 − i) sees the scene turned
  // by −90° about z: (x, y) → (y, −x); pixel (W − 1 − i, j) sees it mirrored: y → −y.
  struct Map
  {
    const char* name;
    int (*i)(int, int, int);
    int (*j)(int, int, int);
    Vec3 (*x)(const Vec3&);
  };
  const Map maps[] = {
    { "quarter turn", [](int, int j, int) { return j; },
      [](int i, int, int w) { return w - 1 - i; },
      [](const Vec3& x) { return Vec3(x.y(), -x.x(), x.z()); } },
    { "mirror", [](int i, int, int w) { return w - 1 - i; }, [](int, int j, int) { return j; },
      [](const Vec3& x) { return Vec3(x.x(), -x.y(), x.z()); } },
  };
  int counts[3] = { 0, 0, 0 }, captured = 0, winding = 0;
  double worstLength = 0, worstPoint = 0;
  for (const Map& m : maps)
  {
    for (int j = 0; j < W; ++j)
      for (int i = 0; i < W; ++i)
      {
        const RayRecord& a = at(i, j);
        const RayRecord& b = at(m.i(i, j, W), m.j(i, j, W));
        ASSERT_EQ(a.termination, b.termination) << m.name << " " << i << "," << j;
        ASSERT_EQ(a.objectId, b.objectId) << m.name << " " << i << "," << j;
        ASSERT_EQ(a.imageOrder, b.imageOrder) << m.name << " " << i << "," << j;
        const double dl = std::abs(a.affineLength - b.affineLength) / a.affineLength;
        const double dx = (m.x(a.hitPoint) - b.hitPoint).norm() / a.hitPoint.norm();
        worstLength = std::max(worstLength, dl);
        worstPoint = std::max(worstPoint, dx);
        EXPECT_LE(dl, 1e-9) << m.name << " " << i << "," << j;
        EXPECT_LE(dx, 1e-9) << m.name << " " << i << "," << j;
        if (&m == &maps[0])
        {
          if (a.objectId >= 0)
            ++counts[a.objectId];
          captured += a.termination == Termination::Captured;
          winding += a.imageOrder >= 1;
        }
      }
  }
  std::printf("[ measured ] symmetry: relative path length difference <= %.3g, relative hit point "
              "difference <= %.3g; sky/disk/ball/hole/winding pixels = %d/%d/%d/%d/%d\n",
              worstLength, worstPoint, counts[0], counts[1], counts[2], captured, winding);
  for (int k = 0; k < 3; ++k)
    EXPECT_GT(counts[k], 20) << "object " << k;
  EXPECT_GT(captured, 20);
  EXPECT_GT(winding, 0);
}

// ---- 5. Einstein ring ---------------------------------------------------------------------------
TEST(FrameTracerLensing, EinsteinRingAtTheAnalyticRadius)
{
  const double M = 1.0, D = 40.0, Ds = 20.0, rho = 0.5;
  const double bc = 3.0 * std::sqrt(3.0) * M;
  auto tail = [&](double b, double r) { return analytic::sweepToInfinity(b, M, r); };
  auto deflection = [&](double b)
  { return analytic::darwinDeflection(analytic::closestApproach(b, M), M); };
  // Past periapsis, the ray has swept π + α̂ − tail(D) − tail(r) at radius r: the point behind the
  // hole (swept angle π) at radius Ds is reached when α̂ = tail(D) + tail(Ds).
  auto bisect = [](auto&& f, double lo, double hi)
  {
    const bool sLo = f(lo) > 0.0;
    EXPECT_NE(sLo, f(hi) > 0.0) << "no sign change in [" << lo << ", " << hi << "]";
    for (int it = 0; it < 100; ++it)
    {
      const double mid = 0.5 * (lo + hi);
      ((f(mid) > 0.0) == sLo ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  const double bE =
    bisect([&](double b) { return deflection(b) - tail(b, D) - tail(b, Ds); }, 1.01 * bc, 12.0);
  // A static observer at D sees impact parameter b at sin θ = b √(1 − 2M/D) / D (physics.md).
  const double fo = std::sqrt(1.0 - 2.0 * M / D);
  auto observed = [&](double b) { return std::asin(b * fo / D); };
  const double thetaE = observed(bE);

  // The exact band of the ball: the rays whose closest distance to its centre is ρ. Such a point
  // lies within ρ of Ds in radius, where the ray's offset from the axis is the swept angle − π.
  auto missDistance = [&](double b)
  {
    const double a = deflection(b) - tail(b, D);
    auto dist = [&](double r)
    {
      // The law of cosines without its cancellation: r² + Ds² − 2 r Ds cos δ.
      const double s = std::sin(0.5 * (a - tail(b, r)));
      return std::sqrt((r - Ds) * (r - Ds) + 4.0 * r * Ds * s * s);
    };
    double lo = Ds - rho, hi = Ds + rho;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 60; ++it)
    {
      const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
      (dist(m1) < dist(m2) ? hi : lo) = (dist(m1) < dist(m2) ? m2 : m1);
    }
    return dist(0.5 * (lo + hi));
  };
  const double b1 = bisect([&](double b) { return missDistance(b) - rho; }, 0.8 * bE, bE);
  const double b2 = bisect([&](double b) { return missDistance(b) - rho; }, bE, 1.25 * bE);
  const double theta1 = observed(b1), theta2 = observed(b2);
  const double ballAngle = std::asin(rho / (D + Ds)); // the ball's unlensed angular radius

  const int W = 1601, c = W / 2;
  const double angle = 32;
  const CameraParameters cam = looking(Vec3(0, -D, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), angle, W, W);
  SceneDescription d = describe(M, cam);
  d.scene->add(std::make_unique<Sphere>(0, "source", solid(), Vec3(0, Ds, 0), rho));
  const FrameTracer tracer(d);
  const double pitch = 2.0 * std::tan(0.5 * angle * M_PI / 180.0) / W;
  // Four arms from the centre pixel, over angles clear of the shadow's rim (and of the fainter
  // rings just outside it) and of the frame's edge.
  const double shadow = analytic::shadowAngularRadius(D, M);
  const int arms[4][2] = { { 1, 0 }, { -1, 0 }, { 0, 1 }, { 0, -1 } };
  std::vector<std::pair<int, int>> pixels;
  std::vector<int> arm;
  for (int a = 0; a < 4; ++a)
    for (int k = 1; k < c; ++k)
    {
      const int i = c + k * arms[a][0], j = c + k * arms[a][1];
      const double th = pixelAngle(cam, i, j);
      if (th > 1.15 * shadow && th < 1.15 * theta2)
      {
        pixels.emplace_back(i, j);
        arm.push_back(a);
      }
    }
  const std::vector<RayRecord> recs = tracer.tracePixels(pixels);

  double sum[4] = { 0, 0, 0, 0 };
  int n[4] = { 0, 0, 0, 0 }, first[4] = { -1, -1, -1, -1 }, last[4] = { -1, -1, -1, -1 };
  int misclassified = 0, nearEdge = 0;
  double closest = inf; // of a classified pixel to the band's edges
  for (size_t k = 0; k < recs.size(); ++k)
  {
    const RayRecord& rec = recs[k];
    const int a = arm[k];
    const double th = pixelAngle(cam, rec.i, rec.j);
    const bool hit = rec.objectId == 0;
    // Pixels a hair from the band's edge may go either way within the integration's error.
    const double fromEdge = std::min(std::abs(th - theta1), std::abs(th - theta2));
    if (fromEdge < 1e-6)
    {
      ++nearEdge;
    }
    else if (hit != (th > theta1 && th < theta2))
    {
      ++misclassified;
      ADD_FAILURE() << "pixel " << rec.i << "," << rec.j << " at " << th << " rad: hit " << hit
                    << ", band [" << theta1 << ", " << theta2 << "]";
    }
    if (fromEdge >= 1e-6)
      closest = std::min(closest, fromEdge);
    if (hit)
    {
      sum[a] += th;
      ++n[a];
      const int idx = std::abs(rec.i - c) + std::abs(rec.j - c);
      if (first[a] < 0)
        first[a] = idx;
      last[a] = idx;
    }
  }
  double lo = inf, hi = -inf;
  for (int a = 0; a < 4; ++a)
  {
    ASSERT_GT(n[a], 5) << "arm " << a << " crosses no ring";
    // One contiguous run of pixels per arm: a ring, not scattered hits.
    EXPECT_EQ(last[a] - first[a] + 1, n[a]) << "arm " << a;
    const double mean = sum[a] / n[a];
    lo = std::min(lo, mean);
    hi = std::max(hi, mean);
    EXPECT_NEAR(mean, thetaE, 0.05 * ballAngle) << "arm " << a;
  }
  // A circle: the same radius along rows and along columns.
  EXPECT_LT(hi - lo, 0.5 * pitch);
  std::printf("[ measured ] Einstein ring: b_E = %.9g M, theta_E = %.6g rad, band [%.6g, %.6g] "
              "rad (%d pixels/arm, pitch %.3g rad); arm means in [%.6g, %.6g], off theta_E by "
              "%.3g rad = %.3g of the ball's angular radius; %d misclassified, %d at an edge, the "
              "others >= %.3g rad from one\n",
              bE, thetaE, theta1, theta2, n[0], pitch, lo, hi,
              std::max(std::abs(lo - thetaE), std::abs(hi - thetaE)),
              std::max(std::abs(lo - thetaE), std::abs(hi - thetaE)) / ballAngle, misclassified,
              nearEdge, closest);
}

// ---- 6. threads ---------------------------------------------------------------------------------
TEST(FrameTracerRecords, IdenticalForOneAndTwoThreads)
{
  const int W = 32, H = 24;
  const FrameTracer tracer(photonSphereScene(W, H));
  std::vector<std::pair<int, int>> pixels;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
      pixels.emplace_back(i, j);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<RayRecord> one = tracer.tracePixels(pixels);
  omp_set_num_threads(2);
  const std::vector<RayRecord> two = tracer.tracePixels(pixels);
  omp_set_num_threads(saved);
  ASSERT_EQ(one.size(), two.size());
  int winding = 0;
  for (size_t k = 0; k < one.size(); ++k)
  {
    EXPECT_EQ(firstDifference(one[k], two[k]), "") << "pixel " << one[k].i << "," << one[k].j;
    winding += one[k].imageOrder >= 1;
  }
  // The frame must hold rays near the photon sphere, the costly and sensitive ones.
  EXPECT_GT(winding, 10);
}

// ---- 7. image order -----------------------------------------------------------------------------
TEST(FrameTracerRecords, ImageOrderCountsHalfTurns)
{
  const double M = 1.0, ro = 30.0, skyR = 1000.0;
  // A row of 101 pixels 2.4e-5 rad apart, from just inside the shadow's rim outwards: the rays
  // outside have b/b_c − 1 from ~1e-4 to ~1e-2 and wind once or more about the hole. The forward
  // axis is aimed in coordinates, where the static observer's radial lengths stretch by
  // 1/√(1 − 2M/r): tan θ_frame = tan ψ_coord √(1 − 2M/r).
  const double thetaC = analytic::shadowAngularRadius(ro, M) + 1.1e-3;
  const double tanPsi = std::tan(thetaC) / std::sqrt(1.0 - 2.0 * M / ro);
  const Vec3 eye(0, -ro, 0);
  const double halfAngle = std::atan(1.2e-5);
  CameraParameters cam =
    looking(eye, eye + Vec3(tanPsi, 1, 0), Vec3(0, 0, 1), 2.0 * halfAngle * 180.0 / M_PI, 101, 1);
  SceneDescription d = describe(M, cam);
  d.scene->add(std::make_unique<CelestialSphere>(0, "sky", solid(), skyR));
  const FrameTracer tracer(d);
  const std::vector<RayRecord> recs = tracer.traceRows(0, 1);
  int captured = 0, escaped = 0, order3 = 0;
  double worst = 0, worstEquivalent = 0;
  for (const RayRecord& rec : recs)
  {
    EXPECT_EQ(rec.imageOrder, static_cast<int>(std::floor(rec.winding / M_PI)));
    if (rec.termination == Termination::Captured)
    {
      ++captured;
      continue;
    }
    ASSERT_EQ(rec.objectId, 0) << rec.i;
    ASSERT_LT(radialVelocity(rec.origin, rec.momentum, M), 0.0);
    ++escaped;
    const double b = invariants(rec).b();
    const double excess = b / (3.0 * std::sqrt(3.0) * M) - 1.0;
    const double psi = sweptAngle(b, M, ro, rec.hitPoint.norm(), true);
    // Near b_c, α̂ ≈ −ln(b/b_c − 1) + const (Bozza): an integration error worth δ in b/b_c moves
    // the sweep by δ/(b/b_c − 1). Measured at the default tolerances: δ ≈ 5e-10 on every ray.
    const double err = std::abs(rec.winding - psi);
    worst = std::max(worst, err);
    worstEquivalent = std::max(worstEquivalent, err * excess);
    EXPECT_LT(err, 1e-7 + 2e-9 / excess) << "pixel " << rec.i << " b/b_c - 1 = " << excess;
    EXPECT_GE(rec.imageOrder, 1) << rec.i;
    if (std::abs(psi / M_PI - std::round(psi / M_PI)) > 1e-5)
    {
      EXPECT_EQ(rec.imageOrder, static_cast<int>(std::floor(psi / M_PI))) << rec.i;
    }
    order3 += rec.imageOrder >= 3;
  }
  std::printf("[ measured ] image order: %d captured, %d escaped (%d of order >= 3), "
              "|winding - Darwin sweep| <= %.3g rad, times (b/b_c - 1) <= %.3g\n",
              captured, escaped, order3, worst, worstEquivalent);
  EXPECT_GT(captured, 0);
  EXPECT_GT(escaped, 50);
  EXPECT_GT(order3, 0);

  // Looking away from the hole, the sky is seen directly: order 0, winding tail(r_o) − tail(R).
  cam = looking(eye, Vec3(0, -2 * ro, 0), Vec3(0, 0, 1), 60, 5, 5);
  SceneDescription away = describe(M, cam);
  away.scene->add(std::make_unique<CelestialSphere>(0, "sky", solid(), skyR));
  for (const RayRecord& rec : FrameTracer(away).traceRows(0, 5))
  {
    ASSERT_EQ(rec.objectId, 0);
    EXPECT_EQ(rec.imageOrder, 0);
    const double b = invariants(rec).b();
    EXPECT_NEAR(rec.winding, sweptAngle(b, M, ro, rec.hitPoint.norm(), false), 1e-8);
  }
}

// ---- 8. subsets ---------------------------------------------------------------------------------
TEST(FrameTracerRecords, SubsetsMatchWholeRows)
{
  const int W = 16, H = 12;
  const FrameTracer tracer(photonSphereScene(W, H));
  const std::vector<RayRecord> all = tracer.traceRows(0, H);
  auto at = [&](int i, int j) -> const RayRecord& { return all[static_cast<size_t>(j) * W + i]; };

  // Any order, repeats allowed: each pixel's record must not depend on what else is traced.
  const std::vector<std::pair<int, int>> subset = { { 5, 3 }, { 0, 0 },  { 15, 11 }, { 7, 6 },
                                                    { 5, 3 }, { 9, 2 },  { 3, 10 },  { 8, 5 },
                                                    { 8, 6 }, { 14, 0 }, { 0, 11 } };
  const std::vector<RayRecord> some = tracer.tracePixels(subset);
  ASSERT_EQ(some.size(), subset.size());
  for (size_t k = 0; k < subset.size(); ++k)
  {
    const auto [i, j] = subset[k];
    // The Jacobians depend on which neighbours were traced with the pixel: left out here.
    EXPECT_EQ(firstDifference(some[k], at(i, j), false), "") << i << "," << j;
  }

  // A band of rows: the same records, with the Jacobians of its inner rows. Its edge rows may lack
  // the neighbours across the band's edge, so there only ∂/∂i must agree.
  const int r0 = 3, r1 = 7;
  const std::vector<RayRecord> band = tracer.traceRows(r0, r1);
  ASSERT_EQ(band.size(), static_cast<size_t>((r1 - r0) * W));
  for (const RayRecord& rec : band)
  {
    const RayRecord& ref = at(rec.i, rec.j);
    const bool inner = rec.j > r0 && rec.j < r1 - 1;
    EXPECT_EQ(firstDifference(rec, ref, inner), "") << rec.i << "," << rec.j;
    RayRecord along = rec;
    along.dudj = ref.dudj;
    along.dvdj = ref.dvdj;
    EXPECT_EQ(firstDifference(along, ref, true), "") << rec.i << "," << rec.j;
  }
}

// ---- 8b. rays integrated ------------------------------------------------------------------------
namespace
{
long long raysCharged(const std::vector<RayRecord>& records)
{
  long long rays = 0;
  for (const RayRecord& r : records)
    rays += r.raysPerPixel;
  return rays;
}
}

// Over a whole frame traced a ray a pixel every ray is charged to one of its pixels (a centre ray,
// an anti-aliasing sample, an edge midpoint to its lower or left pixel, Antialiasing.h): the
// records' raysPerPixel add up to what the tracer integrated, traced by rows or as a list of all
// its pixels. On the adaptive grid a block may trace a ray on its border that the block owning
// the pixel does not use: the records then hold fewer.
TEST(FrameTracerRays, AWholeFrameIntegratesTheRaysItsRecordsCount)
{
  const int W = 32, H = 24;
  for (int lattice : { 1, 4 })
  {
    SceneDescription d = photonSphereScene(W, H);
    d.rendering.gridLattice = lattice;
    const FrameTracer tracer(d);
    ASSERT_EQ(tracer.raysIntegrated(), 0);
    const std::vector<RayRecord> rows = tracer.traceRows(0, H);
    const long long charged = raysCharged(rows);
    // Edges between the disk, the ball, the sky and the hole: the adaptive rendering added rays.
    EXPECT_GT(charged, static_cast<long long>(W) * H / (lattice * lattice)) << lattice;
    if (lattice > 1)
    {
      EXPECT_GE(tracer.raysIntegrated(), charged);
      continue;
    }
    EXPECT_EQ(tracer.raysIntegrated(), charged);
    std::vector<std::pair<int, int>> pixels;
    for (int j = H - 1; j >= 0; --j) // another order than the rows'
      for (int i = 0; i < W; ++i)
        pixels.emplace_back(i, j);
    const long long before = tracer.raysIntegrated();
    const std::vector<RayRecord> listed = tracer.tracePixels(pixels);
    EXPECT_EQ(raysCharged(listed), charged);
    EXPECT_EQ(tracer.raysIntegrated() - before, charged);
  }
}

// A subset's records leave out the rays of the edge neighbours traced for them (and dropped); the
// tracer counts those too. The neighbours are found here by scanning the frame.
TEST(FrameTracerRays, ASubsetCountsTheNeighboursItTracesAndDrops)
{
  const int W = 32, H = 24;
  std::vector<std::pair<int, int>> subset;
  for (int j = 1; j < H; j += 5) // scattered pixels
    for (int i = 2; i < W; i += 7)
      subset.emplace_back(i, j);
  for (int j = 10; j < 14; ++j) // a block
    for (int i = 19; i < 23; ++i)
      subset.emplace_back(i, j);
  subset.emplace_back(0, 0); // a corner
  std::vector<char> in(static_cast<std::size_t>(W) * H, 0), below(in.size(), 0);
  for (const auto& [i, j] : subset)
    in[static_cast<std::size_t>(j) * W + i] = 1;
  long long neighbours = 0, belowOrLeft = 0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
    {
      if (in[static_cast<std::size_t>(j) * W + i])
        continue;
      auto asked = [&](int a, int b)
      { return a >= 0 && a < W && b >= 0 && b < H && in[static_cast<std::size_t>(b) * W + a]; };
      neighbours += asked(i - 1, j) || asked(i + 1, j) || asked(i, j - 1) || asked(i, j + 1);
      // Edges whose midpoint ray the frame charges to this pixel, not to the one asked for.
      belowOrLeft += asked(i + 1, j) + asked(i, j + 1);
    }
  ASSERT_GT(neighbours, 0);

  // One ray a pixel (textures filtered, no extra rays): each asked-for entry and each neighbour.
  SceneDescription filtered = photonSphereScene(W, H);
  filtered.rendering.mode = AntialiasMode::Filter;
  const FrameTracer plain(filtered);
  const std::vector<RayRecord> one = plain.tracePixels(subset);
  EXPECT_EQ(raysCharged(one), static_cast<long long>(subset.size()));
  EXPECT_EQ(plain.raysIntegrated(), static_cast<long long>(subset.size()) + neighbours);

  // Adaptive: the records' own rays, every neighbour's centre ray, and at most one midpoint ray
  // for each edge whose midpoint the frame charges to the neighbour.
  const FrameTracer adaptive(photonSphereScene(W, H));
  const std::vector<RayRecord> some = adaptive.tracePixels(subset);
  const long long own = raysCharged(some);
  EXPECT_GT(own, static_cast<long long>(subset.size())); // the rendering added rays
  EXPECT_GE(adaptive.raysIntegrated(), own + neighbours);
  EXPECT_LE(adaptive.raysIntegrated(), own + neighbours + belowOrLeft);
  std::printf("[ measured ] a subset of %zu entries: %lld rays in its records, %lld integrated "
              "(%lld edge neighbours)\n",
              subset.size(), own, static_cast<long long>(adaptive.raysIntegrated()), neighbours);
}

// Neighbours given beside the pixels (tracePixelsBeside): with the whole frame's own centre rays
// there, the records are the whole frame's bit for bit (Jacobians and colours included) and the
// tracer integrates exactly the neighbours' rays fewer than tracePixels; neighbours left out of
// the border are traced. Given other samples, the records' rays stay their own and their
// Jacobians follow the samples.
TEST(FrameTracerRays, NeighboursGivenBesideThePixelsAreReadInsteadOfTraced)
{
  const int W = 32, H = 24;
  SceneDescription d = photonSphereScene(W, H);
  d.rendering = scatteredPixelRendering(d.rendering); // lattice 1: scattered pixels
  const std::vector<RayRecord> whole = FrameTracer(d).traceRows(0, H);
  std::vector<std::pair<int, int>> pixels;
  for (int j = 6; j < 12; ++j) // a block
    for (int i = 8; i < 16; ++i)
      pixels.emplace_back(i, j);
  for (int j = 1; j < H; j += 6) // scattered pixels
    for (int i = 20; i < W; i += 5)
      pixels.emplace_back(i, j);
  pixels.emplace_back(0, 0); // a corner
  const std::vector<std::pair<int, int>> halo = edgeNeighbours(pixels, W, H);
  auto sampleOf = [&](int i, int j)
  { return jacobianSample(whole[static_cast<std::size_t>(j) * W + i]); };

  const FrameTracer reference(d);
  const std::vector<RayRecord> traced = reference.tracePixels(pixels);
  const long long tracedRays = reference.raysIntegrated();
  for (const bool everyOther : { false, true })
  {
    std::vector<JacobianSample> border;
    for (const auto& [i, j] : halo)
      if (!everyOther || (i + j) % 2 == 0)
        border.push_back(sampleOf(i, j));
    const FrameTracer tracer(d);
    const std::vector<RayRecord> beside = tracer.tracePixelsBeside(pixels, border);
    ASSERT_EQ(beside.size(), pixels.size());
    for (std::size_t k = 0; k < pixels.size(); ++k)
    {
      const RayRecord& w = whole[static_cast<std::size_t>(pixels[k].second) * W + pixels[k].first];
      EXPECT_EQ(firstDifference(beside[k], w), "") << pixels[k].first << "," << pixels[k].second;
      EXPECT_EQ(beside[k].color, w.color);
      EXPECT_EQ(firstDifference(beside[k], traced[k]), "");
    }
    EXPECT_EQ(tracer.raysIntegrated(), tracedRays - static_cast<long long>(border.size()))
      << (everyOther ? "every other neighbour given" : "every neighbour given");
  }

  // Other samples: a neighbour's (u, v) a little off moves the Jacobians that read it.
  std::vector<JacobianSample> shifted;
  for (const auto& [i, j] : halo)
  {
    JacobianSample s = sampleOf(i, j);
    s.u += 1e-3;
    s.v += 1e-3;
    shifted.push_back(s);
  }
  const std::vector<RayRecord> off = FrameTracer(d).tracePixelsBeside(pixels, shifted);
  int jacobiansMoved = 0;
  for (std::size_t k = 0; k < pixels.size(); ++k)
  {
    EXPECT_TRUE(off[k].objectId == traced[k].objectId && off[k].u == traced[k].u &&
                off[k].v == traced[k].v && off[k].hitPoint == traced[k].hitPoint &&
                off[k].termination == traced[k].termination)
      << pixels[k].first << "," << pixels[k].second;
    jacobiansMoved += off[k].dudi != traced[k].dudi || off[k].dvdj != traced[k].dvdj;
  }
  EXPECT_GT(jacobiansMoved, 0);

  // A border sample outside the frame, on a pixel asked for, or given twice is refused.
  const FrameTracer tracer(d);
  JacobianSample outside = sampleOf(halo[0].first, halo[0].second);
  outside.i = W;
  EXPECT_THROW(tracer.tracePixelsBeside(pixels, { outside }), InvalidParameter);
  EXPECT_THROW(tracer.tracePixelsBeside(pixels, { sampleOf(8, 6) }), InvalidParameter);
  const JacobianSample twice = sampleOf(halo[0].first, halo[0].second);
  EXPECT_THROW(tracer.tracePixelsBeside(pixels, { twice, twice }), InvalidParameter);
}

// Centre rays kept between calls (CentreRays): a list traced after another takes the centre rays
// the first traced (its pixels and their edge neighbours) instead of tracing them again. Its
// records are those of the same list traced on a fresh tracer, bit for bit (Jacobians and colours
// included), and the tracer integrates exactly the centre rays it did not have fewer.
TEST(FrameTracerRays, KeptCentreRaysAreReusedAndGiveTheSameRecords)
{
  const int W = 32, H = 24;
  SceneDescription d = photonSphereScene(W, H);
  d.rendering = scatteredPixelRendering(d.rendering); // lattice 1: scattered pixels
  std::vector<std::pair<int, int>> first, second;
  for (int j = 6; j < 12; ++j) // a block, then a band overlapping it and its neighbours
    for (int i = 8; i < 16; ++i)
      first.emplace_back(i, j);
  for (int j = 4; j < 18; ++j)
    for (int i = 15; i < 18; ++i)
      second.emplace_back(i, j);
  second.emplace_back(3, 3); // and a pixel far from both

  const FrameTracer fresh(d);
  const std::vector<RayRecord> alone = fresh.tracePixels(second);
  const long long aloneRays = fresh.raysIntegrated();

  const FrameTracer tracer(d);
  CentreRays kept;
  const std::vector<RayRecord> a = tracer.tracePixels(first, kept);
  // Every centre ray it traced is kept: the pixels asked for and their edge neighbours.
  EXPECT_EQ(kept.size(), first.size() + edgeNeighbours(first, W, H).size());
  const long long before = tracer.raysIntegrated();
  const std::vector<RayRecord> b = tracer.tracePixels(second, kept);
  ASSERT_EQ(b.size(), alone.size());
  for (std::size_t k = 0; k < b.size(); ++k)
  {
    EXPECT_EQ(firstDifference(b[k], alone[k]), "") << second[k].first << "," << second[k].second;
    EXPECT_EQ(b[k].raysPerPixel, alone[k].raysPerPixel);
    EXPECT_EQ(b[k].color, alone[k].color);
  }
  // The centre rays of the second list (its pixels and their neighbours) found among the first's.
  std::vector<std::pair<int, int>> traced = first, asked = second;
  for (const auto& n : edgeNeighbours(first, W, H))
    traced.push_back(n);
  for (const auto& n : edgeNeighbours(second, W, H))
    asked.push_back(n);
  std::sort(traced.begin(), traced.end());
  long long reused = 0;
  for (const auto& ij : asked)
    reused += std::binary_search(traced.begin(), traced.end(), ij);
  ASSERT_GT(reused, 10);
  EXPECT_EQ(tracer.raysIntegrated() - before, aloneRays - reused);
  std::printf("[ measured ] %zu pixels after %zu: %lld rays integrated, %lld on a fresh tracer "
              "(%lld centre rays kept)\n",
              second.size(), first.size(), static_cast<long long>(tracer.raysIntegrated() - before),
              aloneRays, reused);
}

// ---- 9. Jacobians -------------------------------------------------------------------------------
TEST(FrameTracerRecords, JacobiansMatchThePinholeProjection)
{
  // Head-on planes in flat space: the pinhole maps pixel (i, j) to the plane point
  // D (x(i), y(j)) with x = (2(i + ½)/W − 1) t·aspect and y = (2(j + ½)/H − 1) t, t = tan(½ angle),
  // so ∂s/∂i = 2 D t aspect / W and ∂s/∂j = 2 D t / H, exactly (the map is linear, and so finite
  // differences are exact to round-off).
  const int W = 30, H = 20;
  const double angle = 40, t = std::tan(0.5 * angle * M_PI / 180.0), aspect = double(W) / H;
  const CameraParameters cam = looking(Vec3(0, -10, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), angle, W, H);
  SceneDescription d = describe(0.0, cam);
  const double D1 = 8, hw = 2, hh = 1.5;  // a board at y = −2
  const double D2 = 15, tile = 4, sh = 3; // a strip at y = 5: infinite along x, tiled
  d.scene->add(std::make_unique<Rectangle>(0, "board", solid(), Vec3(0, -2, 0), Vec3(1, 0, 0),
                                           Vec3(0, 0, 1), hw, hh));
  d.scene->add(std::make_unique<Rectangle>(1, "strip", solid(), Vec3(0, 5, 0), Vec3(1, 0, 0),
                                           Vec3(0, 0, 1), inf, sh, tile));
  const FrameTracer tracer(d);
  const std::vector<RayRecord> recs = tracer.traceRows(0, H);
  auto at = [&](int i, int j) -> const RayRecord*
  {
    if (i < 0 || i >= W || j < 0 || j >= H)
      return nullptr;
    return &recs[static_cast<size_t>(j) * W + i];
  };
  auto sameObject = [&](const RayRecord& r, const RayRecord* o)
  { return o && o->objectId == r.objectId; };
  const double dudi[2] = { D1 * 2 * t * aspect / W / (2 * hw), D2 * 2 * t * aspect / W / tile };
  const double dvdj[2] = { D1 * 2 * t / H / (2 * hh), D2 * 2 * t / H / (2 * sh) };
  int counts[3] = { 0, 0, 0 }, undefined = 0;
  double worst = 0;
  for (const RayRecord& r : recs)
  {
    ++counts[r.objectId + 1];
    const bool alongI =
      r.objectId >= 0 && (sameObject(r, at(r.i - 1, r.j)) || sameObject(r, at(r.i + 1, r.j)));
    const bool alongJ =
      r.objectId >= 0 && (sameObject(r, at(r.i, r.j - 1)) || sameObject(r, at(r.i, r.j + 1)));
    if (!alongI)
    {
      ++undefined;
      EXPECT_TRUE(std::isnan(r.dudi) && std::isnan(r.dvdi)) << r.i << "," << r.j;
    }
    else
    {
      worst = std::max(worst, std::abs(r.dudi / dudi[r.objectId] - 1));
      EXPECT_NEAR(r.dudi, dudi[r.objectId], 1e-9 * dudi[r.objectId]) << r.i << "," << r.j;
      EXPECT_NEAR(r.dvdi, 0.0, 1e-12) << r.i << "," << r.j;
    }
    if (!alongJ)
    {
      EXPECT_TRUE(std::isnan(r.dudj) && std::isnan(r.dvdj)) << r.i << "," << r.j;
    }
    else
    {
      worst = std::max(worst, std::abs(r.dvdj / dvdj[r.objectId] - 1));
      EXPECT_NEAR(r.dvdj, dvdj[r.objectId], 1e-9 * dvdj[r.objectId]) << r.i << "," << r.j;
      EXPECT_NEAR(r.dudj, 0.0, 1e-12) << r.i << "," << r.j;
    }
  }
  std::printf("[ measured ] Jacobians: relative error <= %.3g; pixels missing/board/strip = "
              "%d/%d/%d, %d without a same-object neighbour along i (misses included)\n",
              worst, counts[0], counts[1], counts[2], undefined);
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[1], 20);
  EXPECT_GT(counts[2], 20);
}
