#include "ObjectHierarchy.h"

#include <limits>
#include <stdexcept>

namespace asrt
{
void ObjectHierarchy::build(std::vector<Ball> balls)
{
  this->Nodes.clear();
  this->Order.clear();
  if (balls.empty())
    return;
  if (balls.size() >= std::numeric_limits<std::uint32_t>::max())
    throw InvalidParameter("a scene may hold fewer than 2^32 bounded objects");
  const auto count = static_cast<std::uint32_t>(balls.size());
  // A binary tree with leaves of at least one object has fewer than 2n nodes.
  this->Nodes.reserve(2 * static_cast<std::size_t>(count));
  this->Nodes.emplace_back();
  this->split(balls, 0, 0, count, 1);
  this->Order.reserve(count);
  for (const Ball& b : balls)
    this->Order.push_back(b.index);
}

void ObjectHierarchy::split(std::vector<Ball>& balls, std::uint32_t node, std::uint32_t first,
                            std::uint32_t count, int depth)
{
  // The traversals hold at most one pending node a level (see kStackSize).
  if (depth >= kStackSize)
    throw std::logic_error("object hierarchy deeper than its traversal stack");
  const auto begin = balls.begin() + first, end = begin + count;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  Vec3 centerLo = lo, centerHi = hi;
  double maxRadius = 0;
  for (auto b = begin; b != end; ++b)
  {
    lo = lo.cwiseMin(b->center - Vec3::Constant(b->radius));
    hi = hi.cwiseMax(b->center + Vec3::Constant(b->radius));
    centerLo = centerLo.cwiseMin(b->center);
    centerHi = centerHi.cwiseMax(b->center);
    maxRadius = std::max(maxRadius, b->radius);
  }
  {
    Node& n = this->Nodes[node];
    n.lo = lo;
    n.hi = hi;
    n.maxRadius = maxRadius;
    n.scale = std::max(largestCoordinate(lo), largestCoordinate(hi));
  }
  if (count <= kLeafSize)
  {
    this->Nodes[node].first = first;
    this->Nodes[node].count = count;
    return;
  }
  int axis = 0;
  (centerHi - centerLo).maxCoeff(&axis);
  // The median by centre along the axis, ties by index so that the tree does not depend on the
  // standard library's partition order.
  const std::uint32_t leftCount = count / 2;
  std::nth_element(begin, begin + leftCount, end,
                   [axis](const Ball& a, const Ball& b)
                   {
                     return a.center[axis] < b.center[axis] ||
                            (a.center[axis] == b.center[axis] && a.index < b.index);
                   });
  const auto children = static_cast<std::uint32_t>(this->Nodes.size());
  this->Nodes[node].first = children;
  this->Nodes[node].count = 0;
  this->Nodes.emplace_back();
  this->Nodes.emplace_back();
  this->split(balls, children, first, leftCount, depth + 1);
  this->split(balls, children + 1, first + leftCount, count - leftCount, depth + 1);
}
}
