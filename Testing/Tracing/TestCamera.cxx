// The camera and its observer: the tetrad is orthonormal in the metric, every pixel's momentum is
// null, flat space gives the pinhole's directions, and a static observer sees the Schwarzschild
// shadow at the analytic angular size (which tests the frame's aberration and the tracing).
#include "Camera.h"
#include "CameraFixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace asrt;
using asrt::testing::looking;

namespace
{

void expectOrthonormalTetrad(const Spacetime& st, const Camera& cam)
{
  const Mat4 g = st.metric(Vec4(0, cam.parameters().position.x(), cam.parameters().position.y(),
                                cam.parameters().position.z()));
  const Vec4* legs[4] = { &cam.velocity(), &cam.right(), &cam.up(), &cam.forward() };
  const double eta[4] = { -1, 1, 1, 1 };
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      EXPECT_NEAR(legs[a]->dot(g * *legs[b]), a == b ? eta[a] : 0.0, 1e-13) << a << "," << b;
}
}

TEST(Camera, TetradIsOrthonormalAndPixelRaysAreNull)
{
  const SchwarzschildSpacetime schw(1.0);
  const KerrSpacetime kerr(1.0, 0.9);
  const ReissnerNordstromSpacetime rn(1.0, 0.6);
  for (const Spacetime* st : std::initializer_list<const Spacetime*>{ &schw, &kerr, &rn })
  {
    for (ObserverMotion motion : { ObserverMotion::Static, ObserverMotion::ZAMO })
    {
      const Camera cam(*st,
                       looking(Vec3(3, -12, 5), Vec3(0, 0, 0), Vec3(0, 0, 1), 40, 64, 48, motion));
      expectOrthonormalTetrad(*st, cam);
      for (int j = 0; j < 48; j += 7)
        for (int i = 0; i < 64; i += 9)
        {
          const PhasePoint z = cam.pixelRay(i, j);
          EXPECT_NEAR(st->value(z.x, z.p), 0.0, 1e-14) << st->name() << " " << i << "," << j;
          // E_local = 1: −p·u = 1 for the photon arriving at the eye (past-directed here).
          EXPECT_NEAR(z.p.dot(cam.velocity()), 1.0, 1e-13);
        }
    }
  }
}

TEST(Camera, FlatSpaceIsAPinhole)
{
  const MinkowskiSpacetime st;
  const Camera cam(st, looking(Vec3(0, -10, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), 60, 100, 50));
  const double t = std::tan(M_PI / 6); // half of the 60° vertical angle
  // Pixel centre (i + ½, j + ½) → (x, y) on the image plane at unit distance; x runs right (+x),
  // y up (+z), forward is +y.
  for (const auto& [i, j] : { std::pair<int, int>{ 0, 0 }, { 99, 49 }, { 37, 12 } })
  {
    const double x = (2.0 * (i + 0.5) / 100 - 1) * t * 2.0, y = (2.0 * (j + 0.5) / 50 - 1) * t;
    const Vec3 expected = Vec3(x, 1.0, y).normalized();
    const PhasePoint z = cam.pixelRay(i, j);
    // In flat space the ray moves along dx/dλ = η p, i.e. the spatial p for a past-directed ray.
    EXPECT_LT((z.p.tail<3>().normalized() - expected).norm(), 1e-14) << i << "," << j;
  }
}

TEST(Camera, RefusesImpossibleObservers)
{
  const SchwarzschildSpacetime schw(1.0);
  const KerrSpacetime kerr(1.0, 0.99);
  auto base = looking(Vec3(0, -30, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), 30, 10, 10);
  auto expectRefused = [&](const Spacetime& st, CameraParameters p, const char* word)
  {
    try
    {
      Camera c(st, p);
      ADD_FAILURE() << "accepted: " << word;
    }
    catch (const InvalidParameter& e)
    {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  auto p = base;
  p.position = Vec3(0, -1.5, 0);
  expectRefused(schw, p, "horizon");
  p = base;
  p.position = Vec3(0, -1.8, 0.0); // equatorial ergosphere of a = 0.99 reaches r = 2M
  expectRefused(kerr, p, "ergosphere");
  p.observer = ObserverMotion::ZAMO; // a valid observer there
  EXPECT_NO_THROW(Camera(kerr, p));
  p = base;
  p.position = Vec3(NAN, 0, 0);
  expectRefused(schw, p, "finite");
  p = base;
  p.width = 0;
  expectRefused(schw, p, "resolution");
  p = base;
  p.viewAngle = 180;
  expectRefused(schw, p, "view angle");
  p = base;
  p.viewUp = Vec3(0, 1, 0); // along the view direction
  expectRefused(schw, p, "parallel");
  p = base;
  p.focalPoint = p.position;
  expectRefused(schw, p, "coincides");
}

TEST(Camera, StaticObserverSeesTheAnalyticShadow)
{
  // sin α_sh = (b_c/r_o)√(1 − 2M/r_o) (physics.md). Bisect the capture boundary over the angle
  // from the forward axis; the observer's aberration and the tracing both enter.
  const SchwarzschildSpacetime st(1.0);
  for (double ro : { 6.0, 15.0, 100.0 })
  {
    const Camera cam(st, looking(Vec3(0, -ro, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), 90, 1000, 1));
    IntegratorConfig cfg;
    cfg.method = "SchwarzschildSplit4";
    cfg.step = 0.002;
    auto prop = makePropagator(st, cfg);
    TraceOptions opts;
    opts.escapeRadius = 2 * ro + 100;
    auto captured = [&](double psi)
    {
      const double x = std::tan(psi) / cam.tanHalfAngle(); // aspect 1000:1 handled below
      const double i = (x / 1000.0 + 1.0) * 500.0 - 0.5;
      return traceRay(st, *prop, cam.pixelRay(i, 0), opts).termination == Termination::Captured;
    };
    double lo = 0.0, hi = 1.5;
    ASSERT_TRUE(captured(lo));
    ASSERT_FALSE(captured(hi));
    for (int it = 0; it < 40; ++it)
    {
      const double mid = 0.5 * (lo + hi);
      (captured(mid) ? lo : hi) = mid;
    }
    EXPECT_NEAR(0.5 * (lo + hi), analytic::shadowAngularRadius(ro, 1.0), 1e-7) << "r_o = " << ro;
  }
}
