// The k-d tree's nearest-point searches (KdTreeIndex.h) against a brute-force scan of every point:
// scattered points, a lattice whose points tie in distance, repeated points, radii from 0 up.
#include "KdTreeIndex.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

using asrt::Vec3;

namespace
{
/// The lowest index among the nearest points within `radius` (inclusive), −1 if none.
std::int64_t bruteNearest(const std::vector<Vec3>& points, const Vec3& x, double radius)
{
  std::int64_t best = -1;
  double bestDist2 = radius * radius;
  for (std::size_t k = 0; k < points.size(); ++k)
  {
    const double d2 = (points[k] - x).squaredNorm();
    if (d2 < bestDist2 || (d2 == bestDist2 && best < 0))
    {
      best = static_cast<std::int64_t>(k);
      bestDist2 = d2;
    }
  }
  return best;
}

std::vector<std::int64_t> bruteWithin(const std::vector<Vec3>& points, const Vec3& x, double radius)
{
  std::vector<std::int64_t> out;
  for (std::size_t k = 0; k < points.size(); ++k)
    if ((points[k] - x).squaredNorm() <= radius * radius)
      out.push_back(static_cast<std::int64_t>(k));
  return out;
}

void expectAgreesWithBruteForce(const std::vector<Vec3>& points, std::mt19937& rng)
{
  const auto index = asrt::kdTreeIndexFactory()(points);
  std::uniform_real_distribution<double> coordinate(-1.2, 1.2);
  std::vector<std::int64_t> within;
  for (int q = 0; q < 400; ++q)
  {
    // Queries anywhere, and on the points themselves.
    const Vec3 x = q % 4 == 0 && !points.empty()
                     ? points[static_cast<std::size_t>(q) % points.size()]
                     : Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
    for (double radius : { 0.0, 0.05, 0.25, 0.5, 3.0 })
    {
      ASSERT_EQ(index->nearestWithin(x, radius), bruteNearest(points, x, radius))
        << "query " << q << ", radius " << radius;
      index->within(x, radius, within);
      ASSERT_EQ(within, bruteWithin(points, x, radius)) << "query " << q << ", radius " << radius;
    }
  }
}
}

TEST(KdTreeIndex, ScatteredPointsAgreeWithABruteForceScan)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  std::vector<Vec3> points(3000);
  for (Vec3& p : points)
    p = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
  expectAgreesWithBruteForce(points, rng);
}

TEST(KdTreeIndex, TiesAndRepeatedPointsGiveTheLowestIndex)
{
  // A lattice of spacing 0.25: a query at a cell's centre is equally far from 8 points; each
  // point is there twice.
  std::vector<Vec3> points;
  for (int copy = 0; copy < 2; ++copy)
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j)
        for (int k = -4; k <= 4; ++k)
          points.emplace_back(0.25 * i, 0.25 * j, 0.25 * k);
  std::mt19937 rng(11);
  expectAgreesWithBruteForce(points, rng);
  const auto index = asrt::kdTreeIndexFactory()(points);
  const Vec3 centre(0.125, 0.125, 0.125);
  const std::int64_t nearest = index->nearestWithin(centre, 1.0);
  EXPECT_EQ(nearest, bruteNearest(points, centre, 1.0));
  EXPECT_LT(nearest, static_cast<std::int64_t>(points.size() / 2)); // the first copy's
}

TEST(KdTreeIndex, NoPointsFindNothing)
{
  const auto index = asrt::kdTreeIndexFactory()({});
  std::vector<std::int64_t> within{ 1, 2 };
  EXPECT_EQ(index->nearestWithin(Vec3::Zero(), 10.0), -1);
  index->within(Vec3::Zero(), 10.0, within);
  EXPECT_TRUE(within.empty());
}
