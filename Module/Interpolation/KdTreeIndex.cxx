#include "KdTreeIndex.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

namespace asrt
{
namespace
{
constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// The points as nanoflann reads them.
struct PointCloud
{
  const std::vector<Vec3>* points = nullptr;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t k, std::size_t dim) const
  {
    return (*points)[k][static_cast<Eigen::Index>(dim)];
  }
  template<class Box>
  bool kdtree_get_bbox(Box&) const
  {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointCloud>,
                                                 PointCloud, 3, std::size_t>;

/// nanoflann's result-set interface: the nearest point within a squared radius (inclusive), of
/// equally near ones the lowest index.
class NearestWithin
{
public:
  explicit NearestWithin(double radius2)
    : Worst(radius2)
  {
  }
  std::size_t size() const { return this->Found ? 1 : 0; }
  bool full() const { return true; }
  bool addPoint(double dist2, std::size_t index)
  {
    if (dist2 < this->Worst || (dist2 == this->Worst && (!this->Found || index < this->Index)))
    {
      this->Worst = dist2;
      this->Index = index;
      this->Found = true;
    }
    return true;
  }
  /// Just above the nearest distance so far: nanoflann offers only points strictly nearer than
  /// this, and those as near count too (the radius is inclusive, ties go to the lowest index).
  double worstDist() const { return std::nextafter(this->Worst, kInfinity); }
  std::int64_t result() const { return this->Found ? static_cast<std::int64_t>(this->Index) : -1; }

private:
  double Worst;
  std::size_t Index = 0;
  bool Found = false;
};

/// nanoflann's result-set interface: every point within a squared radius (inclusive).
class AllWithin
{
public:
  AllWithin(double radius2, std::vector<std::int64_t>& out)
    : Radius2(radius2)
    , Out(out)
  {
  }
  std::size_t size() const { return this->Out.size(); }
  bool full() const { return true; }
  bool addPoint(double dist2, std::size_t index)
  {
    if (dist2 <= this->Radius2)
      this->Out.push_back(static_cast<std::int64_t>(index));
    return true;
  }
  double worstDist() const { return std::nextafter(this->Radius2, kInfinity); }

private:
  double Radius2;
  std::vector<std::int64_t>& Out;
};

class KdTreeIndex final : public PointIndex
{
public:
  explicit KdTreeIndex(const std::vector<Vec3>& points)
    : Points(points)
    , Cloud{ &this->Points }
    , Index(3, this->Cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10))
  {
    if (!this->Points.empty())
      this->Index.buildIndex();
  }

  std::int64_t nearestWithin(const Vec3& x, double radius) const override
  {
    if (this->Points.empty() || !(radius >= 0))
      return -1;
    NearestWithin found(radius * radius);
    this->Index.findNeighbors(found, x.data(), nanoflann::SearchParams());
    return found.result();
  }

  void within(const Vec3& x, double radius, std::vector<std::int64_t>& out) const override
  {
    out.clear();
    if (this->Points.empty() || !(radius >= 0))
      return;
    AllWithin found(radius * radius, out);
    this->Index.findNeighbors(found, x.data(), nanoflann::SearchParams());
    std::sort(out.begin(), out.end());
  }

private:
  std::vector<Vec3> Points;
  PointCloud Cloud;
  Tree Index;
};
}

PointIndexFactory kdTreeIndexFactory()
{
  return [](const std::vector<Vec3>& points) -> std::unique_ptr<PointIndex>
  { return std::make_unique<KdTreeIndex>(points); };
}
}
