// KerrMinoPropagator at any mass. The truth is the scale symmetry of general relativity: the Kerr
// metric in Kerr–Schild Cartesian coordinates depends on x only through x/M and a/M, so the null
// geodesic of (M, a) from M·x with covector p is M times the geodesic of (1, a/M) from x with
// the same p, its affine parameter scaled by M. A method whose step is given in units of M must
// trace both alike: same ending, same number of steps, the same path scaled by M.
#include "KerrMinoPropagator.h"
#include "RayTracer.h"
#include "Spacetime.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

using namespace asrt;

namespace
{
std::unique_ptr<Spacetime> hole(double M, double spinPerMass)
{
  if (spinPerMass == 0.0)
    return std::make_unique<SchwarzschildSpacetime>(M);
  return std::make_unique<KerrSpacetime>(M, spinPerMass * M);
}

/// Rays from an eye at about 39 M, off the equator, aimed past the hole with impact offsets b
/// (in M) along two transverse directions: captured, strongly and weakly deflected.
std::vector<PhasePoint> raysAtUnitMass(const Spacetime& st)
{
  const Vec3 eye(3.0, -38.0, 10.0);
  const Vec3 in = -eye.normalized();
  const Vec3 side = in.cross(Vec3::UnitZ()).normalized(), up = side.cross(in);
  std::vector<PhasePoint> rays;
  for (const double b : { 1.0, 4.5, 5.5, 7.0, 15.0 })
    for (const Vec3& t : { side, up })
    {
      PhasePoint z;
      z.x = Vec4(0.0, eye.x(), eye.y(), eye.z());
      const Vec3 transverse = (b / eye.norm()) * t;
      const Vec4 partial(-1.0, transverse.x(), transverse.y(), transverse.z());
      z.p = completeNullMomentum(st, z.x, partial, Vec4(0.0, in.x(), in.y(), in.z()), true);
      rays.push_back(z);
    }
  return rays;
}

TraceOptions optionsAtMass(double M)
{
  TraceOptions o;
  o.escapeRadius = 1000.0 * M;
  o.maxSteps = 200000;
  return o;
}

void expectScaledCopy(double spinPerMass, double M)
{
  const auto unit = hole(1.0, spinPerMass);
  const auto scaled = hole(M, spinPerMass);
  KerrMinoPropagator unitProp(*unit, 4, 0.05), scaledProp(*scaled, 4, 0.05);
  for (const PhasePoint& z : raysAtUnitMass(*unit))
  {
    const TraceResult ref = traceRay(*unit, unitProp, z, optionsAtMass(1.0));
    ASSERT_TRUE(ref.termination == Termination::Escaped || ref.termination == Termination::Captured)
      << toString(ref.termination);
    PhasePoint zs = z;
    zs.x = M * z.x;
    const TraceResult res = traceRay(*scaled, scaledProp, zs, optionsAtMass(M));
    SCOPED_TRACE(testing::Message() << "M = " << M << ", a/M = " << spinPerMass << ", ray from "
                                    << z.x.transpose() << " with p = " << z.p.transpose());
    std::printf("[ scale ] M = %g: %s %ld steps vs %s %ld\n", M, toString(res.termination),
                res.steps, toString(ref.termination), ref.steps);
    EXPECT_EQ(toString(res.termination), std::string(toString(ref.termination)));
    EXPECT_NEAR(static_cast<double>(res.steps), static_cast<double>(ref.steps), 1.0);
    const Vec4 end = res.final.x / M;
    EXPECT_LT((end - ref.final.x).norm(), 1e-9 * ref.final.x.norm())
      << end.transpose() << " vs " << ref.final.x.transpose();
    EXPECT_NEAR(res.affineLength / M, ref.affineLength, 1e-9 * std::abs(ref.affineLength));
    EXPECT_NEAR(res.winding, ref.winding, 1e-9);
  }
}
}

TEST(KerrMinoScaling, TinyKerrHoleIsTheUnitHoleScaledDown)
{
  expectScaledCopy(0.7, 1e-6);
  expectScaledCopy(0.1, 1e-12);
}

TEST(KerrMinoScaling, HugeKerrHoleIsTheUnitHoleScaledUp)
{
  expectScaledCopy(0.7, 1e6);
}

TEST(KerrMinoScaling, SchwarzschildThroughKerrMinoScalesToo)
{
  expectScaledCopy(0.0, 1e-6);
  expectScaledCopy(0.0, 1e6);
}
